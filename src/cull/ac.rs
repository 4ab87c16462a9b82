//! `ac`: view-frustum and occlusion culling with adaptive culling and a
//! cost-adaptive budget, paper 002 §4.2–4.4.
//!
//! Traversal (§4.4, "Overall Refined Algorithm"): a DepthList ordered by
//! z_min; the head node's box is tested against everything drawn so far by
//! counting its visible pixels (§4.2's "virtual occlusion buffer", here a
//! forced early depth test adding into a counter per box,
//! shaders/pixel_count.wgsl). Adaptive culling (§4.3, Eq. 1) treats a
//! visible node that contributes too little as occluded; cost-adaptive
//! culling (§4.4, Eq. 2) only frustum-culls what is left once the frame's
//! culling budget is spent. Progressive sampling (§4.2, `ac.sampling`)
//! counts every k-th row of spans. Neither adaptive culling nor sampling is
//! conservative: their error is measured, not assumed.
//!
//! Departures: the listing renders a leaf taken from the DepthList without
//! testing it; here leaves are tested like every node, since the pixel count
//! of its box is what adaptive culling weighs (our leaves hold a few
//! objects, the paper's many polygons). The listing's final
//! `if (UsedTime < Budget) render(remaining_geometry)` is read as "once the
//! budget is used up", which is what the text says. The progressive
//! refinement of §4.2 while the camera stands still is not implemented: a
//! benchmark path always moves.

use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant};

use serde::Serialize;

use super::traversal::{DepthQueue, children, draw_leaf, frustum_cull_subtree, in_frustum, view_depth};
use crate::auto_or::AutoOr;
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{BoxTest, BoxVisibility, Frame};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Ac,
    summary: "V+O with adaptive culling (Eq. 1) and a cost-adaptive budget (Eq. 2) by visible-pixel counts (002 §4.2-4.4)",
    chart_colour: [148, 103, 189],
    conservative: false,
    draws_by_time: true,
    params: &[THRESHOLD, SAMPLING, F_GRAPHICS, EYE_DISTANCE],
    exercised_with: &[],
    needs: Needs::PixelCounts,
    carries: Carries::Nothing,
    auto: Candidacy::Never,
    check: |params| AcParams::from_params(params).map(drop),
    build: |_, params| Ok(Box::new(AdaptiveCulling::new(AcParams::from_params(params)?))),
};

const THRESHOLD: ParamInfo = ParamInfo {
    key: "threshold",
    default: "auto",
    summary: "Eq. 1 threshold in pixels; auto = 100 px on 650x650 scaled to the viewport",
};

const SAMPLING: ParamInfo = ParamInfo {
    key: "sampling",
    default: "1",
    summary: "count every k-th row of spans (1: every pixel)",
};

const F_GRAPHICS: ParamInfo = ParamInfo {
    key: "f_graphics",
    default: "0.3333333333333333",
    summary: "Eq. 2 culling budget = previous render time x this (inf: no budget)",
};

const EYE_DISTANCE: ParamInfo = ParamInfo {
    key: "eye_distance",
    default: "near",
    summary: "Dist(Eye) of Eq. 1: the near plane, or a distance",
};

/// The threshold of Eq. 1: `auto` is the paper's 100 pixels on 650×650,
/// scaled to the viewport.
pub type Threshold = AutoOr<Pixels>;

/// A number of pixels, at least 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pixels(pub f64);

/// Dist(Eye) of Eq. 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EyeDistance {
    /// The near-plane distance: the view plane of the projection.
    Near,
    Units(f64),
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AcParams {
    pub threshold: Threshold,
    pub sampling: u32,
    /// F_graphics of Eq. 2; infinite for no budget.
    pub f_graphics: f64,
    pub eye_distance: EyeDistance,
}

