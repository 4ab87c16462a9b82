//! Occlusion queries on bounding boxes, one batch at a time: every box of a
//! batch is drawn with depth test on and depth/colour writes off inside its
//! own occlusion query, all results are resolved in one go and read back in
//! one GPU→CPU round trip. A query set holds at most 4096 queries, so a
//! larger batch spans several sets (still one round trip).

use std::time::{Duration, Instant};

use glam::{DVec3, Vec4};

use super::targets::DEPTH_FORMAT;
use super::{GpuContext, Readback};
use crate::bounds::Aabb;
use crate::camera::Camera;

/// wgpu's limit on queries per query set.
pub const QUERIES_PER_SET: u32 = 4096;

/// Boxes are grown by this fraction of their distance from the eye before
/// they are drawn, so a box face that coincides with geometry (a building's
/// box and its wall) stays in front of it despite f32 rounding (~1e-7).
const EXPANSION: f64 = 1e-4;

/// The result of testing one box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxVisibility {
    /// The box reaches the near plane or holds the eye: visible, and no query
    /// was issued (its projection is unbounded).
    Unqueried,
    /// Samples that passed the depth test: a count on Vulkan, 0 or 1 on GL.
    Samples(u64),
}

impl BoxVisibility {
    pub fn is_visible(self) -> bool {
        !matches!(self, BoxVisibility::Samples(0))
    }
}

/// Eye-relative corners, as the shader reads them.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct QueryBox {
    min: Vec4,
    max: Vec4,
}

/// Pipelines and buffers for query batches, reused by every mode and frame.
pub struct QueryPool {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    camera: wgpu::Buffer,
    capacity: u32,
    boxes: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    sets: Vec<wgpu::QuerySet>,
    /// Two timestamps around a batch's query passes, where supported.
    timestamps: Option<(wgpu::QuerySet, f64)>,
    resolved: wgpu::Buffer,
    readback: Readback,
    /// Scratch, reused so a batch allocates nothing once warm.
    staging: Vec<QueryBox>,
    queried: Vec<usize>,
    samples: Vec<u64>,
}

/// What one batch cost.
pub struct BatchCost {
    pub queries: u64,
    /// Time from submitting the batch until its results were on the CPU.
    pub wait: Duration,
    /// GPU time of the query passes alone (timestamps), where available.
    pub gpu: Option<Duration>,
}

/// Where results start in the resolve buffer: after the two timestamps that
/// bracket the query passes, at the 256-byte resolve alignment.
const RESULTS_OFFSET: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

