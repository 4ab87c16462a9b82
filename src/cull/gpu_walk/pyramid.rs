//! The depth pyramid two-phase hierarchical-depth culling tests boxes
//! against (issue 20; Unreal's HZB, Bevy's and niagara's depth pyramid):
//! level 0 a power-of-two size at most the depth target's over a divisor
//! (1 is niagara's choice), each further level half the one below, down to
//! one texel. Reverse-Z, so a texel keeps the smallest depth below it: the
//! farthest surface over its footprint.
//!
//! Conservative at every target size, non-power-of-two included (the false
//! culls of bevy#14062): a base texel covers between one and two times the
//! divisor's target texels across (the whole side where the target is
//! narrower than the divisor). Target texel p belongs to base texel
//! ⌊p · base / target⌋ on each side, the map hiz's test reads a box's
//! pixels by (pyramid_test.wgsl), and a base texel takes the least depth
//! over every target texel that belongs to it rather than sampling some of
//! them: each target texel is read once and lies in exactly one base
//! texel. Halving a power of two is exact, so every further texel covers
//! exactly 2×2 texels below it. Hence a texel's depth is at most the depth
//! of every target texel in its footprint (the test below checks it
//! against that definition, computed from the depth target alone).

use crate::gpu::{GpuContext, GpuError, Resolution, check_storage_binding, storage_buffer};

/// One level of the pyramid: its size and where it starts in the buffer
/// (in texels).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PyramidLevel {
    pub width: u32,
    pub height: u32,
    pub offset: u32,
}

/// A level's uniform (`Level` in pyramid.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LevelUniform {
    source_offset: u32,
    source_width: u32,
    source_height: u32,
    offset: u32,
    width: u32,
    height: u32,
    _pad: [u32; 2],
}

/// Most levels a pyramid can have (a base 2^31 texels wide): the length
/// of `Pyramid.levels` in pyramid_test.wgsl.
const MAX_PYRAMID_LEVELS: usize = 32;

/// The pyramid's shape as the box test reads it (`Pyramid` in
/// pyramid_test.wgsl): the target's size, the base's, and per level its
/// width, height and offset (the fourth word pads).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShapeUniform {
    target: [u32; 2],
    base: [u32; 2],
    level_count: u32,
    _pad: [u32; 3],
    levels: [[u32; 4]; MAX_PYRAMID_LEVELS],
}

/// The pyramid over one depth target, and what builds it.
pub struct DepthPyramid {
    levels: Vec<PyramidLevel>,
    texels: wgpu::Buffer,
    /// Its [`ShapeUniform`], for the box test.
    shape: wgpu::Buffer,
    base: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    /// One per level: its uniform, the pyramid and (for the base) the depth.
    groups: Vec<wgpu::BindGroup>,
}

/// The largest power of two at most `n` (n ≥ 1).
fn power_of_two_at_most(n: u32) -> u32 {
    1 << (31 - n.max(1).leading_zeros())
}

/// The levels of the pyramid over a depth target of `resolution` whose
/// base is the largest power of two at most its size over `base_divisor`
/// (and at least one texel) on each side.
pub fn levels(resolution: Resolution, base_divisor: u32) -> Vec<PyramidLevel> {
    let (mut width, mut height) = (
        power_of_two_at_most(resolution.width / base_divisor),
        power_of_two_at_most(resolution.height / base_divisor),
    );
    let mut levels = Vec::new();
    let mut offset = 0;
    loop {
        levels.push(PyramidLevel { width, height, offset });
        if width == 1 && height == 1 {
            return levels;
        }
        offset += width * height;
        (width, height) = ((width / 2).max(1), (height / 2).max(1));
    }
}

