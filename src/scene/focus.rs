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
//!
//! Then, where a ground was exported in one mesh with what stands on it
//! (merged exports and scans give such models), the same rule weighs the
//! parts that stay in pieces: a part at least half as wide as the box,
//! its largest triangles apart from the rest of it where each is at least
//! twice as wide as that rest, the rest fits a box half as wide, and they
//! rise no higher than the rest (a ground and a sea under the model; a
//! hall's roof and walls over its furniture stay, and so does a sky box
//! with the ground in its mesh).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;

use crate::bounds::Aabb;

use super::model::Scene;

/// The most pieces left out: a ground, a sea, a sky, a backdrop.
pub const MAX_LEFT_OUT: usize = 4;

/// What is left must be at most this share of the box's diagonal.
const SHRINK: f64 = 0.5;

/// Pieces left out hold at most this share of the rest's triangles per
/// unit of surface.
const EMPTIER: f64 = 0.1;

/// The most triangles split off one part ([`largest_triangles`]): a ground
/// or a sea of a few quads, not a terrain of fine ones (which is as dense
/// as what stands on it, and stays).
const MOST_SPLIT_OFF: usize = 4096;

/// The box of a scene's detail, and what was left out of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Focus {
    pub bounds: Aabb,
    /// What was left out (huge and nearly empty): whole parts, largest
    /// first; then, largest first, parts' largest triangles and what is
    /// left of such parts.
    pub left_out: Vec<LeftOut>,
}

