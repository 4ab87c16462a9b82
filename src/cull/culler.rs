//! The [`Culler`] trait every mode implements, what it is told each frame
//! ([`FrameInput`]) and what it reports ([`TraversalStats`]).

use std::rc::Rc;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::gpu_walk::VisibleLists;
use crate::camera::Camera;
use crate::gpu::{Frame, GpuAudit, GpuContext, GpuError, GpuSetup, Resolution};
use crate::hierarchy::Hierarchy;
use crate::object_set::ObjectSet;
use crate::scene::Scene;

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
    /// A warm-up frame: run, not recorded. A mode that runs others (`auto`)
    /// runs each of them in it, so their first frames (pipelines compiled
    /// on first use, buffers first filled) are not among the recorded ones.
    pub warm_up: bool,
}

/// A mode's own previous frame, as measured (cost-adaptive culling budgets
/// from it, 002 Eq. 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviousFrame {
    pub frame_ms: f64,
    /// Time spent drawing: GPU time outside box tests where timestamps
    /// exist, else the frame minus culling CPU time and waits for results.
    pub render_ms: f64,
    pub triangles_drawn: u64,
}

/// Which of its strategies a mode that runs others (`auto`) ran in a frame:
/// frames.csv's `strategy` and `probe` columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pick {
    /// The mode that drew the frame.
    pub strategy: &'static str,
    /// Whether it ran to be measured rather than because it was cheapest.
    pub probe: bool,
}

