//! `roc`: raster occlusion culling, the comparator of paper 004 (its [1, 2]):
//! "directly marking visible objects during the rasterization, leveraged by
//! early Z and unordered buffer access", with "indirect multidraw commands to
//! avoid GPU-to-CPU read-back". Every object is a leaf of a flat tree, all
//! tested in one level; the frame is the module above's.

use super::{CullTree, GpuWalk, cull_on_gpu};
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{ModeId, ModeInfo, Needs};
use crate::gpu::{Frame, GpuAudit, GpuContext, GpuSetup};
use crate::object_set::ObjectSet;

/// This mode's entry in the registry.
pub(in crate::cull) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Roc,
    summary: "raster occlusion culling on the GPU: every object's box marks a visibility buffer, indirect multi-draw (004's ROC)",
    conservative: true,
    params: &[],
    needs: Needs::GpuCulling,
    check: |_| Ok(()),
    build: |_, _| Ok(Box::new(RasterOcclusionCulling::new())),
};

#[derive(Default)]
pub struct RasterOcclusionCulling {
    /// Made in `prepare`, over a flat tree: every object its own leaf.
    walk: Option<GpuWalk>,
}

impl RasterOcclusionCulling {
    pub fn new() -> Self {
        RasterOcclusionCulling::default()
    }
}

#[cfg(test)]
impl RasterOcclusionCulling {
    /// The walk, for the test that holds it against its CPU twin.
    pub(super) fn gpu_walk(&self) -> Option<&GpuWalk> {
        self.walk.as_ref()
    }
}

impl Culler for RasterOcclusionCulling {
    fn name(&self) -> &str {
        "roc"
    }

    fn prepare(&mut self, setup: &GpuSetup) {
        let tree = CullTree::flat(setup.scene.objects.len() as u32);
        self.walk = Some(GpuWalk::new(setup, &tree));
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let bounds = input.scene.objects.iter().map(|o| o.bounds);
        cull_on_gpu(ctx, input.camera, self.walk.as_mut(), bounds)
    }

    fn audit(&mut self, gpu: &GpuContext, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        self.walk.as_mut()?.audit(gpu, drawn)
    }
}
