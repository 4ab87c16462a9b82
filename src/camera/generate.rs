//! Camera paths generated from a scene: used when `--path` is omitted and by
//! `occlu path gen`.

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use serde::Serialize;

use super::path::{CameraPath, DEFAULT_FOV_Y_DEG, Interpolation, KeyframeFile, PathError, PathFile};
use crate::scene::Scene;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum PathKind {
    /// Circle the scene at 25° elevation, looking at its centre.
    Orbit,
    /// Eye height along the scene's streets (built-in scenes) or straight
    /// through the middle of the model.
    Walk,
    /// Straight across above the scene, looking ahead and down.
    Flyover,
}

impl fmt::Display for PathKind {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            PathKind::Orbit => "orbit",
            PathKind::Walk => "walk",
            PathKind::Flyover => "flyover",
        })
    }
}

impl FromStr for PathKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        <PathKind as clap::ValueEnum>::from_str(s, true)
    }
}

pub const DEFAULT_FRAMES: u32 = 120;

/// The kind used when no path is given: a walk where the scene suggests one
/// (the city's streets), an orbit otherwise.
pub fn default_kind(scene: &Scene) -> PathKind {
    if scene.walk_hint.is_some() {
        PathKind::Walk
    } else {
        PathKind::Orbit
    }
}

/// The path used when none is given: [`default_kind`], [`DEFAULT_FRAMES`].
pub fn default_path(scene: &Scene) -> Result<CameraPath, PathError> {
    let kind = default_kind(scene);
    CameraPath::from_file(&generate(kind, scene, DEFAULT_FRAMES), &format!("generated:{kind}"))
}

/// A path of `kind` over `scene`, around and above its up axis.
pub fn generate(kind: PathKind, scene: &Scene, frames: u32) -> PathFile {
    let ground = Ground::of(scene);
    let b = scene.bounds;
    let diagonal = b.extent().length().max(1e-6);
    let keyframes = match kind {
        PathKind::Orbit => orbit(&ground, b.center(), diagonal),
        PathKind::Walk => match &scene.walk_hint {
            Some(line) if line.len() >= 2 => walk_along(line, (diagonal * 0.02).max(1.0)),
            _ => {
                let (axis, length) = ground.longer_axis();
                let height = ground.lowest + 0.05 * ground.height();
                let at = |t: f64| ground.lift(b.center() + axis * length * t, height);
                walk_along(&[at(-0.45), at(0.45)], diagonal * 0.05)
            }
        },
        PathKind::Flyover => {
            let (axis, length) = ground.longer_axis();
            let c = ground.lift(b.center(), ground.highest + 0.25 * length);
            let pitch = 35f64.to_radians();
            let direction = axis * pitch.cos() - ground.up * pitch.sin();
            [(0.0, c - axis * length * 0.6), (1.0, c + axis * length * 0.6)]
                .map(|(time, position)| KeyframeFile {
                    time,
                    position: position.to_array(),
                    direction: Some(direction.to_array()),
                    ..key(time, position)
                })
                .to_vec()
        }
    };
    PathFile {
        frames: Some(frames),
        fps: None,
        near: Some(diagonal * 1e-4),
        fov_y_deg: Some(DEFAULT_FOV_Y_DEG),
        up: Some(ground.up.to_array()),
        interpolation: Interpolation::CatmullRom,
        keyframes,
    }
}

fn key(time: f64, position: DVec3) -> KeyframeFile {
    KeyframeFile {
        time,
        position: position.to_array(),
        target: None,
        direction: None,
        orientation: None,
        up: None,
        fov_y_deg: None,
    }
}

/// The scene's ground plane, as its up axis defines it.
struct Ground {
    up: DVec3,
    /// The two axes spanning the ground, and the scene's extent along each.
    across: [(DVec3, f64); 2],
    /// The scene's lowest and highest points along `up`.
    lowest: f64,
    highest: f64,
}

