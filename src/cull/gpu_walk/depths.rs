//! The depths of the hierarchy a GPU walk over nodes tests, from a start
//! depth down to a bottom depth (`ioc`, and `hiz` with `boxes=nodes`): the
//! parameters, and their choice from the hierarchy's statistics where they
//! are `auto`.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use super::MAX_LEVELS;
use crate::auto_or::AutoOr;
use crate::cull::mode::{ModeError, ModeId, ModeParams, ParamInfo};
use crate::hierarchy::Hierarchy;
use crate::scene::Object;

pub(super) const START: ParamInfo = ParamInfo {
    key: "start",
    default: "auto",
    summary: "depth whose nodes are tested first (root 0); auto: from the hierarchy",
};

pub(super) const BOTTOM: ParamInfo = ParamInfo {
    key: "bottom",
    default: "auto",
    summary: "depth below which nodes are not tested: a visible node there draws its subtree; auto: from the hierarchy",
};

/// A depth of the hierarchy, given or chosen from the hierarchy (`auto`).
pub type Depth = AutoOr<Level>;

/// A depth of the hierarchy: the root is 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level(pub u32);

impl FromStr for Level {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        s.parse()
            .map(Level)
            .map_err(|_| "expected 'auto' or a depth ≥ 0 (the root is 0)".into())
    }
}

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// The depths of the hierarchy a walk tests, from `start` down to
/// `bottom` (ioc's parameters, and hiz's over nodes).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DepthRange {
    pub start: Depth,
    pub bottom: Depth,
}

impl DepthRange {
    /// `mode`'s [`START`] and [`BOTTOM`] parameters.
    pub fn from_params(mode: ModeId, params: &ModeParams) -> Result<DepthRange, ModeError> {
        let p = DepthRange {
            start: params.get(mode, &START)?,
            bottom: params.get(mode, &BOTTOM)?,
        };
        if let (AutoOr::Given(Level(start)), AutoOr::Given(Level(bottom))) = (p.start, p.bottom) {
            if start > bottom {
                let reason = format!("start depth {start} is below the bottom depth {bottom}");
                return Err(ModeError::bad(mode, &START, reason));
            }
            if bottom - start >= MAX_LEVELS {
                let reason = format!("at most {MAX_LEVELS} levels from start to bottom");
                return Err(ModeError::bad(mode, &BOTTOM, reason));
            }
        }
        Ok(p)
    }

    /// The start and bottom depths for `hierarchy` over `objects`: the
    /// given ones, with `auto` replaced by [`auto_depths`], both at most the
    /// hierarchy's deepest (a deeper one walks the same tree, and would be
    /// recorded as if it did not), and the bottom kept within
    /// [`MAX_LEVELS`] of the start.
    pub fn choose(self, hierarchy: &Hierarchy, objects: &[Object]) -> (u32, u32) {
        let deepest = hierarchy.stats().depth.saturating_sub(1);
        let (auto_start, auto_bottom) = auto_depths(hierarchy, objects);
        let start = match (self.start, self.bottom) {
            (AutoOr::Given(Level(d)), _) => d.min(deepest),
            (AutoOr::Auto, AutoOr::Given(Level(bottom))) => auto_start.min(bottom),
            (AutoOr::Auto, AutoOr::Auto) => auto_start,
        };
        let bottom = match self.bottom {
            AutoOr::Given(Level(d)) => d.min(deepest).max(start),
            AutoOr::Auto => auto_bottom.max(start),
        };
        (start, bottom.min(start.saturating_add(MAX_LEVELS - 1)))
    }
}

/// Nodes a level needs before the walk starts there: about twice what one
/// level's fixed cost (a box pass, an expand pass and their barriers) buys
/// in box tests, since a level hides only part of its boxes. Measured on
/// llvmpipe: ~1.1 ms a level (start-depth sweeps) against 4.4-5.5 µs a box
/// (roc: 14.4 ms for 2 625 boxes, 45.8 ms for 10 521); the sweeps in issue
/// 8's note confirm 512. Both were measured before boxes were drawn indexed
/// and outside-frustum nodes left unqueued, which made boxes cheaper.
pub const START_NODES: usize = 512;

