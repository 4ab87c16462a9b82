//! Rendering and the error measure, on every backend present, checked
//! against computations that share no code with the renderer.

mod common;

use std::cell::RefCell;

use common::{DropOneVisible, boxes, run_modes, still};
use glam::DVec3;
use occlu::bench::BenchError;
use occlu::cull::{Culler, FrameInput, ModeParams, TraversalStats, create};
use occlu::gpu::{BackendChoice, Frame, GpuContext, GpuError, Resolution};
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::object_set::ObjectSet;

/// Draws nothing: every visible pixel is an error.
struct DrawNothing;
impl Culler for DrawNothing {
    fn name(&self) -> &str {
        "nothing"
    }
    fn frame(&mut self, _: &mut dyn Frame, _: &FrameInput) -> TraversalStats {
        TraversalStats::default()
    }
}

/// Records the reference visible set it is given, draws it.
struct Recorder<'a>(&'a RefCell<Vec<ObjectSet>>);
impl Culler for Recorder<'_> {
    fn name(&self) -> &str {
        "recorder"
    }
    fn needs_reference(&self) -> bool {
        true
    }
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let visible = input.reference_visible.unwrap().clone();
        ctx.draw(&visible.iter().collect::<Vec<_>>());
        self.0.borrow_mut().push(visible);
        TraversalStats::default()
    }
}

#[test]
fn missing_quad_costs_exactly_its_rasterised_pixels() {
    // A 2.06 × 1.54 quad (a thin box) 10 units ahead, 90° fov at 100×100:
    // one unit at distance 10 is 5 pixels. Edges sit between pixel centres.
    let (w, h) = (100u32, 100u32);
    let scene = boxes(&[(DVec3::new(-1.03, -0.77, -10.0), DVec3::new(1.03, 0.77, -9.999))]);
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 90.0);
    // Independent count: pixel centres whose ray hits the quad's front face.
    let mut expected = 0;
    for py in 0..h {
        for px in 0..w {
            let ndc_x = (f64::from(px) + 0.5) / f64::from(w) * 2.0 - 1.0;
            let ndc_y = 1.0 - (f64::from(py) + 0.5) / f64::from(h) * 2.0;
            let (x, y) = (ndc_x * 9.999, ndc_y * 9.999); // tan(45°) = 1
            if x.abs() < 1.03 && y.abs() < 0.77 {
                expected += 1;
            }
        }
    }
    assert_eq!(expected, 10 * 8);
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    for gpu in common::gpus() {
        let mut cullers: Vec<Box<dyn Culler>> = vec![
            Box::new(DrawNothing),
            create("dr", &scene, &ModeParams::default()).unwrap(),
        ];
        let out = run_modes(
            &gpu,
            &scene,
            &hierarchy,
            &path,
            &mut cullers,
            Resolution { width: w, height: h },
        );
        let (nothing, dr) = (&out.rows[0], &out.rows[1]);
        assert_eq!(nothing.error_pixels, Some(expected), "{}", gpu.adapter);
        assert_eq!(nothing.missed_objects, Some(1));
        assert_eq!(nothing.visible_objects, Some(1));
        assert_eq!(dr.error_pixels, Some(0), "{}", gpu.adapter);
        assert_eq!((dr.objects_drawn, dr.triangles_drawn), (1, 12));
    }
}

/// Nearest box hit along the ray through (sx, sy) of the image, by slab
/// tests in f64: no triangles, no GPU, no shared code.
fn ray_cast(list: &[(DVec3, DVec3)], eye: DVec3, fov_y: f64, aspect: f64, sx: f64, sy: f64) -> Option<usize> {
    let t = (fov_y / 2.0).tan();
    let dir = DVec3::new((sx * 2.0 - 1.0) * t * aspect, (1.0 - sy * 2.0) * t, -1.0);
    let mut best: Option<(f64, usize)> = None;
    for (k, &(min, max)) in list.iter().enumerate() {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let (o, d) = (eye[a], dir[a]);
            let (ta, tb) = ((min[a] - o) / d, (max[a] - o) / d);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        if t0 <= t1 && best.is_none_or(|(bt, _)| t0 < bt) {
            best = Some((t0, k));
        }
    }
    best.map(|(_, k)| k)
}

