//! CPU twins of the walk's compute stages, written from their contracts,
//! not from the shaders:
//!
//! - [`walk`], of `cs_early_frustum`, `cs_expand` and `cs_compact` (004 §2
//!   and the module above): given the tree, the node states the walk left
//!   (the CPU's frustum and near-plane rules and the level tests' marks),
//!   the objects visible in the last frame and those outside the frustum
//!   (frustum.rs's `gpu_verdict`), what the walk must have counted, marked
//!   and drawn;
//! - [`NodeBoxes`], of `cs_prepare` (prepare_nodes.wgsl): each node's
//!   eye-relative box and word, in f64, as gpu/conservative.rs prepares a
//!   box for a test;
//! - [`BoxOnTarget`], of hiz's box test (pyramid_test.wgsl's header): in
//!   f64, whether a box lies behind the pyramid, and pixel by pixel behind
//!   the depth where the pyramid does not hide it.
//!
//! The test below holds the GPU's audit and marks against them, frame by
//! frame.

use std::ops::RangeInclusive;

use glam::{DMat4, DVec2, DVec3, Vec4Swizzles};

use super::CullTree;
use super::layout::{OUTSIDE_FRUSTUM, REACHES_NEAR, TO_TEST};
use super::pyramid::PyramidLevel;
use crate::bounds::Aabb;
use crate::camera::{Camera, Containment};
use crate::gpu::{BoxMargins, EyeBox, QueryBox, Resolution, ShaderBoxPlanes, eye_relative_box};

/// A walk's node boxes for one camera as `cs_prepare` should make them,
/// prepared in f64.
pub(super) struct NodeBoxes {
    /// One per node, eye-relative; empty for a node outside the frustum or
    /// reaching the near plane.
    pub boxes: Vec<QueryBox>,
    /// One per node, its state before the walk: [`TO_TEST`],
    /// [`OUTSIDE_FRUSTUM`] or [`REACHES_NEAR`].
    pub states: Vec<u32>,
}

impl NodeBoxes {
    /// `bounds`, one box per node, prepared for `camera` with the frame's
    /// `margins`.
    pub fn new(camera: &Camera, margins: BoxMargins, bounds: impl Iterator<Item = Aabb>) -> NodeBoxes {
        let view = camera.view_rotation();
        let frustum = camera.frustum();
        let (mut boxes, mut states) = (Vec::new(), Vec::new());
        for b in bounds {
            // The frustum test comes first: the near-plane rule must not
            // take a box beside the camera for one that holds it.
            let (q, state) = if frustum.classify(&b) == Containment::Outside {
                (bytemuck::Zeroable::zeroed(), OUTSIDE_FRUSTUM)
            } else {
                match eye_relative_box(camera, &view, margins, &b) {
                    EyeBox::Testable(q) => (q, TO_TEST),
                    EyeBox::ReachesNear => (bytemuck::Zeroable::zeroed(), REACHES_NEAR),
                }
            };
            boxes.push(q);
            states.push(state);
        }
        NodeBoxes { boxes, states }
    }
}

/// What one walk did, by the CPU's reckoning.
#[derive(Debug, Default, PartialEq)]
pub(super) struct CpuWalk {
    /// Nodes reached: the seed, and every child of a visible inner node.
    pub visited: u64,
    /// Reached nodes whose box was tested (drawn into the visibility
    /// buffer, or compared with the pyramid).
    pub tested: u64,
    /// Tested, and not found visible: the subtree is culled.
    pub hidden: u64,
    /// Reached, and outside the frustum: culled untested.
    pub outside: u64,
    /// Every node reached and not outside the frustum: queued for a test
    /// (those reaching the near plane pass it untested).
    pub queued: Vec<u32>,
    /// Objects of visible leaves inside the frustum: this frame's visible
    /// list.
    pub marked: Vec<bool>,
    /// Objects of last frame's visible list inside the frustum: drawn
    /// first, as occluders.
    pub early: Vec<bool>,
    /// Objects drawn: early, or marked now (drawn after the walk).
    pub drawn: Vec<bool>,
}

