//! A glTF file's own cameras, and the animations that move them: where each
//! camera of the default scene stands, and an animated camera's pose over
//! time, so that `occlu path gen --kind cameras` and `--kind animation`
//! (and, with an animated camera, the default path) replay what the file's
//! author framed.
//!
//! An animation is evaluated as glTF 2.0 defines it ("Animations"): each
//! channel sets one node's translation, rotation or scale, LINEAR (slerp for
//! rotations), STEP or CUBICSPLINE (Hermite, tangents scaled by the key
//! interval) between its keys, held before the first key and after the last;
//! a camera's pose is its node's world transform through the node tree,
//! scale removed. Poses are sampled at every key time of the channels that
//! move the camera or its ancestors, and at [`SAMPLES_PER_SECOND`] between
//! them.

use glam::{DMat4, DQuat, DVec3};
use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation, Property};

use crate::text::number;

/// A camera pose: the eye and the camera-to-world rotation (looking down its
/// −Z with +Y up, as glTF cameras do), and its perspective, if any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    pub eye: DVec3,
    pub rotation: DQuat,
    /// Vertical field of view, degrees (perspective cameras).
    pub fov_y_deg: Option<f64>,
    pub near: Option<f64>,
}

/// A camera of the file's default scene.
#[derive(Clone, Debug, PartialEq)]
pub struct FileCamera {
    pub name: String,
    pub node: usize,
    /// "perspective" or "orthographic" (drawn as perspective by occlu).
    pub projection: &'static str,
    pub pose: CameraPose,
}

/// An animation of the file.
#[derive(Clone, Debug, PartialEq)]
pub struct FileAnimation {
    pub name: String,
    pub channels: usize,
    /// Seconds from the first key to the last.
    pub duration: f64,
    /// The first camera it moves, and that camera's poses over time.
    pub camera: Option<AnimatedCamera>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct AnimatedCamera {
    pub name: String,
    /// (time in seconds, pose), increasing in time.
    pub poses: Vec<(f64, CameraPose)>,
}

/// Vets an accessor (what it is for, the component types and dimensions
/// allowed) before the gltf reader, which trusts it, touches it.
pub type CheckAccessor<'c> =
    dyn Fn(&gltf::Accessor, &str, &[gltf::accessor::DataType], gltf::accessor::Dimensions) -> Result<(), String> + 'c;

/// Poses sampled per second between key times.
pub const SAMPLES_PER_SECOND: f64 = 30.0;

/// Samples an animation may give a path at most.
const MAX_SAMPLES: usize = 100_000;

/// The default scene's node tree: each node's parent and rest transform.
struct Nodes {
    parent: Vec<Option<usize>>,
    rest: Vec<([f64; 3], DQuat, [f64; 3])>,
}

impl Nodes {
    /// The tree of the nodes in the default scene (`reached`), which the
    /// mesh loader has checked to be trees: a node outside it is no parent.
    fn of(gltf: &gltf::Gltf, reached: &[bool]) -> Nodes {
        let mut parent = vec![None; gltf.nodes().len()];
        for node in gltf.nodes().filter(|n| reached[n.index()]) {
            for child in node.children() {
                parent[child.index()] = Some(node.index());
            }
        }
        let rest = gltf
            .nodes()
            .map(|n| {
                let (t, r, s) = n.transform().decomposed();
                (
                    t.map(f64::from),
                    DQuat::from_array(r.map(f64::from)).normalize(),
                    s.map(f64::from),
                )
            })
            .collect();
        Nodes { parent, rest }
    }

    /// `node` and its ancestors, from `node` up to its root.
    fn chain(&self, node: usize) -> Vec<usize> {
        let mut chain = vec![node];
        while let Some(p) = self.parent[chain[chain.len() - 1]] {
            if chain.len() > self.parent.len() {
                break;
            }
            chain.push(p);
        }
        chain
    }

