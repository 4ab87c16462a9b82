//! The numerical rules that make box tests conservative: a box test never
//! judges hidden an object that direct rendering shows in any pixel.
//!
//! A box test calls an object hidden when no fragment of its bounding box
//! passes the depth test. In exact arithmetic that is safe; a rasteriser in
//! f32 breaks it in two ways, and each has a rule here:
//!
//! 1. **Rounding** of surfaces that coincide with a box face: boxes are
//!    grown ([`BOX_GROWTH`], and enough to cover sub-pixel snapping,
//!    [`SubpixelPrecision`]) and raised in depth by the backend's rounding error,
//!    relative and, on GL's clip range, absolute ([`BoxMargins`]).
//! 2. **Depth extrapolated on triangles seen edge-on**, which may land
//!    outside the object's box: the scene's fragment stage discards every
//!    fragment nearer than where its pixel's ray enters the object's box
//!    ([`FragmentLimit`]), for every mode and the reference alike.
//!
//! docs/box-tests.md gives the argument that the two together suffice, with
//! the measurements on real models that found each rule.

use glam::{DMat3, DVec3, Vec4};

use super::resolution::Resolution;
use crate::bounds::Aabb;
use crate::camera::{Camera, nearest_view_depth};

/// Boxes are grown by at least this fraction of their reach from the eye
/// before they are tested (rule 1, relative to the depth at the pixel).
pub(crate) const BOX_GROWTH: f64 = 1e-4;

/// Raise of a tested box per unit of its nearest corner's depth (rule 1,
/// relative to the largest depth of a triangle): 4 steps of 2^-24.
const RAISE_PER_DEPTH: f64 = 1.0 / (1u32 << 22) as f64;

/// The raise GL adds to every tested box (rule 1, absolute): 4 steps of
/// 2^-24.
const GL_RAISE: f64 = 1.0 / (1u32 << 22) as f64;

/// The largest raise a box reaching depth 1 can get on any backend.
const MAX_RAISE: f64 = GL_RAISE + RAISE_PER_DEPTH;

/// How far one frame's box tests stay clear of rounding: the backend's
/// depth margins, and a growth that covers both the depth rounding and
/// sub-pixel snapping at the frame's field of view and resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxMargins {
    /// Fraction of a box's reach (its largest eye-relative coordinate) that
    /// it is grown by.
    growth: f64,
    depth: DepthMargins,
}

impl BoxMargins {
    pub fn new(
        depth: DepthMargins,
        subpixel: SubpixelPrecision,
        camera: &Camera,
        resolution: Resolution,
    ) -> BoxMargins {
        // A box grown by g holds the ball of radius g round each of its
        // points, whose outline is at least g · f / d pixels wide at
        // distance d ≤ √3 · reach, with f = height / (2 tan(fov / 2)). It
        // must reach beyond the object's outline by the snap of the
        // object's vertices and of its own: twice a vertex's error.
        let pixel = 2.0 * (camera.fov_y / 2.0).tan() / f64::from(resolution.height);
        let snap_margin = 2.0 * subpixel.vertex_error(resolution);
        BoxMargins {
            growth: BOX_GROWTH.max(3f64.sqrt() * snap_margin * pixel),
            depth,
        }
    }

    /// The backend's depth margins they hold.
    pub(crate) fn depth(self) -> DepthMargins {
        self.depth
    }

    /// The margins of a box test made exactly, on the CPU in f64: the whole
    /// growth, so its outline holds every pixel a fragment of the object
    /// may land on (within a vertex's error on each axis, √2 of it across,
    /// where the growth moves the outline twice that error out), but only
    /// the raise the [`FragmentLimit`] keeps, a fragment's own error: the
    /// other half of the raise allows for the rounding of a box the GPU
    /// draws.
    pub(crate) fn for_exact_tests(self) -> BoxMargins {
        BoxMargins {
            growth: self.growth,
            depth: DepthMargins {
                absolute: self.depth.absolute / 2.0,
                per_depth: self.depth.per_depth / 2.0,
            },
        }
    }

    /// These margins as a shader that makes boxes from f32 parts reads
    /// them (gpu_walk's prepare_nodes.wgsl): the growth per unit of reach,
    /// the raise's absolute part and its part per unit of depth, and the
    /// nearest view depth at which a box reaches the near plane for
    /// `camera`. The raise and that depth are taken [`SHADER_SAFETY`] larger,
    /// so their f32 rounding, and the shader's of the quotient it makes of
    /// them, never leaves them below what [`eye_relative_box`] uses.
    pub(crate) fn for_shader(&self, camera: &Camera) -> [f32; 4] {
        let safe = 1.0 + SHADER_SAFETY;
        [
            self.growth as f32,
            (self.depth.absolute * safe) as f32,
            (self.depth.per_depth * safe) as f32,
            (camera.near / (1.0 - MAX_RAISE) * safe) as f32,
        ]
    }
}

/// How much larger [`BoxMargins::for_shader`] takes what must not come out
/// smaller: a hundred times f32's rounding.
const SHADER_SAFETY: f64 = 1e-5;

/// How finely the adapter snaps a vertex on screen before it rasterises:
/// the bits of sub-pixel precision its API reports (Vulkan's
/// `subPixelPrecisionBits`, GL's `GL_SUBPIXEL_BITS`; gpu/context.rs asks).
/// A snap moves a vertex by less than one step of that grid whichever way
/// it rounds. Box tests grow by twice this error ([`BoxMargins`]), and swr
/// places its occluders' outlines within it of the GPU's
/// (cull/swr/mesh.rs): at 8 bits, the figure llvmpipe, lavapipe and
/// desktop GPUs report, a step is 1/256 pixel, sixteen times finer than the
/// 4 bits Vulkan allows at least, so far fewer pixel centres along an
/// occluder's outline are left in doubt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SubpixelPrecision {
    bits: u32,
}

