//! Compressed glTF, as gltfpack writes it: quantized positions
//! (KHR_mesh_quantization) and meshopt-compressed buffers
//! (EXT_meshopt_compression, and KHR_meshopt_compression with version 1
//! of its attribute codec; the octahedral filter on normals and the
//! exponential filter on positions) and Draco-compressed primitives
//! (KHR_draco_mesh_compression, both of its mesh codings, float and
//! integer positions) load as the model they were made from; so do meshes
//! drawn once per instance (EXT_mesh_gpu_instancing, as gltfpack writes
//! the three crates that share one mesh).
//!
//! The files in `tests/fixtures/compressed/` were made from the model
//! [`source`] builds, by `scripts/make-compressed-fixtures` (gltfpack and
//! glTF-Transform). A test checks that `source.glb` there is still what
//! [`source`] builds, so the fixtures cannot drift from the model.

mod common;

use std::path::{Path, PathBuf};

use common::gltf_writer::{GltfWriter, cube_indices};
use glam::DVec3;
use occlu::camera::Camera;
use occlu::camera::look_rotation;
use occlu::gpu::Resolution;
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};
use serde_json::json;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/compressed")
}

/// Twelve boxes of assorted sizes at unround positions, three of them one
/// mesh shared by three nodes (one scaled and rotated): 144 triangles.
fn source() -> Vec<u8> {
    let mut w = GltfWriter::default();
    let box_mesh = |w: &mut GltfWriter, name: &str, min: [f32; 3], max: [f32; 3]| {
        let p: Vec<[f32; 3]> = (0..8)
            .map(|i| {
                let pick = |bit: usize, k: usize| if i & bit == 0 { min[k] } else { max[k] };
                [pick(1, 0), pick(2, 1), pick(4, 2)]
            })
            .collect();
        let mesh = w.mesh(name, &[(&p, Some(&cube_indices()), 4)]);
        // Normals (occlu reads none), so compressors use their filters on
        // them (meshopt's octahedral), which decoding must get through.
        let normals: Vec<f32> = p
            .iter()
            .flat_map(|v| {
                let c = [0, 1, 2].map(|k| v[k] - 0.5 * (min[k] + max[k]));
                let length = c.iter().map(|x| x * x).sum::<f32>().sqrt();
                c.map(|x| x / length)
            })
            .collect();
        let normal = w.floats(&normals, "VEC3");
        w.meshes[mesh]["primitives"][0]["attributes"]["NORMAL"] = json!(normal);
        mesh
    };
    let mut roots = Vec::new();
    for k in 0..9 {
        let x = -13.37 + 4.21 * k as f32;
        let height = 1.3 + 0.77 * (k % 4) as f32;
        let m = box_mesh(&mut w, &format!("block{k}"), [x, 0.0, -7.9], [x + 3.1, height, -4.45]);
        roots.push(w.node(json!({"name": format!("block{k}"), "mesh": m})));
    }
    let shared = box_mesh(&mut w, "crate", [-0.5, 0.0, -0.5], [0.5, 0.83, 0.5]);
    roots.push(w.node(json!({"name": "crate_a", "mesh": shared, "translation": [2.5, 0.0, -2.0]})));
    roots.push(w.node(json!({"name": "crate_b", "mesh": shared, "translation": [-3.25, 0.0, -1.5]})));
    roots.push(w.node(json!({
        "name": "crate_c", "mesh": shared, "translation": [0.4, 0.0, -11.0],
        "scale": [2.0, 2.0, 2.0], "rotation": [0.0, 0.3826834, 0.0, 0.9238795]
    })));
    w.glb(&roots)
}

fn load_fixture(name: &str) -> Result<Scene, String> {
    load(&SceneSpec::File(fixtures().join(name)), &LoadOptions::default()).map_err(|e| e.to_string())
}

#[test]
fn the_fixtures_were_made_from_the_model_the_tests_build() {
    let path = fixtures().join("source.glb");
    if std::env::var_os("OCCLU_WRITE_FIXTURES").is_some() {
        std::fs::create_dir_all(fixtures()).unwrap();
        std::fs::write(&path, source()).unwrap();
    }
    let committed = std::fs::read(&path).unwrap();
    assert!(
        committed == source(),
        "{} is not what source() builds: run scripts/make-compressed-fixtures",
        path.display()
    );
}

