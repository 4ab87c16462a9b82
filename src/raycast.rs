//! CPU ray casts against a scene's triangles, through its hierarchy, in f64:
//! the first surface a ray meets, every surface along a line, and the
//! distance from a point to the nearest surface. Generated walks use them to
//! find the ground and free space, and a run uses them to count frames with
//! geometry inside the near plane.
//!
//! Two levels of trees: the scene's hierarchy over objects, then one tree
//! per mesh over its triangles in the mesh's own frame, built the first time
//! a search reaches the mesh (a planned walk casts tens of thousands of
//! rays; a mesh is thousands of triangles).
//!
//! A caster may be given a [`Budget`]: its box and triangle tests are
//! counted, told to a listener now and then (progress, and a way to stop),
//! and once the budget is spent or the listener asks to stop, every search
//! finds nothing and [`RayCaster::stopped`] says why. A model whose every
//! ray meets millions of triangles (50 000 instances of one mesh in one
//! place) then costs a known amount of work, not hours.

use std::cell::{Cell, RefCell};
use std::ops::ControlFlow;
use std::sync::OnceLock;

use glam::{DAffine3, DVec3};

use crate::bounds::Aabb;
use crate::hierarchy::{Hierarchy, HierarchyParams, Item};
use crate::scene::Scene;

/// A scene and a hierarchy over its objects, ready for ray casts.
pub struct RayCaster<'a> {
    scene: &'a Scene,
    hierarchy: Hierarchy,
    /// Each object's world-to-local transform; none where its transform
    /// has none (it flattens the mesh: a floor made of a box scaled to no
    /// height), whose triangles are met in the world.
    to_local: Vec<Option<DAffine3>>,
    /// Each mesh's tree over its triangles (indices into the mesh's
    /// triangle list), built on first use.
    mesh_trees: Vec<OnceLock<Hierarchy>>,
    work: Work<'a>,
}

/// How much a caster may search: box and triangle tests, each a unit of
/// work, and whom it tells as they are spent.
pub struct Budget<'a> {
    /// Tests allowed in all.
    pub tests: u64,
    /// Told the tests spent and allowed every [`Budget::TELL_EVERY`] tests;
    /// breaking stops every search.
    pub listener: Box<dyn FnMut(u64, u64) -> ControlFlow<()> + 'a>,
}

impl Budget<'_> {
    /// Tests between two calls of the listener (a few milliseconds).
    pub const TELL_EVERY: u64 = 1 << 18;

    /// No limit, no listener.
    pub fn unlimited() -> Budget<'static> {
        Budget {
            tests: u64::MAX,
            listener: Box::new(|_, _| ControlFlow::Continue(())),
        }
    }
}

/// Why a caster's searches stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stopped {
    /// Its budget was spent.
    Spent,
    /// Its listener asked it to stop (Ctrl-C).
    Interrupted,
}

/// The tests a caster has spent against its budget. Each test costs a
/// decrement; the listener is told, and the budget checked, at the end of
/// a stretch of tests.
struct Work<'a> {
    budget: RefCell<Budget<'a>>,
    /// Tests counted up to the start of the current stretch.
    counted: Cell<u64>,
    /// The tests of the current stretch before the next telling, and
    /// those left of them; both 0 once stopped.
    stretch: Cell<u64>,
    left: Cell<u64>,
    stopped: Cell<Option<Stopped>>,
}

impl<'a> Work<'a> {
    fn new(budget: Budget<'a>) -> Work<'a> {
        let work = Work {
            budget: RefCell::new(budget),
            counted: Cell::new(0),
            stretch: Cell::new(0),
            left: Cell::new(0),
            stopped: Cell::new(None),
        };
        work.next_stretch();
        work
    }

    /// Tests spent so far.
    fn spent(&self) -> u64 {
        self.counted.get() + self.stretch.get() - self.left.get()
    }

    /// Charges one test; whether the search may go on.
    #[inline]
    fn charge(&self) -> bool {
        match self.left.get() {
            0 => self.tell(),
            left => {
                self.left.set(left - 1);
                true
            }
        }
    }

    /// The test that ends a stretch: the listener told, the budget checked.
    #[cold]
    fn tell(&self) -> bool {
        if self.stopped.get().is_some() {
            return false;
        }
        let spent = self.counted.get() + self.stretch.get() + 1;
        self.counted.set(spent);
        let stopped = {
            let mut budget = self.budget.borrow_mut();
            let tests = budget.tests;
            if (budget.listener)(spent, tests).is_break() {
                Some(Stopped::Interrupted)
            } else {
                (spent > tests).then_some(Stopped::Spent)
            }
        };
        self.stopped.set(stopped);
        match stopped {
            Some(_) => {
                self.stretch.set(0);
                self.left.set(0);
                false
            }
            None => {
                self.next_stretch();
                true
            }
        }
    }

    /// Starts the stretch that ends at the next telling: after
    /// [`Budget::TELL_EVERY`] tests, or with the first test past the budget.
    fn next_stretch(&self) {
        let counted = self.counted.get();
        let tests = self.budget.borrow().tests;
        let end = counted.saturating_add(Budget::TELL_EVERY).min(tests.saturating_add(1));
        let stretch = end - counted - 1;
        self.stretch.set(stretch);
        self.left.set(stretch);
    }
}

/// A surface a ray met: its distance along the ray (in units of the ray's
/// direction) and the object it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub object: u32,
}

