//! `dr`: direct rendering (paper 002 §5, "DR – without any culling"). The
//! baseline every culler must beat, and the image every culler must match.

use super::{Culler, FrameInput, TraversalStats};
use crate::gpu::FrameCtx;
use crate::scene::Scene;

pub struct DirectRendering {
    all: Vec<u32>,
}

impl DirectRendering {
    pub fn new(scene: &Scene) -> Self {
        DirectRendering {
            all: (0..scene.objects.len() as u32).collect(),
        }
    }
}

impl Culler for DirectRendering {
    fn name(&self) -> &str {
        "dr"
    }

    fn frame(&mut self, ctx: &mut FrameCtx, _input: &FrameInput) -> TraversalStats {
        ctx.draw(&self.all);
        TraversalStats::default()
    }
}
