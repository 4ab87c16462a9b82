//! `chc`: coherent hierarchical culling over a ternary tree, paper 001 on
//! the algorithm it builds on (001 §3: [KS05], "also similar to [BWPP04]",
//! coherent hierarchical culling).
//!
//! One frame:
//!
//! 1. **Maintenance** (001 §3.1): every moved object is moved in the tree
//!    ([`TernaryTree::update`]); its time, with TightBox computation and
//!    split/merge, is reported as the frame's maintenance.
//! 2. **Traversal**, front to back by nearest box corner (as 003 §4.2). A
//!    node outside the frustum is culled. A node found visible in the
//!    previous frame is not waited for (001 §3: "a node visible in a few
//!    recent frames will probably be visible again in this frame. Hence we
//!    can skip the occlusion query and render it immediately"): an inner one
//!    is opened, a leaf drawn at once and queried after the frame for the
//!    next one. Every other node needs a query, and its query joins the
//!    batch in flight (001 §3, Figure 1: several queries at once).
//! 3. **Colliding queries** (001 §3.5): a query whose screen rectangle
//!    overlaps one already in the batch, which is nearer, waits: the batch is
//!    sent first and its visible nodes drawn, so the nearer objects can hide
//!    the farther node. The batch is also sent when the queue runs dry. A
//!    visible node marks its ancestors visible (CHC's pull-up); a visible
//!    leaf is drawn, a visible inner node opened.
//! 4. **End of frame**: the leaves drawn without waiting are queried in one
//!    batch for the next frame, but each only once in `chc.visible_for`
//!    frames, siblings in the same frame so that they can merge; the others
//!    stay visible. 001 §3 builds on this: "a node visible in a few recent
//!    frames will probably be visible again in this frame. Hence we can
//!    skip the occlusion query"; CHC++ (Mattausch, Bittner and Wimmer,
//!    Eurographics 2008) likewise queries a visible node only now and then.
//!    Every query also counts the box's total pixels (001 §3.3), and leaves
//!    are split or merged by their ratios (001 §3.4), split across the axis
//!    that faces the camera.
//!
//! Conservative: a node is culled only by a query that found its box hidden
//! behind depth really drawn this frame, and every box a query tests holds
//! the objects below it (cells, TightBoxes and straddle boxes alike).
//!
//! Departures: queries count pixels in one instanced draw per batch (the
//! portable path of `gpu::queries`), so a batch is one round trip rather
//! than asynchronous per-query results. A visible leaf's queries are spread
//! over the frames by its parent's id, where CHC++ draws a random first
//! frame per node. The coherence state's clock is the mode's own
//! traversals, not the frames it is run in, which may skip or start again.
//! Where `auto` runs it after another culler, it is handed the objects that
//! culler drew ([`Culler::seed_visible`]) and starts as if it had found them
//! visible itself: its own visibility is from the last frame it ran, too
//! old to use, and from nothing it would descend the tree from the root,
//! one round trip a level (29 in one frame of a furnished room walked
//! inside, 301 ms on a loaded llvmpipe).

mod ternary;

use std::time::Instant;

use serde::Serialize;

use super::occupancy::ScreenRect;
use super::traversal::{DepthQueue, nearest_corner};
use crate::bounds::Aabb;
use crate::camera::{Camera, Containment, Frustum};
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::last_frame::{LastFrame, Since};
use crate::cull::mode::{Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{BoxVisibility, Frame, Resolution};
use crate::scene::Scene;
use ternary::{Pixels, TernaryTree, TreeParams, facing_axis};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Chc,
    summary: "coherent culling on a ternary tree: last frame's visible nodes unwaited, TightBoxes, split/merge, colliding queries wait (001)",
    chart_colour: [214, 39, 40],
    conservative: true,
    draws_by_time: false,
    params: &[R_SPLIT, O_SPLIT, R_MERGE, O_MERGE, TIGHT_AFTER, VISIBLE_FOR],
    exercised_with: &[("visible_for", "1")],
    needs: Needs::PixelCounts,
    carries: Carries::VisibleOnCpu,
    auto: Candidacy::Always,
    check: |params| ChcParams::from_params(params).map(drop),
    build: |scene, params| Ok(Box::new(CoherentCulling::new(scene, ChcParams::from_params(params)?))),
};

const R_SPLIT: ParamInfo = ParamInfo {
    key: "r_split",
    default: "0.25",
    summary: "split a leaf whose visible/total pixels reach this …",
};

