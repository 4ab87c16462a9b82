//! `oracle`: draws exactly the objects that own a pixel of the reference
//! frame, with no tests at all: the floor of any object-level culler (004's
//! REF, "ideal precomputed culling"). Its time is the cost of drawing the
//! visible set alone; no real mode can draw less and still be exact.

use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeId, ModeInfo, Needs};
use crate::gpu::Frame;

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Oracle,
    summary: "draws exactly the objects visible in the reference frame: the floor for object-level culling",
    chart_colour: [20, 20, 20],
    conservative: true,
    draws_by_time: false,
    params: &[],
    exercised_with: &[],
    needs: Needs::Nothing,
    carries: Carries::Nothing,
    auto: Candidacy::Never,
    check: |_| Ok(()),
    build: |_, _| Ok(Box::new(Oracle::new())),
};

#[derive(Default)]
pub struct Oracle {
    visible: Vec<u32>,
}

impl Oracle {
    pub fn new() -> Self {
        Oracle::default()
    }
}

impl Culler for Oracle {
    fn name(&self) -> &str {
        ModeId::Oracle.name()
    }

    fn needs_reference(&self) -> bool {
        true
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        self.visible.clear();
        if let Some(reference) = input.reference_visible {
            self.visible.extend(reference.iter());
        }
        ctx.draw(&self.visible);
        TraversalStats::default()
    }
}
