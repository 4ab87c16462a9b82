//! Culling modes: one file per mode, each behind the [`Culler`] trait.
//!
//! A mode owns its state between frames (temporal coherence lives inside the
//! mode) and touches the GPU only through [`FrameCtx`], which counts what it
//! draws and queries. To add a mode: write `cull/NAME.rs` implementing
//! [`Culler`] and declaring its registry entry (`MODE`: name, summary,
//! parameters, needs, constructor), and name it in [`ModeId`].

mod ac;
mod auto;
mod chc;
mod dr;
pub mod gpu_walk;
pub mod occupancy;
mod omq;
mod oracle;
mod sq;
pub mod traversal;
mod vfc;

use std::collections::BTreeMap;
use std::fmt::Display;
use std::str::FromStr;
use std::time::Duration;

use crate::camera::Camera;
use crate::gpu::{FrameCtx, GpuAudit, GpuContext, GpuSetup, Resolution};
use crate::hierarchy::Hierarchy;
use crate::object_set::ObjectSet;
use crate::scene::Scene;

pub use ac::{AcParams, AdaptiveCulling, EyeDistance, Threshold};
pub use auto::{AutoCulling, AutoParams};
pub use chc::{ChcParams, CoherentCulling};
pub use dr::DirectRendering;
pub use gpu_walk::ioc::{Depth, IocParams, IterativeOcclusionCulling};
pub use gpu_walk::roc::RasterOcclusionCulling;
pub use omq::{OccupancyMapQueries, OmqParams};
pub use oracle::Oracle;
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

    /// Creates the mode's own GPU resources (pipelines, buffers), once,
    /// untimed, before its first frame. Modes that only draw and test boxes
    /// through [`FrameCtx`] have none.
    fn prepare(&mut self, _setup: &GpuSetup) {}

    /// After each frame, untimed: what the mode's own GPU work drew and
    /// tested, read back from the GPU, with what it drew added to `drawn`
    /// (`None` when it did none this frame).
    fn audit(&mut self, _gpu: &GpuContext, _drawn: &mut ObjectSet) -> Option<GpuAudit> {
        None
    }

    /// Renders one frame: decides what to draw and draws it through `ctx`.
    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats;
}

/// Every mode, in the order `all` runs them and `--help` lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModeId {
    Dr,
    Vfc,
    Sq,
    Omq,
    Ac,
    Chc,
    Roc,
    Ioc,
    Auto,
    Oracle,
}

impl ModeId {
    pub const ALL: [ModeId; 10] = [
        ModeId::Dr,
        ModeId::Vfc,
        ModeId::Sq,
        ModeId::Omq,
        ModeId::Ac,
        ModeId::Chc,
        ModeId::Roc,
        ModeId::Ioc,
        ModeId::Auto,
        ModeId::Oracle,
    ];

    /// The mode's registry entry, declared in its own file.
    pub fn info(self) -> &'static ModeInfo {
        match self {
            ModeId::Dr => &dr::MODE,
            ModeId::Vfc => &vfc::MODE,
            ModeId::Sq => &sq::MODE,
            ModeId::Omq => &omq::MODE,
            ModeId::Ac => &ac::MODE,
            ModeId::Chc => &chc::MODE,
            ModeId::Roc => &gpu_walk::roc::MODE,
            ModeId::Ioc => &gpu_walk::ioc::MODE,
            ModeId::Auto => &auto::MODE,
            ModeId::Oracle => &oracle::MODE,
        }
    }

    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The mode's culler; scratch space is sized for `scene`, which each
    /// frame then brings in [`FrameInput`].
    pub fn create(self, scene: &Scene, params: &ModeParams) -> Result<Box<dyn Culler>, ModeError> {
        (self.info().build)(scene, params)
    }
}

impl Display for ModeId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModeId {
    type Err = ModeError;

    fn from_str(name: &str) -> Result<ModeId, ModeError> {
        ModeId::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| ModeError::Unknown(name.to_string()))
    }
}

/// A mode's registry entry: all the rest of the program knows of it.
pub struct ModeInfo {
    pub id: ModeId,
    /// The mode's name on the command line and in result files.
    pub name: &'static str,
    pub summary: &'static str,
    /// Whether the mode may never change a pixel (0 error required).
    pub conservative: bool,
    /// Parameters it takes as `--param NAME.KEY=VALUE`.
    pub params: &'static [ParamInfo],
    /// What it needs from the adapter beyond drawing and occlusion queries;
    /// a mode whose needs are not met is skipped, with a message.
    pub needs: Needs,
    /// Parses the mode's parameters, so a bad value is reported before any
    /// work.
    pub check: fn(&ModeParams) -> Result<(), ModeError>,
    /// Creates the mode's culler (see [`ModeId::create`]).
    pub build: BuildCuller,
}

