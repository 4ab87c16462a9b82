//! `swr`'s occlusion buffer: occluder triangles rasterised on the CPU,
//! conservatively, into a low-resolution depth buffer of cells; a pyramid
//! of the buffer's farthest depths; and the test of a box against it.
//! Screen positions are framebuffer pixels (x right, y down); depth is
//! reverse-Z (`near / distance`, 0 = nothing drawn).
//!
//! Why it is conservative. A box is hidden when, at every pixel centre its
//! rectangle covers, it lies behind what the buffer holds there (a cell's
//! depth, or its plane; [`OcclusionBuffer::hides`]) or its pixel ray misses
//! it. That is safe if, at every pixel centre a cell holds, the occluder
//! it took its depth from is drawn this frame (the mode's step 5) no
//! farther than the cell's depth and its plane. The
//! GPU draws a triangle whose corners it placed within some error of ours
//! (sub-pixel snapping, [`VERTEX_ERROR`]; f32 vertices,
//! [`VertexError`]), so at a centre it covers it may draw the depth of any
//! point that near the centre. An occluder is a triangle, or two triangles
//! of one mesh sharing an edge taken as one quad ([`ScreenPolygon`]). It
//! writes a cell only where every pixel centre the cell holds (not merely
//! the cell's middle) lies inside its outline by twice that error, so the
//! disc of that radius round the centre lies inside the shape (for a quad,
//! inside every edge's line puts a point in the quad: that region is the
//! quad's kernel). The GPU's placement moves every point of the shape by
//! at most the error, continuously across a shared edge, and a map that
//! moves each point of a disc by less than its radius still covers the
//! disc's centre and the points round it; the GPU draws every pixel centre
//! inside the triangles it placed, one of the two where a centre lies on
//! their shared edge (the fill rule). So the centre is drawn. Its depth
//! is that of a point of either triangle within that error of it, which
//! the cell's plane lies below: the first triangle's plane, lowered by its
//! greatest change within the error, and further by as much as it ever
//! lies above the second's plane over the quad, then moved farther by the
//! GPU's depth rounding ([`DEPTH_MARGIN`]). The cell's depth is that
//! plane's least over its centres (depth is affine across a triangle on
//! screen, so at a corner of their rectangle). A cell keeps the nearest
//! such depth of the occluders covering it, with its plane. A pyramid level
//! keeps the least of the 2×2 texels below it. Both halves of a quad must
//! be at least [`QUAD_HALF_HEIGHT`] covers high over their shared edge: the
//! depth margins bound f32 interpolation over triangles, not over slivers
//! (gpu/conservative.rs, rule 2), and a centre inside a quad may lie in
//! either half.
//!
//! The GPU must also draw every fragment of an occluder the buffer counts:
//! the scene's fragment stage discards only fragments nearer than the
//! object's box (`FragmentLimit`, gpu/conservative.rs), and an occluder's
//! triangles lie within its box (the box is its mesh's bounds, placed).

use std::ops::Range;

use glam::{DVec2, DVec3};

use crate::gpu::{BoxPlanes, Resolution, ScreenPlane};

/// Pixels the GPU may place a triangle's corner from where the CPU
/// projects it, on each axis, besides a triangle's own
/// [`VertexError`]: twice the largest sub-pixel snap Vulkan
/// allows (1/32).
const VERTEX_ERROR: f64 = 1.0 / 16.0;

/// A cell's depth is moved farther by this fraction, and by
/// [`DEPTH_ABSOLUTE`], than the triangle's exact depth: the GPU
/// interpolates depth in f32, and GL keeps only absolute precision of it
/// (gpu/conservative.rs, rule 1); both apply on every backend.
const DEPTH_MARGIN: f64 = 1.0 / (1u32 << 18) as f64;
const DEPTH_ABSOLUTE: f64 = 1.0 / (1u32 << 21) as f64;