impl Ground {
    fn of(scene: &Scene) -> Ground {
        let up = scene.up.axis.vector();
        let (right, ahead) = scene.up.axis.ground_axes();
        let (b, e) = (scene.bounds, scene.bounds.extent());
        let along = |axis: DVec3| e.dot(axis.abs());
        let heights = b.corners().map(|c| c.dot(up));
        Ground {
            up,
            across: [(right, along(right)), (ahead, along(ahead))],
            lowest: heights.into_iter().fold(f64::INFINITY, f64::min),
            highest: heights.into_iter().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    fn height(&self) -> f64 {
        self.highest - self.lowest
    }

    /// The longer ground axis (pointing to its positive side) and the
    /// scene's extent along it.
    fn longer_axis(&self) -> (DVec3, f64) {
        let [a, b] = self.across;
        let (axis, length) = if a.1 >= b.1 { a } else { b };
        (axis.abs(), length)
    }

    /// `point` moved along `up` to `height`.
    fn lift(&self, point: DVec3, height: f64) -> DVec3 {
        point + self.up * (height - point.dot(self.up))
    }
}

/// Circles the scene's centre `c` about its up axis at 25° elevation, far
/// enough that the bounding sphere (of diameter `diagonal`) fits the
/// vertical field of view.
fn orbit(ground: &Ground, c: DVec3, diagonal: f64) -> Vec<KeyframeFile> {
    let radius = 0.5 * diagonal / (DEFAULT_FOV_Y_DEG.to_radians() / 2.0).sin();
    let elevation = 25f64.to_radians();
    let [(right, _), (ahead, _)] = ground.across;
    let steps = 24;
    (0..=steps)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(steps);
            // For +Y up, (+X, −Z): anticlockwise seen from above.
            let around = right * a.cos() - ahead * a.sin();
            let p = c + radius * (around * elevation.cos() + ground.up * elevation.sin());
            KeyframeFile {
                target: Some(c.to_array()),
                ..key(f64::from(k), p)
            }
        })
        .collect()
}

/// Keyframes every `spacing` units along a polyline, each looking at the
/// point `3·spacing` further on (past the end: straight ahead). Time is
/// arc length, so the walk has constant speed.
fn walk_along(line: &[DVec3], spacing: f64) -> Vec<KeyframeFile> {
    let lengths: Vec<f64> = line.windows(2).map(|w| (w[1] - w[0]).length()).collect();
    let total: f64 = lengths.iter().sum();
    let at = |s: f64| -> DVec3 {
        let mut s = s;
        for (w, &len) in line.windows(2).zip(&lengths) {
            if s <= len || len == 0.0 {
                return w[0] + (w[1] - w[0]) * (s / len.max(f64::MIN_POSITIVE)).min(1.0);
            }
            s -= len;
        }
        // Beyond the end: keep going in the last direction.
        let (a, b) = (line[line.len() - 2], line[line.len() - 1]);
        b + (b - a).normalize_or_zero() * s
    };
    let count = ((total / spacing).ceil() as usize).max(1);
    (0..=count)
        .map(|k| {
            let s = total * k as f64 / count as f64;
            KeyframeFile {
                target: Some(at(s + 3.0 * spacing).to_array()),
                ..key(s, at(s))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::path::CameraPath;
    use crate::scene::{LoadOptions, SceneSpec, load};

    fn city() -> Scene {
        load(&SceneSpec::Builtin("city:blocks=2".into()), &LoadOptions::default()).unwrap()
    }

    #[test]
    fn every_kind_gives_a_valid_path_inside_sensible_bounds() {
        let scene = city();
        for kind in [PathKind::Orbit, PathKind::Walk, PathKind::Flyover] {
            let file = generate(kind, &scene, 30);
            let path = CameraPath::from_file(&file, "gen").unwrap();
            assert_eq!(path.frames, 30);
            for f in 0..30 {
                let c = path.camera(f, 4.0 / 3.0);
                assert!(c.eye.is_finite() && c.rotation.is_finite(), "{kind} frame {f}");
            }
        }
    }

    #[test]
    fn city_walk_stays_at_eye_height_on_the_streets() {
        let scene = city();
        let path = CameraPath::from_file(&generate(PathKind::Walk, &scene, 50), "walk").unwrap();
        for f in 0..50 {
            let c = path.camera(f, 1.0);
            assert!((c.eye.y - crate::scene::builtin::EYE_HEIGHT).abs() < 1e-6);
            // No building contains the eye.
            assert!(
                scene
                    .objects
                    .iter()
                    .filter(|o| o.name.ends_with("/shell"))
                    .all(|o| !o.bounds.contains_point(c.eye))
            );
            assert!(c.forward().y.abs() < 1e-6, "looks along the street");
        }
    }

    #[test]
    fn orbit_keeps_the_scene_centre_in_view() {
        let scene = city();
        let path = CameraPath::from_file(&generate(PathKind::Orbit, &scene, 40), "orbit").unwrap();
        let c = scene.bounds.center();
        for f in 0..40 {
            let cam = path.camera(f, 4.0 / 3.0);
            let to_centre = (c - cam.eye).normalize();
            assert!(cam.forward().dot(to_centre) > 0.999, "frame {f}");
        }
    }
}
