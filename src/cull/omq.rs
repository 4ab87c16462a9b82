//! `omq`: hierarchical occlusion culling with an Occupancy Map and multiple
//! occlusion queries, paper 003 §3–4 (configuration (c) of §5).
//!
//! Three stages per frame, each following one listing of 003 §4.2:
//!
//! 1. Front to back, a node whose screen rectangle covers an empty cell of
//!    the Occupancy Map cannot be hidden by anything drawn so far: it is
//!    visible without a query (a leaf is drawn and marked in the map, an
//!    inner node is opened). Nodes over full cells go to the pending list.
//! 2. Up to `max_tests` batches: the map is cleared, pending nodes are taken
//!    front to back and a node joins the batch's test list if its rectangle
//!    still covers a cell no box of the list covers (then it is marked), so
//!    no box of a batch can be tested against another's not-yet-drawn
//!    geometry where it matters (003 §3.2, Figure 2). The list is queried in
//!    one round trip; visible leaves are drawn, visible inner nodes' children
//!    become pending.
//! 3. The remaining pending nodes are queried in brute-force batches until
//!    none are left.
//!
//! Then `max_tests = 7/10 · m` for the next frame, m being this frame's
//! number of batches of stages 2 and 3 (003: "n_frame+1 = 7/10 · m_frame").
//!
//! Departures from the listings: children are tested against the frustum
//! when they enter the queue or the pending list rather than when they leave
//! it (the same nodes are culled, but stage 3 never queries a box outside the
//! frustum); a leaf's objects are frustum-tested one by one before drawing,
//! as in `vfc`; `max_tests` never drops below 1, so stage 2 always runs.
//! Conservative like the paper: a node is culled only by a query that found
//! its box hidden behind geometry that was really drawn.

use glam::DVec3;
use serde::Serialize;

use super::occupancy::{OccupancyMap, ScreenRect};
use super::traversal::{DepthQueue, children, draw_leaf, in_frustum, nearest_corner};
use crate::bounds::Aabb;
use crate::camera::{Camera, Containment, Frustum};
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{BoxTest, BoxVisibility, Frame, Resolution};
use crate::hierarchy::Hierarchy;
use crate::scene::Scene;

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Omq,
    summary: "Occupancy Map + multiple occlusion queries in three stages (003 §3-4)",
    chart_colour: [44, 160, 44],
    conservative: true,
    draws_by_time: false,
    params: &[OM, INITIAL_MAX_TESTS, FACTOR],
    exercised_with: &[],
    needs: Needs::Nothing,
    carries: Carries::Nothing,
    auto: Candidacy::Always,
    check: |params| OmqParams::from_params(params).map(drop),
    build: |_, params| Ok(Box::new(OccupancyMapQueries::new(OmqParams::from_params(params)?))),
};

const OM: ParamInfo = ParamInfo {
    key: "om",
    default: "64x48",
    summary: "Occupancy Map cells across x down",
};

const INITIAL_MAX_TESTS: ParamInfo = ParamInfo {
    key: "initial_max_tests",
    default: "4",
    summary: "stage-2 batches in the first frame",
};

const FACTOR: ParamInfo = ParamInfo {
    key: "factor",
    default: "0.7",
    summary: "next frame's max_tests = factor x this frame's batches",
};

/// What one frame's traversal looks at.
struct View<'a> {
    scene: &'a Scene,
    hierarchy: &'a Hierarchy,
    camera: &'a Camera,
    frustum: Frustum,
    eye: DVec3,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OmqParams {
    /// Occupancy Map cells across and down the screen.
    pub om: Resolution,
    /// Stage-2 batches allowed in the first frame.
    pub initial_max_tests: u32,
    /// max_tests of the next frame = factor · batches of this one (003: 7/10).
    pub factor: f64,
}

