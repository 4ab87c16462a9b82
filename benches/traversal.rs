//! Per-frame CPU work of culling, along each built-in scene's default
//! 120-frame walk: `cargo bench --bench traversal`.
//!
//! - **frustum traversal**: `vfc`'s whole frame (002 §4.1), and the first
//!   step of every hierarchical mode;
//! - **front-to-back order**: every node in the frustum through the
//!   nearest-corner queue (003 §4.2), the order `sq`, `omq` and `chc` visit
//!   nodes in; an upper bound, since those stop below hidden nodes;
//! - **box preparation**: the eye-relative f64 boxes `hiz` (one per
//!   object) stages for the GPU every frame, before its planes (`roc` and
//!   `ioc` make theirs on the GPU: `benches/culling_cpu.rs`).
//!
//! Means per frame over the walk, each the median of several passes.

mod common;

use std::hint::black_box;
use std::time::{Duration, Instant};

use occlu::bounds::Aabb;
use occlu::camera::{Camera, Containment};
use occlu::cull::TraversalStats;
use occlu::cull::gpu_walk::NodeBoxes;
use occlu::cull::traversal::{DepthQueue, frustum_cull_subtree, nearest_corner};
use occlu::gpu::{BoxMargins, DepthMargins, Resolution};
use occlu::hierarchy::Hierarchy;

use common::{FRAMES, SCENES};

const PASSES: usize = 7;

fn main() {
    for spec in SCENES {
        let (scene, hierarchy, cameras) = common::walk(spec);
        println!(
            "{spec}: {} objects, {} nodes, {FRAMES} frames",
            scene.objects.len(),
            hierarchy.nodes.len()
        );

        let (mut stack, mut visible) = (Vec::new(), Vec::new());
        let mut drawn = 0;
        let vfc = per_frame(&cameras, |camera| {
            let mut stats = TraversalStats::default();
            visible.clear();
            let frustum = camera.frustum();
            frustum_cull_subtree(&scene, &hierarchy, 0, &frustum, &mut stack, &mut visible, &mut stats);
            drawn += visible.len();
        });
        report(
            "frustum traversal (vfc)",
            vfc,
            drawn / (PASSES * cameras.len()),
            "objects kept",
        );

        let mut queue = DepthQueue::default();
        let mut popped = 0;
        let order = per_frame(&cameras, |camera| {
            popped += front_to_back(&hierarchy, camera, &mut queue)
        });
        report("front-to-back order", order, popped / (PASSES * cameras.len()), "nodes");

        let objects: Vec<Aabb> = scene.objects.iter().map(|o| o.bounds).collect();
        prepare_boxes("hiz boxes (every object, without planes)", &cameras, &objects);
        println!();
    }
}

/// Visits every node in the frustum nearest corner first; the count.
fn front_to_back(hierarchy: &Hierarchy, camera: &Camera, queue: &mut DepthQueue) -> usize {
    let frustum = camera.frustum();
    queue.clear();
    queue.push(0, 0.0);
    let mut visited = 0;
    while let Some(n) = queue.pop() {
        visited += 1;
        for c in hierarchy.nodes[n as usize].children() {
            let b = &hierarchy.nodes[c].bounds;
            if frustum.classify(b) != Containment::Outside {
                queue.push(c as u32, nearest_corner(b, camera.eye));
            }
        }
    }
    visited
}

fn prepare_boxes(what: &str, cameras: &[Camera], bounds: &[Aabb]) {
    let mut boxes = NodeBoxes::default();
    let depth = DepthMargins::for_backend(wgpu::Backend::Vulkan);
    let mut tested = 0;
    let time = per_frame(cameras, |camera| {
        let margins = BoxMargins::new(depth, camera, Resolution::DEFAULT);
        boxes.prepare(camera, margins, bounds.iter().copied());
        tested += boxes.counts().1;
    });
    report(what, time, tested / (PASSES * cameras.len()), "to test");
}

/// Mean time per camera of `f`, the median over [`PASSES`] passes.
fn per_frame(cameras: &[Camera], mut f: impl FnMut(&Camera)) -> Duration {
    let mut passes: Vec<Duration> = (0..PASSES)
        .map(|_| {
            let start = Instant::now();
            for camera in cameras {
                f(black_box(camera));
            }
            start.elapsed() / cameras.len() as u32
        })
        .collect();
    passes.sort();
    passes[PASSES / 2]
}

fn report(what: &str, per_frame: Duration, count: usize, unit: &str) {
    println!(
        "  {what:<36} {:>8.1} µs/frame   {count:>6} {unit}",
        per_frame.as_secs_f64() * 1e6
    );
}
