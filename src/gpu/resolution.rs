//! [`Resolution`]: the size of what is rendered, a plain value that the
//! camera, the configuration and the modes share with the GPU's targets.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// Width × height in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Resolution {
    pub width: u32,
    pub height: u32,
}

/// Largest side accepted: beyond common texture limits and any use here.
const MAX_SIDE: u32 = 8192;

impl Resolution {
    /// The papers' resolution (003 and 004 measure at 800×600).
    pub const DEFAULT: Resolution = Resolution {
        width: 800,
        height: 600,
    };

    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }

    pub fn pixels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

impl FromStr for Resolution {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("resolution must be WIDTHxHEIGHT with sides in 1..={MAX_SIDE}, got '{s}'");
        let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let side = |v: &str| v.trim().parse::<u32>().ok().filter(|n| (1..=MAX_SIDE).contains(n));
        Ok(Resolution {
            width: side(w).ok_or_else(bad)?,
            height: side(h).ok_or_else(bad)?,
        })
    }
}

impl TryFrom<String> for Resolution {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl From<Resolution> for String {
    fn from(r: Resolution) -> String {
        r.to_string()
    }
}

impl fmt::Display for Resolution {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}
