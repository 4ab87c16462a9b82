//! Culling modes: one file per mode, each behind the [`Culler`] trait.
//!
//! A mode owns its state between frames (temporal coherence lives inside the
//! mode) and touches the GPU only through [`FrameCtx`], which counts what it
//! draws. To add a mode: write `cull/NAME.rs` implementing [`Culler`], add
//! it to [`MODES`] and to [`create`].

mod dr;
mod oracle;
mod vfc;

use crate::camera::Camera;
use crate::gpu::FrameCtx;
use crate::hierarchy::Hierarchy;
use crate::object_set::ObjectSet;
use crate::scene::Scene;

pub use dr::DirectRendering;
pub use oracle::Oracle;
pub use vfc::FrustumCulling;

/// What a mode is told about the frame it renders.
pub struct FrameInput<'a> {
    pub frame: u32,
    pub camera: &'a Camera,
    /// The objects that own at least one pixel of the reference frame; given
    /// only to modes whose [`Culler::needs_reference`] is true (the oracle).
    pub reference_visible: Option<&'a ObjectSet>,
}

/// Hierarchy traversal counts of one frame (drawing is counted by `FrameCtx`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    pub nodes_visited: u64,
    pub nodes_culled_frustum: u64,
    pub nodes_culled_occlusion: u64,
}

pub trait Culler {
    /// The mode's name on the command line and in result files.
    fn name(&self) -> &str;

    /// The mode's parameters, recorded in summary.json.
    fn parameters(&self) -> serde_json::Value {
        serde_json::json!({})
    }

    /// Whether the mode needs the reference visible set (only the oracle).
    fn needs_reference(&self) -> bool {
        false
    }

    /// Renders one frame: decides what to draw and draws it through `ctx`.
    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats;
}

/// A mode on the command line.
pub struct ModeInfo {
    pub name: &'static str,
    pub summary: &'static str,
    /// Whether the mode may never change a pixel (0 error required).
    pub conservative: bool,
}

pub const MODES: &[ModeInfo] = &[
    ModeInfo {
        name: "dr",
        summary: "direct rendering: every object, no culling (002 §5)",
        conservative: true,
    },
    ModeInfo {
        name: "vfc",
        summary: "hierarchical view-frustum culling with the fully-inside shortcut (002 §4.1)",
        conservative: true,
    },
    ModeInfo {
        name: "oracle",
        summary: "draws exactly the objects visible in the reference frame: the floor for object-level culling",
        conservative: true,
    },
];

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ModeError {
    #[error("unknown mode '{0}' (modes: {list}, or all)", list = mode_names().join(", "))]
    Unknown(String),
    #[error("no modes given")]
    Empty,
}

pub fn mode_names() -> Vec<&'static str> {
    MODES.iter().map(|m| m.name).collect()
}

/// Parses a comma-separated mode list (`all` for every mode); duplicates are
/// dropped, the order kept.
pub fn parse_modes(list: &[String]) -> Result<Vec<&'static str>, ModeError> {
    let mut modes: Vec<&'static str> = Vec::new();
    for name in list.iter().flat_map(|s| s.split(',')).map(str::trim) {
        let found: Vec<&'static str> = if name == "all" {
            mode_names()
        } else {
            vec![
                MODES
                    .iter()
                    .find(|m| m.name == name)
                    .ok_or_else(|| ModeError::Unknown(name.to_string()))?
                    .name,
            ]
        };
        for m in found {
            if !modes.contains(&m) {
                modes.push(m);
            }
        }
    }
    if modes.is_empty() {
        return Err(ModeError::Empty);
    }
    Ok(modes)
}

/// Creates the culler of a mode named by [`parse_modes`].
pub fn create<'a>(name: &str, scene: &'a Scene, hierarchy: &'a Hierarchy) -> Result<Box<dyn Culler + 'a>, ModeError> {
    Ok(match name {
        "dr" => Box::new(DirectRendering::new(scene)),
        "vfc" => Box::new(FrustumCulling::new(scene, hierarchy)),
        "oracle" => Box::new(Oracle::new()),
        other => return Err(ModeError::Unknown(other.to_string())),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_lists_parse_in_order_without_duplicates() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert_eq!(parse_modes(&s(&["vfc,dr", "vfc"])), Ok(vec!["vfc", "dr"]));
        assert_eq!(parse_modes(&s(&["all"])), Ok(mode_names()));
        assert_eq!(parse_modes(&s(&["dr,bogus"])), Err(ModeError::Unknown("bogus".into())));
        assert_eq!(parse_modes(&s(&[])), Err(ModeError::Empty));
        assert!(ModeError::Unknown("x".into()).to_string().contains("dr, vfc, oracle"));
    }
}
