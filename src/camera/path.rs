//! Camera paths: the JSON format (documented in README.md), its validation,
//! and sampling one camera per frame.
//!
//! Positions follow a Catmull–Rom spline parameterised by keyframe time
//! (tangents from neighbouring keyframes, one-sided at the ends), so uneven
//! keyframe spacing gives no speed jumps; orientations are interpolated by
//! shortest-arc slerp; the field of view linearly.

use std::path::Path;

use glam::{DQuat, DVec3, DVec4};
use serde::{Deserialize, Serialize};

use super::{Camera, look_rotation, up_along_view};
pub use crate::scene::cameras::{FOV_RANGE, NEAR_RANGE};
use crate::scene::{MAX_COORDINATE, within_range};
use crate::text::{number, vector};

/// The file format, as written and read.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PathFile {
    /// Number of frames sampled evenly from the first to the last keyframe.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<u32>,
    /// Alternatively, frames per second of keyframe time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
    /// Near-plane distance in scene units (default 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<f64>,
    /// Default vertical field of view in degrees (default 60).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov_y_deg: Option<f64>,
    /// Default up vector (default [0, 1, 0]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
    #[serde(default)]
    pub interpolation: Interpolation,
    #[serde(deserialize_with = "keyframe_objects")]
    pub keyframes: Vec<KeyframeFile>,
}

#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Interpolation {
    #[default]
    CatmullRom,
    Linear,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct KeyframeFile {
    /// Seconds (or any unit): strictly increasing.
    pub time: f64,
    pub position: [f64; 3],
    /// Exactly one of `target` (a point looked at), `direction` (a view
    /// vector) or `orientation` (camera-to-world quaternion x, y, z, w).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<[f64; 4]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov_y_deg: Option<f64>,
}

/// What a camera path is, for messages about one written otherwise.
const PATH_FORM: &str = r#"a camera path, a JSON object: {"frames": 120, "keyframes": [{"time": 0, "position": [x, y, z], "target": [x, y, z]}, ...]}"#;

/// `T` read from a JSON object only, `what` saying what was expected. serde's
/// derive also takes a struct written as an array of its fields in order,
/// which no one writes on purpose and which its errors describe in its own
/// terms ("expected struct PathFile with 7 elements"). Read in one pass,
/// so a hostile shape fails where it starts, as the fields' own types
/// make it.
fn from_object<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    deserializer: D,
    what: &'static str,
) -> Result<T, D::Error> {
    struct Object<T>(&'static str, std::marker::PhantomData<T>);
    impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Object<T> {
        type Value = T;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.0)
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
            T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
        }
    }
    deserializer.deserialize_map(Object(what, std::marker::PhantomData))
}

/// A path file read from a JSON object only ([`from_object`]).
struct PathObject(PathFile);

impl<'de> Deserialize<'de> for PathObject {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        from_object(deserializer, PATH_FORM).map(PathObject)
    }
}

/// Keyframes, each read from a JSON object only ([`from_object`]).
fn keyframe_objects<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Vec<KeyframeFile>, D::Error> {
    struct Keyframe(KeyframeFile);
    impl<'de> Deserialize<'de> for Keyframe {
        fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
            from_object(
                deserializer,
                "a keyframe: a JSON object of time, position and target, direction or orientation",
            )
            .map(Keyframe)
        }
    }
    Ok(Vec::<Keyframe>::deserialize(deserializer)?
        .into_iter()
        .map(|k| k.0)
        .collect())
}

pub const DEFAULT_NEAR: f64 = 0.1;
pub const DEFAULT_FOV_Y_DEG: f64 = 60.0;
/// At 30 fps, nearly an hour of flythrough.
pub const MAX_FRAMES: u32 = 100_000;

