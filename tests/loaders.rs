//! OBJ and glTF loading: triangle counts, instancing, transforms, clustering
//! and every kind of bad input.

mod common;

use common::gltf_writer::{GltfWriter, cube, instanced_scene};
use common::{THREE_OBJECTS_OBJ, occlu, stdout, write};
use glam::DVec3;
use occlu::scene::{LoadOptions, SceneSpec, load};
use serde_json::{Value, json};

fn load_file(path: &std::path::Path) -> Result<occlu::scene::Scene, occlu::scene::SceneError> {
    load(&SceneSpec::File(path.into()), &LoadOptions::default())
}

#[test]
fn obj_objects_and_groups_become_objects() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "three.obj", THREE_OBJECTS_OBJ);
    let s = load_file(&obj).unwrap();
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["quad", "tetra", "lone"]);
    assert_eq!(s.objects.iter().map(|o| o.triangles).collect::<Vec<_>>(), [2, 4, 1]);
    assert_eq!(s.triangles(), 7);
    assert_eq!(s.bounds.min, DVec3::ZERO);
    assert_eq!(s.bounds.max, DVec3::new(5.0, 1.0, 1.0));
    assert!(s.warnings.is_empty());
}

#[test]
fn info_reports_obj_triangle_counts() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "three.obj", THREE_OBJECTS_OBJ);
    let out = occlu(&["info", obj.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let v: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(v["triangles"], 7);
    assert_eq!(v["objects"], 3);
    assert!(v["hierarchy"]["nodes"].as_u64().unwrap() >= 1);
    // Each phase of the load, which together take no longer than the load.
    let phases = ["read_ms", "parse_ms", "validate_ms", "closed_ms", "cluster_ms"].map(|phase| {
        v["load_phases"][phase]
            .as_f64()
            .unwrap_or_else(|| panic!("{phase} in {v}"))
    });
    let sum: f64 = phases.iter().sum();
    assert!(phases.iter().all(|&ms| ms >= 0.0) && sum > 0.0, "{phases:?}");
    assert!(sum <= v["load_ms"].as_f64().unwrap(), "{phases:?} in {}", v["load_ms"]);

    let out = occlu(&["info", obj.to_str().unwrap()]);
    let load = stdout(&out)
        .lines()
        .find(|l| l.starts_with("load "))
        .map(str::to_string);
    let words = ["read", "parse", "validate", "closed-solid test", "clustering"];
    assert!(
        load.as_ref().is_some_and(|l| words.iter().all(|w| l.contains(w))),
        "{load:?}"
    );
}

#[test]
fn obj_usemtl_splits_are_merged_back_into_one_object() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "m.obj",
        "o box\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 4\n",
    );
    let s = load_file(&obj).unwrap();
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.objects[0].triangles, 2);
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "d.obj",
        "o d\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\nl 1 2\n",
    );
    let s = load_file(&obj).unwrap();
    assert_eq!(s.triangles(), 1);
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("dropped 2 degenerate triangles ('d': 2)"))
    );
    assert!(s.warnings.iter().any(|w| w.contains("ignored 1 line/point elements")));
}

#[test]
fn obj_polylines_are_skipped_not_drawn() {
    // tobj, which read OBJ files until issue 38, drew a polyline of three
    // or more points as a triangle fan.
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "l.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nl 1 2 3 4\nf 2 4 3\np 1\n",
    );
    let s = load_file(&obj).unwrap();
    assert_eq!(s.triangles(), 1, "the face alone");
    assert_eq!(
        s.warnings,
        ["ignored 2 line/point elements ('l'/'p'): only faces are rendered"]
    );
}

