//! The Occupancy Map of paper 003 §3: a low-resolution bitmap of the screen,
//! one bit per cell, with two questions asked of screen rectangles: "is any
//! cell under this rectangle empty?" and "mark this rectangle".
//!
//! Rows are stored as 64-bit words, so both operations touch one word per
//! 64 cells of a row. Rectangles come from [`ScreenRect::of_box`], which is
//! conservative: it always covers every pixel the box can touch.

use glam::DVec3;

use crate::bounds::Aabb;
use crate::camera::Camera;

/// Cells `x0..x1` × `y0..y1` (half-open); empty when `x0 == x1` or `y0 == y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScreenRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl ScreenRect {
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    /// Whether the two rectangles share a cell.
    pub fn overlaps(&self, other: &ScreenRect) -> bool {
        !self.is_empty()
            && !other.is_empty()
            && self.x0 < other.x1
            && other.x0 < self.x1
            && self.y0 < other.y1
            && other.y0 < self.y1
    }

    /// The cells the projection of `bounds` may touch on a `cols`×`rows`
    /// grid over the viewport, rounded outward. A box with a corner on or
    /// behind the near plane covers the whole screen: its projection is
    /// unbounded.
    pub fn of_box(bounds: &Aabb, camera: &Camera, cols: u32, rows: u32) -> ScreenRect {
        let whole = ScreenRect {
            x0: 0,
            y0: 0,
            x1: cols,
            y1: rows,
        };
        let view = camera.view_rotation();
        let f = 1.0 / (camera.fov_y / 2.0).tan();
        let (mut lo_x, mut lo_y, mut hi_x, mut hi_y) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for corner in bounds.corners() {
            let v: DVec3 = view * (corner - camera.eye);
            let depth = -v.z;
            if depth <= camera.near {
                return whole;
            }
            // Normalised device coordinates, then cells with y down.
            let x = (v.x * f / camera.aspect / depth + 1.0) * 0.5 * f64::from(cols);
            let y = (1.0 - v.y * f / depth) * 0.5 * f64::from(rows);
            lo_x = lo_x.min(x);
            hi_x = hi_x.max(x);
            lo_y = lo_y.min(y);
            hi_y = hi_y.max(y);
        }
        let clamp = |v: f64, n: u32| v.clamp(0.0, f64::from(n)) as u32;
        // Outward: floor the low edge, ceil the high edge, with slack where
        // rounding error could reach a neighbour. Off screen gives an empty
        // rectangle.
        ScreenRect {
            x0: clamp((lo_x - RECT_SLACK).floor(), cols),
            y0: clamp((lo_y - RECT_SLACK).floor(), rows),
            x1: clamp((hi_x + RECT_SLACK).ceil(), cols),
            y1: clamp((hi_y + RECT_SLACK).ceil(), rows),
        }
    }
}

/// Cells of slack on each side of a projected rectangle: the GPU rasterises
/// in f32, this projection is f64; 1e-3 cells is far above their difference
/// and far below a cell.
const RECT_SLACK: f64 = 1e-3;

pub struct OccupancyMap {
    cols: u32,
    rows: u32,
    words_per_row: usize,
    bits: Vec<u64>,
}

impl OccupancyMap {
    pub fn new(cols: u32, rows: u32) -> Self {
        let words_per_row = cols.div_ceil(64) as usize;
        OccupancyMap {
            cols,
            rows,
            words_per_row,
            bits: vec![0; words_per_row * rows as usize],
        }
    }

    pub fn cols(&self) -> u32 {
        self.cols
    }

    pub fn rows(&self) -> u32 {
        self.rows
    }

    pub fn clear(&mut self) {
        self.bits.fill(0);
    }

    /// Whether any cell under `rect` is unset. An empty rectangle has none.
    pub fn any_empty(&self, rect: &ScreenRect) -> bool {
        !rect.is_empty()
            && (rect.y0..rect.y1).any(|y| {
                let row = &self.bits[y as usize * self.words_per_row..];
                words(rect.x0, rect.x1).any(|(w, mask)| row[w] & mask != mask)
            })
    }

