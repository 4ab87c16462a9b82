//! Planning time of the default path on models of about a million
//! triangles: `cargo bench --bench planning`.
//!
//! - the built-in city (1.5 M triangles) without its streets, planned as
//!   a loaded city is: a place, walked down its streets;
//! - a hall of 1 M triangles: 40 statues (bumpy scanned spheres of 25 392
//!   triangles) in the aisles beside two rows of columns, under a roof,
//!   with a door: an interior, walked inside;
//! - the same hall on a ground plane 20 times wider: the plane is left out
//!   of the focus, and the hall walked inside;
//! - every model directly in `../shared/models`, where present.
//!
//! `cargo bench --bench planning -- WORD` plans only those whose name
//! holds WORD.
//!
//! For each, the median of several plannings of the default path
//! (`camera::generate::plan`: the lines of sight from the orbit, the
//! walk's floors, links, streets and interior, the keyframes), the box and
//! triangle tests they spent, and the kind and class chosen. Target on the
//! project's 2-core machine: at most 1 s for 1 M triangles (the CPU time,
//! where other work shares the machine).

mod common;

use std::cell::Cell;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::Instant;

use common::{median, scan};
use glam::{DAffine3, DVec3};
use occlu::camera::generate::{Generated, plan_heard};
use occlu::scene::{LoadOptions, Scene, SceneBuilder, SceneSpec, load};

#[path = "../tests/common/gltf_writer.rs"]
#[allow(dead_code)] // the bench uses the cube's indices only
mod gltf_writer;

#[path = "../tests/common/hall.rs"]
mod hall;

const RUNS: usize = 3;

fn main() {
    // `cargo bench --bench planning -- WORD` plans only the scenes whose
    // name holds WORD (cargo passes `--bench` too).
    let only = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let wanted = |name: &str| only.as_deref().is_none_or(|w| name.contains(w));
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models");
    let mut models: Vec<_> = std::fs::read_dir(&shared)
        .map(|dir| dir.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    models.retain(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("obj" | "glb" | "gltf")));
    models.sort();
    let mut scenes: Vec<(String, Box<dyn Fn() -> Scene>)> = vec![
        (
            "built-in city, without its streets".into(),
            Box::new(|| {
                let mut city =
                    load(&SceneSpec::Builtin("city".into()), &LoadOptions::default()).expect("built-in city");
                city.walk_hint = None;
                city
            }),
        ),
        ("hall with 40 statues".into(), Box::new(|| hall(false))),
        (
            "hall with 40 statues, on a plane 20 times wider".into(),
            Box::new(|| hall(true)),
        ),
    ];
    for model in models {
        let name = model.file_name().unwrap_or_default().to_string_lossy().into_owned();
        scenes.push((
            name,
            Box::new(move || {
                load(&SceneSpec::File(model.clone()), &LoadOptions::default()).expect("shared model loads")
            }),
        ));
    }
    for (name, scene) in scenes.iter().filter(|(name, _)| wanted(name)) {
        measure(name, &scene());
    }
}

/// Plans `scene`'s default path [`RUNS`] times and prints the median
/// time (wall, and the planning thread's CPU where the platform tells it:
/// on a shared machine the wall clock also counts other work), the tests
/// spent (as last told, to within `Budget::TELL_EVERY`), and what was
/// chosen.
fn measure(what: &str, scene: &Scene) {
    let (mut wall, mut cpu) = (Vec::with_capacity(RUNS), Vec::with_capacity(RUNS));
    let spent = Cell::new(0);
    let mut last: Option<Generated> = None;
    for _ in 0..RUNS {
        let (started, cpu_started) = (Instant::now(), thread_cpu_seconds());
        let listener = Box::new(|tests, _| {
            spent.set(tests);
            ControlFlow::Continue(())
        });
        let generated = plan_heard(None, scene, None, listener).expect("a default path");
        wall.push(started.elapsed().as_secs_f64());
        cpu.extend(thread_cpu_seconds().zip(cpu_started).map(|(end, start)| end - start));
        last = Some(std::hint::black_box(generated));
    }
    let generated = last.expect("RUNS > 0");
    let class = generated.why.split(" (").next().unwrap_or_default();
    let triangles = scene.triangles() as f64 / 1e6;
    let cpu = match cpu.len() {
        0 => String::new(),
        _ => format!(", CPU {:.3} s", median(cpu)),
    };
    println!(
        "{what}: {triangles:.2} M triangles, {} objects: {} ({class}); {:.3} s{cpu}, about {} M tests",
        scene.objects.len(),
        generated.kind,
        median(wall),
        spent.get() / 1_000_000
    );
}

/// The CPU time this thread has used (planning runs on one thread).
#[cfg(unix)]
fn thread_cpu_seconds() -> Option<f64> {
    let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec through a valid pointer.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0;
    ok.then_some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
}

#[cfg(not(unix))]
fn thread_cpu_seconds() -> Option<f64> {
    None
}

/// The hall of the tests (`tests/common/hall.rs`: 48 × 24, 12 tall, two
/// rows of seven columns, a door in the east wall) with 20 statues in each
/// aisle, on a ground plane 20 times wider when `on_plane`.
fn hall(on_plane: bool) -> Scene {
    let mut builder = SceneBuilder::new("bench hall".into(), occlu::scene::DEFAULT_CLUSTER_TRIANGLES);
    let mut boxes = hall::hall();
    if on_plane {
        boxes.push((
            "ground".into(),
            DVec3::new(-456.0, -1.5, -228.0),
            DVec3::new(504.0, -0.5, 252.0),
        ));
    }
    for (name, min, max) in boxes {
        let corners: Vec<DVec3> = (0..8)
            .map(|i| DVec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), max, min))
            .collect();
        let group = builder
            .add_mesh(&name, &corners, &gltf_writer::cube_indices())
            .expect("box");
        builder
            .add_object(&name, &group, DAffine3::IDENTITY)
            .expect("box placed");
    }
    let (positions, indices) = scan(46);
    let statue = builder.add_mesh("statue", &positions, &indices).expect("statue");
    for aisle in [4.0, 20.0] {
        for k in 0..20 {
            let at = DVec3::new(2.5 + 2.2 * f64::from(k), 1.2, aisle);
            builder
                .add_object("statue", &statue, DAffine3::from_translation(at))
                .expect("statue placed");
        }
    }
    builder.finish().expect("the hall has geometry")
}