const O_SPLIT: ParamInfo = ParamInfo {
    key: "o_split",
    default: "12",
    summary: "… and which holds at least this many objects",
};

const R_MERGE: ParamInfo = ParamInfo {
    key: "r_merge",
    default: "0.75",
    summary: "merge sibling leaves whose visible/total pixels are at most this …",
};

const O_MERGE: ParamInfo = ParamInfo {
    key: "o_merge",
    default: "5",
    summary: "… and which hold at most this many objects each",
};

const TIGHT_AFTER: ParamInfo = ParamInfo {
    key: "tight_after",
    default: "3",
    summary: "frames without change before a node's TightBox replaces its cell",
};

const VISIBLE_FOR: ParamInfo = ParamInfo {
    key: "visible_for",
    default: "8",
    summary: "frames a leaf found visible is drawn before it is queried again, siblings at frames of their own so the queries spread (1: every frame, as CHC)",
};

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ChcParams {
    #[serde(flatten)]
    pub tree: TreeParams,
    /// Frames a visible leaf is drawn before it is queried again (001 §3:
    /// "a node visible in a few recent frames will probably be visible
    /// again in this frame"); at least 1.
    pub visible_for: u32,
}

impl ChcParams {
    pub fn from_params(params: &ModeParams) -> Result<ChcParams, ModeError> {
        let ratio = |param: &ParamInfo| -> Result<f64, ModeError> {
            let r: f64 = params.get(ModeId::Chc, param)?;
            if (0.0..=1.0).contains(&r) {
                Ok(r)
            } else {
                let reason = format!("a pixel ratio must be in 0..=1, got {r}");
                Err(ModeError::bad(ModeId::Chc, param, reason))
            }
        };
        Ok(ChcParams {
            tree: TreeParams {
                r_split: ratio(&R_SPLIT)?,
                o_split: params.get(ModeId::Chc, &O_SPLIT)?,
                r_merge: ratio(&R_MERGE)?,
                o_merge: params.get(ModeId::Chc, &O_MERGE)?,
                tight_after: params.get(ModeId::Chc, &TIGHT_AFTER)?,
            },
            visible_for: match params.get(ModeId::Chc, &VISIBLE_FOR)? {
                0 => {
                    let reason = "must be at least 1 (1 queries every visible leaf every frame), got 0".into();
                    return Err(ModeError::bad(ModeId::Chc, &VISIBLE_FOR, reason));
                }
                frames => frames,
            },
        })
    }
}

/// Nodes and the boxes their queries test.
#[derive(Default)]
struct QueryList {
    nodes: Vec<u32>,
    boxes: Vec<Aabb>,
}

impl QueryList {
    fn clear(&mut self) {
        self.nodes.clear();
        self.boxes.clear();
    }
}

/// Queries sent together: no two of their screen rectangles overlap.
#[derive(Default)]
struct QueryBatch {
    queries: QueryList,
    rects: Vec<ScreenRect>,
}

impl QueryBatch {
    fn clear(&mut self) {
        self.queries.clear();
        self.rects.clear();
    }

    /// Whether `rect` overlaps a query already in the batch (001 §3.5).
    fn collides(&self, rect: &ScreenRect) -> bool {
        self.rects.iter().any(|r| r.overlaps(rect))
    }
}

/// Query answers, reused from batch to batch.
#[derive(Default)]
struct Answers {
    visibility: Vec<BoxVisibility>,
    totals: Vec<u64>,
}

impl Answers {
    /// Tests `list` in one round trip, counting visible and total pixels,
    /// and records them on its nodes (001 §3.3).
    fn query(&mut self, ctx: &mut dyn Frame, tree: &mut TernaryTree, list: &QueryList, frame: u32) {
        ctx.test_boxes_with_totals(&list.boxes, 1, &mut self.visibility, &mut self.totals);
        for (k, &node) in list.nodes.iter().enumerate() {
            if let BoxVisibility::Samples(visible) = self.visibility[k] {
                tree.node_mut(node).pixels = Some(Pixels {
                    frame,
                    visible,
                    total: self.totals[k],
                });
            }
        }
    }
}

/// What one frame's traversal looks at.
struct View<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    frustum: Frustum,
    resolution: Resolution,
    frame: u32,
}

