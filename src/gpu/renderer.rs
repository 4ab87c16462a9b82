//! The scene on the GPU and the two pipelines that draw it: `shaded` (what
//! every mode renders, timed) and `reference` (depth and object ids for the
//! error measure, untimed). Both share one vertex stage.

use glam::Mat4;

use super::conservative::{BoxMargins, FragmentLimit, PixelRays};
use super::context::{GpuContext, GpuError};
use super::resolution::Resolution;
use super::targets::{COLOR_FORMAT, DEPTH_FORMAT, ID_FORMAT, RenderTargets};
use crate::camera::Camera;
use crate::scene::{Object, Scene};

/// The index range an object draws.
#[derive(Clone, Copy, Debug)]
pub struct DrawRange {
    pub first_index: u32,
    pub index_count: u32,
}

/// What scene.wgsl knows of one object (`struct Object`), rewritten every
/// frame.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ObjectData {
    /// Camera-relative model-view matrix.
    model_view: Mat4,
    /// No fragment of the object is nearer than this (see
    /// `gpu/conservative.rs`, rule 2).
    limit: FragmentLimit,
}

// The WGSL structs' sizes: a mismatch would shift every field after it.
const _: () = assert!(std::mem::size_of::<ObjectData>() == 80);
const _: () = assert!(std::mem::size_of::<CameraUniform>() == 176);

/// Geometry and per-object data in GPU buffers.
pub struct GpuScene {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// One [`ObjectData`] per object.
    object_data: wgpu::Buffer,
    pub draws: Vec<DrawRange>,
    /// Reused every frame, so the upload allocates nothing.
    staging: Vec<ObjectData>,
    /// Per object, its bounds' centre's squared distance from the eye, as
    /// [`SceneRenderer::set_camera`] last set it: what
    /// [`SceneRenderer::order_nearest_first`] sorts by.
    distances: Vec<f32>,
}

