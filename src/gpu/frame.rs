//! [`FrameCtx`]: the operations a culling mode may perform on the GPU during
//! one timed frame: draw objects, test boxes against what is drawn, and, for
//! modes with GPU work of their own (the GPU walk), record it into the
//! frame, read results back, and draw commands the GPU built.
//! Every mode goes through these operations, which do the counting
//! themselves, so no mode can draw or query without paying for it or report
//! its own figures.

use std::time::{Duration, Instant};

use super::conservative::BoxMargins;
use super::context::GpuContext;
use super::queries::{BatchAnswers, BoxTest, BoxVisibility, QueryPool, TestTarget};
use super::renderer::DrawRange;
use super::renderer::{Draws, IndirectDraws, SceneRenderer};
use super::resolution::Resolution;
use super::targets::RenderTargets;
use super::timing::{GpuSpan, GpuTimer};
use crate::bounds::Aabb;
use crate::camera::Camera;
use crate::hierarchy::Hierarchy;
use crate::object_set::ObjectSet;
use crate::scene::Scene;

/// What a mode did on the GPU in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameCounters {
    /// Draw calls (an object drawn twice counts twice).
    pub objects_drawn: u64,
    pub triangles_drawn: u64,
    /// Occlusion queries issued.
    pub queries: u64,
    /// Query batches: GPU→CPU round trips.
    pub query_batches: u64,
    /// Time spent waiting for query results.
    pub query_wait: Duration,
    /// GPU time of the query passes (timestamps), where the adapter has them.
    pub query_gpu: Option<Duration>,
    /// Of that, building a depth pyramid to test against.
    pub pyramid_gpu: Option<Duration>,
}

/// Result of a finished frame.
pub struct FrameOutcome {
    pub counters: FrameCounters,
    /// Time the mode spent inside `FrameCtx` operations (encoding, submitting,
    /// waiting for results), excluded from its CPU culling time. Preparing
    /// boxes for a test is culling, and not part of it.
    pub gpu_ops: Duration,
}

/// What the CPU did during a GPU operation of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpKind {
    /// Encoding and submitting commands.
    Commands,
    /// Waiting for results on the CPU: a batch of box tests (and reading
    /// them out), or a mode's own read-back.
    WaitForResults,
    /// Waiting for the GPU to finish the frame.
    WaitForGpu,
}

/// A stretch of a frame the CPU spent in a GPU operation, on its own clock:
/// the frame's timeline ([`crate::measure::FrameTimeline`]) is made from
/// these, the gaps between them inside the mode's `frame` call being its
/// culling.
#[derive(Clone, Copy, Debug)]
pub struct OpSpan {
    pub kind: OpKind,
    pub start: Instant,
    pub end: Instant,
    /// For a wait for box tests, where the tests ran on the GPU (timestamps).
    pub tests: Option<GpuSpan>,
}

/// What a mode's own GPU work drew and tested in a frame, read back after
/// it, untimed ([`crate::cull::Culler::audit`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuAudit {
    pub triangles_drawn: u64,
    /// Nodes the walk reached.
    pub nodes_visited: u64,
    /// Of those, boxes drawn into the visibility buffer (the others were
    /// outside the frustum or reached the near plane).
    pub nodes_tested: u64,
    /// Tested and hidden.
    pub nodes_hidden: u64,
    pub nodes_outside_frustum: u64,
    /// Objects drawn first, as last frame's visible list, and after the
    /// walk, newly visible: every object the walk drew.
    pub drawn_early: u64,
    pub drawn_late: u64,
    /// The walk and the compaction on the GPU, where timestamps exist.
    pub cull_gpu: Option<GpuSpan>,
    /// Within it, the depth pyramid's build, for a walk that tests
    /// against one.
    pub pyramid_gpu: Option<GpuSpan>,
}

impl FrameOutcome {
    /// Adds what a mode's own GPU work drew and tested (each node box drawn
    /// into the visibility buffer counts as a query); its node counts go to
    /// the mode's traversal figures (`TraversalStats::add_gpu_audit`).
    pub fn add_gpu_audit(&mut self, audit: &GpuAudit) {
        let c = &mut self.counters;
        c.objects_drawn += audit.drawn_early + audit.drawn_late;
        c.triangles_drawn += audit.triangles_drawn;
        c.queries += audit.nodes_tested;
        if let Some(t) = audit.cull_gpu {
            *c.query_gpu.get_or_insert(Duration::ZERO) += t.duration();
        }
        if let Some(t) = audit.pyramid_gpu {
            *c.pyramid_gpu.get_or_insert(Duration::ZERO) += t.duration();
        }
    }
}