/// The walk of `tree` whose nodes ended in `states`, after a frame in
/// which `visible_last` were visible, with the objects `outside` the
/// frustum.
pub(super) fn walk(tree: &CullTree, states: &[u32], visible_last: &[bool], outside: &[bool]) -> CpuWalk {
    let objects = tree.order.len();
    let mut w = CpuWalk {
        marked: vec![false; objects],
        ..CpuWalk::default()
    };
    let mut near = 0;
    let reach = |node: u32, w: &mut CpuWalk, queue: &mut Vec<u32>| {
        w.visited += 1;
        if states[node as usize] == OUTSIDE_FRUSTUM {
            w.outside += 1;
        } else {
            queue.push(node);
        }
    };
    let mut queue = Vec::new();
    for &node in &tree.seed {
        reach(node, &mut w, &mut queue);
    }
    while !queue.is_empty() {
        let mut next = Vec::new();
        for node in std::mem::take(&mut queue) {
            w.queued.push(node);
            match states[node as usize] {
                TO_TEST => {
                    w.hidden += 1;
                    continue;
                }
                REACHES_NEAR => near += 1,
                _ => {}
            }
            let n = tree.nodes[node as usize];
            if n.child_count == 0 {
                let first = n.first_object as usize;
                for &object in &tree.order[first..first + n.object_count as usize] {
                    w.marked[object as usize] = !outside[object as usize];
                }
            } else {
                for child in n.first_child..n.first_child + n.child_count {
                    reach(child, &mut w, &mut next);
                }
            }
        }
        queue = next;
    }
    w.tested = w.visited - w.outside - near;
    w.early = visible_last.iter().zip(outside).map(|(&v, &o)| v && !o).collect();
    w.drawn = w.marked.iter().zip(&w.early).map(|(&m, &e)| m || e).collect();
    w
}

/// The level and the texels (columns, rows) hiz's test reads for the
/// pixels `first` to `last` (x, y, inclusive) of a target of `size`: the
/// base texels whose footprints hold those pixels, at the finest level
/// where they span fewer than `span` + 1 texels across.
fn texels_read(
    first: [u32; 2],
    last: [u32; 2],
    size: Resolution,
    levels: &[PyramidLevel],
    span: u32,
) -> (usize, [RangeInclusive<u32>; 2]) {
    let base = levels[0];
    let texel = |p: u32, base_side: u32, side: u32| (u64::from(p) * u64::from(base_side) / u64::from(side)) as u32;
    let (bx0, bx1) = (
        texel(first[0], base.width, size.width),
        texel(last[0], base.width, size.width),
    );
    let (by0, by1) = (
        texel(first[1], base.height, size.height),
        texel(last[1], base.height, size.height),
    );
    let k = (0..levels.len())
        .find(|&k| (bx1 >> k) - (bx0 >> k) < span && (by1 >> k) - (by0 >> k) < span)
        .unwrap_or(levels.len() - 1);
    (k, [bx0 >> k..=bx1 >> k, by0 >> k..=by1 >> k])
}

/// What hiz's test must find for one box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Verdict {
    Visible,
    Hidden,
    /// An edge of the box's rectangle within 1e-3 pixel of a pixel's edge,
    /// or a depth compared within 1e-5 of the other (or, for a plane, within
    /// what its f32 evaluation may move it): f32 may decide either way.
    TooClose,
}

/// A box hiz tests (`query`, prepared for `camera` at `size`), on the
/// target, in f64: the pixels its rectangle touches and its nearest depth.
pub(super) struct BoxOnTarget {
    first: [u32; 2],
    last: [u32; 2],
    nearest: f64,
    on_pixel_edge: bool,
}

impl BoxOnTarget {
    pub(super) fn new(query: &QueryBox, camera: &Camera, size: Resolution) -> BoxOnTarget {
        let view_projection = camera.projection() * DMat4::from_mat3(camera.view_rotation());
        let (min, max) = (query.min.xyz().as_dvec3(), query.max.xyz().as_dvec3());
        let (mut low, mut high, mut nearest) = (DVec2::INFINITY, DVec2::NEG_INFINITY, f64::NEG_INFINITY);
        for corner in 0..8 {
            let pick = |bit: u32, axis: usize| if corner & bit != 0 { max[axis] } else { min[axis] };
            let clip = view_projection * DVec3::new(pick(1, 0), pick(2, 1), pick(4, 2)).extend(1.0);
            let ndc = clip.truncate() / clip.w;
            low = low.min(ndc.truncate());
            high = high.max(ndc.truncate());
            // The raise lifts depth, not the outline (gpu/conservative.rs).
            nearest = nearest.max(ndc.z + f64::from(query.min.w));
        }
        let (width, height) = (f64::from(size.width), f64::from(size.height));
        // Pixel edges, rows from the top.
        let edges = [
            (low.x * 0.5 + 0.5) * width,
            (high.x * 0.5 + 0.5) * width,
            (0.5 - high.y * 0.5) * height,
            (0.5 - low.y * 0.5) * height,
        ];
        let pixel = |edge: f64, side: f64| edge.floor().clamp(0.0, side - 1.0) as u32;
        BoxOnTarget {
            first: [pixel(edges[0], width), pixel(edges[2], height)],
            last: [pixel(edges[1], width), pixel(edges[3], height)],
            nearest,
            on_pixel_edge: edges.iter().any(|e| (e - e.round()).abs() < 1e-3),
        }
    }