/// The reference depth of `scene` seen from a fixed camera above and in
/// front of the blocks, on the first adapter.
fn depth(scene: &Scene) -> Vec<f32> {
    let eye = DVec3::new(1.0, 9.0, 12.0);
    let camera = Camera {
        eye,
        rotation: look_rotation(DVec3::new(0.0, 0.0, -6.0) - eye, DVec3::Y),
        fov_y: 60f64.to_radians(),
        near: 0.1,
        aspect: 4.0 / 3.0,
    };
    common::reference_depth(
        scene,
        &camera,
        Resolution {
            width: 160,
            height: 120,
        },
    )
}

#[test]
fn compressed_files_load_as_their_source() {
    let source = load_fixture("source.glb").unwrap();
    let source_depth = depth(&source);
    let covered = source_depth.iter().filter(|&&d| d > 0.0).count();
    assert!(covered > 1000, "the camera sees the model ({covered} pixels)");
    let step = 37.0 / f64::from((1 << 14) - 1);
    let mut depths = std::collections::HashMap::new();
    for file in [
        "float.glb",
        "meshopt-float.glb",
        "quantized.glb",
        "meshopt-quantized.glb",
        "meshopt-exponential.glb",
        "draco.glb",
        "draco-sequential.glb",
        "instanced.glb",
        "instanced-quantized.glb",
        "khr-meshopt.glb",
        "khr-meshopt-octahedral.glb",
        "khr-meshopt-exponential.glb",
    ] {
        let scene = load_fixture(file).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(scene.triangles(), source.triangles(), "{file}");
        // The tools' bounds agree with what they stored (or describe values
        // before a rounding they applied, which is not checked).
        assert!(
            !scene.warnings.iter().any(|w| w.contains("beyond the bounds")),
            "{file}: {:?}",
            scene.warnings
        );
        for k in 0..3 {
            let (a, b) = (
                scene.bounds.min[k] - source.bounds.min[k],
                scene.bounds.max[k] - source.bounds.max[k],
            );
            assert!(a.abs() <= step && b.abs() <= step, "{file}: bounds {a} {b}");
        }
        // gltfpack bakes node transforms into vertices and quantizes
        // positions to 14 bits of the model's extent (37 units: 2.3e-3),
        // glTF-Transform's Draco to 14 bits of each mesh's, so surfaces move
        // by up to that: in depth well under 1e-5 here, with some edge
        // pixels changing owner.
        let d = depth(&scene);
        let moved = d
            .iter()
            .zip(&source_depth)
            .filter(|(a, b)| (*a - *b).abs() > 1e-5)
            .count();
        assert!(
            moved * 50 < covered,
            "{file}: {moved} of {covered} pixels moved by more than 1e-5"
        );
        depths.insert(file, d);
    }
    // Compression itself loses nothing: each meshopt file holds exactly the
    // triangles gltfpack wrote without it (its index codec may rotate a
    // triangle's corners, which can change a rasterised depth's last bit).
    for (plain, compressed) in [
        ("float.glb", "meshopt-float.glb"),
        ("quantized.glb", "meshopt-quantized.glb"),
        ("quantized-1.3.glb", "khr-meshopt.glb"),
    ] {
        let (a, b) = (load_fixture(plain).unwrap(), load_fixture(compressed).unwrap());
        assert!(
            triangles(&a) == triangles(&b),
            "{compressed} holds other triangles than {plain}"
        );
    }
    let (float, quantized) = (
        load_fixture("float.glb").unwrap(),
        load_fixture("quantized.glb").unwrap(),
    );
    assert!(
        triangles(&float) != triangles(&quantized),
        "the comparison sees a 14-bit step"
    );
}

