//! glTF 2.0 (`.gltf` with external or embedded buffers, and `.glb`) through
//! the gltf crate: the node hierarchy with its transforms, mesh instancing
//! (a mesh used by several nodes is validated and clustered once) and every
//! triangle primitive. Images are never decoded: visibility needs positions.

use std::collections::{HashMap, HashSet};
use std::path::{Component, Path};

use base64::Engine as _;
use glam::{DAffine3, DMat4, DVec3};
use gltf::mesh::Mode;

use super::cameras;
use super::draco::{self, DRACO, DracoStreams};
use super::gltf_json;
use super::instancing::{self, INSTANCING};
use super::memory;
use super::meshopt::{self, EXT_MESHOPT, KHR_MESHOPT};
use super::model::{MeshGroup, SceneBuilder};
use super::source::{LoadOptions, SceneError, read_model_file};
use crate::input::folder_of;
use crate::text;

/// Reads `bytes`, the glTF or GLB file `path`, into `builder`: its buffers,
/// an object for each mesh group of each node of its scene, its cameras
/// and camera animations, and warnings of what is ignored.
pub fn load(path: &Path, bytes: &[u8], options: &LoadOptions, builder: &mut SceneBuilder) -> Result<(), SceneError> {
    // glTF JSON may start with the byte order mark some editors write: it
    // is dropped before the JSON is read, here and for the buffers.
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    let (gltf, raw) = parse(path, bytes)?;
    if let Some((_, length)) = glb_header(bytes)
        && length < bytes.len()
    {
        builder.warn(format!(
            "the GLB header gives a length of {length} bytes, but the file has {}: its chunks were read by their own lengths",
            bytes.len()
        ));
    }
    warn_of_what_is_ignored(&gltf, builder);
    let (buffers, held_bytes) = load_buffers(path, &gltf, &raw, options, builder)?;
    let mut draco = draco_streams(&raw, &gltf, options).map_err(parse_error(path))?;
    let reached = add_node_trees(path, &gltf, &raw, &buffers, held_bytes, &mut draco, builder)?;
    let outside = gltf
        .nodes()
        .filter(|n| n.mesh().is_some() && !reached[n.index()])
        .count();
    if outside > 0 {
        builder.warn(format!(
            "ignored {} with a mesh outside the scene drawn (the default scene, or else the first)",
            text::count(outside, "node")
        ));
    }
    add_cameras(&gltf, &buffers, &reached, builder);
    Ok(())
}

/// A file's error at parsing, with the file named.
fn parse_error(path: &Path) -> impl Fn(String) -> SceneError + Copy + '_ {
    move |message| SceneError::Parse {
        path: path.into(),
        message,
    }
}

/// The document, validated, with the extensions occlu decodes itself
/// taken off its required list, and its JSON as written where one of them
/// is used (they are read from it; null otherwise); refused when it is not
/// glTF or is invalid.
fn parse(path: &Path, bytes: &[u8]) -> Result<(gltf::Gltf, serde_json::Value), SceneError> {
    let parse_error = parse_error(path);
    let invalid = |e: gltf::Error| parse_error(format!("invalid glTF: {}", summarise(&e)));
    // glTF is a GLB (binary, starting with its magic) or JSON (an object,
    // perhaps after the byte order mark some editors write): anything else
    // (an OBJ named .glb, a GLB with a wrong magic) is said to be neither,
    // not reported as a JSON syntax error at its first byte.
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    if !bytes.starts_with(b"glTF") && first != Some(&b'{') {
        return Err(parse_error(
            "not glTF: neither a GLB (which starts with the bytes 'glTF') nor glTF JSON (an object, starting with '{')"
                .into(),
        ));
    }
    if let Some((version, length)) = glb_header(bytes) {
        if version != 2 {
            return Err(parse_error(format!(
                "a GLB of container version {version}, and occlu reads version 2 (glTF 2.0; {CONVERT})"
            )));
        }
        if length < 12 {
            return Err(parse_error(format!(
                "invalid GLB: its header gives a length of {length} bytes, less than its own 12"
            )));
        }
        if length > bytes.len() {
            return Err(parse_error(format!(
                "invalid GLB: its header gives a length of {length} bytes, but the file has {}: is it cut short?",
                bytes.len()
            )));
        }
    }
    // Text the crate would read wrong, or at a cost out of proportion to
    // it, is refused first (a GLB whose JSON cannot be found is left to
    // the crate, which names what is wrong).
    let counts = match gltf_json::text(bytes) {
        Ok(text) => gltf_json::census(&text).map_err(parse_error)?,
        Err(_) => gltf_json::JsonCounts::default(),
    };
    counts.check_as_structs(memory::available()).map_err(parse_error)?;
    // gltf-json's validator indexes primitive accessors without a bounds
    // check, so those are checked first; validation then also refuses files
    // that require an extension occlu does not read. A file of another glTF
    // version is named so, whether or not it reads as glTF 2.0.
    let unvalidated = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| {
        let document = gltf_json::text(bytes).and_then(|text| gltf_json::parsed::<serde_json::Value>(&text));
        let asset = document.map(|json| json["asset"].clone()).unwrap_or_default();
        let version = asset["version"].as_str().unwrap_or("2.0");
        unreadable_version(version, asset["minVersion"].as_str()).map_or_else(|| invalid(e), parse_error)
    })?;
    let asset = &unvalidated.document.as_json().asset;
    if let Some(message) = unreadable_version(&asset.version, asset.min_version.as_deref()) {
        return Err(parse_error(message));
    }
    check_primitive_accessors(unvalidated.document.as_json()).map_err(parse_error)?;
    check_cameras_and_channels(unvalidated.document.as_json()).map_err(parse_error)?;
    let listed = |extension: &str| unvalidated.extensions_used().any(|e| e == extension);
    let text = gltf_json::text(bytes).map_err(parse_error)?;
    let sites = gltf_json::parsed(&text).map_err(parse_error)?;
    if let Some((site, extension)) = undeclared_use(&sites, listed) {
        return Err(parse_error(format!(
            "{site} uses {extension}, but extensionsUsed does not list {extension}, as glTF requires"
        )));
    }
    // The JSON is read as written where the file uses an extension read
    // from it.
    let raw = match READ_FROM_JSON.iter().any(|e| listed(e)) {
        true => {
            counts.check_as_value(memory::available()).map_err(parse_error)?;
            gltf_json::parsed(&text).map_err(parse_error)?
        }
        false => serde_json::Value::Null,
    };
    let draco_decoded = draco::decoded_accessors(&raw).map_err(parse_error)?;
    let mut json = unvalidated.document.into_json();
    json.extensions_required
        .retain(|e| !DECODED.contains(&e.as_str()) && !NO_GEOMETRY.iter().any(|kind| e.starts_with(kind)));
    let document = validated(json, &draco_decoded).map_err(invalid)?;
    let gltf = gltf::Gltf {
        document,
        blob: unvalidated.blob,
    };
    Ok((gltf, raw))
}

