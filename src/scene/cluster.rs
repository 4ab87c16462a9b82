//! Splitting large meshes into spatially coherent clusters, so that a model
//! made of one huge mesh still gives a culler something to cull.
//!
//! Triangles are split recursively at the median centroid along the longest
//! axis of their centroid bounds (a balanced k-d split) until each part holds
//! at most the target number of triangles. Each cluster gets its own compact
//! vertex list; vertices on a cut are duplicated.

use glam::DVec3;

use crate::bounds::Aabb;

pub struct Cluster {
    /// Source-mesh vertex ids this cluster uses, in first-use order.
    pub vertices: Vec<u32>,
    /// Triangles as indices into `vertices`.
    pub indices: Vec<u32>,
    /// Bounds of the cluster's vertices in source-mesh space.
    pub bounds: Aabb,
}

pub fn split(positions: &[DVec3], indices: &[u32], max_triangles: u32) -> Vec<Cluster> {
    let triangle_count = indices.len() / 3;
    if triangle_count == 0 {
        return Vec::new();
    }
    let centroid = |t: u32| {
        let t = t as usize * 3;
        (positions[indices[t] as usize] + positions[indices[t + 1] as usize] + positions[indices[t + 2] as usize]) / 3.0
    };
    let mut order: Vec<u32> = (0..triangle_count as u32).collect();
    let max = max_triangles.max(1) as usize;

    // Ranges of `order` that still need splitting, and finished ones.
    let mut pending: Vec<std::ops::Range<usize>> = Vec::new();
    pending.push(0..triangle_count);
    let mut done = Vec::new();
    while let Some(range) = pending.pop() {
        if range.len() <= max {
            done.push(range);
            continue;
        }
        let part = &mut order[range.clone()];
        let bounds = Aabb::from_points(part.iter().map(|&t| centroid(t)));
        let axis = bounds.extent().max_position();
        let mid = part.len() / 2;
        part.select_nth_unstable_by(mid, |&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
        pending.push(range.start + mid..range.end);
        pending.push(range.start..range.start + mid);
    }
    done.sort_by_key(|r| r.start);

    let mut local = vec![u32::MAX; positions.len()];
    done.into_iter()
        .map(|range| {
            let mut cluster = Cluster {
                vertices: Vec::new(),
                indices: Vec::with_capacity(range.len() * 3),
                bounds: Aabb::EMPTY,
            };
            for &t in &order[range] {
                for &v in &indices[t as usize * 3..t as usize * 3 + 3] {
                    let slot = &mut local[v as usize];
                    if *slot == u32::MAX {
                        *slot = cluster.vertices.len() as u32;
                        cluster.vertices.push(v);
                        cluster.bounds = cluster.bounds.grown(positions[v as usize]);
                    }
                    cluster.indices.push(*slot);
                }
            }
            for &v in &cluster.vertices {
                local[v as usize] = u32::MAX;
            }
            cluster
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat grid of `n`×`n` quads (2·n² triangles) in the xz plane.
    fn grid(n: u32) -> (Vec<DVec3>, Vec<u32>) {
        let positions = (0..=n)
            .flat_map(|z| (0..=n).map(move |x| DVec3::new(x as f64, 0.0, z as f64)))
            .collect();
        let v = |x: u32, z: u32| z * (n + 1) + x;
        let indices = (0..n)
            .flat_map(|z| {
                (0..n).flat_map(move |x| {
                    [
                        v(x, z),
                        v(x + 1, z),
                        v(x + 1, z + 1),
                        v(x, z),
                        v(x + 1, z + 1),
                        v(x, z + 1),
                    ]
                })
            })
            .collect();
        (positions, indices)
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