/// Every triangle of `scene` in world space, each starting at its least
/// corner (so a rotation of its corners is the same triangle), sorted.
fn triangles(scene: &Scene) -> Vec<[[u64; 3]; 3]> {
    let mut out = Vec::new();
    for object in &scene.objects {
        let mesh = &scene.meshes[object.mesh as usize];
        let range = mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize;
        for t in scene.indices[range].chunks(3) {
            let corner = |i: u32| {
                let v = DVec3::from(scene.vertices[i as usize].map(f64::from));
                object.transform.transform_point3(v).to_array().map(f64::to_bits)
            };
            let c = [corner(t[0]), corner(t[1]), corner(t[2])];
            let least = (0..3).min_by_key(|&k| c[k]).unwrap();
            out.push([c[least], c[(least + 1) % 3], c[(least + 2) % 3]]);
        }
    }
    out.sort();
    out
}

#[test]
fn draco_codes_integer_positions_losslessly() {
    let source = load_fixture("source.glb").unwrap();
    // Integer positions (KHR_mesh_quantization) are coded losslessly: the
    // Draco file holds exactly the triangles of the file it was made from,
    // dequantized as its accessors say.
    let (plain, draco) = (
        load_fixture("transform-quantized.glb").unwrap(),
        load_fixture("draco-quantized.glb").unwrap(),
    );
    assert!(
        triangles(&plain) == triangles(&draco),
        "draco-quantized.glb holds other triangles"
    );
    assert!(
        triangles(&plain) != triangles(&source),
        "the comparison sees quantization"
    );
}

#[test]
fn malformed_draco_data_is_an_error_not_a_crash() {
    let file = Unpacked::fixture("draco.glb");
    let (json, bin) = (&file.json, &file.bin);
    let try_load = |json: &serde_json::Value, bin: &[u8]| file.load(json, bin);
    assert!(try_load(json, bin).is_ok(), "the unchanged file loads");
    let edited = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut json = json.clone();
        edit(&mut json);
        json
    };
    fn draco(json: &mut serde_json::Value) -> &mut serde_json::Value {
        &mut json["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
    }
    let refused = [
        (
            edited(&|j| draco(j)["attributes"]["POSITION"] = 7.into()),
            "holds no attribute of id 7",
        ),
        (
            edited(&|j| draco(j)["attributes"]["POSITION"] = "0".into()),
            "names no POSITION attribute id",
        ),
        (
            edited(&|j| draco(j)["bufferView"] = 99.into()),
            "names bufferView 99, and the file has 10",
        ),
        (
            edited(&|j| j["bufferViews"][0]["byteLength"] = 20.into()),
            "data does not decode",
        ),
        (
            edited(&|j| j["bufferViews"][0]["byteOffset"] = 1_000_000.into()),
            "bufferView 0 lies outside its buffer",
        ),
        (
            edited(&|j| j["accessors"][2]["componentType"] = 5123.into()),
            "but its accessor describes 3 × U16",
        ),
        (
            edited(&|j| draco(j)["attributes"]["POSITION"] = 0.into()),
            "holds Normal there",
        ),
        (
            edited(&|j| draco(j)["attributes"] = 1.into()),
            "names no POSITION attribute id",
        ),
    ];
    for (json, why) in refused {
        let e = try_load(&json, bin).unwrap_err();
        assert!(e.contains(why) && !e.contains('\n'), "{why}: {e}");
    }
    // Every byte of the streams overwritten, and each one flipped in turn:
    // refused or decoded into some geometry, never a panic.
    for fill in [0x00, 0xff, 0xa0] {
        let _ = try_load(json, &vec![fill; bin.len()]);
    }
    let first_view = json["bufferViews"][0]["byteLength"].as_u64().unwrap() as usize;
    for at in 0..first_view {
        let mut flipped = bin.clone();
        flipped[at] ^= 0x5a;
        let _ = try_load(json, &flipped);
    }
}

