//! Splitting large meshes into spatially coherent clusters, so that a model
//! made of one huge mesh still gives a culler something to cull.
//!
//! Triangles are split recursively at the median centroid along the longest
//! axis of their centroid bounds (a balanced k-d split) until each part holds
//! at most the target number of triangles. Each cluster gets its own compact
//! vertex list; vertices on a cut are duplicated.
//!
//! In time proportional to the mesh times the depth of the split, with
//! small constants: each triangle's centroid is computed once and kept
//! beside it, so every level partitions one contiguous array in place
//! (`select_nth_unstable_by`) and reads no vertex. The centroids are
//! computed, and the halves of a cut split and their clusters gathered, on
//! separate cores while there are cores for them. The clusters are those
//! of one core, to the index: the same partitions in the same order.

use glam::DVec3;

use crate::bounds::Aabb;
use crate::parallel;

pub struct Cluster {
    /// Source-mesh vertex ids this cluster uses, in first-use order.
    pub vertices: Vec<u32>,
    /// Triangles as indices into `vertices`.
    pub indices: Vec<u32>,
    /// Bounds of the cluster's vertices in source-mesh space.
    pub bounds: Aabb,
}

pub fn split(positions: &[DVec3], indices: &[u32], max_triangles: u32) -> Vec<Cluster> {
    let mesh = Mesh {
        positions,
        indices,
        max_triangles: max_triangles.max(1) as usize,
    };
    let count = indices.len() / 3;
    if count <= mesh.max_triangles {
        // One cluster or none: no centroids needed.
        return (count > 0)
            .then(|| mesh.gather(0..count as u32, &mut Vec::new()))
            .into_iter()
            .collect();
    }
    let parts = parallel::parts_for(count, TRIANGLES_PER_PART);
    let mut triangles = vec![
        Triangle {
            centroid: DVec3::ZERO,
            id: 0,
        };
        count
    ];
    // Centroids, a share of the triangles a core.
    let share = count.div_ceil(parts);
    parallel::map(triangles.chunks_mut(share).enumerate().collect(), |(k, these)| {
        for (t, triangle) in (k * share..).zip(these) {
            let [a, b, c] = [0, 1, 2].map(|corner| positions[indices[3 * t + corner] as usize]);
            *triangle = Triangle {
                centroid: (a + b + c) / 3.0,
                id: t as u32,
            };
        }
    });
    mesh.split(&mut triangles, parts, &mut Vec::new())
}

/// A triangle of the source mesh and its centroid.
#[derive(Clone, Copy)]
struct Triangle {
    centroid: DVec3,
    id: u32,
}

/// Triangles in a share below which another thread does not pay.
const TRIANGLES_PER_PART: usize = 1 << 15;

/// The mesh being split, and the cluster size.
struct Mesh<'a> {
    positions: &'a [DVec3],
    indices: &'a [u32],
    max_triangles: usize,
}

