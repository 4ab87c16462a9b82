//! What the program knows of a mode without running it: its [`ModeId`]
//! and name, its entry ([`ModeInfo`]: summary, parameters, needs,
//! constructor), and the parameters a run gives it ([`ModeParams`]).

use std::collections::BTreeMap;
use std::fmt::Display;
use std::str::FromStr;

use super::culler::Culler;
use crate::gpu::GpuContext;
use crate::scene::Scene;

/// Declares [`ModeId`] from `mode_table!`'s lines (cull/mod.rs): the enum,
/// [`ModeId::ALL`] and [`ModeId::name`].
macro_rules! declare_mode_ids {
    ($($id:ident => $name:literal, $($module:ident)::+;)*) => {
        /// Every mode, in the order `all` runs them and `--help` lists them;
        /// each one's entry (what it does, needs and takes) is declared in
        /// its own file, and found by [`ModeId::info`] (registry.rs).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum ModeId {
            $($id,)*
        }

        impl ModeId {
            pub const ALL: &[ModeId] = &[$(ModeId::$id),*];

            /// The mode's name on the command line and in result files.
            pub fn name(self) -> &'static str {
                match self {
                    $(ModeId::$id => $name,)*
                }
            }
        }
    };
}

mode_table!(declare_mode_ids);

impl Display for ModeId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl ModeId {
    /// The mode a summary's name is of: a mode's name, or a sweep's label
    /// of one (`ac[f_graphics=0.5]`).
    pub fn of_label(label: &str) -> Option<ModeId> {
        label.split('[').next()?.parse().ok()
    }

    /// Whether a summary's count `what` of the mode labelled `label`
    /// follows the times it measured ([`ModeInfo::draws_by_time`]): the
    /// work it did (triangles, round trips), and, for a mode that is not
    /// conservative, its error too (where its budget ran out decides what
    /// it drew wrong).
    pub fn counts_follow_time(label: &str, what: CountKind) -> bool {
        ModeId::of_label(label).is_some_and(|m| {
            let info = m.info();
            info.draws_by_time && (what == CountKind::Work || !info.conservative)
        })
    }

    /// Whether the mode labelled `label` culls on the GPU alone: where the
    /// adapter has no indirect counts, it reads its lists' lengths back, a
    /// round trip a frame.
    pub fn walks_on_gpu(label: &str) -> bool {
        ModeId::of_label(label).is_some_and(|m| m.info().needs == Needs::GpuCulling)
    }
}

/// What a summary's count measures: the work a mode did, or its error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CountKind {
    Work,
    Error,
}

impl FromStr for ModeId {
    type Err = ModeError;

    fn from_str(name: &str) -> Result<ModeId, ModeError> {
        ModeId::ALL
            .iter()
            .copied()
            .find(|m| m.name() == name)
            .ok_or_else(|| ModeError::Unknown(name.to_string()))
    }
}

/// A mode's registry entry: all the rest of the program knows of it.
pub struct ModeInfo {
    pub id: ModeId,
    pub summary: &'static str,
    /// The colour (sRGB) its lines and bars keep in every chart.
    pub chart_colour: [u8; 3],
    /// Whether the mode may never change a pixel (0 error required).
    pub conservative: bool,
    /// Whether what it draws and tests follows times it measures (a
    /// budget of the previous frame's drawing, a strategy chosen by frame
    /// times, a buffer that rests where it did not pay), so that its
    /// counters vary from run to run as the machine's times do
    /// ([`ModeId::counts_follow_time`]): `compare` judges them as it judges
    /// frame times, and `merge` does not cross-check them between
    /// adapters.
    pub draws_by_time: bool,
    /// Parameters it takes as `--param NAME.KEY=VALUE`.
    pub params: &'static [ParamInfo],
    /// Values (key, value) of its parameters under which every frame
    /// exercises its culling, where its defaults let it skip some (`swr`'s
    /// buffer rests where it does not pay): what `occlu stress` and the
    /// exactness tests run it with ([`ModeParams::exercising_every_frame`]).
    pub exercised_with: &'static [(&'static str, &'static str)],
    /// What it needs from the adapter beyond drawing and occlusion queries;
    /// a mode whose needs are not met is skipped, with a message.
    pub needs: Needs,
    /// What it carries from one frame to the next, which `auto` hands over
    /// when it switches to it.
    pub carries: Carries,
    /// Whether `auto` may run it.
    pub auto: Candidacy,
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

/// What a mode carries from one frame to the next that decides what it
/// draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Carries {
    /// Nothing: every frame decides afresh.
    Nothing,
    /// Last frame's visible objects, on the CPU, as occluders: another
    /// culler's can be handed to it ([`Culler::seed_visible`]), and it
    /// draws only what its own test passes, so a larger set gives it more
    /// occluders, not more to draw.
    OccludersOnCpu,
    /// Last frame's visible objects, on the CPU, drawn before anything is
    /// tested: another culler's can be handed to it
    /// ([`Culler::seed_visible`]), and it draws all it is handed.
    VisibleOnCpu,
    /// Last frame's visible objects, on the GPU, in lists that other GPU
    /// walks can share ([`Culler::share_visible_lists`]).
    VisibleOnGpu,
    /// State of its own that another culler's cannot stand in for.
    OwnState,
}

