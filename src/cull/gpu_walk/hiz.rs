//! `hiz`: two-phase hierarchical-depth culling, as engines ship it
//! (Unreal's HZB, Bevy's two-phase occlusion culling, zeux's niagara). Each
//! frame: (1) **early**: last frame's visible objects are drawn, their depth
//! this frame's occluders; (2) **pyramid**: each texel keeps the farthest
//! depth below it (pyramid.rs); (3) **cull**: a compute pass tests the boxes
//! of the objects in the frustum (`boxes=objects`) or of the hierarchy's
//! nodes (`boxes=nodes`) against the finest level where the box spans at
//! most `texels`² texels, and a box that survives and covers at most
//! `pixels` pixels against the depth at each pixel by the planes where the
//! pixel's ray enters it (pyramid_test.wgsl, gpu/conservative.rs's
//! `BoxPlanes`, made there from the box); (4) **late**: the newly visible
//! objects are drawn. Every object found visible is next frame's list;
//! nothing per object passes between the CPU and the GPU in a frame but
//! the boxes of objects that moved (on GL, without an indirect count, two
//! lengths are read back too).
//!
//! Departures: no early cull against last frame's pyramid (step 1 draws
//! last frame's list untested, as roc and ioc do, so one pyramid a frame
//! suffices and nothing visible last frame is hidden by stale depth); boxes
//! grown eye-relative on the GPU from each centre in two f32 parts (the
//! engines keep one), so a box far from the origin keeps its place; 4×4
//! texels read by default, not 2×2 (`texels=2` is the engines'); the
//! pyramid's base a power of two at most the target over `base`, each
//! target texel read by the base texel its test maps it to (bevy#14062);
//! and the per-pixel test after the pyramid, which engines lack: a box just
//! behind a wall seen at a slant is not hidden by a farthest depth over
//! texels of several pixels, and this test hides what roc's fragments
//! hide.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use super::depths::{BOTTOM, DepthRange, START};
use super::{GpuCulling, NodeTest, Walked};
use crate::auto_or::AutoOr;
use crate::cull::mode::{Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};

/// This mode's entry in the registry.
pub(in crate::cull) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Hiz,
    summary: "two-phase hierarchical-depth culling: last frame's visible objects drawn, a depth pyramid built from them, every box tested against it in a compute pass (small ones pixel by pixel where it cannot hide them), the newly visible drawn (Unreal's HZB, Bevy, niagara)",
    chart_colour: [227, 119, 194],
    conservative: true,
    draws_by_time: false,
    params: &[TEXELS, BASE, PIXELS, BOXES, START, BOTTOM],
    exercised_with: &[],
    needs: Needs::GpuCulling,
    carries: Carries::VisibleOnGpu,
    auto: Candidacy::Always,
    check: |params| HizParams::from_params(params).map(drop),
    build: |_, params| Ok(Box::new(hierarchical_depth_culling(HizParams::from_params(params)?))),
};

const TEXELS: ParamInfo = ParamInfo {
    key: "texels",
    default: "4",
    summary: "texels a box's rectangle may span across at the pyramid level it is read at (2 to 16): 2 reads at most 2×2 texels as the engines do; 4 reads a level finer, which hides more for about the same test time",
};

/// The range of [`TEXELS`].
const TEXELS_RANGE: std::ops::RangeInclusive<u32> = 2..=16;

const BASE: ParamInfo = ParamInfo {
    key: "base",
    default: "4",
    summary: "the pyramid's base is the largest power of two at most the target's size over this (1 to 16; 1 is niagara's base): a smaller base is built faster, and boxes it cannot hide are read pixel by pixel (hiz.pixels)",
};

/// The range of [`BASE`].
const BASE_RANGE: std::ops::RangeInclusive<u32> = 1..=16;

const PIXELS: ParamInfo = ParamInfo {
    key: "pixels",
    default: "65536",
    summary: "where the pyramid cannot hide a box whose rectangle holds at most this many pixels, compare it with the depth at each of them, by the planes where pixel rays enter it (0: the pyramid alone, as the engines test; at most 65536)",
};

/// The range of [`PIXELS`].
const PIXELS_RANGE: std::ops::RangeInclusive<u32> = 0..=1 << 16;

const BOXES: ParamInfo = ParamInfo {
    key: "boxes",
    default: "objects",
    summary: "what is tested against the pyramid: objects (every object's box, one level) or nodes (the hierarchy's, from hiz.start to hiz.bottom)",
};

/// What hiz tests against the pyramid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxesTested {
    Objects,
    Nodes,
}

impl FromStr for BoxesTested {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "objects" => Ok(BoxesTested::Objects),
            "nodes" => Ok(BoxesTested::Nodes),
            _ => Err("expected 'objects' or 'nodes'".into()),
        }
    }
}

