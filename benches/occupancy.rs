//! Occupancy Map operations per second (paper 003 §3): `cargo bench --bench
//! occupancy`. Random rectangles of typical node sizes on maps of several
//! resolutions: lookups ("is any cell under this rectangle empty?"), marks,
//! and conservative projection of boxes to rectangles.

use std::hint::black_box;
use std::time::Instant;

use glam::DVec3;
use occlu::bounds::Aabb;
use occlu::camera::{Camera, look_rotation};
use occlu::cull::occupancy::{OccupancyMap, ScreenRect};

const OPERATIONS: usize = 2_000_000;

fn main() {
    for (cols, rows) in [(32, 24), (64, 48), (160, 120), (400, 300)] {
        let rects = random_rects(cols, rows, 4096);
        let mut om = OccupancyMap::new(cols, rows);
        // Half the map marked, so lookups neither stop at once nor scan all.
        for r in rects.iter().step_by(2).take(40) {
            om.mark(r);
        }
        let start = Instant::now();
        let mut empty = 0usize;
        for i in 0..OPERATIONS {
            empty += usize::from(om.any_empty(black_box(&rects[i % rects.len()])));
        }
        let lookups = OPERATIONS as f64 / start.elapsed().as_secs_f64();
        let start = Instant::now();
        for i in 0..OPERATIONS {
            if i % 256 == 0 {
                om.clear();
            }
            om.mark(black_box(&rects[i % rects.len()]));
        }
        let marks = OPERATIONS as f64 / start.elapsed().as_secs_f64();
        println!(
            "{cols:>3}x{rows:<3} lookups {:7.1} M/s ({:.0}% found an empty cell)   marks {:7.1} M/s",
            lookups / 1e6,
            100.0 * empty as f64 / OPERATIONS as f64,
            marks / 1e6
        );
    }
    let camera = Camera {
        eye: DVec3::new(10.0, 1.7, 10.0),
        rotation: look_rotation(DVec3::new(1.0, -0.05, 0.3), DVec3::Y),
        fov_y: 60f64.to_radians(),
        near: 0.1,
        aspect: 4.0 / 3.0,
    };
    let boxes: Vec<Aabb> = (0..4096)
        .map(|i| {
            let c = DVec3::new(
                20.0 + (i % 64) as f64 * 3.0,
                (i % 7) as f64,
                (i / 64) as f64 * 3.0 - 90.0,
            );
            Aabb::new(c, c + DVec3::new(2.0, 3.0, 2.0))
        })
        .collect();
    let start = Instant::now();
    let mut cells = 0u64;
    for i in 0..OPERATIONS {
        let r = ScreenRect::of_box(black_box(&boxes[i % boxes.len()]), &camera, 64, 48);
        cells += u64::from(r.x1 - r.x0);
    }
    black_box(cells);
    println!(
        "box → screen rectangle (8 corners projected)  {:7.1} M/s",
        OPERATIONS as f64 / start.elapsed().as_secs_f64() / 1e6
    );
}

/// Rectangles of 1–25% of the map's width and height, seeded.
fn random_rects(cols: u32, rows: u32, n: usize) -> Vec<ScreenRect> {
    let mut rng = occlu::rng::Rng::new(99);
    let mut next = |m: u32| rng.int(0, m.max(1) - 1);
    (0..n)
        .map(|_| {
            let (w, h) = (1 + next(cols / 4), 1 + next(rows / 4));
            let (x0, y0) = (next(cols - w + 1), next(rows - h + 1));
            ScreenRect {
                x0,
                y0,
                x1: x0 + w,
                y1: y0 + h,
            }
        })
        .collect()
}
