//! The reference frame and the error of each mode against it (untimed).
//!
//! Per frame: direct rendering into the reference depth and object-id
//! targets, then a compute pass sets one bit per object id present (the
//! reference visible set). After every mode has rendered, one compute pass
//! per mode counts the pixels whose depth differs from the reference in any
//! bit and finds the largest difference, and one read-back returns them all.
//! Where a mode got pixels wrong, one more pass charges them to the objects
//! that own them in the reference ([`ErrorMeter::attribute_wrong_pixels`]).

use crate::gpu::{GpuContext, Readback, RenderTargets, SceneRenderer};
use crate::object_set::ObjectSet;

const WORKGROUP: u32 = 8;

pub struct ErrorMeter {
    all_objects: Vec<u32>,
    mark_visible: wgpu::ComputePipeline,
    visible_group: wgpu::BindGroup,
    visible_bits: wgpu::Buffer,
    visible_readback: Readback,
    count_wrong: wgpu::ComputePipeline,
    /// One bind group per mode: its depth target and its counter slot.
    wrong_groups: Vec<wgpu::BindGroup>,
    wrong_counts: wgpu::Buffer,
    wrong_readback: Readback,
    /// Bytes between the counter slots of two modes.
    slot_stride: u64,
    words: Vec<u32>,
    copy_depth: wgpu::ComputePipeline,
    /// The reference depth's, then each mode's.
    depth_groups: Vec<wgpu::BindGroup>,
    depth_values: wgpu::Buffer,
    depth_readback: Readback,
    attribute: Attribution,
}

/// How one mode's depth differs from the reference in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthError {
    /// Pixels whose depth differs in any bit.
    pub wrong_pixels: u64,
    /// The largest |depth − reference depth| over the frame (reverse-Z depth,
    /// `near / distance`); 0 when no pixel differs.
    pub max_difference: f32,
}

/// Wrong pixels of one mode charged to one object of the reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectError {
    pub object: u32,
    pub wrong_pixels: u64,
    /// The first wrong pixel of the object, row-major from the top left.
    pub first_pixel: (u32, u32),
}

/// The pass behind [`ErrorMeter::attribute_wrong_pixels`]: two words per
/// object (attribute_wrong_pixels in error.wgsl), one bind group per mode.
struct Attribution {
    pipeline: wgpu::ComputePipeline,
    groups: Vec<wgpu::BindGroup>,
    per_object: wgpu::Buffer,
    readback: Readback,
}

/// Bytes of one mode's [`DepthError`] on the GPU: two u32 atomics.
const ERROR_SLOT_BYTES: u64 = 8;

