//! GPU-driven culling (`roc`, `ioc`, paper 004; `hiz`): exact images, the objects
//! a hand-made scene leaves visible, and round trips per frame, on every
//! backend.

mod common;

use common::{boxes, held, run_modes};
use glam::DVec3;
use std::rc::Rc;

use occlu::cull::{Culler, FrameInput, Labeled, ModeId, ModeParams, TraversalStats, VisibleLists, create};
use occlu::gpu::{Frame, GpuAudit, GpuContext, GpuError, GpuSetup, Resolution};
use occlu::hierarchy::Hierarchy;
use occlu::measure::FrameStats;
use occlu::object_set::ObjectSet;
use occlu::scene::Scene;

const RES: Resolution = Resolution { width: 128, height: 96 };

/// `mode` with `items` as its parameters, under `label`.
fn mode(scene: &Scene, label: &str, mode: &str, items: &[&str]) -> Box<dyn Culler> {
    let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
    Box::new(Labeled {
        label: label.into(),
        inner: create(
            mode,
            scene,
            &ModeParams::parse(&items, &[mode.parse().unwrap()]).unwrap(),
        )
        .unwrap(),
    })
}

/// Round trips a GPU-driven frame may take: none where draws take their
/// count from a GPU buffer, one (the list lengths) elsewhere.
fn round_trips(gpu: &GpuContext) -> u64 {
    u64::from(!gpu.indirect_count)
}

fn assert_exact(rows: &[FrameStats], gpu: &GpuContext) {
    for r in rows {
        assert_eq!(
            (r.error_pixels, r.missed_objects),
            (Some(0), Some(0)),
            "{} frame {} on {}",
            r.mode,
            r.frame,
            gpu.adapter
        );
    }
}

#[test]
fn gpu_walks_draw_what_a_wall_leaves_visible() {
    // The camera at the origin looks down -z (90° field of view).
    let scene = boxes(&[
        (DVec3::new(-3.0, -3.0, -10.1), DVec3::new(3.0, 3.0, -9.9)), // 0 wall
        (DVec3::new(-0.5, -0.5, -20.5), DVec3::new(0.5, 0.5, -19.5)), // 1 hidden by it
        (DVec3::new(10.0, -0.5, -20.5), DVec3::new(11.0, 0.5, -19.5)), // 2 beside it
        (DVec3::new(-0.2, -0.3, -0.5), DVec3::new(0.2, -0.1, 0.5)),  // 3 through the near plane
        (DVec3::new(-1.0, -1.0, 5.0), DVec3::new(1.0, 1.0, 7.0)),    // 4 behind the eye
        // 5: level with the eye, far off to the side: it spans the near
        // plane's depth but lies outside the frustum.
        (DVec3::new(40.0, -1.0, -2.0), DVec3::new(42.0, 1.0, 2.0)),
    ]);
    let path = held(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 90.0, 4);
    let hierarchy = Hierarchy::build(&scene.objects, &common::one_object_per_leaf());
    let deepest = hierarchy.stats().depth - 1;
    let full = format!("ioc.bottom={deepest}");
    for gpu in common::gpus() {
        let mut cullers = vec![
            mode(&scene, "roc", "roc", &[]),
            mode(&scene, "ioc", "ioc", &["ioc.start=0", &full]),
            mode(&scene, "ioc[root]", "ioc", &["ioc.start=0", "ioc.bottom=0"]),
            mode(&scene, "hiz", "hiz", &[]),
            mode(&scene, "hiz[engines]", "hiz", &["hiz.texels=2"]),
        ];
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, RES).rows;
        assert_exact(&rows, &gpu);
        for r in &rows {
            let at = format!("{} frame {} on {}", r.mode, r.frame, gpu.adapter);
            // Frame 0 has no occluders from a previous frame: everything in
            // the frustum is found visible. Frame 1 draws those, so its test
            // finds the hidden box; from frame 2 on it is not drawn at all.
            let expected = match (r.mode.as_str(), r.frame) {
                // The root is visible: all its subtree inside the frustum,
                // the hidden box too, not the two outside it.
                ("ioc[root]", _) => 4,
                (_, 0 | 1) => 4,
                _ => 3, // the wall, the box beside it, the one at the near plane
            };
            assert_eq!(r.objects_drawn, expected, "{at}: {r:?}");
            assert_eq!(r.query_batches, round_trips(&gpu), "{at}");
        }
        let first = |m: &str| rows.iter().find(|r| r.mode == m).unwrap();
        let roc = first("roc");
        assert_eq!(roc.traversal.nodes_visited, 6, "roc visits every object's box");
        assert_eq!(
            roc.traversal.nodes_culled_frustum, 2,
            "the boxes behind the eye and off to the side"
        );
        assert_eq!(roc.queries, 3, "the box through the near plane is visible untested");
        for m in ["hiz", "hiz[engines]"] {
            let hiz = first(m);
            let at = format!("{m} on {}", gpu.adapter);
            assert_eq!(
                (
                    hiz.traversal.nodes_visited,
                    hiz.traversal.nodes_culled_frustum,
                    hiz.queries
                ),
                (6, 2, 3),
                "{at}: as roc"
            );
            let frame = |k: u32| rows.iter().find(|r| r.mode == m && r.frame == k).unwrap();
            let (second, third) = (frame(1).traversal, frame(2).traversal);
            assert_eq!(
                (second.drawn_early, second.drawn_late, second.nodes_culled_occlusion),
                (4, 0, 1),
                "{at}: frame 1 draws what frame 0 found and hides the box behind the wall"
            );
            assert_eq!((third.drawn_early, third.drawn_late), (3, 0), "{at}");
        }
        let root = first("ioc[root]");
        assert_eq!(
            (root.traversal.nodes_visited, root.queries),
            (1, 0),
            "a bottom of 0 visits the root alone, which holds the eye"
        );
        assert!(
            first("ioc").traversal.nodes_visited > 6,
            "the full walk visits inner nodes too"
        );
    }
}