/// A triangle's box, for building a mesh's tree: every triangle costs one
/// intersection test.
struct TriangleBox(Aabb);

impl Item for TriangleBox {
    fn bounds(&self) -> Aabb {
        self.0
    }

    fn cost(&self) -> f64 {
        1.0
    }
}

/// A mesh tree's leaves hold a few triangles, and a node test costs about
/// one triangle test.
const MESH_TREE: HierarchyParams = HierarchyParams {
    max_leaf_objects: 4,
    traversal_cost: 1.0,
    bins: 16,
};

impl<'a> RayCaster<'a> {
    /// A caster without limit.
    pub fn new(scene: &'a Scene) -> RayCaster<'a> {
        RayCaster::with_budget(scene, Budget::unlimited())
    }

    /// A caster that stops searching once `budget` is spent or its
    /// listener breaks.
    pub fn with_budget(scene: &'a Scene, budget: Budget<'a>) -> RayCaster<'a> {
        RayCaster {
            hierarchy: Hierarchy::build(&scene.objects, &HierarchyParams::default()),
            to_local: scene
                .objects
                .iter()
                .map(|o| Some(o.transform.inverse()).filter(DAffine3::is_finite))
                .collect(),
            mesh_trees: scene.meshes.iter().map(|_| OnceLock::new()).collect(),
            scene,
            work: Work::new(budget),
        }
    }

    /// Why the searches stopped, if they did: from then on every search
    /// finds nothing, so what was found since the last check may be wrong.
    pub fn searching(&self) -> Result<(), Stopped> {
        self.work.stopped.get().map_or(Ok(()), Err)
    }

    /// The box and triangle tests done so far.
    pub fn tests(&self) -> u64 {
        self.work.spent()
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
            let mut meet = |[a, b, c]: [DVec3; 3], (origin, direction): (DVec3, DVec3)| {
                if let Some(t) = intersect(origin, direction, a, b, c)
                    && t > 0.0
                    && t <= reach.get()
                {
                    let mut shortened = reach.get();
                    found(Hit { t, object }, &mut shortened);
                    reach.set(shortened);
                }
            };
            let mesh = self.scene.objects[object as usize].mesh;
            match self.to_local[object as usize] {
                // An affine map keeps a line's parameter: t is the same in
                // the mesh's local frame.
                Some(local) => {
                    let ray = (local.transform_point3(origin), local.transform_vector3(direction));
                    let local_inverse = ray.1.recip();
                    let near_enough = |bounds: &Aabb| slab(bounds, ray.0, local_inverse, reach.get());
                    self.visit_triangles(mesh, &near_enough, &mut |corners| meet(corners, ray));
                }
                None => {
                    let world = self.scene.objects[object as usize].transform;
                    let near_enough = |bounds: &Aabb| slab(&bounds.transformed(&world), origin, inverse, reach.get());
                    self.visit_triangles(mesh, &near_enough, &mut |corners| {
                        meet(corners.map(|v| world.transform_point3(v)), (origin, direction))
                    });
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
            let object = &self.scene.objects[object as usize];
            let world = object.transform;
            // The world box of a local box holds its triangles: its distance
            // bounds theirs from below, whatever the transform's scale.
            let near_enough = |bounds: &Aabb| box_distance(&bounds.transformed(&world), point) <= best.get();
            self.visit_triangles(object.mesh, &near_enough, &mut |corners| {
                let [a, b, c] = corners.map(|v| world.transform_point3(v));
                let d = closest_point(point, a, b, c).distance(point);
                if d <= best.get() {
                    best.set(d);
                    found = true;
                }
            });
        });
        found.then(|| best.get())
    }

