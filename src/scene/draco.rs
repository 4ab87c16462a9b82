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
//! Departures from the extension's conformance section: the decoded faces
//! are an index stream read by the primitive's mode, as three.js reads
//! them (the extension allows TRIANGLES and TRIANGLE_STRIP and says the
//! data is "decoded accordingly"; a fan is read as one too); the
//! accessors' counts are not held against the decoded data, which is what
//! the file's geometry is; and points no face uses are left out (a stream
//! may hold millions of them in a few bytes).

use std::collections::{HashMap, HashSet};

use super::gltf_json::list;
use draco_core::{
    DataType, DecodeLimits, DecoderBuffer, ErrorKind, GeometryAttributeType, Mesh, MeshDecoder, PointIndex,
};
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
            let draco = extension_of(primitive).map_err(|what| format!("mesh {m} primitive {p}: {DRACO} {what}"))?;
            if draco.view >= views.len() {
                return Err(format!(
                    "mesh {m} primitive {p}: {DRACO} names bufferView {}, and the file has {}",
                    draco.view,
                    views.len()
                ));
            }
            primitives.insert((m, p), draco);
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

/// A primitive's Draco extension object, read; what is wrong with it.
fn extension_of(primitive: &Value) -> Result<DracoPrimitive, &'static str> {
    let extension = &primitive["extensions"][DRACO];
    let view = extension["bufferView"]
        .as_u64()
        .and_then(|v| usize::try_from(v).ok())
        .ok_or("names no bufferView index")?;
    let position = extension["attributes"]["POSITION"]
        .as_u64()
        .and_then(|id| u32::try_from(id).ok())
        .ok_or("names no POSITION attribute id")?;
    Ok(DracoPrimitive { view, position })
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

/// The accessors whose data Draco streams hold (of the document `raw`):
/// the indices and the attributes the extension names of each primitive
/// that carries one. They have no buffer view, which glTF's validation
/// would otherwise refuse. A malformed extension object is named here,
/// before that validation would call its accessors empty.
pub fn decoded_accessors(raw: &Value) -> Result<HashSet<u64>, String> {
    let mut decoded = HashSet::new();
    for ((m, p), primitive) in with_draco(raw) {
        extension_of(primitive).map_err(|what| format!("mesh {m} primitive {p}: {DRACO} {what}"))?;
        let named = primitive["extensions"][DRACO]["attributes"]
            .as_object()
            .into_iter()
            .flat_map(|attributes| attributes.keys())
            .map(|name| &primitive["attributes"][name]);
        decoded.extend(named.chain([&primitive["indices"]]).filter_map(Value::as_u64));
    }
    Ok(decoded)
}

/// The geometry of one Draco stream: the positions of the points its faces
/// use (the stored components, as the accessor's type describes them) and
/// its faces as a stream of indices into them.
pub struct Decoded {
    pub positions: Vec<[f64; 3]>,
    pub stream: Vec<u32>,
    /// Bytes the decoder allocated for the stream's attributes and faces.
    pub bytes: u64,
}

/// Bytes of one decoded face: three point indices.
const FACE_BYTES: u64 = 12;

/// Decodes `stream`, the Draco data of `primitive`, allocating at most
/// `budget` bytes for its attributes and as many for its faces, and no
/// more than draco-core's own ceilings for one stream; its POSITION
/// attribute must hold three components of glTF's type `component` per
/// point.
fn decode(stream: &[u8], primitive: DracoPrimitive, component: GltfType, budget: u64) -> Result<Decoded, String> {
    // The header: "DRACO", its version, then what it encodes (0: points).
    if stream.starts_with(b"DRACO") && stream.get(7) == Some(&0) {
        return Err(format!("{DRACO} data is a point cloud, with no faces to draw"));
    }
    let ceilings = DecodeLimits::default();
    let limits = ceilings
        .with_max_decoded_bytes(budget.min(ceilings.max_decoded_bytes))
        .with_max_faces((budget / FACE_BYTES).min(ceilings.max_faces));
    let mut buffer = DecoderBuffer::new(stream).with_limits(limits);
    let mut mesh = Mesh::new();
    MeshDecoder::new()
        .decode(&mut buffer, &mut mesh)
        .map_err(|e| match e.kind() {
            ErrorKind::LimitExceeded => format!(
                "{DRACO} data decodes to more than occlu allows: {budget} bytes are left of what --max-file-size \
             allows a file's decoded data, and one stream may take {} ({e})",
                ceilings.max_decoded_bytes
            ),
            _ => format!("{DRACO} data does not decode: {e}"),
        })?;
    let id = primitive.position;
    let attribute = mesh
        .attribute_by_unique_id(id)
        .ok_or_else(|| format!("{DRACO} data holds no attribute of id {id} (POSITION)"))?;
    if !matches!(
        attribute.attribute_type(),
        GeometryAttributeType::Position | GeometryAttributeType::Generic
    ) {
        return Err(format!(
            "{DRACO} names attribute {id} as POSITION, but the stream holds {:?} there",
            attribute.attribute_type()
        ));
    }
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
    // The points the faces use, in order, each numbered by its place there
    // (sized by the faces, not by the points the stream declares).
    let points = mesh.num_points();
    let corners = || mesh.faces().iter().flatten().map(|corner| corner.0);
    let mut used: Vec<u32> = corners().collect();
    used.sort_unstable();
    used.dedup();
    if let Some(&beyond) = used.last().filter(|&&p| p as usize >= points) {
        return Err(format!("{DRACO} data has a face corner at point {beyond} of {points}"));
    }
    let place = |point: u32| used.partition_point(|&p| p < point) as u32;
    let indices: Vec<u32> = corners().map(place).collect();
    // Every point used must have a value: draco-core reads a missing one as
    // zero, which would put a vertex at the origin without a word.
    let values = attribute.buffer().data();
    let (stride, width) = (attribute.byte_stride() as usize, attribute.data_type().byte_length());
    let mut positions = Vec::with_capacity(used.len());
    for &point in &used {
        let value = attribute.mapped_index(PointIndex(point)).0 as usize;
        let bytes = (value < attribute.size())
            .then(|| values.get(value.checked_mul(stride)?..)?.get(..3 * width))
            .flatten()
            .ok_or_else(|| format!("{DRACO} data gives point {point} no POSITION value"))?;
        positions.push(std::array::from_fn(|k| {
            component_value(attribute.data_type(), &bytes[k * width..])
        }));
    }
    let bytes = (0..mesh.num_attributes())
        .map(|a| mesh.attribute(a).buffer().data().len() as u64)
        .fold(mesh.num_faces() as u64 * FACE_BYTES, u64::saturating_add);
    Ok(Decoded {
        positions,
        stream: indices,
        bytes,
    })
}

/// The little-endian value of `data_type` (one of glTF's component types)
/// at the start of `bytes`, which holds one, as f64: exact for these types.
fn component_value(data_type: DataType, bytes: &[u8]) -> f64 {
    match data_type {
        DataType::Int8 => f64::from(bytes[0] as i8),
        DataType::Uint8 => f64::from(bytes[0]),
        DataType::Int16 => f64::from(i16::from_le_bytes([bytes[0], bytes[1]])),
        DataType::Uint16 => f64::from(u16::from_le_bytes([bytes[0], bytes[1]])),
        _ => f64::from(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
    }
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
        assert_eq!((first.positions.len(), first.stream.len(), first.bytes), (8, 36, one));
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