/// What a mode creates its own GPU resources from, once, before its first
/// frame ([`crate::cull::Culler::prepare`]).
pub struct GpuSetup<'a> {
    pub gpu: &'a GpuContext,
    /// The camera uniform the scene renderer fills every frame.
    pub camera: &'a wgpu::Buffer,
    /// Every object's index range, in object order.
    pub draws: &'a [DrawRange],
    /// The scene and hierarchy as the session starts (movers where the
    /// scene put them, before any frame poses them).
    pub scene: &'a Scene,
    pub hierarchy: &'a Hierarchy,
    /// The mode's own depth target, which its frames draw into, and its
    /// size.
    pub depth: &'a wgpu::TextureView,
    pub resolution: Resolution,
}

/// A mode's own GPU work, recorded into its frame by [`FrameCtx::record`].
pub struct GpuWork<'e> {
    pub gpu: &'e GpuContext,
    /// The frame's encoder, after every draw so far.
    pub encoder: &'e mut wgpu::CommandEncoder,
    /// This mode's depth target.
    pub depth: &'e wgpu::TextureView,
}

/// What a mode does in a frame: draw objects and test boxes against what
/// is drawn. [`FrameCtx`] does it on the GPU and counts it; unit tests of a
/// mode's logic give it a double that records the calls and answers the
/// tests from a rule.
pub trait Frame {
    /// Draws `objects`, shaded. Every draw is on the depth buffer before
    /// any later test.
    fn draw(&mut self, objects: &[u32]);

    /// Tests `boxes` as one batch against the depth drawn so far, one round
    /// trip: one result per box in `out`; a box that reaches the near plane
    /// is visible untested.
    fn test_boxes(&mut self, boxes: &[Aabb], kind: BoxTest, out: &mut Vec<BoxVisibility>);

    /// [`Frame::test_boxes`] by pixel counts that also counts the pixels
    /// each box covers in all (001 §3.3's additional query), in the same
    /// round trip; `totals` gets 0 for a box not tested. Needs
    /// [`GpuContext::pixel_counts`].
    fn test_boxes_with_totals(
        &mut self,
        boxes: &[Aabb],
        sampling: u32,
        out: &mut Vec<BoxVisibility>,
        totals: &mut Vec<u64>,
    );

    /// The frame on the GPU, for a mode with GPU work of its own; `None`
    /// where there is no GPU (a test double).
    fn on_gpu(&mut self) -> Option<&mut dyn GpuFrame>;
}

/// The GPU operations of a frame, for modes with GPU work of their own;
/// each is counted like the rest.
pub trait GpuFrame {
    /// The adapter, for what it can do.
    fn gpu(&self) -> &GpuContext;

    /// The margins this frame's box tests keep (for boxes a mode prepares
    /// itself).
    fn margins(&self) -> BoxMargins;

    /// Records a mode's own GPU work into the frame, after everything drawn
    /// so far. Its time is GPU operations, not culling. `work` only records:
    /// reading results back is [`GpuFrame::round_trip`], which counts it.
    fn record(&mut self, work: &mut dyn FnMut(GpuWork));

    /// Submits everything recorded so far and hands `read` a fresh encoder
    /// to copy results from and submit, then wait for: one round trip, its
    /// time counted as waiting for results.
    fn round_trip(&mut self, read: &mut dyn FnMut(&GpuContext, wgpu::CommandEncoder));

    /// Draws, shaded, the commands the GPU built. What they drew is counted
    /// after the frame, from the mode's audit.
    fn draw_indirect(&mut self, draws: IndirectDraws);

    /// Submits everything recorded so far and waits until the GPU has
    /// finished it: the time to here is then what the frame so far cost.
    fn wait_for_gpu(&mut self);

    /// Clears colour and depth, as at the start of the frame, so that
    /// another strategy can render the frame from nothing (what was drawn
    /// stays counted).
    fn clear(&mut self);
}

pub struct FrameCtx<'a> {
    gpu: &'a GpuContext,
    renderer: &'a SceneRenderer,
    targets: &'a RenderTargets,
    queries: &'a mut QueryPool,
    camera: &'a Camera,
    /// What this frame's box tests stay clear of.
    margins: BoxMargins,
    depth: &'a wgpu::TextureView,
    timer: Option<(&'a GpuTimer, usize)>,
    encoder: wgpu::CommandEncoder,
    /// Objects drawn but not yet encoded: they are encoded as one pass,
    /// nearest first, before the next query batch or at the end of the
    /// frame.
    queued: &'a mut Vec<u32>,
    counters: FrameCounters,
    drawn: &'a mut ObjectSet,
    gpu_ops: Duration,
    ops: &'a mut Vec<OpSpan>,
}

