//! Per-frame CPU work of culling, along each built-in scene's default
//! 120-frame walk: `cargo bench --bench traversal`.
//!
//! - **frustum traversal**: `vfc`'s whole frame (002 §4.1), and the first
//!   step of every hierarchical mode;
//! - **front-to-back order**: every node in the frustum through the
//!   nearest-corner queue (003 §4.2), the order `sq`, `omq` and `chc` visit
//!   nodes in; an upper bound, since those stop below hidden nodes.
//!
//! (`roc`, `ioc` and `hiz` make their boxes on the GPU: their CPU a frame
//! is in `benches/culling_cpu.rs`.)
//!
//! Means per frame over the walk, each the median of several passes.

mod common;

use std::hint::black_box;
use std::time::{Duration, Instant};

use occlu::camera::{Camera, Containment};
use occlu::cull::TraversalStats;
use occlu::cull::traversal::{DepthQueue, frustum_cull_subtree, nearest_corner};
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