impl ErrorMeter {
    pub fn new(gpu: &GpuContext, targets: &RenderTargets, objects: usize) -> ErrorMeter {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("error.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/error.wgsl").into()),
        });
        let pipeline = |entry: &str| gpu.compute_pipeline(&module, entry, None);
        let storage = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let texture = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };

        let mark_visible = pipeline("mark_visible_objects");
        // Scenes are never empty, so this is at least one word.
        let visible_bytes = objects.div_ceil(32) as u64 * 4;
        let visible_bits = storage("reference visible set", visible_bytes);
        let visible_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mark visible"),
            layout: &mark_visible.get_bind_group_layout(0),
            entries: &[
                texture(0, &targets.reference_ids),
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: visible_bits.as_entire_binding(),
                },
            ],
        });

        let count_wrong = pipeline("count_depth_differences");
        let modes = targets.mode_depths.len();
        let slot_stride = u64::from(device.limits().min_storage_buffer_offset_alignment).max(ERROR_SLOT_BYTES);
        let wrong_counts = storage("wrong pixel counts", slot_stride * modes.max(1) as u64);
        let wrong_groups = targets
            .mode_depths
            .iter()
            .enumerate()
            .map(|(k, depth)| {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("count wrong pixels"),
                    layout: &count_wrong.get_bind_group_layout(0),
                    entries: &[
                        texture(0, &targets.reference_depth),
                        texture(1, depth),
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer: &wrong_counts,
                                offset: slot_stride * k as u64,
                                size: wgpu::BufferSize::new(ERROR_SLOT_BYTES),
                            }),
                        },
                    ],
                })
            })
            .collect();
        let copy_depth = pipeline("copy_depth");
        let depth_bytes = targets.resolution.pixels() * 4;
        let depth_values = storage("depth values", depth_bytes);
        let depth_groups = std::iter::once(&targets.reference_depth)
            .chain(&targets.mode_depths)
            .map(|depth| {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("copy depth"),
                    layout: &copy_depth.get_bind_group_layout(0),
                    entries: &[
                        texture(0, depth),
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: depth_values.as_entire_binding(),
                        },
                    ],
                })
            })
            .collect();
        let attribute = pipeline("attribute_wrong_pixels");
        let per_object_bytes = objects as u64 * 8;
        let per_object = storage("wrong pixels per object", per_object_bytes);
        let attribution = Attribution {
            groups: targets
                .mode_depths
                .iter()
                .map(|depth| {
                    device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("attribute wrong pixels"),
                        layout: &attribute.get_bind_group_layout(0),
                        entries: &[
                            texture(0, &targets.reference_depth),
                            texture(1, depth),
                            texture(2, &targets.reference_ids),
                            wgpu::BindGroupEntry {
                                binding: 3,
                                resource: per_object.as_entire_binding(),
                            },
                        ],
                    })
                })
                .collect(),
            pipeline: attribute,
            readback: Readback::new(gpu, "wrong pixels per object readback", per_object_bytes),
            per_object,
        };
        ErrorMeter {
            attribute: attribution,
            all_objects: (0..objects as u32).collect(),
            mark_visible,
            visible_group,
            visible_readback: Readback::new(gpu, "visible readback", visible_bytes),
            visible_bits,
            count_wrong,
            wrong_groups,
            wrong_readback: Readback::new(gpu, "wrong pixel readback", slot_stride * modes.max(1) as u64),
            wrong_counts,
            slot_stride,
            words: Vec::new(),
            copy_depth,
            depth_groups,
            depth_readback: Readback::new(gpu, "depth readback", depth_bytes),
            depth_values,
        }
    }

    /// Renders the reference frame for the current camera and returns the
    /// set of objects that own at least one of its pixels.
    pub fn render_reference(
        &mut self,
        gpu: &GpuContext,
        renderer: &SceneRenderer,
        targets: &RenderTargets,
    ) -> ObjectSet {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        renderer.encode_reference(&mut encoder, targets, &self.all_objects);
        encoder.clear_buffer(&self.visible_bits, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.mark_visible);
            pass.set_bind_group(0, &self.visible_group, &[]);
            dispatch_per_pixel(&mut pass, targets);
        }
        let bytes = self.visible_bits.size();
        self.visible_readback
            .copy(&mut encoder, &self.visible_bits, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        let mut words = Vec::new();
        self.visible_readback.read(gpu, bytes, &mut words);
        ObjectSet::from_words(words)
    }

    /// Measures, for every mode, how its depth differs from the reference
    /// (`encoder` may carry other end-of-frame work).
    pub fn count_wrong_pixels(
        &mut self,
        gpu: &GpuContext,
        targets: &RenderTargets,
        mut encoder: wgpu::CommandEncoder,
    ) -> Vec<DepthError> {
        encoder.clear_buffer(&self.wrong_counts, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.count_wrong);
            for group in &self.wrong_groups {
                pass.set_bind_group(0, group, &[]);
                dispatch_per_pixel(&mut pass, targets);
            }
        }
        let bytes = self.wrong_counts.size();
        self.wrong_readback.copy(&mut encoder, &self.wrong_counts, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        self.wrong_readback.read(gpu, bytes, &mut self.words);
        let stride = (self.slot_stride / 4) as usize;
        (0..self.wrong_groups.len())
            .map(|k| DepthError {
                wrong_pixels: u64::from(self.words[k * stride]),
                max_difference: f32::from_bits(self.words[k * stride + 1]),
            })
            .collect()
    }

    /// Charges mode `mode`'s wrong pixels of the last frame to the objects
    /// that own them in the reference: one entry per such object, by
    /// object id, into `out`. A pixel the reference leaves empty belongs to
    /// no object and is not charged.
    pub fn attribute_wrong_pixels(
        &mut self,
        gpu: &GpuContext,
        targets: &RenderTargets,
        mode: usize,
        out: &mut Vec<ObjectError>,
    ) {
        let a = &mut self.attribute;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&a.per_object, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&a.pipeline);
            pass.set_bind_group(0, &a.groups[mode], &[]);
            dispatch_per_pixel(&mut pass, targets);
        }
        let bytes = a.per_object.size();
        a.readback.copy(&mut encoder, &a.per_object, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        a.readback.read(gpu, bytes, &mut self.words);
        let width = targets.resolution.width;
        out.clear();
        out.extend(
            self.words
                .chunks_exact(2)
                .enumerate()
                .filter(|(_, w)| w[0] > 0)
                .map(|(object, w)| {
                    let first = !w[1];
                    ObjectError {
                        object: object as u32,
                        wrong_pixels: u64::from(w[0]),
                        first_pixel: (first % width, first / width),
                    }
                }),
        );
    }

    /// The current depth of the reference (`mode` `None`) or of mode
    /// `mode`, row-major from the top-left pixel.
    pub fn read_depth(&mut self, gpu: &GpuContext, targets: &RenderTargets, mode: Option<usize>, out: &mut Vec<f32>) {
        let group = &self.depth_groups[mode.map_or(0, |k| k + 1)];
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.copy_depth);
            pass.set_bind_group(0, group, &[]);
            dispatch_per_pixel(&mut pass, targets);
        }
        let bytes = self.depth_values.size();
        self.depth_readback.copy(&mut encoder, &self.depth_values, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        self.depth_readback.read(gpu, bytes, out);
    }
}

fn dispatch_per_pixel(pass: &mut wgpu::ComputePass, targets: &RenderTargets) {
    let r = targets.resolution;
    pass.dispatch_workgroups(r.width.div_ceil(WORKGROUP), r.height.div_ceil(WORKGROUP), 1);
}
