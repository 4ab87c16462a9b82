//! The part of a model that holds its detail: the box that orbits,
//! flyovers, the overview picture and a planned walk's grid frame. A ground
//! plane 20 times wider than the room standing on it, or a sky dome around
//! a town, makes the raw bounds many times larger than anything there is to
//! see, and a path framing them shows a speck.
//!
//! Parts (meshes as placed) are weighed by their triangles. The largest
//! parts are left out when they are huge and nearly empty: without them
//! the rest fits a box at most half as wide (its diagonal), and each of
//! them is at least twice as wide as that rest and holds at most a tenth as
//! many triangles per unit of its box's surface. A few at most
//! ([`MAX_LEFT_OUT`]), largest first, a group of equals together (ground
//! and water of one size), each judged against what is left.

use crate::bounds::Aabb;

use super::model::Scene;

/// The most parts left out: a ground, a sea, a sky, a backdrop.
pub const MAX_LEFT_OUT: usize = 4;

/// What is left must be at most this share of the box's diagonal.
const SHRINK: f64 = 0.5;

/// Parts left out hold at most this share of the rest's triangles per unit
/// of surface.
const EMPTIER: f64 = 0.1;

/// The box of a scene's detail, and the parts left out of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Focus {
    pub bounds: Aabb,
    /// The parts left out (huge and nearly empty), largest first.
    pub left_out: Vec<u32>,
}

impl Focus {
    /// The focus of `scene`: its bounds without its huge, nearly empty
    /// parts (the module says which those are).
    pub fn of(scene: &Scene) -> Focus {
        let mut parts = vec![(Aabb::EMPTY, 0u64); scene.parts.len()];
        for o in &scene.objects {
            let (bounds, triangles) = &mut parts[o.part as usize];
            *bounds = bounds.union(o.bounds);
            *triangles += u64::from(o.triangles);
        }
        let mut order: Vec<u32> = (0..parts.len() as u32).collect();
        let size = |p: &u32| parts[*p as usize].0.extent().length();
        order.sort_by(|a, b| size(b).total_cmp(&size(a)).then(a.cmp(b)));
        // What is left once the `k` largest are out: its box and triangles.
        let mut left = vec![(Aabb::EMPTY, 0u64); order.len() + 1];
        for k in (0..order.len()).rev() {
            let (bounds, triangles) = parts[order[k] as usize];
            left[k] = (left[k + 1].0.union(bounds), left[k + 1].1 + triangles);
        }
        let diagonal = |b: &Aabb| b.extent().length();
        let density =
            |(bounds, triangles): (Aabb, u64)| triangles as f64 / bounds.surface_area().max(f64::MIN_POSITIVE);
        let mut out = 0;
        'search: while out < MAX_LEFT_OUT {
            for k in out + 1..=MAX_LEFT_OUT.min(order.len() - 1) {
                let rest = left[k];
                let shrinks = diagonal(&rest.0) <= SHRINK * diagonal(&left[out].0);
                let empty = |&p: &u32| {
                    let part = parts[p as usize];
                    SHRINK * diagonal(&part.0) >= diagonal(&rest.0) && density(part) <= EMPTIER * density(rest)
                };
                if shrinks && order[out..k].iter().all(empty) {
                    out = k;
                    continue 'search;
                }
            }
            break;
        }
        Focus {
            bounds: left[out].0,
            left_out: order[..out].to_vec(),
        }
    }

    /// What the focus leaves out, for a path's reason; `None` when nothing.
    pub fn note(&self, scene: &Scene) -> Option<String> {
        if self.left_out.is_empty() {
            return None;
        }
        let names: Vec<String> = self
            .left_out
            .iter()
            .map(|&p| format!("'{}'", scene.parts[p as usize].name))
            .collect();
        let e = self.bounds.extent();
        Some(format!(
            "framing its detail ({:.3} × {:.3} × {:.3}) without {} (huge and nearly empty)",
            e.x,
            e.y,
            e.z,
            names.join(", ")
        ))
    }
}

/// Scenes of boxes for the tests of what frames a focus.
#[cfg(test)]
pub(crate) mod fixtures {
    use glam::{DAffine3, DVec3};