#[derive(Debug, thiserror::Error)]
pub enum PathError {
    #[error("{path}: {error}")]
    Io { path: String, error: std::io::Error },
    #[error("{path}: invalid camera path JSON: {message}")]
    Json { path: String, message: String },
    #[error("{path}: {message}")]
    Invalid { path: String, message: String },
    #[error("the frame count must be in 1..={MAX_FRAMES}")]
    FrameCount,
    /// A path from the model file that the file does not hold.
    #[error("{0}")]
    NotInFile(String),
    /// Planning a path was asked to stop (Ctrl-C).
    #[error("interrupted while a camera path was planned")]
    Interrupted,
}

/// A validated keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    pub time: f64,
    pub position: DVec3,
    pub rotation: DQuat,
    pub fov_y: f64,
}

/// A validated path: at least one keyframe, strictly increasing times.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    /// Where it came from (a file, or `generated:KIND`).
    pub source: String,
    pub keyframes: Vec<Keyframe>,
    pub near: f64,
    pub frames: u32,
    pub interpolation: Interpolation,
}

impl CameraPath {
    pub fn load(path: &Path) -> Result<CameraPath, PathError> {
        let name = path.display().to_string();
        let text = crate::input::read_text(path, crate::input::TEXT_LIMIT).map_err(|error| PathError::Io {
            path: name.clone(),
            error,
        })?;
        CameraPath::parse(&text, &name)
    }

