//! Culling modes: one file per mode, each behind the [`Culler`] trait.
//!
//! A mode owns its state between frames (temporal coherence lives inside the
//! mode) and touches the GPU only through [`FrameCtx`], which counts what it
//! draws and queries. To add a mode: write `cull/NAME.rs` implementing
//! [`Culler`], add it to [`MODES`] and to [`create`].

mod ac;
mod auto;
mod chc;
mod dr;
pub mod ioc;
pub mod occupancy;
mod omq;
mod oracle;
mod roc;
mod sq;
pub mod traversal;
mod vfc;

use std::collections::BTreeMap;
use std::fmt::Display;
use std::str::FromStr;
use std::time::Duration;

use crate::camera::Camera;
use crate::gpu::{FrameCtx, GpuAudit, GpuContext, Resolution};
use crate::hierarchy::Hierarchy;
use crate::object_set::ObjectSet;
use crate::scene::Scene;

pub use ac::{AcParams, AdaptiveCulling, EyeDistance, Threshold};
pub use auto::{AutoCulling, AutoParams};
pub use chc::{ChcParams, CoherentCulling};
pub use dr::DirectRendering;
pub use ioc::{Depth, IocParams, IterativeOcclusionCulling};
pub use omq::{OccupancyMapQueries, OmqParams};
pub use oracle::Oracle;
pub use roc::RasterOcclusionCulling;
pub use sq::SingleQueries;
pub use vfc::FrustumCulling;

/// What a mode is told about the frame it renders.
pub struct FrameInput<'a> {
    pub frame: u32,
    pub camera: &'a Camera,
    pub resolution: Resolution,
    /// The scene at this frame: movers placed, object bounds current.
    pub scene: &'a Scene,
    /// The shared hierarchy, refit around moved objects for modes whose
    /// [`Culler::traverses_hierarchy`] is true.
    pub hierarchy: &'a Hierarchy,
    /// Objects whose pose changed since the previous frame.
    pub moved: &'a [u32],
    /// The objects that own at least one pixel of the reference frame; given
    /// only to modes whose [`Culler::needs_reference`] is true (the oracle).
    pub reference_visible: Option<&'a ObjectSet>,
    /// What this mode's previous frame cost; `None` in its first frame.
    pub previous: Option<PreviousFrame>,
}

/// A mode's own previous frame, as measured (cost-adaptive culling budgets
/// from it, 002 Eq. 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviousFrame {
    pub frame_ms: f64,
    /// Time spent drawing: GPU time outside box tests where timestamps
    /// exist, else the frame minus culling CPU time and waits for results.
    pub render_ms: f64,
}

/// Hierarchy traversal counts of one frame (drawing is counted by `FrameCtx`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    pub nodes_visited: u64,
    pub nodes_culled_frustum: u64,
    pub nodes_culled_occlusion: u64,
    /// Queries made unnecessary (the Occupancy Map's empty-area rule, or
    /// chc's nodes visible in the last frame).
    pub queries_skipped: u64,
    /// Queries held back because a nearer query in flight covered part of
    /// their screen rectangle (chc, 001 §3.5).
    pub queries_delayed: u64,
    /// Nodes visible but treated as occluded for their small contribution
    /// (adaptive culling, 002 Eq. 1).
    pub nodes_culled_adaptive: u64,
    /// Nodes left when the culling budget ran out, only frustum-culled and
    /// drawn (cost-adaptive culling, 002 Eq. 2).
    pub nodes_past_budget: u64,
    /// Time spent keeping the mode's own spatial structure current with
    /// moved objects (part of its CPU time).
    pub maintenance: Duration,
}

impl TraversalStats {
    /// Adds the nodes a GPU-driven walk visited, found outside the frustum
    /// and found hidden.
    pub fn add_gpu_audit(&mut self, audit: &GpuAudit) {
        self.nodes_visited += audit.nodes_visited;
        self.nodes_culled_frustum += audit.nodes_outside_frustum;
        self.nodes_culled_occlusion += audit.nodes_hidden;
    }
}