/// Everything a frame of one mode renders with.
pub struct FrameResources<'a> {
    pub gpu: &'a GpuContext,
    pub renderer: &'a SceneRenderer,
    pub targets: &'a RenderTargets,
    pub queries: &'a mut QueryPool,
    pub timer: Option<&'a GpuTimer>,
    /// Scratch for queued draws, reused from frame to frame.
    pub draw_queue: &'a mut Vec<u32>,
    /// Where the frame's GPU operations are logged, cleared first.
    pub ops: &'a mut Vec<OpSpan>,
}

impl<'a> FrameCtx<'a> {
    /// Starts the frame of mode `slot` (its own depth target and timer
    /// span) and clears its targets.
    pub(crate) fn begin(
        resources: FrameResources<'a>,
        slot: usize,
        camera: &'a Camera,
        drawn: &'a mut ObjectSet,
    ) -> FrameCtx<'a> {
        let start = Instant::now();
        let FrameResources {
            gpu,
            renderer,
            targets,
            queries,
            timer,
            draw_queue: queued,
            ops,
        } = resources;
        drawn.clear();
        queued.clear();
        ops.clear();
        let depth = &targets.mode_depths[slot];
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        if let Some(t) = timer {
            t.begin(&mut encoder, slot);
        }
        encode_clear(renderer, &mut encoder, targets, depth);
        log(ops, OpKind::Commands, start, Instant::now());
        FrameCtx {
            gpu,
            renderer,
            targets,
            queries,
            camera,
            margins: BoxMargins::new(gpu.depth_margins, gpu.subpixel, camera, targets.resolution),
            depth,
            timer: timer.map(|t| (t, slot)),
            encoder,
            queued,
            counters: FrameCounters::default(),
            drawn,
            gpu_ops: Duration::ZERO,
            ops,
        }
    }

    fn test(&mut self, boxes: &[Aabb], kind: BoxTest, out: &mut Vec<BoxVisibility>, totals: Option<&mut Vec<u64>>) {
        let start = Instant::now();
        let encoder = self.take_recorded();
        let target = TestTarget {
            depth: self.depth,
            camera: self.camera,
            margins: self.margins,
        };
        let answers = BatchAnswers {
            visibility: out,
            totals,
        };
        let tested = Instant::now();
        let cost = self.queries.test(self.gpu, encoder, target, boxes, kind, answers);
        let end = Instant::now();
        if cost.queries > 0 {
            self.counters.queries += cost.queries;
            self.counters.query_batches += 1;
            self.counters.query_wait += cost.wait;
            if let Some(gpu) = cost.gpu {
                *self.counters.query_gpu.get_or_insert(Duration::ZERO) += gpu.duration();
            }
        }
        self.gpu_ops += (end - start).saturating_sub(cost.prepare);
        // Preparing the boxes is culling: it stays out of the log. A batch
        // whose boxes all reached the near plane waited for nothing; the
        // wait of another holds reading its results out (microseconds).
        let waited = if cost.queries > 0 { cost.submitted } else { end };
        log(self.ops, OpKind::Commands, start, tested);
        log(self.ops, OpKind::Commands, tested + cost.prepare, waited);
        if let Some(wait) = log(self.ops, OpKind::WaitForResults, waited, end) {
            wait.tests = cost.gpu;
        }
    }

    fn encode_queued_draws(&mut self) {
        if !self.queued.is_empty() {
            self.renderer.order_nearest_first(self.queued);
            self.renderer.encode_shaded(
                &mut self.encoder,
                self.targets,
                self.depth,
                false,
                Draws::Objects(self.queued),
            );
            self.queued.clear();
        }
    }

    /// Encodes the queued draws and takes the encoder holding everything
    /// recorded so far, leaving a fresh one.
    fn take_recorded(&mut self) -> wgpu::CommandEncoder {
        self.encode_queued_draws();
        let fresh = self.gpu.device.create_command_encoder(&Default::default());
        std::mem::replace(&mut self.encoder, fresh)
    }

    /// Submits the rest of the frame and waits until the GPU has finished it.
    pub(crate) fn finish(mut self) -> FrameOutcome {
        let start = Instant::now();
        self.encode_queued_draws();
        if let Some((t, slot)) = self.timer {
            t.end(&mut self.encoder, slot);
        }
        submit_and_wait(self.gpu, self.ops, self.encoder, start);
        FrameOutcome {
            counters: self.counters,
            gpu_ops: self.gpu_ops,
        }
    }
}

