//! `swr`'s occlusion buffer: occluder triangles rasterised on the CPU,
//! conservatively, into a low-resolution depth buffer of cells; a pyramid
//! of the buffer's farthest depths; and the test of a box against it.
//! Screen positions are framebuffer pixels (x right, y down); depth is
//! reverse-Z (`near / distance`, 0 = nothing drawn).
//!
//! Why it is conservative. A box is hidden when its nearest depth lies
//! behind the farthest depth the buffer holds over the cells its pixels
//! fall in. That is safe if, at every pixel centre a cell holds, the
//! occluders drawn this frame are no farther than the cell's depth. The
//! GPU draws a triangle whose corners it placed within some error of ours
//! (sub-pixel snapping, [`VERTEX_ERROR`]; f32 vertices,
//! [`ScreenTriangle::error`]), so at a centre it covers it may draw the
//! depth of any point that near the centre. So a triangle writes a cell
//! only where it covers every pixel centre the cell holds (not merely the
//! cell's middle) by twice that error, and it writes the farthest depth it
//! reaches over the centres' rectangle widened by that error (depth is
//! affine across a triangle on screen, so the least over the widened
//! rectangle's corners), moved farther by the GPU's depth rounding
//! ([`DEPTH_MARGIN`]). A cell keeps the nearest such depth of the triangles
//! covering it. A pyramid level keeps the least of the 2×2 texels below it.
//!
//! The GPU must also draw every fragment of an occluder the buffer counts:
//! the scene's fragment stage discards only fragments nearer than the
//! object's box (`FragmentLimit`, gpu/conservative.rs), and an occluder's
//! triangles lie within its box (the box is its mesh's bounds, placed).

use glam::DVec3;

use crate::gpu::Resolution;

/// Pixels the GPU may place a triangle's corner from where the CPU
/// projects it, on each axis, besides a triangle's own
/// [`ScreenTriangle::error`]: twice the largest sub-pixel snap Vulkan
/// allows (1/32).
const VERTEX_ERROR: f64 = 1.0 / 16.0;

/// A cell's depth is moved farther by this fraction, and by
/// [`DEPTH_ABSOLUTE`], than the triangle's exact depth: the GPU
/// interpolates depth in f32, and GL keeps only absolute precision of it
/// (gpu/conservative.rs, rule 1); both apply on every backend.
const DEPTH_MARGIN: f64 = 1.0 / (1u32 << 18) as f64;
const DEPTH_ABSOLUTE: f64 = 1.0 / (1u32 << 21) as f64;

/// Texels across a box's rectangle may span at the pyramid level it is
/// read at.
const TEST_SPAN: u32 = 8;

/// An occluder triangle on screen: per corner its pixel position (x, y)
/// and depth (z), and how far beyond [`VERTEX_ERROR`] the GPU's f32 vertex
/// transform may place its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenTriangle {
    pub corners: [DVec3; 3],
    pub error: VertexError,
}

/// How far the GPU may place a triangle's corners from the CPU's
/// projection: `pixels` on each axis, and `depth` as a fraction of their
/// depth.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexError {
    pub pixels: f64,
    pub depth: f64,
}

/// One level of the buffer's pyramid.
struct Level {
    width: u32,
    height: u32,
    depth: Vec<f32>,
}

pub struct OcclusionBuffer {
    target: Resolution,
    /// Per column of cells, the first and last pixel centre it holds (x);
    /// per row likewise (y).
    columns: Vec<[f64; 2]>,
    rows: Vec<[f64; 2]>,
    /// Level 0 holds the cells; each further level halves them (rounding
    /// up) down to one texel.
    levels: Vec<Level>,
    /// Breaks the rule above on purpose, for the test that sees the error
    /// meter catch it: a cell takes a triangle's depth at its middle
    /// wherever the triangle covers the middle, as a plain rasteriser does.
    #[cfg(test)]
    pub(super) careless: bool,
}