/// The first part of a document (of its `sites`) that carries an extension
/// occlu reads from the JSON ([`READ_FROM_JSON`]) which `listed` says its
/// `extensionsUsed` does not list, as a JSON path, and that extension.
/// Such a file is refused by name: read without its extension, an instanced
/// node would be drawn once, and a compressed primitive, buffer view or
/// buffer would fail on the data it lacks, or draw the fallback in its
/// place.
fn undeclared_use(sites: &gltf_json::ExtensionSites, listed: impl Fn(&str) -> bool) -> Option<(String, &'static str)> {
    const MESHOPT: [&str; 2] = [EXT_MESHOPT, KHR_MESHOPT];
    let carried = |site: &gltf_json::Site, extensions: &[&'static str]| {
        let names = &site.extensions.0;
        extensions
            .iter()
            .copied()
            .find(|&e| !listed(e) && names.iter().any(|n| n == e))
    };
    let in_list = |key: &str, sites: &[gltf_json::Site], extensions: &[&'static str]| {
        let mut sites = sites.iter().enumerate();
        sites.find_map(|(k, site)| Some((format!("{key}[{k}]"), carried(site, extensions)?)))
    };
    let primitives = sites
        .meshes
        .iter()
        .enumerate()
        .find_map(|(m, mesh)| in_list(&format!("meshes[{m}].primitives"), &mesh.primitives, &[DRACO]));
    primitives
        .or_else(|| in_list("nodes", &sites.nodes, &[INSTANCING]))
        .or_else(|| in_list("bufferViews", &sites.buffer_views, &MESHOPT))
        .or_else(|| in_list("buffers", &sites.buffers, &MESHOPT))
}

/// The document `json`, validated as the gltf crate validates it, except
/// that the accessors `draco_decoded` (by index), whose data Draco streams
/// hold, need no buffer view.
fn validated(json: gltf::json::Root, draco_decoded: &HashSet<u64>) -> Result<gltf::Document, gltf::Error> {
    use gltf::json::validation::{Error, Validate};
    let mut problems = Vec::new();
    json.validate(&json, gltf::json::Path::new, &mut |path, problem| {
        problems.push((path(), problem))
    });
    let decoded = |path: &gltf::json::Path| {
        path.as_str()
            .strip_prefix("accessors[")
            .and_then(|rest| rest.strip_suffix("].bufferView")?.parse().ok())
            .is_some_and(|a| draco_decoded.contains(&a))
    };
    problems.retain(|(path, problem)| !(matches!(problem, Error::Missing) && decoded(path)));
    match problems.is_empty() {
        true => Ok(gltf::Document::from_json_without_validation(json)),
        false => Err(gltf::Error::Validation(problems)),
    }
}

/// A GLB's header: its container version, and the length it gives for
/// the whole file. None for glTF JSON, or a file too short to hold one.
fn glb_header(bytes: &[u8]) -> Option<(u32, usize)> {
    let [v0, v1, v2, v3, l0, l1, l2, l3] = *bytes.strip_prefix(b"glTF")?.first_chunk::<8>()?;
    let length = u32::from_le_bytes([l0, l1, l2, l3]);
    Some((u32::from_le_bytes([v0, v1, v2, v3]), length as usize))
}

/// How to make a glTF 1.0 file one occlu reads.
const CONVERT: &str = "gltf-pipeline -i IN -o OUT converts glTF 1.0 to 2.0";

/// Why occlu cannot read a file written for glTF `version` that needs
/// `min_version` at least: the specification's check (section 3.2) that a
/// reader supports the file's major version, and its minimum one. occlu
/// reads 2.0: a version whose major (what comes before its first dot) is
/// not written `2`, or a minimum version other than 2.0, is refused. None
/// for glTF 2.0 and its minor versions.
fn unreadable_version(version: &str, min_version: Option<&str>) -> Option<String> {
    if version.split('.').next() != Some("2") {
        return Some(format!(
            "written for glTF '{version}', and occlu reads glTF 2.0 ({CONVERT})"
        ));
    }
    let least = min_version?;
    let digits = |part: &str| !part.is_empty() && part.bytes().all(|b| b.is_ascii_digit());
    match least.split_once('.') {
        Some(("2", minor)) if digits(minor) && minor.bytes().all(|b| b == b'0') => None,
        Some((major, minor)) if digits(major) && digits(minor) => {
            Some(format!("needs glTF '{least}' at least, and occlu reads glTF 2.0"))
        }
        _ => Some(format!("its minVersion '{least}' is not a glTF version such as 2.0")),
    }
}

/// Warns of what the file holds and occlu does not draw as the file means
/// it: skins and morph targets, points and lines.
fn warn_of_what_is_ignored(gltf: &gltf::Gltf, builder: &mut SceneBuilder) {
    if gltf.skins().next().is_some()
        || gltf
            .meshes()
            .flat_map(|m| m.primitives())
            .any(|p| p.morph_targets().next().is_some())
    {
        builder.warn("skins and morph targets are ignored: meshes are drawn in their rest pose".into());
    }
    let points_and_lines = gltf
        .meshes()
        .flat_map(|m| m.primitives())
        .filter(|p| !draws_triangles(p.mode()))
        .count();
    if points_and_lines > 0 {
        builder.warn(format!(
            "ignored {}: they draw no depth",
            text::count(points_and_lines, "point or line primitive")
        ));
    }
}

/// Whether a primitive of `mode` draws triangles, not points or lines.
fn draws_triangles(mode: Mode) -> bool {
    matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)
}