pub struct CoherentCulling {
    params: ChcParams,
    tree: TernaryTree,
    queue: DepthQueue,
    batch: QueryBatch,
    /// Leaves drawn without waiting.
    drawn_unqueried: QueryList,
    /// Those of them queried after the frame.
    checked: QueryList,
    answers: Answers,
    objects: Vec<u32>,
    /// What another culler drew last frame, taken as this mode's visible
    /// set at the start of the next ([`Culler::seed_visible`]).
    handed: Option<Vec<u32>>,
    /// Traversals run, the clock of the tree's coherence state (a node
    /// visible in the traversal before this one is not waited for): the
    /// frames it runs in need not follow each other, under `auto` or where
    /// a bench's recording starts its frames again after the warm-up.
    traversals: u32,
    /// The frame it last ran in, to tell which movers to move in the tree.
    last_frame: LastFrame,
}

impl CoherentCulling {
    /// Builds the ternary tree over `scene`'s objects as they stand.
    pub fn new(scene: &Scene, params: ChcParams) -> Self {
        let bounds: Vec<Aabb> = scene.objects.iter().map(|o| o.bounds).collect();
        CoherentCulling {
            params,
            tree: TernaryTree::build(&bounds, params.tree),
            queue: DepthQueue::default(),
            batch: QueryBatch::default(),
            drawn_unqueried: QueryList::default(),
            checked: QueryList::default(),
            answers: Answers::default(),
            objects: Vec::new(),
            handed: None,
            traversals: 0,
            last_frame: LastFrame::default(),
        }
    }

    /// Queues `node` by its box's nearest corner, unless nothing lies below.
    fn push(&mut self, node: u32, view: &View) {
        if self.tree.node(node).count > 0 {
            let b = self.tree.query_box(node, view.frame);
            self.queue.push(node, nearest_corner(&b, view.camera.eye));
        }
    }

    fn open(&mut self, node: u32, view: &View) {
        for child in self.tree.children(node) {
            self.push(child, view);
        }
    }

    /// Draws the objects of leaf `node` the frustum does not exclude.
    fn draw(&mut self, ctx: &mut dyn Frame, node: u32, view: &View) {
        self.objects.clear();
        let scene = view.scene;
        self.objects.extend(
            self.tree
                .node(node)
                .objects
                .iter()
                .filter(|&&o| view.frustum.classify(&scene.objects[o as usize].bounds) != Containment::Outside),
        );
        ctx.draw(&self.objects);
    }

    /// Sends the batch and acts on its answers.
    fn flush(&mut self, ctx: &mut dyn Frame, view: &View, stats: &mut TraversalStats) {
        self.answers.query(ctx, &mut self.tree, &self.batch.queries, view.frame);
        for k in 0..self.batch.queries.nodes.len() {
            let node = self.batch.queries.nodes[k];
            if !self.answers.visibility[k].is_visible() {
                stats.nodes_culled_occlusion += 1;
                continue;
            }
            self.tree.pull_up_visibility(node);
            if self.tree.node(node).split.is_some() {
                self.open(node, view);
            } else {
                self.draw(ctx, node, view);
            }
        }
        self.batch.clear();
    }
}

impl Culler for CoherentCulling {
    fn name(&self) -> &str {
        ModeId::Chc.name()
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(self.params).expect("plain struct serialises")
    }

