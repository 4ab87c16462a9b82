//! GPU-driven culling, paper 004: the visibility of tree nodes is decided
//! on the GPU, level by level, and the GPU builds the draw lists itself, so
//! no per-node result travels back to the CPU. Two modes share it: `roc`
//! (004's comparator, [`roc`]) walks a flat tree, every object a leaf;
//! `ioc` (004 §2, [`ioc`]) the bounding-volume hierarchy cut at a bottom
//! depth. What the GPU walks is a [`CullTree`] (tree.rs); each mode owns
//! its [`GpuWalk`] (pool.rs: pipelines, scratch, the tree on the GPU), made
//! in [`Culler::prepare`](super::Culler::prepare).
//!
//! One frame (`cull_on_gpu`), every step through `GpuFrame`:
//!
//! 1. Last frame's visible objects are drawn first: they are this frame's
//!    occluders, and part of its image.
//! 2. Per level: the boxes of the queued nodes are drawn against that depth
//!    with forced early depth testing; a fragment that passes marks its node
//!    in the visibility buffer (raster_mark.wgsl). Then `cs_expand` queues
//!    the children of visible inner nodes and marks the objects of visible
//!    leaves (raster_cull.wgsl). The queue's length stays on the GPU: it is
//!    the instance count of the next level's indirect draw and dispatch.
//!    Boxes that reach the near plane are marked by the CPU, which cannot
//!    rasterise them, and boxes outside the frustum are never queued.
//! 3. `cs_compact` turns the marks into next frame's visible list and the
//!    list of objects visible now but not drawn in step 1.
//! 4. That list is drawn by indirect multi-draw.
//!
//! Conservative in the current frame: an object is left out only when every
//! fragment of its box failed the depth test against objects really drawn.
//! Round trips: none where indirect draws take their count from a buffer
//! (Vulkan); elsewhere (GL) the list lengths are read back before step 4.
//! After the frame, untimed, the mode's audit reads back which objects were
//! drawn, how many nodes each level tested and hid, and the GPU time of
//! steps 2-3, for the statistics.
//!
//! Departure: the boxes are made eye-relative and grown on the CPU in f64
//! (as for every box test here) and uploaded each frame, rather than
//! transformed on the GPU from world coordinates in f32.

pub mod ioc;
mod pool;
pub mod roc;
mod tree;
#[cfg(test)]
mod twin;

pub use pool::{DrawList, GpuWalk, NodeBoxes};
pub use tree::{CullTree, MAX_LEVELS, TreeNode};

use crate::bounds::Aabb;
use crate::camera::Camera;
use crate::cull::culler::TraversalStats;
use crate::gpu::Frame;

/// One frame of GPU-driven culling over `walk`'s tree, whose nodes have the
/// boxes `bounds` this frame: steps 1-4 above. The traversal figures are
/// counted on the GPU and added after the frame (the mode's audit): the
/// ones returned are empty.
///
/// # Panics
/// Without a walk or a GPU frame: a session prepares every mode (which
/// makes its walk) and runs it on the GPU.
pub(super) fn cull_on_gpu(
    frame: &mut dyn Frame,
    camera: &Camera,
    walk: Option<&mut GpuWalk>,
    bounds: impl ExactSizeIterator<Item = Aabb>,
) -> TraversalStats {
    let walk = walk.expect("the session prepared the mode, which made its walk");
    let ctx = frame.on_gpu().expect("the session runs GPU walks on the GPU");
    let indirect_count = ctx.gpu().indirect_count;
    ctx.draw_indirect(walk.list(DrawList::Visible, indirect_count));
    // Preparing the boxes is culling work on the CPU, outside `record`.
    walk.prepare_boxes(camera, ctx.margins(), bounds);
    ctx.record(&mut |work| walk.begin(work));
    for _ in 0..walk.levels() {
        ctx.record(&mut |work| walk.walk_level(work));
    }
    ctx.record(&mut |work| walk.compact(work));
    if !indirect_count {
        ctx.round_trip(&mut |gpu, encoder| walk.read_counts(gpu, encoder));
    }
    ctx.draw_indirect(walk.list(DrawList::NewlyVisible, indirect_count));
    TraversalStats::default()
}