/// How high each triangle of a quad must stand over their shared edge, in
/// multiples of the cover, for the quad to be rasterised as one: at least
/// 0.375 pixel, so a corner's sub-pixel snap tilts the triangle's depth
/// plane by at most a twelfth of its rise across it, as for a triangle that
/// covers a centre by the cover on its own.
const QUAD_HALF_HEIGHT: f64 = 3.0;

/// Texels across a box's rectangle may span at the pyramid level it is
/// read at.
const TEST_SPAN: u32 = 8;

/// An occluder on screen: per corner its pixel position (x, y) and depth
/// (z). Three corners are a triangle; four are two triangles abc and acd
/// of one mesh that share the edge a–c, so the GPU draws them without a
/// gap (the fill rule gives each pixel centre on a shared edge to one of
/// them), and the buffer may take them as one quad: a triangle alone
/// leaves empty every cell along its edges, and a mesh of quads would
/// occlude nothing along their diagonals. With them, how far beyond
/// [`VERTEX_ERROR`] the GPU's f32 vertex transform may place the corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenPolygon {
    corners: [DVec3; 4],
    sides: usize,
    error: VertexError,
}

impl ScreenPolygon {
    pub fn triangle([a, b, c]: [DVec3; 3], error: VertexError) -> ScreenPolygon {
        ScreenPolygon {
            corners: [a, b, c, c],
            sides: 3,
            error,
        }
    }

    /// Triangles abc and acd, which share the edge a–c.
    pub fn quad(corners: [DVec3; 4], error: VertexError) -> ScreenPolygon {
        ScreenPolygon {
            corners,
            sides: 4,
            error,
        }
    }

    /// How far the GPU may place a corner from ours, in pixels on each axis.
    fn slack(&self) -> f64 {
        VERTEX_ERROR + self.error.pixels
    }

    /// A quad's two triangles, when it must be rasterised as them: folded
    /// on screen (both on one side of a–c; they cover less than the quad)
    /// or a half too thin (see the module's doc). Each alone is safe.
    fn halves_apart(&self) -> Option<[ScreenPolygon; 2]> {
        let [a, b, c, d] = self.corners;
        let (first, second) = (twice_area(a, b, c), twice_area(a, c, d));
        let least = QUAD_HALF_HEIGHT * 2.0 * self.slack() * (c - a).truncate().length();
        let whole = first * second > 0.0 && first.abs().min(second.abs()) >= least;
        (self.sides == 4 && !whole).then(|| [[a, b, c], [a, c, d]].map(|t| ScreenPolygon::triangle(t, self.error)))
    }

    /// Its outline's inward edge functions, scaled to distances in pixels
    /// (a point is inside by `cover` when every one is at least that); `None`
    /// when it is too small to hold a disc of radius `cover` (a triangle
    /// needs 3√3 · cover² of area, any shape π · cover²), so covers no centre
    /// by that much. Not for a quad to be rasterised as its halves.
    fn inward_edges(&self) -> Option<[[f64; 3]; 4]> {
        let [a, b, c, d] = self.corners;
        let area = twice_area(a, b, c) + if self.sides == 4 { twice_area(a, c, d) } else { 0.0 };
        let cover = 2.0 * self.slack();
        let disc_factor = if self.sides == 3 {
            3.0 * 3f64.sqrt()
        } else {
            std::f64::consts::PI
        };
        if !area.is_finite() || area.abs() / 2.0 < disc_factor * cover * cover {
            return None;
        }
        let mut edges = [[0.0; 3]; 4];
        for (k, edge) in edges.iter_mut().enumerate().take(self.sides) {
            let (p, q) = (self.corners[k], self.corners[(k + 1) % self.sides]);
            let (dx, dy) = (q.x - p.x, q.y - p.y);
            let s = area.signum() / (dx * dx + dy * dy).sqrt();
            // inside(x, y) = s · ((q − p) × ((x, y) − p))
            *edge = [-dy * s, dx * s, (dy * p.x - dx * p.y) * s];
        }
        Some(edges)
    }