impl DepthPyramid {
    /// The pyramid over `depth`, a depth target of `resolution`; an error
    /// when its texels exceed what the adapter binds as one buffer (about
    /// 4/3 of the base, which is up to the target's size).
    pub fn new(
        gpu: &GpuContext,
        resolution: Resolution,
        base_divisor: u32,
        depth: &wgpu::TextureView,
    ) -> Result<DepthPyramid, GpuError> {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pyramid.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("pyramid.wgsl").into()),
        });
        let (base, reduce) = (
            gpu.compute_pipeline(&module, "cs_base", None),
            gpu.compute_pipeline(&module, "cs_reduce", None),
        );
        let levels = levels(resolution, base_divisor);
        let last = levels[levels.len() - 1];
        let bytes = u64::from(last.offset + 1) * 4;
        check_storage_binding(
            gpu,
            "storage binding for hiz's depth pyramid (bytes; a smaller --resolution fits)",
            bytes,
        )?;
        let mut shape = ShapeUniform {
            target: [resolution.width, resolution.height],
            base: [levels[0].width, levels[0].height],
            level_count: levels.len() as u32,
            _pad: [0; 3],
            levels: [[0; 4]; MAX_PYRAMID_LEVELS],
        };
        for (slot, level) in shape.levels.iter_mut().zip(&levels) {
            *slot = [level.width, level.height, level.offset, 0];
        }
        let shape = gpu.buffer_with(
            "depth pyramid shape",
            bytemuck::bytes_of(&shape),
            wgpu::BufferUsages::UNIFORM,
        );
        let texels = storage_buffer(gpu, "depth pyramid", bytes, wgpu::BufferUsages::COPY_SRC);
        let groups = levels
            .iter()
            .enumerate()
            .map(|(k, level)| {
                let source = match k {
                    0 => PyramidLevel {
                        width: resolution.width,
                        height: resolution.height,
                        offset: 0,
                    },
                    _ => levels[k - 1],
                };
                let uniform = LevelUniform {
                    source_offset: source.offset,
                    source_width: source.width,
                    source_height: source.height,
                    offset: level.offset,
                    width: level.width,
                    height: level.height,
                    _pad: [0; 2],
                };
                let uniform = gpu.buffer_with(
                    "pyramid level",
                    bytemuck::bytes_of(&uniform),
                    wgpu::BufferUsages::UNIFORM,
                );
                let mut entries = vec![
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: texels.as_entire_binding(),
                    },
                ];
                if k == 0 {
                    entries.push(wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(depth),
                    });
                }
                let layout = if k == 0 { &base } else { &reduce }.get_bind_group_layout(0);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("pyramid level"),
                    layout: &layout,
                    entries: &entries,
                })
            })
            .collect();
        Ok(DepthPyramid {
            levels,
            texels,
            shape,
            base,
            reduce,
            groups,
        })
    }

    /// What the box test binds: every level's texels, and the shape that
    /// says where each level lies.
    pub fn bindings(&self) -> [&wgpu::Buffer; 2] {
        [&self.texels, &self.shape]
    }

    /// Builds the pyramid from the depth drawn so far: one dispatch a level.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("depth pyramid"),
            timestamp_writes: None,
        });
        for (k, (level, group)) in self.levels.iter().zip(&self.groups).enumerate() {
            pass.set_pipeline(if k == 0 { &self.base } else { &self.reduce });
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(level.width.div_ceil(8), level.height.div_ceil(8), 1);
        }
    }
}

#[cfg(test)]
impl DepthPyramid {
    pub fn levels(&self) -> &[PyramidLevel] {
        &self.levels
    }

    /// Every level's texels, row by row.
    pub fn read(&self, gpu: &GpuContext) -> Vec<Vec<f32>> {
        let bytes = self.texels.size();
        let readback = crate::gpu::Readback::new(gpu, "depth pyramid", bytes);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        readback.copy(&mut encoder, &self.texels, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        let mut all: Vec<f32> = Vec::new();
        readback.read(gpu, bytes, &mut all);
        self.levels
            .iter()
            .map(|l| all[l.offset as usize..(l.offset + l.width * l.height) as usize].to_vec())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::generate::default_path;
    use crate::cull::create;
    use crate::cull::culler::Culler;
    use crate::cull::gpu_walk::layout::shader_constants;
    use crate::gpu::wgsl::{parse, struct_layout};
    use crate::gpu::{BOXES_WGSL, CAMERA_WGSL};
    use crate::hierarchy::{Hierarchy, HierarchyParams};
    use crate::scene::{LoadOptions, SceneSpec, load};
    use crate::session::{RunOptions, Session};
    use crate::world::World;

    /// Texel (`x`, `y`) of `level` by the definition: the least depth of
    /// every target texel (of a `width` × `height` target) in its
    /// footprint. A level-k texel spans 2^k base texels across; target
    /// texel p lies in base texel ⌊p · base / side⌋.
    fn by_definition(depth: &[f32], width: u32, height: u32, base: PyramidLevel, k: u32, x: u32, y: u32) -> f32 {
        let span = |i: u32, base_side: u32, side: u32| {
            let (first, end) = ((i << k).min(base_side), ((i + 1) << k).min(base_side));
            // [first, end) base texels hold the target texels p with
            // first ≤ p·base/side < end.
            let lo = (u64::from(first) * u64::from(side)).div_ceil(u64::from(base_side));
            let hi = (u64::from(end) * u64::from(side)).div_ceil(u64::from(base_side));
            lo as u32..hi as u32
        };
        let mut least = 1.0f32;
        for ty in span(y, base.height, height) {
            for tx in span(x, base.width, width) {
                least = least.min(depth[(ty * width + tx) as usize]);
            }
        }
        least
    }

    #[test]
    fn the_uniforms_are_laid_out_as_the_shaders_read_them() {
        let module = parse(include_str!("pyramid.wgsl"));
        let (members, size) = struct_layout(&module, "Level");
        let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "source_offset",
                "source_width",
                "source_height",
                "offset",
                "width",
                "height"
            ]
        );
        assert!(
            members
                .iter()
                .enumerate()
                .all(|(k, (_, offset))| *offset == 4 * k as u32)
        );
        // The Rust side pads to a uniform's 16-byte multiple.
        assert_eq!(
            std::mem::size_of::<LevelUniform>(),
            (size as usize).next_multiple_of(16)
        );
        // The box test's view of the pyramid (pyramid_test.wgsl, after what
        // it is appended to and the constants it takes).
        let test = [
            CAMERA_WGSL,
            BOXES_WGSL,
            &shader_constants(),
            &super::super::level_test::pyramid_test_source(4, 1024),
        ]
        .concat();
        let (members, size) = struct_layout(&parse(&test), "Pyramid");
        assert_eq!(
            members,
            [
                ("target_size", 0),
                ("base_size", 8),
                ("level_count", 16),
                ("levels", 32)
            ]
            .map(|(n, o)| (n.to_string(), o))
        );
        assert_eq!(std::mem::size_of::<ShapeUniform>(), size as usize);
        assert_eq!(std::mem::offset_of!(ShapeUniform, levels), 32);
        assert_eq!(std::mem::offset_of!(ShapeUniform, level_count), 16);
        // The queue's header (level_test.rs's PIXEL_WORK_HEADER), and the
        // planes the probe test in twin.rs reads back as ShaderBoxPlanes.
        let module = parse(&test);
        let (members, size) = struct_layout(&module, "BoxPlanes");
        assert_eq!(
            (members, size),
            (
                [("entries", 0), ("exits", 48)]
                    .map(|(n, o)| (n.to_string(), o))
                    .to_vec(),
                std::mem::size_of::<crate::gpu::ShaderBoxPlanes>() as u32
            )
        );
        for queue in ["PixelWork", "PixelQueue"] {
            let (members, _) = struct_layout(&module, queue);
            let offsets: Vec<u32> = members.iter().map(|(_, o)| *o).collect();
            assert_eq!(offsets, [0, 12, 16], "{queue}");
        }
    }

