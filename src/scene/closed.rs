//! Whether a mesh is a closed solid, judged on the mesh as loaded, before
//! it is cut into clusters (a cluster of a closed mesh is open).
//!
//! In time proportional to the mesh. Edges are matched by vertex id first,
//! each filed under its lower end (a counting sort), which leaves each
//! vertex a handful of edges to compare, shared over the cores. Only the
//! edges left unmatched (none in a closed mesh whose corners are shared;
//! the rim of an open one) have their ends welded by position, through a
//! hash map (foldhash, not the standard SipHash), and are matched again.

use std::collections::HashMap;

use glam::DVec3;

use crate::bounds::Aabb;
use crate::parallel;

/// Whether the triangles `indices` over `positions` form a closed solid:
/// welded by position, every edge is walked once in each direction
/// (watertight and consistently wound), and they enclose a volume (a
/// surface stored twice, once per side, encloses none). A line then crosses
/// the surface an even number of times, and an odd count means "inside".
pub fn is_closed(positions: &[DVec3], indices: &[u32]) -> bool {
    !indices.is_empty() && encloses_volume(positions, indices) && {
        let unmatched = unmatched_edges(positions.len(), indices);
        unmatched.is_empty() || cancel_once_welded(positions, &unmatched)
    }
}

/// An edge between two vertices, and how many more times the triangles
/// walk it from `lower` to `upper` than back.
#[derive(Clone, Copy, Debug)]
struct Unmatched {
    lower: u32,
    upper: u32,
    net: i64,
}

/// The edges of the triangles `indices` over `vertices` vertices that are
/// not walked as often one way as the other, by vertex id.
fn unmatched_edges(vertices: usize, indices: &[u32]) -> Vec<Unmatched> {
    // Each edge filed under its lower end, as its upper end and whether it
    // runs down: `start[v]..start[v + 1]` are the edges filed under `v`.
    let mut start = vec![0; vertices + 1];
    for t in indices.chunks_exact(3) {
        for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            start[u.min(v) as usize + 1] += 1;
        }
    }
    for v in 1..start.len() {
        start[v] += start[v - 1];
    }
    let mut filed = vec![0u64; indices.len()];
    let mut next = start.clone();
    for t in indices.chunks_exact(3) {
        for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let slot = &mut next[u.min(v) as usize];
            filed[*slot] = u64::from(u.max(v)) << 1 | u64::from(u > v);
            *slot += 1;
        }
    }

    // Vertices in ranges of about equal edge counts, one per part.
    let total = filed.len();
    let parts = parallel::parts_for(total, EDGES_PER_PART);
    let mut ranges = Vec::with_capacity(parts);
    let mut rest = filed.as_mut_slice();
    let mut lower = 0;
    for k in 1..=parts {
        let upper = if k == parts {
            vertices
        } else {
            start.partition_point(|&s| s * parts < total * k)
        };
        let (range, after) = std::mem::take(&mut rest).split_at_mut(start[upper] - start[lower]);
        ranges.push((lower..upper, range));
        (rest, lower) = (after, upper);
    }
    parallel::map(ranges, |(vertices, filed)| {
        let offset = start[vertices.start];
        let mut unmatched = Vec::new();
        for v in vertices {
            let edges = &mut filed[start[v] - offset..start[v + 1] - offset];
            edges.sort_unstable();
            for to_one_end in edges.chunk_by(|a, b| a >> 1 == b >> 1) {
                let down = to_one_end.iter().filter(|&&e| e & 1 == 1).count() as i64;
                let net = to_one_end.len() as i64 - 2 * down;
                if net != 0 {
                    let upper = (to_one_end[0] >> 1) as u32;
                    unmatched.push(Unmatched {
                        lower: v as u32,
                        upper,
                        net,
                    });
                }
            }
        }
        unmatched
    })
    .concat()
}

/// Edges per part of the matching below which a thread does not pay.
const EDGES_PER_PART: usize = 1 << 16;

