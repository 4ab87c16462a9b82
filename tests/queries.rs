//! Occlusion queries and the query modes (sq, omq), on every backend
//! present: the batch primitive against known geometry, then the modes on
//! hand-made scenes and on the city, against the direct-rendering reference.

mod common;

use std::cell::RefCell;

use common::{boxes, run_modes, still};
use glam::DVec3;
use occlu::camera::path::CameraPath;
use occlu::cull::{Culler, FrameInput, ModeParams, TraversalStats, create};
use occlu::gpu::{BoxTest, BoxVisibility, Frame, QUERIES_PER_SET, Resolution};
use occlu::hierarchy::Hierarchy;
use occlu::measure::FrameStats;
use occlu::scene::Scene;

const RES: Resolution = Resolution { width: 128, height: 96 };

/// A wall 10 units ahead: x, y in [-5, 5], front face at z = -10.
fn wall() -> (DVec3, DVec3) {
    (DVec3::new(-5.0, -5.0, -10.1), DVec3::new(5.0, 5.0, -10.0))
}

fn cube(centre: DVec3, half: f64) -> occlu::bounds::Aabb {
    occlu::bounds::Aabb::new(centre - DVec3::splat(half), centre + DVec3::splat(half))
}

/// Draws the wall, then tests each batch with its kind of test, recording
/// the results in order.
struct WallThenTests<'a> {
    tests: Vec<(Vec<occlu::bounds::Aabb>, BoxTest)>,
    results: &'a RefCell<Vec<Vec<BoxVisibility>>>,
}

