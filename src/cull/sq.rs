//! `sq`: hierarchical occlusion culling with one occlusion query per node,
//! each awaited before the traversal goes on (stop-and-wait). This is
//! configuration (b) of paper 003 §5, "a single occlusion query for each
//! node in the scene graph (without using an Occupancy Map)", the baseline
//! the Occupancy Map and multiple queries were designed to beat.
//!
//! Traversal (003 §4.2): nodes front to back by their nearest box corner;
//! a node outside the frustum is culled; otherwise its box is queried
//! against everything drawn so far; a hidden node is culled with its
//! subtree; a visible leaf is drawn; a visible inner node's children join
//! the queue.

use super::traversal::{DepthQueue, draw_leaf, nearest_corner};
use crate::camera::Containment;
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeId, ModeInfo, Needs};
use crate::gpu::{BoxTest, BoxVisibility, Frame};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Sq,
    summary: "front-to-back traversal, one occlusion query per node, each awaited (003 §5 b)",
    chart_colour: [255, 127, 14],
    conservative: true,
    draws_by_time: false,
    params: &[],
    exercised_with: &[],
    needs: Needs::Nothing,
    carries: Carries::Nothing,
    auto: Candidacy::Never,
    check: |_| Ok(()),
    build: |_, _| Ok(Box::new(SingleQueries::new())),
};

#[derive(Default)]
pub struct SingleQueries {
    queue: DepthQueue,
    objects: Vec<u32>,
    result: Vec<BoxVisibility>,
}

impl SingleQueries {
    pub fn new() -> Self {
        SingleQueries::default()
    }
}

impl Culler for SingleQueries {
    fn name(&self) -> &str {
        ModeId::Sq.name()
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let (frustum, eye) = (input.camera.frustum(), input.camera.eye);
        let nodes = &input.hierarchy.nodes;
        let mut stats = TraversalStats::default();
        self.queue.clear();
        self.queue.push(0, nearest_corner(&nodes[0].bounds, eye));
        while let Some(index) = self.queue.pop() {
            let node = &nodes[index as usize];
            stats.nodes_visited += 1;
            if frustum.classify(&node.bounds) == Containment::Outside {
                stats.nodes_culled_frustum += 1;
                continue;
            }
            ctx.test_boxes(std::slice::from_ref(&node.bounds), BoxTest::Occlusion, &mut self.result);
            if !self.result[0].is_visible() {
                stats.nodes_culled_occlusion += 1;
                continue;
            }
            if node.is_leaf() {
                draw_leaf(ctx, input.scene, input.hierarchy, node, &frustum, &mut self.objects);
            } else {
                for child in node.children() {
                    self.queue.push(child as u32, nearest_corner(&nodes[child].bounds, eye));
                }
            }
        }
        stats
    }
}