impl SubpixelPrecision {
    /// The least Vulkan allows (4 bits, a step of 1/16 pixel): taken where
    /// the API reports nothing (Metal, Direct3D 12), or the report cannot
    /// be read.
    pub const COARSEST: SubpixelPrecision = SubpixelPrecision { bits: 4 };

    /// A report of finer precision is taken as this: no rasteriser known
    /// snaps finer (Direct3D's 16.8 fixed point, and Vulkan's and GL's
    /// drivers here), and a report that overstates can then claim no more.
    const FINEST_TAKEN: u32 = 8;

    /// What an adapter reports, taken at [`Self::COARSEST`] below Vulkan's
    /// and GL's least (no conformant adapter reports less; a failed GL
    /// query reads 0) and at most [`Self::FINEST_TAKEN`].
    pub fn reported(bits: u32) -> SubpixelPrecision {
        SubpixelPrecision {
            bits: bits.clamp(Self::COARSEST.bits, Self::FINEST_TAKEN),
        }
    }

    pub fn bits(self) -> u32 {
        self.bits
    }

    /// Pixels the GPU may place a vertex from where its f32 clip position
    /// projects, on each axis, on a target of `resolution`: one step of the
    /// sub-pixel grid, and the f32 rounding of the perspective division and
    /// the viewport transform (a few steps of 2^-24 of the target's size).
    pub fn vertex_error(self, resolution: Resolution) -> f64 {
        let step = 1.0 / f64::from(1u32 << self.bits);
        step + f64::from(resolution.width.max(resolution.height)) / f64::from(1u32 << 21)
    }
}

/// The depth margins of one backend (rule 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthMargins {
    /// Added to every raise: the backend's absolute depth error.
    absolute: f64,
    /// The raise per unit of the box's nearest depth.
    per_depth: f64,
}

impl DepthMargins {
    pub fn for_backend(backend: wgpu::Backend) -> DepthMargins {
        DepthMargins {
            absolute: if backend == wgpu::Backend::Gl { GL_RAISE } else { 0.0 },
            per_depth: RAISE_PER_DEPTH,
        }
    }

    /// How much a box whose nearest corner lies at `nearest_depth` is raised
    /// when it is tested.
    fn raise(self, nearest_depth: f64) -> f64 {
        self.absolute + self.per_depth * nearest_depth
    }

    /// How far from a surface's depth the GPU may draw it, where none of it
    /// lies nearer than `nearest_depth`: half the raise of a box there (the
    /// other half separates the box from the surface's own rounding, and
    /// the [`FragmentLimit`] keeps this half,
    /// [`BoxMargins::for_exact_tests`]).
    pub(crate) fn fragment_error(self, nearest_depth: f64) -> f64 {
        self.raise(nearest_depth) / 2.0
    }
}

/// Eye-relative corners of a box grown for testing, as boxes.wgsl reads
/// them; `min.w` holds the box's raise in depth.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct QueryBox {
    pub(crate) min: Vec4,
    pub(crate) max: Vec4,
}

/// A box made ready for a depth test.
pub(crate) enum EyeBox {
    /// It reaches the near plane or holds the eye: visible, untestable (its
    /// projection is unbounded).
    ReachesNear,
    /// Grown by its [`BoxMargins`], eye-relative, with its raise.
    Testable(QueryBox),
}

/// `b` relative to the eye, grown by `fraction` of its reach from the eye.
fn grown_eye_relative(camera: &Camera, b: &Aabb, fraction: f64) -> (DVec3, DVec3) {
    let (min, max) = (b.min - camera.eye, b.max - camera.eye);
    let reach = min.abs().max(max.abs()).max_element();
    let grow = DVec3::splat(fraction * reach + f64::MIN_POSITIVE);
    (min - grow, max + grow)
}

/// Prepares `b`, which must not lie outside `camera`'s frustum, for a depth
/// test by `camera`, whose `view_rotation()` is `view` (computed once per
/// batch by the caller).
pub(crate) fn eye_relative_box(camera: &Camera, view: &DMat3, margins: BoxMargins, b: &Aabb) -> EyeBox {
    let (min, max) = grown_eye_relative(camera, b, margins.growth);
    // The box reaches the near plane when a corner is nearer than it along
    // the view direction (this also covers holding the eye). The raise
    // lifts a corner at distance t to near / t + raise, which must stay
    // below 1 (the near plane) or the corner would be clipped away: checked
    // for the largest raise, which costs a test of a box within a millionth
    // of the near distance beyond it.
    let nearest = nearest_view_depth(view, min, max);
    if nearest <= camera.near / (1.0 - MAX_RAISE) {
        EyeBox::ReachesNear
    } else {
        EyeBox::Testable(QueryBox {
            min: min.as_vec3().extend(margins.depth.raise(camera.near / nearest) as f32),
            max: max.as_vec3().extend(0.0),
        })
    }
}

/// The world direction of the ray through pixel centre (x, y) (framebuffer
/// coordinates, centres at .5), scaled to view depth 1, is
/// `x · per_x + y · per_y + constant`: the camera's part of every
/// [`FragmentLimit`] and [`BoxPlanes`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PixelRays {
    per_x: DVec3,
    per_y: DVec3,
    constant: DVec3,
}

