//! How a level of a GPU walk finds which of its queued nodes are visible:
//! by drawing their boxes against the depth drawn so far (004's marking
//! pass, raster_mark.wgsl: roc, ioc), or by comparing each box with a depth
//! pyramid built from that depth (pyramid_test.wgsl: hiz). Either way a
//! visible node's word of the visibility buffer becomes `VISIBLE`, so the
//! rest of the walk (pool.rs, walk.wgsl) does not know which ran.

use super::pyramid::DepthPyramid;
use super::words::{DISPATCH_OFFSET, boxes_module};
use crate::gpu::{
    BOX_TEST, GpuError, GpuSetup, GpuTimer, bind_buffers, bind_group_layout, box_index_buffer, box_test_pipeline,
    depth_only_pass, set_box_indices,
};

/// How a level finds which of its queued nodes are visible.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeTest {
    /// Each box is drawn against the depth drawn so far, and a fragment
    /// that passes marks its node (004: roc, ioc).
    Raster,
    /// Each box's nearest depth is compared, in a compute pass, with the
    /// farthest depth of a pyramid built from the depth drawn so far over
    /// the box's screen rectangle, read at the finest level where the
    /// rectangle spans at most `texels` texels across (hiz).
    Pyramid { texels: u32 },
}

/// A level's test, with what it binds per queue: `groups[i]` reads queue
/// `i`.
pub(super) enum LevelTest {
    Raster {
        mark: wgpu::RenderPipeline,
        box_indices: wgpu::Buffer,
        groups: [wgpu::BindGroup; 2],
    },
    Pyramid {
        pyramid: DepthPyramid,
        test: wgpu::ComputePipeline,
        groups: [wgpu::BindGroup; 2],
    },
}

impl LevelTest {
    /// `node_test`'s pipelines, bound to the walk's two queues (each with
    /// its level's arguments) and its visibility buffer; boxes are bound
    /// by `box_layout`'s group.
    pub(super) fn new(
        setup: &GpuSetup,
        node_test: NodeTest,
        box_layout: &wgpu::BindGroupLayout,
        queues: &[wgpu::Buffer; 2],
        level_args: &[wgpu::Buffer; 2],
        node_visible: &wgpu::Buffer,
    ) -> Result<LevelTest, GpuError> {
        use wgpu::BufferBindingType::{Storage, Uniform};
        use wgpu::ShaderStages as S;
        let gpu = setup.gpu;
        let read = Storage { read_only: true };
        let write = Storage { read_only: false };
        Ok(match node_test {
            NodeTest::Raster => {
                let module = boxes_module(gpu, "boxes.wgsl + raster_mark.wgsl", include_str!("raster_mark.wgsl"));
                let mark_layout = bind_group_layout(gpu, "mark", &[(S::VERTEX, read), (S::FRAGMENT, write)]);
                let mark = box_test_pipeline(
                    gpu,
                    "mark visible nodes",
                    &[Some(box_layout), Some(&mark_layout)],
                    wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_queued"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_mark"),
                        compilation_options: Default::default(),
                        targets: &[],
                    }),
                    BOX_TEST,
                );
                LevelTest::Raster {
                    mark,
                    box_indices: box_index_buffer(gpu),
                    groups: [0, 1].map(|i| bind_buffers(gpu, &mark_layout, &[&queues[i], node_visible])),
                }
            }
            NodeTest::Pyramid { texels } => {
                let module = boxes_module(gpu, "boxes.wgsl + pyramid_test.wgsl", &pyramid_test_source(texels));
                let test_layout = bind_group_layout(
                    gpu,
                    "pyramid test",
                    &[
                        (S::COMPUTE, read),
                        (S::COMPUTE, read),
                        (S::COMPUTE, write),
                        (S::COMPUTE, read),
                        (S::COMPUTE, Uniform),
                    ],
                );
                let pyramid = DepthPyramid::new(gpu, setup.resolution, setup.depth)?;
                let [pyramid_texels, shape] = pyramid.bindings();
                let groups = [0, 1].map(|i| {
                    let buffers = [&queues[i], &level_args[i], node_visible, pyramid_texels, shape];
                    bind_buffers(gpu, &test_layout, &buffers)
                });
                let layouts = [Some(box_layout), Some(&test_layout)];
                LevelTest::Pyramid {
                    test: gpu.compute_pipeline(&module, "cs_test", Some(&layouts)),
                    pyramid,
                    groups,
                }
            }
        })
    }

    /// Before a walk's first level: builds the pyramid, where there is one,
    /// from the depth drawn so far (last frame's visible list), within
    /// `timer`'s span.
    pub(super) fn begin(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<(&GpuTimer, usize)>) {
        if let LevelTest::Pyramid { pyramid, .. } = self {
            if let Some((t, span)) = timer {
                t.begin(encoder, span);
            }
            pyramid.encode(encoder);
            if let Some((t, span)) = timer {
                t.end(encoder, span);
            }
        }
    }

    /// Marks the visible nodes of queue `input`, whose level's arguments
    /// (`arguments`) hold an indexed indirect draw of its boxes and, at
    /// [`DISPATCH_OFFSET`], an indirect dispatch over it.
    pub(super) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        boxes: &wgpu::BindGroup,
        input: usize,
        arguments: &wgpu::Buffer,
    ) {
        match self {
            LevelTest::Raster {
                mark,
                box_indices,
                groups,
            } => {
                let mut pass = depth_only_pass(encoder, "mark visible nodes", depth, None);
                pass.set_pipeline(mark);
                pass.set_bind_group(0, boxes, &[]);
                pass.set_bind_group(1, &groups[input], &[]);
                set_box_indices(&mut pass, box_indices);
                pass.draw_indexed_indirect(arguments, 0);
            }
            LevelTest::Pyramid { test, groups, .. } => {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("test boxes against the pyramid"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(test);
                pass.set_bind_group(0, boxes, &[]);
                pass.set_bind_group(1, &groups[input], &[]);
                pass.dispatch_workgroups_indirect(arguments, DISPATCH_OFFSET);
            }
        }
    }

    /// The pyramid, where the test has one.
    #[cfg(test)]
    pub(super) fn pyramid(&self) -> Option<&DepthPyramid> {
        match self {
            LevelTest::Pyramid { pyramid, .. } => Some(pyramid),
            LevelTest::Raster { .. } => None,
        }
    }
}

/// pyramid_test.wgsl after the one constant it takes from the mode's
/// parameters (the shared ones come from [`boxes_module`]).
pub(super) fn pyramid_test_source(texels: u32) -> String {
    format!(
        "const MAX_TEXELS: u32 = {texels}u;\n{}",
        include_str!("pyramid_test.wgsl")
    )
}
