//! Which triangles of a mesh share an edge: what makes a mesh's triangles
//! one surface to the rasteriser (mesh.rs). Found once per run of clusters
//! stored against one origin, by position, since the GPU places equal f32
//! positions of the run's objects under one transform at one point
//! whatever their index.

use std::ops::Range;

use super::mesh::NO_NEIGHBOUR;
use crate::scene::Scene;

/// Per run of meshes stored against one origin (at its first mesh), its
/// triangles' [`neighbours`], made once.
#[derive(Default)]
pub struct RunNeighbours {
    per_run: Vec<Option<Vec<[u32; 3]>>>,
}

/// Triangles of runs a thread makes the neighbours of, at least: a scene's
/// many runs, made when the mode is prepared, are shared over the cores
/// (the 24 M triangles of `city:blocks=32` took 5.4 s on one core of this
/// 2-core machine, 4.0 s on both), a frame's few stay on the calling
/// thread.
const TRIANGLES_PER_THREAD: usize = 1 << 18;

impl RunNeighbours {
    /// Makes the neighbours of the runs of meshes of `scene`'s `objects`
    /// that have none yet.
    pub fn make(&mut self, scene: &Scene, objects: impl Iterator<Item = u32>) {
        self.per_run.resize(scene.meshes.len(), None);
        let run_of = |o: u32| &scene.meshes[scene.objects[o as usize].mesh as usize].shares_origin_with;
        let mut lacking: Vec<Range<u32>> = objects
            .map(run_of)
            .filter(|run| self.per_run[run.start as usize].is_none())
            .cloned()
            .collect();
        if lacking.is_empty() {
            return;
        }
        lacking.sort_unstable_by_key(|run| run.start);
        lacking.dedup();
        let triangles = |run: &Range<u32>| run_indices(scene, run).len() / 3;
        let total: usize = lacking.iter().map(triangles).sum();
        // Part k ends where the triangles so far first reach (k + 1) / parts
        // of them.
        let parts = crate::parallel::parts_for(total, TRIANGLES_PER_THREAD);
        let (mut shares, mut so_far) = (vec![Vec::new(); parts], 0);
        for run in lacking {
            let k = (so_far * parts / total.max(1)).min(parts - 1);
            so_far += triangles(&run);
            shares[k].push(run);
        }
        let made = crate::parallel::map(shares, |runs| {
            runs.into_iter()
                .map(|run| {
                    let made = neighbours(run_indices(scene, &run), |v| scene.vertices[v as usize]);
                    (run.start, made)
                })
                .collect::<Vec<_>>()
        });
        for (start, made) in made.into_iter().flatten() {
            self.per_run[start as usize] = Some(made);
        }
    }

    /// The neighbours of the run of meshes `run`.
    ///
    /// # Panics
    /// Where they were not made: [`Self::make`] for an object of the run
    /// first.
    pub fn of(&self, run: &Range<u32>) -> &[[u32; 3]] {
        self.per_run[run.start as usize]
            .as_deref()
            .expect("made for an object of the run first")
    }
}

/// The indices of the run of meshes `run` (consecutive in the index buffer,
/// as they are in the scene's meshes).
pub fn run_indices<'a>(scene: &'a Scene, run: &Range<u32>) -> &'a [u32] {
    let (first, last) = (&scene.meshes[run.start as usize], &scene.meshes[run.end as usize - 1]);
    &scene.indices[first.first_index as usize..(last.first_index + last.index_count) as usize]
}

/// Per triangle of `indices` (three per triangle), the triangle across
/// each edge (corner k to k + 1): the one other triangle holding that
/// edge, in the opposite direction (so both turn the same way when they lie
/// on either side of it); [`NO_NEIGHBOUR`] where no triangle, or more than
/// one, shares it, or the two run it the same way.
pub fn neighbours(indices: &[u32], position: impl Fn(u32) -> [f32; 3]) -> Vec<[u32; 3]> {
    // One number per position (−0 is 0; a NaN position may match another
    // of the same bits, which is harmless: no patch holds its triangles,
    // the GPU placing them nowhere).
    let key = |i: u32| position(i).map(|c| if c == 0.0 { 0 } else { c.to_bits() });
    let mut by_position: Vec<([u32; 3], u32)> = (0..indices.len() as u32)
        .map(|s| (key(indices[s as usize]), s))
        .collect();
    by_position.sort_unstable();
    let mut point = vec![0u32; indices.len()];
    let mut next = 0;
    for (k, &(position, slot)) in by_position.iter().enumerate() {
        if k > 0 && by_position[k - 1].0 != position {
            next += 1;
        }
        point[slot as usize] = next;
    }
    // Each edge as (lower point, higher point), whether it runs upwards,
    // and where it is (triangle, corner).
    let mut edges: Vec<(u64, bool, u32, u8)> = Vec::with_capacity(indices.len());
    for t in 0..indices.len() / 3 {
        for k in 0..3 {
            let (u, v) = (point[3 * t + k], point[3 * t + (k + 1) % 3]);
            if u != v {
                let key = u64::from(u.min(v)) << 32 | u64::from(u.max(v));
                edges.push((key, u < v, t as u32, k as u8));
            }
        }
    }
    edges.sort_unstable();
    let mut across = vec![[NO_NEIGHBOUR; 3]; indices.len() / 3];
    let mut start = 0;
    while start < edges.len() {
        let end = start + edges[start..].partition_point(|e| e.0 == edges[start].0);
        if let [(_, up, t, k), (_, other_up, s, j)] = edges[start..end]
            && up != other_up
        {
            across[t as usize][k as usize] = s;
            across[s as usize][j as usize] = t;
        }
        start = end;
    }
    across
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangles_sharing_an_edge_by_position_in_opposite_directions_are_neighbours() {
        // A square of two triangles, the second's corners at copies of the
        // first's positions (indices 3 and 4), and -0 for 0; then a
        // triangle on the square's right edge running it the square's way
        // (a fold: no neighbour), and a lone triangle.
        let positions = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.5, 0.0],
            [5.0, 5.0, 5.0],
            [6.0, 5.0, 5.0],
            [5.0, 6.0, 5.0],
        ];
        let position = |i: u32| positions[i as usize];
        let indices = [0, 1, 2, 3, 4, 5, 1, 2, 6, 7, 8, 9];
        let n = NO_NEIGHBOUR;
        assert_eq!(
            neighbours(&indices, position),
            [[n, n, 1], [0, n, n], [n, n, n], [n, n, n]],
            "the diagonal 0-2 joins the square's halves; the fold on edge 1-2 leaves it to none"
        );
        // A third triangle on the diagonal makes it shared by three: none.
        let indices = [0, 1, 2, 3, 4, 5, 2, 0, 6];
        assert_eq!(neighbours(&indices, position), [[n; 3]; 3]);
    }
}