impl PixelRays {
    pub(crate) fn new(camera: &Camera, resolution: Resolution) -> PixelRays {
        let f = 1.0 / (camera.fov_y / 2.0).tan();
        let (w, h) = (f64::from(resolution.width), f64::from(resolution.height));
        let (sx, sy) = (camera.aspect / f, 1.0 / f);
        // In camera space the ray is ((2x / w − 1) · sx, (1 − 2y / h) · sy, −1).
        let to_world = DMat3::from_quat(camera.rotation);
        let (right, up, back) = (to_world.x_axis, to_world.y_axis, to_world.z_axis);
        PixelRays {
            per_x: right * (2.0 * sx / w),
            per_y: up * (-2.0 * sy / h),
            constant: -right * sx + up * sy - back,
        }
    }

    /// The three vectors as the camera uniform holds them.
    pub(super) fn uniform(&self) -> [Vec4; 3] {
        [self.per_x, self.per_y, self.constant].map(|v| v.as_vec3().extend(0.0))
    }
}

/// Per world axis along which the eye lies outside the eye-relative box
/// `min`..`max`: the coordinate of the box's face that faces the eye, and
/// of the face opposite; `None` where the eye lies within the box's extent
/// along the axis (no face across it faces the eye).
fn faces_across(min: DVec3, max: DVec3) -> [Option<(f64, f64)>; 3] {
    [0, 1, 2].map(|axis| {
        if min[axis] > 0.0 {
            Some((min[axis], max[axis]))
        } else if max[axis] < 0.0 {
            Some((max[axis], min[axis]))
        } else {
            None
        }
    })
}

/// Per world axis, `near / face` for the face of the eye-relative box
/// `min`..`max` across that axis that faces the eye, and 0 where none does.
/// The pixel ray d meets that face's plane at view depth t = face / d_axis,
/// so at depth `near / t = d_axis · near / face`.
fn facing_scales(near: f64, min: DVec3, max: DVec3) -> [f64; 3] {
    faces_across(min, max).map(|faces| faces.map_or(0.0, |(facing, _)| near / facing))
}

/// A depth affine in the pixel position (x, y) (framebuffer coordinates):
/// `per_x · x + per_y · y + constant`, as the depth over one plane is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ScreenPlane {
    pub(crate) per_x: f64,
    pub(crate) per_y: f64,
    pub(crate) constant: f64,
}

impl ScreenPlane {
    pub(crate) fn at(&self, x: f64, y: f64) -> f64 {
        self.per_x * x + self.per_y * y + self.constant
    }

    /// Its greatest value over the rectangle `x` × `y` (each `[low,
    /// high]`): at the corner it rises towards.
    pub(crate) fn max_over(&self, x: [f64; 2], y: [f64; 2]) -> f64 {
        self.at(
            if self.per_x > 0.0 { x[1] } else { x[0] },
            if self.per_y > 0.0 { y[1] } else { y[0] },
        )
    }

    pub(crate) fn minus(&self, other: &ScreenPlane) -> ScreenPlane {
        ScreenPlane {
            per_x: self.per_x - other.per_x,
            per_y: self.per_y - other.per_y,
            constant: self.constant - other.constant,
        }
    }
}

/// Where pixel rays meet an eye-relative box, for tests finer than its
/// nearest corner and its screen rectangle. A ray entering the box does so
/// on a face that faces the eye, at the least of those faces' plane depths,
/// and leaves it through a far face (the slab test); each plane's depth is
/// affine in the pixel's position (d_axis · near / face). So where a ray
/// enters the box it does so at most at each entry plane, and it enters no
/// farther than it leaves: where an entry plane lies behind an exit plane,
/// the ray misses the box.
///
/// Why that bounds the GPU's fragments, which need not lie inside the box:
/// for a box test of an object's box (or of a box holding it), grown and
/// raised by its [`BoxMargins`], a fragment of the object survives only
/// where its pixel's ray meets the object's box grown by half the growth,
/// at most at that box's entry depth plus half the raise
/// ([`FragmentLimit`]), and the ray meets it where it meets the tested box
/// (whose outline reaches at least 1/16 pixel beyond the object's, more
/// than a sub-pixel snap). The entry planes of the tested box, raised by
/// its full raise and their rounding, lie above that limit; its exit
/// planes, lowered by their rounding, below the half-grown box's.
/// By default, none: nothing bounded, no miss.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BoxPlanes {
    /// Per axis across which the eye lies outside the box: the plane of
    /// the face facing it, raised by the box's raise and by its rounding
    /// anywhere on the target (at most three)...
    entries: [ScreenPlane; 3],
    /// ...and the plane of the face opposite, lowered by its rounding.
    exits: [ScreenPlane; 3],
    count: usize,
}

impl BoxPlanes {
    /// The planes of a box tested as `q` (eye-relative, grown, with its
    /// raise) by `camera` on a target of `target` pixels.
    pub(crate) fn new(camera: &Camera, q: &QueryBox, rays: &PixelRays, target: Resolution) -> BoxPlanes {
        let (min, max) = (q.min.truncate().as_dvec3(), q.max.truncate().as_dvec3());
        let (width, height) = (f64::from(target.width), f64::from(target.height));
        let mut planes = BoxPlanes {
            entries: [ScreenPlane::default(); 3],
            exits: [ScreenPlane::default(); 3],
            count: 0,
        };
        // The plane of the face at eye-relative coordinate `face` across
        // `axis`, moved by `sign` times its rounding.
        let plane = |axis: usize, face: f64, sign: f64| {
            let scale = camera.near / face;
            let (per_x, per_y, constant) = (
                scale * rays.per_x[axis],
                scale * rays.per_y[axis],
                scale * rays.constant[axis],
            );
            // A few roundings of each term in f64.
            let rounding = (constant.abs() + per_x.abs() * width + per_y.abs() * height) * f64::EPSILON * 8.0;
            ScreenPlane {
                per_x,
                per_y,
                constant: constant + sign * rounding,
            }
        };
        for (axis, faces) in faces_across(min, max).into_iter().enumerate() {
            let Some((near_face, far_face)) = faces else {
                continue;
            };
            let mut entry = plane(axis, near_face, 1.0);
            entry.constant += f64::from(q.min.w);
            planes.entries[planes.count] = entry;
            planes.exits[planes.count] = plane(axis, far_face, -1.0);
            planes.count += 1;
        }
        planes
    }

