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
use occlu::session::{RunOptions, Session};
use occlu::world::World;

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

#[test]
fn a_modes_draws_go_nearest_first_so_where_two_objects_tie_in_depth_the_nearer_one_shows() {
    // Two thin boxes whose fronts lie in one plane 10 units ahead (90° fov
    // at 100 × 100: a unit is 5 pixels), overlapping over x in [-1, 1]. At
    // equal depth the strict depth test keeps what was drawn first, so the
    // overlap shows which went first. The small box's centre (10.0 from
    // the eye) is nearer than the wide one's (10.8), whichever the scene
    // lists first, and whichever order a mode hands them over in.
    let (w, h) = (100u32, 100u32);
    let small = (DVec3::new(-2.0, -1.0, -10.0), DVec3::new(1.0, 1.0, -9.999));
    let wide = (DVec3::new(-1.0, -1.0, -10.0), DVec3::new(9.0, 1.0, -9.999));
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 90.0);
    let options = RunOptions {
        warmup: 0,
        resolution: Resolution { width: w, height: h },
        measure_error: false,
    };
    let camera = path.camera(0, options.resolution.aspect());
    // Row 50's pixels at x = -1.5 (the small box alone), 0 (both) and 5
    // (the wide box alone).
    let pixel = |x: f64| 50 * w as usize + (50.0 + 5.0 * x) as usize;
    let rgb = |image: &[u8], x: f64| {
        let i = pixel(x) * 3;
        [image[i], image[i + 1], image[i + 2]].map(f64::from)
    };
    let apart = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>();
    for gpu in common::gpus() {
        for list in [[wide, small], [small, wide]] {
            let scene = boxes(&list);
            let mut world = World::new(scene.clone(), common::hierarchy(&scene));
            let mut cullers: Vec<Box<dyn Culler>> = ["dr", "vfc", "oracle"]
                .iter()
                .map(|m| create(m, &scene, &ModeParams::default()).unwrap())
                .collect();
            let mut session = Session::new(&gpu, &world, &mut cullers, true, &options).unwrap();
            session.keep_colours();
            session.frame(0, &camera, &mut world, &mut cullers, 0).unwrap();
            for (k, culler) in cullers.iter().enumerate() {
                // The premise: both fronts draw one depth, bit for bit.
                let depth = session.mode_depth(k).unwrap();
                let [alone, both, other] = [-1.5, 0.0, 5.0].map(|x| depth[pixel(x)].to_bits());
                assert!(
                    alone == both && both == other && alone != 0,
                    "{}: {alone} {both} {other}",
                    gpu.adapter
                );
                let image = session.colour(k).unwrap();
                let (alone, both, other) = (rgb(&image, -1.5), rgb(&image, 0.0), rgb(&image, 5.0));
                // The two boxes' colours differ far more than one box's
                // shading does over a few pixels.
                assert!(apart(alone, other) > 30.0, "{}: {alone:?} {other:?}", gpu.adapter);
                assert!(
                    apart(both, alone) < apart(both, other) / 4.0,
                    "{} on {}: the overlap is {both:?}, the small box {alone:?}, the wide one {other:?}",
                    culler.name(),
                    gpu.adapter
                );
            }
        }
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
fn a_backend_this_system_never_has_is_a_clear_input_error() {
    // Metal exists only on Apple systems; on macOS there is no DX12.
    let absent = if cfg!(target_os = "macos") {
        BackendChoice::Dx12
    } else {
        BackendChoice::Metal
    };
    match GpuContext::new(absent) {
        Err(e @ GpuError::NotOnThisSystem(..)) => {
            assert!(e.is_input_error());
            assert!(
                e.to_string().contains(&format!("the {absent} backend exists only on")),
                "{e}"
            );
        }
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

/// A pixel's coverage the adapter may decide either way: its centre lies
/// within `error` (on each axis) of an edge of `corners`, so a vertex
/// snapped that far may move the edge past it.
fn in_doubt(corners: [[f64; 2]; 3], centre: [f64; 2], error: f64) -> bool {
    // Liang and Barsky: whether the edge meets the square of half-side
    // `error` round the centre.
    let meets = |p: [f64; 2], q: [f64; 2]| {
        let (mut enter, mut leave) = (0.0f64, 1.0f64);
        for axis in 0..2 {
            let d = q[axis] - p[axis];
            let (lo, hi) = (centre[axis] - error - p[axis], centre[axis] + error - p[axis]);
            if d == 0.0 {
                if lo > 0.0 || hi < 0.0 {
                    return false;
                }
            } else {
                let (a, b) = (lo / d, hi / d);
                enter = enter.max(a.min(b));
                leave = leave.min(a.max(b));
            }
        }
        enter <= leave
    };
    (0..3).any(|k| meets(corners[k], corners[(k + 1) % 3]))
}

/// Whether `centre` lies inside triangle `corners` (either turn).
fn inside(corners: [[f64; 2]; 3], centre: [f64; 2]) -> bool {
    let side = |p: [f64; 2], q: [f64; 2]| (q[0] - p[0]) * (centre[1] - p[1]) - (q[1] - p[1]) * (centre[0] - p[0]);
    let sides = [0, 1, 2].map(|k| side(corners[k], corners[(k + 1) % 3]));
    sides.iter().all(|&s| s > 0.0) || sides.iter().all(|&s| s < 0.0)
}

#[test]
fn every_adapter_draws_each_pixel_centre_clear_of_a_triangles_edges_by_its_reported_snap_as_the_exact_triangle_does() {
    // swr vouches for a pixel centre only where it lies clear of an
    // occluder's outline by the snap the adapter reports: here each of 1024
    // random triangles, one in each 8 × 8 tile of the target, with corners
    // on a grid of 2^-12 pixel (so the shader's and the viewport's
    // arithmetic is exact and only the snap moves them), is drawn, and every
    // centre clear of its edges by the snap must be drawn as the exact
    // triangle holds it.
    const SIDE: u32 = 256;
    const SHADER: &str = "
        @vertex fn vs(@location(0) pixel: vec2<f32>) -> @builtin(position) vec4<f32> {
            return vec4<f32>(pixel.x / 128.0 - 1.0, 1.0 - pixel.y / 128.0, 0.5, 1.0);
        }
        @fragment fn fs() -> @location(0) vec4<f32> {
            return vec4<f32>(1.0);
        }";
    let mut rng = occlu::rng::Rng::new(7);
    let on_grid = |v: f64| (v * 4096.0).round() / 4096.0;
    let triangles: Vec<[[f64; 2]; 3]> = (0..(SIDE / 8) * (SIDE / 8))
        .map(|tile| {
            let origin = [f64::from(tile % (SIDE / 8) * 8), f64::from(tile / (SIDE / 8) * 8)];
            [0; 3].map(|_| [0, 1].map(|axis| on_grid(origin[axis] + rng.range(0.0, 8.0))))
        })
        .collect();
    let vertices: Vec<[f32; 2]> = triangles.iter().flatten().map(|p| p.map(|v| v as f32)).collect();
    for gpu in common::gpus() {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("snap"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let format = wgpu::TextureFormat::Rgba8Unorm;
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("snap"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 8,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x2],
                })],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("snap"),
            size: wgpu::Extent3d {
                width: SIDE,
                height: SIDE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let buffer = gpu.buffer_with("snap", bytemuck::cast_slice(&vertices), wgpu::BufferUsages::VERTEX);
        let readback = occlu::gpu::Readback::new(&gpu, "snap", u64::from(SIDE * SIDE * 4));
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let view = target.create_view(&Default::default());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&pipeline);
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..vertices.len() as u32, 0..1);
        }
        readback.copy_texture(&mut encoder, &target, SIDE * 4, SIDE);
        gpu.queue.submit([encoder.finish()]);
        let mut pixels: Vec<[u8; 4]> = Vec::new();
        readback.read(&gpu, u64::from(SIDE * SIDE * 4), &mut pixels);
        gpu.check().unwrap();

        let resolution = Resolution {
            width: SIDE,
            height: SIDE,
        };
        let error = gpu.subpixel.vertex_error(resolution);
        let (mut checked, mut near_an_edge) = (0, 0);
        for (tile, &corners) in triangles.iter().enumerate() {
            let origin = [tile as u32 % (SIDE / 8) * 8, tile as u32 / (SIDE / 8) * 8];
            for (x, y) in (0..8).flat_map(|x| (0..8).map(move |y| (origin[0] + x, origin[1] + y))) {
                let centre = [f64::from(x) + 0.5, f64::from(y) + 0.5];
                if in_doubt(corners, centre, error) {
                    continue;
                }
                let drawn = pixels[(y * SIDE + x) as usize][0] == 255;
                assert_eq!(
                    drawn,
                    inside(corners, centre),
                    "{}: {} sub-pixel bits reported, yet the pixel at {centre:?} of {corners:?}, clear of its edges by {error}, is drawn {drawn}",
                    gpu.adapter,
                    gpu.subpixel.bits()
                );
                checked += 1;
                near_an_edge += usize::from(in_doubt(corners, centre, 16.0 * error));
            }
        }
        // Centres clear of an edge by the error but within 16 times it: where
        // a snap coarser than reported would draw them otherwise.
        assert!(
            checked > 20_000 && near_an_edge > 1_000,
            "{checked} centres checked, {near_an_edge} near an edge"
        );
    }
}