    use crate::bounds::Aabb;
    use crate::scene::builtin::shapes::cuboid;
    use crate::scene::{Scene, SceneBuilder, TriangleSoup};

    /// A scene of boxes `(name, min, max, cuts)`, each a part of its own,
    /// made of `cuts`² boxes side by side across the ground (more
    /// triangles, the same box), +Y up.
    pub fn boxes(boxes: &[(&str, DVec3, DVec3, u32)]) -> Scene {
        let mut builder = SceneBuilder::new("test".into(), 1 << 20);
        for &(name, min, max, cuts) in boxes {
            let mut soup = TriangleSoup::default();
            let step = (max - min) / f64::from(cuts);
            for i in 0..cuts {
                for k in 0..cuts {
                    let corner = min + step * DVec3::new(f64::from(i), 0.0, f64::from(k));
                    let far = corner + step * DVec3::new(1.0, f64::from(cuts), 1.0);
                    cuboid(&mut soup, corner, far);
                }
            }
            let group = builder.add_mesh(name, &soup.positions, &soup.indices).unwrap();
            builder.add_object(name, &group, DAffine3::IDENTITY).unwrap();
        }
        builder.finish().unwrap()
    }

    /// A room's pieces, 10 × 3 × 7 in all ([`ROOM`]).
    pub fn room() -> Vec<(&'static str, DVec3, DVec3, u32)> {
        vec![
            ("table", DVec3::new(2.0, 0.0, 2.0), DVec3::new(4.0, 1.0, 3.0), 3),
            ("wall", DVec3::new(0.0, 0.0, 0.0), DVec3::new(10.0, 3.0, 0.2), 3),
            ("chair", DVec3::new(6.0, 0.0, 6.0), DVec3::new(7.0, 1.5, 7.0), 3),
        ]
    }

    /// The box of [`room`].
    pub const ROOM: Aabb = Aabb {
        min: DVec3::ZERO,
        max: DVec3::new(10.0, 3.0, 7.0),
    };

    /// A flat ground of two triangles a face, 220 across, under [`room`].
    pub fn ground() -> (&'static str, DVec3, DVec3, u32) {
        (
            "ground",
            DVec3::new(-105.0, -0.1, -105.0),
            DVec3::new(115.0, 0.0, 115.0),
            1,
        )
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::fixtures::{ROOM, boxes as scene, ground, room};
    use super::*;

    #[test]
    fn a_huge_ground_and_sky_are_left_out_and_what_holds_the_triangles_stays() {
        let mut boxes = room();
        assert_eq!(Focus::of(&scene(&boxes)).bounds, ROOM, "nothing to leave out");
        boxes.push(ground());
        boxes.push(("sky", DVec3::splat(-500.0), DVec3::splat(500.0), 2));
        let s = scene(&boxes);
        let focus = Focus::of(&s);
        assert_eq!(focus.bounds, ROOM);
        let names: Vec<&str> = focus
            .left_out
            .iter()
            .map(|&p| s.parts[p as usize].name.as_str())
            .collect();
        assert_eq!(names, ["sky", "ground"]);
        assert!(focus.note(&s).unwrap().contains("without 'sky', 'ground'"));

        // A ground as dense as the room is part of the model (a terrain).
        boxes.pop();
        boxes.last_mut().unwrap().3 = 60;
        assert_eq!(Focus::of(&scene(&boxes)).bounds.extent().x, 220.0);
        // Ground and water of one size go together.
        let mut boxes = room();
        boxes.push(ground());
        boxes.push((
            "water",
            DVec3::new(-105.0, -0.3, -105.0),
            DVec3::new(115.0, -0.2, 115.0),
            1,
        ));
        assert_eq!(Focus::of(&scene(&boxes)).bounds, ROOM);
        // A plane a little wider than the room does not halve the box.
        let mut boxes = room();
        boxes.push(("ground", DVec3::new(-2.0, -0.1, -2.0), DVec3::new(12.0, 0.0, 9.0), 1));
        assert_eq!(Focus::of(&scene(&boxes)).left_out, Vec::<u32>::new());
    }
}