    /// Planes the depth of any fragment of an object inside the box lies at
    /// or below (see above).
    pub(crate) fn entries(&self) -> &[ScreenPlane] {
        &self.entries[..self.count]
    }

    /// A box's planes with one entry plane and no exit: its depth is at
    /// most `entry` at every pixel centre, and no ray is known to miss it.
    #[cfg(test)]
    pub(crate) fn entering_at(entry: ScreenPlane) -> BoxPlanes {
        let mut planes = BoxPlanes::default();
        planes.entries[0] = entry;
        planes.count = 1;
        planes
    }

    /// The planes of the faces opposite the entries, in their order.
    pub(crate) fn exits(&self) -> &[ScreenPlane] {
        &self.exits[..self.count]
    }

    /// Whether every ray through a pixel centre in the rectangle `x` × `y`
    /// misses the box: enters it (by one axis) beyond where it leaves it
    /// (by another).
    pub(crate) fn missed_over(&self, x: [f64; 2], y: [f64; 2]) -> bool {
        self.entries().iter().enumerate().any(|(i, entry)| {
            self.exits()
                .iter()
                .enumerate()
                .any(|(j, exit)| i != j && entry.minus(exit).max_over(x, y) < 0.0)
        })
    }
}

/// What pyramid_test.wgsl's `box_planes`, which makes a box's [`BoxPlanes`]
/// in f32 from the tested box and the camera uniform, moves each plane by:
/// an entry up and an exit down, by this fraction of its terms' size over
/// the target (|constant| + raise + |per_x| · width + |per_y| · height), so
/// that its value at any pixel centre still lies at or above the entry
/// plane (at or below the exit plane) in exact arithmetic. Making a
/// coefficient rounds the ray and the near distance to f32 (one step of
/// 2^-24 each), divides (5 steps: 2.5 of 2^-23, as Vulkan and GLSL ES allow
/// for a normal divisor; a subnormal face bounds nothing) and multiplies
/// (one): 8 steps of each coefficient, so of the terms' size. The raise,
/// the margin and the evaluation at a pixel (two products, two sums) add a
/// step of the terms' size each: about 14 in all, and this is 64 of them.
pub(crate) const PLANE_ROUNDING: f64 = 1.0 / (1u32 << 18) as f64;

/// How far scene.wgsl's fragment limit may lie below its exact value, as
/// a fraction of its terms' size over the target (|scale| · (|ray_c| +
/// |ray_x| · width + |ray_y| · height) + raise), its inputs being the f32
/// values the uniforms hold: two products and two sums make the ray, a
/// product and a sum the limit, each within a step of 2^-24 of the terms'
/// size (a GPU's add and multiply may round either way, or fuse): six
/// steps, and this is eight.
const LIMIT_ROUNDING: f64 = 1.0 / (1u32 << 21) as f64;

/// Where a shader's plane stands for no bound (an entry) or no miss (an
/// exit): far beyond any depth, yet finite after any sum the shader makes.
/// A plane whose coefficients reach a tenth of it (a face within f32's
/// smallest distances of the eye) bounds nothing.
pub(crate) const UNBOUNDED: f32 = 1e30;

/// A box's [`BoxPlanes`] as pyramid_test.wgsl's `box_planes` makes them: per
/// world axis, the entry and exit plane's `per_x`, `per_y` and `constant`
/// (w pads) in f32; an axis with no face across it holds [`UNBOUNDED`]
/// (`-UNBOUNDED` for the exit).
#[cfg(test)]
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ShaderBoxPlanes {
    pub(crate) entries: [[f32; 4]; 3],
    pub(crate) exits: [[f32; 4]; 3],
}

#[cfg(test)]
impl ShaderBoxPlanes {
    /// The CPU twin of `box_planes`, step by step in f32: the planes of the
    /// tested box `q` for `camera` on a `target` of pixels, from the rays
    /// and near distance as the camera uniform holds them, each quotient
    /// moved by `quotient_steps` steps of f32 (a GPU's division may be 2.5
    /// steps off).
    pub(crate) fn as_the_shader_makes(
        camera: &Camera,
        q: &QueryBox,
        target: Resolution,
        quotient_steps: i32,
    ) -> ShaderBoxPlanes {
        let [ray_x, ray_y, ray_c] = PixelRays::new(camera, target).uniform();
        let near = camera.projection().w_axis.z as f32;
        let size = [target.width as f32, target.height as f32];
        let moved = |plane: [f32; 3], raise: f32, sign: f32| {
            let terms = plane[2].abs() + raise + plane[0].abs() * size[0] + plane[1].abs() * size[1];
            let margin = PLANE_ROUNDING as f32 * terms;
            let plane = [plane[0], plane[1], plane[2] + raise + sign * margin, 0.0];
            plane.iter().all(|v| v.abs() < UNBOUNDED / 10.0).then_some(plane)
        };
        let mut planes = ShaderBoxPlanes {
            entries: [[0.0, 0.0, UNBOUNDED, 0.0]; 3],
            exits: [[0.0, 0.0, -UNBOUNDED, 0.0]; 3],
        };
        for (axis, faces) in faces_across(q.min.truncate().as_dvec3(), q.max.truncate().as_dvec3())
            .into_iter()
            .enumerate()
        {
            let Some((facing, opposite)) = faces.filter(|&(facing, _)| (facing as f32).abs() >= f32::MIN_POSITIVE)
            else {
                continue;
            };
            let plane = |face: f64| {
                let scale = f32_steps(near / face as f32, quotient_steps);
                [scale * ray_x[axis], scale * ray_y[axis], scale * ray_c[axis]]
            };
            if let (Some(entry), Some(exit)) = (moved(plane(facing), q.min.w, 1.0), moved(plane(opposite), 0.0, -1.0)) {
                (planes.entries[axis], planes.exits[axis]) = (entry, exit);
            }
        }
        planes
    }
}