    /// Pixels its rectangle holds.
    pub(super) fn pixels(&self) -> u64 {
        let side = |axis: usize| u64::from(self.last[axis] - self.first[axis] + 1);
        side(0) * side(1)
    }

    /// Whether its rectangle meets the pixels `first` to `last` (x, y,
    /// inclusive).
    pub(super) fn meets(&self, first: [u32; 2], last: [u32; 2]) -> bool {
        (0..2).all(|axis| self.first[axis] <= last[axis] && first[axis] <= self.last[axis])
    }

    /// The pyramid's part of hiz's test (pyramid_test.wgsl's header): against
    /// a pyramid of `levels` holding `texels` over a `size` target, reading
    /// the finest level where the rectangle spans fewer than `span` + 1
    /// texels across.
    pub(super) fn pyramid_verdict(
        &self,
        size: Resolution,
        levels: &[PyramidLevel],
        texels: &[Vec<f32>],
        span: u32,
    ) -> Verdict {
        let (k, [xs, ys]) = texels_read(self.first, self.last, size, levels, span);
        let mut farthest = 1.0f64;
        for y in ys {
            for x in xs.clone() {
                farthest = farthest.min(f64::from(texels[k][(y * levels[k].width + x) as usize]));
            }
        }
        if self.on_pixel_edge || (self.nearest - farthest).abs() <= 1e-5 * farthest {
            Verdict::TooClose
        } else if self.nearest < farthest {
            Verdict::Hidden
        } else {
            Verdict::Visible
        }
    }

