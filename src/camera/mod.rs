//! Cameras, projection and frustum tests, all in f64.
//!
//! Conventions: right-handed world, +Y up; the camera looks down its local
//! −Z with +Y up. Depth is reverse-Z with an infinite far plane: the near
//! plane maps to depth 1, infinity to 0, and the depth test is `Greater`.
//! Model-view matrices are built camera-relative (the eye is subtracted in
//! f64 before anything is rounded to f32), so geometry far from the origin
//! renders as precisely as geometry at it.

pub mod generate;
pub mod path;
pub mod walk;

use glam::{DAffine3, DMat3, DMat4, DQuat, DVec3, DVec4};

use crate::bounds::Aabb;

/// One view of the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    /// Camera-to-world rotation.
    pub rotation: DQuat,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Distance of the near plane.
    pub near: f64,
    /// Width over height of the viewport.
    pub aspect: f64,
}

impl Camera {
    pub fn forward(&self) -> DVec3 {
        self.rotation * DVec3::NEG_Z
    }

    /// World-to-camera rotation.
    pub fn view_rotation(&self) -> DMat3 {
        DMat3::from_quat(self.rotation.conjugate())
    }

    /// Object-to-camera transform with the eye subtracted in f64.
    pub fn model_view(&self, model: &DAffine3) -> DAffine3 {
        let r = self.view_rotation();
        DAffine3 {
            matrix3: r * model.matrix3,
            translation: r * (model.translation - self.eye),
        }
    }

    /// Reverse-Z perspective with an infinite far plane, wgpu depth range
    /// [0, 1]: clip = (x·f/aspect, y·f, near, −z), so depth = near / −z.
    pub fn projection(&self) -> DMat4 {
        let f = 1.0 / (self.fov_y / 2.0).tan();
        DMat4::from_cols(
            DVec4::new(f / self.aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, f, 0.0, 0.0),
            DVec4::new(0.0, 0.0, 0.0, -1.0),
            DVec4::new(0.0, 0.0, self.near, 0.0),
        )
    }

    pub fn frustum(&self) -> Frustum {
        Frustum::new(self)
    }
}

/// Depth along the view direction of the nearest point of the eye-relative
/// box `min`..`max`, for a camera whose `view_rotation()` is `view`: the
/// nearest corner's, found axis by axis.
pub fn nearest_view_depth(view: &DMat3, min: DVec3, max: DVec3) -> f64 {
    // Depth is −(row z of view) · p; its least over the box takes, on each
    // axis, whichever bound makes that axis's term larger.
    let forward = -view.row(2);
    (forward * min).min(forward * max).element_sum()
}

/// Rotation of a camera at the origin looking along `forward` with `up`
/// as close to its +Y as possible. When `up` is (nearly) parallel to
/// `forward` (looking straight up or down), the world axis least aligned with
/// `forward` stands in for it, so every direction gives a valid camera.
pub fn look_rotation(forward: DVec3, up: DVec3) -> DQuat {
    let (f, up) = (unit(forward), unit(up));
    let mut right = f.cross(up);
    if up_along_view(f, up) {
        let a = f.abs();
        let fallback = if a.x <= a.y && a.x <= a.z {
            DVec3::X
        } else if a.y <= a.z {
            DVec3::Y
        } else {
            DVec3::Z
        };
        right = f.cross(fallback);
    }
    let right = right.normalize();
    let true_up = right.cross(f);
    DQuat::from_mat3(&DMat3::from_cols(right, true_up, -f)).normalize()
}

/// `v` scaled to unit length, by its largest component first so that huge
/// or tiny vectors cannot overflow.
fn unit(v: DVec3) -> DVec3 {
    (v / v.abs().max_element()).normalize()
}

/// Whether `up` is (nearly) parallel to the view direction `forward`
/// (both non-zero), so that it leaves the camera's roll undefined: within
/// about 1e-6 radians. [`look_rotation`] takes another axis then; a camera
/// path refuses such a keyframe.
pub fn up_along_view(forward: DVec3, up: DVec3) -> bool {
    unit(forward).cross(unit(up)).length_squared() < 1e-12
}