/// Adds an object for each mesh group of each node that has a mesh,
/// depth-first over the node trees of the default scene (or the first),
/// or, with no scene, of every node that is nobody's child; the nodes
/// reached. A mesh used by several nodes is loaded once.
fn add_node_trees(
    path: &Path,
    gltf: &gltf::Gltf,
    raw: &serde_json::Value,
    buffers: &[Vec<u8>],
    held_bytes: u64,
    draco: &mut DracoStreams,
    builder: &mut SceneBuilder,
) -> Result<Vec<bool>, SceneError> {
    let parse_error = parse_error(path);
    let read = |index: usize, what: &str, types: &[gltf::accessor::DataType], dimensions| {
        let accessor = gltf
            .accessors()
            .nth(index)
            .ok_or_else(|| format!("{what}: accessor {index} does not exist"))?;
        check_accessor(&accessor, what, types, dimensions, buffers)?;
        read_vectors::<4>(&accessor, buffers).ok_or_else(|| format!("{what}: data lies outside its buffer"))
    };
    // Instances share accessors freely, and a compressed view of them may
    // decode a thousand times its bytes, so a few bytes could place
    // millions of objects: a file's instances together may be no more than
    // the buffer bytes it holds could as plain translations,
    // DECODED_PER_FILE_BYTE times over.
    let most_instances = DECODED_PER_FILE_BYTE.saturating_mul(held_bytes) / 12;
    let (mut instances_placed, mut not_unit_instances) = (0u64, 0);
    let scene = gltf.default_scene().or_else(|| gltf.scenes().next());
    let roots: Vec<gltf::Node> = match &scene {
        Some(scene) => scene.nodes().collect(),
        // No scene: every node that is nobody's child is a root.
        None => {
            let children: HashSet<usize> = gltf.nodes().flat_map(|n| n.children().map(|c| c.index())).collect();
            gltf.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    let mut mesh_groups: HashMap<usize, Vec<MeshGroup>> = HashMap::new();
    // glTF requires disjoint trees; the validator does not check it, and a
    // node reached twice (shared children, a cycle) would multiply the
    // scene or never end, so it is an error.
    let mut reached = vec![false; gltf.nodes().len()];
    let mut stack: Vec<(gltf::Node, DMat4)> = roots.into_iter().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut not_unit = 0;
    let mut loose = LooseBounds::new(raw);
    while let Some((node, parent)) = stack.pop() {
        let index = node.index();
        if std::mem::replace(&mut reached[index], true) {
            return Err(parse_error(format!(
                "node {index} is reached twice: glTF node hierarchies must be trees"
            )));
        }
        let (local, normalised) = local_transform(&node).map_err(parse_error)?;
        not_unit += usize::from(normalised);
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            if let std::collections::hash_map::Entry::Vacant(slot) = mesh_groups.entry(mesh.index()) {
                slot.insert(load_mesh(path, &mesh, buffers, draco, &mut loose, builder)?);
            }
            let node_name = node
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("node{index}"));
            let groups = &mesh_groups[&mesh.index()];
            let transform = DAffine3::from_mat4(world);
            // An instanced node draws its instances, and not itself.
            let placed: Vec<(String, DAffine3)> = match instancing::of_node(raw, index, &read).map_err(parse_error)? {
                Some((list, normalised)) => {
                    not_unit_instances += normalised;
                    instances_placed += list.len() as u64;
                    if instances_placed > most_instances {
                        return Err(parse_error(format!(
                            "its nodes place more than {most_instances} instances ({INSTANCING}): \
                             {DECODED_PER_FILE_BYTE} times what its {held_bytes} bytes of buffers hold \
                             as translations"
                        )));
                    }
                    list.iter()
                        .enumerate()
                        .map(|(i, instance)| (format!("{node_name}[{i}]"), transform * *instance))
                        .collect()
                }
                None => vec![(node_name, transform)],
            };
            for (node_name, transform) in placed {
                for (k, group) in groups.iter().enumerate() {
                    let name = if groups.len() > 1 {
                        format!("{node_name}/{k}")
                    } else {
                        node_name.clone()
                    };
                    builder
                        .add_object(&name, group, transform)
                        .map_err(|error| SceneError::Geometry {
                            path: path.into(),
                            error,
                        })?;
                }
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if not_unit > 0 {
        builder.warn(format!(
            "normalised the rotations of {}: glTF requires unit quaternions, and theirs were not",
            text::count(not_unit, "node")
        ));
    }
    if not_unit_instances > 0 {
        builder.warn(format!(
            "normalised the rotations of {}: {INSTANCING} requires unit quaternions, and theirs were not",
            text::count(not_unit_instances, "instance")
        ));
    }
    loose.warn(builder);
    if scene.is_none()
        && let Some(lost) = gltf.nodes().find(|n| n.mesh().is_some() && !reached[n.index()])
    {
        return Err(parse_error(format!(
            "node {} is in a cycle of child links and reachable from no root",
            lost.index()
        )));
    }
    Ok(reached)
}

/// How far from unit length a node's rotation may be and be used as
/// written: well beyond the rounding of a unit quaternion written in f32.
const UNIT_ROTATION_TOLERANCE: f64 = 1e-5;

/// A node's transform relative to its parent, in f64, and whether its
/// rotation was normalised; refused when it is not finite in f32, not
/// affine, or holds a rotation that is none (the zero quaternion). glTF
/// requires unit quaternions; one off unit length (a hand-edited file)
/// would scale and shear the mesh, composed as written, where the cameras
/// take it normalised (cameras.rs), so it is normalised here too.
fn local_transform(node: &gltf::Node) -> Result<(DMat4, bool), String> {
    let index = node.index();
    let mut transform = node.transform();
    let mut normalised = false;
    if let gltf::scene::Transform::Decomposed { rotation, .. } = &mut transform {
        let length = rotation.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>().sqrt();
        if length == 0.0 {
            return Err(format!(
                "node {index}: rotation [0, 0, 0, 0] is not a rotation: glTF requires a unit quaternion"
            ));
        }
        if (length - 1.0).abs() > UNIT_ROTATION_TOLERANCE {
            *rotation = rotation.map(|v| (f64::from(v) / length) as f32);
            normalised = true;
        }
    }
    let matrix = transform.matrix();
    if matrix.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("node {index}: transform is not finite in f32"));
    }
    if matrix.iter().map(|column| column[3]).ne([0.0, 0.0, 0.0, 1.0]) {
        return Err(format!("node {index}: matrix is not affine"));
    }
    Ok((DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))), normalised))
}