    /// The world transform at the end of `chain` (from [`Nodes::chain`]),
    /// with `local` giving each node's transform.
    fn world(chain: &[usize], local: &dyn Fn(usize) -> DMat4) -> DMat4 {
        chain.iter().rev().fold(DMat4::IDENTITY, |m, &n| m * local(n))
    }
}

/// Node transforms evaluated, in all, per file: a camera sampled N times
/// under a chain of L nodes costs N·L.
const MAX_WORK: usize = 20_000_000;

/// Animation keys read, in all, per file.
const MAX_KEYS: usize = 10_000_000;

/// One channel's keys, read and checked.
struct Channel {
    node: usize,
    property: Property,
    interpolation: Interpolation,
    times: Vec<f64>,
    /// Per key: one value, or for CUBICSPLINE in-tangent, value, out-tangent.
    values: Vec<[f64; 4]>,
}

impl Channel {
    /// The channel's value at `t`.
    fn at(&self, t: f64) -> [f64; 4] {
        let n = self.times.len();
        let stride = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        let value = |k: usize| self.values[k * stride + stride / 2];
        if t <= self.times[0] || n == 1 {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let u = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if self.property == Property::Rotation => {
                let (a, b) = (DQuat::from_array(value(k)), DQuat::from_array(value(k + 1)));
                a.normalize().slerp(b.normalize(), u).to_array()
            }
            Interpolation::Linear => {
                let (a, b) = (value(k), value(k + 1));
                [0, 1, 2, 3].map(|i| a[i] + (b[i] - a[i]) * u)
            }
            Interpolation::CubicSpline => {
                let dt = t1 - t0;
                let (p0, m0) = (self.values[k * 3 + 1], self.values[k * 3 + 2]);
                let (p1, m1) = (self.values[(k + 1) * 3 + 1], self.values[(k + 1) * 3]);
                let (u2, u3) = (u * u, u * u * u);
                let h = [
                    2.0 * u3 - 3.0 * u2 + 1.0,
                    u3 - 2.0 * u2 + u,
                    -2.0 * u3 + 3.0 * u2,
                    u3 - u2,
                ];
                [0, 1, 2, 3].map(|i| h[0] * p0[i] + h[1] * dt * m0[i] + h[2] * p1[i] + h[3] * dt * m1[i])
            }
        }
    }
}

/// What [`read`] found: the cameras, the animations, and what it had to
/// leave out (a camera it cannot place, an animation it cannot replay),
/// which the model loads without.
pub struct Found {
    pub cameras: Vec<FileCamera>,
    pub animations: Vec<FileAnimation>,
    pub warnings: Vec<String>,
}

/// The cameras of the default scene's nodes (`reached[n]`: node `n` is in
/// it) and every animation, with the poses of the cameras they move.
/// `check` vets an accessor before it is read, as the mesh loader does.
/// Only channels that move a camera are read; keys and work are bounded.
pub fn read(gltf: &gltf::Gltf, buffers: &[Vec<u8>], reached: &[bool], check: &CheckAccessor) -> Found {
    let nodes = Nodes::of(gltf, reached);
    let rest = |n: usize| {
        let (t, r, s) = nodes.rest[n];
        DMat4::from_scale_rotation_translation(DVec3::from(s), r, DVec3::from(t))
    };
    let mut warnings = Vec::new();
    let mut cameras = Vec::new();
    // The nodes whose motion moves a camera: cameras and their ancestors.
    let mut moves_a_camera = vec![false; nodes.parent.len()];
    let mut chains = Vec::new();
    let mut budget = Budget::default();
    for node in gltf.nodes().filter(|n| reached[n.index()]) {
        let Some(camera) = node.camera() else { continue };
        let name = node.name().map_or_else(|| name_of_camera(&camera), str::to_string);
        if let Some(fault) = projection_fault(&camera) {
            warnings.push(format!("camera '{name}' is left out: {fault}"));
            continue;
        }
        let chain = nodes.chain(node.index());
        // Placing a camera evaluates its chain: nested cameras cost the
        // square of their depth.
        budget.work += chain.len();
        if budget.work > MAX_WORK {
            warnings.push(format!(
                "camera '{name}' (node {}) and those after it are left out: placing them passes the {MAX_WORK} node transforms occlu evaluates per file",
                node.index()
            ));
            break;
        }
        match pose_of(&camera, Nodes::world(&chain, &rest)) {
            Some(pose) => {
                for &n in &chain {
                    moves_a_camera[n] = true;
                }
                if let gltf::camera::Projection::Orthographic(_) = camera.projection() {
                    warnings.push(format!(
                        "camera '{name}' is orthographic: occlu draws it in perspective from where it stands, at a path's default field of view"
                    ));
                }
                cameras.push(FileCamera {
                    name,
                    node: node.index(),
                    projection: match camera.projection() {
                        gltf::camera::Projection::Perspective(_) => "perspective",
                        gltf::camera::Projection::Orthographic(_) => "orthographic",
                    },
                    pose,
                });
                chains.push((chain, camera));
            }
            None => warnings.push(format!(
                "camera '{name}' is left out: its node's transform cannot place it (not finite, or scaled to nothing)"
            )),
        }
    }
    let mut animations = Vec::new();
    for animation in gltf.animations() {
        let name = animation
            .name()
            .map_or_else(|| format!("animation{}", animation.index()), str::to_string);
        let moved = Moved {
            cameras: &cameras,
            chains: &chains,
            nodes: &moves_a_camera,
        };
        let camera = match replay(&animation, &moved, &nodes, buffers, check, &mut budget) {
            Ok(camera) => camera,
            Err(e) => {
                warnings.push(format!("animation '{name}' is not replayed: {e}"));
                None
            }
        };
        animations.push(FileAnimation {
            name,
            channels: animation.channels().count(),
            duration: duration(&animation),
            camera,
        });
    }
    Found {
        cameras,
        animations,
        warnings,
    }
}

/// The cameras an animation may move: their entries, their node chains (in
/// the same order), and which nodes lie on a chain.
struct Moved<'c, 'g> {
    cameras: &'c [FileCamera],
    chains: &'c [(Vec<usize>, gltf::Camera<'g>)],
    nodes: &'c [bool],
}

