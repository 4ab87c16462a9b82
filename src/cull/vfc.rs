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

use super::traversal::leaf_objects_in_frustum;
use super::{Culler, FrameInput, TraversalStats};
use crate::camera::Containment;
use crate::gpu::FrameCtx;
use crate::hierarchy::Hierarchy;
use crate::scene::Scene;

pub struct FrustumCulling<'a> {
    scene: &'a Scene,
    hierarchy: &'a Hierarchy,
    /// Reused between frames: the traversal allocates nothing.
    visible: Vec<u32>,
    stack: Vec<u32>,
}

impl<'a> FrustumCulling<'a> {
    pub fn new(scene: &'a Scene, hierarchy: &'a Hierarchy) -> Self {
        FrustumCulling {
            scene,
            hierarchy,
            visible: Vec::with_capacity(scene.objects.len()),
            stack: Vec::new(),
        }
    }
}

impl Culler for FrustumCulling<'_> {
    fn name(&self) -> &str {
        "vfc"
    }

    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats {
        let frustum = input.camera.frustum();
        let mut stats = TraversalStats::default();
        self.visible.clear();
        self.stack.clear();
        self.stack.push(0);
        while let Some(index) = self.stack.pop() {
            let node = &self.hierarchy.nodes[index as usize];
            stats.nodes_visited += 1;
            match frustum.classify(&node.bounds) {
                Containment::Outside => stats.nodes_culled_frustum += 1,
                // Fully inside: the whole subtree is potentially visible.
                Containment::Inside => self.visible.extend_from_slice(self.hierarchy.subtree_objects(node)),
                Containment::Intersecting if node.is_leaf() => {
                    leaf_objects_in_frustum(self.scene, self.hierarchy, node, &frustum, &mut self.visible)
                }
                Containment::Intersecting => self.stack.extend(node.children().map(|c| c as u32)),
            }
        }
        ctx.draw(&self.visible);
        stats
    }
}
