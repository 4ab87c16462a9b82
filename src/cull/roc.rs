//! `roc`: raster occlusion culling, the comparator of paper 004 (its [1, 2]):
//! "directly marking visible objects during the rasterization, leveraged by
//! early Z and unordered buffer access", with "indirect multidraw commands to
//! avoid GPU-to-CPU read-back".
//!
//! One frame (004 §1-2, shared with `ioc` through [`cull_on_gpu`]):
//!
//! 1. Last frame's visible objects are drawn first: they are this frame's
//!    occluders, and part of its image.
//! 2. The box of every object is drawn once against that depth with forced
//!    early depth testing; a fragment that passes marks its object in the
//!    visibility buffer. Boxes that reach the near plane are marked by the
//!    CPU, which cannot rasterise them.
//! 3. A compute pass compacts the marked objects into next frame's visible
//!    list and into the list of those not drawn in step 1.
//! 4. That list is drawn by indirect multi-draw.
//!
//! Conservative in the current frame: an object is left out only when every
//! fragment of its box failed the depth test against objects really drawn.
//! Round trips: none where indirect draws take their count from a buffer
//! (Vulkan); elsewhere (GL) the list lengths are read back before step 4.
//!
//! Departure: the boxes are made eye-relative and grown on the CPU in f64
//! (as for every box test here) and uploaded each frame, rather than
//! transformed on the GPU from world coordinates in f32.

use super::{Culler, FrameInput, ModeId, ModeInfo, Needs, TraversalStats};
use crate::bounds::Aabb;
use crate::gpu::{CullTree, DrawList, FrameCtx, GpuCullTree};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Roc,
    name: "roc",
    summary: "raster occlusion culling on the GPU: every object's box marks a visibility buffer, indirect multi-draw (004's ROC)",
    conservative: true,
    params: &[],
    needs: Needs::GpuCulling,
    check: |_| Ok(()),
    build: |_, _| Ok(Box::new(RasterOcclusionCulling::new())),
};

#[derive(Default)]
pub struct RasterOcclusionCulling {
    /// Every object its own leaf; uploaded in the first frame.
    tree: Option<GpuCullTree>,
}

impl RasterOcclusionCulling {
    pub fn new() -> Self {
        RasterOcclusionCulling::default()
    }
}

impl Culler for RasterOcclusionCulling {
    fn name(&self) -> &str {
        "roc"
    }

    fn culls_on_gpu(&self) -> bool {
        true
    }

    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats {
        let objects = &input.scene.objects;
        let tree = self
            .tree
            .get_or_insert_with(|| ctx.upload_cull_tree(&CullTree::flat(objects.len() as u32)));
        cull_on_gpu(ctx, tree, objects.iter().map(|o| o.bounds))
    }
}

/// One frame of GPU-driven culling over `tree`, whose nodes have the boxes
/// `bounds` this frame: steps 1-4 above, step 2 taken level by level from
/// the tree's seed (one level for roc's flat tree). The traversal figures
/// are counted on the GPU and added after the frame: the ones returned are
/// empty.
pub(super) fn cull_on_gpu(
    ctx: &mut FrameCtx,
    tree: &mut GpuCullTree,
    bounds: impl ExactSizeIterator<Item = Aabb>,
) -> TraversalStats {
    ctx.draw_gpu_list(tree, DrawList::Visible);
    ctx.begin_gpu_walk(tree, bounds);
    for _ in 0..tree.levels() {
        ctx.walk_gpu_level(tree);
    }
    ctx.compact_gpu_lists(tree);
    ctx.draw_gpu_list(tree, DrawList::NewlyVisible);
    TraversalStats::default()
}