impl AcParams {
    pub fn from_params(params: &ModeParams) -> Result<AcParams, ModeError> {
        let bad = |param, reason| ModeError::bad(ModeId::Ac, param, reason);
        let sampling: u32 = params.get(ModeId::Ac, &SAMPLING)?;
        if sampling == 0 {
            return Err(bad(&SAMPLING, "must be at least 1".into()));
        }
        let f_graphics: f64 = params.get(ModeId::Ac, &F_GRAPHICS)?;
        if f_graphics.is_nan() || f_graphics < 0.0 {
            return Err(bad(
                &F_GRAPHICS,
                format!("must be 0 or more (inf: no budget), got {f_graphics}"),
            ));
        }
        Ok(AcParams {
            threshold: params.get(ModeId::Ac, &THRESHOLD)?,
            sampling,
            f_graphics,
            eye_distance: params.get(ModeId::Ac, &EYE_DISTANCE)?,
        })
    }
}

/// The paper's view plane and threshold, "100 (0.02 % of view plane) … on a
/// view plane of 650 by 650 pixels", scaled to the viewport by default.
const PAPER_THRESHOLD: f64 = 100.0;
const PAPER_VIEW_PLANE: f64 = 650.0 * 650.0;

impl Threshold {
    fn pixels(self, viewport_pixels: u64) -> f64 {
        match self {
            AutoOr::Auto => PAPER_THRESHOLD * viewport_pixels as f64 / PAPER_VIEW_PLANE,
            AutoOr::Given(Pixels(p)) => p,
        }
    }
}

impl FromStr for Pixels {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.parse::<f64>() {
            Ok(p) if p >= 0.0 && p.is_finite() => Ok(Pixels(p)),
            _ => Err("expected 'auto' or a number of pixels ≥ 0".into()),
        }
    }
}

impl FromStr for EyeDistance {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "near" {
            return Ok(EyeDistance::Near);
        }
        match s.parse::<f64>() {
            Ok(d) if d > 0.0 && d.is_finite() => Ok(EyeDistance::Units(d)),
            _ => Err("expected 'near' or a positive distance".into()),
        }
    }
}

impl fmt::Display for Pixels {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl fmt::Display for EyeDistance {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            EyeDistance::Near => f.write_str("near"),
            EyeDistance::Units(d) => write!(f, "{d}"),
        }
    }
}

