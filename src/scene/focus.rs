//! The part of a model that holds its detail: the box that orbits,
//! flyovers, the overview picture and a planned walk's grid frame. A ground
//! plane 20 times wider than the room standing on it, or a sky dome around
//! a town, makes the raw bounds many times larger than anything there is to
//! see, and a path framing them shows a speck.
//!
//! The model is weighed in pieces by their triangles: its parts (meshes as
//! placed), each with its few largest triangles split off where the rest
//! of the part fits a box at most half as wide without them (a ground quad
//! exported in one mesh with the house on it, as merged exports and scans
//! give). The largest pieces are left out when they are huge and nearly
//! empty: without them the rest fits a box at most half as wide (its
//! diagonal), and each of them is at least twice as wide as that rest and
//! holds at most a tenth as many triangles per unit of its box's surface.
//! A few at most ([`MAX_LEFT_OUT`]), largest first, a group of equals
//! together (ground and water of one size), each judged against what is
//! left.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::bounds::Aabb;

use super::model::Scene;

/// The most pieces left out: a ground, a sea, a sky, a backdrop.
pub const MAX_LEFT_OUT: usize = 4;

/// What is left must be at most this share of the box's diagonal.
const SHRINK: f64 = 0.5;

/// Pieces left out hold at most this share of the rest's triangles per
/// unit of surface.
const EMPTIER: f64 = 0.1;

/// The most triangles split off one part ([`largest_triangles`]): a ground,
/// a sea or a sky of a few hundred quads, not a terrain of fine ones (which
/// is as dense as what stands on it, and stays).
const MOST_SPLIT_OFF: usize = 4096;

/// The box of a scene's detail, and what was left out of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Focus {
    pub bounds: Aabb,
    /// What was left out (huge and nearly empty), largest first.
    pub left_out: Vec<LeftOut>,
}

/// A piece of the model the focus left out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeftOut {
    /// A whole part (or all of it but the triangles split off it).
    Part(u32),
    /// The `count` largest triangles of a part.
    Triangles { part: u32, count: u32 },
}

/// A piece weighed for the focus: its box, its triangles, and what it is.
#[derive(Clone, Copy)]
struct Piece {
    bounds: Aabb,
    triangles: u64,
    what: LeftOut,
}