#[test]
fn reference_visible_set_matches_cpu_ray_casting() {
    // 60 seeded boxes in front of the camera, many hiding others.
    let mut rng = occlu::rng::Rng::new(7);
    let mut rand = || rng.range(0.0, 1.0);
    let list: Vec<(DVec3, DVec3)> = (0..60)
        .map(|_| {
            let c = DVec3::new(rand() * 16.0 - 8.0, rand() * 12.0 - 6.0, -5.0 - rand() * 25.0);
            let e = DVec3::new(0.3 + rand() * 2.0, 0.3 + rand() * 2.0, 0.3 + rand() * 2.0);
            (c - e, c + e)
        })
        .collect();
    let scene = boxes(&list);
    let (w, h, fov) = (160u32, 120u32, 70f64);
    let path = still(DVec3::ZERO, DVec3::NEG_Z, fov);
    let aspect = f64::from(w) / f64::from(h);
    // Per object: pixels whose centre it owns, and whether it owns any of a
    // 3×3 grid of samples inside some pixel (edges may go either way).
    let mut centre_pixels = vec![0usize; list.len()];
    let mut touches = vec![false; list.len()];
    for py in 0..h {
        for px in 0..w {
            for (i, j) in (0..9).map(|s| (s % 3, s / 3)) {
                let sx = (f64::from(px) + 0.05 + 0.45 * f64::from(i)) / f64::from(w);
                let sy = (f64::from(py) + 0.05 + 0.45 * f64::from(j)) / f64::from(h);
                if let Some(k) = ray_cast(&list, DVec3::ZERO, fov.to_radians(), aspect, sx, sy) {
                    touches[k] = true;
                    if (i, j) == (1, 1) {
                        centre_pixels[k] += 1;
                    }
                }
            }
        }
    }
    let surely: Vec<usize> = (0..list.len()).filter(|&k| centre_pixels[k] >= 4).collect();
    let hidden = touches.iter().filter(|&&t| !t).count();
    assert!(
        surely.len() >= 10 && hidden >= 5,
        "a test with both visible and hidden boxes: {} / {hidden}",
        surely.len()
    );
    for gpu in common::gpus() {
        let seen = RefCell::new(Vec::new());
        let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(Recorder(&seen))];
        let out = run_modes(
            &gpu,
            &scene,
            &common::hierarchy(&scene),
            &path,
            &mut cullers,
            Resolution { width: w, height: h },
        );
        assert_eq!(
            out.rows[0].error_pixels,
            Some(0),
            "drawing the visible set changes no pixel"
        );
        let visible = &seen.borrow()[0];
        for &k in &surely {
            assert!(
                visible.contains(k as u32),
                "{}: box {k} owns {} pixels but is not visible",
                gpu.adapter,
                centre_pixels[k]
            );
        }
        for k in visible.iter() {
            assert!(
                touches[k as usize],
                "{}: box {k} is visible on the GPU but hidden by ray casting",
                gpu.adapter
            );
        }
    }
}

#[test]
fn exact_modes_show_no_error_and_a_wrong_culler_is_caught() {
    let (scene, hierarchy, path) = common::small_city(6);
    for gpu in common::gpus() {
        let mut cullers: Vec<Box<dyn Culler>> = ["dr", "vfc", "oracle"]
            .iter()
            .map(|m| create(m, &scene, &ModeParams::default()).unwrap())
            .collect();
        cullers.push(Box::new(DropOneVisible(Vec::new())));
        let out = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL);
        assert_eq!(out.rows.len(), 6 * 4);
        let sum = |mode: &str, f: fn(&occlu::measure::FrameStats) -> u64| -> u64 {
            out.rows.iter().filter(|r| r.mode == mode).map(f).sum()
        };
        for mode in ["dr", "vfc", "oracle"] {
            assert_eq!(sum(mode, |r| r.error_pixels.unwrap()), 0, "{mode} on {}", gpu.adapter);
            assert_eq!(sum(mode, |r| r.missed_objects.unwrap()), 0, "{mode} on {}", gpu.adapter);
        }
        assert!(
            sum("drop-one", |r| r.error_pixels.unwrap()) > 0,
            "the measure must see a dropped object"
        );
        assert_eq!(
            sum("drop-one", |r| r.missed_objects.unwrap()),
            6,
            "one missed object per frame"
        );
        let (dr, vfc, oracle) = (
            sum("dr", |r| r.triangles_drawn),
            sum("vfc", |r| r.triangles_drawn),
            sum("oracle", |r| r.triangles_drawn),
        );
        assert!(vfc * 10 < dr * 7, "vfc draws {vfc} of {dr} triangles");
        assert!(oracle < vfc, "the oracle draws least");
        assert_eq!(
            sum("oracle", |r| r.objects_drawn),
            sum("oracle", |r| r.visible_objects.unwrap())
        );
        assert!(
            out.rows
                .iter()
                .all(|r| r.frame_ms > 0.0 && r.cpu_ms >= 0.0 && r.cpu_ms <= r.frame_ms)
        );
    }
}

