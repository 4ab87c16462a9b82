//! GPU pieces of `occlu render`: reading a colour target back, and drawing
//! coloured lines (frustum edges, boxes) over a picture.

use super::context::GpuContext;
use super::readback::Readback;
use super::renderer::module_with_camera;
use super::resolution::Resolution;
use super::targets::{COLOR_FORMAT, texture_2d};

/// One end of a line: eye-relative world position and colour (0..1).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LineVertex {
    pub position: [f32; 3],
    pub colour: [f32; 3],
}

/// Draws line lists with the camera uniform the scene renderer fills.
pub struct LinePainter {
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
}

impl LinePainter {
    pub fn new(gpu: &GpuContext, camera: &wgpu::Buffer) -> LinePainter {
        let device = &gpu.device;
        let module = module_with_camera(gpu, "lines.wgsl", &[include_str!("../../shaders/lines.wgsl")]);
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lines"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_line"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<LineVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::LineList,
                ..Default::default()
            },
            // Over everything: the culled boxes are what the picture is for.
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_line"),
                compilation_options: Default::default(),
                targets: &[Some(COLOR_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lines"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        LinePainter { pipeline, bind_group }
    }

    /// Draws `lines` (pairs of vertices) over `target` and waits.
    pub fn draw(&self, gpu: &GpuContext, target: &wgpu::TextureView, lines: &[LineVertex]) {
        if lines.is_empty() {
            return;
        }
        let vertices = gpu.buffer_with("lines", bytemuck::cast_slice(lines), wgpu::BufferUsages::VERTEX);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lines"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.draw(0..lines.len() as u32, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait_idle();
    }
}

/// A colour texture that can be drawn into, copied into and read back.
pub fn picture_target(gpu: &GpuContext, resolution: Resolution) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST;
    texture_2d(gpu, "picture", resolution, COLOR_FORMAT, usage)
}

/// Reads an RGBA8 texture back as tightly packed RGB rows.
pub fn read_rgb(gpu: &GpuContext, texture: &wgpu::Texture, resolution: Resolution) -> Vec<u8> {
    let (w, h) = (resolution.width, resolution.height);
    // Rows of a texture copy are padded to 256 bytes.
    let row = (w * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let readback = Readback::new(gpu, "picture readback", u64::from(row * h));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    readback.copy_texture(&mut encoder, texture, row, h);
    gpu.queue.submit([encoder.finish()]);
    let mut bytes: Vec<u8> = Vec::new();
    readback.read(gpu, u64::from(row * h), &mut bytes);
    bytes
        .chunks(row as usize)
        .flat_map(|r| r[..(w * 4) as usize].chunks(4).flat_map(|p| [p[0], p[1], p[2]]))
        .collect()
}