impl OmqParams {
    pub fn from_params(params: &ModeParams) -> Result<OmqParams, ModeError> {
        let factor: f64 = params.get(ModeId::Omq, &FACTOR)?;
        if !(factor > 0.0 && factor.is_finite()) {
            let reason = format!("must be a positive number, got {factor}");
            return Err(ModeError::bad(ModeId::Omq, &FACTOR, reason));
        }
        Ok(OmqParams {
            om: params.get(ModeId::Omq, &OM)?,
            initial_max_tests: params.get(ModeId::Omq, &INITIAL_MAX_TESTS)?,
            factor,
        })
    }
}

/// Where opened nodes' children go: the front-to-back queue of the current
/// stage, or the pending list of the next batch.
#[derive(Clone, Copy)]
enum Destination {
    Queue,
    Pending,
}

pub struct OccupancyMapQueries {
    params: OmqParams,
    /// Carried from frame to frame.
    max_tests: u32,
    om: OccupancyMap,
    queue: DepthQueue,
    pending: Vec<u32>,
    test_list: Vec<u32>,
    boxes: Vec<Aabb>,
    results: Vec<BoxVisibility>,
    objects: Vec<u32>,
}

impl OccupancyMapQueries {
    pub fn new(params: OmqParams) -> Self {
        OccupancyMapQueries {
            params,
            max_tests: params.initial_max_tests.max(1),
            om: OccupancyMap::new(params.om.width, params.om.height),
            queue: DepthQueue::default(),
            pending: Vec::new(),
            test_list: Vec::new(),
            boxes: Vec::new(),
            results: Vec::new(),
            objects: Vec::new(),
        }
    }

    fn rect(&self, view: &View, node: u32) -> ScreenRect {
        let bounds = &view.hierarchy.nodes[node as usize].bounds;
        ScreenRect::of_box(bounds, view.camera, self.om.cols(), self.om.rows())
    }

    /// Frustum-tests the children of `node`; those inside go to `into`.
    fn open(&mut self, view: &View, node: u32, into: Destination, stats: &mut TraversalStats) {
        let hierarchy = view.hierarchy;
        for child in in_frustum(
            hierarchy,
            children(&hierarchy.nodes[node as usize]),
            &view.frustum,
            stats,
        ) {
            match into {
                Destination::Queue => self
                    .queue
                    .push(child, nearest_corner(&hierarchy.nodes[child as usize].bounds, view.eye)),
                Destination::Pending => self.pending.push(child),
            }
        }
    }

    fn draw_leaf(&mut self, ctx: &mut dyn Frame, view: &View, node: u32) {
        let n = &view.hierarchy.nodes[node as usize];
        draw_leaf(ctx, view.scene, view.hierarchy, n, &view.frustum, &mut self.objects);
    }

    /// One multiple occlusion query over the test list: visible leaves are
    /// drawn, visible inner nodes' children become pending.
    fn query_test_list(&mut self, ctx: &mut dyn Frame, view: &View, stats: &mut TraversalStats) {
        self.boxes.clear();
        let nodes = &view.hierarchy.nodes;
        self.boxes
            .extend(self.test_list.iter().map(|&n| nodes[n as usize].bounds));
        ctx.test_boxes(&self.boxes, BoxTest::Occlusion, &mut self.results);
        // By index: drawing and opening need `self` while the list is read.
        for k in 0..self.test_list.len() {
            let node = self.test_list[k];
            if !self.results[k].is_visible() {
                stats.nodes_culled_occlusion += 1;
            } else if nodes[node as usize].is_leaf() {
                self.draw_leaf(ctx, view, node);
            } else {
                self.open(view, node, Destination::Pending, stats);
            }
        }
        self.test_list.clear();
    }
}