#[test]
fn missing_backend_is_a_clear_error() {
    // No Metal adapter exists on Linux; on macOS there is no DX12.
    let absent = if cfg!(target_os = "macos") {
        BackendChoice::Dx12
    } else {
        BackendChoice::Metal
    };
    match GpuContext::new(absent) {
        Err(e @ GpuError::NoAdapter(_)) => assert!(e.to_string().contains("no graphics adapter")),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("{absent} should not exist here"),
    }
}

/// Draws the reference visible set and notes, per frame, how many movers it
/// holds and how many objects moved.
struct MoverWatch<'a> {
    movers: Vec<u32>,
    seen: &'a RefCell<Vec<(usize, usize)>>,
    visible: Vec<u32>,
}
impl Culler for MoverWatch<'_> {
    fn name(&self) -> &str {
        "mover-watch"
    }
    fn needs_reference(&self) -> bool {
        true
    }
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let reference = input.reference_visible.unwrap();
        let visible_movers = self.movers.iter().filter(|&&m| reference.contains(m)).count();
        self.seen.borrow_mut().push((visible_movers, input.moved.len()));
        self.visible.clear();
        self.visible.extend(reference.iter());
        ctx.draw(&self.visible);
        TraversalStats::default()
    }
}

#[test]
fn conservative_modes_stay_exact_while_cars_drive_through_the_city() {
    let frames = 24;
    let (scene, hierarchy, path) = common::builtin("city:blocks=2,movers=40", frames);
    let movers: Vec<u32> = scene.movers.iter().map(|m| m.object).collect();
    let modes: Vec<&str> = occlu::cull::modes()
        .filter(|m| m.conservative)
        .map(|m| m.id.name())
        .collect();
    for gpu in common::gpus() {
        let seen = RefCell::new(Vec::new());
        let mut cullers: Vec<Box<dyn Culler>> = modes
            .iter()
            .map(|m| create(m, &scene, &ModeParams::default()).unwrap())
            .collect();
        cullers.push(Box::new(MoverWatch {
            movers: movers.clone(),
            seen: &seen,
            visible: Vec::new(),
        }));
        let out = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL);
        for row in &out.rows {
            let at = format!("{} frame {} on {}", row.mode, row.frame, gpu.adapter);
            assert_eq!(row.error_pixels, Some(0), "{at}");
            assert_eq!(row.missed_objects, Some(0), "{at}");
        }
        let seen = seen.borrow();
        assert_eq!(seen[0].1, 0, "frame 0 is where the scene was built");
        assert!(seen[1..].iter().all(|&(_, moved)| moved == movers.len()), "{seen:?}");
        let frames_with_movers = seen.iter().filter(|&&(visible, _)| visible > 0).count();
        assert!(
            frames_with_movers * 2 >= frames as usize,
            "cars are in view in most frames: {seen:?}"
        );
        let refits = out.rows.iter().filter(|r| r.mode == "vfc" && r.maintenance_ms > 0.0);
        assert_eq!(
            refits.count(),
            frames as usize - 1,
            "vfc refits the hierarchy after every move"
        );
    }
}