#[test]
fn an_extension_a_file_uses_without_listing_it_is_named() {
    // Read without its extension, the instanced node would be drawn once,
    // and the compressed files would fail on data they lack.
    // The last case: a fallback buffer alone (its views' extension objects
    // taken off).
    for (fixture, extension, site) in [
        ("draco.glb", "KHR_draco_mesh_compression", "meshes[0].primitives[0]"),
        ("instanced.glb", "EXT_mesh_gpu_instancing", "nodes[1]"),
        ("meshopt-quantized.glb", "EXT_meshopt_compression", "bufferViews[0]"),
        ("khr-meshopt.glb", "KHR_meshopt_compression", "bufferViews[0]"),
        ("meshopt-quantized.glb", "EXT_meshopt_compression", "buffers[1]"),
    ] {
        let file = Unpacked::fixture(fixture);
        let mut json = file.json.clone();
        if site.starts_with("buffers") {
            for view in json["bufferViews"].as_array_mut().unwrap() {
                if let Some(extensions) = view["extensions"].as_object_mut() {
                    extensions.remove(extension);
                }
            }
        }
        for list in ["extensionsUsed", "extensionsRequired"] {
            if let Some(names) = json[list].as_array_mut() {
                names.retain(|name| name != extension);
            }
        }
        let Err(e) = file.load(&json, &file.bin) else {
            panic!("{fixture} loads without {extension} listed")
        };
        let expected = format!("{site} uses {extension}, but extensionsUsed does not list {extension}");
        assert!(e.contains(&expected) && !e.contains('\n'), "{fixture}: {e}");
    }
}

#[test]
fn an_extension_name_written_with_escapes_is_the_same_name() {
    let file = Unpacked::fixture("instanced.glb");
    let mut json = file.json.clone();
    for list in ["extensionsUsed", "extensionsRequired"] {
        json[list]
            .as_array_mut()
            .unwrap()
            .retain(|name| name != "EXT_mesh_gpu_instancing");
    }
    let text = json
        .to_string()
        .replace("\"EXT_mesh_gpu_instancing\":", "\"EXT_mesh_gpu_instanc\\u0069ng\":");
    assert!(text.contains("instanc\\u0069ng"), "the node's extension escaped");
    let Err(e) = file.load_text(&text) else {
        panic!("loads with the instanced node drawn once")
    };
    assert!(e.contains("nodes[1] uses EXT_mesh_gpu_instancing"), "{e}");
}

#[test]
fn a_file_that_only_mentions_an_extension_loads_whatever_else_its_json_holds() {
    // Named in a node's name, beside extras the gltf crate skips unread:
    // arrays nested 200 deep, a number beyond f64.
    let file = Unpacked::fixture("float.glb");
    let mut json = file.json.clone();
    json["nodes"][0]["name"] = "EXT_mesh_gpu_instancing".into();
    let deep = format!("{}{}", "[".repeat(200), "]".repeat(200));
    let text = json
        .to_string()
        .replacen('{', &format!("{{\"extras\":{{\"deep\":{deep},\"big\":1e400}},"), 1);
    let scene = file.load_text(&text).unwrap();
    assert_eq!(
        scene.objects.len(),
        file.load(&file.json, &file.bin).unwrap().objects.len()
    );
}

#[test]
fn instances_shared_by_many_nodes_are_bounded_by_the_file() {
    let file = Unpacked::fixture("instanced.glb");
    let json = &file.json;
    let instanced = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| !n["extensions"]["EXT_mesh_gpu_instancing"].is_null())
        .unwrap()
        .clone();
    let try_with = |copies: usize| {
        let mut json = json.clone();
        let first = json["nodes"].as_array().unwrap().len();
        for _ in 0..copies {
            json["nodes"].as_array_mut().unwrap().push(instanced.clone());
        }
        let scene = json["scene"].as_u64().unwrap_or(0) as usize;
        for k in first..first + copies {
            json["scenes"][scene]["nodes"].as_array_mut().unwrap().push(k.into());
        }
        file.load(&json, &file.bin)
    };
    // Three instances a node: 30 more nodes place 90 more objects; 2 000
    // would place 6 000 from a file whose buffers hold a few kilobytes.
    assert_eq!(try_with(30).unwrap().objects.len(), 4 + 90);
    let Err(e) = try_with(2000) else {
        panic!("2 000 nodes of three instances each load")
    };
    assert!(
        e.contains("its nodes place more than") && e.contains("EXT_mesh_gpu_instancing"),
        "{e}"
    );
}

