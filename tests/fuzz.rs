//! Fuzz-style tests of everything that reads user files: seeded random
//! mutations of valid OBJ, glTF, GLB and camera-path inputs, and inputs
//! generated from each format's grammar with hostile numbers, go through the
//! loaders. Every input must end in a model or a clear error, never a panic;
//! what loads must be usable (finite bounds, a hierarchy, finite cameras).
//!
//! Bounded and reproducible: a fixed seed and a fixed number of inputs per
//! corpus entry. A failing input is written to the temporary directory and
//! named in the failure, so it can be replayed.

mod common;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use common::THREE_OBJECTS_OBJ;
use common::gltf_writer::instanced_scene;
use glam::{DAffine3, DVec3};
use occlu::camera::path::CameraPath;
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::report::Fingerprint;
use occlu::rng::Rng;
use occlu::scene::{DEFAULT_CLUSTER_TRIANGLES, LoadOptions, Scene, SceneBuilder, load_bytes};

/// Mutated inputs per corpus entry.
const MUTANTS: u32 = 5000;
/// Grammar-generated inputs per format.
const GENERATED: u32 = 5000;

/// Numbers that break parsers and arithmetic.
const HOSTILE_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "3.4e38",
    "1e19",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "2147483648",
    "18446744073709551615",
    "99999999999999999999999",
    "0.5",
    "1e",
    "-",
    "",
];

/// Bytes and tokens that break structure.
const HOSTILE_TOKENS: &[&str] = &[
    "\0", "\n", "\r", "{", "}", "[", "]", ",", ":", "\"", "/", "\\", "null", "[]", "{}", "\"\"", "-1", "#", "f ", "v ",
    "o ", "g ", "1//", "é", "\u{FEFF}",
];

fn pick<'a>(rng: &mut Rng, list: &[&'a str]) -> &'a str {
    list[rng.int(0, list.len() as u32 - 1) as usize]
}

fn position(rng: &mut Rng, len: usize) -> usize {
    if len == 0 { 0 } else { rng.int(0, len as u32) as usize }
}

/// One to four random edits: bit flips, deletions, duplications, hostile
/// tokens, numbers replaced by hostile ones, splices from another input.
fn mutate(rng: &mut Rng, input: &[u8], other: &[u8]) -> Vec<u8> {
    let mut out = input.to_vec();
    for _ in 0..rng.int(1, 4) {
        let at = position(rng, out.len());
        match rng.int(0, 6) {
            0 if !out.is_empty() => {
                let i = at.min(out.len() - 1);
                out[i] ^= 1 << rng.int(0, 7);
            }
            1 => {
                let end = (at + rng.int(1, 16) as usize).min(out.len());
                out.drain(at..end);
            }
            2 => {
                let end = (at + rng.int(1, 64) as usize).min(out.len());
                let chunk = out[at..end].to_vec();
                let to = position(rng, out.len());
                out.splice(to..to, chunk);
            }
            3 => {
                let token = pick(rng, HOSTILE_TOKENS).as_bytes().to_vec();
                out.splice(at..at, token);
            }
            4 => replace_number(rng, &mut out, at),
            5 => out.truncate(at),
            _ => {
                let from = position(rng, other.len());
                let end = (from + rng.int(1, 64) as usize).min(other.len());
                out.splice(at..at, other[from..end].iter().copied());
            }
        }
    }
    out
}

/// Replaces the first number at or after `from` with a hostile one.
fn replace_number(rng: &mut Rng, text: &mut Vec<u8>, from: usize) {
    let Some(start) = text[from..].iter().position(u8::is_ascii_digit).map(|i| i + from) else {
        return;
    };
    let is_number = |b: &u8| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'-' | b'+');
    let end = text[start..]
        .iter()
        .position(|b| !is_number(b))
        .map_or(text.len(), |i| i + start);
    let number = pick(rng, HOSTILE_NUMBERS).as_bytes().to_vec();
    text.splice(start..end, number);
}

/// Runs `load` on `input`; a panic fails the test, naming a file that holds
/// the input.
fn must_not_panic(kind: &str, case: u32, input: &[u8], load: impl FnOnce(&[u8])) {
    if catch_unwind(AssertUnwindSafe(|| load(input))).is_err() {
        let saved = std::env::temp_dir().join(format!("occlu-fuzz-{kind}-{case}.bin"));
        std::fs::write(&saved, input).expect("the failing input is saved");
        panic!("{kind} input {case} panicked; it is saved in {}", saved.display());
    }
}