/// A mode's constructor: its culler for a scene, with its parameters.
pub type BuildCuller = fn(&Scene, &ModeParams) -> Result<Box<dyn Culler>, ModeError>;

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
    /// The parameter called `key`, if the mode declares one.
    pub fn param(&self, key: &str) -> Option<&'static ParamInfo> {
        self.params.iter().find(|p| p.key == key)
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

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ModeError {
    #[error("unknown mode '{0}' (modes: {list}, or all)", list = ModeId::ALL.map(ModeId::name).join(", "))]
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
    pub fn parse(items: &[String], modes: &[ModeId]) -> Result<ModeParams, ModeError> {
        let mut values = BTreeMap::new();
        for item in items {
            let (key, value) = item
                .split_once('=')
                .filter(|(k, _)| k.contains('.'))
                .ok_or_else(|| ModeError::MalformedParam(item.clone()))?;
            let (mode, name) = key.split_once('.').unwrap_or((key, ""));
            let info = mode
                .parse::<ModeId>()
                .ok()
                .filter(|m| modes.contains(m))
                .map(ModeId::info);
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
            (mode.info().check)(&params)?;
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

    /// The value of `param` of `mode`: the one given, or the default its
    /// declaration holds (the only place defaults are written).
    pub fn get<T: FromStr>(&self, mode: ModeId, param: &ParamInfo) -> Result<T, ModeError>
    where
        T::Err: Display,
    {
        let full = format!("{mode}.{}", param.key);
        let value = self.values.get(&full).map_or(param.default, String::as_str);
        value.parse().map_err(|e| ModeError::BadParam {
            key: full,
            reason: format!("'{value}': {e}"),
        })
    }
}

/// Every mode's registry entry, in [`ModeId::ALL`]'s order.
pub fn modes() -> impl Iterator<Item = &'static ModeInfo> {
    ModeId::ALL.into_iter().map(ModeId::info)
}

/// The culler of the mode called `name` (see [`ModeId::create`]).
pub fn create(name: &str, scene: &Scene, params: &ModeParams) -> Result<Box<dyn Culler>, ModeError> {
    name.parse::<ModeId>()?.create(scene, params)
}

/// Parses a comma-separated mode list (`all` for every mode); duplicates are
/// dropped, the order kept.
pub fn parse_modes(list: &[String]) -> Result<Vec<ModeId>, ModeError> {
    let mut modes: Vec<ModeId> = Vec::new();
    for name in list.iter().flat_map(|s| s.split(',')).map(str::trim) {
        let found = if name == "all" {
            ModeId::ALL.to_vec()
        } else {
            vec![name.parse()?]
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
    fn prepare(&mut self, setup: &GpuSetup) {
        self.inner.prepare(setup)
    }
    fn audit(&mut self, gpu: &GpuContext, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        self.inner.audit(gpu, drawn)
    }
    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats {
        self.inner.frame(ctx, input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_is_its_own_and_its_defaults_parse() {
        for id in ModeId::ALL {
            assert_eq!(id.info().id, id, "{id}'s entry names another mode");
            assert_eq!(id.name().parse::<ModeId>(), Ok(id));
            assert_eq!((id.info().check)(&ModeParams::default()), Ok(()), "{id}'s defaults");
            for p in id.info().params {
                assert_eq!(id.info().param(p.key).map(|q| q.default), Some(p.default));
            }
        }
        let mut names: Vec<&str> = ModeId::ALL.map(ModeId::name).to_vec();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), ModeId::ALL.len(), "names are unique");
    }

    #[test]
    fn mode_lists_parse_in_order_without_duplicates() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert_eq!(parse_modes(&s(&["vfc,dr", "vfc"])), Ok(vec![ModeId::Vfc, ModeId::Dr]));
        assert_eq!(parse_modes(&s(&["all"])), Ok(ModeId::ALL.to_vec()));
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
        let p = ModeParams::parse(&items(&["omq.om=80x60", "omq.factor=0.5"]), &[ModeId::Omq]).unwrap();
        assert_eq!(p.get(ModeId::Omq, ModeId::Omq.info().param("factor").unwrap()), Ok(0.5));
        assert_eq!(
            p.get(ModeId::Omq, ModeId::Omq.info().param("initial_max_tests").unwrap()),
            Ok(4u32)
        );
        let err = |v: &[&str], modes: &[ModeId]| ModeParams::parse(&items(v), modes).unwrap_err().to_string();
        assert!(err(&["omq.bogus=1"], &[ModeId::Omq]).contains("omq takes omq.om, omq.initial_max_tests, omq.factor"));
        assert!(err(&["omq.om=1x1"], &[ModeId::Vfc]).contains("'omq' is not being run"));
        assert!(err(&["vfc.x=1"], &[ModeId::Vfc]).contains("vfc takes no parameters"));
        assert!(err(&["omq"], &[ModeId::Omq]).contains("not MODE.KEY=VALUE"));
        assert!(
            err(&["omq.factor=fast"], &[ModeId::Omq]).contains("'fast'"),
            "values are parsed up front"
        );
        assert!(err(&["omq.factor=-1"], &[ModeId::Omq]).contains("positive"));
    }
}
