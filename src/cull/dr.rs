//! `dr`: direct rendering (paper 002 §5, "DR – without any culling"). The
//! baseline every culler must beat, and the image every culler must match.

use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeId, ModeInfo, Needs};
use crate::gpu::Frame;
use crate::scene::Scene;

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Dr,
    summary: "direct rendering: every object, no culling (002 §5)",
    chart_colour: [127, 127, 127],
    conservative: true,
    draws_by_time: false,
    params: &[],
    exercised_with: &[],
    needs: Needs::Nothing,
    carries: Carries::Nothing,
    auto: Candidacy::Never,
    check: |_| Ok(()),
    build: |scene, _| Ok(Box::new(DirectRendering::new(scene))),
};

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
        ModeId::Dr.name()
    }

    fn frame(&mut self, ctx: &mut dyn Frame, _input: &FrameInput) -> TraversalStats {
        ctx.draw(&self.all);
        TraversalStats::default()
    }
}