/// Loads a model from bytes; what loads must have finite bounds and a
/// hierarchy that covers every object.
fn load_model(dir: &Path, file_name: &str, bytes: &[u8]) -> Result<(), String> {
    let scene = load_bytes(&dir.join(file_name), bytes, &LoadOptions::default()).map_err(|e| e.to_string())?;
    assert!(scene.bounds.min.is_finite() && scene.bounds.max.is_finite());
    assert!(scene.objects.iter().all(|o| o.triangles > 0));
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    assert_eq!(hierarchy.objects.len(), scene.objects.len());
    Ok(())
}

/// Parses a path; what parses must give finite cameras for every frame
/// sampled.
fn load_path(bytes: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes);
    let path = CameraPath::parse(&text, "fuzz").map_err(|e| e.to_string())?;
    for frame in [0, 1, path.frames / 2, path.frames.saturating_sub(1)] {
        let camera = path.camera(frame, 4.0 / 3.0);
        assert!(camera.eye.is_finite() && camera.rotation.is_finite() && camera.fov_y.is_finite());
    }
    Ok(())
}

/// Every error names the input it is about (the file, or the path's
/// source, each named `fuzz`). It may quote the input's line breaks: the
/// CLI shows it escaped to one line (`text::one_line`, applied once where
/// text is shown).
fn check_error(result: Result<(), String>, errors: &mut u32) {
    if let Err(message) = result {
        assert!(message.contains("fuzz"), "an error that names no input: {message}");
        *errors += 1;
    }
}

/// Mutants of every corpus entry, with the outcome counts for sanity.
fn fuzz_corpus(kind: &str, corpus: &[Vec<u8>], seed: u64, load: &dyn Fn(&[u8]) -> Result<(), String>) -> (u32, u32) {
    let mut rng = Rng::new(seed);
    let (mut loaded, mut errors) = (0, 0);
    for (k, input) in corpus.iter().enumerate() {
        // The seed input itself must load.
        load(input).unwrap_or_else(|e| panic!("{kind} corpus entry {k} does not load: {e}"));
        let other = &corpus[(k + 1) % corpus.len()];
        for i in 0..MUTANTS {
            let case = k as u32 * MUTANTS + i;
            let mutant = mutate(&mut rng, input, other);
            must_not_panic(kind, case, &mutant, |m| {
                let result = load(m);
                loaded += u32::from(result.is_ok());
                check_error(result, &mut errors);
            });
        }
    }
    (loaded, errors)
}

fn obj_corpus() -> Vec<Vec<u8>> {
    let rich = "# normals, texture coordinates, negative indices, polygons, materials\n\
        mtllib missing.mtl\no a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvt 0 0\nvn 0 0 1\n\
        usemtl red\nf 1/1/1 2/1/1 3/1/1 4/1/1\ng b\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf -3 -2 -1\n\
        l 1 2\np 3\ns off\nf 1//1 2//1 5//1\n";
    vec![THREE_OBJECTS_OBJ.as_bytes().to_vec(), rich.as_bytes().to_vec()]
}

#[test]
fn mutated_obj_files_load_or_fail_naming_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let (loaded, errors) = fuzz_corpus("obj", &obj_corpus(), 1, &|b| load_model(dir.path(), "fuzz.obj", b));
    // Both outcomes occur: the mutations neither break everything nor nothing.
    assert!(loaded > 100 && errors > 100, "loaded {loaded}, errors {errors}");
}

#[test]
fn mutated_gltf_and_glb_files_load_or_fail_naming_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let (w, roots) = instanced_scene();
    let gltf = [w.gltf_embedded(&roots).into_bytes()];
    let (loaded, errors) = fuzz_corpus("gltf", &gltf, 2, &|b| load_model(dir.path(), "fuzz.gltf", b));
    assert!(loaded > 20 && errors > 100, "gltf: loaded {loaded}, errors {errors}");
    let glb = [w.glb(&roots)];
    let (loaded, errors) = fuzz_corpus("glb", &glb, 3, &|b| load_model(dir.path(), "fuzz.glb", b));
    assert!(loaded > 20 && errors > 100, "glb: loaded {loaded}, errors {errors}");
}

fn path_corpus() -> Vec<Vec<u8>> {
    let sample = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/paths/city-corner.json")).unwrap();
    let frames = br#"{"frames": 5, "near": 0.01, "up": [0, 0, 1], "interpolation": "linear", "keyframes": [
        {"time": -1, "position": [1e6, 0, 0], "target": [0, 0, 0], "up": [0, 1, 0]},
        {"time": 3, "position": [0, 1, 0], "direction": [0, -1, 0]}]}"#;
    vec![sample, frames.to_vec()]
}

