//! Testing bounding boxes against the depth drawn so far, one batch at a
//! time, in one of two ways:
//!
//! - **Occlusion queries**: every box is drawn inside its own occlusion
//!   query (depth test on, depth and colour writes off); a query set holds
//!   at most 4096 queries, so a larger batch spans several sets. GL reports
//!   0/1 per query, Vulkan a sample count.
//! - **Pixel counts**: all boxes in one instanced draw whose fragment stage
//!   (forced early depth test) adds one per visible pixel to the box's
//!   counter: counts on every backend, optionally sampled (002 §4.2). On
//!   request a second draw without the depth test counts each box's total
//!   pixels, visible or not (001 §3.3's additional query).
//!
//! Either way a batch costs one GPU→CPU round trip: results (and two
//! timestamps around the test passes) are resolved into one buffer and read
//! back together.

use std::time::{Duration, Instant};

use super::conservative::{BoxMargins, EyeBox, QueryBox, eye_relative_box};
use super::context::{GpuContext, GpuError};
use super::readback::Readback;
use super::renderer::module_with_camera;
use super::targets::DEPTH_FORMAT;
use super::timing::GpuSpan;
use crate::bounds::Aabb;
use crate::camera::Camera;

/// wgpu's limit on queries per query set.
pub const QUERIES_PER_SET: u32 = 4096;

/// Pixels per span of the sampled pixel count (002 §4.2: "spans of ten
/// pixels").
const SPAN: u32 = 10;

/// How a batch of boxes is tested.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxTest {
    /// One occlusion query per box.
    Occlusion,
    /// Visible pixels per box, counting only every `sampling`-th row of spans
    /// (1: every pixel). Needs [`GpuContext::pixel_counts`].
    PixelCount { sampling: u32 },
}

/// The result of testing one box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxVisibility {
    /// The box reaches the near plane or holds the eye: visible, and not
    /// tested (its projection is unbounded).
    Unqueried,
    /// Samples that passed the depth test: a count on Vulkan and for pixel
    /// counts (of the sampled pixels only), 0 or 1 for queries on GL.
    Samples(u64),
}

impl BoxVisibility {
    pub fn is_visible(self) -> bool {
        !matches!(self, BoxVisibility::Samples(0))
    }
}

/// What a batch is tested against: a mode's depth target, seen by a
/// camera, with the frame's margins.
#[derive(Clone, Copy)]
pub struct TestTarget<'a> {
    pub depth: &'a wgpu::TextureView,
    pub camera: &'a Camera,
    pub margins: BoxMargins,
}

/// Where a batch's answers go: one visibility per box, and with `totals`
/// (pixel counts only) the pixels each box covers, visible or not.
pub struct BatchAnswers<'a> {
    pub visibility: &'a mut Vec<BoxVisibility>,
    pub totals: Option<&'a mut Vec<u64>>,
}

/// What one batch cost.
pub struct BatchCost {
    /// Boxes actually tested (unqueried ones excluded).
    pub queries: u64,
    /// When the batch was submitted, and how long after it its results
    /// were on the CPU.
    pub submitted: Instant,
    pub wait: Duration,
    /// The test passes alone on the GPU (timestamps), where available.
    pub gpu: Option<GpuSpan>,
    /// CPU time spent preparing the boxes (made eye-relative, grown, the
    /// near-plane rule applied): culling work rather than GPU work.
    pub prepare: Duration,
}

/// Where results start in the read-back buffer: after the two timestamps
/// that bracket the test passes, at the 256-byte resolve alignment.
const RESULTS_OFFSET: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

/// The uniform of pixel_count.wgsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Sampling {
    step: u32,
    span: u32,
    _pad: [u32; 2],
}

