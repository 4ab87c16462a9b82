//! Every loader's results, pinned: each built-in scene and each model in
//! ../shared/models is loaded and summarised in one line (triangles,
//! objects, parts, closed parts, a hash of every object and part, and the
//! geometry's fingerprint), compared with the lines below. They were
//! written by the loaders as they stood before loading was made fast
//! (issue 38); a change to parsing, validation, the closed-solid test or
//! the clustering that changes what a scene holds shows here, model by
//! model. The built-in scenes always run; the shared models skip, saying
//! so, where that folder is absent.
//!
//! A deliberate change to what loaders produce rewrites the lines: the
//! failure message prints the whole table as it now stands.

mod common;

use std::fmt::Write as _;

use common::{cannot_run, shared_models, shared_models_dir};
use occlu::report::Fingerprint;
use occlu::scene::{DEFAULT_CLUSTER_TRIANGLES, LoadOptions, Scene, SceneSpec, load};

/// Built-in scenes and the cluster budget each is loaded with.
const BUILTIN: &[(&str, u32)] = &[
    ("city", DEFAULT_CLUSTER_TRIANGLES),
    ("city:blocks=2", DEFAULT_CLUSTER_TRIANGLES),
    ("city:blocks=2,movers=40", DEFAULT_CLUSTER_TRIANGLES),
    ("city:blocks=1,seed=7", 64),
    ("forest", DEFAULT_CLUSTER_TRIANGLES),
    ("forest:trees=200,seed=3", 32),
    ("office", DEFAULT_CLUSTER_TRIANGLES),
    ("office:rooms=2,seed=3", 32),
];

const BUILTIN_DIGESTS: &[&str] = &[
    "city | 1480192 triangles, 2625 objects, 2348 meshes, 2625 parts, 2625 closed | ed2a42e14a4b88da e17049c13b87eb1c",
    "city:blocks=2 | 101080 triangles, 186 objects, 155 meshes, 186 parts, 186 closed | 0298cd91058ce9e0 b6c462295023a28c",
    "city:blocks=2,movers=40 | 112280 triangles, 226 objects, 155 meshes, 226 parts, 226 closed | ff401ae8398a488e b04cbc33edd54452",
    "city:blocks=1,seed=7 @64 | 26320 triangles, 548 objects, 492 meshes, 48 parts, 48 closed | dbe6fbd4fa348d5a cdda60044daa414c",
    "forest | 495952 triangles, 2016 objects, 2016 meshes, 2016 parts, 2016 closed | 0d1a03b2c7ec4409 c30a4d4ab1ed1e17",
    "forest:trees=200,seed=3 @32 | 49744 triangles, 2384 objects, 2384 meshes, 216 parts, 216 closed | c90bf1f44df7cc22 2ad91e88f90718be",
    "office | 108996 triangles, 721 objects, 721 meshes, 721 parts, 721 closed | 2f20ba67bc1dbd86 753348661d7dd84f",
    "office:rooms=2,seed=3 @32 | 4356 triangles, 186 objects, 186 meshes, 33 parts, 33 closed | c18af39b8cc65ac3 6701123650971ae8",
];

/// Shared models loaded with a small cluster budget too, besides the
/// default one: splits many levels deep.
const SMALL_BUDGET: &[(&str, u32)] = &[("bunny.obj", 256), ("two-cylinder-engine.glb", 256)];

const SHARED_DIGESTS: &[&str] = &[
    "bunny.obj | 69451 triangles, 32 objects, 32 meshes, 1 parts, 0 closed | fd518c8d192473f4 01c414474831142c",
    "bunny.obj @256 | 69451 triangles, 512 objects, 512 meshes, 1 parts, 0 closed | dfcb6034fba8ab9e ec2347013f5a14b4",
    "den-haag.obj | 41183 triangles, 1992 objects, 1992 meshes, 1991 parts, 1988 closed | 7f4994ca60d75ca1 d617b36e75b1c8c3",
    "kenney-city/building-garage.glb | 195 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 435a6342c5740c21 46d7e2a413e27375",
    "kenney-city/building-small-a.glb | 440 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 7e88a877e26d1c25 e66129987c162189",
    "kenney-city/building-small-b.glb | 566 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | af0fe8c788d86288 3c6df034438563cf",
    "kenney-city/building-small-c.glb | 817 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 692ae69b22e50fb8 51aab2706ca7800d",
    "kenney-city/building-small-d.glb | 438 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 83c9d2359a863d64 296c73f94b5460a9",
    "kenney-city/grass-trees-tall.glb | 472 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 9e5920611b648b4c 3c2fbe71092cf42a",
    "kenney-city/grass-trees.glb | 380 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | bfa45692f6376a50 355457a492b328f1",
    "kenney-city/grass.glb | 30 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | cda75cc755f9aef7 dc71fd4cf320ba2e",
    "kenney-city/pavement-fountain.glb | 152 triangles, 1 objects, 1 meshes, 1 parts, 1 closed | 02e675e2a6d9e467 681932b27e7c07fb",
    "kenney-city/pavement.glb | 20 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | b4ed77b9ddc2fc13 3fbd7fcb530ecbb9",
    "kenney-city/road-corner.glb | 126 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 7a03f0ae62d4f74e ed6390dac1abb299",
    "kenney-city/road-intersection.glb | 152 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 8f7ba5e078bc7dff 2605da132cca1d2d",
    "kenney-city/road-split.glb | 100 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 2151d8a0f8503d2e 74e81ac6164fdfad",
    "kenney-city/road-straight-lightposts.glb | 185 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 7bd7fc52666434c5 a55359b53d83c851",
    "kenney-city/road-straight.glb | 53 triangles, 1 objects, 1 meshes, 1 parts, 0 closed | 324b1b4eab52501f c85a5fcfad1d6131",
    "teapot.obj | 6320 triangles, 2 objects, 2 meshes, 1 parts, 0 closed | 2d168a5e4ab5e875 2c355649a4007459",
    "two-cylinder-engine.glb | 110336 triangles, 124 objects, 43 meshes, 115 parts, 26 closed | e631417e1118c3ee 95cf44c985845a01",
    "two-cylinder-engine.glb @256 | 110336 triangles, 657 objects, 392 meshes, 115 parts, 26 closed | f189755fda2e707c 8cb5b015d2857fc5",
];