/// The file's cameras and camera animations (of the nodes `reached`), with
/// a warning for each animation that moves no camera.
fn add_cameras(gltf: &gltf::Gltf, buffers: &[Vec<u8>], reached: &[bool], builder: &mut SceneBuilder) {
    let check = |accessor: &gltf::Accessor, what: &str, types: &[gltf::accessor::DataType], dims| {
        check_accessor(accessor, what, types, dims, buffers)
    };
    let cameras::Found {
        cameras,
        animations,
        warnings,
    } = cameras::read(gltf, buffers, reached, &check);
    for warning in warnings {
        builder.warn(warning);
    }
    let unused: Vec<&str> = animations
        .iter()
        .filter(|a| a.camera.is_none())
        .map(|a| a.name.as_str())
        .collect();
    if !unused.is_empty() {
        builder.warn(format!(
            "{} animations move no camera and are not replayed (occlu animates no objects): {}",
            unused.len(),
            unused.join(", ")
        ));
    }
    builder.set_cameras(cameras, animations);
}

/// Extensions the loader reads itself, which gltf-json does not know.
const DECODED: [&str; 5] = ["KHR_mesh_quantization", EXT_MESHOPT, KHR_MESHOPT, DRACO, INSTANCING];

/// Those of them read from the document's JSON as written.
const READ_FROM_JSON: [&str; 4] = [EXT_MESHOPT, KHR_MESHOPT, DRACO, INSTANCING];

/// Kinds of extension that change no geometry, by the prefix of their
/// names: materials, textures, lights and metadata, which a visibility
/// benchmark never reads. A file that requires one loads whether or not
/// gltf-json knows it (it knows `EXT_texture_webp` but not
/// `EXT_texture_avif`); any other it does not know stays refused, since it
/// may move, add or hide geometry (`MSFT_lod`).
const NO_GEOMETRY: [&str; 7] = [
    "KHR_materials_",
    "KHR_texture_",
    "EXT_texture_",
    "MSFT_texture_",
    "KHR_lights_",
    "EXT_lights_",
    "KHR_xmp",
];

/// A validation error in one line: each kind of problem once, with how often
/// it occurs and where first ("195 × Missing data (first at
/// accessors[0].bufferView)"), not one entry per element.
fn summarise(e: &gltf::Error) -> String {
    let gltf::Error::Validation(problems) = e else {
        return e.to_string();
    };
    let mut kinds: Vec<(String, usize, String)> = Vec::new();
    for (path, problem) in problems {
        let problem = problem.to_string();
        match kinds.iter_mut().find(|(kind, _, _)| *kind == problem) {
            Some((_, count, _)) => *count += 1,
            None => kinds.push((problem, 1, path.to_string())),
        }
    }
    let parts: Vec<String> = kinds
        .iter()
        .map(|(kind, count, first)| match count {
            1 => format!("{first}: {kind}"),
            n => format!("{n} × {kind} (first at {first})"),
        })
        .collect();
    parts.join("; ")
}

/// Every buffer's bytes, with meshopt-compressed views (EXT or KHR) decoded into
/// their placeholder buffers, and how many of those bytes the file holds
/// (before decoding); each file read is noted in `builder`.
fn load_buffers(
    path: &Path,
    gltf: &gltf::Gltf,
    raw: &serde_json::Value,
    options: &LoadOptions,
    builder: &mut SceneBuilder,
) -> Result<(Vec<Vec<u8>>, u64), SceneError> {
    let parse_error = parse_error(path);
    let compressed = match gltf.extensions_used().any(|e| e == EXT_MESHOPT || e == KHR_MESHOPT) {
        true => Some(meshopt::compressed_views(raw).map_err(parse_error)?),
        false => None,
    };
    // Decoded data may be several times the file's size; past a bound on
    // that, the file is refused before anything is allocated for it.
    let most = DECODED_PER_FILE_BYTE.saturating_mul(options.max_file_size);
    let too_much = |what: String| {
        parse_error(format!(
            "{what} decompressed bytes, beyond the {most} that --max-file-size allows ({DECODED_PER_FILE_BYTE} per byte)"
        ))
    };
    if let Some(views) = &compressed {
        let total = views
            .iter()
            .map(|v| v.decoded_length() as u64)
            .fold(0u64, u64::saturating_add);
        if total > most {
            return Err(too_much(format!("its compressed buffer views declare {total}")));
        }
    }
    let placeholder = |index| compressed.is_some() && meshopt::is_placeholder(raw, index);
    // The buffers with data of their own first, placeholders empty.
    let mut buffers = Vec::new();
    for buffer in gltf.buffers() {
        buffers.push(if placeholder(buffer.index()) {
            Vec::new()
        } else {
            buffer_data(path, gltf, &buffer, options, builder)?
        });
    }
    let held = buffers.iter().map(|b| b.len() as u64).sum();
    let Some(views) = &compressed else {
        return Ok((buffers, held));
    };
    // Every view's stream lies in data the file holds, and claims no more
    // than its length can hold (`meshopt::compressed_views`), before any
    // placeholder is allocated: what they claim is bounded by real bytes.
    for v in views {
        v.stream(&buffers).map_err(parse_error)?;
    }
    for buffer in gltf.buffers().filter(|b| placeholder(b.index())) {
        // Filled by decoding, and only as far as the views decoded into
        // it reach (their sum is bounded above), whatever it declares.
        let into: Vec<_> = views.iter().filter(|v| v.target == buffer.index()).collect();
        let length = into
            .iter()
            .map(|v| v.target_offset.saturating_add(v.decoded_length()))
            .max()
            .unwrap_or(0);
        // It holds what its views decode to and the padding between them:
        // a view placed far out would have zeros allocated for nothing.
        let decoded = into
            .iter()
            .map(|v| v.decoded_length())
            .fold(0usize, usize::saturating_add);
        let room = decoded.saturating_add(VIEW_PADDING * into.len());
        if length > room {
            return Err(parse_error(format!(
                "buffer {}: its {} views decode to {decoded} bytes but reach byte {length}: more than \
                 padding between them",
                buffer.index(),
                into.first().map_or(EXT_MESHOPT, |v| v.extension)
            )));
        }
        if length > buffer.length() {
            return Err(parse_error(format!(
                "buffer {}: its compressed views decode to {length} bytes, more than the {} it declares",
                buffer.index(),
                buffer.length()
            )));
        }
        if length as u64 > most {
            return Err(too_much(format!("buffer {} needs {length}", buffer.index())));
        }
        let zeros = &mut buffers[buffer.index()];
        zeros
            .try_reserve_exact(length)
            .map_err(|e| parse_error(format!("buffer {}: {e}", buffer.index())))?;
        zeros.resize(length, 0);
    }
    meshopt::decode(&mut buffers, views, options.max_file_size).map_err(parse_error)?;
    Ok((buffers, held))
}