/// The pixels cell `c` of `cells` along a side of `pixels` holds: those
/// whose index maps to it by `⌊p · cells / pixels⌋`, as
/// [`OcclusionBuffer::farthest_over`] maps them.
fn held_pixels(c: u32, cells: u32, pixels: u32) -> [u32; 2] {
    let first = (u64::from(c) * u64::from(pixels)).div_ceil(u64::from(cells));
    let end = (u64::from(c + 1) * u64::from(pixels)).div_ceil(u64::from(cells));
    [first as u32, end as u32 - 1]
}

/// `cells` along a side of `pixels`, as `pixel` maps into them.
fn cell_of(pixel: u32, cells: u32, pixels: u32) -> u32 {
    (u64::from(pixel) * u64::from(cells) / u64::from(pixels)) as u32
}

impl OcclusionBuffer {
    /// A buffer of `cells` (at most the target's size on each side) over a
    /// target of `target` pixels.
    pub fn new(target: Resolution, cells: Resolution) -> OcclusionBuffer {
        let (width, height) = (cells.width.min(target.width), cells.height.min(target.height));
        let centres = |n: u32, pixels: u32| {
            (0..n)
                .map(|c| held_pixels(c, n, pixels).map(|p| f64::from(p) + 0.5))
                .collect()
        };
        let mut levels = Vec::new();
        let (mut w, mut h) = (width, height);
        loop {
            levels.push(Level {
                width: w,
                height: h,
                depth: vec![0.0; (w * h) as usize],
            });
            if w == 1 && h == 1 {
                break;
            }
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
        }
        OcclusionBuffer {
            target,
            columns: centres(width, target.width),
            rows: centres(height, target.height),
            levels,
            #[cfg(test)]
            careless: false,
        }
    }

    /// The render size it was made for.
    pub fn target(&self) -> Resolution {
        self.target
    }

    /// The buffer's size in cells.
    pub fn cells(&self) -> Resolution {
        Resolution {
            width: self.levels[0].width,
            height: self.levels[0].height,
        }
    }

    /// Every cell's depth, row by row.
    #[cfg(test)]
    pub fn depths(&self) -> &[f32] {
        &self.levels[0].depth
    }

    /// Forgets every occluder.
    pub fn clear(&mut self) {
        self.levels[0].depth.fill(0.0);
    }

