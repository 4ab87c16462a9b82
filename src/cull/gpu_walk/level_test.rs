//! How a level of a GPU walk finds which of its queued nodes are visible:
//! by drawing their boxes against the depth drawn so far (004's marking
//! pass, raster_mark.wgsl: roc, ioc), or by comparing each box with a depth
//! pyramid built from that depth (pyramid_test.wgsl: hiz). Either way a
//! visible node's word of the visibility buffer becomes `VISIBLE`, so the
//! rest of the walk (walk.rs, walk.wgsl) does not know which ran.

use super::layout::{DISPATCH_OFFSET, MAX_GROUPS, boxes_module};
use super::pyramid::DepthPyramid;
use crate::gpu::{
    BOX_TEST, GpuContext, GpuError, GpuSetup, GpuTimer, PLANE_ROUNDING, UNBOUNDED, bind_buffers, bind_group_layout,
    box_index_buffer, box_test_pipeline, depth_only_pass, set_box_indices, storage_buffer,
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
    /// rectangle spans at most `texels` texels across (hiz; the base is the
    /// largest power of two at most the target over `base_divisor`); where that
    /// fails and the rectangle holds at most `pixels` pixels, the box is
    /// compared with the depth itself at each of them.
    Pyramid {
        texels: u32,
        base_divisor: u32,
        pixels: u32,
    },
}

impl NodeTest {
    /// Whether it reads the depth pixel by pixel.
    fn reads_pixels(&self) -> bool {
        matches!(self, NodeTest::Pyramid { pixels, .. } if *pixels > 0)
    }
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
        pixels: Box<PixelTest>,
    },
}

/// hiz's pixel by pixel test, what pyramid_test.wgsl binds as group 2:
/// the depth, and the boxes the pyramid did not hide (`PixelWork`); where
/// the test reads no pixels, the same bindings, one entry long, and no
/// passes.
pub(super) struct PixelTest {
    /// `PixelWork`: the indirect dispatch of `cs_pixels`, the count queued,
    /// the queue.
    work: wgpu::Buffer,
    /// `work`'s first words as each level starts: no workgroups, none
    /// queued.
    reset: wgpu::Buffer,
    /// `work` bound to write (binding 1, for `cs_test` and
    /// `cs_pixel_args`), and to read (binding 2, for `cs_pixels`, whose
    /// dispatch reads it as arguments too: a buffer bound to write may not
    /// be read so in the same dispatch).
    write_group: wgpu::BindGroup,
    read_group: wgpu::BindGroup,
    /// `cs_pixel_args` and `cs_pixels`.
    passes: Option<[wgpu::ComputePipeline; 2]>,
}

/// Bytes of `PixelWork` before its queue.
const PIXEL_WORK_HEADER: u64 = 16;