pub trait Culler {
    /// The mode's name on the command line and in result files.
    fn name(&self) -> &str;

    /// The mode's parameters, recorded in summary.json.
    fn parameters(&self) -> serde_json::Value {
        serde_json::json!({})
    }

    /// Whether the mode needs the reference visible set (only the oracle).
    fn needs_reference(&self) -> bool {
        false
    }

    /// Whether the mode traverses the shared hierarchy, which is then refit
    /// around moved objects at the start of its timed frame.
    fn traverses_hierarchy(&self) -> bool {
        false
    }

    /// Whether the mode walks a tree on the GPU (`FrameCtx::begin_gpu_walk`
    /// and the operations after it).
    fn culls_on_gpu(&self) -> bool {
        false
    }

    /// Renders one frame: decides what to draw and draws it through `ctx`.
    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats;
}

/// A mode on the command line.
pub struct ModeInfo {
    pub name: &'static str,
    pub summary: &'static str,
    /// Whether the mode may never change a pixel (0 error required).
    pub conservative: bool,
    /// Parameters it takes as `--param NAME.KEY=VALUE`.
    pub params: &'static [ParamInfo],
    /// What it needs from the adapter beyond drawing and occlusion queries;
    /// a mode whose needs are not met is skipped, with a message.
    pub needs: Needs,
}

/// Adapter capabilities a mode may need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Needs {
    /// Drawing and occlusion queries: every adapter.
    Nothing,
    /// Visible pixels counted per box (`GpuContext::pixel_counts`).
    PixelCounts,
    /// Culling on the GPU alone (`GpuContext::gpu_driven`).
    GpuCulling,
}

impl ModeInfo {
    /// The mode named `name`, which must be one of [`MODES`] (mode names are
    /// checked by [`parse_modes`] before anything runs).
    pub fn named(name: &str) -> &'static ModeInfo {
        MODES
            .iter()
            .find(|m| m.name == name)
            .unwrap_or_else(|| panic!("'{name}' is not in MODES"))
    }

    /// Why the mode cannot run on `gpu`, or `None` when it can.
    pub fn unsupported_on(&self, gpu: &GpuContext) -> Option<&'static str> {
        match self.needs {
            Needs::PixelCounts if !gpu.pixel_counts => Some(
                "the adapter cannot count visible pixels (needs SHADER_EARLY_DEPTH_TEST and fragment storage writes)",
            ),
            Needs::GpuCulling if !gpu.gpu_driven => Some(
                "the adapter cannot cull on the GPU (needs SHADER_EARLY_DEPTH_TEST, fragment storage writes, compute shaders, indirect draws, INDIRECT_FIRST_INSTANCE and 8 storage buffers per stage)",
            ),
            _ => None,
        }
    }
}

pub struct ParamInfo {
    pub key: &'static str,
    pub default: &'static str,
    pub summary: &'static str,
}