/// The pixel-count pipeline and its per-box counters.
struct Counting {
    pipeline: wgpu::RenderPipeline,
    /// Counts every covered pixel into `totals`.
    totals_pipeline: wgpu::RenderPipeline,
    totals: wgpu::Buffer,
    totals_group: wgpu::BindGroup,
    layout: wgpu::BindGroupLayout,
    sampling: wgpu::Buffer,
    counts: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// Pipelines and buffers for box tests, reused by every mode and frame.
pub struct QueryPool {
    occlusion: wgpu::RenderPipeline,
    counting: Option<Counting>,
    box_layout: wgpu::BindGroupLayout,
    camera: wgpu::Buffer,
    capacity: u32,
    boxes: wgpu::Buffer,
    box_group: wgpu::BindGroup,
    box_indices: wgpu::Buffer,
    sets: Vec<wgpu::QuerySet>,
    /// Two timestamps around a batch's test passes, where supported.
    timestamps: Option<(wgpu::QuerySet, f64)>,
    resolved: wgpu::Buffer,
    readback: Readback,
    /// Scratch, reused so a batch allocates nothing once warm.
    staging: Vec<QueryBox>,
    tested: Vec<usize>,
    words: Vec<u32>,
}

/// The box vertex stage every box test draws with (a box per instance,
/// eye-relative, raised in depth: see conservative.rs), written after
/// camera.wgsl.
pub(crate) const BOXES_WGSL: &str = include_str!("../../shaders/boxes.wgsl");

impl QueryPool {
    /// `camera` is the uniform buffer the scene renderer fills per frame.
    pub fn new(gpu: &GpuContext, camera: &wgpu::Buffer) -> QueryPool {
        let device = &gpu.device;
        let module = module_with_camera(gpu, "boxes.wgsl", &[BOXES_WGSL]);
        let box_layout = box_bind_group_layout(gpu);
        // Only on adapters that have the feature: the module is invalid elsewhere.
        let count_module = gpu.pixel_counts.then(|| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("pixel_count.wgsl"),
                source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/pixel_count.wgsl").into()),
            })
        });
        let vertex = wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_box"),
            compilation_options: Default::default(),
            buffers: &[],
        };
        let pipeline = |label, layouts: &[Option<&wgpu::BindGroupLayout>], fragment, compare| {
            box_test_pipeline(gpu, label, layouts, vertex.clone(), fragment, compare)
        };
        let test = BOX_TEST;
        let occlusion = pipeline("occlusion queries", &[Some(&box_layout)], None, test);
        let counting = count_module.as_ref().map(|count_module| {
            let fragment = wgpu::ShaderStages::FRAGMENT;
            let layout = bind_group_layout(
                gpu,
                "pixel counts",
                &[
                    (fragment, wgpu::BufferBindingType::Storage { read_only: false }),
                    (fragment, wgpu::BufferBindingType::Uniform),
                ],
            );
            let fragment = wgpu::FragmentState {
                module: count_module,
                entry_point: Some("fs_count"),
                compilation_options: Default::default(),
                targets: &[],
            };
            let sampling = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("sampling"),
                size: std::mem::size_of::<Sampling>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let (counts, bind_group) = count_buffer(gpu, &layout, &sampling, QUERIES_PER_SET);
            let (totals, totals_group) = count_buffer(gpu, &layout, &sampling, QUERIES_PER_SET);
            let layouts = [Some(&box_layout), Some(&layout)];
            Counting {
                pipeline: pipeline("pixel counts", &layouts, Some(fragment.clone()), test),
                totals_pipeline: pipeline("total pixels", &layouts, Some(fragment), wgpu::CompareFunction::Always),
                totals,
                totals_group,
                layout,
                sampling,
                counts,
                bind_group,
            }
        });
        let (boxes, box_group) = box_buffer(gpu, &box_layout, camera, QUERIES_PER_SET);
        QueryPool {
            occlusion,
            counting,
            box_layout,
            camera: camera.clone(),
            capacity: QUERIES_PER_SET,
            boxes,
            box_group,
            box_indices: box_index_buffer(gpu),
            sets: vec![query_set(gpu)],
            timestamps: gpu.timestamps.then(|| {
                let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("box test timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                (set, f64::from(gpu.queue.get_timestamp_period()))
            }),
            resolved: result_buffer(gpu, QUERIES_PER_SET),
            readback: Readback::new(gpu, "box test readback", result_bytes(QUERIES_PER_SET)),
            staging: Vec::new(),
            tested: Vec::new(),
            words: Vec::new(),
        }
    }

    /// Tests `boxes` against `depth` after the work already in `encoder`:
    /// submits it with the batch, waits for the results, and writes one
    /// [`BoxVisibility`] per box to `answers`. With totals, pixel counts
    /// also count every pixel each box covers, visible or not (0 for a box
    /// that was not tested), in the same round trip.
    ///
    /// # Panics
    /// On [`BoxTest::PixelCount`] when the adapter lacks pixel counts (modes
    /// that count pixels declare it and are not run on such adapters), and
    /// on `totals` with [`BoxTest::Occlusion`].
    pub fn test(
        &mut self,
        gpu: &GpuContext,
        mut encoder: wgpu::CommandEncoder,
        target: TestTarget,
        boxes: &[Aabb],
        kind: BoxTest,
        answers: BatchAnswers,
    ) -> BatchCost {
        let BatchAnswers {
            visibility: out,
            mut totals,
        } = answers;
        assert!(
            totals.is_none() || kind != BoxTest::Occlusion,
            "total pixels are counted by pixel counts only"
        );
        let depth = target.depth;
        let started = Instant::now();
        self.prepare(target.camera, target.margins, boxes, out);
        let prepare = started.elapsed();
        if let Some(t) = totals.as_deref_mut() {
            t.clear();
            t.resize(boxes.len(), 0);
        }
        let count = self.staging.len() as u32;
        if count == 0 {
            gpu.queue.submit([encoder.finish()]);
            return BatchCost {
                queries: 0,
                submitted: Instant::now(),
                wait: Duration::ZERO,
                gpu: None,
                prepare,
            };
        }
        self.reserve(gpu, count);
        gpu.queue
            .write_buffer(&self.boxes, 0, bytemuck::cast_slice(&self.staging));
        if let Some((set, _)) = &self.timestamps {
            encoder.write_timestamp(set, 0);
        }
        let result_bytes = match kind {
            BoxTest::Occlusion => {
                self.encode_occlusion_queries(&mut encoder, depth, count);
                u64::from(count) * 8
            }
            BoxTest::PixelCount { sampling } => {
                self.encode_pixel_counts(gpu, &mut encoder, depth, count, sampling, totals.is_some());
                u64::from(count) * 4
            }
        };
        let total_bytes = if totals.is_some() { u64::from(count) * 4 } else { 0 };
        if let Some((set, _)) = &self.timestamps {
            encoder.write_timestamp(set, 1);
            encoder.resolve_query_set(set, 0..2, &self.resolved, 0);
        }
        let source = match (kind, &self.counting) {
            (BoxTest::PixelCount { .. }, Some(c)) => &c.counts,
            _ => &self.resolved,
        };
        let source_offset = if kind == BoxTest::Occlusion { RESULTS_OFFSET } else { 0 };
        self.readback.copy(&mut encoder, &self.resolved, 0, 0, 16);
        self.readback
            .copy(&mut encoder, source, source_offset, RESULTS_OFFSET, result_bytes);
        if let (Some(c), true) = (&self.counting, total_bytes > 0) {
            self.readback
                .copy(&mut encoder, &c.totals, 0, RESULTS_OFFSET + result_bytes, total_bytes);
        }
        let submitted = Instant::now();
        gpu.queue.submit([encoder.finish()]);
        self.readback
            .read(gpu, RESULTS_OFFSET + result_bytes + total_bytes, &mut self.words);
        let wait = submitted.elapsed();

        let results = &self.words[(RESULTS_OFFSET / 4) as usize..];
        for (k, &i) in self.tested.iter().enumerate() {
            out[i] = BoxVisibility::Samples(match kind {
                BoxTest::Occlusion => u64::from(results[2 * k]) | (u64::from(results[2 * k + 1]) << 32),
                BoxTest::PixelCount { .. } => u64::from(results[k]),
            });
        }
        if let Some(t) = totals {
            let covered = &results[self.tested.len()..];
            for (k, &i) in self.tested.iter().enumerate() {
                t[i] = u64::from(covered[k]);
            }
        }
        let gpu_time = self.timestamps.as_ref().map(|&(_, period_ns)| {
            let tick = |i: usize| u64::from(self.words[2 * i]) | (u64::from(self.words[2 * i + 1]) << 32);
            GpuSpan::of_ticks(tick(0), tick(1), period_ns)
        });
        BatchCost {
            queries: u64::from(count),
            submitted,
            wait,
            gpu: gpu_time,
            prepare,
        }
    }

    /// Grows every box, marks the ones reaching the near plane visible
    /// without a test, and stages the others eye-relative.
    fn prepare(&mut self, camera: &Camera, margins: BoxMargins, boxes: &[Aabb], out: &mut Vec<BoxVisibility>) {
        out.clear();
        self.staging.clear();
        self.tested.clear();
        let view = camera.view_rotation();
        for (i, b) in boxes.iter().enumerate() {
            match eye_relative_box(camera, &view, margins, b) {
                EyeBox::ReachesNear => out.push(BoxVisibility::Unqueried),
                EyeBox::Testable(q) => {
                    out.push(BoxVisibility::Samples(0));
                    self.tested.push(i);
                    self.staging.push(q);
                }
            }
        }
    }

    fn encode_occlusion_queries(&self, encoder: &mut wgpu::CommandEncoder, depth: &wgpu::TextureView, count: u32) {
        for (set_index, first) in (0..count).step_by(QUERIES_PER_SET as usize).enumerate() {
            let n = (count - first).min(QUERIES_PER_SET);
            let set = &self.sets[set_index];
            {
                let mut pass = depth_only_pass(encoder, "occlusion queries", depth, Some(set));
                pass.set_pipeline(&self.occlusion);
                pass.set_bind_group(0, &self.box_group, &[]);
                set_box_indices(&mut pass, &self.box_indices);
                for q in 0..n {
                    pass.begin_occlusion_query(q);
                    pass.draw_indexed(0..BOX_INDEX_COUNT, 0, first + q..first + q + 1);
                    pass.end_occlusion_query();
                }
            }
            encoder.resolve_query_set(set, 0..n, &self.resolved, RESULTS_OFFSET + u64::from(first) * 8);
        }
    }

    fn encode_pixel_counts(
        &self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        count: u32,
        sampling: u32,
        totals: bool,
    ) {
        let counting = self
            .counting
            .as_ref()
            .expect("pixel counts are only requested on adapters that have them");
        let uniform = Sampling {
            step: sampling.max(1),
            span: SPAN,
            _pad: [0; 2],
        };
        gpu.queue
            .write_buffer(&counting.sampling, 0, bytemuck::bytes_of(&uniform));
        encoder.clear_buffer(&counting.counts, 0, Some(u64::from(count) * 4));
        if totals {
            encoder.clear_buffer(&counting.totals, 0, Some(u64::from(count) * 4));
        }
        let mut pass = depth_only_pass(encoder, "pixel counts", depth, None);
        pass.set_pipeline(&counting.pipeline);
        pass.set_bind_group(0, &self.box_group, &[]);
        pass.set_bind_group(1, &counting.bind_group, &[]);
        set_box_indices(&mut pass, &self.box_indices);
        pass.draw_indexed(0..BOX_INDEX_COUNT, 0, 0..count);
        if totals {
            pass.set_pipeline(&counting.totals_pipeline);
            pass.set_bind_group(1, &counting.totals_group, &[]);
            pass.draw_indexed(0..BOX_INDEX_COUNT, 0, 0..count);
        }
    }

    /// Grows the buffers and query sets to hold `count` boxes.
    fn reserve(&mut self, gpu: &GpuContext, count: u32) {
        if count > self.capacity {
            let capacity = count.next_multiple_of(QUERIES_PER_SET);
            (self.boxes, self.box_group) = box_buffer(gpu, &self.box_layout, &self.camera, capacity);
            if let Some(c) = &mut self.counting {
                (c.counts, c.bind_group) = count_buffer(gpu, &c.layout, &c.sampling, capacity);
                (c.totals, c.totals_group) = count_buffer(gpu, &c.layout, &c.sampling, capacity);
            }
            self.resolved = result_buffer(gpu, capacity);
            self.readback = Readback::new(gpu, "box test readback", result_bytes(capacity));
            self.capacity = capacity;
        }
        while (self.sets.len() as u32) * QUERIES_PER_SET < count {
            self.sets.push(query_set(gpu));
        }
    }
}

