//! GPU-driven culling, paper 004: the visibility of tree nodes is decided
//! on the GPU, level by level, and the GPU builds the draw lists itself, so
//! no per-node result travels back to the CPU. Three modes share it, each a
//! [`GpuCulling`] (culling.rs) that differs in what it walks and how a level
//! tests boxes: `roc` (004's comparator, [`roc`]) every object's box,
//! `ioc` (004 §2, [`ioc`]) the hierarchy cut at a bottom depth, both by
//! drawing the boxes against the depth ([`NodeTest::Raster`]); `hiz`
//! (two-phase hierarchical-depth culling, [`hiz`]) objects or nodes in a
//! compute pass against a depth pyramid ([`NodeTest::Pyramid`]).
//!
//! A frame (culling.rs's `cull_on_gpu`) draws last frame's visible objects
//! first, tests the tree level by level against that depth, and draws the
//! newly visible objects by indirect multi-draw. Conservative in the
//! current frame: an object is left out only when its box lies behind depth
//! really drawn. Round trips: none where indirect draws take their count
//! from a buffer (Vulkan); on GL the list lengths are read back once.
//!
//! Departure: the boxes (and hiz's pixel planes, pyramid_test.wgsl's
//! `box_planes`) are made on the GPU as engines make them, but from
//! positions in two f32 parts and with margins that hold the box the CPU
//! makes in f64 (prepare_nodes.wgsl), not from world coordinates in f32.

mod culling;
pub mod depths;
mod frustum;
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
pub use walk::{DrawList, GpuWalk};
