//! A minimal glTF/GLB writer for test fixtures: meshes of positions and
//! indices, nodes with transforms and children.

use base64::Engine;
use serde_json::{Value, json};

/// Positions, optional indices and the glTF primitive mode (4: triangles,
/// 5: strip, 1: lines).
pub type Primitive<'a> = (&'a [[f32; 3]], Option<&'a [u32]>, u32);

#[derive(Default)]
pub struct GltfWriter {
    bin: Vec<u8>,
    pub buffer_views: Vec<Value>,
    pub accessors: Vec<Value>,
    pub meshes: Vec<Value>,
    pub nodes: Vec<Value>,
    pub extra: serde_json::Map<String, Value>,
}

impl GltfWriter {
    /// A buffer view of `bytes` (`target` 0 for none), 4-byte aligned.
    pub fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if target != 0 {
            view["target"] = json!(target);
        }
        self.buffer_views.push(view);
        self.bin.extend_from_slice(bytes);
        self.buffer_views.len() - 1
    }

    pub fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34962);
        let (mut min, mut max) = ([f32::MAX; 3], [f32::MIN; 3]);
        for v in p {
            for i in 0..3 {
                min[i] = min[i].min(v[i]);
                max[i] = max[i].max(v[i]);
            }
        }
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": p.len(), "type": "VEC3",
            "min": min, "max": max
        }));
        self.accessors.len() - 1
    }

    /// An accessor of `values`, `components` floats each ("SCALAR", "VEC3",
    /// "VEC4"), with min and max as animation inputs need.
    pub fn floats(&mut self, values: &[f32], kind: &str) -> usize {
        let components = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 0);
        let (mut min, mut max) = (vec![f32::MAX; components], vec![f32::MIN; components]);
        for chunk in values.chunks(components) {
            for (k, &v) in chunk.iter().enumerate() {
                min[k] = min[k].min(v);
                max[k] = max[k].max(v);
            }
        }
        self.buffer_views[view].as_object_mut().unwrap().remove("target");
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": values.len() / components,
            "type": kind, "min": min, "max": max
        }));
        self.accessors.len() - 1
    }

    /// An accessor over `bytes` as `accessor` describes them (its
    /// `bufferView` is filled in).
    pub fn raw(&mut self, bytes: &[u8], mut accessor: Value) -> usize {
        accessor["bufferView"] = json!(self.view(bytes, 34962));
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    pub fn indices(&mut self, i: &[u32]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5125, "count": i.len(), "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    /// A mesh with one primitive per (positions, indices, mode) triple.
    pub fn mesh(&mut self, name: &str, primitives: &[Primitive]) -> usize {
        let prims: Vec<Value> = primitives
            .iter()
            .map(|&(p, i, mode)| {
                let pos = self.positions(p);
                let mut prim = json!({"attributes": {"POSITION": pos}, "mode": mode});
                if let Some(i) = i {
                    prim["indices"] = json!(self.indices(i));
                }
                prim
            })
            .collect();
        self.meshes.push(json!({"name": name, "primitives": prims}));
        self.meshes.len() - 1
    }

    pub fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    fn document(&self, buffer: Value, roots: &[usize]) -> Value {
        let mut doc = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "accessors": self.accessors,
            "bufferViews": self.buffer_views,
            "buffers": [buffer],
        });
        for (k, v) in &self.extra {
            doc[k] = v.clone();
        }
        doc
    }

    /// A binary .glb with `roots` as the scene's root nodes.
    pub fn glb(&self, roots: &[usize]) -> Vec<u8> {
        let document = self.document(json!({"byteLength": self.bin.len()}), roots);
        occlu::export::pack(&document, self.bin.clone()).expect("test models are small")
    }

    /// A .gltf whose buffer is the external file `bin_name` (written by the
    /// caller from [`GltfWriter::bin`]).
    pub fn gltf_external(&self, roots: &[usize], bin_name: &str) -> String {
        self.document(json!({"byteLength": self.bin.len(), "uri": bin_name}), roots)
            .to_string()
    }

    /// A self-contained .gltf: the buffer as a base64 data URI.
    pub fn gltf_embedded(&self, roots: &[usize]) -> String {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        let uri = format!("data:application/octet-stream;base64,{data}");
        self.document(json!({"byteLength": self.bin.len(), "uri": uri}), roots)
            .to_string()
    }

    pub fn bin(&self) -> &[u8] {
        &self.bin
    }
}

/// A cube mesh used by three nodes (one under a scaled parent) and a
/// two-primitive mesh (a strip of 4 triangles, a list of 1): 41 triangles,
/// 5 objects. Returns the writer and the scene's root nodes.
pub fn instanced_scene() -> (GltfWriter, Vec<usize>) {
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let cube_mesh = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let strip: Vec<[f32; 3]> = (0..6).map(|k| [k as f32, (k % 2) as f32, 0.0]).collect();
    let tri = [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]];
    let two = w.mesh("two", &[(&strip, None, 5), (&tri, None, 4)]);
    let a = w.node(json!({"name": "a", "mesh": cube_mesh, "translation": [10.0, 0.0, 0.0]}));
    let b = w.node(json!({"name": "b", "mesh": cube_mesh, "translation": [0.0, 0.0, -10.0]}));
    let child = w.node(json!({"name": "child", "mesh": cube_mesh, "translation": [1.0, 0.0, 0.0]}));
    let parent = w.node(json!({"name": "parent", "children": [child], "scale": [2.0, 2.0, 2.0]}));
    let t = w.node(json!({"name": "t", "mesh": two}));
    (w, vec![a, b, parent, t])
}

/// A unit cube at the origin: 8 vertices, 12 triangles.
pub fn cube() -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    (p, cube_indices())
}

/// The 12 triangles of a box whose corners are numbered by bits (bit 0:
/// max x, bit 1: max y, bit 2: max z).
pub fn cube_indices() -> Vec<u32> {
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    faces.iter().flat_map(|&[a, b, c, d]| [a, b, c, a, c, d]).collect()
}