pub(crate) fn depth_only_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    depth: &wgpu::TextureView,
    queries: Option<&wgpu::QuerySet>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
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
        occlusion_query_set: queries,
        multiview_mask: None,
    })
}

/// The 12 triangles of a box over its 8 corners (bit 0 picks max x, bit 1
/// max y, bit 2 max z), counter-clockwise seen from outside. Box tests draw
/// indexed, so each corner is shaded once rather than once per triangle.
const BOX_INDICES: [u16; 36] = [
    0, 6, 2, 0, 4, 6, // -x
    1, 7, 5, 1, 3, 7, // +x
    0, 5, 4, 0, 1, 5, // -y
    2, 7, 3, 2, 6, 7, // +y
    0, 3, 1, 0, 2, 3, // -z
    4, 7, 6, 4, 5, 7, // +z
];

/// Indices one box draws.
pub(crate) const BOX_INDEX_COUNT: u32 = BOX_INDICES.len() as u32;

/// A buffer of [`BOX_INDICES`], for [`set_box_indices`].
pub(crate) fn box_index_buffer(gpu: &GpuContext) -> wgpu::Buffer {
    gpu.buffer_with(
        "box indices",
        bytemuck::cast_slice(&BOX_INDICES),
        wgpu::BufferUsages::INDEX,
    )
}

