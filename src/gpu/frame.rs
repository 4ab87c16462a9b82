//! [`FrameCtx`]: the operations a culling mode may perform on the GPU during
//! one timed frame: draw objects, and test boxes against what is drawn.
//! Every mode goes through these operations, which do the counting
//! themselves, so no mode can draw or query without paying for it or report
//! its own figures.

use std::time::{Duration, Instant};

use super::queries::{BatchAnswers, BoxTest, BoxVisibility, QueryPool, TestTarget};
use super::{GpuContext, GpuTimer, RenderTargets, SceneRenderer};
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
    /// waiting for results), excluded from its CPU culling time.
    pub gpu_ops: Duration,
}

pub struct FrameCtx<'a> {
    gpu: &'a GpuContext,
    renderer: &'a SceneRenderer,
    targets: &'a RenderTargets,
    queries: &'a mut QueryPool,
    camera: &'a Camera,
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
        renderer.encode_shaded(&mut encoder, targets, depth, true, &[]);
        FrameCtx {
            gpu,
            renderer,
            targets,
            queries,
            camera,
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
        self.gpu_ops += start.elapsed();
    }

    fn encode_queued_draws(&mut self) {
        if !self.queued.is_empty() {
            self.renderer
                .encode_shaded(&mut self.encoder, self.targets, self.depth, false, self.queued);
            self.queued.clear();
        }
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