    /// The depth plane through the first triangle's corners.
    fn first_plane(&self) -> ScreenPlane {
        let [a, b, c, _] = self.corners;
        plane_through([a, b, c])
    }

    /// What a cell it covers holds at each centre: the first triangle's
    /// plane lowered by its change within the slack, and for a quad until
    /// it lies below the second's wherever the GPU may draw either (within
    /// the slack of the corners' hull: the difference is affine, so at a
    /// corner; nothing for a flat quad), then moved farther by the depth
    /// margins (all affine).
    fn cell_plane(&self) -> ScreenPlane {
        let [a, _, c, d] = self.corners;
        let (first, slack) = (self.first_plane(), self.slack());
        let below_second = if self.sides == 4 {
            let second = plane_through([a, c, d]);
            let (dx, dy) = (first.per_x - second.per_x, first.per_y - second.per_y);
            let widest = self
                .corners
                .iter()
                .map(|p| first.at(p.x, p.y) - second.at(p.x, p.y))
                .fold(f64::NEG_INFINITY, f64::max);
            // A NaN stays one, and writes nothing.
            let below = widest + slack * (dx.abs() + dy.abs());
            if below < 0.0 { 0.0 } else { below }
        } else {
            0.0
        };
        let keep = 1.0 - DEPTH_MARGIN - self.error.depth;
        ScreenPlane {
            per_x: first.per_x * keep,
            per_y: first.per_y * keep,
            constant: (first.constant - slack * (first.per_x.abs() + first.per_y.abs()) - below_second) * keep
                - DEPTH_ABSOLUTE,
        }
    }
}

/// Twice the signed area of the screen triangle pqr: its sign is its
/// winding.
fn twice_area(p: DVec3, q: DVec3, r: DVec3) -> f64 {
    (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x)
}

/// The depth plane through the corners of screen triangle pqr.
fn plane_through([p, q, r]: [DVec3; 3]) -> ScreenPlane {
    let area = twice_area(p, q, r);
    let per_x = ((q.z - p.z) * (r.y - p.y) - (r.z - p.z) * (q.y - p.y)) / area;
    let per_y = ((r.z - p.z) * (q.x - p.x) - (q.z - p.z) * (r.x - p.x)) / area;
    ScreenPlane {
        per_x,
        per_y,
        constant: p.z - per_x * p.x - per_y * p.y,
    }
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
    /// The least distance between a cell's first and last pixel centre,
    /// across (x) and down (y): an outline narrower than that plus twice
    /// the cover holds no whole cell.
    least_held: DVec2,
    /// Level 0 holds the cells (each the least of its plane over its pixel
    /// centres); each further level halves them (rounding up) down to one
    /// texel.
    levels: Vec<Level>,
    /// Per cell, the depth it holds at each pixel centre: the plane of the
    /// occluder that wrote it, lowered by the GPU's placement and rounding
    /// ([`OcclusionBuffer::rasterise`]), so a box just behind a wall seen at
    /// a slant is hidden even where the wall's depth changes across the
    /// cell by more than the gap; meaningless where the cell holds no
    /// depth.
    planes: Vec<ScreenPlane>,
    /// Breaks the rule above on purpose, for the test that sees the error
    /// meter catch it: a cell takes a triangle's depth at its middle
    /// wherever the triangle covers the middle, as a plain rasteriser does
    /// (among the cells an occluder can cover whole, which the bounds
    /// check in [`OcclusionBuffer::rasterise`] leaves to it).
    #[cfg(test)]
    pub(super) careless: bool,
}

