//! Whether a mesh is a closed solid, judged on the mesh as loaded, before
//! it is cut into clusters (a cluster of a closed mesh is open).

use std::collections::HashMap;

use glam::DVec3;

use crate::bounds::Aabb;

/// Whether the triangles `indices` over `positions` form a closed solid:
/// welded by position, every edge is walked once in each direction
/// (watertight and consistently wound), and they enclose a volume (a
/// surface stored twice, once per side, encloses none). A line then crosses
/// the surface an even number of times, and an odd count means "inside".
pub fn is_closed(positions: &[DVec3], indices: &[u32]) -> bool {
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    let mut id = |v: u32| {
        let key = positions[v as usize].to_array().map(f64::to_bits);
        let next = welded.len() as u32;
        *welded.entry(key).or_insert(next)
    };
    let mut edges: HashMap<(u32, u32), i64> = HashMap::new();
    let mut volume = 0.0;
    let mut bounds = Aabb::EMPTY;
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [id(t[0]), id(t[1]), id(t[2])];
        for (u, v) in [(a, b), (b, c), (c, a)] {
            // +1 one way, -1 the other: a closed, consistently wound
            // surface sums to 0 on every edge.
            *edges.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
        }
        let [p, q, r] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
        volume += p.dot(q.cross(r)) / 6.0;
        bounds = bounds.grown(p).grown(q).grown(r);
    }
    let e = bounds.extent();
    !edges.is_empty() && edges.values().all(|&n| n == 0) && volume.abs() >= 0.01 * e.x * e.y * e.z
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
}