#[test]
fn mutated_camera_paths_parse_or_fail_naming_the_input() {
    let (loaded, errors) = fuzz_corpus("path", &path_corpus(), 4, &load_path);
    assert!(loaded > 20 && errors > 100, "loaded {loaded}, errors {errors}");
}

/// A number: usually plain, hostile in one of `odds` cases.
fn number(rng: &mut Rng, odds: u32, lo: f64, hi: f64) -> String {
    if rng.int(1, odds) == 1 {
        pick(rng, HOSTILE_NUMBERS).to_string()
    } else {
        format!("{}", rng.range(lo, hi))
    }
}

/// How often an element is hostile: half the inputs are clean apart from
/// rare slips, so some load and the loaders' checks after parsing run too.
fn odds(rng: &mut Rng) -> u32 {
    if rng.int(0, 1) == 0 { 200 } else { 8 }
}

/// Random OBJ text from the format's grammar: vertices with hostile
/// coordinates (some with a w or a colour), texture coordinates, normals,
/// faces whose corners name them in and out of range (negative, zero,
/// huge), lines and points, objects, groups and materials, words apart by
/// any whitespace.
fn generated_obj(rng: &mut Rng) -> String {
    let odds = odds(rng);
    let mut text = String::new();
    let (mut vertices, mut texcoords, mut normals) = (0, 0, 0);
    let index = |rng: &mut Rng, count: u32| match rng.int(1, odds) {
        1 => pick(rng, HOSTILE_NUMBERS).to_string(),
        2 => format!("-{}", rng.int(1, 12)),
        _ => format!("{}", rng.int(1, count.max(1))),
    };
    for _ in 0..rng.int(1, 30) {
        let line = match rng.int(0, 15) {
            0..=4 => {
                vertices += 1;
                let extra = match rng.int(1, odds) {
                    1 => 1,
                    2 => 3,
                    _ => 0,
                };
                let numbers: Vec<String> = (0..3 + extra).map(|_| number(rng, odds, -1e3, 1e3)).collect();
                format!("v {}", numbers.join(" "))
            }
            5..=7 => {
                // Texture coordinates and normals named mostly where some were given.
                let form = match rng.int(0, 3) {
                    1 if texcoords == 0 && rng.int(1, odds) > 1 => 0,
                    2 if normals == 0 && rng.int(1, odds) > 1 => 0,
                    form => form,
                };
                let corners: Vec<String> = (0..rng.int(3, 5))
                    .map(|_| {
                        let v = index(rng, vertices);
                        match form {
                            0 => v,
                            1 => format!("{v}/{}", index(rng, texcoords)),
                            2 => format!("{v}//{}", index(rng, normals)),
                            _ => format!("{v}/{}/{}", rng.int(0, 3), rng.int(0, 3)),
                        }
                    })
                    .collect();
                format!("f {}", corners.join(" "))
            }
            8 => format!("o obj{}", rng.int(0, 3)),
            9 if rng.int(1, odds) == 1 => format!("g {}", pick(rng, HOSTILE_TOKENS)),
            9 => "g group".to_string(),
            10 => {
                texcoords += 1;
                format!("vt {} {}", number(rng, odds, 0.0, 1.0), number(rng, odds, 0.0, 1.0))
            }
            11 => {
                normals += 1;
                format!("vn 0 {} 1", number(rng, odds, -1.0, 1.0))
            }
            12 => {
                let points: Vec<String> = (0..rng.int(1, 4)).map(|_| index(rng, vertices)).collect();
                format!("{} {}", ["l", "p"][rng.int(0, 1) as usize], points.join(" "))
            }
            13 if rng.int(1, odds) == 1 => "usemtl".to_string(),
            13 => "usemtl red".to_string(),
            14 if vertices >= 4 => format!("f\u{a0}1 2\t3\u{b}{}", rng.int(1, 4)),
            _ => "# a comment".to_string(),
        };
        text += &line;
        text.push('\n');
    }
    text
}

