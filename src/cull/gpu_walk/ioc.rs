//! `ioc`: iterative hierarchical raster occlusion culling, paper 004 §2.
//!
//! `roc` run over the bounding-volume hierarchy instead of single objects:
//! "The BVH is iteratively traversed from a moderate depth down to a deeper
//! level (but not the bottom of the tree)." The nodes at the start depth are
//! tested as one batch; "if the node is culled, we stop the traversal for
//! the node [...]. If the node is a leaf, we directly mark it as a
//! potentially visible occludee in the VB. Otherwise, we tightly pack and
//! enqueue them for the next occlusion test [...]. At the bottom level, all
//! the children in the subtrees of the visible nodes are marked as
//! potentially visible." The hierarchy is cut at the bottom depth once
//! ([`CullTree::cut`]), so a visible node there is a leaf whose subtree's
//! objects are marked.
//!
//! Departure: 004 reads the size of each level's queue back "to drive the
//! indirect multidraw call of the next occlusion test". Here the queue's
//! length is written by the GPU straight into the next level's indirect draw
//! and dispatch arguments, so a level needs no read-back at all; the only
//! one left is roc's list lengths on adapters without indirect counts.
//!
//! Start and bottom depths: 004 names their choice as its open problem.
//! `auto` picks them from the hierarchy alone, see
//! [`auto_depths`](super::depths::auto_depths).

use super::depths::{BOTTOM, DepthRange, START};
use super::{GpuCulling, NodeTest, Walked};
use crate::cull::mode::{Candidacy, Carries, ModeId, ModeInfo, Needs};

/// This mode's entry in the registry.
pub(in crate::cull) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Ioc,
    summary: "iterative hierarchical raster occlusion culling: roc over the hierarchy, level by level from a start to a bottom depth (004 §2)",
    chart_colour: [188, 189, 34],
    conservative: true,
    draws_by_time: false,
    params: &[START, BOTTOM],
    exercised_with: &[],
    needs: Needs::GpuCulling,
    carries: Carries::VisibleOnGpu,
    auto: Candidacy::Always,
    check: |params| DepthRange::from_params(ModeId::Ioc, params).map(drop),
    build: |_, params| {
        Ok(Box::new(iterative_occlusion_culling(DepthRange::from_params(
            ModeId::Ioc,
            params,
        )?)))
    },
};

/// ioc: the hierarchy's nodes over `range`, their boxes drawn against the
/// depth.
pub fn iterative_occlusion_culling(range: DepthRange) -> GpuCulling {
    GpuCulling::new(
        ModeId::Ioc,
        Walked::Nodes(range),
        NodeTest::Raster,
        serde_json::json!(range),
    )
}