/// Keys read and node transforms evaluated so far in the file.
#[derive(Default)]
struct Budget {
    keys: usize,
    work: usize,
}

/// An animation's length in seconds, from its inputs' `min` and `max` (which
/// glTF requires of animation inputs; 0 where they are missing).
fn duration(animation: &gltf::Animation) -> f64 {
    let bound = |value: Option<serde_json::Value>| value.and_then(|v| v.get(0).and_then(serde_json::Value::as_f64));
    let (mut first, mut last) = (f64::INFINITY, f64::NEG_INFINITY);
    for channel in animation.channels() {
        let input = channel.sampler().input();
        if let (Some(a), Some(b)) = (bound(input.min()), bound(input.max())) {
            first = first.min(a);
            last = last.max(b);
        }
    }
    if last >= first { last - first } else { 0.0 }
}

/// The poses of the first camera `animation` moves, if it moves one.
fn replay(
    animation: &gltf::Animation,
    moved: &Moved,
    nodes: &Nodes,
    buffers: &[Vec<u8>],
    check: &CheckAccessor,
    budget: &mut Budget,
) -> Result<Option<AnimatedCamera>, String> {
    let mut channels = Vec::new();
    for channel in animation.channels() {
        if !moved.nodes[channel.target().node().index()] {
            continue;
        }
        let what = format!("channel {}", channel.index());
        if let Some(c) = read_channel(&channel, buffers, check).map_err(|e| format!("{what}: {e}"))? {
            budget.keys += c.times.len();
            if budget.keys > MAX_KEYS {
                return Err(format!("the file's camera animations hold more than {MAX_KEYS} keys"));
            }
            channels.push(c);
        }
    }
    let Some(((chain, camera), file_camera)) = moved
        .chains
        .iter()
        .zip(moved.cameras)
        .find(|((chain, _), _)| channels.iter().any(|c| chain.contains(&c.node)))
    else {
        return Ok(None);
    };
    let relevant: Vec<&Channel> = channels.iter().filter(|c| chain.contains(&c.node)).collect();
    let times = sample_times(&relevant)?;
    budget.work += times.len() * chain.len();
    if budget.work > MAX_WORK {
        return Err(format!(
            "sampling it ({} poses through {} nodes) passes the {MAX_WORK} node transforms occlu evaluates per file",
            times.len(),
            chain.len()
        ));
    }
    let poses = times
        .into_iter()
        .map(|t| {
            let world = Nodes::world(chain, &|n| animated(nodes, &relevant, t, n));
            pose_of(camera, world)
                .map(|pose| (t, pose))
                .ok_or_else(|| format!("at {t} s the camera's transform cannot place it"))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Some(AnimatedCamera {
        name: file_camera.name.clone(),
        poses,
    }))
}

/// The near planes a view takes: outside it reverse-Z depth of the
/// farthest renderable geometry (`MAX_COORDINATE`) leaves f32's normal
/// range, or culls everything.
pub const NEAR_RANGE: std::ops::RangeInclusive<f64> = 1e-9..=1e9;
/// The vertical fields of view a view takes, degrees: wider would make
/// the projection degenerate in f32; narrower, the adapters do not draw
/// what they are given. Measured (`occlu stress --cases fov-narrowest`,
/// and a wall 0.1 mm to 67 mm before the eye hiding another, one frame at
/// 400x300): at 0.5° and narrower, llvmpipe and lavapipe leave columns of
/// the wall at the view's edge undrawn (up to 15), so 300 to 9 900 pixels
/// of the wall behind show, which a box test or `swr`'s buffer, taking
/// the wall as drawn, cannot know; from 1° to 60°, the eye down to 10⁻⁷
/// before the wall, never.
pub const FOV_RANGE: std::ops::RangeInclusive<f64> = 1.0..=179.9;

/// Why `camera`'s projection gives no view occlu can take, if it does not:
/// a near plane in [`NEAR_RANGE`] (glTF lets an orthographic one's znear
/// be 0) and, for a perspective one, a field of view in [`FOV_RANGE`]
/// (glTF allows any below pi: a camera of yfov 3.1415, 179.995°, made a
/// path from it fail).
fn projection_fault(camera: &gltf::Camera) -> Option<String> {
    let (znear, yfov) = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => (p.znear(), Some(p.yfov())),
        gltf::camera::Projection::Orthographic(o) => (o.znear(), None),
    };
    // JSON holds no NaN: the numbers compare.
    if !NEAR_RANGE.contains(&f64::from(znear)) {
        return Some(format!(
            "its znear is {znear}: occlu's views take near planes from {:e} to {:e}",
            NEAR_RANGE.start(),
            NEAR_RANGE.end()
        ));
    }
    match yfov {
        Some(yfov) if fov_degrees(yfov).is_none() => Some(format!(
            "its yfov is {}°: occlu's views take fields of view from {}° to {}°",
            number((f64::from(yfov).to_degrees() * 1e3).round() / 1e3),
            FOV_RANGE.start(),
            FOV_RANGE.end()
        )),
        _ => None,
    }
}

