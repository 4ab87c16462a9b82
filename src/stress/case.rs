//! A stress case: a scene, the cameras of its frames, and the baseline
//! case whose image it must reproduce (stress/cases.rs makes them).

use serde::Serialize;

use crate::camera::Camera;
use crate::gpu::Resolution;
use crate::scene::Scene;

/// One hard case: a scene and the cameras of its frames.
pub struct StressCase {
    pub name: String,
    /// What makes it hard, in a line.
    pub summary: String,
    pub scene: Scene,
    /// One camera per frame; the aspect is set to the viewport's when run.
    pub cameras: Vec<Camera>,
    /// The untransformed case whose image this one must reproduce.
    pub baseline: Option<Baseline>,
    /// The target size this case runs at, where the size is its difficulty
    /// (a depth pyramid over a size that is not a power of two); `None`:
    /// the run's.
    pub resolution: Option<Resolution>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Baseline {
    pub case: String,
    pub tolerance: DepthTolerance,
}

/// How far a pixel's depth may be from the baseline's: |a − b| ≤
/// max(relative · max(a, b), absolute). Depth is reverse-Z, `near / distance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DepthTolerance {
    pub relative: f64,
    pub absolute: f64,
}

impl DepthTolerance {
    /// Bit for bit: a translated scene. The eye is subtracted in f64 before
    /// anything is rounded to f32 (and vertices are stored relative to an
    /// origin near them), so the GPU sees the same numbers.
    pub const EXACT: DepthTolerance = DepthTolerance {
        relative: 0.0,
        absolute: 0.0,
    };

    /// A scaled scene: every f32 vertex and matrix entry rounds differently,
    /// by f32's last place (6e-8 relative), which a surface seen at a grazing
    /// angle turns into up to ~1e-5 of depth at a pixel centre. The absolute
    /// term is for wgpu's GL backend, which maps depth to GL's [−1, 1] clip
    /// range as 2z − w (naga's `ADJUST_COORDINATE_SPACE`): there depth keeps
    /// about 1e-7 of absolute precision rather than reverse-Z's relative one.
    pub const SCALED: DepthTolerance = DepthTolerance {
        relative: 1e-4,
        absolute: 1e-6,
    };

    pub(super) fn allows(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= (self.relative * a.max(b)).max(self.absolute)
    }
}
