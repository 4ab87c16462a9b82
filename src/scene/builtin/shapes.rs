//! Closed primitive shapes for procedural scenes.

use glam::DVec3;

use crate::scene::TriangleSoup;

/// An axis-aligned box: 8 shared vertices, 12 triangles.
pub fn cuboid(soup: &mut TriangleSoup, min: DVec3, max: DVec3) {
    let corners: [DVec3; 8] = std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    });
    // Two triangles per face; corner bit 0 = x, bit 1 = y, bit 2 = z.
    const FACES: [[u32; 4]; 6] = [
        [0, 2, 6, 4], // -x
        [1, 5, 7, 3], // +x
        [0, 4, 5, 1], // -y
        [2, 3, 7, 6], // +y
        [0, 1, 3, 2], // -z
        [4, 6, 7, 5], // +z
    ];
    soup.append(&corners, FACES.iter().flat_map(|&[a, b, c, d]| [a, b, c, a, c, d]));
}

/// A closed cylinder with its axis along `axis` (unit), `segments` sides.
pub fn cylinder(soup: &mut TriangleSoup, base: DVec3, axis: DVec3, radius: f64, length: f64, segments: u32) {
    let u = axis.any_orthonormal_vector();
    let v = axis.cross(u);
    let ring = |offset: f64| {
        (0..segments).map(move |k| {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(segments);
            base + axis * offset + (u * a.cos() + v * a.sin()) * radius
        })
    };
    // Rings first, then the two cap centres.
    let mut positions: Vec<DVec3> = ring(0.0).chain(ring(length)).collect();
    positions.push(base);
    positions.push(base + axis * length);
    let (c0, c1) = (2 * segments, 2 * segments + 1);
    let indices = (0..segments).flat_map(|k| {
        let next = (k + 1) % segments;
        [
            k,
            next,
            segments + next, // side
            k,
            segments + next,
            segments + k, // side
            c0,
            next,
            k, // bottom cap
            c1,
            segments + k,
            segments + next, // top cap
        ]
    });
    soup.append(&positions, indices);
}

/// A closed UV sphere: `segments` around, `segments / 2` rings from pole
/// to pole, each pole a fan (no triangle of zero area).
pub fn sphere(soup: &mut TriangleSoup, centre: DVec3, radius: f64, segments: u32) {
    let rings = (segments / 2).max(2);
    let at = |ring: u32, k: u32| {
        let polar = std::f64::consts::PI * f64::from(ring) / f64::from(rings);
        let around = std::f64::consts::TAU * f64::from(k) / f64::from(segments);
        centre + radius * DVec3::new(polar.sin() * around.cos(), polar.cos(), polar.sin() * around.sin())
    };
    // The rings between the poles, then the two poles.
    let mut positions: Vec<DVec3> = (1..rings)
        .flat_map(|ring| (0..segments).map(move |k| at(ring, k)))
        .collect();
    positions.push(centre + DVec3::Y * radius);
    positions.push(centre - DVec3::Y * radius);
    let (north, south) = ((rings - 1) * segments, (rings - 1) * segments + 1);
    let vertex = |ring: u32, k: u32| (ring - 1) * segments + k % segments;
    let caps = (0..segments).flat_map(|k| {
        [
            north,
            vertex(1, k),
            vertex(1, k + 1),
            south,
            vertex(rings - 1, k + 1),
            vertex(rings - 1, k),
        ]
    });
    let bands = (1..rings - 1).flat_map(|ring| {
        (0..segments).flat_map(move |k| {
            let (a, b) = (vertex(ring, k), vertex(ring, k + 1));
            let (c, d) = (vertex(ring + 1, k), vertex(ring + 1, k + 1));
            [a, d, b, a, c, d]
        })
    });
    let indices: Vec<u32> = caps.chain(bands).collect();
    soup.append(&positions, indices);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::Aabb;

    #[test]
    fn cuboid_is_closed_with_twelve_triangles() {
        let mut s = TriangleSoup::default();
        cuboid(&mut s, DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(s.triangles(), 12);
        assert_closed(&s);
        // Total area 2(1·2 + 2·3 + 3·1) = 22.
        assert!((area(&s) - 22.0).abs() < 1e-12);
    }

    #[test]
    fn cylinder_is_closed_and_bounded() {
        let mut s = TriangleSoup::default();
        cylinder(&mut s, DVec3::ZERO, DVec3::Y, 0.5, 2.0, 16);
        assert_eq!(s.triangles(), 64);
        assert_closed(&s);
        let b = Aabb::from_points(s.positions.iter().copied());
        assert!((b.max.y - 2.0).abs() < 1e-12 && b.min.y.abs() < 1e-12);
        assert!(b.max.x <= 0.5 + 1e-12 && b.max.x > 0.49);
    }

    #[test]
    fn sphere_is_closed_and_bounded_and_encloses_a_ball() {
        let mut s = TriangleSoup::default();
        sphere(&mut s, DVec3::new(1.0, 2.0, 3.0), 0.5, 16);
        // Two fans of 16 and 6 bands of 32.
        assert_eq!(s.triangles(), 2 * 16 + 6 * 32);
        assert_closed(&s);
        let b = Aabb::from_points(s.positions.iter().copied());
        assert!((b.max.y - 2.5).abs() < 1e-12 && (b.min.y - 1.5).abs() < 1e-12);
        assert!(b.max.x <= 1.5 + 1e-12 && b.max.x > 1.49);
        // Its triangles all turn one way (each edge's twin runs the other
        // way, above), the cuboid's way, and enclose about the ball's
        // volume.
        let mut cube = TriangleSoup::default();
        cuboid(&mut cube, DVec3::ZERO, DVec3::ONE);
        assert_eq!(volume(&s).signum(), volume(&cube).signum());
        let ball = 4.0 / 3.0 * std::f64::consts::PI * 0.125;
        assert!((0.9 * ball..ball).contains(&volume(&s).abs()), "{}", volume(&s));
    }

    /// The signed volume the triangles enclose (its sign says which way
    /// they turn).
    fn volume(s: &TriangleSoup) -> f64 {
        s.indices
            .chunks(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| s.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    fn area(s: &TriangleSoup) -> f64 {
        s.indices
            .chunks(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| s.positions[i as usize]);
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
    }

    /// Every edge is shared by exactly two triangles, in opposite directions.
    fn assert_closed(s: &TriangleSoup) {
        let mut edges = std::collections::HashMap::new();
        for t in s.indices.chunks(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a, b)).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }
}