impl GpuScene {
    pub fn upload(gpu: &GpuContext, scene: &Scene) -> Result<GpuScene, GpuError> {
        let limits = gpu.device.limits();
        let check = |what, need: u64, limit: u64| {
            if need > limit {
                Err(GpuError::TooLarge { what, need, limit })
            } else {
                Ok(())
            }
        };
        let vertex_bytes = std::mem::size_of_val(scene.vertices.as_slice()) as u64;
        let index_bytes = std::mem::size_of_val(scene.indices.as_slice()) as u64;
        let object_bytes = (scene.objects.len() * std::mem::size_of::<ObjectData>()) as u64;
        check("vertex buffer", vertex_bytes, limits.max_buffer_size)?;
        check("index buffer", index_bytes, limits.max_buffer_size)?;
        check(
            "per-object storage binding",
            object_bytes,
            limits.max_storage_buffer_binding_size,
        )?;
        let init = |label, contents: &[u8], usage| gpu.buffer_with(label, contents, usage);
        Ok(GpuScene {
            vertices: init(
                "vertices",
                bytemuck::cast_slice(&scene.vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: init(
                "indices",
                bytemuck::cast_slice(&scene.indices),
                wgpu::BufferUsages::INDEX,
            ),
            object_data: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("object data"),
                size: object_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            draws: scene
                .objects
                .iter()
                .map(|o| {
                    let m = &scene.meshes[o.mesh as usize];
                    DrawRange {
                        first_index: m.first_index,
                        index_count: m.index_count,
                    }
                })
                .collect(),
            staging: Vec::with_capacity(scene.objects.len()),
            distances: Vec::with_capacity(scene.objects.len()),
        })
    }
}

/// camera.wgsl: `struct Camera` ([`CameraUniform`]) and its binding, which
/// every shader that reads the camera starts with.
pub(crate) const CAMERA_WGSL: &str = include_str!("../../shaders/camera.wgsl");

/// A shader module of camera.wgsl followed by `parts`.
pub(crate) fn module_with_camera(gpu: &GpuContext, label: &str, parts: &[&str]) -> wgpu::ShaderModule {
    let source: String = std::iter::once(CAMERA_WGSL).chain(parts.iter().copied()).collect();
    gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// The camera as every shader reads it (`struct Camera` in camera.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraUniform {
    /// Camera space to clip space: scene geometry.
    projection: Mat4,
    /// Eye-relative world positions to clip space: test boxes, the
    /// overview's lines.
    view_projection: Mat4,
    /// The world direction of the ray through pixel (x, y) is
    /// `x · rays[0] + y · rays[1] + rays[2]`: for fragment limits.
    rays: [glam::Vec4; 3],
}

pub struct SceneRenderer {
    pub scene: GpuScene,
    camera: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    shaded: wgpu::RenderPipeline,
    reference: wgpu::RenderPipeline,
    /// Counts surfaces per pixel (no depth test), for pictures.
    heat: wgpu::RenderPipeline,
}

impl CameraUniform {
    /// `camera` for a picture of `resolution`.
    fn new(camera: &Camera, resolution: Resolution) -> CameraUniform {
        let projection = camera.projection();
        CameraUniform {
            projection: projection.as_mat4(),
            view_projection: (projection * glam::DMat4::from_mat3(camera.view_rotation())).as_mat4(),
            rays: PixelRays::new(camera, resolution).uniform(),
        }
    }
}

/// A camera uniform of its own, for tests of a shader that reads it.
#[cfg(test)]
pub(crate) fn camera_buffer(gpu: &GpuContext, camera: &Camera, resolution: Resolution) -> wgpu::Buffer {
    let uniform = CameraUniform::new(camera, resolution);
    gpu.buffer_with("camera", bytemuck::bytes_of(&uniform), wgpu::BufferUsages::UNIFORM)
}

impl SceneRenderer {
    pub fn new(gpu: &GpuContext, scene: GpuScene) -> SceneRenderer {
        let device = &gpu.device;
        let module = module_with_camera(gpu, "scene.wgsl", &[include_str!("../../shaders/scene.wgsl")]);
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: std::mem::size_of::<CameraUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        };
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &[
                // The fragment stage reads the camera's pixel rays; objects
                // reach it as varyings (some GLES adapters have no storage
                // buffers in fragment shaders).
                entry(
                    0,
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    buffer(wgpu::BufferBindingType::Uniform),
                ),
                entry(
                    1,
                    wgpu::ShaderStages::VERTEX,
                    buffer(wgpu::BufferBindingType::Storage { read_only: true }),
                ),
            ],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: camera.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: scene.object_data.as_entire_binding(),
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        // `depth`: test and write depth; otherwise `blend` accumulates.
        let pipeline = |label, fragment_entry, target: wgpu::ColorTargetState, depth: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: 12,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                    })],
                },
                // No back-face culling: file winding is unreliable, and
                // visibility must not depend on it.
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: depth.then(|| wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Greater),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment_entry),
                    compilation_options: Default::default(),
                    targets: &[Some(target)],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        SceneRenderer {
            shaded: pipeline("shaded", "fs_shaded", COLOR_FORMAT.into(), true),
            reference: pipeline("reference", "fs_object_id", ID_FORMAT.into(), true),
            heat: pipeline(
                "depth complexity",
                "fs_heat",
                wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: Some(wgpu::BlendState {
                        color: wgpu::BlendComponent {
                            src_factor: wgpu::BlendFactor::One,
                            dst_factor: wgpu::BlendFactor::One,
                            operation: wgpu::BlendOperation::Add,
                        },
                        alpha: wgpu::BlendComponent::REPLACE,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                },
                false,
            ),
            scene,
            camera,
            bind_group,
        }
    }

    /// The uniform set by [`SceneRenderer::set_camera`], a [`CameraUniform`].
    pub fn camera_uniform(&self) -> &wgpu::Buffer {
        &self.camera
    }

    /// Uploads the camera uniform and, for every object, its camera-relative
    /// model-view matrix (computed in f64 from the objects' current
    /// transforms, rounded to f32 last) and its fragment limit for a
    /// picture of `resolution`; keeps each object's distance from the eye
    /// for [`Self::order_nearest_first`].
    pub fn set_camera(&mut self, gpu: &GpuContext, camera: &Camera, resolution: Resolution, objects: &[Object]) {
        let scene = &mut self.scene;
        let view = camera.view_rotation();
        let margins = BoxMargins::new(gpu.depth_margins, gpu.subpixel, camera, resolution);
        scene.staging.clear();
        scene.staging.extend(objects.iter().map(|o| ObjectData {
            model_view: glam::DMat4::from(camera.model_view(&o.transform)).as_mat4(),
            limit: FragmentLimit::new(camera, &view, margins, &o.bounds),
        }));
        gpu.queue
            .write_buffer(&scene.object_data, 0, bytemuck::cast_slice(&scene.staging));
        scene.distances.clear();
        scene.distances.extend(
            objects
                .iter()
                .map(|o| o.bounds.center().distance_squared(camera.eye) as f32),
        );
        let uniform = CameraUniform::new(camera, resolution);
        gpu.queue.write_buffer(&self.camera, 0, bytemuck::bytes_of(&uniform));
    }

    /// Orders `objects` nearest first by their bounds' centres (ties by
    /// index), as an engine sorts its opaque draws: what is drawn first
    /// fills the depth buffer, so that the GPU's early depth test spares the
    /// shading of what lies behind it. Every list of objects a mode draws
    /// goes through here (the frame's queue), so a mode's time says what
    /// it culled, not the order in which its culling happened to find what
    /// it draws. (Measured on llvmpipe
    /// and lavapipe, as a share of `roc`'s frame, whose indirect draws this
    /// order leaves alone: `vfc` on the default city 3.25–3.49 in
    /// hierarchy order, 3.01–3.19 nearest first; on the two-cylinder
    /// engine 1.42–1.50 and 1.27–1.43; on the bunny 1.02–1.08 and
    /// 0.97–1.01.)
    pub fn order_nearest_first(&self, objects: &mut [u32]) {
        let distances = &self.scene.distances;
        debug_assert_eq!(distances.len(), self.scene.draws.len(), "set_camera comes first");
        // A distance is never negative, so its bits sort as it does.
        objects.sort_unstable_by_key(|&o| (u64::from(distances[o as usize].to_bits()) << 32) | u64::from(o));
    }

    /// Records a shaded pass into `depth` drawing `draws`, clearing first
    /// when `clear` is set.
    pub fn encode_shaded(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        depth: &wgpu::TextureView,
        clear: bool,
        draws: Draws,
    ) {
        let color_load = if clear {
            wgpu::LoadOp::Clear(wgpu::Color {
                r: 0.62,
                g: 0.74,
                b: 0.86,
                a: 1.0,
            })
        } else {
            wgpu::LoadOp::Load
        };
        let mut pass = begin_pass(encoder, "shaded", &targets.color, color_load, depth, clear);
        self.draw(&mut pass, &self.shaded, draws);
    }

    /// Records the reference pass: every object into the reference depth and
    /// object-id targets.
    pub fn encode_reference(&self, encoder: &mut wgpu::CommandEncoder, targets: &RenderTargets, all: &[u32]) {
        let mut pass = begin_pass(
            encoder,
            "reference",
            &targets.reference_ids,
            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            &targets.reference_depth,
            true,
        );
        self.draw(&mut pass, &self.reference, Draws::Objects(all));
    }

    /// Records a pass counting, per pixel of `target`, the surfaces of
    /// `objects` drawn over it (depth complexity, saturating at 255).
    pub fn encode_depth_complexity(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        objects: &[u32],
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth complexity"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draw(&mut pass, &self.heat, Draws::Objects(objects));
    }

    fn draw(&self, pass: &mut wgpu::RenderPass, pipeline: &wgpu::RenderPipeline, draws: Draws) {
        if let Draws::Objects([])
        | Draws::Indirect(IndirectDraws {
            count: IndirectCount::Known(0),
            ..
        }) = draws
        {
            return;
        }
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
        pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        match draws {
            Draws::Objects(objects) => {
                for &o in objects {
                    let d = self.scene.draws[o as usize];
                    pass.draw_indexed(d.first_index..d.first_index + d.index_count, 0, o..o + 1);
                }
            }
            Draws::Indirect(IndirectDraws {
                commands,
                offset,
                count,
            }) => match count {
                IndirectCount::Known(n) => pass.multi_draw_indexed_indirect(commands, offset, n),
                IndirectCount::InBuffer {
                    buffer,
                    offset: count_offset,
                    max,
                } => pass.multi_draw_indexed_indirect_count(commands, offset, buffer, count_offset, max),
            },
        }
    }
}