/// Where a box lies relative to the frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    Outside,
    Intersecting,
    Inside,
}

/// A plane `normal · p + offset ≥ 0` (inside), in eye-centred coordinates.
#[derive(Clone, Copy, Debug)]
struct Plane {
    normal: DVec3,
    offset: f64,
}

/// The view frustum as the near plane and four side planes through the eye
/// (there is no far plane). Boxes are tested in eye-centred coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    eye: DVec3,
    planes: [Plane; 5],
}

/// Relative slack of the outside test: a box must be clearly outside, by more
/// than f32 rasterisation could blur, before it is culled. At least the GPU
/// walks' own test's slack plus its error (`gpu_walk/frustum.rs`), so that
/// test culls every object this one does.
pub const OUTSIDE_SLACK: f64 = 6e-6;

impl Frustum {
    fn new(cam: &Camera) -> Frustum {
        let ty = (cam.fov_y / 2.0).tan();
        let tx = ty * cam.aspect;
        let r = DMat3::from_quat(cam.rotation);
        let plane = |n: DVec3, offset: f64| {
            let len = n.length();
            Plane {
                normal: r * (n / len),
                offset: offset / len,
            }
        };
        Frustum {
            eye: cam.eye,
            planes: [
                plane(DVec3::new(0.0, 0.0, -1.0), -cam.near),
                plane(DVec3::new(1.0, 0.0, -tx), 0.0),
                plane(DVec3::new(-1.0, 0.0, -tx), 0.0),
                plane(DVec3::new(0.0, 1.0, -ty), 0.0),
                plane(DVec3::new(0.0, -1.0, -ty), 0.0),
            ],
        }
    }

    /// The eye, and the five planes (unit normal pointing inwards, and
    /// offset) in eye-centred world coordinates: a point p is inside where
    /// `normal · (p − eye) + offset ≥ 0` for every plane.
    pub fn planes(&self) -> (DVec3, [(DVec3, f64); 5]) {
        (self.eye, self.planes.map(|p| (p.normal, p.offset)))
    }