/// `v` moved `steps` representable f32 values up (down where negative).
#[cfg(test)]
fn f32_steps(v: f32, steps: i32) -> f32 {
    (0..steps.unsigned_abs()).fold(v, |v, _| if steps > 0 { v.next_up() } else { v.next_down() })
}

/// Where an object's fragments may lie (rule 2). For each world axis along
/// which the eye lies outside the object's box, the face across that axis
/// that faces the eye: the pixel ray d meets its plane (eye-relative
/// coordinate `face`) at view depth t = face / d_axis, so at depth
/// `near / t = d_axis · near / face`. `scale` holds `near / face` per axis
/// (0 where the eye lies within the box's extent along that axis, which
/// sets no bound). The least of the three depths is where the ray enters
/// the box, the greatest depth (nearest the eye) it reaches inside it;
/// scene.wgsl discards fragments of greater depth (reverse-Z: nearer) than
/// that plus `raise`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FragmentLimit {
    scale: [f32; 3],
    raise: f32,
}

impl FragmentLimit {
    /// The limit for an object with world bounds `bounds`, seen by `camera`
    /// (whose `view_rotation()` is `view`), whose box tests keep `margins`:
    /// the box is grown and raised by half of them, so a box test always
    /// lies in front of the bound.
    pub fn new(camera: &Camera, view: &DMat3, margins: BoxMargins, bounds: &Aabb) -> FragmentLimit {
        let (min, max) = grown_eye_relative(camera, bounds, margins.growth / 2.0);
        let scale = facing_scales(camera.near, min, max);
        // Half the raise the object's own box test gets (a box reaching the
        // near plane is never tested: any finite raise will do).
        let nearest = nearest_view_depth(view, min, max).max(camera.near);
        FragmentLimit {
            scale: scale.map(|s| s as f32),
            raise: margins.depth.fragment_error(camera.near / nearest) as f32,
        }
    }
}

/// A face of an object's box that faces the eye, on screen, as the scene's
/// fragment stage bounds the object's fragments by it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FacingFace {
    /// The depth where each pixel's ray meets the face's plane: no point of
    /// the box lies nearer.
    pub(crate) face: ScreenPlane,
    /// scene.wgsl keeps every fragment of the object whose depth lies at or
    /// below this plane at its pixel centre, and below each such plane of
    /// its box: the face grown by half its box test's growth, raised by
    /// the fragment's own error ([`DepthMargins::fragment_error`]). The
    /// shader computes it from the f32 values the uniforms hold, which this
    /// takes, and rounds in evaluating it: it is lowered by
    /// [`LIMIT_ROUNDING`] of its terms' size over the target.
    pub(crate) kept_below: ScreenPlane,
}