    /// Calls `visit` with every object whose box `wanted` accepts, and whose
    /// hierarchy nodes' boxes it accepts too; `wanted` is asked as the search
    /// goes, so a bound `visit` tightens prunes what is left.
    fn visit_objects(&self, wanted: &dyn Fn(&Aabb) -> bool, visit: &mut dyn FnMut(u32)) {
        descend(&self.hierarchy, &self.work, wanted, &mut |object| {
            if self.work.charge() && wanted(&self.scene.objects[object as usize].bounds) {
                visit(object);
            }
        });
    }

    /// Calls `visit` with the local corners of every triangle of `mesh` in a
    /// leaf whose boxes (local) `wanted` accepts.
    fn visit_triangles(&self, mesh: u32, wanted: &dyn Fn(&Aabb) -> bool, visit: &mut dyn FnMut([DVec3; 3])) {
        let tree = self.mesh_trees[mesh as usize].get_or_init(|| {
            let boxes: Vec<TriangleBox> = self
                .triangles(mesh)
                .map(|corners| TriangleBox(corners.iter().fold(Aabb::EMPTY, |b, &v| b.grown(v))))
                .collect();
            Hierarchy::build(&boxes, &MESH_TREE)
        });
        descend(tree, &self.work, wanted, &mut |triangle| {
            if self.work.charge() {
                visit(self.scene.triangle(mesh, triangle));
            }
        });
    }

    /// The triangles of a mesh, in its local frame.
    fn triangles(&self, mesh: u32) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        (0..self.scene.meshes[mesh as usize].triangles()).map(move |t| self.scene.triangle(mesh, t))
    }
}

