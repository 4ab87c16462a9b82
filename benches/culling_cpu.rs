//! Culling CPU a frame against the scene's object count, for every culling
//! mode: `cargo bench --bench culling_cpu`.
//!
//! The scene is the small built-in city (`city:blocks=2`) with enough props
//! (`props=N`: bollards, bins and lamp posts on its pavements) to hold 1 k,
//! 10 k, 100 k and 1 M objects, so it grows in objects and barely in
//! triangles a prop. Each mode runs the city's default walk on the best
//! adapter present without error measurement, after warm-up frames; the
//! table gives each mode's mean `cpu_ms` (its `frame` call minus its GPU
//! operations: what the CPU spent deciding) and, for scale, `vfc`'s, the
//! reference line: a frustum traversal of the hierarchy.
//!
//! `cargo bench --bench culling_cpu -- MODES [MAX_OBJECTS]` runs only the
//! comma-separated MODES (default: every mode but dr, ac and auto, which
//! decide nothing of their own or by time) up to MAX_OBJECTS objects
//! (default 1 000 000). `OCCLU_BACKEND=gl|vulkan` picks the adapter.

use std::ops::ControlFlow;
use std::time::Instant;

use occlu::bench::run;
use occlu::camera::generate::default_path;
use occlu::cull::{Culler, ModeId, ModeParams, parse_modes};
use occlu::gpu::{BackendChoice, GpuContext, Resolution};
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::scene::{LoadOptions, SceneSpec, load};
use occlu::session::RunOptions;
use occlu::world::World;

const OBJECTS: [u32; 4] = [1_000, 10_000, 100_000, 1_000_000];
const FRAMES: u32 = 8;
const WARMUP: u32 = 2;
const BASE: &str = "city:blocks=2";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with('-')).collect();
    let modes = match args.first() {
        Some(list) => parse_modes(std::slice::from_ref(list)).expect("MODES: a comma-separated list of modes"),
        None => ModeId::ALL
            .iter()
            .copied()
            .filter(|m| !matches!(m, ModeId::Dr | ModeId::Ac | ModeId::Auto))
            .collect(),
    };
    let max_objects: u32 = args.get(1).map_or(OBJECTS[3], |a| a.parse().expect("MAX_OBJECTS"));
    let backend = match std::env::var("OCCLU_BACKEND").as_deref() {
        Ok("gl") => BackendChoice::Gl,
        Ok("vulkan") => BackendChoice::Vulkan,
        _ => BackendChoice::Auto,
    };
    let gpu = GpuContext::new(backend).expect("an adapter");
    println!("{} on {}, {FRAMES} frames after {WARMUP} warm-up", BASE, gpu.adapter);
    let base = load(&SceneSpec::Builtin(BASE.into()), &LoadOptions::default()).expect("the city");
    let (path, _) = default_path(&base).expect("the city's walk");
    let path = path.with_frames(FRAMES).expect("frames");
    let header: Vec<String> = modes.iter().map(|m| format!("{:>8}", m.name())).collect();
    println!(
        "{:>9} {:>8}  {}   (mean culling CPU ms a frame)",
        "objects",
        "build s",
        header.join(" ")
    );
    for objects in OBJECTS.into_iter().filter(|&n| n <= max_objects) {
        let props = objects.saturating_sub(base.objects.len() as u32);
        let started = Instant::now();
        let spec = format!("{BASE},props={props}");
        let scene = load(&SceneSpec::Builtin(spec), &LoadOptions::default()).expect("the city with props");
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        let built = started.elapsed().as_secs_f64();
        let mut row = Vec::new();
        for &mode in &modes {
            if mode.info().unsupported_on(&gpu).is_some() {
                row.push(format!("{:>8}", "–"));
                continue;
            }
            let culler = mode.create(&scene, &ModeParams::default()).expect("default parameters");
            let mut cullers: Vec<Box<dyn Culler>> = vec![culler];
            let options = RunOptions {
                warmup: WARMUP,
                resolution: Resolution::DEFAULT,
                measure_error: false,
            };
            let mut world = World::new(scene.clone(), hierarchy.clone());
            let out = run(&gpu, &mut world, &path, &mut cullers, &options, None, &mut |_, _| {
                ControlFlow::Continue(())
            })
            .expect("the run");
            let cpu: f64 = out.rows.iter().map(|r| r.cpu_ms).sum::<f64>() / out.rows.len() as f64;
            row.push(format!("{cpu:>8.3}"));
        }
        println!("{:>9} {built:>8.1}  {}", scene.objects.len(), row.join(" "));
    }
}