/// roc on even frames and hiz on odd ones, the two walks sharing one set
/// of visible lists (as `auto`'s walks do); at frame `upload.0` the lists
/// are first made to hold `upload.1`.
struct Alternating {
    walks: [Box<dyn Culler>; 2],
    lists: Option<Rc<VisibleLists>>,
    upload: (u32, Vec<u32>),
    ran: usize,
}

impl Culler for Alternating {
    fn name(&self) -> &str {
        "roc/hiz"
    }
    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        let lists = Rc::new(VisibleLists::new(setup.gpu, setup.draws)?);
        for walk in &mut self.walks {
            walk.share_visible_lists(&lists);
            walk.prepare(setup)?;
        }
        self.lists = Some(lists);
        Ok(())
    }
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        if input.frame == self.upload.0 {
            let gpu = ctx.on_gpu().unwrap().gpu();
            self.lists.as_ref().unwrap().upload(gpu, &self.upload.1);
        }
        self.ran = input.frame as usize % 2;
        self.walks[self.ran].frame(ctx, input)
    }
    fn audit(&mut self, gpu: &GpuContext, input: &FrameInput, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        self.walks[self.ran].audit(gpu, input, drawn)
    }
}

#[test]
fn walks_sharing_visible_lists_start_where_the_last_one_ended_and_from_what_is_uploaded() {
    let scene = boxes(&[
        (DVec3::new(-3.0, -3.0, -10.1), DVec3::new(3.0, 3.0, -9.9)), // 0 wall
        (DVec3::new(-0.5, -0.5, -20.5), DVec3::new(0.5, 0.5, -19.5)), // 1 hidden by it
        (DVec3::new(10.0, -0.5, -20.5), DVec3::new(11.0, 0.5, -19.5)), // 2 beside it
    ]);
    let path = held(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 90.0, 5);
    let hierarchy = Hierarchy::build(&scene.objects, &common::one_object_per_leaf());
    for gpu in common::gpus() {
        let alternating = Alternating {
            walks: [mode(&scene, "roc", "roc", &[]), mode(&scene, "hiz", "hiz", &[])],
            lists: None,
            upload: (3, vec![2]),
            ran: 0,
        };
        let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(alternating)];
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, RES).rows;
        assert_exact(&rows, &gpu);
        let early_late: Vec<(u64, u64)> = rows
            .iter()
            .map(|r| (r.traversal.drawn_early, r.traversal.drawn_late))
            .collect();
        // roc finds all three visible at frame 0; hiz draws them first at
        // frame 1 and hides the box behind the wall; roc draws the two
        // left at frame 2. At frame 3 the lists hold the box beside the
        // wall alone: nothing drawn first hides the wall or the box behind
        // it, so both are drawn late, and at frame 4 roc draws all three.
        assert_eq!(
            early_late,
            [(0, 3), (3, 0), (2, 0), (1, 2), (3, 0)],
            "on {}",
            gpu.adapter
        );
    }
}