    /// Sets every cell under `rect`.
    pub fn mark(&mut self, rect: &ScreenRect) {
        if rect.is_empty() {
            return;
        }
        for y in rect.y0..rect.y1 {
            let row = &mut self.bits[y as usize * self.words_per_row..];
            for (w, mask) in words(rect.x0, rect.x1) {
                row[w] |= mask;
            }
        }
    }
}

/// The words of a row that cells `x0..x1` (non-empty) fall in, each with the
/// mask of those cells.
fn words(x0: u32, x1: u32) -> impl Iterator<Item = (usize, u64)> {
    let (first, last) = ((x0 / 64) as usize, ((x1 - 1) / 64) as usize);
    (first..=last).map(move |w| {
        let lo = if w == first { x0 % 64 } else { 0 };
        let hi = if w == last { (x1 - 1) % 64 } else { 63 };
        // Bits lo..=hi.
        let mask = (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
        (w, mask)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::look_rotation;

    /// Brute force: one bool per cell.
    struct Reference {
        cols: u32,
        cells: Vec<bool>,
    }

    impl Reference {
        fn any_empty(&self, r: &ScreenRect) -> bool {
            (r.y0..r.y1).any(|y| (r.x0..r.x1).any(|x| !self.cells[(y * self.cols + x) as usize]))
        }
        fn mark(&mut self, r: &ScreenRect) {
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    self.cells[(y * self.cols + x) as usize] = true;
                }
            }
        }
    }

    #[test]
    fn word_wide_operations_match_a_per_cell_reference() {
        // 150 columns: three words per row, the last one partial.
        let (cols, rows) = (150, 37);
        let mut om = OccupancyMap::new(cols, rows);
        let mut reference = Reference {
            cols,
            cells: vec![false; (cols * rows) as usize],
        };
        let mut rng = crate::rng::Rng::new(3);
        let mut next = |n: u32| rng.int(0, n - 1);
        for round in 0..4000 {
            let (x0, y0) = (next(cols), next(rows));
            let r = ScreenRect {
                x0,
                y0,
                x1: (x0 + next(90)).min(cols),
                y1: (y0 + next(12)).min(rows),
            };
            assert_eq!(om.any_empty(&r), reference.any_empty(&r), "round {round}: {r:?}");
            if next(3) == 0 {
                om.mark(&r);
                reference.mark(&r);
            }
            if next(500) == 0 {
                om.clear();
                reference.cells.fill(false);
            }
        }
    }

    #[test]
    fn rectangles_overlap_only_when_they_share_a_cell() {
        let r = |x0, y0, x1, y1| ScreenRect { x0, y0, x1, y1 };
        let a = r(2, 2, 5, 5);
        assert!(a.overlaps(&r(4, 4, 8, 8)) && r(4, 4, 8, 8).overlaps(&a));
        assert!(a.overlaps(&r(3, 0, 4, 9)), "a bar across it");
        assert!(!a.overlaps(&r(5, 2, 7, 5)), "edge to edge: half-open cells");
        assert!(!a.overlaps(&r(2, 5, 5, 6)));
        assert!(!a.overlaps(&r(3, 3, 3, 4)), "an empty rectangle covers nothing");
    }

    #[test]
    fn edge_words_are_masked_exactly() {
        let mut om = OccupancyMap::new(128, 1);
        om.mark(&ScreenRect {
            x0: 63,
            y0: 0,
            x1: 65,
            y1: 1,
        });
        assert!(!om.any_empty(&ScreenRect {
            x0: 63,
            y0: 0,
            x1: 65,
            y1: 1
        }));
        assert!(om.any_empty(&ScreenRect {
            x0: 62,
            y0: 0,
            x1: 64,
            y1: 1
        }));
        assert!(om.any_empty(&ScreenRect {
            x0: 64,
            y0: 0,
            x1: 66,
            y1: 1
        }));
        om.mark(&ScreenRect {
            x0: 0,
            y0: 0,
            x1: 128,
            y1: 1,
        });
        assert!(!om.any_empty(&ScreenRect {
            x0: 0,
            y0: 0,
            x1: 128,
            y1: 1
        }));
        assert!(
            !om.any_empty(&ScreenRect {
                x0: 5,
                y0: 0,
                x1: 5,
                y1: 1
            }),
            "empty rect has no empty cell"
        );
    }

    fn camera() -> Camera {
        Camera {
            eye: DVec3::new(1e5, 2.0, -3e5),
            rotation: look_rotation(DVec3::new(0.2, -0.1, -1.0), DVec3::Y),
            fov_y: 60f64.to_radians(),
            near: 0.1,
            aspect: 4.0 / 3.0,
        }
    }

    #[test]
    fn projected_rectangles_cover_every_projected_point() {
        // Brute force: dense points of each box, projected through the same
        // matrices the GPU uses, must land inside the rectangle.
        let cam = camera();
        let (cols, rows) = (80u32, 60u32);
        let mvp = cam.projection() * glam::DMat4::from(cam.model_view(&glam::DAffine3::IDENTITY));
        let mut rng = crate::rng::Rng::new(11);
        let mut rand = || rng.range(0.0, 1.0);
        let forward = cam.forward();
        let mut checked = 0;
        for _ in 0..300 {
            let centre =
                cam.eye + forward * (2.0 + rand() * 60.0) + DVec3::new(rand() - 0.5, rand() - 0.5, rand() - 0.5) * 60.0;
            let half = DVec3::new(rand(), rand(), rand()) * 5.0;
            let b = Aabb::new(centre - half, centre + half);
            let r = ScreenRect::of_box(&b, &cam, cols, rows);
            for i in 0..=8 {
                for j in 0..=8 {
                    for k in 0..=8 {
                        let p = b.min + b.extent() * DVec3::new(i as f64, j as f64, k as f64) / 8.0;
                        let clip = mvp * p.extend(1.0);
                        if clip.w <= cam.near {
                            continue;
                        }
                        let (x, y) = (clip.x / clip.w, clip.y / clip.w);
                        if x.abs() > 1.0 || y.abs() > 1.0 {
                            continue;
                        }
                        let cx = ((x + 1.0) * 0.5 * f64::from(cols)).floor().min(f64::from(cols - 1)) as u32;
                        let cy = ((1.0 - y) * 0.5 * f64::from(rows)).floor().min(f64::from(rows - 1)) as u32;
                        assert!(
                            (r.x0..r.x1).contains(&cx) && (r.y0..r.y1).contains(&cy),
                            "point {p:?} in cell ({cx}, {cy}) outside {r:?}"
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 10_000, "only {checked} visible sample points");
    }

    #[test]
    fn boxes_reaching_the_near_plane_cover_the_whole_screen() {
        let cam = camera();
        let around_eye = Aabb::new(cam.eye - DVec3::ONE, cam.eye + DVec3::ONE);
        let whole = ScreenRect {
            x0: 0,
            y0: 0,
            x1: 64,
            y1: 48,
        };
        assert_eq!(ScreenRect::of_box(&around_eye, &cam, 64, 48), whole);
        // Behind the camera, partly: one corner behind the near plane.
        let f = cam.forward();
        let crossing = Aabb::from_points([cam.eye + f * 0.05, cam.eye + f * 10.0 + DVec3::splat(0.5)]);
        assert_eq!(ScreenRect::of_box(&crossing, &cam, 64, 48), whole);
        // Far to the side: off screen, an empty rectangle.
        let right = cam.rotation * DVec3::X;
        let off = Aabb::from_points([cam.eye + f * 10.0 + right * 100.0, cam.eye + f * 11.0 + right * 101.0]);
        assert!(ScreenRect::of_box(&off, &cam, 64, 48).is_empty());
    }
}