    /// Conservative: `Outside` only when the box lies wholly behind one plane.
    pub fn classify(&self, b: &Aabb) -> Containment {
        let (min, max) = (b.min - self.eye, b.max - self.eye);
        let slack = OUTSIDE_SLACK * (min.abs().max(max.abs()).max_element() + 1e-30);
        let mut inside = true;
        for p in &self.planes {
            let n = p.normal;
            // The corner farthest along the normal, and the one least along it.
            let far = DVec3::select(n.cmpge(DVec3::ZERO), max, min);
            let near = DVec3::select(n.cmpge(DVec3::ZERO), min, max);
            if n.dot(far) + p.offset < -slack {
                return Containment::Outside;
            }
            if n.dot(near) + p.offset < slack {
                inside = false;
            }
        }
        if inside {
            Containment::Inside
        } else {
            Containment::Intersecting
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(eye: DVec3, forward: DVec3) -> Camera {
        Camera {
            eye,
            rotation: look_rotation(forward, DVec3::Y),
            fov_y: 60f64.to_radians(),
            near: 0.1,
            aspect: 4.0 / 3.0,
        }
    }

    /// Clip-space position of a world point, through the same matrices the
    /// GPU uses.
    fn project(cam: &Camera, p: DVec3) -> DVec4 {
        let mv = cam.model_view(&DAffine3::IDENTITY);
        cam.projection() * mv.transform_point3(p).extend(1.0)
    }

    #[test]
    fn nearest_view_depth_is_the_nearest_corner_along_the_view() {
        let cam = camera(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.3, -0.4, -1.0));
        let view = cam.view_rotation();
        let (min, max) = (DVec3::new(-4.0, -1.0, -9.0), DVec3::new(2.0, 5.0, -6.0));
        let corners = Aabb::new(min, max).corners();
        let nearest = corners.iter().map(|&c| -(view * c).z).fold(f64::INFINITY, f64::min);
        assert!((nearest_view_depth(&view, min, max) - nearest).abs() < 1e-12);
    }

    #[test]
    fn projection_maps_near_to_one_and_far_towards_zero() {
        let cam = camera(DVec3::ZERO, DVec3::NEG_Z);
        let at = |z: f64| {
            let c = project(&cam, DVec3::new(0.0, 0.0, z));
            c.z / c.w
        };
        assert!((at(-0.1) - 1.0).abs() < 1e-15);
        assert!((at(-10.0) - 0.01).abs() < 1e-15);
        assert!(at(-1e9) > 0.0 && at(-1e9) < 1e-9);
    }

    #[test]
    fn look_rotation_points_the_camera_and_survives_vertical_views() {
        for f in [
            DVec3::X,
            DVec3::new(1.0, 2.0, -3.0),
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::new(0.0, 0.0, -1e200),
            DVec3::splat(1e-300),
        ] {
            let q = look_rotation(f, DVec3::new(0.0, 1e300, 0.0));
            let expected = (f / f.abs().max_element()).normalize();
            assert!((q * DVec3::NEG_Z - expected).length() < 1e-12, "{f:?}");
            assert!(q.is_finite() && q.is_normalized());
        }
    }

    #[test]
    fn model_view_is_exact_far_from_the_origin() {
        // The same relative geometry at 1e7 gives the same camera-space matrix.
        let offset = DVec3::new(1e7, -1e7, 1e7);
        let model = DAffine3::from_translation(DVec3::new(3.0, 1.0, -7.0));
        let near = camera(DVec3::ZERO, DVec3::new(1.0, -0.2, -1.0)).model_view(&model);
        let far = camera(offset, DVec3::new(1.0, -0.2, -1.0)).model_view(&(DAffine3::from_translation(offset) * model));
        assert!((near.translation - far.translation).length() < 1e-8);
    }

    #[test]
    fn frustum_classification_matches_projected_corners() {
        // Brute force: a box is outside when all its sample points project
        // outside the same clip plane; inside when all corners are inside.
        let cam = camera(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.3, -0.1, -1.0));
        let f = cam.frustum();
        let mut rng = crate::rng::Rng::new(1);
        let mut rand = || rng.range(0.0, 1.0);
        let inside_clip = |c: DVec4| c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z <= c.w;
        let mut seen = [0; 3];
        for _ in 0..2000 {
            let c = DVec3::new(rand() * 60.0 - 30.0, rand() * 60.0 - 30.0, rand() * 60.0 - 50.0);
            let e = DVec3::new(rand(), rand(), rand()) * 4.0;
            let b = Aabb::new(c, c + e);
            let corners_in = b.corners().iter().filter(|&&p| inside_clip(project(&cam, p))).count();
            match f.classify(&b) {
                Containment::Inside => {
                    seen[0] += 1;
                    assert_eq!(corners_in, 8, "inside box {b:?} has a corner outside");
                }
                Containment::Outside => {
                    seen[1] += 1;
                    // Dense sampling of the box: nothing may be visible.
                    for i in 0..=6 {
                        for j in 0..=6 {
                            for k in 0..=6 {
                                let p = b.min + b.extent() * DVec3::new(i as f64, j as f64, k as f64) / 6.0;
                                assert!(
                                    !inside_clip(project(&cam, p)),
                                    "culled box {b:?} has visible point {p:?}"
                                );
                            }
                        }
                    }
                }
                Containment::Intersecting => seen[2] += 1,
            }
        }
        assert!(seen.iter().all(|&n| n > 50), "every class exercised: {seen:?}");
    }

    #[test]
    fn box_holding_the_eye_is_never_outside() {
        let cam = camera(DVec3::ZERO, DVec3::NEG_Z);
        let b = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        assert_eq!(cam.frustum().classify(&b), Containment::Intersecting);
        // Entirely behind the camera.
        let behind = Aabb::new(DVec3::new(-1.0, -1.0, 1.0), DVec3::new(1.0, 1.0, 2.0));
        assert_eq!(cam.frustum().classify(&behind), Containment::Outside);
        // Between the eye and the near plane.
        let too_close = Aabb::new(DVec3::new(-0.01, -0.01, -0.05), DVec3::new(0.01, 0.01, -0.02));
        assert_eq!(cam.frustum().classify(&too_close), Containment::Outside);
    }
}
