//! Geometry validation shared by every loader: bad input is an error naming
//! the mesh and the element, degenerate triangles are dropped and counted.

use glam::DVec3;

use crate::bounds::Aabb;
use crate::text::{number, vector};

/// Coordinates beyond this are refused: the renderer works in f32
/// (camera-relative), and 1e18 units leave ample room below f32's 3.4e38
/// for every product the pipeline forms.
pub const MAX_COORDINATE: f64 = 1e18;

pub fn within_range(p: DVec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// The finest detail positions may keep, as a share of the model's size:
/// the spacing of f64 at the model's farthest coordinate beyond it means
/// the file's positions were rounded coarser than that when read.
const FINEST_SHARE: f64 = 1e-5;

/// A warning when the model lies so far from the origin for its size that
/// f64 rounded its positions coarser than [`FINEST_SHARE`] of the size
/// (a 1-unit model at 1e17, where f64 steps by 16: its shape is gone, and
/// it may render as nothing), or has no size at all (its transforms scale
/// it to a point, wherever it lies).
pub fn coarse_coordinates(bounds: &Aabb) -> Option<String> {
    let reach = bounds.min.abs().max(bounds.max.abs()).max_element();
    let size = bounds.extent().max_element();
    if size == 0.0 {
        return Some(format!(
            "every position lies at one point ({}): the model has no size, and nothing of it can be seen",
            vector(bounds.min.to_array())
        ));
    }
    let step = f64::from_bits(reach.to_bits() + 1) - reach;
    (step > FINEST_SHARE * size).then(|| {
        format!(
            "coordinates reach {}, where f64 keeps steps of {} units, more than {FINEST_SHARE:e} of the model's size ({} units): its shape may be lost as read; move it nearer the origin",
            number(reach),
            number(step),
            number(size)
        )
    })
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    #[error("mesh '{mesh}': vertex {vertex} has a non-finite position {position:?}")]
    NonFinitePosition {
        mesh: String,
        vertex: usize,
        position: [f64; 3],
    },
    #[error(
        "mesh '{mesh}': vertex {vertex} at {position:?} lies beyond ±{MAX_COORDINATE:e}, which occlu cannot render"
    )]
    OutOfRange {
        mesh: String,
        vertex: usize,
        position: [f64; 3],
    },
    #[error("object '{object}': its transform is not finite or places it beyond ±{MAX_COORDINATE:e}")]
    ObjectOutOfRange { object: String },
    #[error("mesh '{mesh}': index {index} (entry {entry} of the index list) is out of range for {vertices} vertices")]
    IndexOutOfRange {
        mesh: String,
        entry: usize,
        index: u32,
        vertices: usize,
    },
    #[error("mesh '{mesh}': {len} indices do not form whole triangles")]
    PartialTriangle { mesh: String, len: usize },
    #[error(
        "mesh '{mesh}' brings the model to {triangles} triangles, more than the {most} {}",
        memory_gib.map_or("that 32-bit indices reach".to_string(), |gib| format!("that the {gib:.1} GiB of memory available holds"))
    )]
    TooManyTriangles {
        mesh: String,
        triangles: u64,
        most: u64,
        memory_gib: Option<f64>,
    },
}

/// The triangles of a mesh that survived validation.
pub struct ValidTriangles {
    pub indices: Vec<u32>,
    pub degenerate: usize,
}

/// A triangle whose doubled area is below this fraction of its longest edge
/// squared is a line or a point: it covers no pixels, so it is dropped.
const DEGENERATE_RATIO: f64 = 1e-12;

pub fn triangles(mesh: &str, positions: &[DVec3], indices: &[u32]) -> Result<ValidTriangles, GeometryError> {
    if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !within_range(**p)) {
        let (mesh, position) = (mesh.to_string(), p.to_array());
        return Err(if p.is_finite() {
            GeometryError::OutOfRange { mesh, vertex, position }
        } else {
            GeometryError::NonFinitePosition { mesh, vertex, position }
        });
    }
    if !indices.len().is_multiple_of(3) {
        return Err(GeometryError::PartialTriangle {
            mesh: mesh.to_string(),
            len: indices.len(),
        });
    }
    if let Some((entry, &index)) = indices
        .iter()
        .enumerate()
        .find(|&(_, &i)| i as usize >= positions.len())
    {
        return Err(GeometryError::IndexOutOfRange {
            mesh: mesh.to_string(),
            entry,
            index,
            vertices: positions.len(),
        });
    }
    let mut kept = Vec::with_capacity(indices.len());
    let mut degenerate = 0;
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
        let (ab, ac, bc) = (b - a, c - a, c - b);
        let longest = ab.length_squared().max(ac.length_squared()).max(bc.length_squared());
        if ab.cross(ac).length() <= DEGENERATE_RATIO * longest || longest == 0.0 {
            degenerate += 1;
        } else {
            kept.extend_from_slice(t);
        }
    }
    Ok(ValidTriangles {
        indices: kept,
        degenerate,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Vec<DVec3> {
        vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn keeps_good_triangles_and_drops_degenerate_ones() {
        let mut p = quad();
        p.push(DVec3::new(2.0, 0.0, 0.0)); // collinear with 0 and 1
        let v = triangles("q", &p, &[0, 1, 2, 0, 2, 3, 0, 1, 4, 2, 2, 3]).unwrap();
        assert_eq!(v.indices, vec![0, 1, 2, 0, 2, 3]);
        assert_eq!(v.degenerate, 2);
    }

    #[test]
    fn nan_vertex_is_named() {
        let mut p = quad();
        p[2].y = f64::NAN;
        let e = triangles("wall", &p, &[0, 1, 2]).err().unwrap();
        assert!(matches!(e, GeometryError::NonFinitePosition { vertex: 2, .. }));
        assert!(e.to_string().contains("mesh 'wall': vertex 2"));
    }

    #[test]
    fn infinite_and_unrenderably_far_vertices_are_rejected() {
        let mut p = quad();
        p[0].x = f64::INFINITY;
        assert!(matches!(
            triangles("m", &p, &[0, 1, 2]),
            Err(GeometryError::NonFinitePosition { .. })
        ));
        p[0].x = 1e39;
        let e = triangles("m", &p, &[0, 1, 2]).err().unwrap();
        assert!(matches!(e, GeometryError::OutOfRange { vertex: 0, .. }), "{e}");
        p[0].x = -1e17;
        assert!(triangles("m", &p, &[0, 1, 2]).is_ok(), "far but renderable");
    }

    #[test]
    fn huge_triangles_are_not_mistaken_for_degenerate_ones() {
        let s = 1e17;
        let p = vec![DVec3::ZERO, DVec3::new(s, 0.0, 0.0), DVec3::new(0.0, s, 0.0)];
        assert_eq!(triangles("big", &p, &[0, 1, 2]).map(|v| v.degenerate), Ok(0));
    }

    #[test]
    fn index_out_of_range_is_named() {
        let e = triangles("m", &quad(), &[0, 1, 7]).err().unwrap();
        assert_eq!(
            e,
            GeometryError::IndexOutOfRange {
                mesh: "m".into(),
                entry: 2,
                index: 7,
                vertices: 4
            }
        );
    }

    #[test]
    fn partial_triangle_is_rejected() {
        assert!(matches!(
            triangles("m", &quad(), &[0, 1]),
            Err(GeometryError::PartialTriangle { len: 2, .. })
        ));
    }
}
