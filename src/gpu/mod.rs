//! Headless wgpu: adapter choice, the scene on the GPU, render targets,
//! occlusion-query batches, and the per-frame operations every culling mode
//! goes through ([`FrameCtx`]).

mod conservative;
mod context;
mod frame;
mod picture;
mod queries;
mod readback;
mod renderer;
mod resolution;
mod targets;
mod timing;
#[cfg(test)]
pub(crate) mod wgsl;

#[cfg(test)]
pub(crate) use conservative::ShaderBoxPlanes;
/// A ray caster's view of pixels and boxes, for tests of box tests.
#[cfg(test)]
pub(crate) use conservative::tests::{
    assert_planes_bound, camera as test_camera, entry_depth, pixel_ray, random_boxes_in_view,
};
pub use conservative::{BoxMargins, DepthMargins, SubpixelPrecision};
pub(crate) use conservative::{
    BoxPlanes, EyeBox, FacingFace, PLANE_ROUNDING, PixelRays, QueryBox, ScreenPlane, UNBOUNDED, eye_relative_box,
};
pub use context::{AdapterReport, BackendChoice, GpuContext, GpuError};
pub use frame::{
    Frame, FrameCounters, FrameCtx, FrameOutcome, FrameResources, GpuAudit, GpuFrame, GpuSetup, GpuWork, OpKind, OpSpan,
};
pub use picture::{LinePainter, LineVertex, picture_target, read_rgb};
/// The building blocks of box tests, for modes that test boxes their own
/// way (the GPU walk).
pub(crate) use queries::{
    BOX_INDEX_COUNT, BOX_TEST, BOXES_WGSL, bind_buffers, bind_group_layout, box_bind_group_layout, box_buffer,
    box_index_buffer, box_test_pipeline, check_storage_binding, depth_only_pass, set_box_indices, storage_buffer,
};
pub use queries::{BoxTest, BoxVisibility, QUERIES_PER_SET, QueryPool};
pub use readback::Readback;
#[cfg(test)]
pub(crate) use renderer::CAMERA_WGSL;
#[cfg(test)]
pub(crate) use renderer::camera_buffer;
pub(crate) use renderer::module_with_camera;
pub use renderer::{DrawRange, Draws, GpuScene, IndirectCount, IndirectDraws, SceneRenderer};
pub use resolution::Resolution;
pub use targets::RenderTargets;
#[cfg(test)]
pub(crate) use targets::texture_2d;
pub use timing::{GpuSpan, GpuTimer};