/// Bytes of padding a decoded buffer may hold per view beside the views'
/// data: glTF aligns a view to at most 4 bytes, exporters to 16.
const VIEW_PADDING: usize = 16;

/// Decompressed bytes allowed per byte --max-file-size allows: meshopt
/// rarely shrinks real geometry more than 4:1.
const DECODED_PER_FILE_BYTE: u64 = 8;

/// Accessor indices of every primitive must exist.
fn check_primitive_accessors(json: &gltf::json::Root) -> Result<(), String> {
    let count = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets = primitive
                .targets
                .iter()
                .flatten()
                .flat_map(|t| [&t.positions, &t.normals, &t.tangents].into_iter().flatten());
            let mut used = primitive
                .attributes
                .values()
                .chain(primitive.indices.iter())
                .chain(targets);
            if let Some(bad) = used.find(|a| a.value() >= count) {
                return Err(format!(
                    "mesh {m} primitive {p}: accessor {} does not exist ({count} accessors)",
                    bad.value()
                ));
            }
        }
    }
    Ok(())
}

/// What gltf-json's validator lets through and the gltf crate's readers
/// then unwrap: a camera whose `type` names a projection it does not
/// carry (or none glTF defines), and an animation channel whose target
/// node does not exist or whose path is none glTF defines.
fn check_cameras_and_channels(json: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    for (c, camera) in json.cameras.iter().enumerate() {
        let (kind, carried) = match camera.type_ {
            Checked::Valid(Type::Perspective) => ("perspective", camera.perspective.is_some()),
            Checked::Valid(Type::Orthographic) => ("orthographic", camera.orthographic.is_some()),
            Checked::Invalid => {
                return Err(format!(
                    "camera {c}: its type is neither \"perspective\" nor \"orthographic\""
                ));
            }
        };
        if !carried {
            return Err(format!(
                "camera {c}: its type is \"{kind}\" but it has no \"{kind}\" object"
            ));
        }
    }
    let nodes = json.nodes.len();
    for (a, animation) in json.animations.iter().enumerate() {
        for (k, channel) in animation.channels.iter().enumerate() {
            let target = &channel.target;
            if target.node.value() >= nodes {
                return Err(format!(
                    "animation {a} channel {k}: target node {} does not exist ({nodes} nodes)",
                    target.node.value()
                ));
            }
            if let Checked::Invalid = target.path {
                return Err(format!(
                    "animation {a} channel {k}: its target path is none of translation, rotation, scale and weights"
                ));
            }
        }
    }
    Ok(())
}

/// Checks that an accessor holds elements of `dimensions` components of
/// one of `types`.
fn check_kind(
    accessor: &gltf::Accessor,
    what: &str,
    types: &[gltf::accessor::DataType],
    dimensions: gltf::accessor::Dimensions,
) -> Result<(), String> {
    let (data_type, dims) = (accessor.data_type(), accessor.dimensions());
    if !types.contains(&data_type) || dims != dimensions {
        return Err(format!(
            "{what} must be a {dimensions:?} accessor of {types:?} (found {data_type:?} {dims:?})"
        ));
    }
    Ok(())
}

/// Checks an accessor before the gltf reader touches it: the reader trusts
/// strides, component types and counts, and would panic, or allocate for the
/// declared count, on bad ones.
fn check_accessor(
    accessor: &gltf::Accessor,
    what: &str,
    types: &[gltf::accessor::DataType],
    dimensions: gltf::accessor::Dimensions,
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    check_kind(accessor, what, types, dimensions)?;
    let count = accessor.count();
    if count == 0 {
        return Err(format!("{what} accessor is empty"));
    }
    let too_many = match accessor.view() {
        Some(view) => {
            if let Some(stride) = view.stride().filter(|&s| s < accessor.size()) {
                return Err(format!(
                    "{what}: byteStride {stride} is smaller than its {}-byte elements",
                    accessor.size()
                ));
            }
            count
                .checked_mul(accessor.size())
                .is_none_or(|bytes| bytes > view.length())
        }
        // Validation lets only the accessors a Draco stream fills lack both:
        // such an accessor cannot be read as anything else.
        None if accessor.sparse().is_none() => {
            return Err(format!(
                "{what}: accessor {} holds no data of its own (a Draco stream fills it), so it cannot be read here",
                accessor.index()
            ));
        }
        // A sparse accessor without data of its own: its count still cannot
        // sensibly exceed the bytes the file carries.
        None => count > buffers.iter().map(Vec::len).sum(),
    };
    if too_many {
        return Err(format!("{what}: {count} elements do not fit the data the file holds"));
    }
    if let Some(sparse) = accessor.sparse()
        && (sparse.count() > count
            || sparse.indices().view().stride().is_some()
            || sparse.values().view().stride().is_some())
    {
        return Err(format!("{what}: malformed sparse storage"));
    }
    if let Some(sparse) = accessor.sparse() {
        check_sparse_indices(&sparse, count, buffers).map_err(|fault| format!("{what}: sparse indices {fault}"))?;
    }
    Ok(())
}

