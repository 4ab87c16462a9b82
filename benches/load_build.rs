//! Load and hierarchy-build throughput on generated models.
//!
//! `cargo bench --bench load_build` writes a 1 M-triangle OBJ (100 objects of
//! 8 192 triangles and one 200 000-triangle mesh that must be split into
//! clusters) and times, over several runs: parsing + validation + clustering
//! (`load`), BVH build (`build`), and generating the built-in city. Medians
//! are printed with throughput. Target: load + build of 1 M triangles under
//! 1 s in release on the 2-core reference machine.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::scene::{LoadOptions, SceneSpec, load};

const RUNS: usize = 5;

fn main() {
    let dir = std::env::temp_dir().join(format!("occlu-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let obj = dir.join("million.obj");
    let (text, triangles) = million_triangle_obj();
    std::fs::write(&obj, &text).expect("write OBJ");
    let mb = text.len() as f64 / 1e6;
    println!(
        "model: {triangles} triangles, {mb:.1} MB of OBJ text ({})",
        obj.display()
    );

    let spec = SceneSpec::File(obj);
    let options = LoadOptions::default();
    let (load_time, scene) = median_of(|| load(&spec, &options).expect("generated model loads"));
    let (build_time, hierarchy) = median_of(|| Hierarchy::build(&scene.objects, &HierarchyParams::default()));
    report("OBJ load (parse, validate, cluster)", load_time, triangles, Some(mb));
    report("hierarchy build", build_time, triangles, None);
    println!(
        "  {} objects after clustering, {} nodes, depth {}",
        scene.objects.len(),
        hierarchy.nodes.len(),
        hierarchy.stats().depth
    );
    report("load + build", load_time + build_time, triangles, None);

    let city = SceneSpec::Builtin("city".into());
    let (city_time, scene) = median_of(|| load(&city, &options).expect("city builds"));
    let city_tris = scene.triangles() as usize;
    report("built-in city generation", city_time, city_tris, None);
    let (city_build, _) = median_of(|| Hierarchy::build(&scene.objects, &HierarchyParams::default()));
    report("built-in city hierarchy", city_build, city_tris, None);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `f` RUNS times; the median duration and the last result.
fn median_of<T>(mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut times = Vec::with_capacity(RUNS);
    let mut last = None;
    for _ in 0..RUNS {
        let start = Instant::now();
        last = Some(std::hint::black_box(f()));
        times.push(start.elapsed());
    }
    times.sort();
    (times[RUNS / 2], last.expect("RUNS > 0"))
}

fn report(what: &str, t: Duration, triangles: usize, megabytes: Option<f64>) {
    let s = t.as_secs_f64();
    let mut line = format!(
        "{what:<40} {:>9.1} ms  {:>7.2} M triangles/s",
        s * 1e3,
        triangles as f64 / s / 1e6
    );
    if let Some(mb) = megabytes {
        let _ = write!(line, "  {:>7.1} MB/s", mb / s);
    }
    println!("{line}");
}

/// 100 terrain-like grids of 8 192 triangles and one of 199 712: 1 018 912.
fn million_triangle_obj() -> (String, usize) {
    let mut text = String::with_capacity(64 << 20);
    let mut base = 1usize;
    let mut triangles = 0;
    let mut grid = |name: &str, n: usize, origin: (f64, f64), text: &mut String| {
        let _ = writeln!(text, "o {name}");
        for z in 0..=n {
            for x in 0..=n {
                let (fx, fz) = (origin.0 + x as f64 * 0.5, origin.1 + z as f64 * 0.5);
                let _ = writeln!(text, "v {fx:.4} {:.4} {fz:.4}", (fx * 0.3).sin() + (fz * 0.2).cos());
            }
        }
        let v = |x: usize, z: usize| base + z * (n + 1) + x;
        for z in 0..n {
            for x in 0..n {
                let _ = writeln!(text, "f {} {} {}", v(x, z), v(x + 1, z), v(x + 1, z + 1));
                let _ = writeln!(text, "f {} {} {}", v(x, z), v(x + 1, z + 1), v(x, z + 1));
            }
        }
        base += (n + 1) * (n + 1);
        triangles += 2 * n * n;
    };
    for i in 0..100 {
        grid(
            &format!("tile{i}"),
            64,
            ((i % 10) as f64 * 40.0, (i / 10) as f64 * 40.0),
            &mut text,
        );
    }
    grid("terrain", 316, (-200.0, -200.0), &mut text);
    (text, triangles)
}