    fn seed_visible(&mut self, visible: &[u32]) {
        self.handed = Some(visible.to_vec());
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let mut stats = TraversalStats::default();
        // The tree's clock: traversal 0 is the tree as built.
        self.traversals += 1;
        let view = View {
            scene: input.scene,
            camera: input.camera,
            frustum: input.camera.frustum(),
            resolution: input.resolution,
            frame: self.traversals,
        };
        let frame = view.frame;

        // 1. Maintenance: moved objects find their nodes; after frames it
        // did not run in, every mover.
        let start = Instant::now();
        let scene = input.scene;
        let every_mover = matches!(self.last_frame.advance(input.frame), Since::First | Since::Gap);
        let movers = scene.movers.iter().map(|m| m.object).filter(|_| every_mover);
        for o in movers.chain(input.moved.iter().copied().filter(|_| !every_mover)) {
            self.tree.update(o, scene.objects[o as usize].bounds, frame);
        }
        stats.maintenance += start.elapsed();
        if let Some(handed) = self.handed.take() {
            self.tree.assume_visited(&handed, frame - 1);
        }

        // 2-3. Front to back; queries in batches of non-overlapping rectangles.
        self.queue.clear();
        self.batch.clear();
        self.drawn_unqueried.clear();
        self.push(0, &view);
        loop {
            while let Some(node) = self.queue.pop() {
                let bounds = self.tree.query_box(node, frame);
                if view.frustum.classify(&bounds) == Containment::Outside {
                    stats.nodes_visited += 1;
                    stats.nodes_culled_frustum += 1;
                    continue;
                }
                let n = self.tree.node(node);
                let leaf = n.split.is_none();
                let was_visible = n.visible && n.last_visited.is_some_and(|f| f + 1 == frame);
                if !was_visible {
                    let (cols, rows) = (view.resolution.width, view.resolution.height);
                    let rect = ScreenRect::of_box(&bounds, view.camera, cols, rows);
                    if self.batch.collides(&rect) {
                        // The nearer query goes first; this node comes out
                        // of the queue again once its answers are drawn.
                        stats.queries_delayed += 1;
                        self.queue.push(node, nearest_corner(&bounds, view.camera.eye));
                        self.flush(ctx, &view, &mut stats);
                        continue;
                    }
                    self.batch.queries.nodes.push(node);
                    self.batch.queries.boxes.push(bounds);
                    self.batch.rects.push(rect);
                }
                stats.nodes_visited += 1;
                let n = self.tree.node_mut(node);
                n.visible = false;
                n.last_visited = Some(frame);
                if was_visible && leaf {
                    self.draw(ctx, node, &view);
                    self.drawn_unqueried.nodes.push(node);
                    self.drawn_unqueried.boxes.push(bounds);
                } else if was_visible {
                    stats.queries_skipped += 1;
                    self.open(node, &view);
                }
            }
            if self.batch.queries.nodes.is_empty() {
                break;
            }
            self.flush(ctx, &view, &mut stats);
        }

        // 4. The leaves drawn without waiting are checked for the next
        // frame where their last query is `visible_for` traversals old (or
        // they have none: handed over, or made by a split), and in one
        // traversal of `visible_for` by their parent's id, so that the
        // checks spread over the traversals and siblings, which merge only
        // when measured together, are checked together; the others stay
        // visible.
        let visible_for = self.params.visible_for;
        let (checked, drawn) = (&mut self.checked, &self.drawn_unqueried);
        checked.clear();
        for (&node, bounds) in drawn.nodes.iter().zip(&drawn.boxes) {
            let n = self.tree.node(node);
            let due = n.pixels.is_none_or(|p| frame.saturating_sub(p.frame) >= visible_for)
                || (u64::from(frame) + u64::from(n.parent)).is_multiple_of(u64::from(visible_for));
            if due {
                checked.nodes.push(node);
                checked.boxes.push(*bounds);
            } else {
                stats.queries_skipped += 1;
                self.tree.pull_up_visibility(node);
            }
        }
        if !checked.nodes.is_empty() {
            self.answers.query(ctx, &mut self.tree, checked, frame);
            for (k, &node) in checked.nodes.iter().enumerate() {
                if self.answers.visibility[k].is_visible() {
                    self.tree.pull_up_visibility(node);
                }
            }
        }
        let start = Instant::now();
        let axis = facing_axis(view.camera.forward());
        self.tree.split_and_merge(frame, axis);
        stats.maintenance += start.elapsed() + self.tree.take_tight_time();
        stats
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::cull::recording::{Call, Recording, camera_down_z, cubes, cuboids, input};

    #[test]
    fn a_query_overlapping_a_nearer_one_in_flight_waits_until_the_nearer_is_drawn() {
        // Down −Z: a near cube on the axis, one far behind it, one off to
        // the side whose rectangle overlaps neither.
        let corners = [
            DVec3::new(-0.5, -0.5, -4.0),
            DVec3::new(-0.5, -0.5, -12.0),
            DVec3::new(3.0, -0.5, -8.0),
        ];
        let (scene, hierarchy) = cubes(&corners);
        let camera = camera_down_z();
        let mut chc = CoherentCulling::new(&scene, one_object_a_leaf());
        // A box shows when it holds part of the near or the side cube: the
        // far one lies in the near one's shadow.
        let seen = [scene.objects[0].bounds, scene.objects[2].bounds];
        let overlaps = |a: &Aabb, b: &Aabb| a.min.cmple(b.max).all() && b.min.cmple(a.max).all();
        let mut double = Recording::new(|b: &Aabb| seen.iter().any(|s| overlaps(b, s)));
        let stats = chc.frame(&mut double, &input(0, &camera, &scene, &hierarchy));
        let (near, far) = (scene.objects[0].bounds.center(), scene.objects[1].bounds.center());
        let near_drawn = double.calls.iter().position(|c| *c == Call::Draw(vec![0]));
        // The first box tested that holds the far cube and not the near one.
        let far_alone = |b: &Aabb| b.contains_point(far) && !b.contains_point(near);
        let far_tested = double
            .calls
            .iter()
            .position(|c| matches!(c, Call::Test(boxes) if boxes.iter().any(far_alone)));
        assert!(stats.queries_delayed >= 1, "{stats:?}");
        let (Some(near_drawn), Some(far_tested)) = (near_drawn, far_tested) else {
            panic!(
                "the near cube drawn and a box around the far one tested: {:?}",
                double.calls
            );
        };
        assert!(near_drawn < far_tested, "{:?}", double.calls);
        let drawn = double.drawn();
        assert!(
            drawn.contains(&0) && drawn.contains(&2) && !drawn.contains(&1),
            "{drawn:?}"
        );
        assert!(stats.nodes_culled_occlusion >= 1, "{stats:?}");
    }

    #[test]
    fn a_leaf_found_visible_is_queried_once_in_visible_for_frames_and_dropped_within_them_once_hidden() {
        // Down −Z: two cubes side by side, both in view, leaves of their own.
        let corners = [DVec3::new(-1.5, -0.5, -6.0), DVec3::new(0.5, -0.5, -6.0)];
        let (scene, hierarchy) = cubes(&corners);
        let camera = camera_down_z();
        let first = scene.objects[0].bounds;
        let runs = |visible_for: u32| {
            let params = ChcParams {
                visible_for,
                ..one_object_a_leaf()
            };
            let mut chc = CoherentCulling::new(&scene, params);
            // The first cube is hidden from frame 9 on.
            let hidden = std::cell::Cell::new(false);
            let mut double = Recording::new(|b: &Aabb| !(hidden.get() && *b == first));
            let mut tests_and_last_drawn = (0, 0);
            for frame in 0..20 {
                hidden.set(frame >= 9);
                double.calls.clear();
                chc.frame(&mut double, &input(frame, &camera, &scene, &hierarchy));
                if (1..9).contains(&frame) {
                    tests_and_last_drawn.0 += double.batches().iter().map(|b| b.len()).sum::<usize>();
                }
                if double.drawn().contains(&0) {
                    tests_and_last_drawn.1 = frame;
                }
            }
            tests_and_last_drawn
        };
        // Frames 1 to 8 find both leaves visible and draw them unwaited:
        // each queried every frame, or in two frames of the eight.
        assert_eq!(runs(1), (16, 9));
        let (tests, last_drawn) = runs(4);
        assert_eq!(tests, 4);
        // Hidden from frame 9: drawn until its next query, at most 4 on.
        assert!((9..13).contains(&last_drawn), "{last_drawn}");
    }

    /// Leaves of one object each, and no split or merge in the way.
    fn one_object_a_leaf() -> ChcParams {
        ChcParams {
            tree: TreeParams {
                o_merge: 0,
                o_split: u32::MAX,
                ..TreeParams::default()
            },
            visible_for: 1,
        }
    }

    #[test]
    fn frames_that_start_again_after_the_warm_up_keep_last_traversal_s_visibility() {
        let (scene, hierarchy) = cubes(&[DVec3::new(-1.5, -0.5, -6.0), DVec3::new(0.5, -0.5, -6.0)]);
        let camera = camera_down_z();
        let mut chc = CoherentCulling::new(&scene, one_object_a_leaf());
        let mut double = Recording::new(|_: &Aabb| true);
        // Warm-up frames 0 to 2, then the recording's frame 0.
        for frame in [0, 1, 2, 0] {
            double.calls.clear();
            chc.frame(&mut double, &input(frame, &camera, &scene, &hierarchy));
        }
        // Both cubes drawn at once, then queried for the next frame: no
        // descent from the root.
        assert!(matches!(double.calls[0], Call::Draw(_)), "{:?}", double.calls);
        assert_eq!(double.batches().len(), 1, "{:?}", double.calls);
    }

    #[test]
    fn a_mover_that_moved_in_frames_it_did_not_run_in_is_found_where_it_is() {
        // Down −Z: a wide wall, a car behind it, then the car drives out to
        // the side while chc does not run (auto runs another mode).
        let (mut scene, hierarchy) = cuboids(&[
            (DVec3::new(-3.0, -1.0, -5.0), DVec3::new(3.0, 1.0, -4.0)),
            (DVec3::new(-0.5, -0.5, -9.0), DVec3::new(0.5, 0.5, -8.0)),
        ]);
        let route = crate::scene::motion::Route::closed(vec![DVec3::ZERO, DVec3::X]).expect("a route");
        scene.movers.push(crate::scene::motion::Mover::new(
            1,
            route,
            0.0,
            0.0,
            glam::DAffine3::IDENTITY,
        ));
        let camera = camera_down_z();
        let wall = scene.objects[0].bounds;
        let mut chc = CoherentCulling::new(&scene, one_object_a_leaf());
        let car = std::cell::Cell::new(scene.objects[1].bounds);
        let overlaps = |a: &Aabb, b: &Aabb| a.min.cmple(b.max).all() && b.min.cmple(a.max).all();
        // What shows: the wall, and the car once it is out beside it.
        let mut double =
            Recording::new(|b: &Aabb| overlaps(b, &wall) || (car.get().min.x > 3.0 && overlaps(b, &car.get())));
        chc.frame(&mut double, &input(0, &camera, &scene, &hierarchy));
        assert_eq!(double.drawn(), [0], "the car hidden behind the wall");
        let out = Aabb {
            min: DVec3::new(4.0, -0.5, -9.0),
            max: DVec3::new(5.0, 0.5, -8.0),
        };
        scene.objects[1].bounds = out;
        car.set(out);
        // Frame 5, in which nothing moved: the car moved in frames 1 to 4.
        double.calls.clear();
        chc.frame(&mut double, &input(5, &camera, &scene, &hierarchy));
        assert!(double.drawn().contains(&1), "{:?}", double.calls);
    }

    #[test]
    fn a_visible_set_handed_over_is_drawn_unwaited_and_the_rest_queried_without_descending_from_the_root() {
        // Down −Z: a row of 8 near cubes, and 8 far ones in their shadow.
        let corners: Vec<DVec3> = [-4.0, -12.0]
            .iter()
            .flat_map(|&z| (0..8).map(move |k| DVec3::new(f64::from(k) * 1.5 - 6.0, -0.5, z)))
            .collect();
        let (scene, hierarchy) = cubes(&corners);
        let camera = camera_down_z();
        // Boxes tight from the first traversal, so the far row's two
        // halves do not overlap on screen.
        let mut params = one_object_a_leaf();
        params.tree.tight_after = 0;
        let near: Vec<Aabb> = scene.objects[..8].iter().map(|o| o.bounds).collect();
        let overlaps = |a: &Aabb, b: &Aabb| a.min.cmple(b.max).all() && b.min.cmple(a.max).all();
        let answers = |b: &Aabb| near.iter().any(|s| overlaps(b, s));
        // A frame long after chc last ran (its own visibility too old):
        // from nothing, it descends the tree a level a round trip.
        let mut unseeded = Recording::new(answers);
        CoherentCulling::new(&scene, params).frame(&mut unseeded, &input(7, &camera, &scene, &hierarchy));
        assert!(unseeded.batches().len() >= 4, "{:?}", unseeded.batches());
        // Handed the near row as another culler drew it: it draws the row
        // before any test, and settles the rest in two round trips (the
        // far cubes' nodes, then the row's leaves for the next frame).
        let mut seeded = Recording::new(answers);
        let mut chc = CoherentCulling::new(&scene, params);
        chc.seed_visible(&(0..8).collect::<Vec<u32>>());
        chc.frame(&mut seeded, &input(7, &camera, &scene, &hierarchy));
        let first_test = seeded.calls.iter().position(|c| matches!(c, Call::Test(_)));
        let mut drawn_first: Vec<u32> = seeded.calls[..first_test.unwrap_or(seeded.calls.len())]
            .iter()
            .flat_map(|c| match c {
                Call::Draw(objects) => objects.clone(),
                Call::Test(_) => Vec::new(),
            })
            .collect();
        let frustum = camera.frustum();
        let in_frustum: Vec<u32> = (0..8)
            .filter(|&o| frustum.classify(&scene.objects[o as usize].bounds) != Containment::Outside)
            .collect();
        assert!(in_frustum.len() >= 4, "{in_frustum:?}");
        drawn_first.sort_unstable();
        assert_eq!(drawn_first, in_frustum, "{:?}", seeded.calls);
        assert!(seeded.batches().len() <= 2, "{:?}", seeded.batches());
        let mut drawn = seeded.drawn();
        drawn.sort_unstable();
        assert_eq!(drawn, in_frustum, "the far row stays hidden");
    }
}