/// Whether a sparse accessor's indices are as the specification requires:
/// strictly increasing, each below the accessor's `count`. The gltf crate's
/// reader applies a value only when its walk through the elements reaches
/// its index, so one out of order, repeated or past the end was left out
/// without a word, and the mesh loaded wrong.
fn check_sparse_indices(
    sparse: &gltf::accessor::sparse::Sparse,
    count: usize,
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    use gltf::accessor::sparse::IndexType;
    let indices = sparse.indices();
    let size = match indices.index_type() {
        IndexType::U8 => 1,
        IndexType::U16 => 2,
        IndexType::U32 => 4,
    };
    // The specification asks at least one (the gltf crate's reader counts
    // one less).
    if sparse.count() == 0 {
        return Err("are none: a sparse accessor names at least one element".into());
    }
    let view = indices.view();
    let bytes = sparse
        .count()
        .checked_mul(size)
        .and_then(|length| Some((indices.offset().checked_add(length)?, length)))
        .filter(|&(end, _)| end <= view.length())
        .and_then(|(_, length)| {
            let start = view.offset().checked_add(indices.offset())?;
            buffers
                .get(view.buffer().index())?
                .get(start..start.checked_add(length)?)
        })
        .ok_or("lie outside their buffer view")?;
    let mut last: Option<u32> = None;
    for word in bytes.chunks_exact(size) {
        let index = word.iter().rev().fold(0, |value, &byte| value << 8 | u32::from(byte));
        if index as usize >= count {
            return Err(format!("name element {index} of {count}"));
        }
        if let Some(last) = last.filter(|&last| index <= last) {
            return Err(format!("do not rise strictly ({index} after {last})"));
        }
        last = Some(index);
    }
    Ok(())
}

/// One mesh group per triangle primitive of the mesh; those stored as
/// written whose vertices reach beyond their declared bounds counted in
/// `loose`.
fn load_mesh(
    path: &Path,
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
    draco: &mut DracoStreams,
    loose: &mut LooseBounds<'_>,
    builder: &mut SceneBuilder,
) -> Result<Vec<MeshGroup>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    let mesh_name = mesh
        .name()
        .map_or_else(|| format!("mesh{}", mesh.index()), str::to_string);
    let mut groups = Vec::new();
    for primitive in mesh.primitives() {
        let element = format!("mesh '{mesh_name}' primitive {}", primitive.index());
        let error = |what: String| SceneError::Parse {
            path: path.into(),
            message: format!("{element}: {what}"),
        };
        // Points and lines draw no depth (warned of, with their count).
        let mode = primitive.mode();
        if !draws_triangles(mode) {
            continue;
        }
        let accessor = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| error("has no POSITION attribute".into()))?;
        // Integer types: KHR_mesh_quantization.
        let types = [DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16];
        check_kind(&accessor, "POSITION", &types, Dimensions::Vec3).map_err(error)?;
        // `stored`: the positions are the values the file stores, not
        // Draco's decoding (rounded by its quantization: [`LooseBounds`]).
        let (positions, triangles, stored) =
            match draco.decode(mesh.index(), primitive.index(), buffers, accessor.data_type()) {
                Some(decoded) => {
                    if accessor.sparse().is_some() {
                        return Err(error(format!(
                            "POSITION has sparse storage, which {DRACO} forbids an accessor it fills"
                        )));
                    }
                    let decoded = decoded.map_err(error)?;
                    let coordinate = coordinate(&accessor);
                    let positions = decoded
                        .positions
                        .iter()
                        .map(|p| DVec3::from(p.map(&coordinate)))
                        .collect();
                    (positions, triangle_list(mode, &decoded.stream), false)
                }
                None => {
                    check_accessor(&accessor, "POSITION", &types, Dimensions::Vec3, buffers).map_err(error)?;
                    if let Some(indices) = primitive.indices() {
                        let types = [DataType::U8, DataType::U16, DataType::U32];
                        check_accessor(&indices, "indices", &types, Dimensions::Scalar, buffers).map_err(error)?;
                    }
                    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                    let positions: Vec<DVec3> = read_vectors::<3>(&accessor, buffers)
                        .ok_or_else(|| error("POSITION data lies outside its buffer".into()))?
                        .into_iter()
                        .map(DVec3::from)
                        .collect();
                    let stream: Vec<u32> = match reader.read_indices() {
                        Some(indices) => indices.into_u32().collect(),
                        None if primitive.indices().is_some() => {
                            return Err(error("index data lies outside its buffer".into()));
                        }
                        None => (0..positions.len() as u32).collect(),
                    };
                    let declared = primitive.indices().map_or(positions.len(), |i| i.count());
                    if positions.len() != accessor.count() || stream.len() != declared {
                        return Err(error("accessor data is shorter than its declared count".into()));
                    }
                    let triangles = triangle_list(mode, &stream);
                    (positions, triangles, true)
                }
            };
        let name = if mesh.primitives().len() > 1 {
            format!("{mesh_name}/{}", primitive.index())
        } else {
            mesh_name.clone()
        };
        if stored {
            loose.check(&name, &accessor, &positions);
        }
        let group = builder
            .add_mesh(&name, &positions, &triangles)
            .map_err(|error| SceneError::Geometry {
                path: path.into(),
                error,
            })?;
        groups.push(group);
    }
    Ok(groups)
}

/// Primitives whose vertices reach beyond the bounds their POSITION
/// accessor declares. glTF requires `min` and `max` there, equal to the
/// values stored (after any sparse substitution; `normalized` does not
/// apply to them), and engines take them for a mesh's bounds: where a
/// vertex lies beyond them, such an engine may cull the mesh while part of
/// it is in view. occlu bounds meshes by their vertices; it says so, naming
/// one of them. Values an encoder rounded are not checked (Draco's
/// quantization, over a range it chose, perhaps the whole scene's;
/// meshopt's exponential filter): exporters measure bounds before that
/// rounding, as this repository's compressed fixtures show (theirs lie
/// 7e-6 and 3e-5 inside vertices near 0.83).
struct LooseBounds<'a> {
    /// The document's JSON as written, which says which buffer views
    /// meshopt's filters rounded (null where no meshopt extension is used).
    document: &'a serde_json::Value,
    count: usize,
    one: Option<String>,
}