/// Binds `indices` (from [`box_index_buffer`]) for drawing boxes.
pub(crate) fn set_box_indices(pass: &mut wgpu::RenderPass, indices: &wgpu::Buffer) {
    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint16);
}

/// The depth test of box tests. Reverse-Z: nearer is greater. Equal passes,
/// so a box face on a surface is not judged hidden by it.
pub(crate) const BOX_TEST: wgpu::CompareFunction = wgpu::CompareFunction::GreaterEqual;

/// A pipeline that draws boxes against a depth target without changing it:
/// back faces culled (the eye is never inside a tested box), depth compared
/// by `compare` (`BOX_TEST`, or `Always` to reach every pixel a box covers),
/// no depth or colour writes; `fragment`, if any, does the counting.
pub(crate) fn box_test_pipeline(
    gpu: &GpuContext,
    label: &str,
    layouts: &[Option<&wgpu::BindGroupLayout>],
    vertex: wgpu::VertexState,
    fragment: Option<wgpu::FragmentState>,
    compare: wgpu::CompareFunction,
) -> wgpu::RenderPipeline {
    let layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: layouts,
        immediate_size: 0,
    });
    gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex,
        primitive: wgpu::PrimitiveState {
            cull_mode: Some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment,
        multiview_mask: None,
        cache: None,
    })
}