impl Culler for OccupancyMapQueries {
    fn name(&self) -> &str {
        ModeId::Omq.name()
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(self.params).expect("plain struct serialises")
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let camera = input.camera;
        let view = View {
            scene: input.scene,
            hierarchy: input.hierarchy,
            camera,
            frustum: camera.frustum(),
            eye: camera.eye,
        };
        let (frustum, eye) = (&view.frustum, view.eye);
        let mut stats = TraversalStats {
            nodes_visited: 1,
            ..Default::default()
        };
        self.om.clear();
        self.queue.clear();
        self.pending.clear();
        let root = &view.hierarchy.nodes[0];
        if frustum.classify(&root.bounds) == Containment::Outside {
            stats.nodes_culled_frustum += 1;
            return stats;
        }
        self.queue.push(0, nearest_corner(&root.bounds, eye));

        // Stage 1: visible nodes in front, found by the Occupancy Map.
        while let Some(node) = self.queue.pop() {
            let rect = self.rect(&view, node);
            if self.om.any_empty(&rect) {
                stats.queries_skipped += 1;
                if view.hierarchy.nodes[node as usize].is_leaf() {
                    self.draw_leaf(ctx, &view, node);
                    self.om.mark(&rect);
                } else {
                    self.open(&view, node, Destination::Queue, &mut stats);
                }
            } else {
                self.pending.push(node);
            }
        }

        // Stage 2: batches arranged by a cleared Occupancy Map each.
        let mut batches = 0;
        while !self.pending.is_empty() && batches < self.max_tests {
            for node in std::mem::take(&mut self.pending) {
                self.queue
                    .push(node, nearest_corner(&view.hierarchy.nodes[node as usize].bounds, eye));
            }
            self.om.clear();
            while let Some(node) = self.queue.pop() {
                let rect = self.rect(&view, node);
                if self.om.any_empty(&rect) {
                    self.test_list.push(node);
                    self.om.mark(&rect);
                } else {
                    self.pending.push(node);
                }
            }
            self.query_test_list(ctx, &view, &mut stats);
            batches += 1;
        }

        // Stage 3: brute-force batches of everything still pending.
        while !self.pending.is_empty() {
            std::mem::swap(&mut self.test_list, &mut self.pending);
            self.query_test_list(ctx, &view, &mut stats);
            batches += 1;
        }

        self.max_tests = ((self.params.factor * f64::from(batches)) as u32).max(1);
        stats
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::cull::recording::{Recording, camera_down_z, cubes, input};

    #[test]
    fn stage_two_takes_the_batches_of_7_10_of_the_last_frames_and_stage_three_the_rest() {
        // A row of cubes down the view axis: the first hides the rest, and
        // each lies on screen inside the one before.
        let corners: Vec<DVec3> = (0..32)
            .map(|k| DVec3::new(-0.5, -0.5, -4.0 - 2.0 * f64::from(k)))
            .collect();
        let (scene, hierarchy) = cubes(&corners);
        let camera = camera_down_z();
        let mut omq = OccupancyMapQueries::new(OmqParams::from_params(&ModeParams::default()).unwrap());
        // 003: "n_frame+1 = 7/10 · m_frame", m being the frame's batches;
        // the first frame takes initial_max_tests (4).
        let mut max_tests = 4usize;
        // The nodes left pending behind the front cube: the siblings of
        // every node on the path from the root to its leaf.
        let (mut p, mut node) = (0, 0);
        while !hierarchy.nodes[node].is_leaf() {
            let children = hierarchy.nodes[node].children();
            p += children.len() - 1;
            node = children
                .into_iter()
                .find(|&c| hierarchy.subtree_objects(&hierarchy.nodes[c]).contains(&0))
                .unwrap();
        }
        assert!(p > 4, "more pending nodes than stage 2 takes in the first frame ({p})");
        for frame in 0..6 {
            let mut double = Recording::new(|_: &Aabb| false);
            omq.frame(&mut double, &input(frame, &camera, &scene, &hierarchy));
            assert_eq!(
                double.drawn(),
                [0],
                "frame {frame}: only the front cube, found by the Occupancy Map"
            );
            let sizes: Vec<usize> = double.batches().iter().map(|b| b.len()).collect();
            // Stage 2: one node a batch (each hides the rest of the list
            // on the Occupancy Map), up to max_tests; stage 3: the rest in
            // one batch.
            let mut expected = vec![1; p.min(max_tests)];
            if p > max_tests {
                expected.push(p - max_tests);
            }
            assert_eq!(sizes, expected, "frame {frame} with max_tests {max_tests}");
            max_tests = ((0.7 * expected.len() as f64) as usize).max(1);
        }
    }
}
