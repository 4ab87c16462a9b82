//! [`FrameCtx`]: the operations a culling mode may perform on the GPU during
//! one timed frame: draw objects, test boxes against what is drawn, and, for
//! GPU-driven modes, walk a tree and draw the lists the GPU built.
//! Every mode goes through these operations, which do the counting
//! themselves, so no mode can draw or query without paying for it or report
//! its own figures.

use std::time::{Duration, Instant};

use super::conservative::BoxMargins;
use super::cull_tree::CullTree;
use super::queries::{BatchAnswers, BoxTest, BoxVisibility, QueryPool, TestTarget};
use super::raster::{DrawList, GpuAudit, GpuCullTree, RasterPool};
use super::{Draws, GpuContext, GpuTimer, RenderTargets, SceneRenderer};
use crate::bounds::Aabb;
use crate::camera::Camera;
use crate::object_set::ObjectSet;

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
}

/// Result of a finished frame.
pub struct FrameOutcome {
    pub counters: FrameCounters,
    /// Time the mode spent inside `FrameCtx` operations (encoding, submitting,
    /// waiting for results), excluded from its CPU culling time. Preparing
    /// boxes for a test is culling, and not part of it.
    pub gpu_ops: Duration,
}

impl FrameOutcome {
    /// Adds what a GPU-driven walk drew and tested (each node box drawn
    /// into the visibility buffer counts as a query); its node counts go to
    /// the mode's traversal figures (`TraversalStats::add_gpu_audit`).
    pub fn add_gpu_audit(&mut self, audit: &GpuAudit) {
        let c = &mut self.counters;
        c.objects_drawn += audit.objects_drawn;
        c.triangles_drawn += audit.triangles_drawn;
        c.queries += audit.nodes_tested;
        if let Some(t) = audit.cull_gpu {
            *c.query_gpu.get_or_insert(Duration::ZERO) += t;
        }
    }
}

pub struct FrameCtx<'a> {
    gpu: &'a GpuContext,
    renderer: &'a SceneRenderer,
    targets: &'a RenderTargets,
    queries: &'a mut QueryPool,
    raster: Option<&'a mut RasterPool>,
    camera: &'a Camera,
    /// What this frame's box tests stay clear of.
    margins: BoxMargins,
    depth: &'a wgpu::TextureView,
    timer: Option<(&'a GpuTimer, usize)>,
    encoder: wgpu::CommandEncoder,
    /// Objects drawn but not yet encoded: they are encoded as one pass before
    /// the next query batch or at the end of the frame.
    queued: &'a mut Vec<u32>,
    counters: FrameCounters,
    drawn: &'a mut ObjectSet,
    gpu_ops: Duration,
}