/// The field of view in degrees, within [`FOV_RANGE`], that a glTF
/// camera's `yfov` (radians in f32, read as the shortest decimal that
/// writes it) names; `None` outside the range. An end of the range put
/// into f32 reads back a hair beyond it (1° is 0.99999997°, as `occlu
/// export` writes a 1° path): what rounds to an end's f32 is that end.
fn fov_degrees(yfov: f32) -> Option<f64> {
    let (least, most) = (*FOV_RANGE.start(), *FOV_RANGE.end());
    let in_f32 = |degrees: f64| degrees.to_radians() as f32;
    // JSON holds no NaN: the numbers compare.
    (in_f32(least)..=in_f32(most))
        .contains(&yfov)
        .then(|| decimal(yfov).to_degrees().clamp(least, most))
}

/// A camera's pose under `world`, or `None` when the transform cannot place
/// it (not finite, or scaled to nothing, which leaves no rotation).
fn pose_of(camera: &gltf::Camera, world: DMat4) -> Option<CameraPose> {
    let (scale, rotation, eye) = world.to_scale_rotation_translation();
    if !(eye.is_finite() && rotation.is_finite() && scale.is_finite() && scale.cmpne(DVec3::ZERO).all()) {
        return None;
    }
    let (fov_y_deg, near) = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => (fov_degrees(p.yfov()), Some(decimal(p.znear()))),
        gltf::camera::Projection::Orthographic(o) => (None, Some(decimal(o.znear()))),
    };
    Some(CameraPose {
        eye,
        rotation: rotation.normalize(),
        fov_y_deg,
        near,
    })
}