    /// Writes `triangle` into the cells it covers (see the module above);
    /// returns how many it wrote.
    pub fn rasterise(&mut self, triangle: &ScreenTriangle) -> u32 {
        let [a, b, c] = triangle.corners;
        let slack = VERTEX_ERROR + triangle.error.pixels;
        let cover = 2.0 * slack;
        // Twice the triangle's area. A triangle too small to hold a disc of
        // radius `cover` (3√3 · cover² for the equilateral, the roomiest)
        // covers no centre by that much.
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if !area.is_finite() || area.abs() / 2.0 < 3.0 * 3f64.sqrt() * cover * cover {
            return 0;
        }
        // Inward edge functions, scaled to distances in pixels: a point is
        // inside by `cover` when every one is at least that.
        let edges = [(a, b), (b, c), (c, a)].map(|(p, q)| {
            let (dx, dy) = (q.x - p.x, q.y - p.y);
            let s = area.signum() / dx.hypot(dy);
            // inside(x, y) = s · ((q − p) × ((x, y) − p))
            [-dy * s, dx * s, (dy * p.x - dx * p.y) * s]
        });
        // The depth plane z = α x + β y + γ through the three corners.
        let alpha = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) / area;
        let beta = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / area;
        let depth_at = |x: f64, y: f64| a.z + alpha * (x - a.x) + beta * (y - a.y);
        let cells = self.cells();
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        let column_range = cell_range(lo.x, hi.x, cells.width, self.target.width);
        let row_range = cell_range(lo.y, hi.y, cells.height, self.target.height);
        let mut written = 0;
        let base = &mut self.levels[0];
        for row in row_range {
            let [y0, y1] = self.rows[row as usize];
            let index = |column: u32| (row * cells.width + column) as usize;
            #[cfg(test)]
            if self.careless {
                for column in column_range.clone() {
                    let [x0, x1] = self.columns[column as usize];
                    let (x, y) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
                    if edges.iter().all(|e| e[0] * x + e[1] * y + e[2] >= 0.0) {
                        let cell = &mut base.depth[index(column)];
                        *cell = cell.max(depth_at(x, y) as f32);
                        written += 1;
                    }
                }
                continue;
            }
            // The x every edge keeps inside by `cover` on both rows of
            // centres (edges are linear, so both rows at both ends of an x
            // range bound the whole rectangle).
            let (mut from, mut to) = (f64::NEG_INFINITY, f64::INFINITY);
            for [ex, ey, ec] in edges {
                let needed = |y: f64| cover - ey * y - ec;
                let (n0, n1) = (needed(y0), needed(y1));
                if ex > 0.0 {
                    from = from.max(n0.max(n1) / ex);
                } else if ex < 0.0 {
                    to = to.min(n0.max(n1) / ex);
                } else if n0.max(n1) > 0.0 {
                    to = f64::NEG_INFINITY;
                }
            }
            // Nothing admitted (a NaN admits nothing either).
            if from.is_nan() || to.is_nan() || from > to {
                continue;
            }
            // The columns of the triangle's span whose centres all lie in
            // [from, to].
            let (start, stop) = (*column_range.start(), *column_range.end() + 1);
            let span = &self.columns[start as usize..stop as usize];
            let first = start + span.partition_point(|&[x0, _]| x0 < from) as u32;
            let end = start + span.partition_point(|&[_, x1]| x1 <= to) as u32;
            for column in first..end {
                let [x0, x1] = self.columns[column as usize];
                // The GPU may draw the depth of any point within `slack` of
                // a centre: the least over the widened rectangle, at the
                // corner the plane falls towards.
                let x = if alpha > 0.0 { x0 - slack } else { x1 + slack };
                let y = if beta > 0.0 { y0 - slack } else { y1 + slack };
                let depth = depth_at(x, y) * (1.0 - DEPTH_MARGIN - triangle.error.depth) - DEPTH_ABSOLUTE;
                if depth <= 0.0 {
                    continue;
                }
                let cell = &mut base.depth[index(column)];
                *cell = cell.max(f32_at_most(depth));
                written += 1;
            }
        }
        written
    }

    /// Builds the pyramid over the cells written since [`Self::clear`].
    pub fn build_pyramid(&mut self) {
        for k in 1..self.levels.len() {
            let (below, above) = self.levels.split_at_mut(k);
            let (below, level) = (&below[k - 1], &mut above[0]);
            for y in 0..level.height {
                for x in 0..level.width {
                    let mut farthest = f32::INFINITY;
                    for by in 2 * y..(2 * y + 2).min(below.height) {
                        for bx in 2 * x..(2 * x + 2).min(below.width) {
                            farthest = farthest.min(below.depth[(by * below.width + bx) as usize]);
                        }
                    }
                    level.depth[(y * level.width + x) as usize] = farthest;
                }
            }
        }
    }

    /// The farthest depth the occluders may have at any of the pixels
    /// `first` to `last` (x, y, inclusive): the least over the cells that
    /// hold them, read at the finest pyramid level where they span at most
    /// [`TEST_SPAN`] texels across.
    pub fn farthest_over(&self, first: [u32; 2], last: [u32; 2]) -> f32 {
        debug_assert!(first[0] <= last[0] && first[1] <= last[1], "{first:?} to {last:?}");
        let cells = self.cells();
        let (x0, x1) = (
            cell_of(first[0], cells.width, self.target.width),
            cell_of(last[0], cells.width, self.target.width),
        );
        let (y0, y1) = (
            cell_of(first[1], cells.height, self.target.height),
            cell_of(last[1], cells.height, self.target.height),
        );
        let k = (0..self.levels.len())
            .find(|&k| (x1 >> k) - (x0 >> k) < TEST_SPAN && (y1 >> k) - (y0 >> k) < TEST_SPAN)
            .unwrap_or(self.levels.len() - 1);
        let level = &self.levels[k];
        let mut farthest = f32::INFINITY;
        for y in y0 >> k..=y1 >> k {
            for x in x0 >> k..=x1 >> k {
                farthest = farthest.min(level.depth[(y * level.width + x) as usize]);
            }
        }
        farthest
    }
}