pub const MODES: &[ModeInfo] = &[
    ModeInfo {
        name: "dr",
        summary: "direct rendering: every object, no culling (002 §5)",
        conservative: true,
        params: &[],
        needs: Needs::Nothing,
    },
    ModeInfo {
        name: "vfc",
        summary: "hierarchical view-frustum culling with the fully-inside shortcut (002 §4.1)",
        conservative: true,
        params: &[],
        needs: Needs::Nothing,
    },
    ModeInfo {
        name: "sq",
        summary: "front-to-back traversal, one occlusion query per node, each awaited (003 §5 b)",
        conservative: true,
        params: &[],
        needs: Needs::Nothing,
    },
    ModeInfo {
        name: "omq",
        summary: "Occupancy Map + multiple occlusion queries in three stages (003 §3-4)",
        conservative: true,
        params: &[
            ParamInfo {
                key: "om",
                default: "64x48",
                summary: "Occupancy Map cells across x down",
            },
            ParamInfo {
                key: "initial_max_tests",
                default: "4",
                summary: "stage-2 batches in the first frame",
            },
            ParamInfo {
                key: "factor",
                default: "0.7",
                summary: "next frame's max_tests = factor x this frame's batches",
            },
        ],
        needs: Needs::Nothing,
    },
    ModeInfo {
        name: "ac",
        summary: "V+O with adaptive culling (Eq. 1) and a cost-adaptive budget (Eq. 2) by visible-pixel counts (002 §4.2-4.4)",
        conservative: false,
        params: &[
            ParamInfo {
                key: "threshold",
                default: "auto",
                summary: "Eq. 1 threshold in pixels; auto = 100 px on 650x650 scaled to the viewport",
            },
            ParamInfo {
                key: "sampling",
                default: "1",
                summary: "count every k-th row of spans (1: every pixel)",
            },
            ParamInfo {
                key: "f_graphics",
                default: "0.3333333333333333",
                summary: "Eq. 2 culling budget = previous render time x this (inf: no budget)",
            },
            ParamInfo {
                key: "eye_distance",
                default: "near",
                summary: "Dist(Eye) of Eq. 1: the near plane, or a distance",
            },
        ],
        needs: Needs::PixelCounts,
    },
    ModeInfo {
        name: "chc",
        summary: "coherent culling on a ternary tree: last frame's visible nodes unwaited, TightBoxes, split/merge, colliding queries wait (001)",
        conservative: true,
        params: &[
            ParamInfo {
                key: "r_split",
                default: "0.25",
                summary: "split a leaf whose visible/total pixels reach this …",
            },
            ParamInfo {
                key: "o_split",
                default: "12",
                summary: "… and which holds at least this many objects",
            },
            ParamInfo {
                key: "r_merge",
                default: "0.75",
                summary: "merge sibling leaves whose visible/total pixels are at most this …",
            },
            ParamInfo {
                key: "o_merge",
                default: "5",
                summary: "… and which hold at most this many objects each",
            },
            ParamInfo {
                key: "tight_after",
                default: "3",
                summary: "frames without change before a node's TightBox replaces its cell",
            },
        ],
        needs: Needs::PixelCounts,
    },
    ModeInfo {
        name: "roc",
        summary: "raster occlusion culling on the GPU: every object's box marks a visibility buffer, indirect multi-draw (004's ROC)",
        conservative: true,
        params: &[],
        needs: Needs::GpuCulling,
    },
    ModeInfo {
        name: "ioc",
        summary: "iterative hierarchical raster occlusion culling: roc over the hierarchy, level by level from a start to a bottom depth (004 §2)",
        conservative: true,
        params: &[
            ParamInfo {
                key: "start",
                default: "auto",
                summary: "depth whose nodes are tested first (root 0); auto: from the hierarchy",
            },
            ParamInfo {
                key: "bottom",
                default: "auto",
                summary: "depth below which nodes are not tested: a visible node there draws its subtree; auto: from the hierarchy",
            },
        ],
        needs: Needs::GpuCulling,
    },
    ModeInfo {
        name: "auto",
        summary: "per frame, vfc or occlusion culling (ioc, or omq without GPU culling), whichever measured cheaper; the other re-measured now and then",
        conservative: true,
        params: &[ParamInfo {
            key: "probe",
            default: "32",
            summary: "frames between re-measurements of the dearer strategy, times how much dearer it was",
        }],
        needs: Needs::Nothing,
    },
    ModeInfo {
        name: "oracle",
        summary: "draws exactly the objects visible in the reference frame: the floor for object-level culling",
        conservative: true,
        params: &[],
        needs: Needs::Nothing,
    },
];

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ModeError {
    #[error("unknown mode '{0}' (modes: {list}, or all)", list = mode_names().join(", "))]
    Unknown(String),
    #[error("no modes given")]
    Empty,
    #[error("'{0}' names more than one mode, and render draws one (e.g. --mode roc)")]
    NotOne(String),
    #[error("parameter '{0}' is not MODE.KEY=VALUE")]
    MalformedParam(String),
    #[error("unknown parameter '{key}' ({known})")]
    UnknownParam { key: String, known: String },
    #[error("parameter '{key}': {reason}")]
    BadParam { key: String, reason: String },
}