impl Focus {
    /// The focus of `scene`: its bounds without its huge, nearly empty
    /// pieces (the module says which those are).
    pub fn of(scene: &Scene) -> Focus {
        let mut pieces = pieces(scene);
        let size = |p: &Piece| p.bounds.extent().length();
        pieces.sort_by(|a, b| size(b).total_cmp(&size(a)));
        // What is left once the `k` largest are out: its box and triangles.
        let mut left = vec![(Aabb::EMPTY, 0u64); pieces.len() + 1];
        for k in (0..pieces.len()).rev() {
            left[k] = (
                left[k + 1].0.union(pieces[k].bounds),
                left[k + 1].1 + pieces[k].triangles,
            );
        }
        let diagonal = |b: &Aabb| b.extent().length();
        let density =
            |(bounds, triangles): (Aabb, u64)| triangles as f64 / bounds.surface_area().max(f64::MIN_POSITIVE);
        let mut out = 0;
        'search: while out < MAX_LEFT_OUT {
            for k in out + 1..=MAX_LEFT_OUT.min(pieces.len().saturating_sub(1)) {
                let rest = left[k];
                let shrinks = diagonal(&rest.0) <= SHRINK * diagonal(&left[out].0);
                let empty = |piece: &Piece| {
                    SHRINK * diagonal(&piece.bounds) >= diagonal(&rest.0)
                        && density((piece.bounds, piece.triangles)) <= EMPTIER * density(rest)
                };
                if shrinks && pieces[out..k].iter().all(empty) {
                    out = k;
                    continue 'search;
                }
            }
            break;
        }
        Focus {
            bounds: left[out].0,
            left_out: pieces[..out].iter().map(|p| p.what).collect(),
        }
    }

    /// What the focus leaves out, for a path's reason; `None` when nothing.
    pub fn note(&self, scene: &Scene) -> Option<String> {
        if self.left_out.is_empty() {
            return None;
        }
        let name = |part: u32| &scene.parts[part as usize].name;
        let names: Vec<String> = self
            .left_out
            .iter()
            .map(|&what| match what {
                LeftOut::Part(part) => format!("'{}'", name(part)),
                LeftOut::Triangles { part, count: 1 } => format!("the largest triangle of '{}'", name(part)),
                LeftOut::Triangles { part, count } => format!("the {count} largest triangles of '{}'", name(part)),
            })
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

/// The pieces [`Focus::of`] weighs: each part, or its largest triangles
/// and the rest of it where [`largest_triangles`] splits them off.
fn pieces(scene: &Scene) -> Vec<Piece> {
    let mut objects = vec![Vec::new(); scene.parts.len()];
    for (o, object) in scene.objects.iter().enumerate() {
        objects[object.part as usize].push(o as u32);
    }
    let mut pieces = Vec::with_capacity(scene.parts.len());
    for (part, objects) in (0..).zip(&objects) {
        let bounds = objects
            .iter()
            .fold(Aabb::EMPTY, |b, &o| b.union(scene.objects[o as usize].bounds));
        let triangles: u64 = objects
            .iter()
            .map(|&o| u64::from(scene.objects[o as usize].triangles))
            .sum();
        match largest_triangles(scene, objects) {
            Some(Split { largest, count, rest }) => {
                pieces.push(Piece {
                    bounds: largest,
                    triangles: u64::from(count),
                    what: LeftOut::Triangles { part, count },
                });
                pieces.push(Piece {
                    bounds: rest,
                    triangles: triangles - u64::from(count),
                    what: LeftOut::Part(part),
                });
            }
            None => pieces.push(Piece {
                bounds,
                triangles,
                what: LeftOut::Part(part),
            }),
        }
    }
    pieces
}

/// A part's largest triangles split off it: their box and count, and the
/// box of the rest of it.
struct Split {
    largest: Aabb,
    count: u32,
    rest: Aabb,
}

/// The fewest of the largest triangles (by their box's diagonal, at most
/// [`MOST_SPLIT_OFF`]) of the part made of `objects` without which the
/// rest of it fits a box at most [`SHRINK`] as wide, each of them at least
/// twice as wide as that rest; `None` where there are no such few. The
/// rest's box is its triangles' as drawn (their corners stored in `f32`),
/// which may lie an `f32` rounding inside or outside the part's box.
fn largest_triangles(scene: &Scene, objects: &[u32]) -> Option<Split> {
    let triangles = || {
        objects.iter().flat_map(|&o| {
            let object = &scene.objects[o as usize];
            (0..object.triangles).map(move |t| {
                let corners = scene
                    .triangle(object.mesh, t)
                    .map(|c| object.transform.transform_point3(c));
                ((o, t), Aabb::from_points(corners))
            })
        })
    };
    // Diagonals are finite and not negative, so their bits order them.
    let size = |b: &Aabb| b.extent().length().to_bits();
    // The largest, in a heap whose top is the least of them; of equals,
    // the first triangles (so a split is the same every run). And the
    // largest of the others.
    let mut heap = BinaryHeap::new();
    let mut largest_other = None;
    for (key, bounds) in triangles() {
        let mut entry = (Reverse(size(&bounds)), key);
        if heap.len() == MOST_SPLIT_OFF {
            match heap.peek_mut() {
                Some(mut least) if entry < *least => entry = std::mem::replace(&mut *least, entry),
                _ => {}
            }
            largest_other = largest_other.max(Some(entry.0.0));
        } else {
            heap.push(entry);
        }
    }
    // Largest first.
    let largest = heap.into_sorted_vec();
    let diagonal = |b: &Aabb| b.extent().length();
    // The `k` largest may be split off only where the k-th is at least
    // twice as wide as the next (which the rest holds): most meshes'
    // triangles have no such gap, and need no second pass.
    let sizes: Vec<f64> = largest.iter().map(|(Reverse(bits), _)| f64::from_bits(*bits)).collect();
    let next = |k: usize| sizes.get(k).copied().or(largest_other.map(f64::from_bits));
    let gaps: Vec<usize> = (1..=largest.len())
        .filter(|&k| next(k).is_some_and(|next| SHRINK * sizes[k - 1] >= next))
        .collect();
    let &(Reverse(least_kept), _) = largest.last().filter(|_| !gaps.is_empty())?;
    let mut by_triangle: Vec<((u32, u32), usize)> = largest.iter().enumerate().map(|(k, &(_, key))| (key, k)).collect();
    by_triangle.sort_unstable();
    // Their boxes, and the box of the others.
    let mut boxes = vec![Aabb::EMPTY; largest.len()];
    let mut others = Aabb::EMPTY;
    for (key, bounds) in triangles() {
        let found = match size(&bounds) < least_kept {
            true => None,
            false => by_triangle.binary_search_by_key(&key, |&(key, _)| key).ok(),
        };
        match found {
            Some(at) => boxes[by_triangle[at].1] = bounds,
            None => others = others.union(bounds),
        }
    }
    // What is left without the `k` largest, for each k.
    let mut rest = vec![others; largest.len() + 1];
    for k in (0..largest.len()).rev() {
        rest[k] = rest[k + 1].union(boxes[k]);
    }
    // Each of them at least twice as wide as the rest, as a piece left
    // out must be (not most of a part of like triangles).
    let count = gaps.into_iter().find(|&k| {
        let left = diagonal(&rest[k]);
        left <= SHRINK * diagonal(&rest[0]) && SHRINK * diagonal(&boxes[k - 1]) >= left
    })?;
    Some(Split {
        largest: boxes[..count].iter().fold(Aabb::EMPTY, |b, &bounds| b.union(bounds)),
        count: count as u32,
        rest: rest[count],
    })
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
            add_box(&mut soup, min, max, cuts);
            let group = builder.add_mesh(name, &soup.positions, &soup.indices).unwrap();
            builder.add_object(name, &group, DAffine3::IDENTITY).unwrap();
        }
        builder.finish().unwrap()
    }

    /// [`boxes`] as one mesh named `name`, as a merged export gives a
    /// model, cut into clusters of 64 triangles, as loading cuts a large
    /// one.
    pub fn one_mesh(name: &str, boxes: &[(&str, DVec3, DVec3, u32)]) -> Scene {
        let mut builder = SceneBuilder::new("test".into(), 64);
        let mut soup = TriangleSoup::default();
        for &(_, min, max, cuts) in boxes {
            add_box(&mut soup, min, max, cuts);
        }
        let group = builder.add_mesh(name, &soup.positions, &soup.indices).unwrap();
        builder.add_object(name, &group, DAffine3::IDENTITY).unwrap();
        builder.finish().unwrap()
    }

    /// The box from `min` to `max` as `cuts`² boxes side by side.
    fn add_box(soup: &mut TriangleSoup, min: DVec3, max: DVec3, cuts: u32) {
        let step = (max - min) / f64::from(cuts);
        for i in 0..cuts {
            for k in 0..cuts {
                let corner = min + step * DVec3::new(f64::from(i), 0.0, f64::from(k));
                let far = corner + step * DVec3::new(1.0, f64::from(cuts), 1.0);
                cuboid(soup, corner, far);
            }
        }
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

    use super::fixtures::{ROOM, boxes as scene, ground, one_mesh, room};
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
            .map(|&what| match what {
                LeftOut::Part(p) => s.parts[p as usize].name.as_str(),
                LeftOut::Triangles { .. } => panic!("parts alone are huge: {what:?}"),
            })
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
        assert_eq!(Focus::of(&scene(&boxes)).left_out, []);
    }

    #[test]
    fn a_huge_ground_in_one_mesh_with_the_room_is_left_out_by_its_largest_triangles() {
        let mut boxes = room();
        boxes.push(ground());
        let s = one_mesh("model", &boxes);
        assert!(s.objects.len() > 1, "the mesh is cut into clusters");
        let focus = Focus::of(&s);
        // (Its box is the triangles' as drawn, corners stored in f32.)
        let off = (focus.bounds.min - ROOM.min)
            .abs()
            .max((focus.bounds.max - ROOM.max).abs());
        assert!(off.max_element() < 1e-6, "{:?}", focus.bounds);
        // The ground's box is 12 triangles, each as wide as the ground on
        // one axis at least.
        assert_eq!(focus.left_out, [LeftOut::Triangles { part: 0, count: 12 }]);
        assert!(
            focus
                .note(&s)
                .unwrap()
                .contains("without the 12 largest triangles of 'model'"),
            "{:?}",
            focus.note(&s)
        );
        // A terrain as dense as the room stays, in one mesh as apart.
        boxes.last_mut().unwrap().3 = 60;
        assert_eq!(Focus::of(&one_mesh("model", &boxes)).bounds.extent().x, 220.0);
        // A plane a little wider than the room does not halve the box.
        let mut boxes = room();
        boxes.push(("ground", DVec3::new(-2.0, -0.1, -2.0), DVec3::new(12.0, 0.0, 9.0), 1));
        assert_eq!(Focus::of(&one_mesh("model", &boxes)).left_out, []);
    }
}
