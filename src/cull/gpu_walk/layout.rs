//! What the walk's buffers hold, word by word, and the constants its
//! shaders share with the Rust side: written as WGSL before each shader's
//! text ([`shader_constants`]), so the two cannot drift apart.

use super::frustum::{GPU_ABSOLUTE_ERROR, GPU_OUTSIDE_SLACK};
use crate::gpu::{BOXES_WGSL, GpuContext, module_with_camera};

/// Threads per workgroup of walk.wgsl, and its grid limit.
pub(super) const GROUP_SIZE: u32 = 64;
pub(super) const MAX_GROUPS: u32 = 65_535;

/// Words of one level's arguments (`Level` in walk.wgsl): an indexed
/// indirect draw (5), an indirect dispatch (3), and counts of nodes hidden,
/// outside the frustum and reaching the near plane (3).
pub(super) const LEVEL_WORDS: usize = 11;
pub(super) const LEVEL_BYTES: u64 = LEVEL_WORDS as u64 * 4;
/// Words of a level: its queue's length (the draw's instance count), its
/// dispatch's workgroups across, and the counts of the nodes it found
/// hidden and outside the frustum.
pub(super) const LEVEL_ENTRIES: usize = 1;
pub(super) const LEVEL_GROUPS_X: usize = 5;
pub(super) const HIDDEN: usize = 8;
pub(super) const LEVEL_OUTSIDE: usize = HIDDEN + 1;
/// Where the dispatch arguments start in a level.
pub(super) const DISPATCH_OFFSET: u64 = LEVEL_GROUPS_X as u64 * 4;

/// What a node's word of the visibility buffer says: set by `cs_prepare`
/// before a walk, and to [`VISIBLE`] by the level's test (raster_mark.wgsl's
/// `fs_mark` for a box a fragment of which passed, pyramid_test.wgsl's
/// `cs_test` for a box not behind the pyramid).
pub(super) const TO_TEST: u32 = 0;
pub(super) const VISIBLE: u32 = 1;
pub(super) const OUTSIDE_FRUSTUM: u32 = 2;
pub(super) const REACHES_NEAR: u32 = 3;
/// What an object's word of the state buffer says (`cs_expand` and
/// `cs_compact`): drawn as visible in the last frame, and marked visible in
/// this walk.
pub(super) const VISIBLE_LAST_FRAME: u32 = 1;
pub(super) const MARKED: u32 = 2;
/// What an object's word of the drawn buffer says after `cs_compact`: drawn
/// first, as last frame's visible list, or after the test, newly visible.
pub(super) const DRAWN_EARLY: u32 = 1;
pub(super) const DRAWN_LATE: u32 = 2;
pub(super) const DRAW_COMMAND_BYTES: u64 = 20;

/// The constants above that the shaders read, as WGSL.
pub(super) fn shader_constants() -> String {
    [
        ("TO_TEST", TO_TEST),
        ("VISIBLE", VISIBLE),
        ("OUTSIDE_FRUSTUM", OUTSIDE_FRUSTUM),
        ("REACHES_NEAR", REACHES_NEAR),
        ("VISIBLE_LAST_FRAME", VISIBLE_LAST_FRAME),
        ("MARKED", MARKED),
        ("DRAWN_EARLY", DRAWN_EARLY),
        ("DRAWN_LATE", DRAWN_LATE),
        ("GROUP_SIZE", GROUP_SIZE),
        ("MAX_GROUPS", MAX_GROUPS),
        ("LEVEL_ENTRIES", LEVEL_ENTRIES as u32),
        ("LEVEL_GROUPS_X", LEVEL_GROUPS_X as u32),
        ("LEVEL_OUTSIDE", LEVEL_OUTSIDE as u32),
    ]
    .iter()
    .map(|(name, value)| format!("const {name}: u32 = {value}u;\n"))
    .chain(
        [
            ("GPU_OUTSIDE_SLACK", GPU_OUTSIDE_SLACK),
            ("GPU_ABSOLUTE_ERROR", GPU_ABSOLUTE_ERROR),
        ]
        .iter()
        .map(|(name, value)| format!("const {name}: f32 = {value:e};\n")),
    )
    .collect()
}

/// A shader module of camera.wgsl, boxes.wgsl (the boxes, `box_clip`), the
/// shared constants and `source`.
pub(super) fn boxes_module(gpu: &GpuContext, label: &str, source: &str) -> wgpu::ShaderModule {
    module_with_camera(gpu, label, &[BOXES_WGSL, &shader_constants(), source])
}