/// Whether the `unmatched` edges cancel once vertices at the same position
/// (bit for bit) are one: the edges that matched by id match still.
fn cancel_once_welded(positions: &[DVec3], unmatched: &[Unmatched]) -> bool {
    let mut first = HashMap::with_capacity_and_hasher(2 * unmatched.len(), foldhash::fast::FixedState::default());
    let mut welded = |v: u32| {
        *first
            .entry(positions[v as usize].to_array().map(f64::to_bits))
            .or_insert(v)
    };
    let mut net = HashMap::with_capacity_and_hasher(unmatched.len(), foldhash::fast::FixedState::default());
    for e in unmatched {
        let (a, b) = (welded(e.lower), welded(e.upper));
        let (key, net_up) = if a < b { ((a, b), e.net) } else { ((b, a), -e.net) };
        *net.entry(key).or_insert(0) += net_up;
    }
    net.values().all(|&n| n == 0)
}

/// Whether no triangle has two corners at one point (which welding would
/// make an edge from a vertex to itself, walked one way only) and the
/// triangles enclose a volume of at least a hundredth of their bounding
/// box (the signed volumes of the tetrahedra they make with the origin,
/// summed in triangle order).
fn encloses_volume(positions: &[DVec3], indices: &[u32]) -> bool {
    let mut volume = 0.0;
    let mut bounds = Aabb::EMPTY;
    let same = |a: DVec3, b: DVec3| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits);
    for t in indices.chunks_exact(3) {
        let [p, q, r] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
        if same(p, q) || same(q, r) || same(r, p) {
            return false;
        }
        volume += p.dot(q.cross(r)) / 6.0;
        bounds = bounds.grown(p).grown(q).grown(r);
    }
    let e = bounds.extent();
    volume.abs() >= 0.01 * e.x * e.y * e.z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's corners and its 12 triangles, wound outward (the
    /// built-in scenes' box).
    fn cube() -> (Vec<DVec3>, Vec<u32>) {
        let mut soup = crate::scene::TriangleSoup::default();
        crate::scene::builtin::shapes::cuboid(&mut soup, DVec3::ZERO, DVec3::ONE);
        (soup.positions, soup.indices)
    }

    #[test]
    fn a_cube_is_closed_and_loses_it_with_a_face_a_flip_or_a_twin() {
        let (corners, indices) = cube();
        assert!(is_closed(&corners, &indices));
        assert!(!is_closed(&corners, &indices[6..]), "a face missing");
        let mut flipped = indices.clone();
        flipped.swap(0, 1);
        assert!(!is_closed(&corners, &flipped), "one triangle wound the other way");
        let twin: Vec<u32> = indices
            .iter()
            .copied()
            .chain(indices.chunks(3).flat_map(|t| [t[0], t[2], t[1]]))
            .collect();
        assert!(!is_closed(&corners, &twin), "both sides stored: no volume");
        // Corners stored once per face (as loaders do for normals) weld.
        let split: Vec<DVec3> = indices.iter().map(|&i| corners[i as usize]).collect();
        assert!(is_closed(&split, &(0..split.len() as u32).collect::<Vec<_>>()));
    }

    /// The definition, computed the plain way (every corner welded through
    /// a map, every welded edge's walks one way minus the other in a map),
    /// to hold the fast test against.
    fn closed_by_definition(positions: &[DVec3], indices: &[u32]) -> bool {
        let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
        let mut id = |v: u32| {
            let next = welded.len() as u32;
            *welded
                .entry(positions[v as usize].to_array().map(f64::to_bits))
                .or_insert(next)
        };
        let mut edges: HashMap<(u32, u32), i64> = HashMap::new();
        let mut volume = 0.0;
        let mut bounds = Aabb::EMPTY;
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [id(t[0]), id(t[1]), id(t[2])];
            for (u, v) in [(a, b), (b, c), (c, a)] {
                *edges.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
            }
            let [p, q, r] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            volume += p.dot(q.cross(r)) / 6.0;
            bounds = bounds.grown(p).grown(q).grown(r);
        }
        let e = bounds.extent();
        !edges.is_empty() && edges.values().all(|&n| n == 0) && volume.abs() >= 0.01 * e.x * e.y * e.z
    }

    /// A cube, a 9-sided cylinder, and two cubes side by side (their faces
    /// meet: corners at the same points, in different vertices).
    fn solids() -> Vec<(Vec<DVec3>, Vec<u32>)> {
        use crate::scene::builtin::shapes::{cuboid, cylinder};
        let mut soups = vec![crate::scene::TriangleSoup::default(); 3];
        cuboid(&mut soups[0], DVec3::ZERO, DVec3::ONE);
        cylinder(&mut soups[1], DVec3::ZERO, DVec3::Y, 1.0, 2.0, 9);
        cuboid(&mut soups[2], DVec3::ZERO, DVec3::ONE);
        cuboid(&mut soups[2], DVec3::X, DVec3::new(2.0, 1.0, 1.0));
        soups.into_iter().map(|s| (s.positions, s.indices)).collect()
    }

    #[test]
    fn agrees_with_the_definition_on_solids_with_corners_split_moved_flipped_dropped_or_doubled() {
        let mut rng = crate::rng::Rng::new(38);
        let mut verdicts = [0; 2];
        for case in 0..600 {
            let (mut positions, mut indices) = solids().swap_remove(case % 3);
            for _ in 0..rng.int(0, 3) {
                let slot = rng.int(0, indices.len() as u32 - 1) as usize;
                let first = slot - slot % 3;
                match rng.int(0, 7) {
                    // A corner given a vertex of its own at the same point
                    // (as a seam of normals or texture coordinates does).
                    0 | 1 => {
                        positions.push(positions[indices[slot] as usize]);
                        indices[slot] = positions.len() as u32 - 1;
                    }
                    // ... or a point a little off: a crack.
                    2 => {
                        positions.push(positions[indices[slot] as usize] + DVec3::splat(1e-9));
                        indices[slot] = positions.len() as u32 - 1;
                    }
                    // ... or the point of the next corner: the triangle
                    // collapses onto an edge.
                    3 => {
                        positions.push(positions[indices[first + (slot + 1) % 3] as usize]);
                        indices[slot] = positions.len() as u32 - 1;
                    }
                    // A vertex moved onto its neighbour: the triangles on
                    // their edge collapse, the edge still matched by id.
                    4 => positions[indices[slot] as usize] = positions[indices[first + (slot + 1) % 3] as usize],
                    5 => indices.swap(first, first + 1),
                    6 => drop(indices.drain(first..first + 3)),
                    _ => indices.extend_from_within(first..first + 3),
                }
                if indices.is_empty() {
                    break;
                }
            }
            let expected = closed_by_definition(&positions, &indices);
            assert_eq!(is_closed(&positions, &indices), expected, "case {case}: {indices:?}");
            verdicts[usize::from(expected)] += 1;
        }
        assert!(
            verdicts.iter().all(|&n| n > 100),
            "closed and open cases both tried: {verdicts:?}"
        );
    }

    #[test]
    fn a_large_solid_is_judged_in_parts_as_a_whole() {
        // 160 000 triangles: their edges are matched in several parts
        // wherever there are cores for them; the caps' centres have 40 000
        // edges each.
        let mut soup = crate::scene::TriangleSoup::default();
        crate::scene::builtin::shapes::cylinder(&mut soup, DVec3::ZERO, DVec3::Z, 1.0, 1.0, 40_000);
        let (positions, indices) = (soup.positions, soup.indices);
        assert!(is_closed(&positions, &indices));
        let split: Vec<DVec3> = indices.iter().map(|&i| positions[i as usize]).collect();
        let corners: Vec<u32> = (0..split.len() as u32).collect();
        assert!(is_closed(&split, &corners), "every corner its own vertex");
        let mut open = indices.clone();
        open.drain(300_000..300_003);
        assert!(!is_closed(&positions, &open), "a triangle missing");
        assert!(!closed_by_definition(&positions, &open));
    }
}
