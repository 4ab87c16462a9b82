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

use std::collections::BTreeSet;

use glam::{DMat4, DQuat, DVec3};
use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation, Property};

use crate::text::one_line;

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

/// The node tree: each node's parent and rest transform.
struct Nodes {
    parent: Vec<Option<usize>>,
    rest: Vec<([f64; 3], DQuat, [f64; 3])>,
}

impl Nodes {
    fn of(gltf: &gltf::Gltf) -> Nodes {
        let mut parent = vec![None; gltf.nodes().len()];
        for node in gltf.nodes() {
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

    /// Whether `node` is `ancestor` or lies below it.
    fn under(&self, mut node: usize, ancestor: usize) -> bool {
        for _ in 0..=self.parent.len() {
            if node == ancestor {
                return true;
            }
            match self.parent[node] {
                Some(p) => node = p,
                None => return false,
            }
        }
        false
    }

    /// `node`'s world transform with `local` giving each node's transform.
    fn world(&self, node: usize, local: &dyn Fn(usize) -> DMat4) -> DMat4 {
        let mut m = local(node);
        let mut at = node;
        for _ in 0..self.parent.len() {
            match self.parent[at] {
                Some(p) => {
                    m = local(p) * m;
                    at = p;
                }
                None => break,
            }
        }
        m
    }
}

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

/// The cameras of the default scene's nodes (`reached[n]`: node `n` is in
/// it) and every animation, with the poses of the cameras they move.
/// `check` vets an accessor before it is read, as the mesh loader does.
pub fn read(
    gltf: &gltf::Gltf,
    buffers: &[Vec<u8>],
    reached: &[bool],
    check: &CheckAccessor,
) -> Result<(Vec<FileCamera>, Vec<FileAnimation>), String> {
    let nodes = Nodes::of(gltf);
    let rest = |n: usize| {
        let (t, r, s) = nodes.rest[n];
        DMat4::from_scale_rotation_translation(DVec3::from(s), r, DVec3::from(t))
    };
    let pose_of = |camera: &gltf::Camera, world: DMat4| -> Result<CameraPose, String> {
        let (_, rotation, eye) = world.to_scale_rotation_translation();
        if !(eye.is_finite() && rotation.is_finite()) {
            return Err(format!(
                "camera '{}': its node's transform is not finite",
                name_of_camera(camera)
            ));
        }
        let (fov_y_deg, near) = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                (Some(decimal(p.yfov()).to_degrees()), Some(decimal(p.znear())))
            }
            gltf::camera::Projection::Orthographic(o) => (None, Some(decimal(o.znear()))),
        };
        Ok(CameraPose {
            eye,
            rotation: rotation.normalize(),
            fov_y_deg,
            near,
        })
    };
    let mut cameras = Vec::new();
    for node in gltf.nodes().filter(|n| reached[n.index()]) {
        if let Some(camera) = node.camera() {
            cameras.push(FileCamera {
                name: node
                    .name()
                    .or(camera.name())
                    .map_or_else(|| format!("camera{}", camera.index()), one_line),
                node: node.index(),
                projection: match camera.projection() {
                    gltf::camera::Projection::Perspective(_) => "perspective",
                    gltf::camera::Projection::Orthographic(_) => "orthographic",
                },
                pose: pose_of(&camera, nodes.world(node.index(), &rest))?,
            });
        }
    }
    let mut animations = Vec::new();
    for animation in gltf.animations() {
        let name = animation
            .name()
            .map_or_else(|| format!("animation{}", animation.index()), one_line);
        let mut channels = Vec::new();
        for channel in animation.channels() {
            let what = format!("animation '{name}' channel {}", channel.index());
            if let Some(c) = read_channel(&channel, buffers, check).map_err(|e| format!("{what}: {e}"))? {
                channels.push(c);
            }
        }
        let first = channels.iter().map(|c| c.times[0]).fold(f64::INFINITY, f64::min);
        let last = channels
            .iter()
            .map(|c| c.times[c.times.len() - 1])
            .fold(f64::NEG_INFINITY, f64::max);
        let duration = if channels.is_empty() { 0.0 } else { last - first };
        let moved = cameras
            .iter()
            .find(|cam| channels.iter().any(|c| nodes.under(cam.node, c.node)));
        let camera = match moved {
            Some(cam) => {
                let camera = gltf
                    .nodes()
                    .nth(cam.node)
                    .and_then(|n| n.camera())
                    .ok_or("a camera node lost its camera")?;
                let relevant: Vec<&Channel> = channels.iter().filter(|c| nodes.under(cam.node, c.node)).collect();
                let poses = sample_times(&relevant)?
                    .into_iter()
                    .map(|t| {
                        let world = nodes.world(cam.node, &|n| animated(&nodes, &relevant, t, n));
                        Ok((t, pose_of(&camera, world)?))
                    })
                    .collect::<Result<Vec<_>, String>>()?;
                Some(AnimatedCamera {
                    name: cam.name.clone(),
                    poses,
                })
            }
            None => None,
        };
        animations.push(FileAnimation {
            name,
            channels: channels.len(),
            duration,
            camera,
        });
    }
    Ok((cameras, animations))
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
    let keys: BTreeSet<u64> = channels
        .iter()
        .flat_map(|c| c.times.iter().map(|t| t.to_bits()))
        .collect();
    let keys: Vec<f64> = keys.into_iter().map(f64::from_bits).collect();
    let mut times = Vec::new();
    for pair in keys.windows(2) {
        // Keys already 1/30 s apart (stored in f32) get no sample between.
        let steps = ((pair[1] - pair[0]) * SAMPLES_PER_SECOND - 1e-3).ceil().max(1.0);
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
        .map_or_else(|| format!("camera{}", camera.index()), one_line)
}
