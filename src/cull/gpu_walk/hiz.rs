//! `hiz`: two-phase hierarchical-depth culling, the occlusion culling most
//! engines ship today: Unreal's HZB occlusion, Bevy's two-phase occlusion
//! culling (`occlusion_culling.wesl`, `downsample_depth.wesl`), zeux's
//! niagara (`drawcull.comp.glsl`, `depthreduce.comp.glsl`). Each frame:
//!
//! 1. **Early**: last frame's visible objects are drawn (indirect
//!    multi-draw); their depth is this frame's occluders.
//! 2. **Pyramid**: a depth pyramid is built from that depth (pyramid.rs):
//!    each texel keeps the farthest depth below it, conservative at any
//!    target size; its base is the largest power of two at most the
//!    target's size over `base` (4 by default).
//! 3. **Cull**: a compute pass a level tests the boxes of every object
//!    in the frustum (`boxes=objects`, as Bevy and niagara do), or of the
//!    hierarchy's nodes from a start depth (`boxes=nodes`): the box's screen
//!    rectangle rounded outward, the finest level where it spans at most
//!    `texels` × `texels` texels (4 by default), and the box's nearest depth
//!    against the farthest of those texels (pyramid_test.wgsl). Where that
//!    does not hide it and the rectangle holds at most `pixels` pixels
//!    (65536, the most, by default), the box is compared with the depth
//!    itself at each pixel, by the planes where the pixel's ray enters it
//!    (gpu/conservative.rs's `BoxPlanes`, made on the CPU) or misses it: the
//!    pass queues such boxes, and a second dispatch gives each a workgroup,
//!    which reads only the pixels of the base texels that do not hide the
//!    box by its planes on their own.
//!    Boxes reaching the near plane are visible untested, as in niagara.
//! 4. **Late**: the newly visible objects are drawn (indirect, the count
//!    from the GPU). Every object found visible in step 3, drawn early or
//!    late, is next frame's visible list; one drawn early and now hidden
//!    drops out of it.
//!
//! No per-object result reaches the CPU; on GL, which has no indirect
//! count, the two list lengths are read back before step 4, as roc does.
//!
//! Departures:
//! - The engines test against last frame's pyramid too, in an early cull
//!   before step 1, and build a second pyramid after step 4 for the next
//!   frame. Here step 1 draws last frame's visible list untested (004's
//!   scheme, shared with roc and ioc), so one pyramid a frame suffices and
//!   an object visible last frame is never culled by stale depth: the
//!   result is conservative in the current frame even when the camera
//!   teleports.
//! - Boxes are made eye-relative and grown on the CPU in f64 (as for every
//!   box test here: gpu/conservative.rs) rather than transformed from world
//!   bounds on the GPU; the engines test bounding spheres or boxes in f32.
//! - The engines read 2×2 texels (niagara, Bevy); here 4×4 by default,
//!   one level finer, since the reads cost little next to the pyramid and
//!   cull more (`texels=2` is theirs).
//! - The pyramid's base is the largest power of two at most the target's
//!   size over `base` (niagara's choice with `base=1`; each reduction stays
//!   2×2); each target texel lies in the base texel its test reads it
//!   by, so none is skipped where the size is not a power of two
//!   (bevy#14062), and the base reads each once.
//! - The engines stop at the pyramid. A box's nearest depth against the
//!   farthest depth over texels of two or more pixels cannot hide a box
//!   just behind a wall seen at a slant, whose depth changes across a
//!   texel by more than the gap; over the default city walk that left four
//!   times as many objects visible as roc's raster test, whatever the
//!   pyramid's resolution. The pixel by pixel test compares what roc's
//!   fragments compare, so hiz hides what roc hides; the pyramid then only
//!   has to hide what lies far behind, and a base a quarter of the target's
//!   on each side (`base=4`) is built three times faster on llvmpipe for the
//!   same result. Boxes the pyramid does not hide are queued on the GPU and
//!   tested one workgroup each, its invocations sharing first the base
//!   texels under the box, each compared with the box's entry planes at
//!   their nearest over its pixels (and, for the rays missing the box,
//!   its exit planes at their farthest), then the pixels of the texels
//!   that did not hide it (every pixel of the rectangle where more than
//!   2 048 texels did not, mostly on fine bases): a large box far
//!   behind a wall, or a long one seen at a slant, is decided mostly from
//!   its texels. On llvmpipe over the default city walk at
//!   `pixels=65536`, the tests after the pyramid took 3.1 ms a frame where
//!   reading every pixel took 5.1, and the rays' misses took another
//!   quarter off.

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
    conservative: true,
    params: &[TEXELS, BASE, PIXELS, BOXES, START, BOTTOM],
    needs: Needs::GpuCulling,
    carries: Carries::VisibleOnGpu,
    auto: Candidacy::Always,
    check: |params| HizParams::from_params(params).map(drop),
    build: |_, params| Ok(Box::new(hierarchical_depth_culling(HizParams::from_params(params)?))),
};

const TEXELS: ParamInfo = ParamInfo {
    key: "texels",
    default: "4",
    summary: "texels a box's rectangle may span across at the pyramid level it is read at (2 to 16): 2 reads at most 2×2 texels as the engines do; 4 reads a level finer, which on the default city walk drew 26% fewer triangles for the same test time",
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
    GpuCulling::new("hiz", walked, test, recorded)
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