#[test]
fn the_forest_is_mostly_visible_where_the_city_is_mostly_hidden_and_every_mode_is_exact_in_it() {
    let modes: Vec<&str> = occlu::cull::modes()
        .filter(|m| m.conservative)
        .map(|m| m.id.name())
        .collect();
    // The share of the objects in the frustum (vfc draws them) that own a
    // pixel: the occlusion a scene offers to cull.
    let visible_share = |rows: &[occlu::measure::FrameStats]| {
        let vfc = rows.iter().filter(|r| r.mode == "vfc");
        let drawn: u64 = vfc.clone().map(|r| r.objects_drawn).sum();
        let visible: u64 = vfc.map(|r| r.visible_objects.unwrap()).sum();
        visible as f64 / drawn as f64
    };
    let gpu = common::gpus().remove(0);
    let mut shares = Vec::new();
    for spec in ["forest:trees=200", "city:blocks=2"] {
        let (scene, hierarchy, path) = common::builtin(spec, 8);
        let mut cullers: Vec<Box<dyn Culler>> = modes
            .iter()
            .map(|m| create(m, &scene, &ModeParams::default()).unwrap())
            .collect();
        let rows = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL).rows;
        for row in &rows {
            let at = format!("{spec}: {} frame {} on {}", row.mode, row.frame, gpu.adapter);
            assert_eq!((row.error_pixels, row.missed_objects), (Some(0), Some(0)), "{at}");
        }
        shares.push(visible_share(&rows));
    }
    assert!(
        shares[0] > 0.6,
        "the forest shows most of what is in the frustum: {shares:?}"
    );
    assert!(shares[1] < 0.3, "the city hides most of it: {shares:?}");
}

#[test]
fn a_gpu_error_at_run_time_is_an_error_not_a_panic() {
    for gpu in common::gpus() {
        assert!(gpu.check().is_ok(), "a fresh device has failed nothing");
        // Invalid on every backend: a mappable buffer may only be a copy
        // target besides. wgpu's default handler would panic here.
        let _ = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("invalid on purpose"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        match gpu.check() {
            Err(e @ GpuError::Failed(_)) => {
                // wgpu's message, naming what failed (raw here: the CLI
                // shows it escaped to one line).
                let message = e.to_string();
                assert!(
                    message.starts_with("the GPU failed: ") && message.contains("'invalid on purpose'"),
                    "{message}"
                );
            }
            other => panic!("{}: {other:?}", gpu.adapter),
        }
    }
}

#[test]
fn a_lost_device_ends_the_run_with_an_error_not_a_panic() {
    let scene = boxes(&[
        (DVec3::new(-1.0, -1.0, -6.0), DVec3::new(1.0, 1.0, -5.0)),
        (DVec3::new(-3.0, -1.0, -9.0), DVec3::new(3.0, 1.0, -8.0)),
    ]);
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = common::held(DVec3::ZERO, DVec3::NEG_Z, 60.0, 3);
    // Lost before the run starts, and in the middle of it: between frames,
    // where every mode (the GPU-driven ones creating their buffers) runs on.
    for lost_after_frames in [0, 1] {
        for gpu in common::gpus() {
            let modes: Vec<&str> = occlu::cull::modes()
                .filter(|m| m.unsupported_on(&gpu).is_none())
                .map(|m| m.id.name())
                .collect();
            let mut cullers: Vec<Box<dyn Culler>> = modes
                .iter()
                .map(|m| create(m, &scene, &ModeParams::default()).unwrap())
                .collect();
            let options = occlu::session::RunOptions {
                warmup: 0,
                resolution: Resolution { width: 32, height: 24 },
                measure_error: true,
            };
            let mut world = occlu::world::World::new(scene.clone(), hierarchy.clone());
            // Destroying the device is what losing it looks like to wgpu.
            if lost_after_frames == 0 {
                gpu.device.destroy();
            }
            let outcome = occlu::bench::run(&gpu, &mut world, &path, &mut cullers, &options, None, &mut |done, _| {
                if done == lost_after_frames {
                    gpu.device.destroy();
                }
                std::ops::ControlFlow::Continue(())
            });
            match outcome {
                Err(BenchError::Gpu(GpuError::Failed(message))) => assert!(!message.contains('\n'), "{message}"),
                Err(other) => panic!("{}: {other}", gpu.adapter),
                Ok(_) => panic!("{}: a run on a destroyed device succeeded", gpu.adapter),
            }
        }
    }
}

/// wgpu's own `create_buffer_init` panics on a lost device; every buffer
/// occlu fills (the scene, the GPU walk's trees, the overview's lines)
/// goes through `buffer_with`, which must not.
#[test]
fn a_buffer_filled_on_a_lost_device_is_an_error_not_a_panic() {
    for gpu in common::gpus() {
        gpu.device.destroy();
        let _ = gpu.buffer_with("probe", &[1, 2, 3], wgpu::BufferUsages::VERTEX);
        assert!(matches!(gpu.check(), Err(GpuError::Failed(_))), "{}", gpu.adapter);
    }
}