#[test]
fn large_meshes_are_clustered_and_keep_every_triangle() {
    // One 20×20 grid (800 triangles) with a 100-triangle cluster budget.
    let mut text = String::from("o grid\n");
    for z in 0..=20 {
        for x in 0..=20 {
            text += &format!("v {x} 0 {z}\n");
        }
    }
    for z in 0..20 {
        for x in 0..20 {
            let v = |x: usize, z: usize| z * 21 + x + 1;
            text += &format!("f {} {} {} {}\n", v(x, z), v(x + 1, z), v(x + 1, z + 1), v(x, z + 1));
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "grid.obj", text);
    let s = load(
        &SceneSpec::File(obj),
        &LoadOptions {
            cluster_triangles: 100,
            ..LoadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(s.triangles(), 800);
    assert!(s.objects.len() >= 8, "{} clusters", s.objects.len());
    assert!(
        s.objects
            .iter()
            .all(|o| o.triangles <= 100 && o.name.starts_with("grid#"))
    );
    // Clusters tile the grid: their bounds together cover it, each a part.
    let area: f64 = s
        .objects
        .iter()
        .map(|o| o.bounds.extent().x * o.bounds.extent().z)
        .sum();
    assert!(area < 400.0 * 1.5, "clusters overlap too much: {area}");
}

#[test]
fn glb_instances_share_one_mesh_and_apply_node_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let (w, roots) = instanced_scene();
    let glb = write(dir.path(), "inst.glb", w.glb(&roots));
    let s = load_file(&glb).unwrap();
    // 3 cube instances (36) + strip (4) + triangle (1).
    assert_eq!(s.triangles(), 41);
    assert_eq!(s.objects.len(), 5);
    let cubes: Vec<_> = s.objects.iter().filter(|o| o.triangles == 12).collect();
    assert_eq!(cubes.len(), 3);
    assert!(
        cubes.windows(2).all(|w| w[0].mesh == w[1].mesh),
        "instances share one mesh"
    );
    let child = s.objects.iter().find(|o| o.name == "child").unwrap();
    // Parent scale 2 applies to the child's translation and size.
    assert_eq!(child.bounds.min, DVec3::new(2.0, 0.0, 0.0));
    assert_eq!(child.bounds.max, DVec3::new(4.0, 2.0, 2.0));
    let a = s.objects.iter().find(|o| o.name == "a").unwrap();
    assert_eq!(a.bounds.min, DVec3::new(10.0, 0.0, 0.0));

    let out = occlu(&["info", glb.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let v: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(v["triangles"], 41);
    assert_eq!(v["meshes"], 3, "one cube mesh, two primitives of the other");
}

#[test]
fn gltf_with_external_buffer_loads() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(json!({"mesh": m}));
    write(dir.path(), "my cube.bin", w.bin());
    let gltf = write(dir.path(), "cube.gltf", w.gltf_external(&[n], "my%20cube.bin"));
    assert_eq!(load_file(&gltf).unwrap().triangles(), 12);
}

#[test]
fn gltf_buffers_outside_the_models_folder_are_refused() {
    // A valid buffer one folder up, one in a subfolder, and a link out.
    let root = tempfile::tempdir().unwrap();
    let model_dir = root.path().join("model");
    std::fs::create_dir_all(model_dir.join("sub")).unwrap();
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(json!({"mesh": m}));
    write(root.path(), "outside.bin", w.bin());
    write(&model_dir.join("sub"), "inside.bin", w.bin());
    std::os::unix::fs::symlink(root.path().join("outside.bin"), model_dir.join("link.bin")).unwrap();
    let load = |uri: &str| load_file(&write(&model_dir, "m.gltf", w.gltf_external(&[n], uri)));
    assert_eq!(load("sub/inside.bin").unwrap().triangles(), 12);
    assert_eq!(load("./sub/inside.bin").unwrap().triangles(), 12);
    let outside = root.path().join("outside.bin");
    for (uri, why) in [
        ("../outside.bin", "leaves the model's folder"),
        ("sub/../../outside.bin", "leaves the model's folder"),
        ("%2E%2E/outside.bin", "leaves the model's folder"),
        (outside.to_str().unwrap(), "leaves the model's folder"),
        (&format!("file://{}", outside.display()), "is not a relative path"),
        ("link.bin", "through a link"),
    ] {
        let e = load(uri).err().unwrap_or_else(|| panic!("{uri} was read")).to_string();
        assert!(
            e.contains(why) && e.contains("buffer 0") && e.contains("--external-buffers") && !e.contains('\n'),
            "{uri}: {e}"
        );
    }
    // A model named without its folder, as `occlu info m.gltf` in the
    // folder names it: the link is followed no further (its folder is
    // `.`, not the empty path, which resolves to nothing), nor is a link
    // that leads nowhere.
    std::os::unix::fs::symlink(root.path().join("absent.bin"), model_dir.join("dangling.bin")).unwrap();
    for (uri, why) in [("link.bin", "through a link"), ("dangling.bin", "dangling.bin")] {
        write(&model_dir, "m.gltf", w.gltf_external(&[n], uri));
        let info = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
            .args(["info", "m.gltf"])
            .current_dir(&model_dir)
            .output()
            .unwrap();
        common::said_one_line(
            &info,
            2,
            &["m.gltf", "buffer 0", why],
            &format!("info m.gltf with {uri}"),
        );
        assert!(stdout(&info).is_empty(), "{uri}: {}", stdout(&info));
    }
    // Unless the user allows buffers elsewhere.
    let external = LoadOptions {
        external_buffers: true,
        ..LoadOptions::default()
    };
    for uri in [
        "../outside.bin",
        outside.to_str().unwrap(),
        &format!("file://{}", outside.display()),
    ] {
        let model = write(&model_dir, "m.gltf", w.gltf_external(&[n], uri));
        let scene = occlu::scene::load(&SceneSpec::File(model), &external).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(scene.triangles(), 12);
    }
}

#[test]
fn files_past_max_file_size_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(json!({"mesh": m}));
    // The buffer file is larger than the model file: bytes past the
    // buffer's declared length are allowed, and count.
    let mut bin = w.bin().to_vec();
    bin.resize(bin.len() + 8192, 0);
    let buffer = write(dir.path(), "cube.bin", &bin);
    let model = write(dir.path(), "m.gltf", w.gltf_external(&[n], "cube.bin"));
    let size = |path: &std::path::Path| std::fs::metadata(path).unwrap().len();
    let load_with = |max_file_size| {
        let options = LoadOptions {
            max_file_size,
            ..LoadOptions::default()
        };
        load(&SceneSpec::File(model.clone()), &options).map_err(|e| e.to_string())
    };
    assert!(load_with(size(&buffer)).is_ok());
    for (max, refused) in [(size(&buffer) - 1, "cube.bin"), (size(&model) - 1, "m.gltf")] {
        let e = load_with(max).unwrap_err();
        assert!(
            e.contains(refused) && e.contains("larger than") && e.contains("--max-file-size"),
            "{max}: {e}"
        );
    }
}

/// Loads a GLB with one cube primitive after `edit` changes its JSON.
fn edited_glb(edit: impl FnOnce(&mut GltfWriter)) -> Result<occlu::scene::Scene, occlu::scene::SceneError> {
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    w.mesh("cube", &[(&p, Some(&i), 4)]);
    w.node(json!({"mesh": 0}));
    edit(&mut w);
    let dir = tempfile::tempdir().unwrap();
    load_file(&write(dir.path(), "e.glb", w.glb(&[0])))
}

/// glTF requires a POSITION accessor's `min` and `max` to be its values'
/// extremes, and engines bound meshes by them: a file whose bounds leave
/// out vertices is told of (occlu bounds meshes by their vertices, so it
/// draws and culls them right), where they do by more than rounding
/// explains; each mesh once, however many nodes place it.
#[test]
fn vertices_beyond_the_bounds_a_gltf_declares_are_told_of() {
    let declared = |min: [f32; 3], max: [f32; 3]| {
        edited_glb(|w| {
            w.accessors[0]["min"] = json!(min);
            w.accessors[0]["max"] = json!(max);
        })
        .unwrap()
    };
    // The unit cube's own bounds, bounds off by less than a hundredth of
    // its size, and wider ones.
    assert!(declared([0.0; 3], [1.0; 3]).warnings.is_empty());
    assert!(declared([0.005, 0.0, -0.005], [1.0, 0.995, 1.0]).warnings.is_empty());
    assert!(declared([-1.0; 3], [2.0; 3]).warnings.is_empty());
    let short = declared([0.0; 3], [1.0, 0.5, 1.0]);
    assert_eq!(short.objects.len(), 1);
    assert_eq!(short.bounds.max, DVec3::ONE, "bounded by its vertices");
    assert_eq!(
        short.warnings,
        [
            "a mesh has vertices beyond the bounds its glTF accessor declares ('cube': y reaches 1 where its POSITION max says 0.5): occlu bounds meshes by their vertices, but an engine that takes the file's bounds may cull it while in view"
        ]
    );
    let below = declared([0.0, 0.0, 0.25], [1.0; 3]);
    assert!(
        below.warnings[0].contains("'cube': z reaches 0 where its POSITION min says 0.25"),
        "{:?}",
        below.warnings
    );
    // A second mesh with bounds too small, placed by two nodes: two
    // meshes, one named.
    let two = edited_glb(|w| {
        w.accessors[0]["max"] = json!([1.0, 1.0, 0.5]);
        let (p, i) = cube();
        let other = w.mesh("other", &[(&p, Some(&i), 4)]);
        let positions = w.meshes[other]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        w.accessors[positions]["min"] = json!([0.5, 0.0, 0.0]);
        let placed = [3.0, 6.0].map(|x| w.node(json!({"mesh": other, "translation": [x, 0.0, 0.0]})));
        w.nodes[0]["children"] = json!(placed);
    })
    .unwrap();
    assert_eq!(two.objects.len(), 3);
    assert_eq!(two.warnings.len(), 1, "{:?}", two.warnings);
    assert!(
        two.warnings[0].starts_with(
            "2 meshes have vertices beyond the bounds their glTF accessors declare (one of them, 'cube': z reaches 1 where its POSITION max says 0.5)"
        ),
        "{:?}",
        two.warnings
    );
}

/// A hostile-input review's finding: a node whose matrix flattened its
/// mesh to a line loaded without a word, and drew nothing. Flattened to a
/// plane, its faces are still drawn, and nothing is said.
#[test]
fn objects_a_transform_flattens_to_a_line_are_kept_and_warned_of() {
    let scaled = |scale: [f32; 3]| edited_glb(|w| w.nodes[0]["scale"] = json!(scale)).unwrap();
    assert!(scaled([1.0, 1e-3, 1.0]).warnings.is_empty());
    assert!(scaled([1.0, 0.0, 1.0]).warnings.is_empty());
    for line in [[1.0, 0.0, 0.0], [1.0, 1e-13, 1e-13]] {
        let flat = scaled(line);
        assert_eq!(flat.objects.len(), 1);
        assert_eq!(
            flat.warnings,
            ["'node0' is placed by a transform that flattens it to a line or a point: it draws nothing"]
        );
    }
    let two = edited_glb(|w| {
        w.nodes[0] = json!({"children": [1, 2, 3]});
        w.node(json!({"mesh": 0, "scale": [0.0, 0.0, 1.0]}));
        w.node(json!({"mesh": 0, "scale": [0.0, 2.0, 0.0], "translation": [5.0, 0.0, 0.0]}));
        w.node(json!({"mesh": 0}));
    })
    .unwrap();
    assert_eq!(
        two.warnings,
        [
            "2 meshes are placed by a transform that flattens them to a line or a point ('node2' the first): they draw nothing"
        ]
    );
}

#[test]
fn a_node_rotation_off_unit_length_is_normalised_as_its_cameras_are_and_the_zero_quaternion_refused() {
    let rotated = |rotation: [f32; 4]| edited_glb(|w| w.nodes[0]["rotation"] = json!(rotation));
    // A half turn about z, written unit and written 3 times too long: the
    // same cube, [-1, 0] × [-1, 0] × [0, 1], and only the long one warned of.
    let unit = rotated([0.0, 0.0, 1.0, 0.0]).unwrap();
    let long = rotated([0.0, 0.0, 3.0, 0.0]).unwrap();
    assert_eq!(long.bounds.min, unit.bounds.min);
    assert_eq!(long.bounds.max, unit.bounds.max);
    assert!(
        (unit.bounds.min - DVec3::new(-1.0, -1.0, 0.0)).abs().max_element() < 1e-6,
        "{:?}",
        unit.bounds
    );
    assert!(unit.warnings.is_empty(), "{:?}", unit.warnings);
    assert_eq!(
        long.warnings,
        ["normalised the rotations of 1 node: glTF requires unit quaternions, and theirs were not"]
    );
    let zero = rotated([0.0; 4])
        .expect_err("the zero quaternion rotates nothing")
        .to_string();
    assert!(
        zero.contains("node 0: rotation [0, 0, 0, 0] is not a rotation"),
        "{zero}"
    );
}

#[test]
fn extras_of_any_json_type_load() {
    for extras in [json!([1, 2]), json!("note"), json!(3), json!(null), json!({"k": true})] {
        let loaded = edited_glb(|w| {
            w.nodes[0]["extras"] = extras.clone();
            w.meshes[0]["extras"] = extras.clone();
            w.extra.insert("extras".into(), extras.clone());
        });
        assert_eq!(
            loaded.map(|s| s.triangles()).map_err(|e| e.to_string()),
            Ok(12),
            "extras {extras}"
        );
    }
}

#[test]
fn sparse_indices_must_rise_strictly_within_the_count_and_points_and_lines_are_skipped() {
    // The cube's eight corners, two of them replaced through a sparse
    // accessor whose indices are `indices`.
    let sparse = |indices: &[u32]| {
        edited_glb(|w| {
            let count = indices.len();
            let indices: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let values: Vec<u8> = [5.0f32, 0.0, 0.0, 0.0, 5.0, 0.0]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect();
            let (indices, values) = (w.view(&indices, 0), w.view(&values, 0));
            w.accessors[0]["sparse"] = json!({
                "count": count,
                "indices": {"bufferView": indices, "componentType": 5125},
                "values": {"bufferView": values},
            });
        })
        .map(|scene| scene.triangles())
        .map_err(|e| e.to_string())
    };
    assert_eq!(sparse(&[1, 2]), Ok(12));
    for (indices, fault) in [
        (&[2, 1][..], "do not rise strictly (1 after 2)"),
        (&[1, 1], "do not rise strictly (1 after 1)"),
        (&[1, 9], "name element 9 of 8"),
        // The gltf crate's reader counts one less than the count.
        (&[], "are none: a sparse accessor names at least one element"),
    ] {
        let error = sparse(indices).unwrap_err();
        assert!(
            error.ends_with(&format!("POSITION: sparse indices {fault}")),
            "{indices:?}: {error}"
        );
    }
    // A line primitive beside the triangles: skipped, and warned of.
    let scene = edited_glb(|w| {
        let (p, i) = cube();
        w.mesh("wire", &[(&p, Some(&i), 1)]);
        w.node(json!({"mesh": 1}));
        w.nodes[0]["children"] = json!([1]);
    });
    let scene = scene.unwrap();
    assert_eq!(scene.triangles(), 12);
    assert_eq!(
        scene.warnings,
        ["ignored 1 point or line primitive: they draw no depth"]
    );
}

#[test]
fn a_node_with_a_mesh_outside_the_scene_drawn_is_warned_of() {
    let scene = edited_glb(|w| {
        w.node(json!({"mesh": 0, "translation": [5, 0, 0]}));
    })
    .unwrap();
    assert_eq!(scene.triangles(), 12);
    assert_eq!(
        scene.warnings,
        ["ignored 1 node with a mesh outside the scene drawn (the default scene, or else the first)"]
    );
}

#[test]
fn bad_gltf_input_is_a_clear_error() {
    let msg = |r: Result<occlu::scene::Scene, occlu::scene::SceneError>| r.expect_err("must fail").to_string();
    // A model of lines alone draws nothing.
    let lines = msg(edited_glb(|w| w.meshes[0]["primitives"][0]["mode"] = json!(1)));
    assert!(lines.contains("the model has no triangles to render"), "{lines}");
    let required = msg(edited_glb(|w| {
        w.extra.insert("extensionsUsed".into(), json!(["EXT_unheard_of"]));
        w.extra.insert("extensionsRequired".into(), json!(["EXT_unheard_of"]));
    }));
    assert!(
        required.contains("EXT_unheard_of") && required.contains("Unsupported extension"),
        "{required}"
    );
    // A required extension of materials, textures, lights or metadata does
    // not affect visibility: it loads, known to gltf-json or not; one that
    // may change geometry is refused.
    let requiring = |extension: &str| {
        edited_glb(|w| {
            w.extra.insert("extensionsUsed".into(), json!([extension]));
            w.extra.insert("extensionsRequired".into(), json!([extension]));
        })
    };
    for extension in [
        "KHR_materials_unlit",
        "KHR_materials_variants",
        "EXT_texture_avif",
        "KHR_xmp_json_ld",
    ] {
        assert!(
            requiring(extension).is_ok(),
            "{extension}: {:?}",
            requiring(extension).err()
        );
    }
    for extension in ["MSFT_lod", "KHR_gaussian_splatting"] {
        let refused = msg(requiring(extension));
        assert!(
            refused.contains(extension) && refused.contains("Unsupported extension"),
            "{refused}"
        );
    }
    let range = msg(edited_glb(|w| {
        let (p, _) = cube();
        let bad = [0u32, 1, 99];
        w.meshes.clear();
        w.mesh("bad", &[(&p, Some(&bad), 4)]);
    }));
    assert!(range.contains("mesh 'bad': index 99"), "{range}");
    let nan = msg(edited_glb(|w| {
        w.meshes.clear();
        w.mesh(
            "nan",
            &[(&[[0.0, 0.0, 0.0], [1.0, f32::NAN, 0.0], [0.0, 1.0, 0.0]], None, 4)],
        );
    }));
    assert!(nan.contains("mesh 'nan': vertex 1 has a non-finite position"), "{nan}");
    let empty = msg(edited_glb(|w| {
        w.nodes.clear();
        w.node(json!({"name": "no mesh"}));
    }));
    assert!(empty.contains("no triangles"), "{empty}");

    let dir = tempfile::tempdir().unwrap();
    // Its length field reads "garb": far more than the file holds.
    let junk = write(dir.path(), "junk.glb", b"glTF\x02\0\0\0garbage");
    let junk = load_file(&junk).unwrap_err().to_string();
    assert!(junk.ends_with("but the file has 15: is it cut short?"), "{junk}");
    let junk = write(dir.path(), "junk.glb", b"glTF\x02\0\0\0\x0f\0\0\0bage");
    assert!(load_file(&junk).unwrap_err().to_string().contains("invalid glTF"));
    let text = write(
        dir.path(),
        "t.gltf",
        r#"{"asset": {"version": "2.0"}, "meshes": [{"primitives": []}]"#,
    );
    assert!(load_file(&text).unwrap_err().to_string().contains("invalid glTF"));
    // Neither a GLB nor JSON: said so, not as a JSON syntax error at byte 1.
    for (name, bytes) in [
        ("magic.glb", b"glTX\x02\0\0\0garbage".as_slice()),
        ("obj.glb", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
    ] {
        let e = load_file(&write(dir.path(), name, bytes)).unwrap_err().to_string();
        assert!(
            e.contains("neither a GLB") && !e.contains("line 1 column 1"),
            "{name}: {e}"
        );
    }
    // glTF JSON after a byte order mark, as some editors write it, loads.
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(json!({"mesh": m}));
    let bom = format!("\u{feff}{}", w.gltf_embedded(&[n]));
    assert_eq!(load_file(&write(dir.path(), "bom.gltf", bom)).unwrap().triangles(), 12);
}

#[test]
fn a_model_scaled_to_a_point_is_warned_of_as_such() {
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(json!({"mesh": m, "scale": [0.0, 0.0, 0.0], "translation": [3.0, 0.0, 0.0]}));
    let dir = tempfile::tempdir().unwrap();
    let scene = load_file(&write(dir.path(), "point.glb", w.glb(&[n]))).unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    let warning = &scene.warnings[0];
    assert!(
        warning.contains("one point ([3, 0, 0])") && warning.contains("no size") && !warning.contains("origin"),
        "{warning}"
    );
}

#[test]
fn bad_obj_input_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let msg = |name: &str, text: &str| load_file(&write(dir.path(), name, text)).unwrap_err().to_string();
    assert!(
        msg("nan.obj", "o n\nv 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")
            .contains("mesh 'n': vertex 1 has a non-finite position")
    );
    assert!(msg("range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n").contains("invalid OBJ"));
    assert!(msg("text.obj", "v 0 0 zero\nf 1 2 3\n").contains("invalid OBJ"));
    assert!(msg("empty.obj", "").contains("no triangles"));
    assert!(msg("points.obj", "v 0 0 0\np 1\n").contains("no triangles"));
    let missing = load_file(&dir.path().join("absent.obj")).unwrap_err().to_string();
    assert!(
        missing.contains("absent.obj") && missing.contains("No such file"),
        "{missing}"
    );
    let ply = load_file(&write(dir.path(), "m.ply", "ply")).unwrap_err().to_string();
    assert!(ply.contains("unsupported model format"));
}

#[test]
fn malformed_gltf_accessors_and_node_graphs_are_errors_not_panics() {
    let msg = |r: Result<occlu::scene::Scene, occlu::scene::SceneError>| r.expect_err("must fail").to_string();
    // Component types the index reader cannot take (it would panic).
    let float = msg(edited_glb(|w| w.accessors[1]["componentType"] = json!(5126)));
    assert!(
        float.contains("indices must be a Scalar accessor of [U8, U16, U32]"),
        "{float}"
    );
    // A stride shorter than the element (the reader would panic).
    let stride = msg(edited_glb(|w| w.buffer_views[0]["byteStride"] = json!(4)));
    assert!(
        stride.contains("byteStride 4 is smaller than its 12-byte elements"),
        "{stride}"
    );
    // An attribute naming a missing accessor (gltf-json's validator would panic).
    let missing = msg(edited_glb(|w| {
        w.meshes[0]["primitives"][0]["attributes"]["POSITION"] = json!(9)
    }));
    assert!(missing.contains("accessor 9 does not exist"), "{missing}");
    // A sparse accessor claiming a billion elements (would allocate 24 GB).
    let sparse = msg(edited_glb(|w| {
        let a = &mut w.accessors[0];
        a["count"] = json!(1_000_000_000u64);
        a.as_object_mut().unwrap().remove("bufferView");
        a["sparse"] =
            json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5125}, "values": {"bufferView": 0}});
    }));
    assert!(sparse.contains("do not fit the data the file holds"), "{sparse}");
    // Shared children: each level would double the scene.
    let dag = msg(edited_glb(|w| {
        w.nodes.clear();
        w.node(json!({"children": [1, 1]}));
        w.node(json!({"mesh": 0}));
    }));
    assert!(dag.contains("node 1 is reached twice"), "{dag}");
    // An index past u32, which gltf-json would keep as its low 32 bits
    // (mesh 0, the file's only mesh, drawn without a word).
    let wrapped = msg(edited_glb(|w| w.nodes[0]["mesh"] = json!(1u64 << 32)));
    assert!(wrapped.contains("`mesh` holds the index 4294967296"), "{wrapped}");
    let projective = msg(edited_glb(|w| {
        w.nodes[0]["matrix"] = json!([1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    }));
    assert!(projective.contains("matrix is not affine"), "{projective}");
    let scaled = msg(edited_glb(|w| w.nodes[0]["scale"] = json!([1e30, 1e30, 1e30])));
    assert!(scaled.contains("beyond ±1e18"), "{scaled}");
    // A camera whose type names a projection it does not carry, and
    // animation channels aimed at a node that does not exist or at no
    // property glTF defines (the gltf crate's readers would panic).
    let perspective = json!({"yfov": 1.0, "znear": 0.1});
    let camera = |w: &mut GltfWriter, camera: Value| {
        w.extra.insert("cameras".into(), json!([camera]));
        w.nodes[0]["camera"] = json!(0);
    };
    let mismatch = msg(edited_glb(|w| {
        camera(w, json!({"type": "orthographic", "perspective": perspective}))
    }));
    assert!(
        mismatch.contains("camera 0: its type is \"orthographic\" but it has no \"orthographic\" object"),
        "{mismatch}"
    );
    let unknown = msg(edited_glb(|w| {
        camera(w, json!({"type": "fisheye", "perspective": perspective}))
    }));
    assert!(unknown.contains("camera 0: its type is neither"), "{unknown}");
    let channel = |w: &mut GltfWriter, target: Value| {
        let times = w.floats(&[0.0, 1.0], "SCALAR");
        let moves = w.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0], "VEC3");
        w.extra.insert(
            "animations".into(),
            json!([{"samplers": [{"input": times, "output": moves}], "channels": [{"sampler": 0, "target": target}]}]),
        );
    };
    let absent = msg(edited_glb(|w| channel(w, json!({"node": 7, "path": "translation"}))));
    assert!(
        absent.contains("animation 0 channel 0: target node 7 does not exist (1 nodes)"),
        "{absent}"
    );
    let bogus = msg(edited_glb(|w| {
        camera(w, json!({"type": "perspective", "perspective": perspective}));
        channel(w, json!({"node": 0, "path": "bogus"}));
    }));
    assert!(
        bogus.contains("animation 0 channel 0: its target path is none of"),
        "{bogus}"
    );
}