    /// The pixels' part (pyramid_test.wgsl's `cs_pixels`, and its
    /// `span_hides_box` over one pixel): each pixel of the rectangle against
    /// `depth` (of a `size` target, row by row) by the box's `planes` as the
    /// shader makes them (`ShaderBoxPlanes::as_the_shader_makes`). `Hidden`
    /// where the box lies behind at every pixel whose ray meets it.
    pub(super) fn pixel_verdict(&self, planes: &ShaderBoxPlanes, size: Resolution, depth: &[f32]) -> Verdict {
        // A plane's value at a centre, and how far the shader's may lie
        // from it: its division may be 2 steps of 2^-23 further off than
        // the twin's, and its evaluation adds a few steps of 2^-24, all of
        // its terms' size; 1e-6 of that size is 16 steps of 2^-24.
        let (width, height) = (f64::from(size.width), f64::from(size.height));
        let value = |p: &[f32; 4], x: f64, y: f64| {
            let [a, b, c] = [p[0], p[1], p[2]].map(f64::from);
            (a * x + b * y + c, 1e-6 * (c.abs() + a.abs() * width + b.abs() * height))
        };
        let mut verdict = Verdict::Hidden;
        for y in self.first[1]..=self.last[1] {
            for x in self.first[0]..=self.last[0] {
                let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                let entries = planes.entries.map(|p| value(&p, cx, cy));
                let exits = planes.exits.map(|p| value(&p, cx, cy));
                // Missed (Hidden), met (Visible), or too close to tell.
                let mut missed = Verdict::Visible;
                for (i, (entry, entry_error)) in entries.iter().enumerate() {
                    for (j, (exit, exit_error)) in exits.iter().enumerate() {
                        if i == j || missed == Verdict::Hidden {
                            continue;
                        } else if (entry - exit).abs() <= entry_error + exit_error {
                            missed = Verdict::TooClose;
                        } else if entry < exit {
                            missed = Verdict::Hidden;
                        }
                    }
                }
                if missed == Verdict::Hidden {
                    continue;
                }
                // The shader's least may be another entry within its own
                // error, so the largest error of a real plane (not one
                // standing for no bound) bounds the least's.
                let (bound, error) = entries
                    .iter()
                    .filter(|(v, _)| v.abs() < 1e29)
                    .fold((self.nearest, 0.0f64), |(b, e), &(v, ve)| (b.min(v), e.max(ve)));
                let drawn = f64::from(depth[(y * size.width + x) as usize]);
                // In front of what is drawn, the box shows here where its
                // ray meets it.
                let here = if (bound - drawn).abs() <= 1e-5 * drawn + error {
                    Verdict::TooClose
                } else if bound < drawn {
                    Verdict::Hidden
                } else {
                    missed
                };
                match here {
                    Verdict::Visible => return Verdict::Visible,
                    Verdict::TooClose => verdict = Verdict::TooClose,
                    Verdict::Hidden => {}
                }
            }
        }
        verdict
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::auto_or::AutoOr;
    use crate::camera::generate::default_path;
    use crate::cull::ModeParams;
    use crate::cull::gpu_walk::GpuCulling;
    use crate::cull::gpu_walk::depths::{DepthRange, Level};
    use crate::cull::gpu_walk::frustum::gpu_verdict;
    use crate::cull::gpu_walk::hiz::{BoxesTested, HizParams, hierarchical_depth_culling};
    use crate::cull::gpu_walk::ioc::iterative_occlusion_culling;
    use crate::cull::gpu_walk::layout::VISIBLE;
    use crate::cull::gpu_walk::layout::boxes_module;
    use crate::cull::gpu_walk::level_test::pyramid_test_source;
    use crate::cull::gpu_walk::pyramid::DepthPyramid;
    use crate::cull::gpu_walk::roc::raster_occlusion_culling;
    use crate::gpu::{
        GpuContext, Readback, assert_planes_bound, camera_buffer, random_boxes_in_view, storage_buffer, test_camera,
        texture_2d,
    };
    use crate::hierarchy::{Hierarchy, HierarchyParams};
    use crate::scene::{LoadOptions, SceneSpec, load};
    use crate::session::{RunOptions, Session};
    use crate::world::World;

    const RESOLUTION: Resolution = Resolution {
        width: 160,
        height: 120,
    };

    /// Runs `mode` through `world` from `cameras` on `gpu`, holding every
    /// frame against the twin's walk of `tree` and, for hiz's test with
    /// `hiz` parameters, the mark of every box it tested against the
    /// twin's verdict ([`BoxOnTarget`]); returns the nodes the walks hid.
    fn compare(
        gpu: &GpuContext,
        mut world: World,
        cameras: &[Camera],
        mut mode: GpuCulling,
        (tree, source): (&CullTree, Option<&[u32]>),
        hiz: Option<HizParams>,
    ) -> u64 {
        let options = RunOptions {
            warmup: 0,
            resolution: RESOLUTION,
            measure_error: false,
        };
        // The error meter reads the mode's depth back each frame.
        let mut session = Session::new(gpu, &world, &mut [Box::new(&mut mode)], hiz.is_some(), &options).unwrap();
        let objects = world.scene.objects.len();
        let (mut visible_last, mut hidden) = (vec![false; objects], 0);
        let (mut tested, mut too_close, mut by_pixels, mut held) = (0, 0, 0, 0);
        for (frame, &camera) in (0..).zip(cameras) {
            world.advance(frame);
            let row = session
                .frame(frame, &camera, &mut world, &mut [Box::new(&mut mode)], 0)
                .unwrap()
                .remove(0);
            let on_gpu = mode.gpu_walk().expect("the session prepared the walk");
            let states = on_gpu.node_states(gpu);
            let outside: Vec<bool> = world
                .scene
                .objects
                .iter()
                .enumerate()
                .map(|(o, object)| {
                    gpu_verdict(&camera, &object.bounds).unwrap_or_else(|| {
                        panic!("frame {frame}: object {o} lies where the GPU may call it either way")
                    })
                })
                .collect();
            let twin = walk(tree, &states, &visible_last, &outside);
            let margins = BoxMargins::new(gpu.depth_margins, gpu.subpixel, &camera, RESOLUTION);
            // Each node's box: its object's, or its hierarchy node's.
            let bounds: Vec<Aabb> = match source {
                Some(source) => source
                    .iter()
                    .map(|&n| world.hierarchy.nodes[n as usize].bounds)
                    .collect(),
                None => world.scene.objects.iter().map(|o| o.bounds).collect(),
            };
            let cpu = NodeBoxes::new(&camera, margins, bounds.into_iter());
            let gpu_boxes = on_gpu.tested_boxes(gpu);
            held += hold_boxes_made_on_the_gpu(&cpu, &states, &gpu_boxes, frame);
            let at = format!("{} frame {frame} on {}", row.mode, gpu.adapter);
            if let Some(params) = hiz {
                let (levels, texels) = on_gpu.pyramid(gpu).expect("a pyramid test");
                // The depth as the frame ended: where objects were drawn
                // after the test (late), nearer than what the test read.
                let depth = session.mode_depth(0).expect("the session has an error meter");
                let view = camera.view_rotation();
                let late: Vec<Option<BoxOnTarget>> = (0..objects)
                    .filter(|&o| twin.marked[o] && !twin.early[o])
                    .map(
                        |o| match eye_relative_box(&camera, &view, margins, &world.scene.objects[o].bounds) {
                            EyeBox::Testable(q) => Some(BoxOnTarget::new(&q, &camera, RESOLUTION)),
                            EyeBox::ReachesNear => None,
                        },
                    )
                    .collect();
                for &node in &twin.queued {
                    let node = node as usize;
                    if !matches!(states[node], TO_TEST | VISIBLE) {
                        continue;
                    }
                    let marked = states[node] != TO_TEST;
                    let query = &gpu_boxes[node];
                    let on_target = BoxOnTarget::new(query, &camera, RESOLUTION);
                    let verdict = match on_target.pyramid_verdict(RESOLUTION, &levels, &texels, params.texels) {
                        Verdict::Visible if on_target.pixels() <= u64::from(params.pixels) => {
                            let planes = ShaderBoxPlanes::as_the_shader_makes(&camera, query, RESOLUTION, 0);
                            let drawn_after =
                                |b: &Option<BoxOnTarget>| b.as_ref().is_none_or(|b| on_target.meets(b.first, b.last));
                            match on_target.pixel_verdict(&planes, RESOLUTION, &depth) {
                                // Hidden by depth drawn after the test proves nothing.
                                Verdict::Hidden if late.iter().any(drawn_after) => continue,
                                Verdict::Hidden => {
                                    by_pixels += 1;
                                    Verdict::Hidden
                                }
                                other => other,
                            }
                        }
                        other => other,
                    };
                    match verdict {
                        Verdict::Visible => assert!(marked, "{at}: box {node} is visible"),
                        Verdict::Hidden => assert!(!marked, "{at}: box {node} is hidden"),
                        Verdict::TooClose => too_close += 1,
                    }
                }
            }
            assert_eq!(row.traversal.nodes_visited, twin.visited, "{at}");
            assert_eq!(row.traversal.nodes_culled_frustum, twin.outside, "{at}");
            assert_eq!(row.traversal.nodes_culled_occlusion, twin.hidden, "{at}");
            assert_eq!(row.queries, twin.tested, "{at}");
            let drawn: Vec<bool> = (0..objects as u32).map(|o| session.drawn[0].contains(o)).collect();
            assert_eq!(drawn, twin.drawn, "{at}");
            // Early: last frame's visible list; late: marked now, not in it.
            let early = twin.early.iter().filter(|&&e| e).count() as u64;
            let late = twin.marked.iter().zip(&twin.early).filter(|&(&m, &e)| m && !e).count() as u64;
            assert_eq!(row.traversal.drawn_early, early, "{at}");
            assert_eq!(row.traversal.drawn_late, late, "{at}");
            hidden += twin.hidden;
            tested += row.queries;
            visible_last = twin.marked;
        }
        assert!(
            too_close * 50 <= tested,
            "{too_close} of {tested} boxes too close to call"
        );
        assert!(held > 0, "boxes made on the GPU held to the CPU's");
        if let Some(params) = hiz.filter(|p| p.pixels > 0) {
            assert!(by_pixels > 20, "{params:?}: {by_pixels} boxes hidden pixel by pixel");
        }
        hidden
    }

    /// Holds the boxes and words a walk made on the GPU to those
    /// the CPU prepares in f64: every node the CPU finds outside the frustum
    /// the GPU does too; one the GPU tests, the CPU tests too, and the GPU's
    /// box holds the CPU's, raised at least as much.
    /// Returns how many boxes it held.
    fn hold_boxes_made_on_the_gpu(cpu: &NodeBoxes, states: &[u32], boxes: &[QueryBox], frame: u32) -> u64 {
        let mut tested = 0;
        for (node, (&cpu_state, gpu_box)) in cpu.states.iter().zip(boxes).enumerate() {
            let at = format!("frame {frame} node {node}");
            let gpu_tested = matches!(states[node], TO_TEST | VISIBLE);
            if cpu_state == OUTSIDE_FRUSTUM {
                assert_eq!(states[node], OUTSIDE_FRUSTUM, "{at}: outside on the CPU");
            }
            if !gpu_tested {
                continue;
            }
            assert_eq!(cpu_state, TO_TEST, "{at}: tested on the GPU only");
            let q = &cpu.boxes[node];
            let holds = gpu_box.min.truncate().cmple(q.min.truncate()).all()
                && gpu_box.max.truncate().cmpge(q.max.truncate()).all();
            assert!(holds, "{at}: {gpu_box:?} holds {q:?}");
            assert!(gpu_box.min.w >= q.min.w, "{at}: {gpu_box:?} raised at least as {q:?}");
            tested += 1;
        }
        tested
    }

    /// The target pixels in a level-`k` texel's footprint along one side:
    /// its base texels [t · 2^k, (t + 1) · 2^k) hold the target pixels p
    /// with first ≤ p · base / side < end (pyramid.rs's definition).
    fn footprint(t: u32, k: usize, base_side: u32, side: u32) -> std::ops::Range<u64> {
        let (first, end) = (
            u64::from(t << k).min(u64::from(base_side)),
            u64::from((t + 1) << k).min(u64::from(base_side)),
        );
        let (side, base_side) = (u64::from(side), u64::from(base_side));
        (first * side).div_ceil(base_side)..(end * side).div_ceil(base_side)
    }

    #[test]
    fn the_texels_read_hold_every_pixel_of_the_rectangle_and_span_at_most_the_limit() {
        let mut rng = crate::rng::Rng::new(20);
        let sizes = [
            (801, 599),
            (1, 1),
            (1023, 1),
            (8191, 3),
            (37, 5),
            (2, 3),
            (640, 480),
            (1920, 1080),
        ];
        for (width, height) in sizes {
            let size = Resolution { width, height };
            for (span, base_divisor) in [(2, 1), (3, 1), (4, 1), (16, 1), (4, 4), (2, 8)] {
                let levels = super::super::pyramid::levels(size, base_divisor);
                let base = levels[0];
                for _ in 0..400 {
                    let pick = |side: u32, rng: &mut crate::rng::Rng| {
                        let a = rng.range(0.0, f64::from(side)) as u32;
                        let b = rng.range(0.0, f64::from(side)) as u32;
                        (a.min(b), a.max(b))
                    };
                    let ((x0, x1), (y0, y1)) = (pick(width, &mut rng), pick(height, &mut rng));
                    let (k, [xs, ys]) = texels_read([x0, y0], [x1, y1], size, &levels, span);
                    let at = format!(
                        "{width}x{height} over {base_divisor}, span {span}: pixels {x0}..={x1} × {y0}..={y1} read level {k} {xs:?} × {ys:?}"
                    );
                    assert!(xs.end() < &levels[k].width && ys.end() < &levels[k].height, "{at}");
                    if k + 1 < levels.len() {
                        assert!(xs.end() - xs.start() < span && ys.end() - ys.start() < span, "{at}");
                    }
                    for x in x0..=x1 {
                        let held = xs
                            .clone()
                            .any(|t| footprint(t, k, base.width, width).contains(&u64::from(x)));
                        assert!(held, "{at}: column {x}");
                    }
                    for y in y0..=y1 {
                        let held = ys
                            .clone()
                            .any(|t| footprint(t, k, base.height, height).contains(&u64::from(y)));
                        assert!(held, "{at}: row {y}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_gpu_walk_counts_marks_and_draws_what_its_cpu_twin_does() {
        let scene = load(
            &SceneSpec::Builtin("city:blocks=2,movers=12".into()),
            &LoadOptions::default(),
        )
        .unwrap();
        let (path, _) = default_path(&scene).unwrap();
        let path = path.with_frames(12).unwrap();
        let path: Vec<Camera> = (0..path.frames).map(|f| path.camera(f, RESOLUTION.aspect())).collect();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        let gpus = GpuContext::every_gpu_driven_adapter();
        // roc's and hiz's flat tree, and ioc's and hiz's hierarchy cut from
        // depth 2 to 6.
        let flat = CullTree::flat(scene.objects.len() as u32);
        let (cut, source) = CullTree::cut(&hierarchy, 2, 6);
        let nodes = DepthRange {
            start: AutoOr::Given(Level(2)),
            bottom: AutoOr::Given(Level(6)),
        };
        for gpu in &gpus {
            let world = || World::new(scene.clone(), hierarchy.clone());
            let hidden = compare(gpu, world(), &path, raster_occlusion_culling(), (&flat, None), None);
            assert!(
                hidden > 50,
                "roc's walks hide nodes, so the comparison means something ({hidden})"
            );
            let hidden = compare(
                gpu,
                world(),
                &path,
                iterative_occlusion_culling(nodes),
                (&cut, Some(&source)),
                None,
            );
            assert!(hidden > 50, "ioc's walks hide nodes ({hidden})");
            // hiz as it runs by default (objects, 4 texels, a base a quarter
            // the target's, pixel by pixel where that fails), on the largest
            // base (whose texels under a large box outnumber the pixel
            // pass's list of open ones), as the engines read (2 texels, the
            // largest base, no pixels), and over nodes.
            let default = HizParams::from_params(&ModeParams::default()).unwrap();
            let finest = HizParams {
                base_divisor: 1,
                ..default
            };
            let engines = HizParams {
                texels: 2,
                base_divisor: 1,
                pixels: 0,
                ..default
            };
            let over_nodes = HizParams {
                boxes: BoxesTested::Nodes,
                range: nodes,
                ..default
            };
            for (params, tree, least) in [
                (default, (&flat, None), 50),
                (finest, (&flat, None), 50),
                (engines, (&flat, None), 50),
                (over_nodes, (&cut, Some(&source[..])), 20),
            ] {
                let mode = hierarchical_depth_culling(params);
                let hidden = compare(gpu, world(), &path, mode, tree, Some(params));
                assert!(hidden > least, "hiz's walks hide boxes ({params:?}: {hidden})");
            }
        }
    }

    /// pyramid_test.wgsl's `box_planes` run on the GPU for each of `boxes_in`,
    /// seen by `camera` on a `target`, and its planes read back.
    fn box_planes_on_the_gpu(
        gpu: &GpuContext,
        camera: &Camera,
        target: Resolution,
        boxes_in: &[QueryBox],
    ) -> Vec<ShaderBoxPlanes> {
        let probe = "@group(2) @binding(3) var<storage, read_write> probed: array<BoxPlanes>;
            @compute @workgroup_size(64)
            fn cs_probe(@builtin(global_invocation_id) id: vec3<u32>) {
                if id.x < arrayLength(&probed) {
                    probed[id.x] = box_planes(boxes[id.x]);
                }
            }";
        let source = [pyramid_test_source(4, 1024).as_str(), probe].concat();
        let module = boxes_module(gpu, "box planes probe", &source);
        let pipeline = gpu.compute_pipeline(&module, "cs_probe", None);
        let depth = texture_2d(
            gpu,
            "depth",
            target,
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let pyramid = DepthPyramid::new(gpu, target, 4, &depth.create_view(&Default::default())).unwrap();
        let storage = wgpu::BufferUsages::STORAGE;
        let boxes = gpu.buffer_with("boxes", bytemuck::cast_slice(boxes_in), storage);
        let bytes = (boxes_in.len() * size_of::<ShaderBoxPlanes>()) as u64;
        let probed = storage_buffer(gpu, "planes", bytes, wgpu::BufferUsages::COPY_SRC);
        let camera = camera_buffer(gpu, camera, target);
        let group = |k: u32, buffers: &[(u32, &wgpu::Buffer)]| {
            let entries: Vec<wgpu::BindGroupEntry> = buffers
                .iter()
                .map(|&(binding, b)| wgpu::BindGroupEntry {
                    binding,
                    resource: b.as_entire_binding(),
                })
                .collect();
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(k),
                entries: &entries,
            })
        };
        let groups = [
            group(0, &[(0, &camera), (1, &boxes)]),
            group(1, &[(4, pyramid.bindings()[1])]),
            group(2, &[(3, &probed)]),
        ];
        let readback = Readback::new(gpu, "planes", bytes);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            for (k, g) in groups.iter().enumerate() {
                pass.set_bind_group(k as u32, g, &[]);
            }
            pass.dispatch_workgroups((boxes_in.len() as u32).div_ceil(64), 1, 1);
        }
        readback.copy(&mut encoder, &probed, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        let mut planes = Vec::new();
        readback.read(gpu, bytes, &mut planes);
        gpu.check().expect("the probe ran");
        planes
    }

    #[test]
    fn box_planes_made_on_the_gpu_are_their_f32_twins_and_bound_every_pixel_centre() {
        let camera = test_camera();
        let target = Resolution::DEFAULT;
        let (size_x, size_y) = (f64::from(target.width), f64::from(target.height));
        let mut boxes: Vec<QueryBox> = random_boxes_in_view(53).into_iter().map(|(_, q)| q).collect();
        // And the edges: a face a hair from the eye's plane (huge
        // coefficients), a box far off, one beside the eye along an axis.
        let edges = [
            ([1e-6, -1.0, -30.0], [2.0, 1.0, -20.0]),
            ([-500.0, -400.0, -9000.0], [600.0, 300.0, -8000.0]),
            ([-1.0, -0.5, -12.0], [1.0, 0.5, -11.0]),
        ];
        boxes.extend(edges.map(|(min, max)| QueryBox {
            min: glam::Vec3::from(min).extend(1e-7),
            max: glam::Vec3::from(max).extend(0.0),
        }));
        for gpu in &GpuContext::every_gpu_driven_adapter() {
            let made = box_planes_on_the_gpu(gpu, &camera, target, &boxes);
            let mut compared = 0;
            for (q, gpu_planes) in boxes.iter().zip(&made) {
                let at = format!("{} on {}", q.min, gpu.adapter);
                // Within its twin's rounding: a division 2.5 steps off, and
                // the sums' and products' few steps of its terms' size.
                let twin = ShaderBoxPlanes::as_the_shader_makes(&camera, q, target, 0);
                let pairs = gpu_planes
                    .entries
                    .iter()
                    .zip(&twin.entries)
                    .chain(gpu_planes.exits.iter().zip(&twin.exits));
                for (got, want) in pairs {
                    let terms = f64::from(want[2].abs())
                        + f64::from(want[0].abs()) * size_x
                        + f64::from(want[1].abs()) * size_y;
                    for k in 0..3 {
                        let off = f64::from(got[k] - want[k]).abs()
                            * if k == 0 {
                                size_x
                            } else if k == 1 {
                                size_y
                            } else {
                                1.0
                            };
                        assert!(off <= 1e-6 * terms, "{at}: {got:?} against its twin {want:?}");
                    }
                }
                // Above each entry plane and below each exit plane, in exact
                // arithmetic, at every 5th pixel centre, summed as the GPU may.
                compared += assert_planes_bound(&camera, q, gpu_planes, target, 5, &at);
            }
            assert!(compared > 500_000, "{compared} comparisons on {}", gpu.adapter);
        }
    }

    #[test]
    fn boxes_made_on_the_gpu_hold_the_cpus_far_from_the_origin() {
        // The stress case whose town lies 1e7 from the origin, where f32
        // steps by a metre: the boxes' two f32 parts are what keep them
        // there. Its coordinates are whole metres, so the eye is moved off
        // them, to give it low parts.
        let case = crate::stress::select(&["offset-1e7".to_string()])
            .unwrap()
            .into_iter()
            .find(|c| c.name == "offset-1e7")
            .expect("the case, after its baseline");
        let cameras: Vec<Camera> = case
            .cameras
            .iter()
            .map(|c| Camera {
                aspect: RESOLUTION.aspect(),
                eye: c.eye + DVec3::new(0.37, 0.21, 0.13),
                ..*c
            })
            .collect();
        let hierarchy = Hierarchy::build(&case.scene.objects, &HierarchyParams::default());
        let flat = CullTree::flat(case.scene.objects.len() as u32);
        let (cut, source) = CullTree::cut(&hierarchy, 1, 4);
        let nodes = DepthRange {
            start: AutoOr::Given(Level(1)),
            bottom: AutoOr::Given(Level(4)),
        };
        for gpu in GpuContext::every_gpu_driven_adapter() {
            let world = || World::new(case.scene.clone(), hierarchy.clone());
            compare(&gpu, world(), &cameras, raster_occlusion_culling(), (&flat, None), None);
            let ioc = iterative_occlusion_culling(nodes);
            compare(&gpu, world(), &cameras, ioc, (&cut, Some(&source)), None);
        }
    }
}
