//! GPU-driven culling, paper 004: the visibility of tree nodes is decided
//! on the GPU, level by level, and the GPU builds the draw lists itself, so
//! no per-node result travels back to the CPU. Three modes share it, each a
//! [`GpuCulling`] (culling.rs) that differs in what it walks and how a level
//! tests boxes:
//!
//! - `roc` (004's comparator, [`roc`]) walks a flat tree, every object a
//!   leaf, and draws the boxes against the depth ([`NodeTest::Raster`]);
//! - `ioc` (004 §2, [`ioc`]) walks the bounding-volume hierarchy cut at a
//!   bottom depth, drawing boxes too;
//! - `hiz` (two-phase hierarchical-depth culling, [`hiz`]) tests objects or
//!   nodes in a compute pass against a depth pyramid ([`NodeTest::Pyramid`],
//!   pyramid.rs).
//!
//! What the GPU walks is a [`CullTree`] (tree.rs); each mode owns its
//! [`GpuWalk`] (walk.rs: pipelines, scratch, the tree on the GPU), made in
//! [`Culler::prepare`](super::Culler::prepare).
//!
//! One frame (culling.rs's `cull_on_gpu`), every step through `GpuFrame`:
//!
//! 1. Last frame's visible objects are drawn first: they are this frame's
//!    occluders, and part of its image.
//! 2. Per level: the boxes of the queued nodes are drawn against that depth
//!    with forced early depth testing; a fragment that passes marks its node
//!    in the visibility buffer (raster_mark.wgsl). hiz instead builds the
//!    depth pyramid once, before the first level, and a compute pass marks
//!    every queued box not behind the pyramid, or for a small one not
//!    behind the depth at each of its pixels (pyramid_test.wgsl). Then
//!    `cs_expand` queues
//!    the children of visible inner nodes and marks the objects of visible
//!    leaves (walk.wgsl). The queue's length stays on the GPU: it is
//!    the instance count of the next level's indirect draw and dispatch.
//!    Boxes that reach the near plane are marked by the CPU, which cannot
//!    rasterise them, and boxes outside the frustum are never queued.
//! 3. `cs_compact` turns the marks into next frame's visible list and the
//!    list of objects visible now but not drawn in step 1.
//! 4. That list is drawn by indirect multi-draw.
//!
//! Conservative in the current frame: an object is left out only when every
//! fragment of its box failed the depth test against objects really drawn
//! (or, for hiz, its box lies behind the farthest of that depth over its
//! screen rectangle).
//! Round trips: none where indirect draws take their count from a buffer
//! (Vulkan); elsewhere (GL) the list lengths are read back before step 4.
//! After the frame, untimed, the mode's audit reads back which objects were
//! drawn (early, in step 1, or late, in step 4), how many nodes each level
//! tested and hid, and the GPU time of steps 2-3 (and of the pyramid), for
//! the statistics.
//!
//! Departure: the boxes are made eye-relative and grown on the CPU in f64
//! (as for every box test here) and uploaded each frame, rather than
//! transformed on the GPU from world coordinates in f32.

mod culling;
pub mod depths;
pub mod hiz;
pub mod ioc;
mod layout;
mod level_test;
mod lists;
mod pyramid;
pub mod roc;
mod tree;
#[cfg(test)]
mod twin;
mod walk;

pub use culling::{GpuCulling, Walked};
pub use level_test::NodeTest;
pub use lists::VisibleLists;
pub use tree::{CullTree, MAX_LEVELS, TreeNode};
pub use walk::{DrawList, GpuWalk, NodeBoxes};
