//! Axis-aligned bounding boxes in f64 world space.
//!
//! Bounds stay in f64 everywhere on the CPU side (DESIGN.md, "Numerical
//! rules"): a scene translated by 1e7 units must cull exactly like the same
//! scene at the origin, which f32 bounds cannot promise.

use glam::{DAffine3, DVec3};
use serde::Serialize;

/// An axis-aligned box; `EMPTY` has `min > max` and unions as the identity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    /// The box that contains nothing: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn new(min: DVec3, max: DVec3) -> Self {
        Aabb { min, max }
    }

    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Self {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.grown(p))
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    pub fn grown(self, p: DVec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, other: Aabb) -> Self {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    pub fn extent(&self) -> DVec3 {
        (self.max - self.min).max(DVec3::ZERO)
    }

    /// Surface area, the probability measure of the surface-area heuristic.
    pub fn surface_area(&self) -> f64 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    pub fn contains_point(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (self.contains_point(other.min) && self.contains_point(other.max))
    }

    /// The least and greatest of `p · direction` over the box: its extent
    /// along a direction (an up axis, a ground axis).
    pub fn span_along(&self, direction: DVec3) -> (f64, f64) {
        let values = self.corners().map(|c| c.dot(direction));
        let least = values.iter().copied().fold(f64::INFINITY, f64::min);
        (least, values.iter().copied().fold(f64::NEG_INFINITY, f64::max))
    }

    /// The eight corners, bit i of the index choosing max over min on axis i.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// The world box of this box under an affine transform (exact for the
    /// transformed corners, so it is the tightest axis-aligned box of them).
    pub fn transformed(&self, transform: &DAffine3) -> Aabb {
        if self.is_empty() {
            return Aabb::EMPTY;
        }
        Aabb::from_points(self.corners().map(|c| transform.transform_point3(c)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_is_union_identity() {
        let b = Aabb::new(DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 3.0, 4.0));
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.union(b), b);
        assert_eq!(b.union(Aabb::EMPTY), b);
    }

    #[test]
    fn transformed_box_holds_every_transformed_corner() {
        let b = Aabb::new(DVec3::new(-1.0, -2.0, -3.0), DVec3::new(1.0, 2.0, 3.0));
        let t = DAffine3::from_scale_rotation_translation(
            DVec3::new(2.0, 1.0, 0.5),
            glam::DQuat::from_rotation_y(0.7) * glam::DQuat::from_rotation_x(-0.3),
            DVec3::new(1e7, -5.0, 3.0),
        );
        let w = b.transformed(&t);
        for c in b.corners() {
            assert!(w.contains_point(t.transform_point3(c)));
        }
        // Tight: every face of the world box touches a transformed corner.
        let pts = b.corners().map(|c| t.transform_point3(c));
        for axis in 0..3 {
            assert!(pts.iter().any(|p| p[axis] == w.min[axis]));
            assert!(pts.iter().any(|p| p[axis] == w.max[axis]));
        }
    }

    #[test]
    fn surface_area_of_unit_cube_is_six() {
        assert_eq!(Aabb::new(DVec3::ZERO, DVec3::ONE).surface_area(), 6.0);
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
    }
}