#[test]
fn gpu_walks_are_exact_on_the_moving_city_within_their_round_trips() {
    let (scene, hierarchy, path) = common::builtin("city:blocks=2,movers=40", 12);
    for gpu in common::gpus() {
        let mut cullers = vec![
            mode(&scene, "vfc", "vfc", &[]),
            mode(&scene, "roc", "roc", &[]),
            mode(&scene, "ioc", "ioc", &[]),
            mode(&scene, "hiz", "hiz", &[]),
            mode(&scene, "hiz[nodes]", "hiz", &["hiz.boxes=nodes"]),
            // Without the pixel test its boxes are made on the GPU.
            mode(&scene, "hiz[pixels=0]", "hiz", &["hiz.pixels=0"]),
        ];
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL).rows;
        assert_exact(&rows, &gpu);
        let sum =
            |mode: &str, f: fn(&FrameStats) -> u64| -> u64 { rows.iter().filter(|r| r.mode == mode).map(f).sum() };
        // From frame 2 on, last frame's visible objects are real occluders.
        let later = |mode: &str| -> u64 {
            let rows = rows.iter().filter(|r| r.mode == mode && r.frame >= 2);
            rows.map(|r| r.triangles_drawn).sum()
        };
        for m in ["roc", "ioc", "hiz", "hiz[nodes]"] {
            assert!(
                rows.iter()
                    .filter(|r| r.mode == m)
                    .all(|r| r.query_batches == round_trips(&gpu)),
                "{m} on {}",
                gpu.adapter
            );
            let (drawn, vfc) = (later(m), later("vfc"));
            // hiz tests a box's screen rectangle against the farthest depth
            // of a few pyramid texels, far coarser than drawing the box at
            // this small size (hiz culled 8 % of vfc's triangles here).
            let share = if m.starts_with("hiz") { 0.97 } else { 2.0 / 3.0 };
            assert!(
                (drawn as f64) < vfc as f64 * share,
                "{m} culls: {drawn} of vfc's {vfc} triangles"
            );
            assert!(sum(m, |r| r.traversal.nodes_culled_occlusion) > 0, "{m} hides nodes");
        }
        let boxes = 12 * scene.objects.len() as u64;
        assert_eq!(
            sum("roc", |r| r.traversal.nodes_visited),
            boxes,
            "roc visits every object's box"
        );
        let (tested, outside) = (
            sum("roc", |r| r.queries),
            sum("roc", |r| r.traversal.nodes_culled_frustum),
        );
        assert!(
            outside > 0 && tested + outside <= boxes,
            "{tested} tested, {outside} outside"
        );
        assert!(
            sum("ioc", |r| r.queries) < sum("roc", |r| r.queries),
            "ioc tests fewer boxes than roc"
        );
        assert!(
            rows.iter()
                .filter(|r| r.mode != "vfc")
                .all(|r| r.query_gpu_ms.is_some() == gpu.timestamps)
        );
        // Only hiz builds a pyramid, and its time is part of the test's.
        assert!(rows.iter().all(|r| {
            let timed = gpu.timestamps && r.mode.starts_with("hiz");
            r.pyramid_gpu_ms.is_some() == timed && r.pyramid_gpu_ms <= r.query_gpu_ms
        }));
        // The first frame has no list from a previous one to draw early.
        for r in rows.iter().filter(|r| r.mode != "vfc" && r.frame == 0) {
            assert_eq!(r.traversal.drawn_early, 0, "{}", r.mode);
        }
    }
}