/// The pixels cell `c` of `cells` along a side of `pixels` holds: those
/// whose index maps to it by `⌊p · cells / pixels⌋`, as
/// [`OcclusionBuffer::hides`] maps them.
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
        let (columns, rows): (Vec<[f64; 2]>, Vec<[f64; 2]>) =
            (centres(width, target.width), centres(height, target.height));
        let least = |held: &[[f64; 2]]| {
            held.iter()
                .map(|[first, last]| last - first)
                .fold(f64::INFINITY, f64::min)
        };
        let least_held = DVec2::new(least(&columns), least(&rows));
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
            columns,
            rows,
            least_held,
            levels,
            planes: vec![ScreenPlane::default(); (width * height) as usize],
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

    /// Every cell's plane, row by row.
    #[cfg(test)]
    pub fn planes(&self) -> &[ScreenPlane] {
        &self.planes
    }

    /// Every cell's depth, row by row.
    pub fn depths(&self) -> &[f32] {
        &self.levels[0].depth
    }

    /// The depth the buffer vouches for at the pixel centre `(x, y)` of
    /// the target: its cell's depth, or its cell's plane there where that
    /// is nearer; 0 where the cell is empty.
    #[cfg(test)]
    pub fn vouched_at(&self, x: f64, y: f64) -> f64 {
        let cells = self.cells();
        let cell = |v: f64, cells: u32, pixels: u32| cell_of(v as u32, cells, pixels);
        let index = (cell(y, cells.height, self.target.height) * cells.width + cell(x, cells.width, self.target.width))
            as usize;
        let depth = f64::from(self.levels[0].depth[index]);
        if depth == 0.0 {
            0.0
        } else {
            depth.max(self.planes[index].at(x, y))
        }
    }

    /// Forgets every occluder.
    pub fn clear(&mut self) {
        self.levels[0].depth.fill(0.0);
    }

    /// Takes each cell of `other` (a buffer of the same size) that is
    /// nearer than this one's, with its plane: as if `other`'s occluders
    /// had been rasterised here after this one's.
    pub fn merge(&mut self, other: &OcclusionBuffer) {
        debug_assert_eq!(self.cells(), other.cells());
        let cells = self.levels[0].depth.iter_mut().zip(&mut self.planes);
        for ((depth, plane), (&theirs, their_plane)) in cells.zip(other.levels[0].depth.iter().zip(&other.planes)) {
            if theirs > *depth {
                *depth = theirs;
                *plane = *their_plane;
            }
        }
    }

    /// Writes `occluder` into the cells it covers (see the module above);
    /// returns how many it wrote.
    pub fn rasterise(&mut self, occluder: &ScreenPolygon) -> u32 {
        // Most occluder triangles are smaller than a cell on some axis (over
        // the default city, 99 % of them write nothing): rule those out
        // from their outline's bounds before any other work. A cell is
        // written only where its pixel centres lie inside by the cover, so
        // within the bounds shrunk by it on both axes; a quad's halves lie
        // within the quad's bounds.
        let cover = 2.0 * occluder.slack();
        let corners = &occluder.corners[..occluder.sides];
        let (lo, hi) = corners
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let (outline, least) = ((hi - lo).truncate(), self.least_held + 2.0 * cover);
        if outline.x < least.x || outline.y < least.y {
            return 0;
        }
        let cells = self.cells();
        let column_range = cell_range(lo.x, hi.x, cells.width, self.target.width);
        let row_range = cell_range(lo.y, hi.y, cells.height, self.target.height);
        let (columns, rows) = (
            centred_within(&self.columns, column_range.clone(), lo.x + cover, hi.x - cover),
            centred_within(&self.rows, row_range, lo.y + cover, hi.y - cover),
        );
        if columns.is_empty() || rows.is_empty() {
            return 0;
        }
        if let Some(halves) = occluder.halves_apart() {
            return halves.iter().map(|half| self.rasterise(half)).sum();
        }
        let Some(edges) = occluder.inward_edges() else {
            return 0;
        };
        let edges = &edges[..occluder.sides];
        // Made for the first cell within the outline (few occluders reach
        // one).
        let mut plane = None;
        let mut written = 0;
        let base = &mut self.levels[0];
        for row in rows {
            let [y0, y1] = self.rows[row as usize];
            let index = |column: u32| (row * cells.width + column) as usize;
            #[cfg(test)]
            if self.careless {
                for column in column_range.clone() {
                    let [x0, x1] = self.columns[column as usize];
                    let (x, y) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
                    if edges.iter().all(|e| e[0] * x + e[1] * y + e[2] >= 0.0) {
                        let first_plane = occluder.first_plane();
                        let depth = first_plane.at(x, y);
                        let cell = &mut base.depth[index(column)];
                        if f64::from(*cell) < depth {
                            *cell = depth as f32;
                            self.planes[index(column)] = first_plane;
                        }
                        written += 1;
                    }
                }
                continue;
            }
            // The x every edge keeps inside by `cover` on both rows of
            // centres (edges are linear, so both rows at both ends of an x
            // range bound the whole rectangle).
            let (mut from, mut to) = (f64::NEG_INFINITY, f64::INFINITY);
            for &[ex, ey, ec] in edges {
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
            for column in centred_within(&self.columns, columns.clone(), from, to) {
                let plane = *plane.get_or_insert_with(|| occluder.cell_plane());
                let farthest = plane.min_over(self.columns[column as usize], [y0, y1]);
                let cell = &mut base.depth[index(column)];
                // Compared as stored, so a cell keeps the first of occluders
                // that round alike (as `merge` keeps the earlier buffer's).
                // A NaN writes nothing.
                let depth = f32_at_most(farthest);
                if farthest.is_nan() || depth <= cell.max(0.0) {
                    continue;
                }
                *cell = depth;
                self.planes[index(column)] = plane;
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

    /// Whether the occluders hide a box over the pixels `first` to `last`
    /// (x, y, inclusive), whose depth is at most `nearest` anywhere and
    /// whose `planes` bound its depth at every pixel centre and tell where
    /// pixel rays miss it. The pixels' cells are read at the finest pyramid
    /// level where they span at most [`TEST_SPAN`] texels across; the box
    /// is hidden when, at each texel, it lies strictly behind the texel's
    /// farthest depth (by `nearest`, or else by its planes over the pixel
    /// centres the texel holds), or no ray through those centres meets it,
    /// or else this holds at each of the texel's children; at a cell, also
    /// when one of its planes lies behind the cell's plane at each centre.
    pub fn hides(&self, first: [u32; 2], last: [u32; 2], nearest: f64, planes: &BoxPlanes) -> bool {
        debug_assert!(first[0] <= last[0] && first[1] <= last[1], "{first:?} to {last:?}");
        let cells = self.cells();
        let query = BoxQuery {
            buffer: self,
            pixels: [first, last],
            columns: [
                cell_of(first[0], cells.width, self.target.width),
                cell_of(last[0], cells.width, self.target.width),
            ],
            rows: [
                cell_of(first[1], cells.height, self.target.height),
                cell_of(last[1], cells.height, self.target.height),
            ],
            nearest,
            planes,
        };
        let ([x0, x1], [y0, y1]) = (query.columns, query.rows);
        let k = (0..self.levels.len())
            .find(|&k| (x1 >> k) - (x0 >> k) < TEST_SPAN && (y1 >> k) - (y0 >> k) < TEST_SPAN)
            .unwrap_or(self.levels.len() - 1);
        query.hides_texels(k as u32, [x0 >> k, x1 >> k], [y0 >> k, y1 >> k])
    }
}

/// A box's test against the buffer ([`OcclusionBuffer::hides`]).
struct BoxQuery<'a> {
    buffer: &'a OcclusionBuffer,
    /// The first and last pixels (x, y) of the box's rectangle.
    pixels: [[u32; 2]; 2],
    /// The cells holding them: first and last column, first and last row.
    columns: [u32; 2],
    rows: [u32; 2],
    /// The box's nearest depth anywhere, raised.
    nearest: f64,
    planes: &'a BoxPlanes,
}

impl BoxQuery<'_> {
    /// Whether the box lies behind the texels `xs` × `ys` (first and last,
    /// inclusive) of level `k`, each in the box's cells.
    fn hides_texels(&self, k: u32, xs: [u32; 2], ys: [u32; 2]) -> bool {
        (ys[0]..=ys[1]).all(|y| (xs[0]..=xs[1]).all(|x| self.hides_texel(k, x, y)))
    }

    fn hides_texel(&self, k: u32, x: u32, y: u32) -> bool {
        let level = &self.buffer.levels[k as usize];
        let farthest = f64::from(level.depth[(y * level.width + x) as usize]);
        if self.nearest < farthest {
            return true;
        }
        // The texel's cells within the box's, along a side.
        let held = |t: u32, [first, last]: [u32; 2]| [(t << k).max(first), ((t + 1) << k).saturating_sub(1).min(last)];
        let [columns, rows] = [held(x, self.columns), held(y, self.rows)];
        // Their pixel centres within the box's pixels.
        let centres = |along: &[[f64; 2]], [from, to]: [u32; 2], axis: usize| {
            [
                along[from as usize][0].max(f64::from(self.pixels[0][axis]) + 0.5),
                along[to as usize][1].min(f64::from(self.pixels[1][axis]) + 0.5),
            ]
        };
        let (xs, ys) = (
            centres(&self.buffer.columns, columns, 0),
            centres(&self.buffer.rows, rows, 1),
        );
        // Each entry plane bounds the box's depth on its own, so the least
        // of them does; a NaN among them is passed over by `min`, and a NaN
        // result hides nothing (`<`, not `>=`), here and below.
        let over = self
            .planes
            .entries()
            .iter()
            .map(|p| p.max_over(xs, ys))
            .fold(f64::INFINITY, f64::min);
        if over < farthest || self.planes.missed_over(xs, ys) {
            return true;
        }
        if k > 0 {
            return self.hides_texels(k - 1, columns.map(|c| c >> (k - 1)), rows.map(|r| r >> (k - 1)));
        }
        // A cell: behind its plane by one of the box's (the box's depth is
        // at most the least of them), at every centre.
        let cell = self.buffer.planes[(y * level.width + x) as usize];
        farthest > 0.0
            && self
                .planes
                .entries()
                .iter()
                .any(|p| p.minus(&cell).max_over(xs, ys) < 0.0)
    }
}

/// The cells along a side whose pixel centres may lie in [lo, hi] (pixel
/// coordinates), clamped to the side.
fn cell_range(lo: f64, hi: f64, cells: u32, pixels: u32) -> Range<u32> {
    let pixel = |v: f64| v.floor().clamp(0.0, f64::from(pixels - 1)) as u32;
    cell_of(pixel(lo), cells, pixels)..cell_of(pixel(hi), cells, pixels) + 1
}

/// The cells of `range` (along a side whose cells hold the pixel centres
/// `centres`) whose centres all lie in [from, to]; none when `to` is NaN.
fn centred_within(centres: &[[f64; 2]], range: Range<u32>, from: f64, to: f64) -> Range<u32> {
    let start = range.start;
    let span = &centres[start as usize..range.end as usize];
    let first = start + span.partition_point(|&[first, _]| first < from) as u32;
    let end = start + span.partition_point(|&[_, last]| last <= to) as u32;
    first..end.max(first)
}

/// The largest f32 at most `v` (a plain cast may round up, nearer).
fn f32_at_most(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) > v { f.next_down() } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// The triangles an occluder stands for.
    fn triangles_of(occluder: &ScreenPolygon) -> Vec<[DVec3; 3]> {
        let [a, b, c, d] = occluder.corners;
        if occluder.sides == 3 {
            vec![[a, b, c]]
        } else {
            vec![[a, b, c], [a, c, d]]
        }
    }

    /// The nearest depth (greatest) of `triangles` at point (x, y), by
    /// barycentric coordinates; 0 where none covers it.
    fn nearest_at(triangles: &[[DVec3; 3]], x: f64, y: f64) -> f64 {
        let mut nearest = 0.0f64;
        for &[a, b, c] in triangles {
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

    /// Triangles and quads from a fraction of a pixel to beyond the screen;
    /// most quads are near parallelograms, some fold on screen (both
    /// triangles on one side of their shared edge) or bend (a reflex
    /// corner).
    fn random_occluders(rng: &mut Rng, size: Resolution, count: usize) -> Vec<ScreenPolygon> {
        let (w, h) = (f64::from(size.width), f64::from(size.height));
        (0..count)
            .map(|_| {
                let centre = DVec3::new(rng.range(-0.2 * w, 1.2 * w), rng.range(-0.2 * h, 1.2 * h), 0.0);
                let reach = rng.range(0.5, 0.8 * w.max(h));
                let mut corner = || {
                    let offset = DVec3::new(rng.range(-reach, reach), rng.range(-reach, reach), 0.0);
                    (centre + offset).with_z(rng.range(1e-4, 0.9))
                };
                let [a, b, c] = [corner(), corner(), corner()];
                let d = corner();
                let error = VertexError::default();
                match rng.range(0.0, 4.0) as u32 {
                    0 | 1 => ScreenPolygon::triangle([a, b, c], error),
                    2 => {
                        let opposite = a + c - b;
                        let d = opposite.lerp(d, 0.2).with_z(d.z);
                        ScreenPolygon::quad([a, b, c, d], error)
                    }
                    _ => ScreenPolygon::quad([a, b, c, d], error),
                }
            })
            .collect()
    }

    /// `occluder` as the GPU may place it: every corner moved by up to the
    /// snap bound on each axis, at the extremes (a shared corner moves
    /// once, for both triangles).
    fn as_the_gpu_may_place(occluder: &ScreenPolygon, rng: &mut Rng) -> ScreenPolygon {
        let mut shift = || {
            if rng.range(0.0, 1.0) < 0.5 {
                -VERTEX_ERROR
            } else {
                VERTEX_ERROR
            }
        };
        ScreenPolygon {
            corners: occluder.corners.map(|c| c + DVec3::new(shift(), shift(), 0.0)),
            ..*occluder
        }
    }

    #[test]
    fn a_cell_holds_no_depth_nearer_than_the_occluders_as_the_gpu_may_draw_them_at_any_pixel_centre_it_holds() {
        let mut rng = Rng::new(21);
        let cases = [
            ((801, 599), (256, 192)),
            ((160, 120), (160, 120)),
            ((37, 5), (10, 3)),
            ((1, 1), (1, 1)),
            ((640, 480), (97, 61)),
        ];
        let (mut written_by_quads, mut written) = (0, 0);
        for ((tw, th), (cw, ch)) in cases {
            let target = Resolution { width: tw, height: th };
            let mut buffer = OcclusionBuffer::new(target, Resolution { width: cw, height: ch });
            let occluders = random_occluders(&mut rng, target, 60);
            for o in &occluders {
                let cells = buffer.rasterise(o);
                written += cells;
                if o.sides == 4 {
                    written_by_quads += cells;
                }
            }
            let triangles: Vec<[DVec3; 3]> = occluders
                .iter()
                .flat_map(|o| triangles_of(&as_the_gpu_may_place(o, &mut rng)))
                .collect();
            // Every pixel, with the cell a box test reads for it (written
            // out here, not taken from the code under test).
            let cells = buffer.cells();
            for py in 0..th {
                for px in 0..tw {
                    let cx = u64::from(px) * u64::from(cells.width) / u64::from(tw);
                    let cy = u64::from(py) * u64::from(cells.height) / u64::from(th);
                    let cell = (cy * u64::from(cells.width) + cx) as usize;
                    let depth = f64::from(buffer.depths()[cell]);
                    if depth == 0.0 {
                        continue;
                    }
                    let (x, y) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
                    let drawn = nearest_at(&triangles, x, y);
                    let plane = buffer.planes[cell].at(x, y);
                    assert!(
                        depth <= plane && plane <= drawn,
                        "{tw}x{th} in {cw}x{ch}: cell ({cx}, {cy}) holds {depth}, its plane {plane} at pixel ({px}, {py}), which shows {drawn}"
                    );
                }
            }
        }
        assert!(written > 1000, "the occluders cover cells ({written})");
        assert!(written_by_quads > 500, "quads cover cells ({written_by_quads})");
    }

    #[test]
    fn a_quad_fills_the_cells_along_its_shared_edge_that_its_triangles_alone_leave_empty() {
        let target = Resolution { width: 64, height: 48 };
        let cells = Resolution { width: 16, height: 12 };
        let at = |x: f64, y: f64| DVec3::new(x, y, 0.5 - 0.2 * x / 64.0);
        // A screen-filling quad whose shared edge runs corner to corner.
        let [a, b, c, d] = [at(-8.0, -8.0), at(72.0, -8.0), at(72.0, 56.0), at(-8.0, 56.0)];
        let error = VertexError::default();
        let mut apart = OcclusionBuffer::new(target, cells);
        let alone = apart.rasterise(&ScreenPolygon::triangle([a, b, c], error))
            + apart.rasterise(&ScreenPolygon::triangle([a, c, d], error));
        let mut together = OcclusionBuffer::new(target, cells);
        assert_eq!(together.rasterise(&ScreenPolygon::quad([a, b, c, d], error)), 192);
        assert!(
            alone < 192 - 12,
            "the diagonal's cells stay empty apart ({alone} written)"
        );
        // Where both write, they agree: the quad's depth is its triangles'.
        for (apart, together) in apart.depths().iter().zip(together.depths()) {
            assert!(*apart == 0.0 || apart == together, "{apart} against {together}");
        }
        // Folded (d on b's side of a–c): each triangle is rasterised alone.
        let folded = at(60.0, 4.0);
        let mut buffer = OcclusionBuffer::new(target, cells);
        let written = buffer.rasterise(&ScreenPolygon::quad([a, b, c, folded], error));
        let mut first_alone = OcclusionBuffer::new(target, cells);
        let expected = first_alone.rasterise(&ScreenPolygon::triangle([a, b, c], error))
            + first_alone.rasterise(&ScreenPolygon::triangle([a, c, folded], error));
        assert_eq!(written, expected);
    }

    #[test]
    fn a_triangle_over_the_whole_screen_fills_every_cell_with_its_farthest_depth() {
        let target = Resolution { width: 64, height: 48 };
        let mut buffer = OcclusionBuffer::new(target, Resolution { width: 16, height: 12 });
        // A plane leaning in x: depth 0.5 at x = 0, 0.3 at x = 64.
        let at = |x: f64, y: f64| DVec3::new(x, y, 0.5 - 0.2 * x / 64.0);
        let whole = ScreenPolygon::triangle(
            [at(-100.0, -100.0), at(300.0, -100.0), at(-100.0, 300.0)],
            VertexError::default(),
        );
        assert_eq!(buffer.rasterise(&whole), 192);
        // Column 0 holds pixels 0..=3, centres 0.5 to 3.5: its farthest is
        // where the GPU may sample beside 3.5.
        let x = 3.5 + VERTEX_ERROR;
        let expected = (0.5 - 0.2 * x / 64.0) * (1.0 - DEPTH_MARGIN) - DEPTH_ABSOLUTE;
        assert_eq!(buffer.depths()[0], f32_at_most(expected));
        assert!(f64::from(buffer.depths()[0]) <= expected);
    }
}