/// The cells along a side whose pixel centres may lie in [lo, hi] (pixel
/// coordinates), clamped to the side.
fn cell_range(lo: f64, hi: f64, cells: u32, pixels: u32) -> std::ops::RangeInclusive<u32> {
    let pixel = |v: f64| v.floor().clamp(0.0, f64::from(pixels - 1)) as u32;
    cell_of(pixel(lo), cells, pixels)..=cell_of(pixel(hi), cells, pixels)
}

/// The largest f32 at most `v` (a plain cast may round up, nearer).
fn f32_at_most(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) > v { f.next_down() } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::Rng;

    /// The nearest depth (greatest) of `triangles` at point (x, y), by
    /// barycentric coordinates; 0 where none covers it.
    fn nearest_at(triangles: &[ScreenTriangle], x: f64, y: f64) -> f64 {
        let mut nearest = 0.0f64;
        for &ScreenTriangle { corners: [a, b, c], .. } in triangles {
            let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            let wa = ((b.x - x) * (c.y - y) - (b.y - y) * (c.x - x)) / area;
            let wb = ((c.x - x) * (a.y - y) - (c.y - y) * (a.x - x)) / area;
            let wc = 1.0 - wa - wb;
            if wa >= 0.0 && wb >= 0.0 && wc >= 0.0 {
                nearest = nearest.max(wa * a.z + wb * b.z + wc * c.z);
            }
        }
        nearest
    }

    fn random_triangles(rng: &mut Rng, size: Resolution, count: usize) -> Vec<ScreenTriangle> {
        let (w, h) = (f64::from(size.width), f64::from(size.height));
        (0..count)
            .map(|_| {
                // Sizes from a fraction of a pixel to beyond the screen.
                let centre = DVec3::new(rng.range(-0.2 * w, 1.2 * w), rng.range(-0.2 * h, 1.2 * h), 0.0);
                let reach = rng.range(0.5, 0.8 * w.max(h));
                ScreenTriangle {
                    corners: [0, 1, 2].map(|_| {
                        let offset = DVec3::new(rng.range(-reach, reach), rng.range(-reach, reach), 0.0);
                        (centre + offset).with_z(rng.range(1e-4, 0.9))
                    }),
                    error: VertexError::default(),
                }
            })
            .collect()
    }

    #[test]
    fn a_cell_holds_no_depth_nearer_than_the_triangles_as_the_gpu_may_draw_them_at_any_pixel_centre_it_holds() {
        let mut rng = Rng::new(21);
        let cases = [
            ((801, 599), (256, 192)),
            ((160, 120), (160, 120)),
            ((37, 5), (10, 3)),
            ((1, 1), (1, 1)),
            ((640, 480), (97, 61)),
        ];
        let mut written = 0;
        for ((tw, th), (cw, ch)) in cases {
            let target = Resolution { width: tw, height: th };
            let mut buffer = OcclusionBuffer::new(target, Resolution { width: cw, height: ch });
            let triangles = random_triangles(&mut rng, target, 40);
            for t in &triangles {
                written += buffer.rasterise(t);
            }
            // The triangles as the GPU may place them: every corner moved
            // by up to the snap bound on each axis, at the extremes.
            let triangles: Vec<ScreenTriangle> = triangles
                .iter()
                .map(|t| ScreenTriangle {
                    corners: t.corners.map(|c| {
                        let mut shift = || {
                            if rng.range(0.0, 1.0) < 0.5 {
                                -VERTEX_ERROR
                            } else {
                                VERTEX_ERROR
                            }
                        };
                        c + DVec3::new(shift(), shift(), 0.0)
                    }),
                    ..*t
                })
                .collect();
            // Every pixel, with the cell a box test reads for it (written
            // out here, not taken from the code under test).
            let cells = buffer.cells();
            for py in 0..th {
                for px in 0..tw {
                    let cx = u64::from(px) * u64::from(cells.width) / u64::from(tw);
                    let cy = u64::from(py) * u64::from(cells.height) / u64::from(th);
                    let depth = f64::from(buffer.depths()[(cy * u64::from(cells.width) + cx) as usize]);
                    if depth == 0.0 {
                        continue;
                    }
                    let drawn = nearest_at(&triangles, f64::from(px) + 0.5, f64::from(py) + 0.5);
                    assert!(
                        depth <= drawn,
                        "{tw}x{th} in {cw}x{ch}: cell ({cx}, {cy}) holds {depth}, pixel ({px}, {py}) shows {drawn}"
                    );
                }
            }
        }
        assert!(written > 1000, "the triangles cover cells ({written})");
    }

    #[test]
    fn the_pyramid_never_reports_a_depth_nearer_than_a_cell_the_pixels_fall_in() {
        let mut rng = Rng::new(22);
        let target = Resolution {
            width: 801,
            height: 599,
        };
        let mut buffer = OcclusionBuffer::new(target, Resolution { width: 203, height: 97 });
        for t in random_triangles(&mut rng, target, 60) {
            buffer.rasterise(&t);
        }
        buffer.build_pyramid();
        let cells = buffer.cells();
        for _ in 0..2000 {
            let (a, b) = (rng.range(0.0, 801.0) as u32, rng.range(0.0, 801.0) as u32);
            let (c, d) = (rng.range(0.0, 599.0) as u32, rng.range(0.0, 599.0) as u32);
            let (first, last) = ([a.min(b), c.min(d)], [a.max(b), c.max(d)]);
            let farthest = buffer.farthest_over(first, last);
            for py in first[1]..=last[1] {
                let cy = cell_of(py, cells.height, target.height);
                for px in first[0]..=last[0] {
                    let cx = cell_of(px, cells.width, target.width);
                    let cell = buffer.depths()[(cy * cells.width + cx) as usize];
                    assert!(
                        farthest <= cell,
                        "{first:?}..{last:?}: {farthest} over cell ({cx}, {cy}) of {cell}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_triangle_over_the_whole_screen_fills_every_cell_with_its_farthest_depth() {
        let target = Resolution { width: 64, height: 48 };
        let mut buffer = OcclusionBuffer::new(target, Resolution { width: 16, height: 12 });
        // A plane leaning in x: depth 0.5 at x = 0, 0.3 at x = 64.
        let at = |x: f64, y: f64| DVec3::new(x, y, 0.5 - 0.2 * x / 64.0);
        let whole = ScreenTriangle {
            corners: [at(-100.0, -100.0), at(300.0, -100.0), at(-100.0, 300.0)],
            error: VertexError::default(),
        };
        assert_eq!(buffer.rasterise(&whole), 192);
        // Column 0 holds pixels 0..=3, centres 0.5 to 3.5: its farthest is
        // where the GPU may sample beside 3.5.
        let x = 3.5 + VERTEX_ERROR;
        let expected = (0.5 - 0.2 * x / 64.0) * (1.0 - DEPTH_MARGIN) - DEPTH_ABSOLUTE;
        assert_eq!(buffer.depths()[0], f32_at_most(expected));
        assert!(f64::from(buffer.depths()[0]) <= expected);
    }
}