#[test]
fn no_gpu_walk_draws_an_object_the_frustum_leaves_out() {
    // Sixteen posts on a ring round the eye, which turns a quarter a frame:
    // what one frame saw has left the frustum in the next, so last frame's
    // visible list must not be drawn whole; and a walk over the root alone
    // finds it visible and must not draw all that lies under it.
    let posts: Vec<(DVec3, DVec3)> = (0..16)
        .map(|k| {
            let a = f64::from(k) * std::f64::consts::TAU / 16.0;
            let centre = DVec3::new(20.0 * a.cos(), 0.0, 20.0 * a.sin());
            (centre - DVec3::ONE, centre + DVec3::ONE)
        })
        .collect();
    let scene = boxes(&posts);
    let directions: Vec<DVec3> = (0..8)
        .map(|f| {
            let a = f64::from(f) * std::f64::consts::FRAC_PI_2 + 0.3;
            DVec3::new(a.cos(), 0.0, a.sin())
        })
        .collect();
    let path = common::turning(DVec3::ZERO, &directions, 60.0);
    let hierarchy = common::hierarchy(&scene);
    for gpu in common::gpus() {
        let mut cullers = vec![
            mode(&scene, "vfc", "vfc", &[]),
            mode(&scene, "roc", "roc", &[]),
            mode(&scene, "ioc", "ioc", &[]),
            mode(&scene, "ioc[root]", "ioc", &["ioc.start=0", "ioc.bottom=0"]),
            mode(&scene, "hiz", "hiz", &[]),
            mode(
                &scene,
                "hiz[root]",
                "hiz",
                &["hiz.boxes=nodes", "hiz.start=0", "hiz.bottom=0"],
            ),
        ];
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, RES).rows;
        assert_exact(&rows, &gpu);
        let triangles = |mode: &str, frame: u32| -> u64 {
            rows.iter()
                .find(|r| r.mode == mode && r.frame == frame)
                .map(|r| r.triangles_drawn)
                .unwrap_or_else(|| panic!("{mode} ran frame {frame}"))
        };
        for frame in 0..path.frames {
            let vfc = triangles("vfc", frame);
            assert!(
                vfc > 0 && vfc < 16 * 12,
                "frame {frame}: vfc draws some posts, not all ({vfc})"
            );
            for m in ["roc", "ioc", "ioc[root]", "hiz", "hiz[root]"] {
                let drawn = triangles(m, frame);
                assert!(
                    drawn <= vfc,
                    "{m} frame {frame} on {}: {drawn} triangles, vfc {vfc}",
                    gpu.adapter
                );
            }
        }
    }
}

#[test]
fn adapters_without_gpu_culling_skip_roc_and_ioc_with_a_reason() {
    let mut gpu = common::gpus().remove(0);
    assert!(gpu.gpu_driven, "Mesa's llvmpipe culls on the GPU: {}", gpu.adapter);
    assert_eq!(ModeId::Roc.info().unsupported_on(&gpu), None);
    gpu.gpu_driven = false;
    for m in [ModeId::Roc, ModeId::Ioc] {
        let reason = m.info().unsupported_on(&gpu).unwrap_or_default();
        assert!(reason.contains("cannot cull on the GPU"), "{m}: {reason:?}");
    }
    assert_eq!(ModeId::Omq.info().unsupported_on(&gpu), None, "other modes still run");
}