impl Culler for WallThenTests<'_> {
    fn name(&self) -> &str {
        "wall-then-tests"
    }
    fn frame(&mut self, ctx: &mut dyn Frame, _: &FrameInput) -> TraversalStats {
        ctx.draw(&[0]);
        for (batch, kind) in &self.tests {
            let mut out = Vec::new();
            ctx.test_boxes(batch, *kind, &mut out);
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
        let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(WallThenTests {
            tests: vec![(singles.clone(), BoxTest::Occlusion), (big.clone(), BoxTest::Occlusion)],
            results: &results,
        })];
        let out = run_modes(&gpu, &scene, &common::hierarchy(&scene), &path, &mut cullers, RES);
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
    let hierarchy = Hierarchy::build(&scene.objects, &common::one_object_per_leaf());
    common::gpus()
        .iter()
        .map(|gpu| {
            let mut cullers: Vec<Box<dyn Culler>> = modes
                .iter()
                .map(|m| create(m, scene, &ModeParams::default()).unwrap())
                .collect();
            run_modes(gpu, scene, &hierarchy, path, &mut cullers, res).rows
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
        assert!(omq.traversal.nodes_culled_occlusion >= 1 && sq.traversal.nodes_culled_occlusion >= 1);
        assert!(omq.traversal.queries_skipped > 0, "the nearest boxes need no query");
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
    let (scene, hierarchy, path) = common::small_city(8);
    let modes = ["vfc", "sq", "omq", "oracle"];
    for gpu in common::gpus() {
        let mut cullers: Vec<Box<dyn Culler>> = modes
            .iter()
            .map(|m| create(m, &scene, &ModeParams::default()).unwrap())
            .collect();
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL).rows;
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

/// Pixel centres whose ray hits `target` no farther than `wall` (or misses
/// the wall): the footprint the depth test lets through, by ray casting.
fn cpu_footprint(target: (DVec3, DVec3), wall: (DVec3, DVec3), res: Resolution, fov_y: f64) -> u64 {
    let hit = |(min, max): (DVec3, DVec3), dir: DVec3| -> Option<f64> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let (ta, tb) = (min[a] / dir[a], max[a] / dir[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        (t0 <= t1).then_some(t0)
    };
    let t = (fov_y.to_radians() / 2.0).tan();
    let aspect = f64::from(res.width) / f64::from(res.height);
    let mut n = 0;
    for py in 0..res.height {
        for px in 0..res.width {
            let sx = (f64::from(px) + 0.5) / f64::from(res.width) * 2.0 - 1.0;
            let sy = 1.0 - (f64::from(py) + 0.5) / f64::from(res.height) * 2.0;
            let dir = DVec3::new(sx * t * aspect, sy * t, -1.0);
            if let Some(tb) = hit(target, dir)
                && hit(wall, dir).is_none_or(|tw| tb <= tw)
            {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn pixel_counts_match_the_ray_cast_footprint_and_query_counts() {
    let res = common::SMALL;
    let wall = (DVec3::new(-5.0, -5.0, -10.1), DVec3::new(0.3, 5.0, -10.0));
    let half_hidden = (DVec3::new(-1.0, -1.0, -14.0), DVec3::new(1.5, 1.0, -12.0));
    let in_front = (DVec3::new(-0.8, 1.2, -7.0), DVec3::new(0.4, 2.0, -6.0));
    let scene = boxes(&[wall]);
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 60.0);
    let to_aabb = |(a, b): (DVec3, DVec3)| occlu::bounds::Aabb::new(a, b);
    let expected = [
        cpu_footprint(half_hidden, wall, res, 60.0),
        cpu_footprint(in_front, wall, res, 60.0),
    ];
    assert!(expected[0] > 150 && expected[1] > 150, "both boxes show: {expected:?}");
    for gpu in common::gpus() {
        assert!(gpu.pixel_counts, "{} cannot count pixels", gpu.adapter);
        let results = RefCell::new(Vec::new());
        let batch = vec![to_aabb(half_hidden), to_aabb(in_front)];
        let kinds = [
            BoxTest::PixelCount { sampling: 1 },
            BoxTest::Occlusion,
            BoxTest::PixelCount { sampling: 2 },
            BoxTest::PixelCount { sampling: 4 },
        ];
        let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(WallThenTests {
            tests: kinds.iter().map(|&k| (batch.clone(), k)).collect(),
            results: &results,
        })];
        run_modes(&gpu, &scene, &common::hierarchy(&scene), &path, &mut cullers, res);
        let r = results.borrow();
        let samples = |v: &BoxVisibility| match v {
            BoxVisibility::Samples(n) => *n,
            BoxVisibility::Unqueried => panic!("not tested"),
        };
        let counts: Vec<u64> = r[0].iter().map(samples).collect();
        for (got, want) in counts.iter().zip(expected) {
            // Boxes are grown by 1e-4 of their distance: at most a pixel or
            // two along the silhouette may differ from the exact footprint.
            assert!(
                got.abs_diff(want) <= 2 + want / 100,
                "{}: counted {got}, ray casting {want}",
                gpu.adapter
            );
        }
        if gpu.adapter.backend == "vulkan" {
            let queried: Vec<u64> = r[1].iter().map(samples).collect();
            assert_eq!(queried, counts, "Vulkan query sample counts equal the pixel counts");
        }
        for (k, sampled) in [(2u64, &r[2]), (4, &r[3])] {
            for (s, full) in sampled.iter().map(samples).zip(&counts) {
                let estimate = s * k;
                assert!(
                    estimate.abs_diff(*full) <= full / 4 + 2 * k,
                    "sampling {k}: {s}·{k} vs {full}"
                );
            }
        }
    }
}

/// Runs modes labelled like a sweep (`ac[threshold=1e9]`) on the small city.
fn city_runs(runs: &[(&str, &[&str])], frames: u32) -> Vec<Vec<FrameStats>> {
    let (scene, hierarchy, path) = common::small_city(frames);
    common::gpus()
        .iter()
        .map(|gpu| {
            let mut cullers: Vec<Box<dyn Culler>> = runs
                .iter()
                .map(|&(label, params)| {
                    let mode = label.split('[').next().unwrap();
                    let items: Vec<String> = params.iter().map(|p| p.to_string()).collect();
                    let params = ModeParams::parse(&items, &[mode.parse().unwrap()]).unwrap();
                    Box::new(occlu::cull::Labeled {
                        label: label.to_string(),
                        inner: create(mode, &scene, &params).unwrap(),
                    }) as Box<dyn Culler>
                })
                .collect();
            run_modes(gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL).rows
        })
        .collect()
}

#[test]
fn adaptive_culling_is_exact_at_threshold_zero_and_trades_error_above_it() {
    let runs: &[(&str, &[&str])] = &[
        ("omq", &[]),
        ("vfc", &[]),
        ("ac[exact]", &["ac.threshold=0", "ac.sampling=1", "ac.f_graphics=inf"]),
        ("ac[default]", &[]),
        ("ac[high]", &["ac.threshold=1e9", "ac.f_graphics=inf"]),
        ("ac[no budget left]", &["ac.threshold=0", "ac.f_graphics=0"]),
        ("ac[sampled]", &["ac.sampling=4", "ac.f_graphics=inf"]),
    ];
    for rows in city_runs(runs, 6) {
        let of = |label: &str| -> Vec<&FrameStats> { rows.iter().filter(|r| r.mode == label).collect() };
        let sum = |label: &str, f: fn(&FrameStats) -> u64| of(label).into_iter().map(f).sum::<u64>();
        for label in ["ac[exact]", "ac[no budget left]"] {
            assert_eq!(sum(label, |r| r.error_pixels.unwrap()), 0, "{label} is conservative");
            assert_eq!(sum(label, |r| r.missed_objects.unwrap()), 0, "{label} is conservative");
        }
        assert!(
            sum("ac[exact]", |r| r.queries) > 0,
            "pixel counts are tests, one round trip each"
        );
        assert_eq!(sum("ac[exact]", |r| r.queries), sum("ac[exact]", |r| r.query_batches));
        // A threshold no footprint reaches: error, and less drawn than omq.
        assert!(sum("ac[high]", |r| r.error_pixels.unwrap()) > 0);
        assert!(sum("ac[high]", |r| r.traversal.nodes_culled_adaptive) > 0);
        assert!(sum("ac[high]", |r| r.triangles_drawn) < sum("omq", |r| r.triangles_drawn));
        // No budget at all: after the first frame (which has no previous
        // render time), everything is only frustum-culled, as vfc.
        for (a, v) in of("ac[no budget left]").into_iter().zip(of("vfc")).skip(1) {
            assert_eq!(a.triangles_drawn, v.triangles_drawn, "frame {}", a.frame);
            assert!(a.traversal.nodes_past_budget > 0 && a.queries == 0);
        }
        // Sampled counts: not conservative, measured (finite, recorded).
        assert!(of("ac[sampled]").iter().all(|r| r.error_pixels.is_some()));
        assert!(of("ac[default]").iter().all(|r| r.error_pixels.is_some()));
    }
}

/// chc with `items` as its parameters.
fn chc(scene: &Scene, items: &[&str]) -> Box<dyn Culler> {
    let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
    create(
        "chc",
        scene,
        &ModeParams::parse(&items, &[occlu::cull::ModeId::Chc]).unwrap(),
    )
    .unwrap()
}

#[test]
fn a_query_behind_a_pending_nearer_one_waits_for_it() {
    // A wall, a box hidden right behind it, and a box off to the side. In
    // the first frame nothing is known visible, so all are queried; the
    // hidden box's rectangle overlaps the wall's, so its query must wait
    // until the wall is drawn (001 §3.5). Sent together, it would be found
    // visible (the wall not drawn yet) and drawn.
    let scene = boxes(&[
        (DVec3::new(-3.0, -3.0, -10.1), DVec3::new(3.0, 3.0, -9.9)),
        (DVec3::new(-0.5, -0.5, -20.5), DVec3::new(0.5, 0.5, -19.5)),
        (DVec3::new(10.0, -0.5, -20.5), DVec3::new(11.0, 0.5, -19.5)),
    ]);
    let path = still(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 90.0);
    for gpu in common::gpus() {
        // One object per leaf, boxes tight from the first frame.
        let mut cullers = vec![chc(&scene, &["chc.o_merge=0", "chc.tight_after=0"])];
        let out = run_modes(&gpu, &scene, &common::hierarchy(&scene), &path, &mut cullers, RES);
        let row = &out.rows[0];
        assert_eq!(
            (row.error_pixels, row.missed_objects),
            (Some(0), Some(0)),
            "{}",
            gpu.adapter
        );
        assert_eq!(row.objects_drawn, 2, "the wall and the side box: {row:?}");
        assert!(row.traversal.queries_delayed >= 1, "{row:?}");
        assert!(row.traversal.nodes_culled_occlusion >= 1, "{row:?}");
    }
}

#[test]
fn chc_is_exact_with_fewer_round_trips_than_sq_on_the_moving_city() {
    let (scene, hierarchy, path) = common::builtin("city:blocks=2,movers=40", 12);
    for gpu in common::gpus() {
        let mut cullers: Vec<Box<dyn Culler>> =
            vec![create("sq", &scene, &ModeParams::default()).unwrap(), chc(&scene, &[])];
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL).rows;
        let sum =
            |mode: &str, f: fn(&FrameStats) -> u64| -> u64 { rows.iter().filter(|r| r.mode == mode).map(f).sum() };
        assert_eq!(sum("chc", |r| r.error_pixels.unwrap()), 0, "{}", gpu.adapter);
        assert_eq!(sum("chc", |r| r.missed_objects.unwrap()), 0, "{}", gpu.adapter);
        let (sq, chc) = (sum("sq", |r| r.query_batches), sum("chc", |r| r.query_batches));
        assert!(chc * 4 < sq, "chc {chc} vs sq {sq} round trips");
        assert!(
            sum("chc", |r| r.traversal.queries_skipped) > 0,
            "visible nodes are opened unqueried"
        );
        let moving = rows.iter().filter(|r| r.mode == "chc" && r.frame > 0);
        assert!(
            moving.clone().all(|r| r.maintenance_ms > 0.0),
            "the tree follows the cars"
        );
        let drawn = sum("chc", |r| r.triangles_drawn);
        let all = scene.triangles() * 12;
        assert!(drawn * 2 < all, "chc culls: {drawn} of {all} triangles");
    }
}