impl QueryPool {
    /// `camera` is the uniform buffer the scene renderer fills per frame.
    pub fn new(gpu: &GpuContext, camera: &wgpu::Buffer) -> QueryPool {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("boxes.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/boxes.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("query boxes"),
            entries: &[
                buffer_entry(0, wgpu::BufferBindingType::Uniform),
                buffer_entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("query boxes"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("query boxes"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_box"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: Some(wgpu::Face::Back),
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                // Reverse-Z: nearer is greater. Equal passes, so a box face
                // on a surface is not judged hidden by it.
                depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: None,
            multiview_mask: None,
            cache: None,
        });
        let (boxes, bind_group) = box_buffer(gpu, &layout, camera, QUERIES_PER_SET);
        let mut pool = QueryPool {
            pipeline,
            layout,
            camera: camera.clone(),
            capacity: QUERIES_PER_SET,
            boxes,
            bind_group,
            sets: Vec::new(),
            timestamps: gpu.timestamps.then(|| {
                let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("query pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                (set, f64::from(gpu.queue.get_timestamp_period()))
            }),
            resolved: result_buffer(gpu, QUERIES_PER_SET),
            readback: Readback::new(gpu, "query readback", result_bytes(QUERIES_PER_SET)),
            staging: Vec::new(),
            queried: Vec::new(),
            samples: Vec::new(),
        };
        pool.sets.push(query_set(gpu));
        pool
    }

    /// Tests `boxes` against `depth` after the work already in `encoder`:
    /// submits it with the batch, waits for the results, and writes one
    /// [`BoxVisibility`] per box to `out`.
    pub fn test(
        &mut self,
        gpu: &GpuContext,
        mut encoder: wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        camera: &Camera,
        boxes: &[Aabb],
        out: &mut Vec<BoxVisibility>,
    ) -> BatchCost {
        out.clear();
        self.staging.clear();
        self.queried.clear();
        let view = camera.view_rotation();
        for (i, b) in boxes.iter().enumerate() {
            let (min, max) = (b.min - camera.eye, b.max - camera.eye);
            let reach = min.abs().max(max.abs()).max_element();
            let grow = DVec3::splat(EXPANSION * reach + f64::MIN_POSITIVE);
            let (min, max) = (min - grow, max + grow);
            // The box reaches the near plane when a corner is nearer than it
            // along the view direction (this also covers holding the eye).
            let nearest = Aabb::new(min, max)
                .corners()
                .iter()
                .map(|&c| -(view * c).z)
                .fold(f64::INFINITY, f64::min);
            if nearest <= camera.near {
                out.push(BoxVisibility::Unqueried);
            } else {
                out.push(BoxVisibility::Samples(0));
                self.queried.push(i);
                self.staging.push(QueryBox {
                    min: min.as_vec3().extend(0.0),
                    max: max.as_vec3().extend(0.0),
                });
            }
        }
        let count = self.staging.len() as u32;
        if count == 0 {
            gpu.queue.submit([encoder.finish()]);
            return BatchCost {
                queries: 0,
                wait: Duration::ZERO,
                gpu: None,
            };
        }
        self.reserve(gpu, count);
        gpu.queue
            .write_buffer(&self.boxes, 0, bytemuck::cast_slice(&self.staging));
        if let Some((set, _)) = &self.timestamps {
            encoder.write_timestamp(set, 0);
        }
        for (set_index, first) in (0..count).step_by(QUERIES_PER_SET as usize).enumerate() {
            let n = (count - first).min(QUERIES_PER_SET);
            let set = &self.sets[set_index];
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("occlusion queries"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: Some(set),
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                for q in 0..n {
                    pass.begin_occlusion_query(q);
                    pass.draw(0..36, first + q..first + q + 1);
                    pass.end_occlusion_query();
                }
            }
            encoder.resolve_query_set(set, 0..n, &self.resolved, RESULTS_OFFSET + u64::from(first) * 8);
        }
        if let Some((set, _)) = &self.timestamps {
            encoder.write_timestamp(set, 1);
            encoder.resolve_query_set(set, 0..2, &self.resolved, 0);
        }
        let bytes = RESULTS_OFFSET + u64::from(count) * 8;
        self.readback.copy_from(&mut encoder, &self.resolved, bytes);
        let submitted = Instant::now();
        gpu.queue.submit([encoder.finish()]);
        self.readback.read(gpu, bytes, &mut self.samples);
        let wait = submitted.elapsed();
        let results = &self.samples[(RESULTS_OFFSET / 8) as usize..];
        for (&i, &s) in self.queried.iter().zip(results) {
            out[i] = BoxVisibility::Samples(s);
        }
        let gpu_time = self.timestamps.as_ref().map(|&(_, period_ns)| {
            let ticks = self.samples[1].saturating_sub(self.samples[0]);
            Duration::from_nanos((ticks as f64 * period_ns) as u64)
        });
        BatchCost {
            queries: u64::from(count),
            wait,
            gpu: gpu_time,
        }
    }

    /// Grows the buffers and query sets to hold `count` boxes.
    fn reserve(&mut self, gpu: &GpuContext, count: u32) {
        if count > self.capacity {
            let capacity = count.next_multiple_of(QUERIES_PER_SET);
            (self.boxes, self.bind_group) = box_buffer(gpu, &self.layout, &self.camera, capacity);
            self.resolved = result_buffer(gpu, capacity);
            self.readback = Readback::new(gpu, "query readback", result_bytes(capacity));
            self.capacity = capacity;
        }
        while (self.sets.len() as u32) * QUERIES_PER_SET < count {
            self.sets.push(query_set(gpu));
        }
    }
}

fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn box_buffer(
    gpu: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    camera: &wgpu::Buffer,
    capacity: u32,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let boxes = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("query boxes"),
        size: u64::from(capacity) * std::mem::size_of::<QueryBox>() as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("query boxes"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: boxes.as_entire_binding(),
            },
        ],
    });
    (boxes, bind_group)
}

fn result_bytes(capacity: u32) -> u64 {
    RESULTS_OFFSET + u64::from(capacity) * 8
}

fn result_buffer(gpu: &GpuContext, capacity: u32) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("query results"),
        size: result_bytes(capacity),
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

fn query_set(gpu: &GpuContext) -> wgpu::QuerySet {
    gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("occlusion queries"),
        ty: wgpu::QueryType::Occlusion,
        count: QUERIES_PER_SET,
    })
}