/// Records a clear of the colour target and `depth`: a frame's start.
fn encode_clear(
    renderer: &SceneRenderer,
    encoder: &mut wgpu::CommandEncoder,
    targets: &RenderTargets,
    depth: &wgpu::TextureView,
) {
    renderer.encode_shaded(encoder, targets, depth, true, Draws::Objects(&[]));
}

/// Submits `encoder` (whose last commands were encoded from `start`) and
/// waits until the GPU has finished it, logging both in `ops`.
fn submit_and_wait(gpu: &GpuContext, ops: &mut Vec<OpSpan>, encoder: wgpu::CommandEncoder, start: Instant) {
    gpu.queue.submit([encoder.finish()]);
    let submitted = Instant::now();
    gpu.wait_idle();
    log(ops, OpKind::Commands, start, submitted);
    log(ops, OpKind::WaitForGpu, submitted, Instant::now());
}

impl Frame for FrameCtx<'_> {
    fn draw(&mut self, objects: &[u32]) {
        let start = Instant::now();
        for &o in objects {
            self.counters.objects_drawn += 1;
            self.counters.triangles_drawn += u64::from(self.renderer.scene.draws[o as usize].index_count / 3);
            self.drawn.insert(o);
        }
        self.queued.extend_from_slice(objects);
        self.gpu_ops += start.elapsed();
    }

    fn test_boxes(&mut self, boxes: &[Aabb], kind: BoxTest, out: &mut Vec<BoxVisibility>) {
        self.test(boxes, kind, out, None);
    }

    fn test_boxes_with_totals(
        &mut self,
        boxes: &[Aabb],
        sampling: u32,
        out: &mut Vec<BoxVisibility>,
        totals: &mut Vec<u64>,
    ) {
        self.test(boxes, BoxTest::PixelCount { sampling }, out, Some(totals));
    }

    fn on_gpu(&mut self) -> Option<&mut dyn GpuFrame> {
        Some(self)
    }
}

impl GpuFrame for FrameCtx<'_> {
    fn gpu(&self) -> &GpuContext {
        self.gpu
    }

    fn margins(&self) -> BoxMargins {
        self.margins
    }

    fn record(&mut self, work: &mut dyn FnMut(GpuWork)) {
        let start = Instant::now();
        self.encode_queued_draws();
        work(GpuWork {
            gpu: self.gpu,
            encoder: &mut self.encoder,
            depth: self.depth,
        });
        let end = Instant::now();
        self.gpu_ops += end - start;
        log(self.ops, OpKind::Commands, start, end);
    }

    fn round_trip(&mut self, read: &mut dyn FnMut(&GpuContext, wgpu::CommandEncoder)) {
        let start = Instant::now();
        let encoder = self.take_recorded();
        let submitted = Instant::now();
        read(self.gpu, encoder);
        let end = Instant::now();
        self.counters.query_batches += 1;
        self.counters.query_wait += end - submitted;
        self.gpu_ops += end - start;
        log(self.ops, OpKind::Commands, start, submitted);
        log(self.ops, OpKind::WaitForResults, submitted, end);
    }

    fn draw_indirect(&mut self, draws: IndirectDraws) {
        let start = Instant::now();
        self.encode_queued_draws();
        self.renderer.encode_shaded(
            &mut self.encoder,
            self.targets,
            self.depth,
            false,
            Draws::Indirect(draws),
        );
        let end = Instant::now();
        self.gpu_ops += end - start;
        log(self.ops, OpKind::Commands, start, end);
    }

    fn wait_for_gpu(&mut self) {
        let start = Instant::now();
        let encoder = self.take_recorded();
        submit_and_wait(self.gpu, self.ops, encoder, start);
        self.gpu_ops += start.elapsed();
    }

    fn clear(&mut self) {
        let start = Instant::now();
        self.encode_queued_draws();
        encode_clear(self.renderer, &mut self.encoder, self.targets, self.depth);
        let end = Instant::now();
        self.gpu_ops += end - start;
        log(self.ops, OpKind::Commands, start, end);
    }
}

/// Appends a span of `kind` from `start` to `end` to `ops` and returns it,
/// unless it is empty.
fn log(ops: &mut Vec<OpSpan>, kind: OpKind, start: Instant, end: Instant) -> Option<&mut OpSpan> {
    (end > start).then(|| {
        ops.push(OpSpan {
            kind,
            start,
            end,
            tests: None,
        });
        ops.last_mut().expect("just pushed")
    })
}