/// One line that changes when anything the scene holds changes: counts in
/// the open, and two hashes: of every part (name, closed) and object (name,
/// mesh, part, triangles, index range, bounds to a millionth of the
/// scene's size, so that the last bits of a built-in scene's sin and cos
/// do not count), with the up axis and warnings; and the geometry's
/// [`Fingerprint::of_scene`] (vertices, indices, transforms; a built-in
/// scene's floats excepted).
fn digest(label: &str, scene: &Scene) -> String {
    let mut text = format!("up {}\n", scene.up.axis);
    for warning in &scene.warnings {
        let _ = writeln!(text, "warning {warning}");
    }
    for part in &scene.parts {
        let _ = writeln!(text, "part {} closed {}", part.name, part.closed);
    }
    let unit = scene.bounds.extent().max_element().max(f64::MIN_POSITIVE) * 1e-6;
    let quantized = |v: glam::DVec3| (v / unit).round().as_i64vec3().to_array();
    for object in &scene.objects {
        let mesh = &scene.meshes[object.mesh as usize];
        let _ = writeln!(
            text,
            "object {} mesh {} part {} triangles {} indices {}+{} bounds {:?} {:?}",
            object.name,
            object.mesh,
            object.part,
            object.triangles,
            mesh.first_index,
            mesh.index_count,
            quantized(object.bounds.min),
            quantized(object.bounds.max)
        );
    }
    format!(
        "{label} | {} triangles, {} objects, {} meshes, {} parts, {} closed | {:016x} {:016x}",
        scene.triangles(),
        scene.objects.len(),
        scene.meshes.len(),
        scene.parts.len(),
        scene.parts.iter().filter(|p| p.closed).count(),
        Fingerprint::of(text.as_bytes()).fnv1a,
        Fingerprint::of_scene(scene).fnv1a
    )
}

/// `actual` equals `expected` line for line; otherwise a message naming
/// each line that differs, then the whole table as it stands.
fn compare(what: &str, actual: &[String], expected: &[&str]) {
    let differing: Vec<String> = (0..actual.len().max(expected.len()))
        .filter(|&i| actual.get(i).map(String::as_str) != expected.get(i).copied())
        .map(|i| {
            format!(
                "  expected {}\n  now      {}",
                expected.get(i).unwrap_or(&"(nothing)"),
                actual.get(i).map_or("(nothing)", String::as_str)
            )
        })
        .collect();
    let table: String = actual.iter().map(|line| format!("    {line:?},\n")).collect();
    assert!(
        differing.is_empty(),
        "{what}: {} lines differ from the loaders' pinned results:\n{}\nthe table now:\n{table}",
        differing.len(),
        differing.join("\n")
    );
}

fn load_with(spec: SceneSpec, cluster_triangles: u32) -> Scene {
    let options = LoadOptions {
        cluster_triangles,
        ..LoadOptions::default()
    };
    load(&spec, &options).unwrap_or_else(|e| panic!("{e}"))
}

fn label(name: &str, cluster_triangles: u32) -> String {
    if cluster_triangles == DEFAULT_CLUSTER_TRIANGLES {
        name.to_string()
    } else {
        format!("{name} @{cluster_triangles}")
    }
}

#[test]
fn builtin_scenes_load_as_before() {
    let actual: Vec<String> = BUILTIN
        .iter()
        .map(|&(spec, budget)| {
            let scene = load_with(SceneSpec::Builtin(spec.into()), budget);
            digest(&label(spec, budget), &scene)
        })
        .collect();
    compare("built-in scenes", &actual, BUILTIN_DIGESTS);
}

#[test]
fn shared_models_load_as_before() {
    let dir = shared_models_dir();
    if !dir.is_dir() {
        cannot_run(&format!("no real models at {} (../shared/models)", dir.display()));
        return;
    }
    let mut actual = Vec::new();
    for (model, _) in shared_models(&dir) {
        let name = model.strip_prefix(&dir).unwrap().to_string_lossy().into_owned();
        let budgets = SMALL_BUDGET
            .iter()
            .filter(|(file, _)| *file == name)
            .map(|&(_, budget)| budget);
        for budget in std::iter::once(DEFAULT_CLUSTER_TRIANGLES).chain(budgets) {
            let scene = load_with(SceneSpec::File(model.clone()), budget);
            actual.push(digest(&label(&name, budget), &scene));
        }
    }
    compare("shared models", &actual, SHARED_DIGESTS);
}