/// Random path JSON: keyframes whose fields may be missing, hostile or of
/// the wrong shape.
fn generated_path(rng: &mut Rng) -> String {
    let odds = odds(rng);
    let vector = |rng: &mut Rng| {
        let n = if rng.int(1, odds) == 1 { rng.int(0, 4) } else { 3 };
        let parts: Vec<String> = (0..n).map(|_| number(rng, odds, -100.0, 100.0)).collect();
        format!("[{}]", parts.join(","))
    };
    let keys: Vec<String> = (0..rng.int(1, 5))
        .map(|k| {
            let time = if rng.int(1, odds) == 1 {
                number(rng, 1, 0.0, 0.0)
            } else {
                k.to_string()
            };
            let mut fields = vec![format!("\"time\": {time}"), format!("\"position\": {}", vector(rng))];
            let views = ["target", "direction", "orientation"];
            let view = views[rng.int(0, 2) as usize];
            let value = if view == "orientation" {
                let parts: Vec<String> = (0..4).map(|_| number(rng, odds, -1.0, 1.0)).collect();
                format!("[{}]", parts.join(","))
            } else {
                vector(rng)
            };
            fields.push(format!("\"{view}\": {value}"));
            if rng.int(1, odds) == 1 {
                fields.push(format!("\"up\": {}", vector(rng)));
            }
            if rng.int(0, 3) == 0 {
                fields.push(format!("\"fov_y_deg\": {}", number(rng, odds, 1.0, 170.0)));
            }
            format!("{{{}}}", fields.join(", "))
        })
        .collect();
    let count = if rng.int(1, odds) == 1 {
        pick(rng, HOSTILE_NUMBERS).to_string()
    } else {
        rng.int(1, 50).to_string()
    };
    let mut top = vec![
        format!("\"keyframes\": [{}]", keys.join(", ")),
        format!("\"frames\": {count}"),
    ];
    if rng.int(0, 2) == 0 {
        top.push(format!("\"near\": {}", number(rng, odds, 1e-3, 1.0)));
    }
    format!("{{{}}}", top.join(", "))
}

#[test]
fn generated_obj_and_path_inputs_load_or_fail_naming_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng::new(5);
    let (mut loaded, mut errors) = ([0; 2], [0; 2]);
    for case in 0..GENERATED {
        let obj = generated_obj(&mut rng);
        must_not_panic("generated-obj", case, obj.as_bytes(), |b| {
            let result = load_model(dir.path(), "fuzz.obj", b);
            loaded[0] += u32::from(result.is_ok());
            check_error(result, &mut errors[0]);
        });
        let path = generated_path(&mut rng);
        must_not_panic("generated-path", case, path.as_bytes(), |b| {
            let result = load_path(b);
            loaded[1] += u32::from(result.is_ok());
            check_error(result, &mut errors[1]);
        });
    }
    assert!(loaded.iter().all(|&n| n > 50), "loaded {loaded:?}, errors {errors:?}");
    assert!(errors.iter().all(|&n| n > 50), "loaded {loaded:?}, errors {errors:?}");
}

/// A scene as occlu built one from tobj's reading of an OBJ file until
/// issue 38 (tobj 4, its options and the merging of consecutive models of
/// one name as they were). `l` elements, which tobj drew as triangle fans
/// and occlu skips, stand here as faces of two corners: nothing drawn, an
/// object ended all the same.
fn scene_through_tobj(path: &Path, bytes: &[u8]) -> Result<Scene, String> {
    // A byte-order mark is no part of the first line (occlu's reader).
    let bytes = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes);
    // Lines end at "\r\n", "\n" or a lone "\r" (occlu's reader). A file
    // that is not UTF-8 occlu refuses whole: it goes to tobj as it is.
    let lines: Vec<Vec<u8>> = match std::str::from_utf8(bytes) {
        Ok(text) => {
            let unix = text.replace("\r\n", "\n").replace('\r', "\n");
            joined(unix.split('\n'))
                .iter()
                .map(|line| as_tobj_reads(line.as_bytes()))
                .collect()
        }
        Err(_) => vec![bytes.to_vec()],
    };
    let bytes = lines.join(&b'\n');
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // tobj's arithmetic on indices may overflow on hostile ones; a debug
    // build panics where the release one rejects the file.
    let read = catch_unwind(|| {
        tobj::load_obj_buf(&mut std::io::Cursor::new(&bytes), &options, |_| {
            Err(tobj::LoadError::GenericFailure)
        })
    });
    let (models, _) = read
        .map_err(|_| "tobj panicked".to_string())?
        .map_err(|e| e.to_string())?;
    let mut meshes: Vec<(String, Vec<DVec3>, Vec<u32>)> = Vec::new();
    for model in models {
        if meshes.last().is_none_or(|(name, ..)| *name != model.name) {
            meshes.push((model.name.clone(), Vec::new(), Vec::new()));
        }
        let (_, positions, indices) = meshes.last_mut().unwrap();
        let base = positions.len() as u32;
        positions.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| DVec3::new(p[0], p[1], p[2])),
        );
        indices.extend(model.mesh.indices.iter().map(|&i| base + i));
    }
    let mut builder = SceneBuilder::new(path.display().to_string(), DEFAULT_CLUSTER_TRIANGLES);
    for (name, positions, indices) in &meshes {
        let group = builder.add_mesh(name, positions, indices).map_err(|e| e.to_string())?;
        builder
            .add_object(name, &group, DAffine3::IDENTITY)
            .map_err(|e| e.to_string())?;
    }
    builder.finish().ok_or_else(|| "no triangles".to_string())
}