// Recorded in summary.json as written on the command line.
impl Serialize for EyeDistance {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

pub struct AdaptiveCulling {
    params: AcParams,
    depth_list: DepthQueue,
    result: Vec<BoxVisibility>,
    objects: Vec<u32>,
    stack: Vec<u32>,
}

impl AdaptiveCulling {
    pub fn new(params: AcParams) -> Self {
        AdaptiveCulling {
            params,
            depth_list: DepthQueue::default(),
            result: Vec::with_capacity(1),
            objects: Vec::new(),
            stack: Vec::new(),
        }
    }
}

impl Culler for AdaptiveCulling {
    fn name(&self) -> &str {
        ModeId::Ac.name()
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(self.params).expect("plain struct serialises")
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let start = Instant::now();
        let camera = input.camera;
        let frustum = camera.frustum();
        let (scene, hierarchy) = (input.scene, input.hierarchy);
        let nodes = &hierarchy.nodes;
        let threshold = self.params.threshold.pixels(input.resolution.pixels());
        let eye_distance = match self.params.eye_distance {
            EyeDistance::Near => camera.near,
            EyeDistance::Units(d) => d,
        };
        // Eq. 2: T_culling = T_render · F_graphics, T_render being the
        // previous frame's drawing time (1/3 as on the O2 by default). No
        // budget in the first frame, which has no previous one.
        let budget = input
            .previous
            .map(|p| p.render_ms * self.params.f_graphics)
            .filter(|ms| ms.is_finite())
            .map(|ms| Duration::from_secs_f64(ms.max(0.0) / 1e3));
        let mut stats = TraversalStats::default();

        // InitDepthList: the uppermost nodes inside the frustum.
        self.depth_list.clear();
        let root = &nodes[0];
        // The root itself only when it is a leaf (then it has no children).
        let uppermost = std::iter::once(0).filter(|_| root.is_leaf()).chain(children(root));
        for node in in_frustum(hierarchy, uppermost, &frustum, &mut stats) {
            self.depth_list
                .push(node, view_depth(&nodes[node as usize].bounds, camera));
        }

        while let Some(index) = self.depth_list.pop() {
            if budget.is_some_and(|b| start.elapsed() >= b) {
                // "Once the accumulated culling time of the current frame
                // exceeds T_culling, the remaining nodes are simply culled
                // against the view-frustum and sent to the rendering
                // pipeline", with §4.1's fully-inside shortcut.
                self.objects.clear();
                let mut rest = Some(index);
                while let Some(node) = rest {
                    stats.nodes_past_budget += 1;
                    frustum_cull_subtree(
                        scene,
                        hierarchy,
                        node,
                        &frustum,
                        &mut self.stack,
                        &mut self.objects,
                        &mut stats,
                    );
                    rest = self.depth_list.pop();
                }
                ctx.draw(&self.objects);
                break;
            }
            let node = &nodes[index as usize];
            ctx.test_boxes(
                std::slice::from_ref(&node.bounds),
                BoxTest::PixelCount {
                    sampling: self.params.sampling,
                },
                &mut self.result,
            );
            if let BoxVisibility::Samples(counted) = self.result[0] {
                if counted == 0 {
                    stats.nodes_culled_occlusion += 1;
                    continue;
                }
                // Eq. 1: measure = V · (Dist(Eye) + Dist(Obj)) / Dist(Eye),
                // V the visible pixels (the footprint on the view plane),
                // Dist(Eye) the eye's distance to the view plane and
                // Dist(Obj) the view plane's to the box's nearest corner:
                // distant nodes weigh more, as §4.3 argues ("a large but
                // distant object might have a larger visual impact"). With
                // sampling, V is the count times k.
                let visible = (counted * u64::from(self.params.sampling)) as f64;
                let distance = (view_depth(&node.bounds, camera) - camera.near).max(0.0);
                let measure = visible * (eye_distance + distance) / eye_distance;
                if measure < threshold {
                    stats.nodes_culled_adaptive += 1;
                    continue;
                }
            }
            if node.is_leaf() {
                draw_leaf(ctx, scene, hierarchy, node, &frustum, &mut self.objects);
            } else {
                for child in in_frustum(hierarchy, children(node), &frustum, &mut stats) {
                    self.depth_list
                        .push(child, view_depth(&nodes[child as usize].bounds, camera));
                }
            }
        }
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_threshold_is_the_papers_scaled_to_the_viewport() {
        assert_eq!(AutoOr::Auto.pixels(650 * 650), 100.0);
        assert!((AutoOr::Auto.pixels(800 * 600) - 113.6).abs() < 0.1);
        assert_eq!(AutoOr::Given(Pixels(7.0)).pixels(1), 7.0);
    }

    #[test]
    fn parameters_parse_and_reject_nonsense() {
        assert_eq!("auto".parse(), Ok(Threshold::Auto));
        assert_eq!("50".parse(), Ok(AutoOr::Given(Pixels(50.0))));
        assert!("-1".parse::<Threshold>().is_err());
        assert_eq!("near".parse(), Ok(EyeDistance::Near));
        assert!("0".parse::<EyeDistance>().is_err());
        let p = |items: &[&str]| {
            let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
            ModeParams::parse(&items, &[ModeId::Ac]).and_then(|m| AcParams::from_params(&m))
        };
        let defaults = p(&[]).unwrap();
        assert_eq!(defaults.threshold, AutoOr::Auto);
        assert_eq!((defaults.sampling, defaults.eye_distance), (1, EyeDistance::Near));
        assert!((defaults.f_graphics - 1.0 / 3.0).abs() < 1e-9);
        assert!(p(&["ac.f_graphics=inf"]).unwrap().f_graphics.is_infinite());
        assert!(p(&["ac.sampling=0"]).is_err());
        assert!(p(&["ac.f_graphics=-1"]).is_err());
    }
}
