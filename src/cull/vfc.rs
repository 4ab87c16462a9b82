//! `vfc`: hierarchical view-frustum culling, paper 002 §4.1.
//!
//! The paper: "Once a bounding volume intersects the view-frustum […] we test
//! whether the bounding volume resides entirely within the view-frustum. In
//! this case, all subtrees of the bounding volume are marked potentially
//! visible. Otherwise, we recursively continue testing the child nodes."
//!
//! Departures: the paper tests boxes with OpenGL's selection mode; here the
//! box is tested against the frustum planes on the CPU in f64 (conservative,
//! see `Frustum::classify`). The paper's "rare case" of a box that contains
//! the whole frustum needs no special handling with plane tests. Objects of
//! an intersecting leaf are tested one by one, since a leaf holds up to a few
//! objects here where the paper's leaves held one geometry node.

use super::traversal::frustum_cull_subtree;
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeId, ModeInfo, Needs};
use crate::gpu::Frame;
use crate::scene::Scene;

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Vfc,
    summary: "hierarchical view-frustum culling with the fully-inside shortcut (002 §4.1)",
    chart_colour: [31, 119, 180],
    conservative: true,
    draws_by_time: false,
    params: &[],
    exercised_with: &[],
    needs: Needs::Nothing,
    carries: Carries::Nothing,
    auto: Candidacy::Always,
    check: |_| Ok(()),
    build: |scene, _| Ok(Box::new(FrustumCulling::new(scene))),
};

pub struct FrustumCulling {
    /// Reused between frames: the traversal allocates nothing.
    visible: Vec<u32>,
    stack: Vec<u32>,
}

impl FrustumCulling {
    pub fn new(scene: &Scene) -> Self {
        FrustumCulling {
            visible: Vec::with_capacity(scene.objects.len()),
            stack: Vec::new(),
        }
    }
}

impl Culler for FrustumCulling {
    fn name(&self) -> &str {
        ModeId::Vfc.name()
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let frustum = input.camera.frustum();
        let mut stats = TraversalStats::default();
        self.visible.clear();
        frustum_cull_subtree(
            input.scene,
            input.hierarchy,
            0,
            &frustum,
            &mut self.stack,
            &mut self.visible,
            &mut stats,
        );
        ctx.draw(&self.visible);
        stats
    }
}
