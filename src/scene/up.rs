//! Which way is up in a scene. Generated paths (the orbit's axis, the
//! walk's eye height, the flyover's height) and the overview picture follow
//! it; a camera path file keeps its own `up`.
//!
//! glTF says +Y (its specification, "Coordinate System and Units"), and the
//! built-in scenes are built +Y up. OBJ says nothing, and much of what is
//! exported as OBJ (CityJSON and GIS exports, CAD, 3ds Max, scans) is +Z up,
//! so `--up auto` on an OBJ picks +Z by [`looks_z_up`](crate::scene::looks_z_up), and +Y otherwise.

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::auto_or::AutoOr;

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

/// What `--up` asks for: `auto` is the format's convention, or for OBJ
/// the rule of [`looks_z_up`](crate::scene::looks_z_up).
pub type UpChoice = AutoOr<UpAxis>;

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
        assert_eq!("z".parse(), Ok(AutoOr::Given(UpAxis::Z)));
        assert_eq!("AUTO".parse(), Ok(UpChoice::Auto));
        assert!("up".parse::<UpChoice>().is_err());
    }
}