/// Node `n`'s transform at time `t`: its rest transform with what
/// `channels` set at `t`.
fn animated(nodes: &Nodes, channels: &[&Channel], t: f64, n: usize) -> DMat4 {
    let (mut translation, mut rotation, mut scale) = nodes.rest[n];
    for c in channels.iter().filter(|c| c.node == n) {
        let v = c.at(t);
        match c.property {
            Property::Translation => translation = [v[0], v[1], v[2]],
            Property::Rotation => rotation = DQuat::from_array(v).normalize(),
            Property::Scale => scale = [v[0], v[1], v[2]],
            Property::MorphTargetWeights => {}
        }
    }
    DMat4::from_scale_rotation_translation(DVec3::from(scale), rotation, DVec3::from(translation))
}

/// The times a camera moved by `channels` is sampled at: every key time,
/// and [`SAMPLES_PER_SECOND`] between them.
fn sample_times(channels: &[&Channel]) -> Result<Vec<f64>, String> {
    let mut keys: Vec<f64> = channels.iter().flat_map(|c| c.times.iter().copied()).collect();
    keys.sort_by(f64::total_cmp);
    // == also merges -0 and +0.
    keys.dedup_by(|a, b| a == b);
    let mut times = Vec::new();
    for pair in keys.windows(2) {
        // Keys already 1/30 s apart get no sample between, though stored in
        // f32, whose rounding grows with the time (about 1e-4 s at 1000 s).
        let slack = 1e-3 + 8.0 * f64::from(f32::EPSILON) * pair[1].abs() * SAMPLES_PER_SECOND;
        let steps = ((pair[1] - pair[0]) * SAMPLES_PER_SECOND - slack).ceil().max(1.0);
        if times.len() as f64 + steps > MAX_SAMPLES as f64 {
            return Err(format!("animates a camera for more than {MAX_SAMPLES} samples"));
        }
        for k in 0..steps as usize {
            times.push(pair[0] + (pair[1] - pair[0]) * k as f64 / steps);
        }
    }
    times.extend(keys.last());
    Ok(times)
}

/// A channel's keys, checked (`None` for morph target weights, which do not
/// move anything).
fn read_channel(
    channel: &gltf::animation::Channel,
    buffers: &[Vec<u8>],
    check: &CheckAccessor,
) -> Result<Option<Channel>, String> {
    use gltf::accessor::{DataType, Dimensions};
    let property = channel.target().property();
    if property == Property::MorphTargetWeights {
        return Ok(None);
    }
    let sampler = channel.sampler();
    check(&sampler.input(), "input", &[DataType::F32], Dimensions::Scalar)?;
    let (types, dims): (&[DataType], _) = match property {
        Property::Rotation => (
            &[DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16],
            Dimensions::Vec4,
        ),
        _ => (&[DataType::F32], Dimensions::Vec3),
    };
    check(&sampler.output(), "output", types, dims)?;
    let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let times: Vec<f64> = reader
        .read_inputs()
        .ok_or("input data lies outside its buffer")?
        .map(f64::from)
        .collect();
    let values: Vec<[f64; 4]> = match reader.read_outputs().ok_or("output data lies outside its buffer")? {
        ReadOutputs::Translations(v) | ReadOutputs::Scales(v) => v
            .map(|p| [f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 0.0])
            .collect(),
        ReadOutputs::Rotations(r) => r.into_f32().map(|q| q.map(f64::from)).collect(),
        ReadOutputs::MorphTargetWeights(_) => return Ok(None),
    };
    let interpolation = sampler.interpolation();
    let per_key = if interpolation == Interpolation::CubicSpline {
        3
    } else {
        1
    };
    if times.is_empty() || values.len() != times.len() * per_key {
        return Err(format!(
            "{} keys but {} values ({per_key} per key expected)",
            times.len(),
            values.len()
        ));
    }
    if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
        return Err("key times must be finite and increasing".into());
    }
    if values.iter().flatten().any(|v| !v.is_finite()) {
        return Err("values must be finite".into());
    }
    Ok(Some(Channel {
        node: channel.target().node().index(),
        property,
        interpolation,
        times,
        values,
    }))
}

/// The f64 nearest the decimal the file's author wrote (0.05, not the
/// 0.05000000074505806 a widened f32 is).
fn decimal(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

fn name_of_camera(camera: &gltf::Camera) -> String {
    camera
        .name()
        .map_or_else(|| format!("camera{}", camera.index()), str::to_string)
}