impl fmt::Display for BoxesTested {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            BoxesTested::Objects => "objects",
            BoxesTested::Nodes => "nodes",
        })
    }
}

impl Serialize for BoxesTested {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HizParams {
    /// Texels across a rectangle may span at the level it is read at.
    pub texels: u32,
    /// The pyramid's base: the largest power of two at most the target's
    /// size over this.
    #[serde(rename = "base")]
    pub base_divisor: u32,
    /// Pixels a rectangle may hold to be tested pixel by pixel where the
    /// pyramid does not hide it (0: never).
    pub pixels: u32,
    pub boxes: BoxesTested,
    /// The depths walked with `boxes=nodes`.
    #[serde(flatten)]
    pub range: DepthRange,
}

impl HizParams {
    pub fn from_params(params: &ModeParams) -> Result<HizParams, ModeError> {
        let p = HizParams {
            texels: params.get(ModeId::Hiz, &TEXELS)?,
            base_divisor: params.get(ModeId::Hiz, &BASE)?,
            pixels: params.get(ModeId::Hiz, &PIXELS)?,
            boxes: params.get(ModeId::Hiz, &BOXES)?,
            range: DepthRange::from_params(ModeId::Hiz, params)?,
        };
        if !TEXELS_RANGE.contains(&p.texels) {
            let reason = format!("{} is not within 2 to 16", p.texels);
            return Err(ModeError::bad(ModeId::Hiz, &TEXELS, reason));
        }
        if !BASE_RANGE.contains(&p.base_divisor) {
            let reason = format!("{} is not within 1 to 16", p.base_divisor);
            return Err(ModeError::bad(ModeId::Hiz, &BASE, reason));
        }
        if !PIXELS_RANGE.contains(&p.pixels) {
            let reason = format!("{} is more than {}", p.pixels, PIXELS_RANGE.end());
            return Err(ModeError::bad(ModeId::Hiz, &PIXELS, reason));
        }
        let fixed = |d| matches!(d, AutoOr::Given(_));
        if p.boxes == BoxesTested::Objects && (fixed(p.range.start) || fixed(p.range.bottom)) {
            let reason = "start and bottom depths apply only with hiz.boxes=nodes".to_string();
            return Err(ModeError::bad(ModeId::Hiz, &BOXES, reason));
        }
        Ok(p)
    }
}

/// hiz over objects or nodes, as `params` say.
pub fn hierarchical_depth_culling(params: HizParams) -> GpuCulling {
    let walked = match params.boxes {
        BoxesTested::Objects => Walked::Objects,
        BoxesTested::Nodes => Walked::Nodes(params.range),
    };
    let test = NodeTest::Pyramid {
        texels: params.texels,
        base_divisor: params.base_divisor,
        pixels: params.pixels,
    };
    // Depths are recorded only where they are used.
    let recorded = match params.boxes {
        BoxesTested::Objects => serde_json::json!({
            "texels": params.texels,
            "base": params.base_divisor,
            "pixels": params.pixels,
            "boxes": params.boxes,
        }),
        BoxesTested::Nodes => serde_json::json!(params),
    };
    GpuCulling::new(ModeId::Hiz, walked, test, recorded)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::gpu_walk::depths::Level;

    fn parse(items: &[&str]) -> Result<HizParams, ModeError> {
        let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
        HizParams::from_params(&ModeParams::parse(&items, &[ModeId::Hiz])?)
    }

    #[test]
    fn depths_are_taken_only_with_nodes() {
        assert_eq!(parse(&[]).unwrap().boxes, BoxesTested::Objects);
        let nodes = parse(&["hiz.boxes=nodes", "hiz.start=3"]).unwrap();
        assert_eq!(
            (nodes.boxes, nodes.range.start),
            (BoxesTested::Nodes, AutoOr::Given(Level(3)))
        );
        let err = parse(&["hiz.start=3"]).unwrap_err().to_string();
        assert!(err.contains("only with hiz.boxes=nodes"), "{err}");
        let err = parse(&["hiz.boxes=meshlets"]).unwrap_err().to_string();
        assert!(err.contains("'objects' or 'nodes'"), "{err}");
        let err = parse(&["hiz.texels=17"]).unwrap_err().to_string();
        assert!(err.contains("within 2 to 16"), "{err}");
        assert_eq!(parse(&["hiz.pixels=0"]).unwrap().pixels, 0);
        assert_eq!(parse(&["hiz.base=1"]).unwrap().base_divisor, 1);
        let err = parse(&["hiz.base=0"]).unwrap_err().to_string();
        assert!(err.contains("within 1 to 16"), "{err}");
        let err = parse(&["hiz.pixels=65537"]).unwrap_err().to_string();
        assert!(err.contains("more than 65536"), "{err}");
    }
}
