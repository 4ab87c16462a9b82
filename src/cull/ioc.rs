//! `ioc`: iterative hierarchical raster occlusion culling, paper 004 §2.
//!
//! `roc` run over the bounding-volume hierarchy instead of single objects:
//! "The BVH is iteratively traversed from a moderate depth down to a deeper
//! level (but not the bottom of the tree)." The nodes at the start depth are
//! tested as one batch; "if the node is culled, we stop the traversal for
//! the node [...]. If the node is a leaf, we directly mark it as a
//! potentially visible occludee in the VB. Otherwise, we tightly pack and
//! enqueue them for the next occlusion test [...]. At the bottom level, all
//! the children in the subtrees of the visible nodes are marked as
//! potentially visible." The hierarchy is cut at the bottom depth once
//! ([`CullTree::cut`]), so a visible node there is a leaf whose subtree's
//! objects are marked.
//!
//! Departure: 004 reads the size of each level's queue back "to drive the
//! indirect multidraw call of the next occlusion test". Here the queue's
//! length is written by the GPU straight into the next level's indirect draw
//! and dispatch arguments, so a level needs no read-back at all; the only
//! one left is roc's list lengths on adapters without indirect counts.
//!
//! Start and bottom depths: 004 names their choice as its open problem.
//! `auto` picks them from the hierarchy alone, see [`auto_depths`].

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use super::roc::cull_on_gpu;
use super::{Culler, FrameInput, ModeError, ModeParams, TraversalStats};
use crate::gpu::{CullTree, FrameCtx, GpuCullTree, MAX_LEVELS};
use crate::hierarchy::Hierarchy;

/// A depth of the hierarchy (root 0), given or chosen from the hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    Auto,
    Fixed(u32),
}

impl FromStr for Depth {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Depth::Auto);
        }
        s.parse()
            .map(Depth::Fixed)
            .map_err(|_| "expected 'auto' or a depth ≥ 0 (the root is 0)".into())
    }
}

impl fmt::Display for Depth {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Depth::Auto => f.write_str("auto"),
            Depth::Fixed(d) => write!(f, "{d}"),
        }
    }
}

impl Serialize for Depth {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IocParams {
    pub start: Depth,
    pub bottom: Depth,
}

impl IocParams {
    pub fn from_params(params: &ModeParams) -> Result<IocParams, ModeError> {
        let p = IocParams {
            start: params.get("ioc", "start")?,
            bottom: params.get("ioc", "bottom")?,
        };
        if let (Depth::Fixed(start), Depth::Fixed(bottom)) = (p.start, p.bottom) {
            if start > bottom {
                return Err(ModeError::BadParam {
                    key: "ioc.start".into(),
                    reason: format!("start depth {start} is below the bottom depth {bottom}"),
                });
            }
            if bottom - start >= MAX_LEVELS {
                return Err(ModeError::BadParam {
                    key: "ioc.bottom".into(),
                    reason: format!("at most {MAX_LEVELS} levels from start to bottom"),
                });
            }
        }
        Ok(p)
    }
}

pub struct IterativeOcclusionCulling {
    params: IocParams,
    /// Chosen in the first frame: the depths, the tree on the GPU, and per
    /// tree node the hierarchy node whose box it tests.
    chosen: Option<(u32, u32)>,
    tree: Option<(GpuCullTree, Vec<u32>)>,
}

impl IterativeOcclusionCulling {
    pub fn new(params: IocParams) -> Self {
        IterativeOcclusionCulling {
            params,
            chosen: None,
            tree: None,
        }
    }
}

impl Culler for IterativeOcclusionCulling {
    fn name(&self) -> &str {
        "ioc"
    }

    fn parameters(&self) -> serde_json::Value {
        let mut p = serde_json::json!(self.params);
        if let Some((start, bottom)) = self.chosen {
            p["start_depth"] = start.into();
            p["bottom_depth"] = bottom.into();
        }
        p
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn culls_on_gpu(&self) -> bool {
        true
    }

    fn frame(&mut self, ctx: &mut FrameCtx, input: &FrameInput) -> TraversalStats {
        let hierarchy = input.hierarchy;
        let (tree, source) = self.tree.get_or_insert_with(|| {
            let (start, bottom) = depths(self.params, hierarchy);
            self.chosen = Some((start, bottom));
            let (tree, source) = CullTree::cut(hierarchy, start, bottom);
            (ctx.upload_cull_tree(&tree), source)
        });
        let bounds = source.iter().map(|&n| hierarchy.nodes[n as usize].bounds);
        cull_on_gpu(ctx, tree, bounds);
        // Nodes tested and hidden are counted on the GPU, read after the frame.
        TraversalStats::default()
    }
}

/// The start and bottom depths for `hierarchy`: the given ones, with `auto`
/// replaced by [`auto_depths`], and the bottom kept within [`MAX_LEVELS`]
/// of the start.
fn depths(params: IocParams, hierarchy: &Hierarchy) -> (u32, u32) {
    let (auto_start, auto_bottom) = auto_depths(hierarchy);
    let start = match (params.start, params.bottom) {
        (Depth::Fixed(d), _) => d,
        (Depth::Auto, Depth::Fixed(bottom)) => auto_start.min(bottom),
        (Depth::Auto, Depth::Auto) => auto_start,
    };
    let bottom = match params.bottom {
        Depth::Fixed(d) => d,
        Depth::Auto => auto_bottom.max(start),
    };
    (start, bottom.min(start + MAX_LEVELS - 1))
}

/// Start and bottom depths from the hierarchy's statistics.
pub fn auto_depths(hierarchy: &Hierarchy) -> (u32, u32) {
    let depth = hierarchy.stats().depth;
    (0, depth.saturating_sub(1))
}
