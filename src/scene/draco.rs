//! `KHR_draco_mesh_compression`, the geometry compression of Blender's
//! glTF exporter, glTF-Transform and glTF-Pipeline: a primitive's
//! geometry is one Draco stream in a buffer view (the extension's
//! `bufferView`), and each attribute it holds is named by its unique id in
//! the stream (the extension's `attributes`). The primitive's accessors
//! describe the decoded data and carry none of their own.
//!
//! The codec is draco-core, a pure-Rust Draco decoder that reads what
//! Google's encoder writes (both mesh encodings, EdgeBreaker and
//! sequential, and the older bitstream versions), refuses a malformed
//! stream with an error, and takes a ceiling on what one decode may
//! allocate.
//!
//! Departures from the extension's conformance section: a Draco stream is
//! decoded into a triangle list whatever the primitive's mode (it allows
//! TRIANGLES and TRIANGLE_STRIP, and a Draco mesh is always faces); and
//! the accessors' counts are not held against the decoded data, which is
//! what the file's geometry is (readers such as three.js and Babylon.js
//! draw it the same way).

use std::collections::{HashMap, HashSet};

use draco_core::{DataType, DecodeLimits, DecoderBuffer, Mesh, MeshDecoder, PointIndex};
use gltf::accessor::DataType as GltfType;
use serde_json::Value;

/// The extension's name, as files list it.
pub const DRACO: &str = "KHR_draco_mesh_compression";

/// A primitive's Draco stream: the buffer view that holds it, and the
/// unique id of its POSITION attribute there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct DracoPrimitive {
    view: usize,
    position: u32,
}

/// The Draco streams of a file's primitives, and how many bytes their
/// decoded attributes may still take.
pub struct DracoStreams {
    /// By mesh index and primitive index.
    primitives: HashMap<(usize, usize), DracoPrimitive>,
    /// Per buffer view, its buffer, offset and length.
    views: Vec<[usize; 3]>,
    budget: u64,
}

impl DracoStreams {
    /// Every primitive of the document `raw` (its JSON) that carries a
    /// Draco stream; `views` gives each buffer view's buffer, offset and
    /// length, and `budget` bounds the bytes all decodes together may
    /// allocate.
    pub fn new(raw: &Value, views: Vec<[usize; 3]>, budget: u64) -> Result<DracoStreams, String> {
        let mut primitives = HashMap::new();
        for ((m, p), primitive) in with_draco(raw) {
            let extension = &primitive["extensions"][DRACO];
            let fail = |what: &str| format!("mesh {m} primitive {p}: {DRACO} {what}");
            let view = extension["bufferView"]
                .as_u64()
                .and_then(|v| usize::try_from(v).ok())
                .filter(|&v| v < views.len())
                .ok_or_else(|| fail("names no bufferView of the file"))?;
            let position = extension["attributes"]["POSITION"]
                .as_u64()
                .and_then(|id| u32::try_from(id).ok())
                .ok_or_else(|| fail("names no POSITION attribute id"))?;
            primitives.insert((m, p), DracoPrimitive { view, position });
        }
        Ok(DracoStreams {
            primitives,
            views,
            budget,
        })
    }

    /// The geometry of primitive `primitive` of mesh `mesh`, from its Draco
    /// stream in `buffers`; its POSITION accessor's components are of
    /// glTF's type `component`. None where it carries no Draco stream.
    pub fn decode(
        &mut self,
        mesh: usize,
        primitive: usize,
        buffers: &[Vec<u8>],
        component: GltfType,
    ) -> Option<Result<Decoded, String>> {
        let draco = *self.primitives.get(&(mesh, primitive))?;
        let [buffer, offset, length] = self.views[draco.view];
        let Some(stream) = buffers
            .get(buffer)
            .and_then(|b| b.get(offset..offset.checked_add(length)?))
        else {
            return Some(Err(format!(
                "{DRACO} bufferView {} lies outside its buffer",
                draco.view
            )));
        };
        let decoded = decode(stream, draco, component, self.budget);
        if let Ok(decoded) = &decoded {
            self.budget = self.budget.saturating_sub(decoded.bytes);
        }
        Some(decoded)
    }
}

/// The primitives of the document `raw` (its JSON) that carry a Draco
/// stream, with their mesh's index and their own.
fn with_draco(raw: &Value) -> impl Iterator<Item = ((usize, usize), &Value)> {
    list(&raw["meshes"]).iter().enumerate().flat_map(move |(m, mesh)| {
        list(&mesh["primitives"])
            .iter()
            .enumerate()
            .filter(|(_, primitive)| !primitive["extensions"][DRACO].is_null())
            .map(move |(p, primitive)| ((m, p), primitive))
    })
}

/// A JSON array's items; none where it is not one.
fn list(value: &Value) -> &[Value] {
    value.as_array().map_or(&[], Vec::as_slice)
}

/// The accessors whose data Draco streams hold (of the document `raw`):
/// the indices and the attributes the extension names of each primitive
/// that carries one. They have no buffer view, which glTF's validation
/// would otherwise refuse.
pub fn decoded_accessors(raw: &Value) -> HashSet<u64> {
    with_draco(raw)
        .flat_map(|(_, primitive)| {
            let named = primitive["extensions"][DRACO]["attributes"]
                .as_object()
                .into_iter()
                .flat_map(|attributes| attributes.keys())
                .map(|name| &primitive["attributes"][name]);
            named.chain([&primitive["indices"]]).filter_map(Value::as_u64)
        })
        .collect()
}