/// Everything a frame of one mode renders with.
pub struct FrameResources<'a> {
    pub gpu: &'a GpuContext,
    pub renderer: &'a SceneRenderer,
    pub targets: &'a RenderTargets,
    pub queries: &'a mut QueryPool,
    /// For modes that cull on the GPU; `None` when none runs.
    pub raster: Option<&'a mut RasterPool>,
    pub timer: Option<&'a GpuTimer>,
    /// Scratch for queued draws, reused from frame to frame.
    pub draw_queue: &'a mut Vec<u32>,
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
        let FrameResources {
            gpu,
            renderer,
            targets,
            queries,
            raster,
            timer,
            draw_queue: queued,
        } = resources;
        drawn.clear();
        queued.clear();
        let depth = &targets.mode_depths[slot];
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        if let Some(t) = timer {
            t.begin(&mut encoder, slot);
        }
        renderer.encode_shaded(&mut encoder, targets, depth, true, Draws::Objects(&[]));
        FrameCtx {
            gpu,
            renderer,
            targets,
            queries,
            raster,
            camera,
            margins: BoxMargins::new(gpu.depth_margins, camera, targets.resolution),
            depth,
            timer: timer.map(|t| (t, slot)),
            encoder,
            queued,
            counters: FrameCounters::default(),
            drawn,
            gpu_ops: Duration::ZERO,
        }
    }

    /// Draws `objects`, shaded, into this mode's frame. Every draw is on the
    /// depth buffer before any later [`FrameCtx::test_boxes`].
    pub fn draw(&mut self, objects: &[u32]) {
        let start = Instant::now();
        for &o in objects {
            self.counters.objects_drawn += 1;
            self.counters.triangles_drawn += u64::from(self.renderer.scene.draws[o as usize].index_count / 3);
            self.drawn.insert(o);
        }
        self.queued.extend_from_slice(objects);
        self.gpu_ops += start.elapsed();
    }

    /// Tests `boxes` as one batch against the depth drawn so far (occlusion
    /// queries or pixel counts), one round trip. Writes one result per box
    /// to `out`; a box that reaches the near plane is visible untested.
    pub fn test_boxes(&mut self, boxes: &[Aabb], kind: BoxTest, out: &mut Vec<BoxVisibility>) {
        self.test(boxes, kind, out, None);
    }

    /// [`FrameCtx::test_boxes`] by pixel counts that also counts the pixels
    /// each box covers in all (001 §3.3's additional query), in the same
    /// round trip; `totals` gets 0 for a box not tested. Needs
    /// [`GpuContext::pixel_counts`].
    pub fn test_boxes_with_totals(
        &mut self,
        boxes: &[Aabb],
        sampling: u32,
        out: &mut Vec<BoxVisibility>,
        totals: &mut Vec<u64>,
    ) {
        self.test(boxes, BoxTest::PixelCount { sampling }, out, Some(totals));
    }

    fn test(&mut self, boxes: &[Aabb], kind: BoxTest, out: &mut Vec<BoxVisibility>, totals: Option<&mut Vec<u64>>) {
        let start = Instant::now();
        self.encode_queued_draws();
        let encoder = std::mem::replace(
            &mut self.encoder,
            self.gpu.device.create_command_encoder(&Default::default()),
        );
        let target = TestTarget {
            depth: self.depth,
            camera: self.camera,
            margins: self.margins,
        };
        let answers = BatchAnswers {
            visibility: out,
            totals,
        };
        let cost = self.queries.test(self.gpu, encoder, target, boxes, kind, answers);
        if cost.queries > 0 {
            self.counters.queries += cost.queries;
            self.counters.query_batches += 1;
            self.counters.query_wait += cost.wait;
            if let Some(gpu) = cost.gpu {
                *self.counters.query_gpu.get_or_insert(Duration::ZERO) += gpu;
            }
        }
        self.gpu_ops += start.elapsed().saturating_sub(cost.prepare);
    }

    fn encode_queued_draws(&mut self) {
        if !self.queued.is_empty() {
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

    /// Whether GPU-driven culling can run here (the session made its pool).
    pub fn can_cull_on_gpu(&self) -> bool {
        self.raster.is_some()
    }

    /// GPU-driven culling (004): puts `tree` on the GPU for this mode, with
    /// an empty visible list. Done once; the mode keeps the result.
    pub fn upload_cull_tree(&mut self, tree: &CullTree) -> GpuCullTree {
        let start = Instant::now();
        let uploaded = pool(&mut self.raster).upload(self.gpu, tree);
        self.gpu_ops += start.elapsed();
        uploaded
    }

    /// Draws one of `tree`'s GPU-built lists, shaded. Objects drawn are
    /// counted after the frame ([`RasterPool::audit`]). Where draws cannot
    /// take their count from a GPU buffer, the newly visible list's length
    /// is read back first: one round trip.
    pub fn draw_gpu_list(&mut self, tree: &mut GpuCullTree, list: DrawList) {
        let start = Instant::now();
        self.encode_queued_draws();
        let indirect_count = self.gpu.indirect_count;
        if list == DrawList::NewlyVisible && !indirect_count {
            let encoder = std::mem::replace(
                &mut self.encoder,
                self.gpu.device.create_command_encoder(&Default::default()),
            );
            let submitted = Instant::now();
            pool(&mut self.raster).read_counts(self.gpu, encoder, tree);
            self.counters.query_batches += 1;
            self.counters.query_wait += submitted.elapsed();
        }
        let draws = Draws::Indirect(RasterPool::list(tree, list, indirect_count));
        self.renderer
            .encode_shaded(&mut self.encoder, self.targets, self.depth, false, draws);
        self.gpu_ops += start.elapsed();
    }

    /// Starts a walk of `tree` (boxes from `bounds`, one per node) with its
    /// seed queued, after everything drawn so far.
    pub fn begin_gpu_walk(&mut self, tree: &GpuCullTree, bounds: impl ExactSizeIterator<Item = Aabb>) {
        let start = Instant::now();
        self.encode_queued_draws();
        let prepare =
            pool(&mut self.raster).begin_walk(self.gpu, &mut self.encoder, self.camera, self.margins, tree, bounds);
        self.gpu_ops += start.elapsed().saturating_sub(prepare);
    }

    /// Tests the queued nodes of `tree` as one batch on the GPU and queues
    /// the children of the visible ones.
    pub fn walk_gpu_level(&mut self, tree: &GpuCullTree) {
        let start = Instant::now();
        pool(&mut self.raster).walk_level(&mut self.encoder, self.depth, tree);
        self.gpu_ops += start.elapsed();
    }

    /// Ends the walk: builds `tree`'s visible and newly visible lists.
    pub fn compact_gpu_lists(&mut self, tree: &GpuCullTree) {
        let start = Instant::now();
        pool(&mut self.raster).compact(&mut self.encoder, tree);
        self.gpu_ops += start.elapsed();
    }

    /// Submits the rest of the frame and waits until the GPU has finished it.
    pub(crate) fn finish(mut self) -> FrameOutcome {
        self.encode_queued_draws();
        if let Some((t, slot)) = self.timer {
            t.end(&mut self.encoder, slot);
        }
        self.gpu.queue.submit([self.encoder.finish()]);
        self.gpu.wait_idle();
        FrameOutcome {
            counters: self.counters,
            gpu_ops: self.gpu_ops,
        }
    }
}

/// The pool of GPU-driven culling, which the session provides to modes that
/// declare `Culler::culls_on_gpu` (run only where `GpuContext::gpu_driven`).
fn pool<'p>(raster: &'p mut Option<&mut RasterPool>) -> &'p mut RasterPool {
    raster
        .as_deref_mut()
        .expect("GPU-driven modes declare Culler::culls_on_gpu and run only where GpuContext::gpu_driven")
}