    #[test]
    fn every_texel_is_the_farthest_depth_in_its_footprint_at_any_size() {
        let gpus = GpuContext::every_adapter();
        let scene = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        let (path, _) = default_path(&scene).unwrap();
        // Odd, prime, one-texel and very flat sizes: bevy#14062's false culls
        // came from sizes that are not powers of two.
        let sizes = [(801, 599), (160, 120), (1, 1), (1023, 1), (37, 5), (2, 3)];
        for gpu in &gpus {
            for ((width, height), base_divisor) in sizes.into_iter().flat_map(|s| [(s, 1), (s, 4)]) {
                let resolution = Resolution { width, height };
                let options = RunOptions {
                    warmup: 0,
                    resolution,
                    measure_error: true,
                };
                let mut world = World::new(scene.clone(), hierarchy.clone());
                let mut dr: [Box<dyn Culler>; 1] = [create("dr", &scene, &Default::default()).unwrap()];
                let mut session = Session::new(gpu, &world, &mut dr, true, &options).unwrap();
                let camera = path.camera(3, resolution.aspect());
                session.frame(3, &camera, &mut world, &mut dr, 0).unwrap();
                let depth = session.mode_depth(0).unwrap();
                let pyramid =
                    DepthPyramid::new(gpu, resolution, base_divisor, &session.targets.mode_depths[0]).unwrap();
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                pyramid.encode(&mut encoder);
                gpu.queue.submit([encoder.finish()]);
                let built = pyramid.read(gpu);
                let base = pyramid.levels()[0];
                let most = (width / base_divisor).max(1);
                assert!(
                    base.width <= most && base.width * 2 > most,
                    "{width} over {base_divisor}: base {}",
                    base.width
                );
                let last = pyramid.levels()[pyramid.levels().len() - 1];
                assert_eq!((last.width, last.height), (1, 1));
                let farthest = depth.iter().copied().fold(1.0f32, f32::min);
                assert_eq!(
                    built[built.len() - 1],
                    [farthest],
                    "{width}x{height}: the top is the farthest depth"
                );
                for (k, (level, texels)) in pyramid.levels().iter().zip(&built).enumerate() {
                    for y in 0..level.height {
                        for x in 0..level.width {
                            let expected = by_definition(&depth, width, height, base, k as u32, x, y);
                            let got = texels[(y * level.width + x) as usize];
                            assert_eq!(
                                got.to_bits(),
                                expected.to_bits(),
                                "{width}x{height} over {base_divisor}: level {k} texel ({x}, {y}) on {}",
                                gpu.adapter
                            );
                        }
                    }
                }
                // The comparison means something: geometry is in view.
                assert!(
                    resolution.pixels() < 100 || depth.iter().any(|&d| d > 0.0),
                    "{width}x{height}: the city is in view"
                );
            }
        }
    }
}