/// Mode parameters given as `MODE.KEY=VALUE` (`--param`, a config's
/// `params`), checked against the parameters the running modes declare.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModeParams {
    values: BTreeMap<String, String>,
}

impl ModeParams {
    pub fn parse(items: &[String], modes: &[&str]) -> Result<ModeParams, ModeError> {
        let mut values = BTreeMap::new();
        for item in items {
            let (key, value) = item
                .split_once('=')
                .filter(|(k, _)| k.contains('.'))
                .ok_or_else(|| ModeError::MalformedParam(item.clone()))?;
            let (mode, name) = key.split_once('.').expect("checked above");
            let info = MODES.iter().find(|m| m.name == mode && modes.contains(&m.name));
            if !info.is_some_and(|m| m.params.iter().any(|p| p.key == name)) {
                let known = match info {
                    Some(m) if m.params.is_empty() => format!("{mode} takes no parameters"),
                    Some(m) => {
                        let keys: Vec<String> = m.params.iter().map(|p| format!("{mode}.{}", p.key)).collect();
                        format!("{mode} takes {}", keys.join(", "))
                    }
                    None => format!("mode '{mode}' is not being run"),
                };
                return Err(ModeError::UnknownParam {
                    key: key.to_string(),
                    known,
                });
            }
            values.insert(key.to_string(), value.trim().to_string());
        }
        let params = ModeParams { values };
        // Parse every typed value now, so a bad one is reported before a
        // long scene load rather than after it.
        for mode in modes {
            match *mode {
                "omq" => drop(OmqParams::from_params(&params)?),
                "ac" => drop(AcParams::from_params(&params)?),
                "chc" => drop(ChcParams::from_params(&params)?),
                "ioc" => drop(IocParams::from_params(&params)?),
                "auto" => drop(AutoParams::from_params(&params)?),
                _ => {}
            }
        }
        Ok(params)
    }

    /// Whether `key` (`MODE.KEY`) was given a value.
    pub fn is_set(&self, key: &str) -> bool {
        self.values.contains_key(key)
    }

    /// These parameters with `key` (`MODE.KEY`) set to `value`.
    pub fn with(&self, key: &str, value: &str) -> ModeParams {
        let mut values = self.values.clone();
        values.insert(key.to_string(), value.to_string());
        ModeParams { values }
    }

    /// The value of `mode.key`: the one given, or the default `MODES`
    /// declares (the only place defaults are written).
    pub fn get<T: FromStr>(&self, mode: &str, key: &str) -> Result<T, ModeError>
    where
        T::Err: Display,
    {
        let full = format!("{mode}.{key}");
        let declared = MODES
            .iter()
            .find(|m| m.name == mode)
            .and_then(|m| m.params.iter().find(|p| p.key == key))
            .unwrap_or_else(|| panic!("{full} is not declared in MODES"));
        let value = self.values.get(&full).map_or(declared.default, String::as_str);
        value.parse().map_err(|e| ModeError::BadParam {
            key: full,
            reason: format!("'{value}': {e}"),
        })
    }
}

pub fn mode_names() -> Vec<&'static str> {
    MODES.iter().map(|m| m.name).collect()
}

/// Parses a comma-separated mode list (`all` for every mode); duplicates are
/// dropped, the order kept.
pub fn parse_modes(list: &[String]) -> Result<Vec<&'static str>, ModeError> {
    let mut modes: Vec<&'static str> = Vec::new();
    for name in list.iter().flat_map(|s| s.split(',')).map(str::trim) {
        let found: Vec<&'static str> = if name == "all" {
            mode_names()
        } else {
            vec![
                MODES
                    .iter()
                    .find(|m| m.name == name)
                    .ok_or_else(|| ModeError::Unknown(name.to_string()))?
                    .name,
            ]
        };
        for m in found {
            if !modes.contains(&m) {
                modes.push(m);
            }
        }
    }
    if modes.is_empty() {
        return Err(ModeError::Empty);
    }
    Ok(modes)
}

