//! CPU ray casts against a scene's triangles, through its hierarchy, in f64:
//! the first surface a ray meets, every surface along a line, and the
//! distance from a point to the nearest surface. Generated walks use them to
//! find the ground and free space, and a run uses them to count frames with
//! geometry inside the near plane.

use std::cell::Cell;

use glam::{DAffine3, DVec3};

use crate::bounds::Aabb;
use crate::hierarchy::{Hierarchy, HierarchyParams};
use crate::scene::Scene;

/// A scene and a hierarchy over its objects, ready for ray casts.
pub struct RayCaster<'a> {
    scene: &'a Scene,
    hierarchy: Hierarchy,
    /// Each object's world-to-local transform.
    to_local: Vec<DAffine3>,
}

/// A surface a ray met: its distance along the ray (in units of the ray's
/// direction) and the object it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub object: u32,
}

impl<'a> RayCaster<'a> {
    pub fn new(scene: &'a Scene) -> RayCaster<'a> {
        RayCaster {
            hierarchy: Hierarchy::build(&scene.objects, &HierarchyParams::default()),
            to_local: scene.objects.iter().map(|o| o.transform.inverse()).collect(),
            scene,
        }
    }

    /// The nearest surface along `origin + t·direction` for `t` in
    /// `(0, max_t]`.
    pub fn first_hit(&self, origin: DVec3, direction: DVec3, max_t: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.cast(origin, direction, max_t, &mut |hit, reach| {
            if best.is_none_or(|b| hit.t < b.t) {
                best = Some(hit);
                *reach = hit.t;
            }
        });
        best
    }

    /// Every surface along `origin + t·direction` for `t` in `(0, max_t]`,
    /// nearest first.
    pub fn all_hits(&self, origin: DVec3, direction: DVec3, max_t: f64, hits: &mut Vec<Hit>) {
        hits.clear();
        self.cast(origin, direction, max_t, &mut |hit, _| hits.push(hit));
        hits.sort_by(|a, b| a.t.total_cmp(&b.t));
    }

    /// Calls `found` with every surface along the ray up to `max_t`; `found`
    /// may shorten the reach (the second argument) to prune the search.
    fn cast(&self, origin: DVec3, direction: DVec3, max_t: f64, found: &mut dyn FnMut(Hit, &mut f64)) {
        let reach = Cell::new(max_t);
        let inverse = direction.recip();
        self.visit_objects(&|bounds| slab(bounds, origin, inverse, reach.get()), &mut |object| {
            // An affine map keeps a line's parameter: t is the same in the
            // mesh's local frame.
            let local = self.to_local[object as usize];
            let (lo, ld) = (local.transform_point3(origin), local.transform_vector3(direction));
            for [a, b, c] in self.triangles(self.scene.objects[object as usize].mesh) {
                if let Some(t) = intersect(lo, ld, a, b, c)
                    && t > 0.0
                    && t <= reach.get()
                {
                    let mut shortened = reach.get();
                    found(Hit { t, object }, &mut shortened);
                    reach.set(shortened);
                }
            }
        });
    }

    /// The distance from `point` to the nearest surface, if one lies within
    /// `within`.
    pub fn nearest_distance(&self, point: DVec3, within: f64) -> Option<f64> {
        let best = Cell::new(within);
        let mut found = false;
        self.visit_objects(&|bounds| box_distance(bounds, point) <= best.get(), &mut |object| {
            let world = self.scene.objects[object as usize].transform;
            for [a, b, c] in self.triangles(self.scene.objects[object as usize].mesh) {
                let [a, b, c] = [a, b, c].map(|v| world.transform_point3(v));
                let d = closest_point(point, a, b, c).distance(point);
                if d <= best.get() {
                    best.set(d);
                    found = true;
                }
            }
        });
        found.then(|| best.get())
    }

    /// Calls `visit` with every object whose box `wanted` accepts, and whose
    /// hierarchy nodes' boxes it accepts too; `wanted` is asked as the search
    /// goes, so a bound `visit` tightens prunes what is left.
    fn visit_objects(&self, wanted: &dyn Fn(&Aabb) -> bool, visit: &mut dyn FnMut(u32)) {
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.hierarchy.nodes[n];
            if !wanted(&node.bounds) {
                continue;
            }
            if !node.is_leaf() {
                stack.extend(node.children());
                continue;
            }
            for &object in self.hierarchy.subtree_objects(node) {
                if wanted(&self.scene.objects[object as usize].bounds) {
                    visit(object);
                }
            }
        }
    }

    /// The triangles of a mesh, in its local frame.
    fn triangles(&self, mesh: u32) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        let mesh = &self.scene.meshes[mesh as usize];
        let range = mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize;
        self.scene.indices[range]
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| DVec3::from(self.scene.vertices[t[k] as usize].map(f64::from))))
    }
}

/// Whether the ray meets `bounds` for some `t` in `[0, reach]` (slab test;
/// `inverse` is the direction's reciprocal, infinite for a zero component).
fn slab(bounds: &Aabb, origin: DVec3, inverse: DVec3, reach: f64) -> bool {
    let a = (bounds.min - origin) * inverse;
    let b = (bounds.max - origin) * inverse;
    // A zero direction component gives 0·∞ = NaN where the origin lies on a
    // face: max/min ignore NaN, which keeps the box.
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(reach);
    near <= far
}

/// Möller–Trumbore: the parameter at which the ray meets the triangle.
fn intersect(origin: DVec3, direction: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) / det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) / det)
}

/// The distance from `point` to `bounds` (0 inside).
fn box_distance(bounds: &Aabb, point: DVec3) -> f64 {
    (bounds.min - point).max(point - bounds.max).max(DVec3::ZERO).length()
}

/// The point of triangle `abc` nearest to `p` (Ericson, Real-Time Collision
/// Detection §5.1.5: by the Voronoi region of `p`).
fn closest_point(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangles_are_hit_where_they_are_and_nearest_points_lie_on_them() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let t = intersect(DVec3::new(0.25, 0.25, 2.0), DVec3::NEG_Z, a, b, c);
        assert_eq!(t, Some(2.0));
        assert_eq!(intersect(DVec3::new(0.75, 0.75, 2.0), DVec3::NEG_Z, a, b, c), None);
        let foot = closest_point(DVec3::new(0.2, 0.2, 3.0), a, b, c);
        assert!(foot.distance(DVec3::new(0.2, 0.2, 0.0)) < 1e-15, "{foot}");
        assert_eq!(closest_point(DVec3::new(-1.0, -1.0, 0.0), a, b, c), a);
        assert_eq!(
            closest_point(DVec3::new(1.0, 1.0, 0.0), a, b, c),
            DVec3::new(0.5, 0.5, 0.0)
        );
        let unit = Aabb::new(DVec3::ZERO, DVec3::ONE);
        assert!(slab(&unit, DVec3::new(0.5, 0.5, 5.0), DVec3::NEG_Z.recip(), 10.0));
        assert!(!slab(&unit, DVec3::new(0.5, 0.5, 5.0), DVec3::NEG_Z.recip(), 3.0));
        assert!(!slab(&unit, DVec3::new(1.5, 0.5, 5.0), DVec3::NEG_Z.recip(), 10.0));
        assert_eq!(box_distance(&unit, DVec3::new(0.5, 3.0, 0.5)), 2.0);
    }
}