/// Declares [`TraversalStats`] from its counters, once: the struct, and
/// each counter's name (its frames.csv column and summary.json key) and
/// value in order. Adding a counter is a line here and the mode that counts
/// it; `FrameStats`, the result files and `compare` pick it up by name.
macro_rules! traversal_stats {
    ($($(#[$doc:meta])* $counter:ident,)*) => {
        /// What a mode counted in one frame besides drawing (which the
        /// [`crate::gpu::Frame`] it draws through counts).
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
        pub struct TraversalStats {
            $($(#[$doc])* #[serde(default)] pub $counter: u64,)*
            /// Time spent keeping the mode's own spatial structure current
            /// with moved objects (part of its CPU time; frames.csv's
            /// `maintenance_ms` with the shared hierarchy's refit).
            #[serde(skip)]
            pub maintenance: Duration,
        }

        impl TraversalStats {
            /// Every counter's name, in order.
            pub const COUNTERS: &[&str] = &[$(stringify!($counter)),*];

            /// Every counter's value, in [`TraversalStats::COUNTERS`]' order.
            pub fn counts(&self) -> impl Iterator<Item = u64> {
                [$(self.$counter),*].into_iter()
            }
        }
    };
}

traversal_stats! {
    /// Nodes reached.
    nodes_visited,
    /// Nodes outside the frustum.
    nodes_culled_frustum,
    /// Nodes found hidden by a test.
    nodes_culled_occlusion,
    /// Queries made unnecessary (the Occupancy Map's empty-area rule, or
    /// coherent culling's nodes visible in the last frame).
    queries_skipped,
    /// Queries held back because a nearer query in flight covered part of
    /// their screen rectangle (coherent culling, 001 §3.5).
    queries_delayed,
    /// Nodes visible but treated as occluded for their small contribution
    /// (adaptive culling, 002 Eq. 1).
    nodes_culled_adaptive,
    /// Nodes left when the culling budget ran out, only frustum-culled and
    /// drawn (cost-adaptive culling, 002 Eq. 2).
    nodes_past_budget,
    /// Objects a GPU walk drew first, as last frame's visible list (the
    /// early pass of two-phase culling).
    drawn_early,
    /// Objects a GPU walk drew after its test, newly visible (the late
    /// pass).
    drawn_late,
    /// Occluder triangles a CPU occlusion buffer rasterised.
    occluder_triangles,
}

impl TraversalStats {
    /// Adds the nodes a GPU-driven walk visited, found outside the frustum
    /// and found hidden, and the objects it drew before and after its test.
    pub fn add_gpu_audit(&mut self, audit: &GpuAudit) {
        self.nodes_visited += audit.nodes_visited;
        self.nodes_culled_frustum += audit.nodes_outside_frustum;
        self.nodes_culled_occlusion += audit.nodes_hidden;
        self.drawn_early += audit.drawn_early;
        self.drawn_late += audit.drawn_late;
    }
}

/// A depth buffer a mode keeps on the CPU (a CPU occlusion buffer), as it
/// stood when the mode last culled, pixel by pixel of the render target,
/// row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct OccluderDepths {
    pub width: u32,
    pub height: u32,
    /// The reverse-Z depth the buffer vouches for at each pixel (its cell's
    /// reference depth, or its working layer's where that covers the
    /// pixel and lies nearer), 0 where no occluder wrote one.
    pub depths: Vec<f32>,
    /// Pixels whose depth is the working layer's (MOC's): occluders cover
    /// them in only part of their cell, so that depth is vouched for only
    /// at these pixels; elsewhere in the cell the reference holds.
    pub partial: Vec<bool>,
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
    /// untimed, before its first frame; fails when the adapter cannot hold
    /// them at this size. Modes that only draw and test boxes through
    /// [`crate::gpu::Frame`] have none.
    fn prepare(&mut self, _setup: &GpuSetup) -> Result<(), GpuError> {
        Ok(())
    }

    /// After each frame (`input`), untimed: what the mode's own GPU work
    /// drew and tested, read back from the GPU, with what it drew added to
    /// `drawn` (`None` when it did none this frame).
    fn audit(&mut self, _gpu: &GpuContext, _input: &FrameInput, _drawn: &mut ObjectSet) -> Option<GpuAudit> {
        None
    }

    /// Renders one frame: decides what to draw and draws it through `ctx`.
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats;

    /// The depth buffer the mode culled its last frame with, for modes that
    /// keep one on the CPU (`occlu render --occluders`).
    fn occluder_depths(&self) -> Option<OccluderDepths> {
        None
    }

    /// Before a frame: the objects (ids of the frame's scene) another culler
    /// drew last frame, for a mode that starts from last frame's visible
    /// objects (as occluders, or drawn first) and did not run then (`auto`
    /// hands them to the culler it probes). Modes that keep no such list
    /// ignore them.
    fn seed_visible(&mut self, _visible: &[u32]) {}

    /// Before `prepare`: keep the visible set between frames in `lists`,
    /// which other GPU walks share (`auto` gives one to every walk it runs,
    /// so each starts where the last one ended). Modes that keep no visible
    /// set on the GPU ignore them.
    fn share_visible_lists(&mut self, _lists: &Rc<VisibleLists>) {}

    /// After a frame, for a mode that runs others: which ran.
    fn pick(&self) -> Option<Pick> {
        None
    }
    /// After a frame of an occlusion culler: whether it was frustum
    /// culling's own, everything in the frustum drawn and nothing tested
    /// for occlusion (`swr` while its buffer rests). `auto` takes such a
    /// frame as `vfc`'s: it says nothing of what occlusion hides, and what
    /// it drew is the whole frustum.
    fn frustum_only(&self) -> bool {
        false
    }
}

/// A borrowed culler runs as the culler it borrows (so a test can keep the
/// mode it hands to a session).
impl<C: Culler + ?Sized> Culler for &mut C {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn parameters(&self) -> serde_json::Value {
        (**self).parameters()
    }
    fn needs_reference(&self) -> bool {
        (**self).needs_reference()
    }
    fn traverses_hierarchy(&self) -> bool {
        (**self).traverses_hierarchy()
    }
    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        (**self).prepare(setup)
    }
    fn audit(&mut self, gpu: &GpuContext, input: &FrameInput, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        (**self).audit(gpu, input, drawn)
    }
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        (**self).frame(ctx, input)
    }
    fn occluder_depths(&self) -> Option<OccluderDepths> {
        (**self).occluder_depths()
    }
    fn seed_visible(&mut self, visible: &[u32]) {
        (**self).seed_visible(visible)
    }
    fn share_visible_lists(&mut self, lists: &Rc<VisibleLists>) {
        (**self).share_visible_lists(lists)
    }
    fn pick(&self) -> Option<Pick> {
        (**self).pick()
    }
    fn frustum_only(&self) -> bool {
        (**self).frustum_only()
    }
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
    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        self.inner.prepare(setup)
    }
    fn audit(&mut self, gpu: &GpuContext, input: &FrameInput, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        self.inner.audit(gpu, input, drawn)
    }
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        self.inner.frame(ctx, input)
    }
    fn occluder_depths(&self) -> Option<OccluderDepths> {
        self.inner.occluder_depths()
    }
    fn seed_visible(&mut self, visible: &[u32]) {
        self.inner.seed_visible(visible)
    }
    fn share_visible_lists(&mut self, lists: &Rc<VisibleLists>) {
        self.inner.share_visible_lists(lists)
    }
    fn pick(&self) -> Option<Pick> {
        self.inner.pick()
    }
    fn frustum_only(&self) -> bool {
        self.inner.frustum_only()
    }
}
