//! `swr`'s culling on the CPU, along each built-in scene's default 120-frame
//! walk at 800×600: `cargo bench --bench swr`.
//!
//! Each frame is the mode's whole frame (occluders chosen, rasterised into
//! the buffer, the pyramid, the hierarchy tested) with the drawing left out,
//! so the time is exactly what frames.csv reports as swr's `cpu_ms`. The
//! walk runs once untimed first, so every timed frame has last frame's
//! visible set as occluders, as in a run. Reported: the median pass's mean
//! per frame, the occluder triangles a frame, and triangles a second over
//! the whole frame; with `swr.triangles=0` (no occluders, nothing hidden)
//! the frame is the box tests alone, and boxes a second. The adapter is
//! taken to snap to 8 sub-pixel bits, as lavapipe and llvmpipe report.
//!
//! `cargo bench --bench swr -- swr.KEY=VALUE ... SCENE ...` runs with those
//! parameters, e.g. `swr.threads=1` or `swr.resolution=128x96`, on those
//! scenes (built-in specs or model files, each along its default walk)
//! instead of the three built-in ones.

mod common;

use std::hint::black_box;
use std::time::{Duration, Instant};

use occlu::bounds::Aabb;
use occlu::camera::Camera;
use occlu::cull::{Culler, FrameInput, ModeId, ModeParams, SoftwareOcclusionCulling, SwrParams, TraversalStats};
use occlu::gpu::{BoxTest, BoxVisibility, Frame, GpuFrame, Resolution, SubpixelPrecision};
use occlu::hierarchy::Hierarchy;
use occlu::scene::Scene;

use common::{FRAMES, SCENES};

const PASSES: usize = 5;

/// A frame that draws nothing: swr asks the GPU for nothing else.
struct NoDrawing;

impl Frame for NoDrawing {
    fn draw(&mut self, objects: &[u32]) {
        black_box(objects);
    }
    fn test_boxes(&mut self, _: &[Aabb], _: BoxTest, _: &mut Vec<BoxVisibility>) {
        unreachable!("swr tests its boxes on the CPU")
    }
    fn test_boxes_with_totals(&mut self, _: &[Aabb], _: u32, _: &mut Vec<BoxVisibility>, _: &mut Vec<u64>) {
        unreachable!("swr tests its boxes on the CPU")
    }
    fn on_gpu(&mut self) -> Option<&mut dyn GpuFrame> {
        None
    }
}

/// The walk's frames through `swr` with `params`: the median pass's time a
/// frame, and the mean counts a frame.
fn walk(scene: &Scene, hierarchy: &Hierarchy, cameras: &[Camera], params: &[&str]) -> (Duration, TraversalStats) {
    let items: Vec<String> = params.iter().map(|p| p.to_string()).collect();
    let params = ModeParams::parse(&items, &[ModeId::Swr]).expect("bench parameters");
    let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&params).expect("bench parameters"));
    swr.assume_subpixel_precision(SubpixelPrecision::reported(8));
    let mut totals = TraversalStats::default();
    let mut run = |count: bool, totals: &mut TraversalStats| {
        for (frame, camera) in cameras.iter().enumerate() {
            let input = FrameInput {
                frame: frame as u32,
                camera,
                resolution: Resolution::DEFAULT,
                scene,
                hierarchy,
                moved: &[],
                reference_visible: None,
                previous: None,
                warm_up: false,
            };
            let stats = swr.frame(&mut NoDrawing, black_box(&input));
            if count {
                totals.occluder_triangles += stats.occluder_triangles;
                totals.nodes_visited += stats.nodes_visited;
                totals.nodes_culled_frustum += stats.nodes_culled_frustum;
            }
        }
    };
    run(true, &mut totals);
    let mut passes: Vec<Duration> = (0..PASSES)
        .map(|_| {
            let start = Instant::now();
            run(false, &mut totals);
            start.elapsed() / cameras.len() as u32
        })
        .collect();
    passes.sort();
    let frames = cameras.len() as u64;
    totals.occluder_triangles /= frames;
    totals.nodes_visited /= frames;
    totals.nodes_culled_frustum /= frames;
    (passes[PASSES / 2], totals)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with('-')).collect();
    let (params, scenes): (Vec<&str>, Vec<&str>) = args.iter().map(String::as_str).partition(|a| a.starts_with("swr."));
    let scenes = if scenes.is_empty() { SCENES.to_vec() } else { scenes };
    for spec in scenes {
        let (scene, hierarchy, cameras) = common::walk(spec);
        println!("{spec}: {} objects, {FRAMES} frames at 800x600", scene.objects.len());
        let (whole, counts) = walk(&scene, &hierarchy, &cameras, &params);
        let ms = whole.as_secs_f64() * 1e3;
        println!(
            "  swr frame                {ms:>7.2} ms   {:>7} occluder triangles   {:>6.2} M triangles/s",
            counts.occluder_triangles,
            counts.occluder_triangles as f64 / whole.as_secs_f64() / 1e6
        );
        let (tests, counts) = walk(&scene, &hierarchy, &cameras, &["swr.triangles=0"]);
        let boxes = counts.nodes_visited - counts.nodes_culled_frustum;
        println!(
            "  box tests alone          {:>7.2} ms   {boxes:>7} node boxes          {:>6.2} M boxes/s",
            tests.as_secs_f64() * 1e3,
            boxes as f64 / tests.as_secs_f64() / 1e6
        );
    }
}