/// Calls `visit` with the items of every leaf of `tree` reached through
/// boxes `wanted` accepts (asked as the search goes), each box charged to
/// `work` (an exhausted budget ends the search).
fn descend(tree: &Hierarchy, work: &Work, wanted: &dyn Fn(&Aabb) -> bool, visit: &mut dyn FnMut(u32)) {
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        let node = &tree.nodes[n];
        if !work.charge() {
            return;
        }
        if !wanted(&node.bounds) {
            continue;
        }
        if node.is_leaf() {
            tree.subtree_objects(node).iter().for_each(|&item| visit(item));
        } else {
            stack.extend(node.children());
        }
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

    /// A bumpy sheet of 2·n² triangles, folded into a tube so rays meet it
    /// several times.
    fn tube(n: u32) -> (Vec<DVec3>, Vec<u32>) {
        let positions = (0..=n)
            .flat_map(|j| {
                (0..=n).map(move |i| {
                    let angle = std::f64::consts::TAU * f64::from(i) / f64::from(n);
                    let radius = 1.0 + 0.1 * (7.0 * angle).sin() * (f64::from(j) * 0.9).cos();
                    DVec3::new(
                        radius * angle.cos(),
                        radius * angle.sin(),
                        4.0 * f64::from(j) / f64::from(n),
                    )
                })
            })
            .collect();
        let indices = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| {
                    let k = j * (n + 1) + i;
                    [k, k + 1, k + n + 2, k, k + n + 2, k + n + 1]
                })
            })
            .collect();
        (positions, indices)
    }

    /// A review's finding: an object whose transform has no inverse (a box
    /// scaled to no height, which the GPU draws as a square) was never hit.
    #[test]
    fn an_object_whose_transform_flattens_it_is_met_where_the_gpu_draws_it() {
        let mut soup = crate::scene::TriangleSoup::default();
        crate::scene::builtin::shapes::cuboid(&mut soup, DVec3::ZERO, DVec3::ONE);
        let mut builder = crate::scene::SceneBuilder::new("test".into(), 1 << 20);
        let group = builder.add_mesh("box", &soup.positions, &soup.indices).unwrap();
        let floor =
            DAffine3::from_translation(DVec3::new(0.0, 2.0, 0.0)) * DAffine3::from_scale(DVec3::new(4.0, 0.0, 4.0));
        builder.add_object("floor", &group, floor).unwrap();
        let scene = builder.finish().unwrap();
        let caster = RayCaster::new(&scene);
        let hit = caster.first_hit(DVec3::new(1.0, 7.0, 3.0), DVec3::NEG_Y, 10.0);
        assert_eq!(hit.map(|h| h.t), Some(5.0));
        assert_eq!(caster.first_hit(DVec3::new(5.0, 7.0, 3.0), DVec3::NEG_Y, 10.0), None);
        assert_eq!(caster.nearest_distance(DVec3::new(1.0, 3.0, 1.0), 10.0), Some(1.0));
    }

    #[test]
    fn a_spent_budget_or_a_listener_that_breaks_stops_every_search() {
        let (positions, indices) = tube(48);
        let mut builder = crate::scene::SceneBuilder::new("test".into(), 1 << 20);
        let group = builder.add_mesh("tube", &positions, &indices).unwrap();
        builder.add_object("tube", &group, DAffine3::IDENTITY).unwrap();
        let scene = builder.finish().unwrap();
        let (origin, across) = (DVec3::new(-5.0, 0.0, 2.0), DVec3::X);
        let unlimited = RayCaster::new(&scene);
        assert!(unlimited.first_hit(origin, across, 10.0).is_some());
        let per_ray = unlimited.tests();
        assert!(per_ray > 0);

        let told = Cell::new(0);
        let budget = Budget {
            tests: 10 * per_ray,
            listener: Box::new(|spent, tests| {
                told.set(told.get() + 1);
                assert!(spent <= tests + 1, "told once the budget is passed");
                ControlFlow::Continue(())
            }),
        };
        let limited = RayCaster::with_budget(&scene, budget);
        let rays = (0..100)
            .take_while(|_| limited.first_hit(origin, across, 10.0).is_some())
            .count();
        assert_eq!(rays, 10, "the eleventh ray passes the budget");
        assert_eq!(limited.searching(), Err(Stopped::Spent));
        assert!(
            limited.first_hit(origin, across, 10.0).is_none(),
            "nothing found once spent"
        );
        assert_eq!(told.get(), 1);

        let listening = Budget {
            tests: u64::MAX,
            listener: Box::new(|_, _| ControlFlow::Break(())),
        };
        let stopped = RayCaster::with_budget(&scene, listening);
        let mut cast = 0;
        while stopped.searching().is_ok() {
            stopped.first_hit(origin, across, 10.0);
            cast += 1;
        }
        assert_eq!(stopped.searching(), Err(Stopped::Interrupted));
        assert_eq!(
            cast as u64,
            Budget::TELL_EVERY.div_ceil(per_ray),
            "stopped when first told"
        );
    }

    #[test]
    fn mesh_trees_find_what_every_triangle_tried_in_turn_finds_under_any_transform() {
        let (positions, indices) = tube(48);
        let mut builder = crate::scene::SceneBuilder::new("test".into(), 1 << 20);
        let group = builder.add_mesh("tube", &positions, &indices).unwrap();
        // Scaled unevenly and turned, so local and world distances differ.
        let transform = DAffine3::from_scale_rotation_translation(
            DVec3::new(3.0, 0.5, 1.5),
            glam::DQuat::from_rotation_y(0.7) * glam::DQuat::from_rotation_x(-0.3),
            DVec3::new(10.0, -5.0, 3.0),
        );
        builder.add_object("tube", &group, transform).unwrap();
        let scene = builder.finish().unwrap();
        assert_eq!(scene.objects.len(), 1, "one mesh, so its tree does the work");
        let object = &scene.objects[0];
        let caster = RayCaster::new(&scene);
        let world: Vec<[DVec3; 3]> = caster
            .triangles(object.mesh)
            .map(|corners| corners.map(|v| object.transform.transform_point3(v)))
            .collect();
        assert_eq!(world.len(), 2 * 48 * 48);
        let mut rng = crate::rng::Rng::new(99);
        let mut random = || rng.range(0.0, 1.0);
        let (mut hits, mut all) = (0, Vec::new());
        for _ in 0..300 {
            let origin = object.bounds.center() + DVec3::new(random() - 0.5, random() - 0.5, random() - 0.5) * 12.0;
            let target = object.bounds.center() + DVec3::new(random() - 0.5, random() - 0.5, random() - 0.5) * 4.0;
            let direction = target - origin;
            let mut expected: Vec<f64> = world
                .iter()
                .filter_map(|&[a, b, c]| intersect(origin, direction, a, b, c).filter(|&t| t > 0.0 && t <= 2.0))
                .collect();
            expected.sort_by(f64::total_cmp);
            caster.all_hits(origin, direction, 2.0, &mut all);
            let found: Vec<f64> = all.iter().map(|h| h.t).collect();
            assert_eq!(found.len(), expected.len(), "{origin} {direction}");
            for (f, e) in found.iter().zip(&expected) {
                assert!((f - e).abs() < 1e-9, "{origin} {direction}: {f} vs {e}");
            }
            let first = caster.first_hit(origin, direction, 2.0).map(|h| h.t);
            assert_eq!(first.is_some(), !expected.is_empty());
            hits += usize::from(first.is_some());
            let nearest = world
                .iter()
                .map(|&[a, b, c]| closest_point(origin, a, b, c).distance(origin))
                .fold(f64::INFINITY, f64::min);
            let found = caster.nearest_distance(origin, f64::INFINITY).unwrap();
            assert!((found - nearest).abs() < 1e-9, "{origin}: {found} vs {nearest}");
        }
        assert!(hits > 100, "the rays meet the tube ({hits} of 300)");
    }
}