impl Mesh<'_> {
    /// The clusters of `triangles`, in order, split over `parts` cores.
    /// `local` maps source vertices to a cluster's own while one is
    /// gathered (`u32::MAX`: not in it); it is made on first use, one per
    /// thread.
    fn split(&self, triangles: &mut [Triangle], parts: usize, local: &mut Vec<u32>) -> Vec<Cluster> {
        if triangles.len() <= self.max_triangles {
            return if triangles.is_empty() {
                Vec::new()
            } else {
                vec![self.gather(triangles.iter().map(|t| t.id), local)]
            };
        }
        let bounds = Aabb::from_points(triangles.iter().map(|t| t.centroid));
        let axis = bounds.extent().max_position();
        let mid = triangles.len() / 2;
        triangles.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        let (below, above) = triangles.split_at_mut(mid);
        if parts > 1 {
            let halves = vec![
                (below, parts / 2, std::mem::take(local)),
                (above, parts - parts / 2, Vec::new()),
            ];
            parallel::map(halves, |(half, parts, mut local)| self.split(half, parts, &mut local))
                .into_iter()
                .flatten()
                .collect()
        } else {
            let mut clusters = self.split(below, 1, local);
            clusters.append(&mut self.split(above, 1, local));
            clusters
        }
    }

    /// One cluster of the triangles `ids`, its vertices in first-use order.
    fn gather(&self, ids: impl ExactSizeIterator<Item = u32>, local: &mut Vec<u32>) -> Cluster {
        if local.is_empty() {
            local.resize(self.positions.len(), u32::MAX);
        }
        let mut cluster = Cluster {
            vertices: Vec::new(),
            indices: Vec::with_capacity(ids.len() * 3),
            bounds: Aabb::EMPTY,
        };
        for t in ids {
            for &v in &self.indices[t as usize * 3..t as usize * 3 + 3] {
                let slot = &mut local[v as usize];
                if *slot == u32::MAX {
                    *slot = cluster.vertices.len() as u32;
                    cluster.vertices.push(v);
                    cluster.bounds = cluster.bounds.grown(self.positions[v as usize]);
                }
                cluster.indices.push(*slot);
            }
        }
        for &v in &cluster.vertices {
            local[v as usize] = u32::MAX;
        }
        cluster
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat grid of `n`×`n` quads (2·n² triangles) in the xz plane.
    fn grid(n: u32) -> (Vec<DVec3>, Vec<u32>) {
        let side = f64::from(n);
        let soup = crate::scene::TriangleSoup::grid(DVec3::ZERO, DVec3::X * side, DVec3::Z * side, [n, n]);
        (soup.positions, soup.indices)
    }

    /// Each triangle as its three positions, sorted, for set comparison.
    fn triangle_set(tris: impl Iterator<Item = [DVec3; 3]>) -> Vec<String> {
        let mut v: Vec<String> = tris.map(|t| format!("{t:?}")).collect();
        v.sort();
        v
    }

    #[test]
    fn small_mesh_is_one_compact_cluster() {
        let (mut p, i) = grid(2);
        p.push(DVec3::splat(100.0)); // unreferenced vertex is not carried
        let c = split(&p, &i, 100);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].indices.len(), i.len());
        assert_eq!(c[0].vertices.len(), 9);
        assert_eq!(c[0].bounds, Aabb::new(DVec3::ZERO, DVec3::new(2.0, 0.0, 2.0)));
    }

    #[test]
    fn large_mesh_is_split_without_losing_or_adding_triangles() {
        let (p, i) = grid(40); // 3200 triangles
        let clusters = split(&p, &i, 500);
        assert!(clusters.len() >= 7, "{} clusters", clusters.len());
        for c in &clusters {
            assert!(c.indices.len() / 3 <= 500);
            for &v in &c.vertices {
                assert!(c.bounds.contains_point(p[v as usize]));
            }
        }
        let original = triangle_set(
            i.chunks(3)
                .map(|t| t.iter().map(|&v| p[v as usize]).collect::<Vec<_>>().try_into().unwrap()),
        );
        let split_tris = triangle_set(clusters.iter().flat_map(|c| {
            c.indices.chunks(3).map(|t| {
                t.iter()
                    .map(|&v| p[c.vertices[v as usize] as usize])
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap()
            })
        }));
        assert_eq!(original, split_tris);
    }

    #[test]
    fn clusters_are_the_same_on_any_number_of_cores() {
        let (p, i) = grid(200); // 80 000 triangles
        let mesh = Mesh {
            positions: &p,
            indices: &i,
            max_triangles: 300,
        };
        let triangles: Vec<Triangle> = i
            .chunks(3)
            .enumerate()
            .map(|(t, c)| Triangle {
                centroid: (p[c[0] as usize] + p[c[1] as usize] + p[c[2] as usize]) / 3.0,
                id: t as u32,
            })
            .collect();
        let split_over = |parts| mesh.split(&mut triangles.clone(), parts, &mut Vec::new());
        let one = split_over(1);
        assert_eq!(one.len(), 512);
        for parts in [2, 3, 8] {
            let many = split_over(parts);
            assert_eq!(many.len(), one.len());
            for (k, (a, b)) in one.iter().zip(&many).enumerate() {
                let same = a.vertices == b.vertices && a.indices == b.indices && a.bounds == b.bounds;
                assert!(
                    same,
                    "cluster {k} split over {parts} parts differs from one split alone"
                );
            }
        }
    }

    #[test]
    fn clusters_are_spatially_coherent() {
        // A 40×40 grid cut into clusters of ≤ 200 triangles: each cluster's
        // footprint must be far smaller than the whole grid.
        let (p, i) = grid(40);
        for c in split(&p, &i, 200) {
            let e = c.bounds.extent();
            assert!(e.x * e.z <= 40.0 * 40.0 / 8.0, "cluster spans {e:?}");
        }
    }
}