/// A piece of the model the focus left out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeftOut {
    /// A part (or all of it but its largest triangles, where those were
    /// weighed apart).
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
        let mut objects = vec![Vec::new(); scene.parts.len()];
        for (o, object) in scene.objects.iter().enumerate() {
            objects[object.part as usize].push(o as u32);
        }
        let parts: Vec<Piece> = (0..)
            .zip(&objects)
            .map(|(part, objects)| Piece {
                bounds: objects
                    .iter()
                    .fold(Aabb::EMPTY, |b, &o| b.union(scene.objects[o as usize].bounds)),
                triangles: scene.triangles_of(objects),
                what: LeftOut::Part(part),
            })
            .collect();
        let mut focus = Focus::without_the_emptiest(parts.clone(), MAX_LEFT_OUT);
        let most = MAX_LEFT_OUT - focus.left_out.len();
        if most == 0 {
            return focus;
        }
        // The parts that stay, each in two pieces where its largest
        // triangles are weighed apart.
        let wide = SHRINK * diagonal(&focus.bounds);
        let up = scene.up.axis.vector();
        let mut split = false;
        let mut pieces = Vec::with_capacity(parts.len());
        for (part, piece) in (0..).zip(parts) {
            if focus.left_out.contains(&piece.what) {
                continue;
            }
            let split_off = match diagonal(&piece.bounds) >= wide {
                true => largest_triangles(scene, &objects[part as usize], up),
                false => None,
            };
            match split_off {
                Some(Split { largest, count, rest }) => {
                    split = true;
                    pieces.push(Piece {
                        bounds: largest,
                        triangles: u64::from(count),
                        what: LeftOut::Triangles { part, count },
                    });
                    pieces.push(Piece {
                        bounds: rest,
                        triangles: piece.triangles - u64::from(count),
                        ..piece
                    });
                }
                None => pieces.push(piece),
            }
        }
        if split {
            let within = Focus::without_the_emptiest(pieces, most);
            if !within.left_out.is_empty() {
                focus.bounds = within.bounds;
                focus.left_out.extend(within.left_out);
            }
        }
        focus
    }

    /// The box of `pieces` without at most `most` of the largest, where
    /// they are huge and nearly empty (the module says which those are).
    fn without_the_emptiest(mut pieces: Vec<Piece>, most: usize) -> Focus {
        pieces.sort_by(|a, b| diagonal(&b.bounds).total_cmp(&diagonal(&a.bounds)));
        // What is left once the `k` largest are out: its box and triangles.
        let mut left = vec![(Aabb::EMPTY, 0u64); pieces.len() + 1];
        for k in (0..pieces.len()).rev() {
            left[k] = (
                left[k + 1].0.union(pieces[k].bounds),
                left[k + 1].1 + pieces[k].triangles,
            );
        }
        let density =
            |(bounds, triangles): (Aabb, u64)| triangles as f64 / bounds.surface_area().max(f64::MIN_POSITIVE);
        let mut out = 0;
        'search: while out < most {
            for k in out + 1..=most.min(pieces.len().saturating_sub(1)) {
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

    /// The focus with `part`, which it left out whole, taken back (a
    /// room's shell that the rest stands in: camera/generate.rs).
    pub fn taking_back(&self, scene: &Scene, part: u32) -> Focus {
        Focus {
            bounds: (scene.objects.iter())
                .filter(|o| o.part == part)
                .fold(self.bounds, |b, o| b.union(o.bounds)),
            left_out: self
                .left_out
                .iter()
                .copied()
                .filter(|&w| w != LeftOut::Part(part))
                .collect(),
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

/// A part's largest triangles split off it: their box and count, and the
/// box of the rest of it.
struct Split {
    largest: Aabb,
    count: u32,
    rest: Aabb,
}

/// The most of the largest triangles (by their box's diagonal, at most
/// [`MOST_SPLIT_OFF`]) of the part made of `objects` without which the
/// rest of it fits a box at most [`SHRINK`] as wide, each of them at least
/// twice as wide as that rest, and rising no higher along `up` than the
/// rest (the most: a ground and a sea together); `None` where there are no
/// such. The rest's box is its triangles' as drawn (their corners stored
/// in `f32`), which may lie an `f32` rounding inside or outside the
/// part's box.
fn largest_triangles(scene: &Scene, objects: &[u32], up: DVec3) -> Option<Split> {
    // The largest triangles' boxes, in `boxes`, ranked by a heap whose top
    // is the least of them (of equals, the later triangle, so a split is
    // the same every run); and the box of all the others. Diagonals are
    // finite and not negative, so their bits order them.
    let mut boxes = Vec::new();
    let mut heap = BinaryHeap::new();
    let mut others = Aabb::EMPTY;
    for &o in objects {
        let object = &scene.objects[o as usize];
        for t in 0..object.triangles {
            let corners = scene
                .triangle(object.mesh, t)
                .map(|c| object.transform.transform_point3(c));
            let bounds = Aabb::from_points(corners);
            let rank = (Reverse(diagonal(&bounds).to_bits()), (o, t));
            if heap.len() < MOST_SPLIT_OFF {
                heap.push((rank, boxes.len()));
                boxes.push(bounds);
                continue;
            }
            match heap.peek_mut() {
                Some(mut least) if rank < least.0 => {
                    let slot = least.1;
                    others = others.union(boxes[slot]);
                    boxes[slot] = bounds;
                    *least = (rank, slot);
                }
                _ => others = others.union(bounds),
            }
        }
    }
    // Largest first.
    let ranked: Vec<Aabb> = heap
        .into_sorted_vec()
        .into_iter()
        .map(|(_, slot)| boxes[slot])
        .collect();
    // The box of what is left without the `k` largest, and of those `k`,
    // for each k.
    let mut rest = vec![others; ranked.len() + 1];
    for k in (0..ranked.len()).rev() {
        rest[k] = rest[k + 1].union(ranked[k]);
    }
    let mut split_off = vec![Aabb::EMPTY; ranked.len() + 1];
    for k in 0..ranked.len() {
        split_off[k + 1] = split_off[k].union(ranked[k]);
    }
    let top = |b: &Aabb| b.span_along(up).1;
    // Each of them at least twice as wide as the rest, as a piece left
    // out must be (not most of a part of like triangles).
    let count = (1..=ranked.len()).rev().find(|&k| {
        let left = diagonal(&rest[k]);
        !rest[k].is_empty()
            && left <= SHRINK * diagonal(&rest[0])
            && SHRINK * diagonal(&ranked[k - 1]) >= left
            && top(&split_off[k]) <= top(&rest[k])
    })?;
    Some(Split {
        largest: split_off[count],
        count: count as u32,
        rest: rest[count],
    })
}

/// The length of a box's diagonal.
fn diagonal(b: &Aabb) -> f64 {
    b.extent().length()
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
        let parts: Vec<_> = boxes
            .iter()
            .map(|&(name, min, max, cuts)| (name, vec![(min, max, cuts)]))
            .collect();
        meshes(1 << 20, &parts)
    }

    /// [`boxes`] as one mesh named `name`, as a merged export gives a
    /// model, cut into clusters of 64 triangles, as loading cuts a large
    /// one.
    pub fn one_mesh(name: &str, boxes: &[(&str, DVec3, DVec3, u32)]) -> Scene {
        let all = boxes.iter().map(|&(_, min, max, cuts)| (min, max, cuts)).collect();
        meshes(64, &[(name, all)])
    }

    /// A box `(min, max, cuts)` as [`boxes`] makes it.
    pub type Cuboids = (DVec3, DVec3, u32);

    /// A scene of meshes, each a part of its own made of its boxes, cut
    /// into clusters of at most `cluster_triangles`.
    pub fn meshes(cluster_triangles: u32, meshes: &[(&str, Vec<Cuboids>)]) -> Scene {
        let mut builder = SceneBuilder::new("test".into(), cluster_triangles);
        for (name, boxes) in meshes {
            let mut soup = TriangleSoup::default();
            for &(min, max, cuts) in boxes {
                let step = (max - min) / f64::from(cuts);
                for i in 0..cuts {
                    for k in 0..cuts {
                        let corner = min + step * DVec3::new(f64::from(i), 0.0, f64::from(k));
                        let far = corner + step * DVec3::new(1.0, f64::from(cuts), 1.0);
                        cuboid(&mut soup, corner, far);
                    }
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

    use crate::bounds::Aabb;

    use super::fixtures::{ROOM, boxes as scene, ground, meshes, one_mesh, room};
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
        // (Its box is the triangles' as drawn, corners stored in f32.)
        let framed = |focus: &Focus, frame: Aabb| {
            let off = (focus.bounds.min - frame.min)
                .abs()
                .max((focus.bounds.max - frame.max).abs());
            assert!(off.max_element() < 1e-6, "{:?}", focus.bounds);
        };
        let focus = Focus::of(&s);
        framed(&focus, ROOM);
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
        // With a pond on the ground too, both go, as they would as parts.
        let pond = ("pond", DVec3::new(-25.0, -0.3, -25.0), DVec3::new(35.0, -0.2, 35.0), 1);
        let focus = Focus::of(&one_mesh("model", &[boxes.clone(), vec![pond]].concat()));
        framed(&focus, ROOM);
        assert_eq!(focus.left_out, [LeftOut::Triangles { part: 0, count: 24 }]);
        // More triangles than are ranked, the first and least of them
        // specks beside the room that the later ones push out of the
        // ranking: they still frame it.
        let specks = ("specks", DVec3::new(-3.0, 0.0, 5.0), DVec3::new(-2.5, 0.1, 5.5), 4);
        let clutter = ("clutter", DVec3::new(0.0, 0.0, 5.0), DVec3::new(10.0, 0.5, 7.0), 20);
        let focus = Focus::of(&one_mesh("model", &[vec![specks, clutter], boxes.clone()].concat()));
        framed(&focus, Aabb::new(DVec3::new(-3.0, 0.0, 0.0), ROOM.max));
        assert_eq!(focus.left_out, [LeftOut::Triangles { part: 0, count: 12 }]);
        // A terrain as dense as the room stays, in one mesh as apart.
        boxes.last_mut().unwrap().3 = 60;
        assert_eq!(Focus::of(&one_mesh("model", &boxes)).bounds.extent().x, 220.0);
        // A plane a little wider than the room does not halve the box.
        let mut boxes = room();
        boxes.push(("ground", DVec3::new(-2.0, -0.1, -2.0), DVec3::new(12.0, 0.0, 9.0), 1));
        assert_eq!(Focus::of(&one_mesh("model", &boxes)).left_out, []);
    }

    #[test]
    fn a_part_left_out_whole_stays_out_whole_and_a_hall_over_its_furniture_stays() {
        // A sky box with a sun in it, and a ground with a drain in a
        // corner: each left out whole, as it would be without them.
        let sky = (DVec3::splat(-500.0), DVec3::splat(500.0), 2);
        let sun = (DVec3::new(0.0, 480.0, 0.0), DVec3::new(40.0, 490.0, 40.0), 1);
        let (_, ground_min, ground_max, cuts) = ground();
        let drain = (DVec3::new(100.0, -1.0, 100.0), DVec3::new(101.0, 0.0, 101.0), 1);
        let mut parts: Vec<_> = room()
            .into_iter()
            .map(|(name, min, max, cuts)| (name, vec![(min, max, cuts)]))
            .collect();
        parts.push(("sky", vec![sky, sun]));
        parts.push(("ground", vec![(ground_min, ground_max, cuts), drain]));
        let focus = Focus::of(&meshes(1 << 20, &parts));
        assert_eq!(focus.bounds, ROOM);
        assert_eq!(focus.left_out, [LeftOut::Part(3), LeftOut::Part(4)]);
        // A hall of 12 triangles 60 × 12 × 40 over furniture gathered in
        // its middle, in one mesh: its walls and roof rise over the
        // furniture, so they are no ground, and it is framed whole.
        let hall = ("hall", DVec3::ZERO, DVec3::new(60.0, 12.0, 40.0), 1);
        let chairs = (1..=4).map(|k| {
            let at = DVec3::new(24.0 + 2.0 * f64::from(k), 0.0, 18.0);
            ("chair", at, at + DVec3::new(0.6, 0.8, 0.6), 1)
        });
        let hall = one_mesh("model", &std::iter::once(hall).chain(chairs).collect::<Vec<_>>());
        assert_eq!(Focus::of(&hall).left_out, []);
    }
}