/// A layout of buffer bindings 0, 1, …, each seen by its stages.
pub(crate) fn bind_group_layout(
    gpu: &GpuContext,
    label: &str,
    buffers: &[(wgpu::ShaderStages, wgpu::BufferBindingType)],
) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = buffers
        .iter()
        .enumerate()
        .map(|(binding, &(visibility, ty))| wgpu::BindGroupLayoutEntry {
            binding: binding as u32,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// Group 0 of boxes.wgsl: the camera uniform and the boxes.
pub(crate) fn box_bind_group_layout(gpu: &GpuContext) -> wgpu::BindGroupLayout {
    // Drawn boxes read them in the vertex stage, a depth pyramid's test in
    // a compute pass.
    let vertex = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::COMPUTE;
    bind_group_layout(
        gpu,
        "boxes",
        &[
            (vertex, wgpu::BufferBindingType::Uniform),
            (vertex, wgpu::BufferBindingType::Storage { read_only: true }),
        ],
    )
}

pub(crate) fn bind_buffers(
    gpu: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// An error where `bytes` exceed what the adapter binds as one storage
/// buffer; `what` names the binding (and what would fit) in it.
pub(crate) fn check_storage_binding(gpu: &GpuContext, what: &'static str, bytes: u64) -> Result<(), GpuError> {
    let limit = gpu.device.limits().max_storage_buffer_binding_size;
    if bytes > limit {
        return Err(GpuError::TooLarge {
            what,
            need: bytes,
            limit,
        });
    }
    Ok(())
}

pub(crate) fn storage_buffer(gpu: &GpuContext, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE | usage,
        mapped_at_creation: false,
    })
}

pub(crate) fn box_buffer(
    gpu: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    camera: &wgpu::Buffer,
    capacity: u32,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let size = u64::from(capacity) * std::mem::size_of::<QueryBox>() as u64;
    // Copied from by the tests that hold boxes made on the GPU to the CPU's.
    let usage = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
    let boxes = storage_buffer(gpu, "test boxes", size, usage);
    let group = bind_buffers(gpu, layout, &[camera, &boxes]);
    (boxes, group)
}

fn count_buffer(
    gpu: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    sampling: &wgpu::Buffer,
    capacity: u32,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let usage = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let counts = storage_buffer(gpu, "pixel counts", u64::from(capacity) * 4, usage);
    let group = bind_buffers(gpu, layout, &[&counts, sampling]);
    (counts, group)
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

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::*;
    use crate::gpu::CAMERA_WGSL;
    use crate::gpu::wgsl::{parse, struct_layout};

    #[test]
    fn a_box_and_the_sampling_are_laid_out_as_the_shaders_read_them() {
        let (members, size) = struct_layout(&parse(&[CAMERA_WGSL, BOXES_WGSL].concat()), "QueryBox");
        assert_eq!(members, [("min".to_string(), 0), ("max".to_string(), 16)]);
        assert_eq!(size_of::<QueryBox>(), size as usize);
        assert_eq!(offset_of!(QueryBox, max), 16);
        let counting = parse(include_str!("../../shaders/pixel_count.wgsl"));
        let (members, size) = struct_layout(&counting, "Sampling");
        assert_eq!(members, [("step".to_string(), 0), ("span".to_string(), 4)]);
        assert_eq!(offset_of!(Sampling, span), 4);
        // The uniform is padded to 16 bytes, as uniforms are bound.
        assert_eq!(size_of::<Sampling>(), (size as usize).next_multiple_of(16));
    }
}
