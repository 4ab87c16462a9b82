//! Which way is up in a scene. Generated paths (the orbit's axis, the
//! walk's eye height, the flyover's height) and the overview picture follow
//! it; a camera path file keeps its own `up`.
//!
//! glTF says +Y (its specification, "Coordinate System and Units"), and the
//! built-in scenes are built +Y up. OBJ says nothing, and much of what is
//! exported as OBJ (CityJSON and GIS exports, CAD, 3ds Max, scans) is +Z up,
//! so `--up auto` on an OBJ picks +Z by [`looks_z_up`], and +Y otherwise.

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::Scene;

/// One of the six axis directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UpAxis {
    X,
    Y,
    Z,
    NegX,
    NegY,
    NegZ,
}

impl UpAxis {
    pub fn vector(self) -> DVec3 {
        match self {
            UpAxis::X => DVec3::X,
            UpAxis::Y => DVec3::Y,
            UpAxis::Z => DVec3::Z,
            UpAxis::NegX => DVec3::NEG_X,
            UpAxis::NegY => DVec3::NEG_Y,
            UpAxis::NegZ => DVec3::NEG_Z,
        }
    }

    /// Two unit axes spanning the ground, `(right, ahead)`, with
    /// `right × ahead = up`: for +Y, (+X, −Z), so a picture looking down
    /// has −Z ("north" in a +Y-up scene) at its top; for +Z, (+X, +Y).
    pub fn ground_axes(self) -> (DVec3, DVec3) {
        let up = self.vector();
        let right = if up.x == 0.0 { DVec3::X } else { DVec3::Y };
        (right, up.cross(right))
    }
}

impl fmt::Display for UpAxis {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            UpAxis::X => "+X",
            UpAxis::Y => "+Y",
            UpAxis::Z => "+Z",
            UpAxis::NegX => "-X",
            UpAxis::NegY => "-Y",
            UpAxis::NegZ => "-Z",
        })
    }
}

impl FromStr for UpAxis {
    type Err = String;

    fn from_str(text: &str) -> Result<UpAxis, String> {
        Ok(match text.to_ascii_lowercase().as_str() {
            "x" | "+x" => UpAxis::X,
            "y" | "+y" => UpAxis::Y,
            "z" | "+z" => UpAxis::Z,
            "-x" => UpAxis::NegX,
            "-y" => UpAxis::NegY,
            "-z" => UpAxis::NegZ,
            _ => return Err(format!("'{text}' is not an up axis (x, y, z, -x, -y, -z or auto)")),
        })
    }
}

/// What `--up` asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpChoice {
    /// The format's convention, or for OBJ the rule of [`looks_z_up`].
    #[default]
    Auto,
    Axis(UpAxis),
}

impl FromStr for UpChoice {
    type Err = String;

    fn from_str(text: &str) -> Result<UpChoice, String> {
        if text.eq_ignore_ascii_case("auto") {
            Ok(UpChoice::Auto)
        } else {
            text.parse().map(UpChoice::Axis)
        }
    }
}

impl fmt::Display for UpChoice {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            UpChoice::Auto => f.write_str("auto"),
            UpChoice::Axis(axis) => axis.fmt(f),
        }
    }
}

impl Serialize for UpChoice {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for UpChoice {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<UpChoice, D::Error> {
        String::deserialize(d)?.parse().map_err(serde::de::Error::custom)
    }
}

/// A scene's up axis and why it was chosen (`info` prints both, and
/// summary.json records them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Up {
    #[serde(with = "axis_text")]
    pub axis: UpAxis,
    pub why: String,
}

impl Default for Up {
    fn default() -> Up {
        Up {
            axis: UpAxis::Y,
            why: "+Y by default".into(),
        }
    }
}

/// Where a scene came from, for the automatic choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Obj,
    Gltf,
    Builtin,
}

/// The up axis of `scene`, loaded from `source`, as `choice` asks.
pub fn choose(choice: UpChoice, source: Source, scene: &Scene) -> Up {
    match (choice, source) {
        (UpChoice::Axis(axis), _) => Up {
            axis,
            why: "given by --up".into(),
        },
        (UpChoice::Auto, Source::Gltf) => Up {
            axis: UpAxis::Y,
            why: "auto: glTF is +Y up".into(),
        },
        (UpChoice::Auto, Source::Builtin) => Up {
            axis: UpAxis::Y,
            why: "auto: built-in scenes are +Y up".into(),
        },
        (UpChoice::Auto, Source::Obj) => match looks_z_up(scene) {
            Some(evidence) => Up {
                axis: UpAxis::Z,
                why: format!("auto: OBJ {evidence}"),
            },
            None => Up {
                axis: UpAxis::Y,
                why: "auto: OBJ, +Y as most OBJ exporters write (it does not look +Z up)".into(),
            },
        },
    }
}

/// Why a model looks +Z up, if it does: it is at least twice as flat in Z as
/// across both X and Y (a city, a site, a floor plan), and it stands on its
/// Z minimum. Standing is told by its objects: many start at the lowest Z
/// and end below the highest (buildings of different heights on a ground),
/// at least twice as many as the other way round. A Y-up model that is
/// merely thin in Z (a facade, a sign) has parts spanning its whole depth,
/// or as many at the back as at the front, and keeps +Y.
pub fn looks_z_up(scene: &Scene) -> Option<String> {
    let (b, e) = (scene.bounds, scene.bounds.extent());
    let across = e.x.min(e.y);
    if !(e.z > 0.0 && e.z * FLATNESS <= across) {
        return None;
    }
    let near = 0.1 * e.z;
    let at_bottom = |o: &super::Object| o.bounds.min.z - b.min.z <= near;
    let at_top = |o: &super::Object| b.max.z - o.bounds.max.z <= near;
    let standing = scene.objects.iter().filter(|o| at_bottom(o) && !at_top(o)).count();
    let hanging = scene.objects.iter().filter(|o| at_top(o) && !at_bottom(o)).count();
    (standing >= MIN_STANDING && standing >= 2 * hanging).then(|| {
        format!(
            "looks +Z up: {:.1}× flatter in Z than across, {standing} objects standing on its Z minimum ({hanging} hanging from its maximum)",
            across / e.z
        )
    })
}

/// How much flatter in the up axis than across a +Z-up model must be.
const FLATNESS: f64 = 2.0;

/// Objects standing on the ground that a +Z-up model needs at least.
const MIN_STANDING: usize = 3;

/// An axis in JSON as `info` prints it ("+Z").
mod axis_text {
    use serde::{Deserialize, Deserializer, Serializer};

    use super::UpAxis;

    pub fn serialize<S: Serializer>(axis: &UpAxis, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(axis)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<UpAxis, D::Error> {
        String::deserialize(d)?.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_read_and_print_and_span_the_ground() {
        for axis in [
            UpAxis::X,
            UpAxis::Y,
            UpAxis::Z,
            UpAxis::NegX,
            UpAxis::NegY,
            UpAxis::NegZ,
        ] {
            assert_eq!(axis.to_string().parse::<UpAxis>(), Ok(axis));
            let (right, ahead) = axis.ground_axes();
            assert_eq!(right.cross(ahead), axis.vector(), "{axis}");
            assert_eq!(right.dot(axis.vector()), 0.0);
        }
        assert_eq!(UpAxis::Y.ground_axes(), (DVec3::X, DVec3::NEG_Z));
        assert_eq!("z".parse(), Ok(UpChoice::Axis(UpAxis::Z)));
        assert_eq!("AUTO".parse(), Ok(UpChoice::Auto));
        assert!("up".parse::<UpChoice>().is_err());
    }
}