/// A culler run under another name: one value of a parameter sweep, e.g.
/// `ac[threshold=50]`.
pub struct Labeled {
    pub label: String,
    pub inner: Box<dyn Culler>,
}

impl Culler for Labeled {
    fn name(&self) -> &str {
        &self.label
    }
    fn parameters(&self) -> serde_json::Value {
        self.inner.parameters()
    }
    fn needs_reference(&self) -> bool {
        self.inner.needs_reference()
    }
    fn traverses_hierarchy(&self) -> bool {
        self.inner.traverses_hierarchy()
    }
    fn culls_on_gpu(&self) -> bool {
        self.inner.culls_on_gpu()
    }
    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats {
        self.inner.frame(ctx, input)
    }
}

/// Creates the culler of a mode named by [`parse_modes`]; scratch space is
/// sized for `scene`, which each frame then brings in [`FrameInput`].
pub fn create(name: &str, scene: &Scene, params: &ModeParams) -> Result<Box<dyn Culler>, ModeError> {
    Ok(match name {
        "dr" => Box::new(DirectRendering::new(scene)),
        "vfc" => Box::new(FrustumCulling::new(scene)),
        "sq" => Box::new(SingleQueries::new()),
        "omq" => Box::new(OccupancyMapQueries::new(OmqParams::from_params(params)?)),
        "ac" => Box::new(AdaptiveCulling::new(AcParams::from_params(params)?)),
        "chc" => Box::new(CoherentCulling::new(scene, ChcParams::from_params(params)?)),
        "roc" => Box::new(RasterOcclusionCulling::new()),
        "ioc" => Box::new(IterativeOcclusionCulling::new(IocParams::from_params(params)?)),
        "auto" => Box::new(AutoCulling::new(scene, AutoParams::from_params(params)?)),
        "oracle" => Box::new(Oracle::new()),
        other => return Err(ModeError::Unknown(other.to_string())),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_lists_parse_in_order_without_duplicates() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert_eq!(parse_modes(&s(&["vfc,dr", "vfc"])), Ok(vec!["vfc", "dr"]));
        assert_eq!(parse_modes(&s(&["all"])), Ok(mode_names()));
        assert_eq!(parse_modes(&s(&["dr,bogus"])), Err(ModeError::Unknown("bogus".into())));
        assert_eq!(parse_modes(&s(&[])), Err(ModeError::Empty));
        assert!(
            ModeError::Unknown("x".into())
                .to_string()
                .contains("dr, vfc, sq, omq, ac, chc, roc, ioc, auto, oracle")
        );
    }

    #[test]
    fn parameters_are_checked_against_the_running_modes() {
        let items = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let p = ModeParams::parse(&items(&["omq.om=80x60", "omq.factor=0.5"]), &["omq"]).unwrap();
        assert_eq!(p.get("omq", "factor"), Ok(0.5));
        assert_eq!(p.get("omq", "initial_max_tests"), Ok(4u32));
        let err = |v: &[&str], modes: &[&str]| ModeParams::parse(&items(v), modes).unwrap_err().to_string();
        assert!(err(&["omq.bogus=1"], &["omq"]).contains("omq takes omq.om, omq.initial_max_tests, omq.factor"));
        assert!(err(&["omq.om=1x1"], &["vfc"]).contains("'omq' is not being run"));
        assert!(err(&["vfc.x=1"], &["vfc"]).contains("vfc takes no parameters"));
        assert!(err(&["omq"], &["omq"]).contains("not MODE.KEY=VALUE"));
        assert!(
            err(&["omq.factor=fast"], &["omq"]).contains("'fast'"),
            "values are parsed up front"
        );
        assert!(err(&["omq.factor=-1"], &["omq"]).contains("positive"));
    }
}