#[test]
fn swr_hides_a_box_behind_two_walls_whose_seam_passes_a_twentieth_of_a_pixel_from_pixel_centres() {
    // Two walls 10 m ahead, each a box of its own, meeting at the x whose
    // pixel column lies at 80.45 on a 160 × 120 target: the seam passes
    // 0.05 pixel from the centres at x = 80.5, within Vulkan's coarsest
    // snap (1/16 pixel), where a GPU snapping that coarsely may leave them
    // undrawn, and clear of the 1/256 pixel of the 8 sub-pixel bits the
    // adapters here report. A box 30 m ahead straddles
    // the seam on screen: swr hides it where the adapter's snap leaves the
    // seam's centres clear, and must draw it where it does not.
    let size = Resolution {
        width: 160,
        height: 120,
    };
    let pixels_at_unit_depth = 60.0 / 30f64.to_radians().tan();
    let seam = 0.45 / pixels_at_unit_depth * 10.0;
    let half = 0.15;
    let scene = common::boxes(&[
        (DVec3::new(-20.0, -20.0, -10.1), DVec3::new(seam, 20.0, -10.0)),
        (DVec3::new(seam, -20.0, -10.1), DVec3::new(20.0, 20.0, -10.0)),
        (
            DVec3::new(3.0 * seam - half, -half, -30.0 - half),
            DVec3::new(3.0 * seam + half, half, -30.0 + half),
        ),
    ]);
    let hierarchy = Hierarchy::build(&scene.objects, &common::one_object_per_leaf());
    // Frame 2 and on: the walls drawn in frame 1 are the occluders.
    let path = common::held(DVec3::ZERO, DVec3::NEG_Z, 60.0, 3);
    let params = ModeParams::parse(
        &["swr.resolution=80x60".to_string(), "swr.rests=false".to_string()],
        &["swr".parse().unwrap()],
    )
    .unwrap();
    for gpu in common::gpus() {
        let clear = gpu.subpixel.vertex_error(size) < 0.04;
        let mut cullers = vec![create("swr", &scene, &params).unwrap()];
        let out = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, size);
        let last = out.rows.last().unwrap();
        let bits = gpu.subpixel.bits();
        assert_eq!(
            last.objects_drawn,
            if clear { 2 } else { 3 },
            "{}, {bits} sub-pixel bits",
            gpu.adapter
        );
        assert!(out.rows.iter().all(|r| r.error_pixels == Some(0)), "{}", gpu.adapter);
    }
}
