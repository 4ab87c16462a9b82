//! `occlu export`: a scene as occlu holds it (after clustering) and a camera
//! path, as one GLB, so a user can replay occlu's scene and path in their
//! own engine: each of occlu's meshes is a glTF mesh, each object a node
//! with its transform, and the path a camera node moved by an animation
//! ("occlu path": one key per frame at 30 frames a second, LINEAR).
//! Loaded back by occlu, the file gives the same triangles and, as its
//! default path, the same cameras.
//!
//! A scene whose up axis is not +Y hangs under a root node that turns it
//! +Y up, as glTF expects.
//!
//! Departures: glTF animates no field of view without an extension, so the
//! camera keeps the first frame's; moving objects (the city's cars) stand
//! where frame 0 puts them; node transforms are written in f32, as glTF
//! stores them, so a scene far from the origin loses the precision occlu
//! keeps in f64.

use serde_json::{Value, json};

use crate::camera::path::CameraPath;
use crate::scene::Scene;
use crate::scene::cameras::SAMPLES_PER_SECOND;

#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("the scene and path need {0} bytes, more than a GLB file holds (4 GiB)")]
    TooLarge(usize),
}

/// The GLB bytes of `scene` and `path` (cameras at `aspect`).
pub fn glb(scene: &Scene, path: &CameraPath, aspect: f64) -> Result<Vec<u8>, ExportError> {
    let mut bin = Binary::default();
    let mut accessors = Vec::new();
    let mut meshes = Vec::new();
    for mesh in &scene.meshes {
        let range = mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize;
        let indices = &scene.indices[range];
        // Each mesh's own vertices, renumbered from 0.
        let first = indices.iter().copied().min().unwrap_or(0);
        let last = indices.iter().copied().max().unwrap_or(0);
        let positions: Vec<f32> = scene.vertices[first as usize..=last as usize]
            .iter()
            .flatten()
            .copied()
            .collect();
        let local: Vec<u32> = indices.iter().map(|i| i - first).collect();
        let position = bin.accessor(&mut accessors, &positions, "VEC3", 34962);
        let index = bin.indices(&mut accessors, &local);
        meshes.push(json!({"primitives": [{"attributes": {"POSITION": position}, "indices": index}]}));
    }
    let mut nodes: Vec<Value> = scene
        .objects
        .iter()
        .map(|o| {
            let matrix: Vec<f32> = glam::DMat4::from(o.transform)
                .to_cols_array()
                .iter()
                .map(|&v| v as f32)
                .collect();
            json!({"name": o.name, "mesh": o.mesh, "matrix": matrix})
        })
        .collect();
    let cameras: Vec<_> = (0..path.frames).map(|f| path.camera(f, aspect)).collect();
    let times: Vec<f32> = (0..path.frames)
        .map(|f| (f64::from(f) / SAMPLES_PER_SECOND) as f32)
        .collect();
    let eyes: Vec<f32> = cameras
        .iter()
        .flat_map(|c| c.eye.to_array())
        .map(|v| v as f32)
        .collect();
    // Each rotation on the same side as the one before (q and -q are one
    // turn), so loaders that interpolate components do not spin.
    let mut previous = glam::DQuat::IDENTITY;
    let turns: Vec<f32> = cameras
        .iter()
        .flat_map(|c| {
            let q = c.rotation.normalize();
            previous = if q.dot(previous) < 0.0 { -q } else { q };
            previous.to_array()
        })
        .map(|v| v as f32)
        .collect();
    let input = bin.accessor(&mut accessors, &times, "SCALAR", 0);
    let translation = bin.accessor(&mut accessors, &eyes, "VEC3", 0);
    let rotation = bin.accessor(&mut accessors, &turns, "VEC4", 0);
    let camera_node = nodes.len();
    nodes.push(json!({
        "name": "occlu camera", "camera": 0,
        "translation": &eyes[..3], "rotation": &turns[..4]
    }));
    // glTF is +Y up: a scene with another up axis hangs under a root that
    // turns its up to +Y, the camera with it.
    let turn = glam::DQuat::from_rotation_arc(scene.up.axis.vector(), glam::DVec3::Y);
    let children: Vec<usize> = (0..nodes.len()).collect();
    nodes.push(json!({"name": "occlu up", "children": children, "rotation": turn.to_array()}));
    let first = &cameras[0];
    let document = json!({
        "asset": {"version": "2.0", "generator": concat!("occlu ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [nodes.len() - 1]}],
        "nodes": nodes,
        "meshes": meshes,
        "cameras": [{"type": "perspective", "name": path.source,
            "perspective": {"yfov": first.fov_y, "znear": path.near, "aspectRatio": aspect}}],
        "animations": [{"name": "occlu path",
            "samplers": [
                {"input": input, "output": translation, "interpolation": "LINEAR"},
                {"input": input, "output": rotation, "interpolation": "LINEAR"}
            ],
            "channels": [
                {"sampler": 0, "target": {"node": camera_node, "path": "translation"}},
                {"sampler": 1, "target": {"node": camera_node, "path": "rotation"}}
            ]}],
        "accessors": accessors,
        "bufferViews": bin.views,
        "buffers": [{"byteLength": bin.bytes.len()}],
    });
    pack(&document, bin.bytes)
}

/// The binary chunk as it is filled, and its buffer views.
#[derive(Default)]
struct Binary {
    bytes: Vec<u8>,
    views: Vec<Value>,
}

impl Binary {
    /// A view of `data` (4-byte aligned), `target` 0 for none.
    fn view(&mut self, data: &[u8], target: u32) -> usize {
        let mut view = json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()});
        if target != 0 {
            view["target"] = json!(target);
        }
        self.bytes.extend_from_slice(data);
        self.bytes.resize(self.bytes.len().next_multiple_of(4), 0);
        self.views.push(view);
        self.views.len() - 1
    }

    /// A float accessor of `kind` ("SCALAR", "VEC3", "VEC4"), with min and
    /// max, as POSITION and animation inputs require.
    fn accessor(&mut self, accessors: &mut Vec<Value>, values: &[f32], kind: &str, target: u32) -> usize {
        let width = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            _ => 4,
        };
        let (mut min, mut max) = (vec![f32::INFINITY; width], vec![f32::NEG_INFINITY; width]);
        for chunk in values.chunks(width) {
            for (k, &v) in chunk.iter().enumerate() {
                min[k] = min[k].min(v);
                max[k] = max[k].max(v);
            }
        }
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": values.len() / width,
            "type": kind, "min": min, "max": max
        }));
        accessors.len() - 1
    }

    fn indices(&mut self, accessors: &mut Vec<Value>, indices: &[u32]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        accessors.push(json!({"bufferView": view, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}));
        accessors.len() - 1
    }
}

/// A GLB container of `document` and `bin` (each padded to 4 bytes).
pub fn pack(document: &Value, mut bin: Vec<u8>) -> Result<Vec<u8>, ExportError> {
    let mut json = document.to_string().into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    if u32::try_from(total).is_err() {
        return Err(ExportError::TooLarge(total));
    }
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}
