//! `roc`: raster occlusion culling, the comparator of paper 004 (its [1, 2]):
//! "directly marking visible objects during the rasterization, leveraged by
//! early Z and unordered buffer access", with "indirect multidraw commands to
//! avoid GPU-to-CPU read-back". Every object is a leaf of a flat tree, all
//! tested in one level; the frame is the module above's.

use super::{GpuCulling, NodeTest, Walked};
use crate::cull::mode::{Candidacy, Carries, ModeId, ModeInfo, Needs};

/// This mode's entry in the registry.
pub(in crate::cull) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Roc,
    summary: "raster occlusion culling on the GPU: every object's box marks a visibility buffer, indirect multi-draw (004's ROC)",
    chart_colour: [23, 190, 207],
    conservative: true,
    draws_by_time: false,
    params: &[],
    exercised_with: &[],
    needs: Needs::GpuCulling,
    carries: Carries::VisibleOnGpu,
    auto: Candidacy::Always,
    check: |_| Ok(()),
    build: |_, _| Ok(Box::new(raster_occlusion_culling())),
};

/// roc: every object's box, drawn against the depth.
pub fn raster_occlusion_culling() -> GpuCulling {
    GpuCulling::new(ModeId::Roc, Walked::Objects, NodeTest::Raster, serde_json::json!({}))
}