/// A hostile-input review's finding: each camera is placed through its
/// chain of ancestors, so 60 000 nested cameras cost 1.8 G node transforms
/// (occlu ran out of memory); past the file's budget of node transforms,
/// the rest are left out, with a warning.
#[test]
fn cameras_nested_past_the_budget_of_node_transforms_are_left_out_with_a_warning() {
    let scene = edited_glb(|w| {
        w.extra.insert(
            "cameras".into(),
            json!([{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}]),
        );
        w.nodes[0]["children"] = json!([1]);
        for k in 1..=7000 {
            let mut node = json!({"camera": 0, "translation": [0.0, 0.0, 0.001]});
            if k < 7000 {
                node["children"] = json!([k + 1]);
            }
            w.node(node);
        }
    })
    .unwrap();
    let warned: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("node transforms"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", scene.warnings);
    // Node k's chain holds k + 1 nodes: 2 + 3 + ... + 6325 passes 20 M.
    assert!(
        warned[0]
            .contains("(node 6324) and those after it are left out: placing them passes the 20000000 node transforms"),
        "{}",
        warned[0]
    );
}

#[test]
fn obj_objects_with_the_same_name_in_different_places_stay_apart() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "dup.obj",
        "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 4 5 6\no a\nv 100 0 0\nv 101 0 0\nv 100 1 0\nf 7 8 9\n",
    );
    let s = load_file(&obj).unwrap();
    assert_eq!(s.objects.len(), 3);
    assert!(
        s.objects.iter().all(|o| o.bounds.extent().x <= 1.0),
        "no object spans both places"
    );
    let far = load_file(&write(dir.path(), "far.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"));
    assert!(far.unwrap_err().to_string().contains("lies beyond ±1e18"));
}

