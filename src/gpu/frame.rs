//! [`FrameCtx`]: the operations a culling mode may perform on the GPU during
//! one timed frame. Every mode goes through the same operations, which do the
//! counting themselves, so no mode can draw without paying for it or report
//! its own figures.

use std::time::{Duration, Instant};

use super::{GpuContext, GpuTimer, RenderTargets, SceneRenderer};
use crate::object_set::ObjectSet;

/// What a mode drew in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DrawCounters {
    /// Draw calls (an object drawn twice counts twice).
    pub objects_drawn: u64,
    pub triangles_drawn: u64,
}

/// Result of a finished frame.
pub struct FrameOutcome {
    pub counters: DrawCounters,
    /// Time the mode spent inside `FrameCtx` operations (encoding, and in
    /// later modes submitting and waiting), excluded from its CPU culling time.
    pub gpu_ops: Duration,
}

pub struct FrameCtx<'a> {
    gpu: &'a GpuContext,
    renderer: &'a SceneRenderer,
    targets: &'a RenderTargets,
    depth: &'a wgpu::TextureView,
    timer: Option<(&'a GpuTimer, usize)>,
    encoder: wgpu::CommandEncoder,
    cleared: bool,
    counters: DrawCounters,
    drawn: &'a mut ObjectSet,
    gpu_ops: Duration,
}

impl<'a> FrameCtx<'a> {
    /// Starts a frame for mode `slot`: its own depth target and timer span.
    pub(crate) fn begin(
        gpu: &'a GpuContext,
        renderer: &'a SceneRenderer,
        targets: &'a RenderTargets,
        slot: usize,
        timer: Option<&'a GpuTimer>,
        drawn: &'a mut ObjectSet,
    ) -> FrameCtx<'a> {
        drawn.clear();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        if let Some(t) = timer {
            t.begin(&mut encoder, slot);
        }
        FrameCtx {
            gpu,
            renderer,
            targets,
            depth: &targets.mode_depths[slot],
            timer: timer.map(|t| (t, slot)),
            encoder,
            cleared: false,
            counters: DrawCounters::default(),
            drawn,
            gpu_ops: Duration::ZERO,
        }
    }

    /// Draws `objects`, shaded, into this mode's frame.
    pub fn draw(&mut self, objects: &[u32]) {
        let start = Instant::now();
        self.renderer
            .encode_shaded(&mut self.encoder, self.targets, self.depth, !self.cleared, objects);
        self.cleared = true;
        for &o in objects {
            self.counters.objects_drawn += 1;
            self.counters.triangles_drawn += u64::from(self.renderer.scene.draws[o as usize].index_count / 3);
            self.drawn.insert(o);
        }
        self.gpu_ops += start.elapsed();
    }

    /// Submits the frame and waits until the GPU has finished it.
    pub(crate) fn finish(mut self) -> FrameOutcome {
        if !self.cleared {
            // A frame that draws nothing still clears to an empty picture.
            self.renderer
                .encode_shaded(&mut self.encoder, self.targets, self.depth, true, &[]);
        }
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