/// `lines` with each that ends in a backslash joined to the next, as
/// occlu's reader continues a statement (by the same tests: `str`'s
/// trimming, and a comment continuing nothing); tobj reads each line alone.
fn joined<'a>(lines: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut joined: Vec<String> = Vec::new();
    let mut open = false;
    for line in lines {
        let body = line
            .trim_end()
            .strip_suffix('\\')
            .filter(|_| !line.trim_start().starts_with('#'));
        match joined.last_mut().filter(|_| open) {
            Some(statement) => {
                statement.push(' ');
                statement.push_str(body.unwrap_or(line));
            }
            None => joined.push(body.unwrap_or(line).to_string()),
        }
        open = body.is_some();
    }
    joined
}

/// `line` written so that tobj reads it as occlu's reader does, where the
/// specification allows what tobj refused or misread: a lone carriage
/// return ends a line (the caller splits there), a statement may be
/// indented, a tab may follow `usemtl` and nothing need, and `vt` may give
/// u alone; and where occlu refuses what tobj read: a w that is not
/// finite.
fn as_tobj_reads(line: &[u8]) -> Vec<u8> {
    let Ok(text) = std::str::from_utf8(line) else {
        return line.to_vec();
    };
    let words: Vec<&str> = text.split_whitespace().collect();
    match words.as_slice() {
        ["l", ..] => b"f 1 2".to_vec(),
        ["vt", u] => format!("vt {u} 0").into_bytes(),
        ["usemtl"] => Vec::new(),
        // occlu refuses a w that is not finite (it would move the vertex
        // to the origin); tobj refuses a vertex it cannot read.
        ["v", _, _, _, w] if w.parse::<f64>().is_ok_and(|w| !w.is_finite()) => b"v unreadable".to_vec(),
        ["usemtl", names @ ..] => format!("usemtl {}", names.join(" ")).into_bytes(),
        _ => text.trim_start().as_bytes().to_vec(),
    }
}

/// What two loaders must agree on: every object, part and vertex, and the
/// warnings, but those of what the file drew nothing from (skipped `l`/`p`
/// elements, faces of one or two corners, unknown statements), which
/// tobj's reading does not give.
fn contents(scene: &Scene) -> String {
    let objects: Vec<String> = scene
        .objects
        .iter()
        .map(|o| format!("{} {} {} {} {:?}", o.name, o.mesh, o.part, o.triangles, o.bounds))
        .collect();
    let parts: Vec<String> = scene.parts.iter().map(|p| format!("{} {}", p.name, p.closed)).collect();
    let ours_alone = [
        "line/point elements",
        "free-form curve",
        "from a first corner that does not see all of the face",
        "of one or two corners",
        "whose statement OBJ does not define",
    ];
    let warnings: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| !ours_alone.iter().any(|o| w.contains(o)))
        .collect();
    format!("{objects:?} {parts:?} {warnings:?} {:?}", Fingerprint::of_scene(scene))
}

#[test]
fn obj_files_load_as_tobj_loaded_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("parity.obj");
    let mut rng = Rng::new(38);
    let corpus = obj_corpus();
    let mutants = (0..MUTANTS).map(|i| mutate(&mut rng, &corpus[i as usize % 2], &corpus[(i as usize + 1) % 2]));
    let mut inputs: Vec<Vec<u8>> = corpus.clone();
    inputs.extend(mutants.collect::<Vec<_>>());
    inputs.extend((0..GENERATED).map(|_| generated_obj(&mut rng).into_bytes()));
    let mut agreed = [0; 2];
    for (case, input) in inputs.iter().enumerate() {
        let ours = load_bytes(&path, input, &LoadOptions::default()).map_err(|e| e.to_string());
        let theirs = scene_through_tobj(&path, input);
        let text = String::from_utf8_lossy(input);
        match (&ours, &theirs) {
            (Ok(a), Ok(b)) => assert_eq!(contents(a), contents(b), "case {case}:\n{text}"),
            (Err(_), Err(_)) => {}
            _ => panic!(
                "case {case}: occlu {:?}, tobj {:?}:\n{text}",
                ours.map(|_| "loads"),
                theirs.map(|_| "loads")
            ),
        }
        agreed[usize::from(ours.is_ok())] += 1;
    }
    assert!(agreed.iter().all(|&n| n > 1000), "errors, loads: {agreed:?}");
    eprintln!("{agreed:?}");
}