#[test]
fn a_glb_header_at_odds_with_its_file_or_another_gltf_version_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (mut w, roots) = instanced_scene();
    let glb = w.glb(&roots);
    let n = glb.len();
    let read = |name: &str, bytes: &[u8]| {
        load(
            &SceneSpec::File(write(dir.path(), name, bytes)),
            &LoadOptions::default(),
        )
    };
    let error = |name: &str, bytes: &[u8]| read(name, bytes).err().map(|e| e.to_string()).unwrap_or_default();
    let edited = |at: usize, value: u32| {
        let mut bytes = glb.clone();
        bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
        bytes
    };
    // Bytes past the length the header gives: the chunks are whole.
    let long = [glb.as_slice(), &[0; 16]].concat();
    let scene = read("long.glb", &long).unwrap();
    assert_eq!(scene.triangles(), 41);
    assert_eq!(
        scene.warnings,
        [format!(
            "the GLB header gives a length of {n} bytes, but the file has {}: its chunks were read by their own lengths",
            n + 16
        )]
    );
    let under = error("under.glb", &edited(8, 11));
    assert!(
        under.ends_with("invalid GLB: its header gives a length of 11 bytes, less than its own 12"),
        "{under}"
    );
    let over = error("over.glb", &edited(8, n as u32 + 8));
    let expected = format!(
        "invalid GLB: its header gives a length of {} bytes, but the file has {n}: is it cut short?",
        n + 8
    );
    assert!(over.ends_with(&expected), "{over}");
    let convert = "gltf-pipeline -i IN -o OUT converts glTF 1.0 to 2.0";
    let binary_1 = error("v1.glb", &edited(4, 1));
    assert!(
        binary_1.ends_with(&format!(
            "a GLB of container version 1, and occlu reads version 2 (glTF 2.0; {convert})"
        )),
        "{binary_1}"
    );
    let named = |version: &str| format!("written for glTF '{version}', and occlu reads glTF 2.0 ({convert})");
    let needs = |least: &str| Some(format!("needs glTF '{least}' at least, and occlu reads glTF 2.0"));
    for (asset, expected) in [
        (json!({"version": "3.0"}), Some(named("3.0"))),
        (json!({"version": "1.0"}), Some(named("1.0"))),
        (json!({"version": "2.1"}), None),
        (json!({"version": "2.0", "minVersion": "2.0"}), None),
        (json!({"version": "2.0", "minVersion": "2.1"}), needs("2.1")),
        // Not MAJOR.MINOR, or a major past what 32 bits hold: only 2 is read.
        (json!({"version": "3"}), Some(named("3"))),
        (json!({"version": "1.0.3"}), Some(named("1.0.3"))),
        (json!({"version": "99999999999.0"}), Some(named("99999999999.0"))),
        (json!({"version": " 2.0"}), Some(named(" 2.0"))),
        (
            json!({"version": "2.0", "minVersion": "2.99999999999"}),
            needs("2.99999999999"),
        ),
        (
            json!({"version": "2.0", "minVersion": "2"}),
            Some("its minVersion '2' is not a glTF version such as 2.0".into()),
        ),
    ] {
        w.extra.insert("asset".into(), asset.clone());
        match (read("version.glb", &w.glb(&roots)), expected) {
            (Ok(scene), None) => assert_eq!(scene.triangles(), 41),
            (Err(e), Some(expected)) => assert!(e.to_string().ends_with(&expected), "{asset}: {e}"),
            (result, expected) => panic!("{asset}: {:?}, expected {expected:?}", result.map(|s| s.triangles())),
        }
    }
    // A glTF 1.0 file (its meshes an object, not an array) is named as one,
    // not as JSON of the wrong shape.
    let old = error(
        "old.gltf",
        br#"{"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}}}"#,
    );
    assert!(old.ends_with(&named("1.0")), "{old}");
}