    /// Parses and validates path JSON; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<CameraPath, PathError> {
        let json = |message: String| PathError::Json {
            path: source.to_string(),
            message,
        };
        let PathObject(file) = serde_json::from_str(text).map_err(|e| json(e.to_string()))?;
        CameraPath::from_file(&file, source)
    }

    pub fn from_file(file: &PathFile, source: &str) -> Result<CameraPath, PathError> {
        let invalid = |message: String| PathError::Invalid {
            path: source.to_string(),
            message,
        };
        let near = file.near.unwrap_or(DEFAULT_NEAR);
        if !NEAR_RANGE.contains(&near) {
            return Err(invalid(format!(
                "near must be in {:e}..={:e}, got {}",
                NEAR_RANGE.start(),
                NEAR_RANGE.end(),
                number(near)
            )));
        }
        let default_up = up(file.up.unwrap_or([0.0, 1.0, 0.0])).map_err(&invalid)?;
        let default_fov = file.fov_y_deg.unwrap_or(DEFAULT_FOV_Y_DEG);
        if file.keyframes.is_empty() {
            return Err(invalid("no keyframes".into()));
        }
        let mut keyframes = Vec::with_capacity(file.keyframes.len());
        for (i, k) in file.keyframes.iter().enumerate() {
            let at = |m: String| invalid(format!("keyframe {i}: {m}"));
            if !k.time.is_finite() {
                return Err(at(format!("time must be finite, got {}", number(k.time))));
            }
            if let Some(prev) = keyframes.last().map(|p: &Keyframe| p.time)
                && k.time <= prev
            {
                return Err(at(format!(
                    "time {} is not after the previous keyframe's {}",
                    number(k.time),
                    number(prev)
                )));
            }
            let position = vec3(k.position, "position").map_err(&at)?;
            let up = match k.up {
                Some(u) => self::up(u).map_err(&at)?,
                None => default_up,
            };
            // A view along `up` leaves the camera's roll to chance.
            let looking = |forward: DVec3| {
                if up_along_view(forward, up) {
                    Err(at(format!(
                        "up {} lies along the view direction {}, which leaves the camera's roll undefined: give the keyframe an up across its view, or an orientation",
                        vector(up.to_array()),
                        vector(forward.to_array())
                    )))
                } else {
                    Ok(look_rotation(forward, up))
                }
            };
            let rotation = match (k.target, k.direction, k.orientation) {
                (Some(t), None, None) => {
                    let forward = vec3(t, "target").map_err(&at)? - position;
                    if forward.length_squared() == 0.0 {
                        return Err(at("target equals position".into()));
                    }
                    looking(forward)?
                }
                (None, Some(d), None) => {
                    looking(nonzero(vec3(d, "direction").map_err(&at)?, "direction").map_err(&at)?)?
                }
                (None, None, Some(q)) => {
                    let q = DVec4::from(q);
                    // Scaled to unit size first, so huge or tiny components
                    // cannot overflow or underflow.
                    let largest = q.abs().max_element();
                    if !q.is_finite() || largest == 0.0 {
                        return Err(at("orientation must be a finite, non-zero quaternion".into()));
                    }
                    DQuat::from_vec4((q / largest).normalize())
                }
                _ => return Err(at("give exactly one of target, direction, orientation".into())),
            };
            let fov = k.fov_y_deg.unwrap_or(default_fov);
            if !FOV_RANGE.contains(&fov) {
                return Err(at(format!(
                    "fov_y_deg must be in {}..={}, got {}",
                    FOV_RANGE.start(),
                    FOV_RANGE.end(),
                    number(fov)
                )));
            }
            keyframes.push(Keyframe {
                time: k.time,
                position,
                rotation,
                fov_y: fov.to_radians(),
            });
        }
        let span = keyframes[keyframes.len() - 1].time - keyframes[0].time;
        if !span.is_finite() {
            return Err(invalid("the keyframe times span more than f64 can hold".into()));
        }
        let frames = match (file.frames, file.fps) {
            (Some(_), Some(_)) => return Err(invalid("give frames or fps, not both".into())),
            (Some(n), None) if n == 0 || n > MAX_FRAMES => {
                return Err(invalid(format!("frames must be in 1..={MAX_FRAMES}, got {n}")));
            }
            (Some(n), None) => n,
            (None, Some(fps)) if fps.is_finite() && fps > 0.0 => {
                let n = (span * fps).floor() + 1.0;
                if n > f64::from(MAX_FRAMES) {
                    return Err(invalid(format!(
                        "fps {} gives {} frames, more than {MAX_FRAMES}",
                        number(fps),
                        number(n)
                    )));
                }
                n as u32
            }
            (None, Some(fps)) => {
                return Err(invalid(format!("fps must be a positive number, got {}", number(fps))));
            }
            (None, None) => return Err(invalid("give frames or fps".into())),
        };
        Ok(CameraPath {
            source: source.to_string(),
            keyframes,
            near,
            frames,
            interpolation: file.interpolation,
        })
    }

    /// The same path sampled with a different number of frames.
    pub fn with_frames(mut self, frames: u32) -> Result<CameraPath, PathError> {
        if frames == 0 || frames > MAX_FRAMES {
            return Err(PathError::FrameCount);
        }
        self.frames = frames;
        Ok(self)
    }

    /// The camera of frame `index` (0-based; clamped to the last frame).
    pub fn camera(&self, index: u32, aspect: f64) -> Camera {
        let keys = &self.keyframes;
        let (t0, t1) = (keys[0].time, keys[keys.len() - 1].time);
        let s = if self.frames > 1 {
            f64::from(index.min(self.frames - 1)) / f64::from(self.frames - 1)
        } else {
            0.0
        };
        let t = t0 + (t1 - t0) * s;
        // Segment i spans keys[i]..keys[i + 1].
        let i = keys
            .partition_point(|k| k.time <= t)
            .saturating_sub(1)
            .min(keys.len().saturating_sub(2));
        let (eye, rotation, fov_y) = if keys.len() == 1 {
            (keys[0].position, keys[0].rotation, keys[0].fov_y)
        } else {
            let (a, b) = (&keys[i], &keys[i + 1]);
            let u = ((t - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
            let eye = match self.interpolation {
                Interpolation::Linear => a.position.lerp(b.position, u),
                Interpolation::CatmullRom => {
                    let (m0, m1) = (self.tangent(i, a.time, b.time), self.tangent(i + 1, a.time, b.time));
                    hermite(a.position, m0, b.position, m1, u)
                }
            };
            (
                eye,
                a.rotation.slerp(b.rotation, u).normalize(),
                a.fov_y + (b.fov_y - a.fov_y) * u,
            )
        };
        Camera {
            eye,
            rotation,
            fov_y,
            near: self.near,
            aspect,
        }
    }

    /// Velocity at keyframe `i` (central difference, one-sided at the ends)
    /// scaled to the segment `t0..t1`. The time ratio is formed first: it is
    /// at most 1, so tiny keyframe gaps cannot overflow.
    fn tangent(&self, i: usize, t0: f64, t1: f64) -> DVec3 {
        let k = &self.keyframes;
        let (lo, hi) = (i.saturating_sub(1), (i + 1).min(k.len() - 1));
        (k[hi].position - k[lo].position) * ((t1 - t0) / (k[hi].time - k[lo].time))
    }
}

fn hermite(p0: DVec3, m0: DVec3, p1: DVec3, m1: DVec3, u: f64) -> DVec3 {
    let (u2, u3) = (u * u, u * u * u);
    p0 * (2.0 * u3 - 3.0 * u2 + 1.0) + m0 * (u3 - 2.0 * u2 + u) + p1 * (-2.0 * u3 + 3.0 * u2) + m1 * (u3 - u2)
}

fn vec3(v: [f64; 3], what: &str) -> Result<DVec3, String> {
    let v = DVec3::from(v);
    if within_range(v) {
        Ok(v)
    } else {
        Err(format!(
            "{what} must be finite and within ±{MAX_COORDINATE:e}, got {}",
            vector(v.to_array())
        ))
    }
}

/// An up vector: finite, within range, and not zero (a zero up gives a
/// camera no orientation at all).
fn up(v: [f64; 3]) -> Result<DVec3, String> {
    nonzero(vec3(v, "up")?, "up")
}

fn nonzero(v: DVec3, what: &str) -> Result<DVec3, String> {
    if v.length_squared() > 0.0 {
        Ok(v)
    } else {
        Err(format!("{what} must not be zero"))
    }
}

impl CameraPath {
    /// How many frames have a surface of `caster`'s scene closer to the eye
    /// than the corners of the near plane (a sphere around the eye holding
    /// the near plane): such a surface may be clipped away, showing what
    /// lies behind it. Movers are counted where frame 0 puts them. Not
    /// counted when `caster` stops (its budget spent, or Ctrl-C).
    pub fn frames_with_geometry_within_near(
        &self,
        caster: &crate::raycast::RayCaster,
        aspect: f64,
    ) -> Result<u32, crate::raycast::Stopped> {
        let mut near = 0;
        for f in 0..self.frames {
            let camera = self.camera(f, aspect);
            let t = (camera.fov_y / 2.0).tan();
            let corner = camera.near * (1.0 + t * t * (1.0 + aspect * aspect)).sqrt();
            let found = caster.nearest_distance(camera.eye, corner).is_some();
            caster.searching()?;
            near += u32::from(found);
        }
        Ok(near)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<CameraPath, PathError> {
        CameraPath::parse(json, "t")
    }

    #[test]
    fn a_path_and_its_keyframes_are_objects_not_arrays_of_their_fields() {
        let error = |json: &str| parse(json).unwrap_err().to_string();
        let positional = r#"[2, null, 0.1, 60, null, "linear", [[0, [0, 1, -20], [0, 1, 0], null, null, null, null],
            [1, [5, 1, -20], [0, 1, 0], null, null, null, null]]]"#;
        for file in [positional, "[]"] {
            let said = error(file);
            assert!(
                said.contains("invalid type: sequence, expected a camera path, a JSON object: {\"frames\""),
                "{said}"
            );
        }
        let key = r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0], "target": [0, 0, -1]},
            [1, [1, 0, 0], [1, 0, -1], null, null, null, null]]}"#;
        let said = error(key);
        assert!(
            said.contains("invalid type: sequence, expected a keyframe: a JSON object") && said.contains("line 2"),
            "{said}"
        );
        assert!(
            error("{").contains("EOF while parsing"),
            "syntax errors say where: {}",
            error("{")
        );
        // Objects read as before.
        assert_eq!(parse(TWO_KEYS).unwrap().keyframes.len(), 2);
    }

    #[test]
    fn huge_and_tiny_orientations_normalise() {
        for q in ["[0, 0.5, 0, 1e308]", "[1e-310, 0, 0, 1e-310]"] {
            let json =
                format!(r#"{{"frames": 2, "keyframes": [{{"time": 0, "position": [0, 0, 0], "orientation": {q}}}]}}"#);
            let r = parse(&json).unwrap().keyframes[0].rotation;
            assert!(r.is_finite() && r.is_normalized(), "{q}: {r:?}");
        }
        assert!(
            parse(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0], "orientation": [0, 0, 0, 0]}]}"#)
                .is_err()
        );
    }

    const TWO_KEYS: &str = r#"{"frames": 11, "keyframes": [
        {"time": 0, "position": [0, 1, 0], "target": [0, 1, -10]},
        {"time": 2, "position": [10, 1, 0], "target": [10, 1, -10], "fov_y_deg": 90}]}"#;

    #[test]
    fn samples_hit_keyframes_and_interpolate_between() {
        let p = parse(TWO_KEYS).unwrap();
        assert_eq!(p.frames, 11);
        let first = p.camera(0, 1.0);
        let last = p.camera(10, 1.0);
        assert_eq!(first.eye, DVec3::new(0.0, 1.0, 0.0));
        assert!((last.eye - DVec3::new(10.0, 1.0, 0.0)).length() < 1e-12);
        assert!((first.forward() - DVec3::NEG_Z).length() < 1e-12);
        assert!((last.fov_y - 90f64.to_radians()).abs() < 1e-12);
        let mid = p.camera(5, 1.0);
        assert!((mid.eye - DVec3::new(5.0, 1.0, 0.0)).length() < 1e-12);
        assert!((mid.fov_y - 75f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn catmull_rom_passes_through_inner_keyframes_smoothly() {
        let p = parse(
            r#"{"frames": 5, "keyframes": [
            {"time": 0, "position": [0, 0, 0], "direction": [1, 0, 0]},
            {"time": 1, "position": [1, 0, 1], "direction": [1, 0, 0]},
            {"time": 2, "position": [2, 0, 0], "direction": [1, 0, 0]}]}"#,
        )
        .unwrap();
        assert!((p.camera(2, 1.0).eye - DVec3::new(1.0, 0.0, 1.0)).length() < 1e-12);
        // Velocity is continuous across the inner keyframe.
        let key = p.keyframes[1].time;
        let probe = |t: f64| {
            let mut q = p.clone();
            q.frames = 2001;
            q.camera((t / 2.0 * 2000.0).round() as u32, 1.0).eye
        };
        let before = (probe(key) - probe(key - 0.001)) / 0.001;
        let after = (probe(key + 0.001) - probe(key)) / 0.001;
        assert!((before - after).length() < 0.01, "{before:?} vs {after:?}");
    }

    #[test]
    fn fps_gives_frames_over_the_span() {
        let p = parse(
            r#"{"fps": 30, "keyframes": [
            {"time": 0, "position": [0, 0, 0], "target": [0, 0, -1]},
            {"time": 2, "position": [1, 0, 0], "target": [1, 0, -1]}]}"#,
        )
        .unwrap();
        assert_eq!(p.frames, 61);
    }

    #[test]
    fn a_view_along_up_needs_an_up_across_it() {
        let down = r#"{"time": 0, "position": [0, 10, 0], "target": [0, 0, 0]"#;
        let e = parse(&format!(r#"{{"frames": 1, "keyframes": [{down}}}]}}"#)).unwrap_err();
        assert!(
            e.to_string()
                .contains("keyframe 0: up [0, 1, 0] lies along the view direction [0, -10, 0]"),
            "{e}"
        );
        let p = parse(&format!(
            r#"{{"frames": 1, "keyframes": [{down}, "up": [0, 0, -1]}}]}}"#
        ))
        .unwrap();
        let c = p.camera(0, 1.0);
        assert!((c.forward() - DVec3::NEG_Y).length() < 1e-12);
        assert!((c.rotation * DVec3::Y - DVec3::NEG_Z).length() < 1e-12, "up as given");
        for zero in [r#""up": [0, 0, 0], "#, ""] {
            let key = if zero.is_empty() { r#", "up": [0, 0, 0]"# } else { "" };
            let json = format!(r#"{{"frames": 1, {zero}"keyframes": [{down}{key}}}]}}"#);
            assert!(
                parse(&json).unwrap_err().to_string().contains("up must not be zero"),
                "{json}"
            );
        }
    }

    #[test]
    fn invalid_paths_say_what_is_wrong() {
        let err = |json: &str| parse(json).expect_err(json).to_string();
        let key = r#"{"time": 0, "position": [0, 0, 0], "target": [0, 0, -1]}"#;
        assert!(err(r#"{"frames": 3, "keyframes": []}"#).contains("no keyframes"));
        assert!(err(&format!(r#"{{"keyframes": [{key}]}}"#)).contains("give frames or fps"));
        assert!(err(&format!(r#"{{"frames": 0, "keyframes": [{key}]}}"#)).contains("frames must be in 1..="));
        assert!(err(&format!(r#"{{"frames": 2, "fps": 3, "keyframes": [{key}]}}"#)).contains("not both"));
        assert!(err(&format!(r#"{{"frames": 2, "near": 0, "keyframes": [{key}]}}"#)).contains("near"));
        assert!(err(&format!(r#"{{"frames": 2, "near": 1e-50, "keyframes": [{key}]}}"#)).contains("near"));
        assert!(err(&format!(r#"{{"frames": 200000, "keyframes": [{key}]}}"#)).contains("frames must be in"));
        assert!(
            err(&format!(
                r#"{{"fps": 1e300, "keyframes": [{key}, {key2}]}}"#,
                key2 = key.replace("\"time\": 0", "\"time\": 1")
            ))
            .contains("more than")
        );
        assert!(err(r#"{"frames": 2, "keyframes": [{"time": -1e308, "position": [0, 0, 0], "target": [0, 0, -1]}, {"time": 1e308, "position": [1, 0, 0], "target": [0, 0, -1]}]}"#).contains("span"));
        assert!(err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0], "target": [0, 0, 1], "fov_y_deg": 1e-300}]}"#).contains("fov_y_deg"));
        // Narrower than the adapters draw a view exactly (FOV_RANGE).
        assert!(err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0], "target": [0, 0, 1], "fov_y_deg": 0.5}]}"#).contains("fov_y_deg must be in 1..=179.9, got 0.5"));
        assert!(
            err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [1e300, 0, 0], "target": [0, 0, 1]}]}"#)
                .contains("within")
        );
        assert!(
            err(&format!(r#"{{"frames": 2, "keyframes": [{key}, {key}]}}"#))
                .contains("keyframe 1: time 0 is not after")
        );
        assert!(err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0]}]}"#).contains("exactly one of"));
        assert!(
            err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0], "target": [0, 0, 0]}]}"#)
                .contains("target equals position")
        );
        assert!(err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0, 0], "target": [0, 0, 1], "fov_y_deg": 180}]}"#).contains("fov_y_deg"));
        assert!(err(r#"{"frames": 2, "keyframs": []}"#).contains("unknown field `keyframs`"));
        assert!(
            err(r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 0], "target": [0, 0, 1]}]}"#)
                .contains("invalid camera path JSON")
        );
    }

    #[test]
    fn written_files_read_back_identically() {
        let file: PathFile = serde_json::from_str(TWO_KEYS).unwrap();
        let text = serde_json::to_string_pretty(&file).unwrap();
        let again: PathFile = serde_json::from_str(&text).unwrap();
        assert_eq!(file, again);
    }
}