/// How many commands an indirect multi-draw takes.
pub enum IndirectCount<'b> {
    /// Known on the CPU.
    Known(u32),
    /// A `u32` in a GPU buffer at an offset, at most `max`.
    InBuffer {
        buffer: &'b wgpu::Buffer,
        offset: u64,
        max: u32,
    },
}

/// Draw commands built on the GPU.
pub struct IndirectDraws<'b> {
    pub commands: &'b wgpu::Buffer,
    pub offset: u64,
    pub count: IndirectCount<'b>,
}

/// What a pass draws: objects named on the CPU, or commands the GPU built.
pub enum Draws<'b> {
    Objects(&'b [u32]),
    Indirect(IndirectDraws<'b>),
}

fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: &wgpu::TextureView,
    color_load: wgpu::LoadOp<wgpu::Color>,
    depth: &wgpu::TextureView,
    clear_depth: bool,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: color_load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                // Reverse-Z: 0 is infinitely far.
                load: if clear_depth {
                    wgpu::LoadOp::Clear(0.0)
                } else {
                    wgpu::LoadOp::Load
                },
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::*;
    use crate::gpu::wgsl::{parse, struct_layout};

    fn members(names: &[(&str, u32)]) -> Vec<(String, u32)> {
        names.iter().map(|&(n, o)| (n.to_string(), o)).collect()
    }

    #[test]
    fn the_camera_and_an_object_are_laid_out_as_the_shaders_read_them() {
        let module = parse(&[CAMERA_WGSL, include_str!("../../shaders/scene.wgsl")].concat());
        let (camera, size) = struct_layout(&module, "Camera");
        assert_eq!(
            camera,
            members(&[
                ("projection", 0),
                ("view_projection", 64),
                ("ray_x", 128),
                ("ray_y", 144),
                ("ray_c", 160)
            ])
        );
        assert_eq!(size_of::<CameraUniform>(), size as usize);
        assert_eq!(offset_of!(CameraUniform, view_projection), 64);
        assert_eq!(offset_of!(CameraUniform, rays), 128);
        let (object, size) = struct_layout(&module, "Object");
        assert_eq!(object, members(&[("model_view", 0), ("limit", 64)]));
        assert_eq!(size_of::<ObjectData>(), size as usize);
        assert_eq!(offset_of!(ObjectData, limit), 64);
    }

    #[test]
    fn every_shader_that_reads_the_camera_parses_after_camera_wgsl() {
        for source in [
            include_str!("../../shaders/scene.wgsl"),
            include_str!("../../shaders/lines.wgsl"),
            super::super::BOXES_WGSL,
        ] {
            let module = parse(&[CAMERA_WGSL, source].concat());
            assert!(
                module
                    .global_variables
                    .iter()
                    .any(|(_, v)| v.name.as_deref() == Some("camera"))
            );
        }
    }
}