/// How far beyond a declared bound a vertex may lie and be taken as on it:
/// this share of the bounds' largest coordinate, as a bound written from
/// the f64 positions an exporter rounded to f32 differs from the stored
/// extreme by at most 6e-8 of it...
const BOUNDS_ROUNDING: f64 = 1e-6;
/// ...and this share of the vertices' largest extent: a bound off by less
/// moves a mesh's culling by less than a pixel wherever its extent spans
/// fewer than a hundred, and an exporter's error worth telling of is far
/// larger.
const BOUNDS_SLACK: f64 = 0.01;

impl<'a> LooseBounds<'a> {
    fn new(document: &'a serde_json::Value) -> Self {
        LooseBounds {
            document,
            count: 0,
            one: None,
        }
    }

    /// Counts mesh `name` (a primitive, as occlu names it) if a vertex of
    /// `positions` (read through `accessor`, as stored) lies beyond the
    /// bounds the accessor declares, by more than [`BOUNDS_ROUNDING`] and
    /// [`BOUNDS_SLACK`] allow; bounds the file does not give (or not as
    /// three numbers each) say nothing.
    fn check(&mut self, name: &str, accessor: &gltf::Accessor, positions: &[DVec3]) {
        let declared = |bound: Option<serde_json::Value>| -> Option<[f64; 3]> {
            let values = bound?
                .as_array()?
                .iter()
                .map(serde_json::Value::as_f64)
                .collect::<Option<Vec<f64>>>()?;
            values.try_into().ok()
        };
        let (Some(min), Some(max)) = (declared(accessor.min()), declared(accessor.max())) else {
            return;
        };
        let rounded = accessor
            .view()
            .is_some_and(|v| meshopt::rounds_values(self.document, v.index()));
        if positions.is_empty() || rounded {
            return;
        }
        // The bounds hold stored values, the positions those values mapped
        // by `coordinate`, which only ever rises: mapping the bounds too
        // compares the two in one space.
        let coordinate = coordinate(accessor);
        let [min, max] = [min, max].map(|bound| DVec3::from(bound.map(&coordinate)));
        let (low, high) = positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let tolerance =
            min.abs().max(max.abs()).max_element() * BOUNDS_ROUNDING + (high - low).max_element() * BOUNDS_SLACK;
        // The axis and side where the vertices reach farthest beyond a
        // bound (the first of equals), if beyond the tolerance anywhere.
        let beyond = (0..3)
            .flat_map(|axis| {
                [
                    (axis, "min", min[axis] - low[axis]),
                    (axis, "max", high[axis] - max[axis]),
                ]
            })
            .filter(|&(.., by)| by > tolerance)
            .reduce(|far, next| if next.2 > far.2 { next } else { far });
        let Some((axis, side, _)) = beyond else {
            return;
        };
        self.count += 1;
        self.one.get_or_insert_with(|| {
            // As the file writes them: stored values.
            let (reach, bound) = match side {
                "min" => (low[axis], accessor.min()),
                _ => (high[axis], accessor.max()),
            };
            let stored = match stored_scale(accessor) {
                Some(scale) => text::number((reach * scale).round()),
                None if accessor.data_type() == gltf::accessor::DataType::F32 => (reach as f32).to_string(),
                None => text::number(reach),
            };
            let bound = bound.map_or_else(String::new, |b| b[axis].to_string());
            format!(
                "'{name}': {} reaches {stored} where its POSITION {side} says {bound}",
                ["x", "y", "z"][axis]
            )
        });
    }

    /// Warns of the meshes counted, naming one.
    fn warn(self, builder: &mut SceneBuilder) {
        let Some(one) = self.one else {
            return;
        };
        let (meshes, have, their, them) = match self.count {
            1 => ("a mesh".to_string(), "has", "its glTF accessor declares", "it"),
            n => (format!("{n} meshes"), "have", "their glTF accessors declare", "them"),
        };
        let which = if self.count == 1 {
            one
        } else {
            format!("one of them, {one}")
        };
        builder.warn(format!(
            "{meshes} {have} vertices beyond the bounds {their} ({which}): occlu bounds meshes by their vertices, but an engine that takes the file's bounds may cull {them} while in view"
        ));
    }
}

/// The file's Draco streams, with a bound on what decoding them may
/// allocate: as for meshopt's, a multiple of the largest file allowed.
fn draco_streams(raw: &serde_json::Value, gltf: &gltf::Gltf, options: &LoadOptions) -> Result<DracoStreams, String> {
    let views = gltf
        .views()
        .map(|v| [v.buffer().index(), v.offset(), v.length()])
        .collect();
    let budget = DECODED_PER_FILE_BYTE.saturating_mul(options.max_file_size);
    DracoStreams::new(raw, views, budget)
}

/// How a POSITION accessor's stored component becomes a coordinate: as it
/// is, or, for normalized integers (KHR_mesh_quantization), mapped to
/// [0, 1] (unsigned) or [−1, 1] (signed) as glTF 2.0 defines them:
/// c / (2^b − 1) and max(c / (2^(b−1) − 1), −1). The node transforms,
/// which quantizing exporters set to undo the scaling, apply afterwards as
/// for any mesh.
fn coordinate(accessor: &gltf::Accessor) -> impl Fn(f64) -> f64 + use<> {
    let most = stored_scale(accessor);
    move |c| most.map_or(c, |most| (c / most).max(-1.0))
}

/// For a normalized integer accessor, the stored value that means 1 (what
/// [`coordinate`] divides by); none for others.
fn stored_scale(accessor: &gltf::Accessor) -> Option<f64> {
    use gltf::accessor::DataType;
    match accessor.data_type() {
        _ if !accessor.normalized() => None,
        DataType::I8 => Some(127.0),
        DataType::U8 => Some(255.0),
        DataType::I16 => Some(32767.0),
        DataType::U16 => Some(65535.0),
        DataType::U32 | DataType::F32 => None,
    }
}