impl FacingFace {
    /// The faces of the object's box `bounds` that face the eye, for
    /// `camera` (whose `view_rotation()` is `view`) on a target of `target`
    /// pixels whose rays are `rays`, with the [`FragmentLimit`] the
    /// renderer gives the object for box tests that keep `margins`.
    pub(crate) fn of_object(
        camera: &Camera,
        view: &DMat3,
        margins: BoxMargins,
        bounds: &Aabb,
        rays: &PixelRays,
        target: Resolution,
    ) -> [Option<FacingFace>; 3] {
        let limit = FragmentLimit::new(camera, view, margins, bounds);
        let faces = faces_across(bounds.min - camera.eye, bounds.max - camera.eye);
        let [per_x, per_y, constant] = rays.uniform().map(|v| v.as_dvec4());
        let (width, height) = (f64::from(target.width), f64::from(target.height));
        let raise = f64::from(limit.raise);
        [0, 1, 2].map(|axis| {
            // The limit's face lies beyond the box's own: the eye lies
            // outside the box along any axis it lies outside the grown one.
            let (scale, (facing, _)) = (f64::from(limit.scale[axis]), faces[axis]?);
            (scale != 0.0).then(|| {
                let shader = ScreenPlane {
                    per_x: scale * per_x[axis],
                    per_y: scale * per_y[axis],
                    constant: scale * constant[axis] + raise,
                };
                let terms = (scale * constant[axis]).abs()
                    + raise.abs()
                    + shader.per_x.abs() * width
                    + shader.per_y.abs() * height;
                let face = camera.near / facing;
                FacingFace {
                    face: ScreenPlane {
                        per_x: face * rays.per_x[axis],
                        per_y: face * rays.per_y[axis],
                        constant: face * rays.constant[axis],
                    },
                    kept_below: ScreenPlane {
                        constant: shader.constant - LIMIT_ROUNDING * terms,
                        ..shader
                    },
                }
            })
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::camera::look_rotation;

    /// scene.wgsl's depth for "no face across this axis": depth is at most 1.
    const NO_LIMIT: f64 = 2.0;

    /// A camera looking down and to the side of the origin.
    pub(crate) fn camera() -> Camera {
        Camera {
            eye: DVec3::new(3.0, 2.0, 10.0),
            rotation: look_rotation(DVec3::new(-0.3, -0.2, -1.0), DVec3::Y),
            fov_y: 60f64.to_radians(),
            near: 0.1,
            aspect: 4.0 / 3.0,
        }
    }

    impl FragmentLimit {
        /// The depth limit for the pixel ray `ray` (world axes, view depth
        /// 1), as scene.wgsl computes it.
        fn at(&self, ray: glam::Vec3) -> f64 {
            let depths = [0, 1, 2].map(|i| {
                if self.scale[i] == 0.0 {
                    NO_LIMIT
                } else {
                    f64::from(self.scale[i] * ray[i])
                }
            });
            depths.into_iter().fold(NO_LIMIT, f64::min) + f64::from(self.raise)
        }
    }

    /// The ray through pixel centre (x, y) in world axes, view depth 1, from
    /// the camera's field of view alone.
    pub(crate) fn pixel_ray(cam: &Camera, r: Resolution, x: f64, y: f64) -> DVec3 {
        let t = (cam.fov_y / 2.0).tan();
        let ndc = (2.0 * x / f64::from(r.width) - 1.0, 1.0 - 2.0 * y / f64::from(r.height));
        cam.rotation * DVec3::new(ndc.0 * cam.aspect * t, ndc.1 * t, -1.0)
    }

    /// Depth (near / view distance) where `ray` enters `b`, by a slab test in
    /// f64; `None` when it misses.
    pub(crate) fn entry_depth(cam: &Camera, b: &Aabb, d: DVec3) -> Option<f64> {
        let (lo, hi) = (b.min - cam.eye, b.max - cam.eye);
        let (mut enter, mut exit) = (0.0f64, f64::INFINITY);
        for i in 0..3 {
            let (a, c) = (lo[i] / d[i], hi[i] / d[i]);
            enter = enter.max(a.min(c));
            exit = exit.min(a.max(c));
        }
        (enter <= exit).then(|| cam.near / enter)
    }

    #[test]
    fn pixel_rays_match_the_projection() {
        let cam = camera();
        let r = Resolution::DEFAULT;
        let [per_x, per_y, constant] = PixelRays::new(&cam, r).uniform();
        for (x, y) in [(0.5, 0.5), (400.5, 300.5), (799.5, 12.5)] {
            let got = (per_x * x as f32 + per_y * y as f32 + constant).truncate().as_dvec3();
            assert!((got - pixel_ray(&cam, r, x, y)).length() < 1e-6, "({x}, {y})");
        }
    }

    #[test]
    fn fragment_limit_is_the_depth_where_each_pixel_ray_enters_the_box() {
        let cam = camera();
        let r = Resolution::DEFAULT;
        let view = cam.view_rotation();
        let b = Aabb::new(DVec3::new(-2.0, -1.0, -6.0), DVec3::new(1.0, 3.0, -2.0));
        let margins = largest_margins(&cam);
        let limit = FragmentLimit::new(&cam, &view, margins, &b);
        let (min, max) = grown_eye_relative(&cam, &b, margins.growth / 2.0);
        let grown = Aabb::new(min + cam.eye, max + cam.eye);
        let mut hits = 0;
        for y in (0..r.height).step_by(7) {
            for x in (0..r.width).step_by(7) {
                let d = pixel_ray(&cam, r, f64::from(x) + 0.5, f64::from(y) + 0.5);
                if let Some(depth) = entry_depth(&cam, &b, d) {
                    hits += 1;
                    let got = limit.at(d.as_vec3());
                    let want =
                        entry_depth(&cam, &grown, d).expect("the grown box holds the box") + f64::from(limit.raise);
                    assert!(got > depth, "({x}, {y}): {got} ≤ {depth}");
                    assert!((got - want).abs() <= 1e-6 * want, "({x}, {y}): {got} against {want}");
                }
            }
        }
        assert!(hits > 200, "the box must cover a good part of the view: {hits}");
    }

    #[test]
    fn facing_faces_are_where_rays_enter_the_box_and_keep_fragments_at_or_below_the_shaders_limit_and_close_to_it() {
        let cam = camera();
        let r = Resolution::DEFAULT;
        let view = cam.view_rotation();
        let margins = largest_margins(&cam);
        let rays = PixelRays::new(&cam, r);
        let [per_x, per_y, constant] = rays.uniform();
        let (mut bounded, mut below) = (0, Vec::new());
        for (b, _) in random_boxes_in_view(57) {
            let limit = FragmentLimit::new(&cam, &view, margins, &b);
            let faces = FacingFace::of_object(&cam, &view, margins, &b, &rays, r);
            let least = |plane: fn(&FacingFace) -> ScreenPlane, x: f64, y: f64| {
                faces
                    .iter()
                    .flatten()
                    .map(|f| plane(f).at(x, y))
                    .fold(NO_LIMIT, f64::min)
            };
            for y in (0..r.height).step_by(11) {
                for x in (0..r.width).step_by(11) {
                    let (x, y) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                    let kept = least(|f| f.kept_below, x, y);
                    let shader = limit.at((per_x * x as f32 + per_y * y as f32 + constant).truncate());
                    if shader >= NO_LIMIT {
                        continue;
                    }
                    bounded += 1;
                    assert!(kept <= shader, "{b:?} at ({x}, {y}): {kept} above {shader}");
                    // Close to it where the object may have fragments; and
                    // there the ray enters the box by the nearest face.
                    if let Some(entry) = entry_depth(&cam, &b, pixel_ray(&cam, r, x, y)) {
                        below.push((shader - kept) / shader);
                        let face = least(|f| f.face, x, y);
                        assert!(
                            (face - entry).abs() <= 1e-9 * entry,
                            "{b:?} at ({x}, {y}): face {face}, enters at {entry}"
                        );
                    }
                }
            }
        }
        assert!(bounded > 10_000, "only {bounded} pixel centres bounded");
        // Rays nearly along a face round its depth over the terms' size,
        // far larger than the depth: some are kept well below it.
        below.sort_by(f64::total_cmp);
        let (median, farthest) = (below[below.len() / 2], below[below.len() - 1]);
        assert!(
            median < 2e-6 && farthest < 1e-3,
            "kept below the limit by {median} of it (median), {farthest} at most"
        );
    }

    /// GL's margins at the coarsest snap, the largest, for `cam` on a
    /// `DEFAULT` target.
    fn largest_margins(cam: &Camera) -> BoxMargins {
        BoxMargins::new(
            DepthMargins::for_backend(wgpu::Backend::Gl),
            SubpixelPrecision::COARSEST,
            cam,
            Resolution::DEFAULT,
        )
    }

    /// Up to 200 boxes of random size and place in front of [`camera`],
    /// each with its test box for a `DEFAULT` target, seeded by `seed`.
    pub(crate) fn random_boxes_in_view(seed: u64) -> Vec<(Aabb, QueryBox)> {
        let cam = camera();
        let margins = largest_margins(&cam);
        let mut rng = crate::rng::Rng::new(seed);
        (0..200)
            .filter_map(|_| {
                let centre = cam.eye
                    + cam.rotation * DVec3::new(rng.range(-8.0, 8.0), rng.range(-6.0, 6.0), -rng.range(0.5, 30.0));
                let half = DVec3::new(rng.range(0.01, 4.0), rng.range(0.01, 4.0), rng.range(0.01, 4.0));
                let b = Aabb::new(centre - half, centre + half);
                match eye_relative_box(&cam, &cam.view_rotation(), margins, &b) {
                    EyeBox::Testable(q) => Some((b, q)),
                    EyeBox::ReachesNear => None,
                }
            })
            .collect()
    }

    #[test]
    fn box_planes_lie_above_every_surviving_fragment_and_claim_misses_only_where_rays_miss_the_object() {
        let cam = camera();
        let r = Resolution::DEFAULT;
        let view = cam.view_rotation();
        let margins = largest_margins(&cam);
        let rays = PixelRays::new(&cam, r);
        // The rays as the scene's fragment stage computes them, in f32.
        let [per_x, per_y, constant] = rays.uniform();
        let (mut hits, mut misses_claimed) = (0, 0);
        for (b, q) in random_boxes_in_view(31) {
            let planes = BoxPlanes::new(&cam, &q, &rays, r);
            let limit = FragmentLimit::new(&cam, &view, margins, &b);
            let (min, max) = grown_eye_relative(&cam, &b, margins.growth / 2.0);
            let object = Aabb::new(min + cam.eye, max + cam.eye);
            for y in (0..r.height).step_by(9) {
                for x in (0..r.width).step_by(9) {
                    let (x, y) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                    let missed = planes.missed_over([x, x], [y, y]);
                    misses_claimed += usize::from(missed);
                    if entry_depth(&cam, &object, pixel_ray(&cam, r, x, y)).is_none() {
                        continue;
                    }
                    hits += 1;
                    assert!(!missed, "{b:?}: a miss claimed at ({x}, {y})");
                    let fragment_ray = (per_x * x as f32 + per_y * y as f32 + constant).truncate();
                    let bound = planes
                        .entries()
                        .iter()
                        .map(|p| p.at(x, y))
                        .fold(f64::INFINITY, f64::min);
                    assert!(bound >= limit.at(fragment_ray), "{b:?} at ({x}, {y})");
                }
            }
        }
        assert!(
            hits > 10_000 && misses_claimed > 10_000,
            "{hits} hits, {misses_claimed} misses claimed"
        );
    }

    /// Holds `shader`, the planes a GPU made (or would make) for the
    /// tested box `q`, to the box's exact planes at every `step`-th pixel
    /// centre of `target`, summed in every order a GPU may sum
    /// `dot(plane, (x, y, 1))` in, fused or not: each axis with a face
    /// across it bounds, its entry at or above the exact entry plane and its
    /// exit at or below the exact exit plane; any other axis bounds nothing
    /// and meets every exit. `at` names the box in a failure. Returns the
    /// comparisons made.
    pub(crate) fn assert_planes_bound(
        camera: &Camera,
        q: &QueryBox,
        shader: &ShaderBoxPlanes,
        target: Resolution,
        step: usize,
        at: &str,
    ) -> u64 {
        let exact = BoxPlanes::new(camera, q, &PixelRays::new(camera, target), target);
        let axes: Vec<usize> = faces_across(q.min.truncate().as_dvec3(), q.max.truncate().as_dvec3())
            .iter()
            .enumerate()
            .filter_map(|(axis, faces)| faces.map(|_| axis))
            .collect();
        for &axis in &axes {
            assert!(shader.entries[axis][2].abs() < 1e29, "{at}: axis {axis} bounds");
        }
        let sums = |[a, b, c, _]: [f32; 4], x: f32, y: f32| {
            [
                a * x + b * y + c,
                a * x + (b * y + c),
                a.mul_add(x, b.mul_add(y, c)),
                b.mul_add(y, a * x) + c,
            ]
        };
        let mut compared = 0;
        for y in (0..target.height).step_by(step) {
            for x in (0..target.width).step_by(step) {
                let (x, y) = (x as f32 + 0.5, y as f32 + 0.5);
                let (cx, cy) = (f64::from(x), f64::from(y));
                for (k, (entry, exit)) in exact.entries().iter().zip(exact.exits()).enumerate() {
                    let (above, below) = (entry.at(cx, cy), exit.at(cx, cy));
                    let axis = axes[k];
                    for value in sums(shader.entries[axis], x, y) {
                        assert!(
                            f64::from(value) >= above,
                            "{at}: entry {axis} at ({x}, {y}): {value} < {above}"
                        );
                    }
                    for value in sums(shader.exits[axis], x, y) {
                        assert!(
                            f64::from(value) <= below,
                            "{at}: exit {axis} at ({x}, {y}): {value} > {below}"
                        );
                    }
                    compared += 1;
                }
                for axis in (0..3).filter(|a| !axes.contains(a)) {
                    assert!(sums(shader.entries[axis], x, y).iter().all(|&v| v >= 1e29), "{at}");
                    assert!(sums(shader.exits[axis], x, y).iter().all(|&v| v <= -1e29), "{at}");
                }
            }
        }
        compared
    }

    #[test]
    fn box_planes_as_the_shader_makes_them_in_f32_lie_above_their_entries_and_below_their_exits() {
        let cam = camera();
        let r = Resolution::DEFAULT;
        let mut compared = 0;
        for (_, q) in random_boxes_in_view(47) {
            // A division a GPU may round 2.5 steps either way.
            for steps in [-3, 0, 3] {
                let shader = ShaderBoxPlanes::as_the_shader_makes(&cam, &q, r, steps);
                compared += assert_planes_bound(&cam, &q, &shader, r, 7, &format!("{q:?}, {steps} steps"));
            }
        }
        assert!(compared > 300_000, "{compared} comparisons");
    }

    #[test]
    fn fragment_limit_is_open_when_the_eye_is_inside_the_box() {
        let cam = camera();
        let around = Aabb::new(cam.eye - DVec3::ONE, cam.eye + DVec3::ONE);
        let depth = DepthMargins::for_backend(wgpu::Backend::Vulkan);
        let margins = BoxMargins::new(depth, SubpixelPrecision::COARSEST, &cam, Resolution::DEFAULT);
        let limit = FragmentLimit::new(&cam, &cam.view_rotation(), margins, &around);
        assert!(limit.at(pixel_ray(&cam, Resolution::DEFAULT, 400.5, 300.5).as_vec3()) >= NO_LIMIT);
    }

    #[test]
    fn boxes_are_raised_by_the_backend_margins() {
        let cam = camera();
        let view = cam.view_rotation();
        let b = Aabb::new(DVec3::new(-2.0, -1.0, -60.0), DVec3::new(1.0, 3.0, -20.0));
        // At 8 sub-pixel bits the box grows by the least fraction only.
        let margins = |backend| {
            BoxMargins::new(
                DepthMargins::for_backend(backend),
                SubpixelPrecision::reported(8),
                &cam,
                Resolution::DEFAULT,
            )
        };
        let raise = |backend| match eye_relative_box(&cam, &view, margins(backend), &b) {
            EyeBox::Testable(q) => f64::from(q.min.w),
            EyeBox::ReachesNear => panic!("the box lies far beyond the near plane"),
        };
        let nearest_depth = cam.near / nearest_view_depth(&view, b.min - cam.eye, b.max - cam.eye);
        let relative = raise(wgpu::Backend::Vulkan);
        assert!(
            (relative / (RAISE_PER_DEPTH * nearest_depth) - 1.0).abs() < 1e-3,
            "{relative}"
        );
        assert!((raise(wgpu::Backend::Gl) - relative - GL_RAISE).abs() < 1e-12);
    }

    #[test]
    fn boxes_grow_by_twice_a_vertexs_snap_at_least() {
        let cam = camera();
        let depth = DepthMargins::for_backend(wgpu::Backend::Vulkan);
        let growth = |subpixel, height| {
            let r = Resolution {
                width: height * 4 / 3,
                height,
            };
            BoxMargins::new(depth, subpixel, &cam, r).growth
        };
        let coarsest = SubpixelPrecision::COARSEST;
        assert_eq!(
            growth(coarsest, 8192),
            BOX_GROWTH,
            "fine pictures keep the relative growth"
        );
        // 160×120 at 60°: a pixel spans 2 tan 30° / 120 = 9.6e-3 at depth 1.
        let r = Resolution {
            width: 160,
            height: 120,
        };
        let pixel = 2.0 * 30f64.to_radians().tan() / 120.0;
        for subpixel in [coarsest, SubpixelPrecision::reported(8)] {
            let snap = subpixel.vertex_error(r);
            let grown = growth(subpixel, 120);
            assert!(
                (grown / (3f64.sqrt() * 2.0 * snap * pixel) - 1.0).abs() < 1e-12,
                "{grown}"
            );
            // Its outline moves out by twice a vertex's snap or more: a box
            // corner at reach 10 grown by growth × 10, seen from 10 · √3 away.
            let shift_px = grown * 10.0 / (10.0 * 3f64.sqrt()) / pixel;
            assert!(shift_px >= 2.0 * snap * (1.0 - 1e-12), "{shift_px}");
        }
        assert!(
            growth(coarsest, 120) > BOX_GROWTH,
            "the coarsest snap sets the growth at 160×120"
        );
    }

    #[test]
    fn an_adapters_report_is_taken_between_vulkans_least_and_eight_bits() {
        assert_eq!(
            SubpixelPrecision::reported(0),
            SubpixelPrecision::COARSEST,
            "a failed GL query"
        );
        assert_eq!(SubpixelPrecision::reported(3).bits(), 4);
        assert_eq!(SubpixelPrecision::reported(6).bits(), 6);
        assert_eq!(SubpixelPrecision::reported(12).bits(), 8);
        let r = Resolution {
            width: 800,
            height: 600,
        };
        // One step of the grid, and f32's rounding of the viewport.
        assert_eq!(
            SubpixelPrecision::reported(8).vertex_error(r),
            1.0 / 256.0 + 800.0 / f64::from(1u32 << 21)
        );
        assert_eq!(
            SubpixelPrecision::COARSEST.vertex_error(r),
            1.0 / 16.0 + 800.0 / f64::from(1u32 << 21)
        );
    }
}