/// Whether `auto` may run a mode: only conservative modes that can be the
/// cheapest on some adapter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Candidacy {
    /// Never: it is not conservative, or another candidate does the same
    /// work for less on every adapter (dr draws what vfc draws and more; sq
    /// waits for every query that omq batches), or it is no culler (the
    /// oracle, auto).
    Never,
    /// On every adapter that meets its needs: which candidate is cheapest
    /// there is measured, not assumed (a GPU walk tests without waiting
    /// for results, yet on a dense scan in 16 clusters, where omq's
    /// Occupancy Map tests a third of the boxes, each GPU walk took 1.08 to
    /// 1.31 times omq's frame on lavapipe and llvmpipe, in two runs on each).
    Always,
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
    #[error("unknown mode '{0}' (modes: {list}, or all)", list = ModeId::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "))]
    Unknown(String),
    #[error("no modes given")]
    Empty,
    #[error("'{0}' names more than one mode, and render draws one (e.g. --mode roc)")]
    NotOne(String),
    #[error("parameter '{0}' is not MODE.KEY=VALUE")]
    MalformedParam(String),
    #[error("parameter '{0}' is given twice")]
    RepeatedParam(String),
    #[error("unknown parameter '{key}' ({known})")]
    UnknownParam { key: String, known: String },
    #[error("parameter '{key}': {reason}")]
    BadParam { key: String, reason: String },
}

impl ModeError {
    /// `param` of `mode` has a value the mode cannot take, for `reason`.
    pub fn bad(mode: ModeId, param: &ParamInfo, reason: String) -> ModeError {
        ModeError::BadParam {
            key: format!("{mode}.{}", param.key),
            reason,
        }
    }
}

/// Mode parameters given as `MODE.KEY=VALUE` (`--param`, a config's
/// `params`), checked against the parameters the running modes declare.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModeParams {
    pub(super) values: BTreeMap<String, String>,
}

impl ModeParams {
    /// Whether `key` (`MODE.KEY`) was given a value.
    pub fn is_set(&self, key: &str) -> bool {
        self.values.contains_key(key)
    }

    /// Every parameter set, as `MODE.KEY` and value, in key order.
    pub fn entries(&self) -> impl Iterator<Item = (&str, &str)> {
        self.values.iter().map(|(key, value)| (key.as_str(), value.as_str()))
    }

    /// The parameters given for `mode`, as `MODE.KEY` and value.
    pub fn given_for(&self, mode: ModeId) -> impl Iterator<Item = (&str, &str)> {
        let prefix = format!("{mode}.");
        self.entries().filter(move |(key, _)| key.starts_with(&prefix))
    }

    /// These parameters with `over`'s set over them, key by key.
    pub fn overridden_by(&self, over: &ModeParams) -> ModeParams {
        let mut values = self.values.clone();
        values.extend(over.values.iter().map(|(k, v)| (k.clone(), v.clone())));
        ModeParams { values }
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
        let given = self.values.get(&format!("{mode}.{}", param.key));
        let value = given.map_or(param.default, String::as_str);
        value
            .parse()
            .map_err(|e| ModeError::bad(mode, param, format!("'{value}': {e}")))
    }
}