impl PixelTest {
    /// The test for a tree of `nodes` nodes, reading `depth`, without its
    /// passes (none where no pixel is read).
    fn new(
        gpu: &GpuContext,
        depth: &wgpu::TextureView,
        nodes: u32,
        reads: bool,
    ) -> (PixelTest, [wgpu::BindGroupLayout; 2]) {
        use wgpu::ShaderStages as S;
        // A queue as long as a dispatch is wide.
        let queued = if reads { nodes.clamp(1, MAX_GROUPS) } else { 1 };
        let work = storage_buffer(
            gpu,
            "boxes tested pixel by pixel",
            // A struct binding is a whole number of its 16-byte alignment.
            (PIXEL_WORK_HEADER + 4 * u64::from(queued)).next_multiple_of(16),
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::INDIRECT,
        );
        let reset = gpu.buffer_with(
            "no boxes tested pixel by pixel",
            bytemuck::cast_slice(&[0u32, 1, 1, 0]),
            wgpu::BufferUsages::COPY_SRC,
        );
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: S::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let depth_entry = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: S::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        // Binding `work_binding` is the queue, to write (1) or read (2).
        let bind = |work_binding: u32| {
            let layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("pixel test"),
                entries: &[depth_entry, storage(work_binding, work_binding == 2)],
            });
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pixel test"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(depth),
                    },
                    wgpu::BindGroupEntry {
                        binding: work_binding,
                        resource: work.as_entire_binding(),
                    },
                ],
            });
            (layout, group)
        };
        let ((write_layout, write_group), (read_layout, read_group)) = (bind(1), bind(2));
        let test = PixelTest {
            work,
            reset,
            write_group,
            read_group,
            passes: None,
        };
        (test, [write_layout, read_layout])
    }
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
        nodes: u32,
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
            NodeTest::Pyramid {
                texels,
                base_divisor,
                pixels,
            } => {
                let module = boxes_module(
                    gpu,
                    "boxes.wgsl + pyramid_test.wgsl",
                    &pyramid_test_source(texels, pixels),
                );
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
                let pyramid = DepthPyramid::new(gpu, setup.resolution, base_divisor, setup.depth)?;
                let [pyramid_texels, shape] = pyramid.bindings();
                let groups = [0, 1].map(|i| {
                    let buffers = [&queues[i], &level_args[i], node_visible, pyramid_texels, shape];
                    bind_buffers(gpu, &test_layout, &buffers)
                });
                let (mut pixels, [write_layout, read_layout]) =
                    PixelTest::new(gpu, setup.depth, nodes, node_test.reads_pixels());
                let pipeline = |entry, pixels_layout| {
                    let layouts = [Some(box_layout), Some(&test_layout), Some(pixels_layout)];
                    gpu.compute_pipeline(&module, entry, Some(&layouts))
                };
                if node_test.reads_pixels() {
                    pixels.passes = Some([
                        pipeline("cs_pixel_args", &write_layout),
                        pipeline("cs_pixels", &read_layout),
                    ]);
                }
                LevelTest::Pyramid {
                    test: pipeline("cs_test", &write_layout),
                    pyramid,
                    groups,
                    pixels: Box::new(pixels),
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
    /// [`DISPATCH_OFFSET`], an indirect dispatch over it. The marking pass
    /// draws against `depth`; the pyramid test reads the depth it was made
    /// over (the same target: [`GpuSetup::depth`]).
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
            LevelTest::Pyramid {
                test, groups, pixels, ..
            } => {
                if pixels.passes.is_some() {
                    encoder.copy_buffer_to_buffer(&pixels.reset, 0, &pixels.work, 0, PIXEL_WORK_HEADER);
                }
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("test boxes against the pyramid"),
                    timestamp_writes: None,
                });
                pass.set_bind_group(0, boxes, &[]);
                pass.set_bind_group(1, &groups[input], &[]);
                pass.set_bind_group(2, &pixels.write_group, &[]);
                pass.set_pipeline(test);
                pass.dispatch_workgroups_indirect(arguments, DISPATCH_OFFSET);
                // The boxes it queued, each by a workgroup of its own.
                if let Some([sizes, test_pixels]) = &pixels.passes {
                    pass.set_pipeline(sizes);
                    pass.dispatch_workgroups(1, 1, 1);
                    pass.set_bind_group(2, &pixels.read_group, &[]);
                    pass.set_pipeline(test_pixels);
                    pass.dispatch_workgroups_indirect(&pixels.work, 0);
                }
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

/// pyramid_test.wgsl after the constants it takes from the mode's
/// parameters (the shared ones come from [`boxes_module`]).
pub(super) fn pyramid_test_source(texels: u32, pixels: u32) -> String {
    format!(
        "const MAX_TEXELS: u32 = {texels}u;\nconst MAX_PIXELS: u32 = {pixels}u;\n\
         const PLANE_ROUNDING: f32 = {PLANE_ROUNDING:e};\nconst UNBOUNDED: f32 = {UNBOUNDED:e};\n{}",
        include_str!("pyramid_test.wgsl")
    )
}