#[test]
fn instances_decoded_from_a_few_compressed_bytes_are_bounded_by_the_bytes_the_file_holds() {
    use meshoptimizer_rs::codec::{VertexEncoding, encode_vertex_buffer};
    use meshoptimizer_rs::{Limits, Workspace};
    // 200 000 translations, all zero, as version 1 of the attribute codec
    // writes them: 2 400 000 bytes from about 2 400.
    let (count, stride) = (200_000usize, 12usize);
    let stream = encode_vertex_buffer(
        &vec![0; count * stride],
        count,
        stride,
        VertexEncoding::new(1, 2).unwrap(),
        &mut Workspace::new(Limits::default()),
    )
    .unwrap();
    let file = Unpacked::fixture("instanced.glb");
    let (mut json, mut bin) = (file.json.clone(), file.bin.clone());
    bin.resize(bin.len().next_multiple_of(4), 0);
    let offset = bin.len();
    bin.extend(&stream);
    bin.resize(bin.len().next_multiple_of(4), 0);
    json["buffers"][0]["byteLength"] = bin.len().into();
    json["buffers"].as_array_mut().unwrap().push(serde_json::json!({
        "byteLength": count * stride, "extensions": {"KHR_meshopt_compression": {"fallback": true}}
    }));
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(serde_json::json!({
        "buffer": 1, "byteLength": count * stride,
        "extensions": {"KHR_meshopt_compression": {
            "buffer": 0, "byteOffset": offset, "byteLength": stream.len(), "byteStride": stride,
            "mode": "ATTRIBUTES", "count": count
        }}
    }));
    let view = views.len() - 1;
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(serde_json::json!({"bufferView": view, "componentType": 5126, "count": count, "type": "VEC3"}));
    let accessor = accessors.len() - 1;
    for extensions in ["extensionsUsed", "extensionsRequired"] {
        json[extensions]
            .as_array_mut()
            .unwrap()
            .push("KHR_meshopt_compression".into());
    }
    let node = json["nodes"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|n| !n["extensions"]["EXT_mesh_gpu_instancing"].is_null())
        .unwrap();
    node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = serde_json::json!({"TRANSLATION": accessor});
    let Err(e) = file.load(&json, &bin) else {
        panic!("200 000 instances from a file of a few kilobytes load")
    };
    assert!(e.contains("its nodes place more than"), "{e}");
}

#[test]
fn repeated_validation_errors_are_summarised() {
    // 40 accessors that all lack their data.
    let mut w = GltfWriter::default();
    let (p, i) = common::gltf_writer::cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(json!({"mesh": m}));
    for k in 0..40 {
        w.accessors
            .push(json!({"bufferView": 99 + k, "componentType": 5126, "count": 1, "type": "VEC3"}));
    }
    let dir = tempfile::tempdir().unwrap();
    let model = common::write(dir.path(), "m.glb", w.glb(&[n]));
    let e = load(&SceneSpec::File(model), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("40 × ") && e.contains("(first at accessors[2]"), "{e}");
    assert!(e.len() < 300, "{e}");
}

/// A fixture GLB's JSON and binary chunks, to be edited, and a folder to
/// load the edited files from.
struct Unpacked {
    json: serde_json::Value,
    bin: Vec<u8>,
    dir: tempfile::TempDir,
}

