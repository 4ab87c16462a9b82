//! Occlusion queries and the query modes (sq, omq), on every backend
//! present: the batch primitive against known geometry, then the modes on
//! hand-made scenes and on the city, against the direct-rendering reference.

mod common;

use std::cell::RefCell;

use common::{boxes, run_modes, still};
use glam::DVec3;
use occlu::camera::generate::{PathKind, generate};
use occlu::camera::path::CameraPath;
use occlu::cull::{Culler, FrameInput, ModeParams, TraversalStats, create};
use occlu::gpu::{BoxVisibility, FrameCtx, QUERIES_PER_SET, Resolution};
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::measure::FrameStats;
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

const RES: Resolution = Resolution { width: 128, height: 96 };

/// A wall 10 units ahead: x, y in [-5, 5], front face at z = -10.
fn wall() -> (DVec3, DVec3) {
    (DVec3::new(-5.0, -5.0, -10.1), DVec3::new(5.0, 5.0, -10.0))
}

fn cube(centre: DVec3, half: f64) -> occlu::bounds::Aabb {
    occlu::bounds::Aabb::new(centre - DVec3::splat(half), centre + DVec3::splat(half))
}

/// Draws the wall, then tests each batch of boxes in turn, recording results.
struct WallThenBatches<'a> {
    batches: Vec<Vec<occlu::bounds::Aabb>>,
    results: &'a RefCell<Vec<Vec<BoxVisibility>>>,
}

impl Culler for WallThenBatches<'_> {
    fn name(&self) -> &str {
        "wall-then-batches"
    }
    fn frame(&mut self, ctx: &mut FrameCtx, _: &FrameInput) -> TraversalStats {
        ctx.draw(&[0]);
        for batch in &self.batches {
            let mut out = Vec::new();
            ctx.test_boxes(batch, &mut out);
            self.results.borrow_mut().push(out);
        }
        TraversalStats::default()
    }
}

#[test]
fn queries_see_what_is_drawn() {
    use BoxVisibility::{Samples, Unqueried};
    let scene = boxes(&[wall()]);
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 60.0);
    let z = |lo: f64, hi: f64| occlu::bounds::Aabb::new(DVec3::new(-1.0, -1.0, lo), DVec3::new(1.0, 1.0, hi));
    let singles = vec![
        z(-15.0, -13.0),                                                                     // behind the wall
        z(-8.0, -6.0),                                                                       // in front
        occlu::bounds::Aabb::new(DVec3::new(4.0, -1.0, -13.0), DVec3::new(7.0, 1.0, -11.0)), // sticks out beside it
        z(-12.0, -10.0),                                                                     // face on the wall's face
        z(-10.2, -10.15),       // just behind its back face
        z(-0.5, -0.05),         // crosses the near plane
        cube(DVec3::ZERO, 1.0), // holds the eye
    ];
    // More boxes than one query set holds: even ones hidden behind the wall,
    // odd ones in front of it.
    let big: Vec<_> = (0..QUERIES_PER_SET as usize + 904)
        .map(|i| {
            let (x, y) = ((i % 71) as f64 / 71.0 * 8.0 - 4.0, (i / 71) as f64 / 71.0 * 8.0 - 4.0);
            // About 2 pixels across where visible, all inside the view.
            cube(DVec3::new(x, y, if i % 2 == 0 { -13.0 } else { -8.0 }), 0.1)
        })
        .collect();
    for gpu in common::gpus() {
        let results = RefCell::new(Vec::new());
        let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(WallThenBatches {
            batches: vec![singles.clone(), big.clone()],
            results: &results,
        })];
        let out = run_modes(&gpu, &scene, &path, &mut cullers, RES);
        let r = results.borrow();
        let seen: Vec<bool> = r[0].iter().map(|v| v.is_visible()).collect();
        assert_eq!(
            seen,
            [false, true, true, true, false, true, true],
            "{}: {:?}",
            gpu.adapter,
            r[0]
        );
        assert!(matches!(r[0][0], Samples(0)) && matches!(r[0][1], Samples(n) if n > 0));
        assert_eq!((r[0][5], r[0][6]), (Unqueried, Unqueried));
        for (i, v) in r[1].iter().enumerate() {
            assert_eq!(
                v.is_visible(),
                i % 2 == 1,
                "{}: box {i} of the big batch: {v:?}",
                gpu.adapter
            );
        }
        let row = &out.rows[0];
        assert_eq!(row.queries, 5 + big.len() as u64, "unqueried boxes cost no query");
        assert_eq!(row.query_batches, 2, "one round trip per batch, however large");
        assert_eq!(row.error_pixels, Some(0));
        if gpu.timestamps {
            let (query, frame) = (row.query_gpu_ms.unwrap(), row.gpu_ms.unwrap());
            assert!(
                query > 0.0 && query <= frame,
                "query passes {query} ms within the frame's {frame} ms"
            );
        }
    }
}