/// The geometry of one Draco stream: its points' positions (the stored
/// components, as the accessor's type describes them) and its triangles
/// as a list of point indices.
pub struct Decoded {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<u32>,
    /// Bytes the decoder allocated for the stream's attributes and faces.
    pub bytes: u64,
}

/// Bytes of one decoded face: three point indices.
const FACE_BYTES: u64 = 12;

/// Decodes `stream`, the Draco data of `primitive`, allocating at most
/// `budget` bytes for its attributes and as many for its faces; its
/// POSITION attribute must hold three components of glTF's type
/// `component` per point.
fn decode(stream: &[u8], primitive: DracoPrimitive, component: GltfType, budget: u64) -> Result<Decoded, String> {
    let limits = DecodeLimits::default()
        .with_max_decoded_bytes(budget)
        .with_max_faces(budget / FACE_BYTES);
    let mut buffer = DecoderBuffer::new(stream).with_limits(limits);
    let mut mesh = Mesh::new();
    MeshDecoder::new()
        .decode(&mut buffer, &mut mesh)
        .map_err(|e| format!("{DRACO} data does not decode: {e}"))?;
    let attribute = mesh.attribute_by_unique_id(primitive.position).ok_or_else(|| {
        format!(
            "{DRACO} data holds no attribute of id {} (POSITION)",
            primitive.position
        )
    })?;
    let stored = match attribute.data_type() {
        DataType::Float32 => Some(GltfType::F32),
        DataType::Int8 => Some(GltfType::I8),
        DataType::Uint8 => Some(GltfType::U8),
        DataType::Int16 => Some(GltfType::I16),
        DataType::Uint16 => Some(GltfType::U16),
        _ => None,
    };
    if stored != Some(component) || attribute.num_components() != 3 {
        return Err(format!(
            "{DRACO} POSITION holds {} × {:?}, but its accessor describes 3 × {component:?}",
            attribute.num_components(),
            attribute.data_type()
        ));
    }
    let points = mesh.num_points();
    // Every point must have a value: draco-core reads a missing one as zero,
    // which would put a vertex at the origin without a word.
    if let Some(point) =
        (0..points).find(|&p| attribute.mapped_index(PointIndex(p as u32)).0 as usize >= attribute.size())
    {
        return Err(format!("{DRACO} data gives point {point} no POSITION value"));
    }
    // Values of at most 16 bits and f32 are exact as f32.
    let values = attribute.read_f32s(points, 3);
    let positions = values
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]].map(f64::from))
        .collect();
    let mut triangles = Vec::with_capacity(mesh.num_faces() * 3);
    for face in mesh.faces() {
        for corner in face {
            if corner.0 as usize >= points {
                return Err(format!(
                    "{DRACO} data has a face corner at point {} of {points}",
                    corner.0
                ));
            }
            triangles.push(corner.0);
        }
    }
    let bytes = (0..mesh.num_attributes())
        .map(|a| mesh.attribute(a).buffer().data().len() as u64)
        .fold(mesh.num_faces() as u64 * FACE_BYTES, u64::saturating_add);
    Ok(Decoded {
        positions,
        triangles,
        bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fixture's JSON, its buffer views and its binary chunk: ten
    /// primitives of 8 points and 12 faces, each with a position and a
    /// normal (glTF-Transform's output).
    fn fixture() -> (Value, Vec<[usize; 3]>, Vec<u8>) {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/compressed/draco.glb");
        let glb = std::fs::read(path).unwrap();
        let glb = gltf::Glb::from_slice(&glb).unwrap();
        let raw: Value = serde_json::from_slice(&glb.json).unwrap();
        let views = list(&raw["bufferViews"])
            .iter()
            .map(|v| ["buffer", "byteOffset", "byteLength"].map(|k| v[k].as_u64().unwrap_or(0) as usize))
            .collect();
        (raw, views, glb.bin.unwrap().into_owned())
    }

    #[test]
    fn decodes_are_bounded_by_the_file_s_budget_together() {
        let (raw, views, bin) = fixture();
        let buffers = [bin];
        // One primitive's decoded bytes: 8 points × (position + normal) in
        // f32, and 12 faces.
        let one = 8 * 2 * 12 + 12 * FACE_BYTES;
        let mut streams = DracoStreams::new(&raw, views.clone(), one).unwrap();
        let first = streams.decode(0, 0, &buffers, GltfType::F32).unwrap().unwrap();
        assert_eq!(
            (first.positions.len(), first.triangles.len(), first.bytes),
            (8, 36, one)
        );
        let second = streams.decode(1, 0, &buffers, GltfType::F32).unwrap();
        assert!(second.is_err_and(|e| e.contains("ceiling")), "the budget is spent");
        assert!(
            streams.decode(0, 1, &buffers, GltfType::F32).is_none(),
            "no such primitive"
        );
        let mut roomy = DracoStreams::new(&raw, views, 10 * one).unwrap();
        assert!((0..10).all(|m| roomy.decode(m, 0, &buffers, GltfType::F32).unwrap().is_ok()));
    }
}