/// The elements of a 3- or 4-vector accessor of floats or integers
/// (KHR_mesh_quantization), each component mapped by [`coordinate`], as
/// `N` components (those it lacks 0, those beyond dropped); `None` for
/// other accessors, or where its data lies outside its buffer.
fn read_vectors<const N: usize>(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Option<Vec<[f64; N]>> {
    use gltf::accessor::DataType;
    match accessor.data_type() {
        DataType::F32 => read_of::<f32, N>(accessor, buffers),
        DataType::I8 => read_of::<i8, N>(accessor, buffers),
        DataType::U8 => read_of::<u8, N>(accessor, buffers),
        DataType::I16 => read_of::<i16, N>(accessor, buffers),
        DataType::U16 => read_of::<u16, N>(accessor, buffers),
        DataType::U32 => None,
    }
}

/// [`read_vectors`] of an accessor of components `T`.
fn read_of<T, const N: usize>(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Option<Vec<[f64; N]>>
where
    T: Copy + Into<f64>,
    [T; 3]: gltf::accessor::Item,
    [T; 4]: gltf::accessor::Item,
{
    match accessor.dimensions() {
        gltf::accessor::Dimensions::Vec3 => read_items::<T, 3, N>(accessor, buffers),
        gltf::accessor::Dimensions::Vec4 => read_items::<T, 4, N>(accessor, buffers),
        _ => None,
    }
}

/// [`read_vectors`] of an accessor of `K` components `T`.
fn read_items<'a, T, const K: usize, const N: usize>(
    accessor: &gltf::Accessor<'a>,
    buffers: &[Vec<u8>],
) -> Option<Vec<[f64; N]>>
where
    T: Copy + Into<f64>,
    [T; K]: gltf::accessor::Item,
{
    let coordinate = coordinate(accessor);
    let data = |b: gltf::Buffer<'a>| buffers.get(b.index()).map(Vec::as_slice);
    let items = gltf::accessor::Iter::<[T; K]>::new(accessor.clone(), data)?;
    Some(
        items
            .map(|item| {
                let mut vector = [0.0; N];
                for (to, from) in vector.iter_mut().zip(item) {
                    *to = coordinate(from.into());
                }
                vector
            })
            .collect(),
    )
}

/// Expands strips and fans into a triangle list (winding is irrelevant: the
/// renderer does not cull back faces, since culling must not depend on it).
fn triangle_list(mode: Mode, stream: &[u32]) -> Vec<u32> {
    let n = stream.len();
    match mode {
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .flat_map(|i| {
                if i % 2 == 0 {
                    [stream[i], stream[i + 1], stream[i + 2]]
                } else {
                    [stream[i + 1], stream[i], stream[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..n.saturating_sub(1))
            .flat_map(|i| [stream[0], stream[i], stream[i + 1]])
            .collect(),
        // A trailing partial triangle is reported by validation.
        _ => stream.to_vec(),
    }
}

/// A buffer's bytes, from the GLB's binary chunk, a data URI or a file
/// (noted in `builder`).
fn buffer_data(
    path: &Path,
    gltf: &gltf::Gltf,
    buffer: &gltf::Buffer,
    options: &LoadOptions,
    builder: &mut SceneBuilder,
) -> Result<Vec<u8>, SceneError> {
    let error = |what: String| SceneError::Parse {
        path: path.into(),
        message: format!("buffer {}: {what}", buffer.index()),
    };
    let mut data = match buffer.source() {
        gltf::buffer::Source::Bin => gltf
            .blob
            .clone()
            .ok_or_else(|| error("refers to the GLB binary chunk, but the file has none".into()))?,
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            let (_, payload) = uri
                .split_once(";base64,")
                .ok_or_else(|| error("data URI is not base64".into()))?;
            base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| error(format!("data URI does not decode: {e}")))?
        }
        gltf::buffer::Source::Uri(uri) => {
            let file = if options.external_buffers {
                buffer_file(path, uri)
            } else {
                beside_the_model(path, uri).map_err(error)?
            };
            let data = read_model_file(&file, options).map_err(|e| error(format!("{}: {e}", file.display())))?;
            builder.read_from(file);
            data
        }
    };
    if data.len() < buffer.length() {
        return Err(error(format!(
            "holds {} bytes, but declares {}",
            data.len(),
            buffer.length()
        )));
    }
    data.truncate(buffer.length());
    Ok(data)
}

/// The file a buffer URI names, which must lie in the model's folder or
/// below it. A model from elsewhere must not make occlu read any other file
/// (`../../etc/passwd`, `/home/…`, `file:` URLs): the URI must be a relative
/// path without `..`, and once links are resolved the file must still lie
/// under the folder.
fn beside_the_model(model: &Path, uri: &str) -> Result<std::path::PathBuf, String> {
    let refuse = |why: &str| {
        Err(format!(
            "URI '{}' {why}: buffers must lie in the model's folder or below it (--external-buffers allows others)",
            uri
        ))
    };
    if uri.contains(':') {
        return refuse("is not a relative path");
    }
    let relative = percent_decode(uri);
    let relative = Path::new(&relative);
    if relative
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return refuse("leaves the model's folder");
    }
    // Resolved, a link inside the folder may still point out of it. A
    // path that cannot be resolved is not read either, so the check is
    // never skipped; and the file read is the one resolved, so a link
    // changed after the check leads nowhere new.
    let resolved = |p: &Path| p.canonicalize().map_err(|e| format!("{}: {e}", p.display()));
    let (folder, file) = (resolved(folder_of(model))?, resolved(&buffer_file(model, uri))?);
    if !file.starts_with(&folder) {
        return refuse("leads out of the model's folder through a link");
    }
    Ok(file)
}

/// The file a buffer URI names, relative to the model's folder (an
/// absolute path stays absolute).
fn buffer_file(model: &Path, uri: &str) -> std::path::PathBuf {
    let relative = percent_decode(uri.strip_prefix("file://").unwrap_or(uri));
    folder_of(model).join(relative)
}

/// URIs in glTF are percent-encoded (a space is `%20`).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(b)) => {
                out.push(b);
                i += 3;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_expand_to_triangle_lists() {
        assert_eq!(
            triangle_list(Mode::TriangleStrip, &[0, 1, 2, 3, 4]),
            vec![0, 1, 2, 2, 1, 3, 2, 3, 4]
        );
        assert_eq!(triangle_list(Mode::TriangleFan, &[0, 1, 2, 3]), vec![0, 1, 2, 0, 2, 3]);
        assert!(triangle_list(Mode::TriangleStrip, &[0, 1]).is_empty());
    }

    #[test]
    fn percent_encoded_uris_decode() {
        assert_eq!(percent_decode("my%20mesh.bin"), "my mesh.bin");
        assert_eq!(percent_decode("100%.bin"), "100%.bin");
    }
}