/// Runs `modes` on `scene` with one object per leaf, so culling decisions
/// are visible per object.
fn run(scene: &Scene, path: &CameraPath, modes: &[&str], res: Resolution) -> Vec<Vec<FrameStats>> {
    let hierarchy = Hierarchy::build(
        &scene.objects,
        &HierarchyParams {
            max_leaf_objects: 1,
            traversal_cost: 0.0,
            ..Default::default()
        },
    );
    common::gpus()
        .iter()
        .map(|gpu| {
            let mut cullers: Vec<Box<dyn Culler>> = modes
                .iter()
                .map(|m| create(m, scene, &hierarchy, &ModeParams::default()).unwrap())
                .collect();
            run_modes(gpu, scene, path, &mut cullers, res).rows
        })
        .collect()
}

#[test]
fn query_modes_cull_what_a_wall_hides_and_draw_what_it_does_not() {
    let scene = boxes(&[
        wall(),
        (DVec3::new(-1.0, -1.0, -15.0), DVec3::new(1.0, 1.0, -13.0)), // hidden
        (DVec3::new(4.0, -1.0, -13.0), DVec3::new(7.0, 1.0, -11.0)),  // sticks out
        (DVec3::new(-1.0, 2.0, -8.0), DVec3::new(1.0, 3.0, -6.0)),    // in front
    ]);
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 60.0);
    for rows in run(&scene, &path, &["dr", "sq", "omq"], RES) {
        for r in &rows {
            assert_eq!((r.error_pixels, r.missed_objects), (Some(0), Some(0)), "{}", r.mode);
        }
        let (sq, omq) = (&rows[1], &rows[2]);
        assert_eq!(sq.objects_drawn, 3, "sq draws all but the hidden box");
        assert_eq!(omq.objects_drawn, 3, "omq draws all but the hidden box");
        assert!(
            sq.queries > 0 && sq.query_batches == sq.queries,
            "stop-and-wait: one round trip per query"
        );
        assert!(omq.nodes_culled_occlusion >= 1 && sq.nodes_culled_occlusion >= 1);
        assert!(omq.queries_skipped > 0, "the nearest boxes need no query");
    }
}

#[test]
fn camera_inside_a_room_culls_what_is_outside() {
    // Six walls around the eye, a box inside the room, one outside.
    let (r, t) = (6.0, 0.1);
    let slab = |axis: usize, side: f64| {
        let (mut lo, mut hi) = (DVec3::splat(-r - t), DVec3::splat(r + t));
        if side < 0.0 {
            hi[axis] = -r;
        } else {
            lo[axis] = r;
        }
        (lo, hi)
    };
    let mut list: Vec<(DVec3, DVec3)> = (0..3).flat_map(|a| [slab(a, -1.0), slab(a, 1.0)]).collect();
    list.push((DVec3::new(-1.0, -1.0, -4.0), DVec3::new(1.0, 1.0, -3.0))); // inside
    list.push((DVec3::new(-1.0, -1.0, -12.0), DVec3::new(1.0, 1.0, -10.0))); // outside
    let scene = boxes(&list);
    let path = still(DVec3::new(0.5, 0.2, 2.0), DVec3::new(0.5, 0.2, -10.0), 90.0);
    for rows in run(&scene, &path, &["dr", "sq", "omq"], RES) {
        for r in &rows[1..] {
            assert_eq!((r.error_pixels, r.missed_objects), (Some(0), Some(0)), "{}", r.mode);
            assert!(r.objects_drawn < 8, "{} drew the box outside the room", r.mode);
        }
    }
}

#[test]
fn query_modes_are_exact_on_the_city_and_omq_saves_round_trips() {
    let scene = load(&SceneSpec::Builtin("city:blocks=2".into()), &LoadOptions::default()).unwrap();
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = CameraPath::from_file(&generate(PathKind::Walk, &scene, 8), "walk").unwrap();
    let modes = ["vfc", "sq", "omq", "oracle"];
    for gpu in common::gpus() {
        let mut cullers: Vec<Box<dyn Culler>> = modes
            .iter()
            .map(|m| create(m, &scene, &hierarchy, &ModeParams::default()).unwrap())
            .collect();
        let rows = run_modes(
            &gpu,
            &scene,
            &path,
            &mut cullers,
            Resolution {
                width: 160,
                height: 120,
            },
        )
        .rows;
        let sum =
            |mode: &str, f: fn(&FrameStats) -> u64| -> u64 { rows.iter().filter(|r| r.mode == mode).map(f).sum() };
        for r in &rows {
            assert_eq!(
                r.error_pixels,
                Some(0),
                "{} frame {} on {}",
                r.mode,
                r.frame,
                gpu.adapter
            );
            assert_eq!(
                r.missed_objects,
                Some(0),
                "{} frame {} on {}",
                r.mode,
                r.frame,
                gpu.adapter
            );
        }
        let (sq_trips, omq_trips) = (sum("sq", |r| r.query_batches), sum("omq", |r| r.query_batches));
        assert!(
            omq_trips * 5 <= sq_trips,
            "omq {omq_trips} vs sq {sq_trips} round trips"
        );
        let vfc = sum("vfc", |r| r.triangles_drawn);
        for mode in ["sq", "omq"] {
            let t = sum(mode, |r| r.triangles_drawn);
            assert!(t * 2 < vfc, "{mode} draws {t} triangles, vfc {vfc}");
        }
    }
}