impl Unpacked {
    fn fixture(name: &str) -> Unpacked {
        let glb = std::fs::read(fixtures().join(name)).unwrap();
        let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
        let json_length = word(12);
        let bin_at = 20 + json_length;
        Unpacked {
            json: serde_json::from_slice(&glb[20..20 + json_length]).unwrap(),
            bin: glb[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec(),
            dir: tempfile::tempdir().unwrap(),
        }
    }

    /// Loads the glTF file of JSON text `text`, its first buffer the
    /// fixture's binary chunk in a file beside it.
    fn load_text(&self, text: &str) -> Result<Scene, String> {
        common::write(self.dir.path(), "m.bin", self.bin.clone());
        let text = text.replacen("\"buffers\":[{", "\"buffers\":[{\"uri\":\"m.bin\",", 1);
        let model = common::write(self.dir.path(), "m.gltf", text.into_bytes());
        load(&SceneSpec::File(model), &LoadOptions::default()).map_err(|e| e.to_string())
    }

    /// Loads the GLB of `json` and `bin`.
    fn load(&self, json: &serde_json::Value, bin: &[u8]) -> Result<Scene, String> {
        let model = common::write(
            self.dir.path(),
            "m.glb",
            occlu::export::pack(json, bin.to_vec()).unwrap(),
        );
        load(&SceneSpec::File(model), &LoadOptions::default()).map_err(|e| e.to_string())
    }
}

/// A mesh's bounds are checked against its vertices where the file stores
/// them as written (meshopt without a filter), not where an encoder
/// rounded them (Draco's quantization, meshopt's exponential filter),
/// whose bounds describe the values before it.
#[test]
fn declared_bounds_are_checked_only_against_values_no_encoder_rounded() {
    for (file, checked) in [
        ("meshopt-float.glb", true),
        ("draco.glb", false),
        ("meshopt-exponential.glb", false),
        ("khr-meshopt-exponential.glb", false),
    ] {
        let unpacked = Unpacked::fixture(file);
        let mut json = unpacked.json.clone();
        let position = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        let max = &mut json["accessors"][position]["max"];
        max[1] = (max[1].as_f64().unwrap() - 1.0).into();
        let scene = unpacked.load(&json, &unpacked.bin).unwrap();
        let warned = scene.warnings.iter().any(|w| w.contains("beyond the bounds"));
        assert_eq!(warned, checked, "{file}: {:?}", scene.warnings);
    }
}

#[test]
fn malformed_meshopt_data_is_an_error_not_a_crash() {
    let file = Unpacked::fixture("meshopt-quantized.glb");
    let (json, bin) = (&file.json, &file.bin);
    let try_load = |json: &serde_json::Value, bin: &[u8]| file.load(json, bin);
    assert!(try_load(json, bin).is_ok(), "the unchanged file loads");
    // The file with its first compressed view's extension object edited.
    let edited = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut json = json.clone();
        edit(&mut json["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]);
        json
    };
    let refused = [
        (edited(&|e| e["mode"] = "SHUFFLE".into()), "no known 'mode'"),
        (
            edited(&|e| e["count"] = (1u64 << 40).into()),
            "decodes to a length other than",
        ),
        (
            edited(&|e| e["byteLength"] = 1_000_000.into()),
            "data lies outside its buffer",
        ),
        (edited(&|e| e["filter"] = "SPIRAL".into()), "unknown 'filter'"),
        // 256 MiB claimed from its 238 bytes, the view and its buffer made
        // to agree: refused before the 256 MiB are allocated.
        (
            {
                let mut json = edited(&|e| e["count"] = (1u64 << 26).into());
                json["bufferViews"][0]["byteLength"] = (1u64 << 28).into();
                json["buffers"][1]["byteLength"] = ((1u64 << 28) + 4096).into();
                json
            },
            "claims 67108864 elements of 4 bytes, more than its 238 compressed bytes can hold",
        ),
        // A view decoded 2 GiB into its buffer, which declares that much:
        // refused before the zeros before it are allocated.
        (
            {
                let mut json = json.clone();
                json["bufferViews"][0]["byteOffset"] = (1u64 << 31).into();
                json["buffers"][1]["byteLength"] = ((1u64 << 31) + (1 << 20)).into();
                json
            },
            "more than padding between them",
        ),
    ];
    for (json, why) in refused {
        let e = try_load(&json, bin).unwrap_err();
        assert!(e.contains(why) && e.contains("EXT_meshopt_compression"), "{why}: {e}");
    }
    // Every byte of the compressed streams overwritten: refused or decoded
    // into some geometry, never a panic.
    for fill in [0x00, 0xff, 0xa0] {
        let garbage = vec![fill; bin.len()];
        let _ = try_load(json, &garbage);
    }
}

#[test]
fn quantized_positions_dequantize_as_gltf_defines_them() {
    // A cube's corners as integers: (component type, normalized, low, high
    // as little-endian bytes, the value each means).
    type Encoding = (u32, bool, Vec<u8>, Vec<u8>, f64, f64);
    let encodings: [Encoding; 4] = [
        // -32768 is clamped to -1 (it would be -1.00003).
        (
            5122,
            true,
            (-32768i16).to_le_bytes().to_vec(),
            32767i16.to_le_bytes().to_vec(),
            -1.0,
            1.0,
        ),
        (5121, true, vec![0], vec![255], 0.0, 1.0),
        (5120, false, vec![(-5i8) as u8], vec![5], -5.0, 5.0),
        (
            5123,
            true,
            0u16.to_le_bytes().to_vec(),
            65535u16.to_le_bytes().to_vec(),
            0.0,
            1.0,
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    // A stored component as a number, as glTF's min and max write it.
    let stored = |component: u32, bytes: &[u8]| -> f64 {
        match component {
            5120 => f64::from(bytes[0] as i8),
            5121 => f64::from(bytes[0]),
            5122 => f64::from(i16::from_le_bytes([bytes[0], bytes[1]])),
            _ => f64::from(u16::from_le_bytes([bytes[0], bytes[1]])),
        }
    };
    for (component, normalized, low, high, lo, hi) in encodings {
        let (stored_low, stored_high) = (stored(component, &low), stored(component, &high));
        let mut w = GltfWriter::default();
        let mut bytes = Vec::new();
        for corner in 0..8 {
            for axis in 0..3 {
                bytes.extend(if corner & (1 << axis) == 0 { &low } else { &high });
            }
            // Each element padded to 4 bytes, as glTF asks of vertex data.
            bytes.resize(bytes.len().next_multiple_of(4), 0);
        }
        let stride = bytes.len() / 8;
        let position = w.raw(
            &bytes,
            json!({"componentType": component, "normalized": normalized, "count": 8, "type": "VEC3",
                   "min": [stored_low, stored_low, stored_low], "max": [stored_high, stored_high, stored_high]}),
        );
        w.buffer_views[position]["byteStride"] = json!(stride.max(4));
        let indices = w.indices(&cube_indices());
        w.meshes
            .push(json!({"name": "q", "primitives": [{"attributes": {"POSITION": position}, "indices": indices}]}));
        let node = w.node(json!({"mesh": 0, "scale": [3.0, 3.0, 3.0], "translation": [10.0, 0.0, 0.0]}));
        w.extra
            .insert("extensionsUsed".into(), json!(["KHR_mesh_quantization"]));
        w.extra
            .insert("extensionsRequired".into(), json!(["KHR_mesh_quantization"]));
        let model = common::write(dir.path(), "q.glb", w.glb(&[node]));
        let scene =
            load(&SceneSpec::File(model), &LoadOptions::default()).unwrap_or_else(|e| panic!("{component}: {e}"));
        // Bounds of the stored values agree with them; the meanings written
        // instead (an exporter's slip where they differ) leave them out.
        assert!(scene.warnings.is_empty(), "{component}: {:?}", scene.warnings);
        if normalized {
            w.accessors[position]["min"] = json!([lo, lo, lo]);
            w.accessors[position]["max"] = json!([hi, hi, hi]);
            let model = common::write(dir.path(), "meant.glb", w.glb(&[node]));
            let scene = load(&SceneSpec::File(model), &LoadOptions::default()).unwrap();
            // The vertices lie beyond both written bounds where the type
            // is signed, by as much (up to rounding) on either side.
            let beyond = |side: &str, value: f64, bound: f64| {
                format!("'q': x reaches {value} where its POSITION {side} says {bound:.1}")
            };
            assert!(
                scene.warnings.len() == 1
                    && (scene.warnings[0].contains(&beyond("max", stored_high, hi))
                        || lo < 0.0 && scene.warnings[0].contains(&beyond("min", -stored_high, lo))),
                "{component}: {:?}",
                scene.warnings
            );
        }
        let expected_min = DVec3::new(10.0 + 3.0 * lo, 3.0 * lo, 3.0 * lo);
        let expected_max = DVec3::new(10.0 + 3.0 * hi, 3.0 * hi, 3.0 * hi);
        assert!(
            scene.bounds.min.distance(expected_min) < 1e-9 && scene.bounds.max.distance(expected_max) < 1e-9,
            "{component} normalized {normalized}: {:?}",
            scene.bounds
        );
    }
}