/// Start and bottom depths from the hierarchy's statistics (004 §4 leaves
/// this choice open):
///
/// - **bottom**: the deepest depth whose nodes hold on average at least
///   `traversal_cost` triangles, the cost of one test in triangles drawn
///   that the hierarchy's build weighs splits with. Below it a test costs
///   more than drawing what it could save.
/// - **start**: the shallowest depth with at least [`START_NODES`] nodes
///   (or the bottom, if no level has that many). A level of fewer nodes
///   costs about as much as its passes alone, and its few large boxes are
///   nearly always visible: it culls too little to pay for itself.
///
/// Measured by sweeps of the 60-frame walk (issue 8's note): on cities of
/// 363, 2 625 and 10 521 objects this picks start 11, 10 and 9 and bottom
/// 11, 14 and 16, at or next to the fastest start of each sweep; every
/// shallower bottom was slower.
pub fn auto_depths(hierarchy: &Hierarchy, objects: &[Object]) -> (u32, u32) {
    // (nodes, triangles) per depth.
    let mut levels: Vec<(usize, u64)> = Vec::new();
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, depth)) = stack.pop() {
        let node = &hierarchy.nodes[i];
        if levels.len() <= depth {
            levels.resize(depth + 1, (0, 0));
        }
        let triangles: u64 = hierarchy
            .subtree_objects(node)
            .iter()
            .map(|&o| u64::from(objects[o as usize].triangles))
            .sum();
        levels[depth].0 += 1;
        levels[depth].1 += triangles;
        stack.extend(node.children().map(|c| (c, depth + 1)));
    }
    let worth_testing =
        |&(nodes, triangles): &(usize, u64)| triangles as f64 >= hierarchy.params.traversal_cost * nodes as f64;
    let bottom = levels.iter().rposition(worth_testing).unwrap_or(0);
    let start = levels
        .iter()
        .position(|&(nodes, _)| nodes >= START_NODES)
        .unwrap_or(bottom)
        .min(bottom);
    (start as u32, bottom as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::gpu_walk::CullTree;
    use crate::hierarchy::HierarchyParams;
    use crate::hierarchy::fixtures::grid_objects;

    fn grid(n: usize, triangles: u32) -> (Hierarchy, Vec<Object>) {
        let mut objects = grid_objects(n);
        for o in &mut objects {
            o.triangles = triangles;
        }
        let params = HierarchyParams {
            max_leaf_objects: 1,
            traversal_cost: 64.0,
            ..HierarchyParams::default()
        };
        (Hierarchy::build(&objects, &params), objects)
    }

    /// The nodes at `depth` (root 0).
    fn level(h: &Hierarchy, depth: u32) -> Vec<usize> {
        let mut nodes = vec![0usize];
        for _ in 0..depth {
            nodes = nodes.iter().flat_map(|&i| h.nodes[i].children()).collect();
        }
        nodes
    }

    /// Mean triangles under the nodes at `depth`.
    fn mean_triangles(h: &Hierarchy, objects: &[Object], depth: u32) -> f64 {
        let nodes = level(h, depth);
        let triangles: u32 = nodes
            .iter()
            .flat_map(|&i| h.subtree_objects(&h.nodes[i]))
            .map(|&o| objects[o as usize].triangles)
            .sum();
        f64::from(triangles) / nodes.len() as f64
    }

    #[test]
    fn auto_depths_start_where_a_level_pays_for_its_passes_and_stop_where_tests_cost_more_than_drawing() {
        // 2000 objects of 1000 triangles: every level is worth testing.
        let (h, objects) = grid(2000, 1000);
        let (start, bottom) = auto_depths(&h, &objects);
        assert_eq!(bottom, h.stats().depth - 1);
        assert!(
            level(&h, start).len() >= START_NODES && level(&h, start - 1).len() < START_NODES,
            "start {start}"
        );
        // 400 objects of 40 triangles: a node must hold two objects (80
        // triangles ≥ 64) to be worth a test, so the leaves are not.
        let (h, objects) = grid(400, 40);
        let (_, bottom) = auto_depths(&h, &objects);
        assert!(bottom < h.stats().depth - 1);
        assert!(
            mean_triangles(&h, &objects, bottom) >= 64.0 && mean_triangles(&h, &objects, bottom + 1) < 64.0,
            "bottom {bottom}"
        );
        // No level has enough nodes: one level, at the bottom.
        let (h, objects) = grid(400, 1000);
        let (start, bottom) = auto_depths(&h, &objects);
        assert_eq!((start, bottom), (h.stats().depth - 1, h.stats().depth - 1));
    }

    #[test]
    fn given_depths_win_over_auto_and_stay_ordered() {
        let (h, objects) = grid(2000, 1000);
        let (auto_start, auto_bottom) = auto_depths(&h, &objects);
        let with = |start, bottom| DepthRange { start, bottom }.choose(&h, &objects);
        assert_eq!(with(AutoOr::Auto, AutoOr::Auto), (auto_start, auto_bottom));
        assert_eq!(with(AutoOr::Given(Level(2)), AutoOr::Given(Level(3))), (2, 3));
        assert_eq!(
            with(AutoOr::Auto, AutoOr::Given(Level(1))),
            (1, 1),
            "an auto start stays above a given bottom"
        );
        // An auto bottom stays below a given start (here, where the auto
        // bottom is above the leaves).
        let (h40, objects40) = grid(400, 40);
        let (_, bottom40) = auto_depths(&h40, &objects40);
        assert!(bottom40 + 1 < h40.stats().depth);
        let below = DepthRange {
            start: AutoOr::Given(Level(bottom40 + 1)),
            bottom: AutoOr::Auto,
        };
        assert_eq!(below.choose(&h40, &objects40), (bottom40 + 1, bottom40 + 1));
        let beyond = AutoOr::Given(Level(u32::MAX));
        let deepest = h.stats().depth - 1;
        assert_eq!(with(beyond, beyond), (deepest, deepest), "no deeper than the hierarchy");
        assert_eq!(with(AutoOr::Given(Level(2)), beyond), (2, deepest));
        let (tree, _) = CullTree::cut(&h, u32::MAX, u32::MAX);
        assert_eq!(tree.levels, 1, "one level: every leaf, as the seed");
    }
}
