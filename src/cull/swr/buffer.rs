//! `swr`'s occlusion buffer, laid out as Intel's Masked Software Occlusion
//! Culling lays out its own (Hasselgren, Andersson, Akenine-Möller, HPG
//! 2016, section 3): cells of a few pixels, each with a **reference
//! layer**, a depth every pixel centre of the cell is drawn at or nearer,
//! and **working layers** (MOC keeps one), each a coverage mask of the
//! cell's pixels (up to 8 × 8 groups of them) with the farthest depth of
//! the occluders that covered them. Occluders that each cover part of a
//! cell merge in the working layers; once their masks together fill it,
//! the farthest depth of the nearest of them that fill it becomes the
//! reference (section 3.2's update). A pyramid of the reference layer's farthest depths serves the
//! box test. Screen positions are framebuffer pixels (x right, y down);
//! depth is reverse-Z (`near / distance`, 0 = nothing drawn).
//!
//! Why it is conservative. A box is hidden when, at every pixel centre its
//! rectangle covers, it lies behind what one of the cell's layers holds
//! there (its depth, or its plane; a working layer only at the centres of
//! its mask; [`OcclusionBuffer::hides`]), or its pixel ray misses it.
//! That is safe if, at every pixel centre a layer holds, an occluder drawn
//! this frame (the mode's step 5) is drawn no farther than the layer's
//! depth and its plane. Each occluder object hands its cells a mask of the
//! pixel groups it is sure to draw, with a depth and plane it is sure to
//! draw them at or nearer (mesh.rs says how, from the GPU's placement and
//! rounding); a working layer keeps the least of the depths merged into
//! it, so its mask's every centre is drawn at least that near, and masks
//! that together fill the cell vouch for the whole cell at the least of
//! their depths. A layer is dropped, never narrowed, when it stops paying
//! (MOC's heuristic, [`Cells::merge`]): dropping what is known is always
//! safe. A pyramid level keeps the least of the 2×2 texels below it.
//!
//! Departures from MOC: its box test reads the reference layer alone, it
//! keeps one working layer, and it clears that when it becomes the
//! reference. Here a cell keeps as many working layers as `swr.layers`
//! asks, so that where several surfaces meet in a cell each keeps its own
//! depth; those nearer than a new reference stay, still vouching for their
//! own masks; and a box test that fails at a cell tries its layers part by
//! part: the box's centres in each working layer's mask behind it, the
//! rest behind the reference, each part over the bounding rectangle of its
//! pixel groups. So a box just behind a wall's outline is hidden though
//! the cell's reference is what lies beyond the wall.

use std::ops::Range;

use crate::cull::culler::OccluderDepths;
use crate::gpu::{BoxPlanes, Resolution, ScreenPlane};

/// Pixel groups of a cell's mask along each side, at most: 8 × 8 bits of a
/// `u64`, row after row.
pub(super) const MASK_SIDE: u32 = 8;

/// Texels across a box's rectangle may span at the pyramid level it is
/// read at.
const TEST_SPAN: u32 = 8;

/// The most layers a cell keeps: a reference and seven working layers.
pub(super) const MAX_LAYERS: u32 = 8;

/// A working layer of a cell, besides its mask of the pixel groups it
/// vouches for (kept apart, so that clearing the buffer writes masks
/// alone): a depth and a plane each of their centres is drawn at or
/// nearer. Merging takes one whose mask is empty, or whose depth is no
/// nearer than the cell's reference, as free ([`holds`]); until it is
/// taken, what it vouches for still holds, and the box test may read it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct WorkingDepth {
    depth: f32,
    plane: ScreenPlane,
}

/// One level of the buffer's pyramid.
struct Level {
    width: u32,
    height: u32,
    depth: Vec<f32>,
}

/// One side of the target (across or down): how its pixels fall into
/// cells, and each cell's into the groups its mask holds one bit for.
pub(super) struct Axis {
    /// Per cell, its first and last pixel centre.
    cells: Vec<[f64; 2]>,
    /// Per cell, its first group; one more entry ends the last.
    first_group: Vec<u32>,
    /// Per pixel, its group; per group, its cell and its first and last
    /// pixel centre.
    group_of: Vec<u32>,
    cell_of_group: Vec<u32>,
    group_centres: Vec<[f64; 2]>,
    /// The least distance from a cell's first pixel centre to its last.
    narrowest: f64,
}

/// The pixels cell `c` of `cells` along a side of `pixels` holds: those
/// whose index maps to it by `⌊p · cells / pixels⌋`, as
/// [`OcclusionBuffer::hides`] maps them.
fn held_pixels(c: u32, cells: u32, pixels: u32) -> [u32; 2] {
    let first = (u64::from(c) * u64::from(pixels)).div_ceil(u64::from(cells));
    let end = (u64::from(c + 1) * u64::from(pixels)).div_ceil(u64::from(cells));
    [first as u32, end as u32 - 1]
}

/// A mask's bit at the start of each of the rows of groups `rows` (bit k
/// for the k-th row): times one row's bits, a mask of those rows (a row's
/// bits fit in its byte, so the product carries nothing between them).
fn row_starts(rows: u64) -> u64 {
    (0..MASK_SIDE)
        .filter(|k| rows >> k & 1 == 1)
        .fold(0, |starts, k| starts | 1 << (k * MASK_SIDE))
}

/// `cells` along a side of `pixels`, as `pixel` maps into them.
fn cell_of(pixel: u32, cells: u32, pixels: u32) -> u32 {
    (u64::from(pixel) * u64::from(cells) / u64::from(pixels)) as u32
}

impl Axis {
    /// `cells` cells over `pixels` pixels: a cell's n pixels split into
    /// min(n, 8) groups, the k-th from its pixel ⌈k · n / groups⌉.
    fn new(cells: u32, pixels: u32) -> Axis {
        let mut axis = Axis {
            cells: Vec::with_capacity(cells as usize),
            first_group: vec![0],
            group_of: Vec::with_capacity(pixels as usize),
            cell_of_group: Vec::new(),
            group_centres: Vec::new(),
            narrowest: f64::INFINITY,
        };
        for c in 0..cells {
            let [first, last] = held_pixels(c, cells, pixels);
            axis.cells.push([f64::from(first) + 0.5, f64::from(last) + 0.5]);
            let n = last - first + 1;
            let groups = n.min(MASK_SIDE);
            let base = axis.cell_of_group.len() as u32;
            axis.group_of.extend((0..n).map(|p| base + p * groups / n));
            axis.cell_of_group.extend((0..groups).map(|_| c));
            // Group k holds the pixels p with ⌊p · groups / n⌋ = k.
            let start = |k: u32| first + (k * n).div_ceil(groups);
            axis.group_centres
                .extend((0..groups).map(|k| [start(k), start(k + 1) - 1].map(|p| f64::from(p) + 0.5)));
            axis.first_group.push(base + groups);
            axis.narrowest = axis.narrowest.min(f64::from(last - first));
        }
        axis
    }

    /// The first and last pixel centre of cell `c`.
    pub(super) fn cell(&self, c: u32) -> [f64; 2] {
        self.cells[c as usize]
    }

    /// The first and last pixel centre of each of the cells `cells`.
    pub(super) fn centres(&self, cells: Range<u32>) -> &[[f64; 2]] {
        &self.cells[cells.start as usize..cells.end as usize]
    }

    /// The pixels whose centres lie in [`lo`, `hi`] (none for NaN).
    fn pixels_within(&self, lo: f64, hi: f64) -> Range<u32> {
        let n = self.group_of.len() as f64;
        // A NaN bounds nothing (and an empty range comes out empty below).
        if lo.is_nan() || hi.is_nan() {
            return 0..0;
        }
        // From pixel ⌈lo − 0.5⌉ to ⌊hi − 0.5⌋, clamped to the side first,
        // so casts round them (a cast truncates; `ceil` and `floor` are
        // calls into libm on a plain x86-64 target).
        let start = (lo - 0.5).max(0.0).min(n);
        let first = start as u32 + u32::from(f64::from(start as u32) < start);
        let end = (hi + 0.5).max(0.0).min(n) as u32;
        if first < end { first..end } else { 0..0 }
    }

    /// The cells holding a pixel centre in [`lo`, `hi`].
    pub(super) fn cells_reaching(&self, lo: f64, hi: f64) -> Range<u32> {
        let pixels = self.pixels_within(lo, hi);
        match pixels.is_empty() {
            true => 0..0,
            false => {
                let cell = |p: u32| self.cell_of_group[self.group_of[p as usize] as usize];
                cell(pixels.start)..cell(pixels.end - 1) + 1
            }
        }
    }

    /// The cells of `cells` whose every pixel centre lies in [`lo`, `hi`]
    /// (none for a NaN).
    pub(super) fn cells_within(&self, lo: f64, hi: f64, cells: &Range<u32>) -> Range<u32> {
        // A range narrower than every cell holds none whole (most rows of
        // a thin triangle): told without a search. (Exact: `narrowest` is
        // a whole number of pixels, and a width at least that does not
        // round below it.)
        if hi - lo < self.narrowest || lo.is_nan() || hi.is_nan() {
            return 0..0;
        }
        // Centres rise cell by cell, so the cells whole are one run: from
        // the first whose first centre is at `lo` or after, to the last
        // whose last centre is at `hi` or before. `cells` is most often a
        // row's few reached cells, so the searches are a step or two.
        let centres = self.centres(cells.clone());
        let first = centres.partition_point(|&[first, _]| first < lo);
        let end = centres.partition_point(|&[_, last]| last <= hi).max(first);
        cells.start + first as u32..cells.start + end as u32
    }

    /// The first and last pixel centre of each group of cell `c`.
    pub(super) fn group_centres(&self, c: u32) -> &[[f64; 2]] {
        &self.group_centres[self.first_group[c as usize] as usize..self.first_group[c as usize + 1] as usize]
    }

    /// The groups holding a pixel centre in [`lo`, `hi`], limited to
    /// `cells`.
    pub(super) fn groups_reaching(&self, lo: f64, hi: f64, cells: &Range<u32>) -> Range<u32> {
        let pixels = self.pixels_within(lo, hi);
        if pixels.is_empty() {
            return 0..0;
        }
        let (first, last) = (
            self.group_of[pixels.start as usize],
            self.group_of[pixels.end as usize - 1],
        );
        self.limited(first..last + 1, cells)
    }

    fn limited(&self, groups: Range<u32>, cells: &Range<u32>) -> Range<u32> {
        let (from, to) = (
            self.first_group[cells.start as usize],
            self.first_group[cells.end as usize],
        );
        let start = groups.start.max(from);
        start..groups.end.min(to).max(start)
    }

    /// The cells the groups `groups` lie in, each with the bits (as one row
    /// of a mask: bit k for its k-th group) of the groups it holds.
    pub(super) fn cells_of(&self, groups: Range<u32>) -> impl Iterator<Item = (u32, u64)> + '_ {
        let cells = match groups.is_empty() {
            true => 0..0,
            false => self.cell_of_group[groups.start as usize]..self.cell_of_group[groups.end as usize - 1] + 1,
        };
        cells.map(move |c| {
            let first = self.first_group[c as usize];
            let from = groups.start.max(first) - first;
            let to = groups.end.min(self.first_group[c as usize + 1]) - first;
            (c, (1u64 << to) - (1u64 << from))
        })
    }

    /// The centres from the first to the last of the groups `bits` (bit k
    /// for its k-th; not none) of cell `c`, within [`lo`, `hi`]: the
    /// inverse of [`Self::cells_of`] for one cell.
    fn centres_of(&self, c: u32, bits: u64, [lo, hi]: [f64; 2]) -> [f64; 2] {
        let first = self.first_group[c as usize];
        let (from, to) = (first + bits.trailing_zeros(), first + 63 - bits.leading_zeros());
        [self.group(from).2[0].max(lo), self.group(to).2[1].min(hi)]
    }

    /// Groups cell `c` holds.
    fn groups_in(&self, c: u32) -> u32 {
        self.first_group[c as usize + 1] - self.first_group[c as usize]
    }

    /// The cell of group `g`, its place there, and its first and last
    /// pixel centre.
    pub(super) fn group(&self, g: u32) -> (u32, u32, [f64; 2]) {
        let cell = self.cell_of_group[g as usize];
        (
            cell,
            g - self.first_group[cell as usize],
            self.group_centres[g as usize],
        )
    }
}

/// Where the buffer's cells and their mask groups lie on the target:
/// fixed for a target and a cell count.
pub struct Grid {
    target: Resolution,
    cells: Resolution,
    pub(super) across: Axis,
    pub(super) down: Axis,
    /// Per column, the bits of one row of its groups; per row, a bit at
    /// the start of each row of its groups ([`row_starts`]): a cell's full
    /// mask is their product, made once as rasterising asks for it at every
    /// cell it marks.
    column_bits: Vec<u64>,
    row_starts: Vec<u64>,
}

impl Grid {
    fn new(target: Resolution, cells: Resolution) -> Grid {
        let (width, height) = (cells.width.min(target.width), cells.height.min(target.height));
        let (across, down) = (Axis::new(width, target.width), Axis::new(height, target.height));
        Grid {
            target,
            cells: Resolution { width, height },
            column_bits: (0..width).map(|c| (1u64 << across.groups_in(c)) - 1).collect(),
            row_starts: (0..height).map(|r| row_starts((1 << down.groups_in(r)) - 1)).collect(),
            across,
            down,
        }
    }

    /// The first and last columns, and rows, of the cells holding the
    /// pixels `first` to `last` (x, y, inclusive), as
    /// [`OcclusionBuffer::hides`] maps them.
    fn cells_holding(&self, first: [u32; 2], last: [u32; 2]) -> [[u32; 2]; 2] {
        let (cells, target) = (self.cells, self.target);
        [
            [first[0], last[0]].map(|x| cell_of(x, cells.width, target.width)),
            [first[1], last[1]].map(|y| cell_of(y, cells.height, target.height)),
        ]
    }

    /// The mask of the groups of cell (`column`, `row`) holding a pixel
    /// centre in `xs` × `ys`; none where they hold none.
    fn groups_holding(&self, column: u32, row: u32, xs: [f64; 2], ys: [f64; 2]) -> Option<u64> {
        let bits = |axis: &Axis, c: u32, [lo, hi]: [f64; 2]| {
            axis.cells_of(axis.groups_reaching(lo, hi, &(c..c + 1)))
                .next()
                .map(|(_, bits)| bits)
        };
        Some(bits(&self.across, column, xs)? * row_starts(bits(&self.down, row, ys)?))
    }

    /// The rectangle of pixel centres from the first to the last column,
    /// and row, of the groups `bits` (not none) of cell (`column`, `row`),
    /// within `xs` × `ys`: it holds their centres, and more where they do
    /// not make a rectangle.
    fn centres_of(&self, column: u32, row: u32, bits: u64, xs: [f64; 2], ys: [f64; 2]) -> ([f64; 2], [f64; 2]) {
        debug_assert!(bits != 0, "a rectangle of no groups");
        let row_of = |k: u32| bits >> (k * MASK_SIDE) & ((1 << MASK_SIDE) - 1);
        let columns = (0..MASK_SIDE).fold(0, |columns, k| columns | row_of(k));
        let rows = (0..MASK_SIDE)
            .filter(|&k| row_of(k) != 0)
            .fold(0, |rows, k| rows | 1 << k);
        (
            self.across.centres_of(column, columns, xs),
            self.down.centres_of(row, rows, ys),
        )
    }

    /// The mask of every group of cell (`column`, `row`).
    pub(super) fn full_mask(&self, column: u32, row: u32) -> u64 {
        self.column_bits[column as usize] * self.row_starts[row as usize]
    }
}

/// The level-0 layers of a run of rows of cells (all of them, or a
/// thread's band).
pub struct Cells<'a> {
    grid: &'a Grid,
    /// The rows of cells it holds.
    rows: Range<u32>,
    /// Per cell, row by row from `rows.start`: the reference layer's depth
    /// and plane, and its `per_cell` working layers.
    depth: &'a mut [f32],
    planes: &'a mut [ScreenPlane],
    masks: &'a mut [u64],
    working: &'a mut [WorkingDepth],
    per_cell: usize,
    #[cfg(test)]
    careless: bool,
}

/// What an occluder vouches for in one cell: the mask groups it is sure
/// to draw, and a depth and a plane it draws each of them at or nearer.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coverage {
    pub(super) mask: u64,
    pub(super) depth: f64,
    pub(super) plane: ScreenPlane,
}

impl Cells<'_> {
    pub(super) fn grid(&self) -> &Grid {
        self.grid
    }

    /// The rows of cells it holds.
    pub(super) fn rows(&self) -> Range<u32> {
        self.rows.clone()
    }

    /// Forgets every occluder.
    fn clear(&mut self) {
        self.depth.fill(0.0);
        self.masks.fill(0);
    }

    /// The reference depth of cell (`column`, `row`).
    pub(super) fn reference(&self, column: u32, row: u32) -> f32 {
        self.reference_row(row)[column as usize]
    }

    /// The reference depths of row `row`'s cells.
    pub(super) fn reference_row(&self, row: u32) -> &[f32] {
        let start = self.index(0, row);
        &self.depth[start..start + self.grid.cells.width as usize]
    }

    /// Where cell (`column`, `row`) lies in the layers' rows, which start
    /// at `rows.start`.
    fn index(&self, column: u32, row: u32) -> usize {
        ((row - self.rows.start) * self.grid.cells.width + column) as usize
    }

    /// Whether anything at most `nearest` deep over the pixels `first` to
    /// `last` (x, y, inclusive) lies behind the reference layer of every
    /// cell holding them in these rows (so it can add nothing to them).
    pub(super) fn behind(&self, first: [u32; 2], last: [u32; 2], nearest: f64) -> bool {
        let [columns, rows] = self.grid.cells_holding(first, last);
        self.cells_behind(columns[0]..columns[1] + 1, rows[0]..rows[1] + 1, nearest)
    }

    /// Whether anything at most `nearest` deep lies behind the reference
    /// layer of every cell of `columns` × `rows` in these rows.
    pub(super) fn cells_behind(&self, columns: Range<u32>, rows: Range<u32>, nearest: f64) -> bool {
        let rows = rows.start.max(self.rows.start)..rows.end.min(self.rows.end);
        rows.into_iter().all(|row| {
            columns
                .clone()
                .all(|column| nearest < f64::from(self.reference(column, row)))
        })
    }

    /// Merges `coverage` into cell (`column`, `row`), as MOC updates a
    /// tile (section 3.2), in reverse-Z, with as many working layers as
    /// the buffer keeps: a cell the occluder covers whole takes its depth
    /// and plane where they are nearer than its reference layer. Otherwise
    /// the occluder takes a working layer that holds nothing, or else
    /// joins the one nearest its depth, which then keeps the union of the
    /// masks, the least of the depths and a plane below both; where the
    /// occluder lies nearer than that layer by more than the layer lies
    /// nearer than the reference (merging would pull the new layer back to
    /// a depth nearly no better than the reference's), it takes the
    /// farthest layer's place instead. Once the working layers' masks and
    /// the occluder's fill the cell, the reference becomes the least depth
    /// of the nearest of them that fill it, with a plane below theirs
    /// ([`filling`]). Departure from MOC,
    /// which clears its one working layer then: the layers nearer than the
    /// new reference stay, each still vouching for its own mask (so a box
    /// just behind a wall's outline, within the wall's pixels of the cell,
    /// is hidden), and the occluder takes the place of one that fell
    /// behind.
    #[inline]
    pub(super) fn merge(&mut self, column: u32, row: u32, coverage: &Coverage) {
        let full = self.grid.full_mask(column, row);
        let index = self.index(column, row);
        let mask = coverage.mask & full;
        // Stored rounded farther; a NaN or nothing in front vouches for nothing.
        let depth = f32_at_most(coverage.depth);
        let reference = self.depth[index];
        if mask == 0 || coverage.depth.is_nan() || depth <= reference.max(0.0) {
            return;
        }
        if mask == full {
            self.depth[index] = depth;
            self.planes[index] = coverage.plane;
            return;
        }
        let centres = (self.grid.across.cell(column), self.grid.down.cell(row));
        let slots = index * self.per_cell..(index + 1) * self.per_cell;
        let (masks, layers) = (&mut self.masks[slots.clone()], &mut self.working[slots]);
        let occluder = WorkingDepth {
            depth,
            plane: coverage.plane,
        };
        #[cfg(test)]
        let careless = self.careless;
        #[cfg(not(test))]
        let careless = false;
        let covered = holding(masks, layers, reference).fold(mask, |covered, k| covered | masks[k]);
        if covered == full || careless {
            let (least, plane) = filling(masks, layers, reference, (mask, &occluder), full, centres);
            (self.depth[index], self.planes[index]) = (least, plane);
            // The occluder keeps a layer where it lies nearer than the new
            // reference (the farthest layer that filled it holds nothing now).
            if depth > least
                && let Some(free) = free_slot(masks, layers, least)
            {
                (masks[free], layers[free]) = (mask, occluder);
            }
            return;
        }
        if let Some(free) = free_slot(masks, layers, reference) {
            (masks[free], layers[free]) = (mask, occluder);
            return;
        }
        // Every slot holds a layer (there is none with one layer a cell:
        // the occluder is dropped).
        let gap = |k: &usize| (layers[*k].depth - depth).abs();
        let Some(nearest) = (0..masks.len()).min_by(|a, b| gap(a).total_cmp(&gap(b))) else {
            return;
        };
        let held = layers[nearest];
        if depth - held.depth <= held.depth - reference {
            masks[nearest] |= mask;
            layers[nearest] = WorkingDepth {
                depth: held.depth.min(depth),
                plane: below_both(held.plane, &coverage.plane, centres),
            };
        } else if let Some(farthest) = (0..masks.len()).min_by(|a, b| layers[*a].depth.total_cmp(&layers[*b].depth)) {
            (masks[farthest], layers[farthest]) = (mask, occluder);
        }
    }
}

/// The working layers a cell of `layers` layers keeps: all but the
/// reference, of at most [`MAX_LAYERS`] (so that [`filling`]'s parts fit).
fn working_layers(layers: u32) -> u32 {
    layers.clamp(1, MAX_LAYERS) - 1
}

/// Whether a working layer of mask `mask` vouches for anything a
/// reference at `reference` does not ([`WorkingDepth`]).
fn holds(mask: u64, layer: &WorkingDepth, reference: f32) -> bool {
    mask != 0 && layer.depth > reference
}

/// The working layers among `masks` and `layers` (one cell's) that hold
/// anything ([`holds`]) beside the reference `reference`.
fn holding<'a>(masks: &'a [u64], layers: &'a [WorkingDepth], reference: f32) -> impl Iterator<Item = usize> + 'a {
    (0..masks.len()).filter(move |&k| holds(masks[k], &layers[k], reference))
}

/// A working layer among `masks` and `layers` (one cell's) that holds
/// nothing beside the reference `reference`, free to take another.
fn free_slot(masks: &[u64], layers: &[WorkingDepth], reference: f32) -> Option<usize> {
    (0..masks.len()).find(|&k| !holds(masks[k], &layers[k], reference))
}

/// The reference a cell takes where its working layers that hold
/// anything beside `reference`, and `occluder` (a mask and its depth),
/// together fill it (`full`): the farthest depth of the nearest of them
/// whose masks fill it, and a plane below theirs over the cell's centres
/// (all of them, if they do not, as in a careless buffer). Taking the
/// nearest first leaves a far layer that the others make needless out.
fn filling(
    masks: &[u64],
    layers: &[WorkingDepth],
    reference: f32,
    occluder: (u64, &WorkingDepth),
    full: u64,
    centres: ([f64; 2], [f64; 2]),
) -> (f32, ScreenPlane) {
    let mut parts = [occluder; MAX_LAYERS as usize];
    let mut count = 1;
    for k in holding(masks, layers, reference) {
        parts[count] = (masks[k], &layers[k]);
        count += 1;
    }
    let parts = &mut parts[..count];
    parts.sort_unstable_by(|a, b| b.1.depth.total_cmp(&a.1.depth));
    let (mut filled, mut least, mut plane) = (parts[0].0, parts[0].1.depth, parts[0].1.plane);
    for (mask, layer) in &parts[1..] {
        if filled == full {
            break;
        }
        plane = below_both(plane, &layer.plane, centres);
        (filled, least) = (filled | mask, layer.depth);
    }
    (least, plane)
}

/// `held` lowered, where it is not already, to lie below `other` over
/// the rectangle `xs` × `ys`: a plane below both there (affine, so the
/// most `held` rises above `other` is at a corner), by more than the
/// rounding of evaluating either at a point of it or of lowering it (a
/// few steps of f64 of their terms' sizes), so that evaluated one by one
/// they keep that order.
pub(super) fn below_both(held: ScreenPlane, other: &ScreenPlane, (xs, ys): ([f64; 2], [f64; 2])) -> ScreenPlane {
    let size = |p: &ScreenPlane| {
        p.constant.abs() + p.per_x.abs() * xs[0].abs().max(xs[1].abs()) + p.per_y.abs() * ys[0].abs().max(ys[1].abs())
    };
    let rounding = 8.0 * f64::EPSILON * (size(&held) + size(other));
    let above = held.minus(other).max_over(xs, ys) + rounding;
    if above > 0.0 {
        ScreenPlane {
            constant: held.constant - above,
            ..held
        }
    } else {
        held
    }
}

pub struct OcclusionBuffer {
    grid: Grid,
    /// Level 0 holds the cells' reference depths; each further level
    /// halves them (rounding up) down to one texel.
    levels: Vec<Level>,
    /// Per cell, the depth its reference layer vouches for at each pixel
    /// centre besides its depth: a plane of the occluder that wrote it
    /// (mesh.rs), so a box just behind a wall seen at a slant is hidden
    /// even where the wall's depth changes across the cell by more than
    /// the gap; meaningless where the cell holds no depth.
    planes: Vec<ScreenPlane>,
    /// Per cell, its `per_cell` working layers.
    masks: Vec<u64>,
    working: Vec<WorkingDepth>,
    per_cell: usize,
    /// Breaks the conservative rule on purpose, for the test that sees the
    /// error meter catch it: working layers become the reference as soon
    /// as they hold anything, whether or not their masks fill the cell.
    #[cfg(test)]
    pub(super) careless: bool,
}

impl OcclusionBuffer {
    /// A buffer of `cells` (at most the target's size on each side) over a
    /// target of `target` pixels, with MOC's two layers a cell: a
    /// reference and one working layer.
    #[cfg(test)]
    pub fn new(target: Resolution, cells: Resolution) -> OcclusionBuffer {
        OcclusionBuffer::with_layers(target, cells, 2)
    }

    /// A buffer of `cells` (at most the target's size on each side) over a
    /// target of `target` pixels, whose cells keep `layers` layers each
    /// (at least 1: the reference).
    pub fn with_layers(target: Resolution, cells: Resolution, layers: u32) -> OcclusionBuffer {
        let grid = Grid::new(target, cells);
        let (width, height) = (grid.cells.width, grid.cells.height);
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
        let count = (width * height) as usize;
        let per_cell = working_layers(layers) as usize;
        OcclusionBuffer {
            grid,
            levels,
            planes: vec![ScreenPlane::default(); count],
            masks: vec![0; count * per_cell],
            working: vec![WorkingDepth::default(); count * per_cell],
            per_cell,
            #[cfg(test)]
            careless: false,
        }
    }

    /// About the bytes a buffer of `cells` with `layers` layers a cell takes
    /// (its pyramid of depths, about a third more than its cells; its reference
    /// planes; its working layers' masks, depths and planes).
    pub fn bytes(cells: Resolution, layers: u32) -> u64 {
        let count = u64::from(cells.width) * u64::from(cells.height);
        let per_cell = u64::from(working_layers(layers));
        let pyramid = count * 4 * 4 / 3;
        let working = (std::mem::size_of::<u64>() + std::mem::size_of::<WorkingDepth>()) as u64;
        pyramid + count * std::mem::size_of::<ScreenPlane>() as u64 + count * per_cell * working
    }

    /// The render size it was made for.
    pub fn target(&self) -> Resolution {
        self.grid.target
    }

    /// The buffer's size in cells.
    pub fn cells(&self) -> Resolution {
        self.grid.cells
    }

    /// Every cell's reference plane, row by row.
    #[cfg(test)]
    pub fn planes(&self) -> &[ScreenPlane] {
        &self.planes
    }

    /// Every cell's reference depth, row by row.
    #[cfg(test)]
    pub fn depths(&self) -> &[f32] {
        &self.levels[0].depth
    }

    /// The layers pixel by pixel of the target: the depth each pixel's
    /// cell vouches for there (its reference depth, or the nearest depth of
    /// a working layer whose mask holds the pixel's group, where that is
    /// nearer), and whether it is a working layer's.
    pub fn per_pixel(&self) -> OccluderDepths {
        let Grid {
            target, across, down, ..
        } = &self.grid;
        let mut picture = OccluderDepths {
            width: target.width,
            height: target.height,
            depths: Vec::with_capacity((target.width * target.height) as usize),
            partial: Vec::with_capacity((target.width * target.height) as usize),
        };
        for &gy in &down.group_of {
            let (row, k, _) = down.group(gy);
            for &gx in &across.group_of {
                let (column, j, _) = across.group(gx);
                let cell = (row * self.grid.cells.width + column) as usize;
                let reference = self.levels[0].depth[cell];
                let working = self
                    .layers_of(cell)
                    .filter(|(mask, _)| mask & 1 << (k * MASK_SIDE + j) != 0)
                    .fold(0.0, |nearest: f32, (_, l)| nearest.max(l.depth));
                picture.depths.push(reference.max(working));
                picture.partial.push(working > reference);
            }
        }
        picture
    }

    /// The depth the buffer vouches for at the pixel centre `(x, y)` of
    /// the target: the nearest of what its cell's layers vouch for there
    /// ([`Self::layers_at`]); 0 where none holds anything.
    #[cfg(test)]
    pub fn vouched_at(&self, x: f64, y: f64) -> f64 {
        let (reference, working) = self.layers_at(x, y);
        working.map_or(reference, |working| reference.max(working))
    }

    /// What its cell's layers vouch for at the pixel centre `(x, y)` of
    /// the target, each its depth, or its plane there where that is nearer
    /// (0 where it holds nothing): the reference's, and the nearest of the
    /// working layers whose masks hold the pixel's group (`None` where
    /// none does).
    #[cfg(test)]
    fn layers_at(&self, x: f64, y: f64) -> (f64, Option<f64>) {
        let (cells, target) = (self.grid.cells, self.grid.target);
        let cell = |v: f64, cells: u32, pixels: u32| cell_of(v as u32, cells, pixels);
        let (column, row) = (cell(x, cells.width, target.width), cell(y, cells.height, target.height));
        let index = (row * cells.width + column) as usize;
        let layer = |depth: f32, plane: &ScreenPlane| match f64::from(depth) {
            0.0 => 0.0,
            depth => depth.max(plane.at(x, y)),
        };
        let reference = layer(self.levels[0].depth[index], &self.planes[index]);
        let groups = self.grid.groups_holding(column, row, [x, x], [y, y]).unwrap_or(0);
        let working = self
            .layers_of(index)
            .filter(|(mask, _)| mask & groups != 0)
            .map(|(_, l)| layer(l.depth, &l.plane))
            .reduce(f64::max);
        (reference, working)
    }

    /// The working layers of cell `index` (row by row): each one's mask,
    /// depth and plane.
    fn layers_of(&self, index: usize) -> impl Iterator<Item = (u64, &WorkingDepth)> {
        let slots = index * self.per_cell..(index + 1) * self.per_cell;
        self.masks[slots.clone()].iter().copied().zip(&self.working[slots])
    }

    /// The cells, cleared, in bands of `rows_per_band` rows of cells (the
    /// last band holds the rest), for threads to fill one band each.
    pub fn cleared_bands(&mut self, rows_per_band: u32) -> impl Iterator<Item = Cells<'_>> {
        let grid = &self.grid;
        let width = grid.cells.width as usize;
        let chunk = width * rows_per_band.max(1) as usize;
        let per_cell = self.per_cell;
        #[cfg(test)]
        let careless = self.careless;
        // Each band's working layers split off the rest in turn (a chunk of
        // them may be empty: a buffer of one layer keeps none).
        let (mut masks_left, mut working_left) = (&mut self.masks[..], &mut self.working[..]);
        self.levels[0]
            .depth
            .chunks_mut(chunk)
            .zip(self.planes.chunks_mut(chunk))
            .enumerate()
            .map(move |(k, (depth, planes))| {
                let (masks, working);
                (masks, masks_left) = std::mem::take(&mut masks_left).split_at_mut(depth.len() * per_cell);
                (working, working_left) = std::mem::take(&mut working_left).split_at_mut(depth.len() * per_cell);
                let first = (k * chunk / width) as u32;
                let mut cells = Cells {
                    grid,
                    rows: first..first + (depth.len() / width) as u32,
                    depth,
                    planes,
                    masks,
                    working,
                    per_cell,
                    #[cfg(test)]
                    careless,
                };
                cells.clear();
                cells
            })
    }

    /// The share of its cells that hold a depth (those left at 0 hold
    /// none).
    pub fn held(&self) -> f64 {
        let cells = &self.levels[0].depth;
        cells.iter().filter(|&&depth| depth > 0.0).count() as f64 / cells.len() as f64
    }

    /// Builds the pyramid over the cells written since [`Self::clear`].
    pub fn build_pyramid(&mut self) {
        for k in 1..self.levels.len() {
            let (below, above) = self.levels.split_at_mut(k);
            let (below, level) = (&below[k - 1], &mut above[0]);
            // A texel's children: its 2 × 2 texels below, the last row or
            // column of an odd side counted twice.
            let width = below.width as usize;
            let row_below = |y: u32| &below.depth[(y.min(below.height - 1) as usize) * width..][..width];
            for (y, texels) in (0..level.height).zip(level.depth.chunks_exact_mut(level.width as usize)) {
                let (top, bottom) = (row_below(2 * y), row_below(2 * y + 1));
                for (x, texel) in texels.iter_mut().enumerate() {
                    let (left, right) = (2 * x, (2 * x + 1).min(width - 1));
                    *texel = top[left].min(top[right]).min(bottom[left]).min(bottom[right]);
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
    /// when one of its planes lies behind the cell's plane at each centre,
    /// or when it lies behind a working layer or the reference at its
    /// centres in that layer's mask and behind the reference at the others,
    /// each part judged over the rectangle of its pixel groups.
    pub fn hides(&self, first: [u32; 2], last: [u32; 2], nearest: f64, planes: &BoxPlanes) -> bool {
        debug_assert!(first[0] <= last[0] && first[1] <= last[1], "{first:?} to {last:?}");
        let [columns, rows] = self.grid.cells_holding(first, last);
        let query = BoxQuery {
            buffer: self,
            pixels: [first, last],
            columns,
            rows,
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

/// What one of a cell's layers vouches for at the centres it holds: a
/// depth, and a plane, each drawn at or nearer (0: nothing).
struct Layer {
    depth: f64,
    plane: ScreenPlane,
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
            centres(&self.buffer.grid.across.cells, columns, 0),
            centres(&self.buffer.grid.down.cells, rows, 1),
        );
        if self.nearest_over(xs, ys) < farthest || self.planes.missed_over(xs, ys) {
            return true;
        }
        if k > 0 {
            return self.hides_texels(k - 1, columns.map(|c| c >> (k - 1)), rows.map(|r| r >> (k - 1)));
        }
        // A cell: behind its plane by one of the box's (the box's depth is
        // at most the least of them), at every centre.
        let index = (y * level.width + x) as usize;
        let reference = Layer {
            depth: farthest,
            plane: self.buffer.planes[index],
        };
        if farthest > 0.0 && self.behind_plane(&reference.plane, xs, ys) {
            return true;
        }
        // Or, where the cell has working layers, part by part: the box's
        // centres in a layer's mask behind it or the reference, and the
        // others behind the reference, each part over the rectangle of its
        // pixel groups (a working layer vouches for its depth and plane at
        // its mask's centres as the reference does everywhere).
        let covered = self
            .buffer
            .layers_of(index)
            .fold(0, |covered, (mask, _)| covered | mask);
        if covered == 0 {
            return false;
        }
        let grid = &self.buffer.grid;
        let Some(groups) = grid.groups_holding(x, y, xs, ys) else {
            return false;
        };
        let hidden_by = |layer: &Layer, (xs, ys): ([f64; 2], [f64; 2])| {
            layer.depth > 0.0
                && (self.nearest < layer.depth
                    || self.nearest_over(xs, ys) < layer.depth
                    || self.behind_plane(&layer.plane, xs, ys))
        };
        // The part no working layer holds first: the reference just failed
        // over the whole cell, so that is where the test most often ends.
        let outside = groups & !covered;
        if outside != 0 && !hidden_by(&reference, grid.centres_of(x, y, outside, xs, ys)) {
            return false;
        }
        // Then each working layer's part that no layer before it hid; what
        // none of them hides, behind the reference.
        let mut left = groups & covered;
        for (mask, layer) in self.buffer.layers_of(index) {
            let part = left & mask;
            if part == 0 {
                continue;
            }
            let working = Layer {
                depth: f64::from(layer.depth),
                plane: layer.plane,
            };
            if hidden_by(&working, grid.centres_of(x, y, part, xs, ys)) {
                left &= !part;
            }
        }
        left == 0 || hidden_by(&reference, grid.centres_of(x, y, left, xs, ys))
    }

    /// The nearest the box may be at the pixel centres `xs` × `ys`, by its
    /// entry planes: each bounds the box's depth on its own, so the least
    /// of them does; a NaN among them is passed over by `min`, and a NaN
    /// result hides nothing (tests take `<`, not `>=`).
    fn nearest_over(&self, xs: [f64; 2], ys: [f64; 2]) -> f64 {
        self.planes
            .entries()
            .iter()
            .map(|p| p.max_over(xs, ys))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether one of the box's entry planes lies behind `plane` at every
    /// pixel centre of `xs` × `ys`.
    fn behind_plane(&self, plane: &ScreenPlane, xs: [f64; 2], ys: [f64; 2]) -> bool {
        self.planes
            .entries()
            .iter()
            .any(|p| p.minus(plane).max_over(xs, ys) < 0.0)
    }
}

/// The largest f32 at most `v` (a plain cast may round up, nearer).
pub(super) fn f32_at_most(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) > v { f.next_down() } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_is_the_share_of_cells_holding_a_depth() {
        let mut buffer = OcclusionBuffer::new(
            Resolution { width: 64, height: 48 },
            Resolution { width: 16, height: 12 },
        );
        assert_eq!(buffer.held(), 0.0);
        buffer.levels[0].depth[..48].fill(0.5);
        assert_eq!(buffer.held(), 0.25);
    }

    /// A coverage of one depth everywhere.
    fn flat(depth: f64, mask: u64) -> Coverage {
        Coverage {
            mask,
            depth,
            plane: ScreenPlane {
                constant: depth,
                ..ScreenPlane::default()
            },
        }
    }

    #[test]
    fn a_working_layer_becomes_the_reference_once_its_mask_is_full_at_the_least_depth_merged_into_it() {
        // 20 × 12 pixels in 5 × 3 cells of 4 × 4 pixels: 16 groups a cell.
        let mut buffer = OcclusionBuffer::new(Resolution { width: 20, height: 12 }, Resolution { width: 5, height: 3 });
        let full = buffer.grid.full_mask(2, 1);
        assert_eq!(full, 0x0f0f_0f0f, "four rows of four groups");
        let (left, right) = (0x0303_0303, 0x0c0c_0c0c);
        {
            let mut cells = buffer.cleared_bands(3).next().unwrap();
            // (Depths that f32 holds exactly.) Half a cell at 0.5: nothing
            // vouched for yet.
            cells.merge(2, 1, &flat(0.5, left));
            assert_eq!(cells.reference(2, 1), 0.0);
            // The other half at 0.375: the cell holds the farther, 0.375.
            cells.merge(2, 1, &flat(0.375, right));
            assert_eq!(cells.reference(2, 1), 0.375);
            // Half again at 0.4375, joining the left half's layer, then the
            // other half at 0.875: together they fill the cell, which takes
            // the farther, 0.4375, and 0.875 keeps the working layer; the
            // left half at 0.75 fills it again.
            cells.merge(2, 1, &flat(0.4375, left));
            cells.merge(2, 1, &flat(0.875, right));
            assert_eq!(cells.reference(2, 1), 0.4375);
            cells.merge(2, 1, &flat(0.75, left));
            assert_eq!(cells.reference(2, 1), 0.75);
            // Nothing behind the reference changes it, whole or in part.
            cells.merge(2, 1, &flat(0.625, full));
            cells.merge(2, 1, &flat(0.6875, left));
            cells.merge(2, 1, &flat(0.5, right));
            assert_eq!(cells.reference(2, 1), 0.75);
            // A whole cover nearer takes the cell, with its plane.
            cells.merge(2, 1, &flat(0.8125, full));
            assert_eq!(cells.reference(2, 1), 0.8125);
        }
        assert_eq!(buffer.planes()[7].constant, 0.8125);
        // Cells of 4 and 3 pixels across, 3 down.
        let edge = OcclusionBuffer::new(Resolution { width: 10, height: 3 }, Resolution { width: 3, height: 1 });
        assert_eq!([0, 2].map(|c| edge.grid.full_mask(c, 0)), [0x0f_0f0f, 0x07_0707]);
    }

    #[test]
    fn a_box_whose_pixels_lie_in_the_working_layers_mask_is_hidden_by_it_after_a_farther_occluder_fills_the_cell() {
        // 20 × 12 pixels in 5 × 3 cells of 4 × 4 pixels: cell (2, 1) holds
        // pixels 8 to 11 across and 4 to 7 down, its left half 8 and 9.
        let mut buffer = OcclusionBuffer::new(Resolution { width: 20, height: 12 }, Resolution { width: 5, height: 3 });
        let (left, right) = (0x0303_0303, 0x0c0c_0c0c);
        {
            let mut cells = buffer.cleared_bands(3).next().unwrap();
            // The left half at 0.5, then the right half far behind it: the
            // cell's reference is the farther, and the left half keeps its
            // own depth.
            cells.merge(2, 1, &flat(0.5, left));
            cells.merge(2, 1, &flat(0.25, right));
            assert_eq!(cells.reference(2, 1), 0.25);
        }
        buffer.build_pyramid();
        let hides = |first, last, nearest| buffer.hides(first, last, nearest, &BoxPlanes::default());
        assert!(hides([8, 4], [9, 7], 0.375), "behind the left half, within it");
        assert!(
            !hides([8, 4], [10, 7], 0.375),
            "reaching into the right half, in front of it"
        );
        assert!(!hides([8, 4], [9, 7], 0.625), "in front of the left half");
        assert!(hides([8, 4], [10, 7], 0.125), "behind the whole cell");
        assert_eq!([9.5, 10.5].map(|x| buffer.vouched_at(x, 5.5)), [0.5, 0.25]);
    }

    #[test]
    fn a_box_behind_the_working_layer_in_its_mask_and_behind_the_reference_elsewhere_is_hidden() {
        // Cell (2, 1) of 4 × 4 pixels (8 to 11 across): its reference at
        // least 0.25 and on a plane rising from 0.25 at x = 8.5 to 0.55 at
        // x = 11.5; its working layer the left half (pixels 8, 9) at 0.5.
        let mut buffer = OcclusionBuffer::new(Resolution { width: 20, height: 12 }, Resolution { width: 5, height: 3 });
        {
            let mut cells = buffer.cleared_bands(3).next().unwrap();
            cells.merge(2, 1, &flat(0.5, 0x0303_0303));
            let rising = ScreenPlane {
                per_x: 0.1,
                per_y: 0.0,
                constant: -0.6,
            };
            cells.merge(
                2,
                1,
                &Coverage {
                    mask: 0x0f0f_0f0f,
                    depth: 0.25,
                    plane: rising,
                },
            );
        }
        buffer.build_pyramid();
        // A box over the whole cell at most `depth` deep everywhere: at
        // 0.44 it lies behind the working layer over pixels 8 and 9, and
        // behind the reference's plane over 10 and 11 (0.45 there at the
        // least), though over the whole cell it lies behind neither.
        let hides = |depth: f64| {
            let planes = BoxPlanes::entering_at(ScreenPlane {
                constant: depth,
                ..ScreenPlane::default()
            });
            buffer.hides([8, 4], [11, 7], depth, &planes)
        };
        assert!(hides(0.44));
        assert!(!hides(0.46), "in front of the reference at pixel 10");
        assert!(!hides(0.52), "in front of the working layer at pixel 8");
    }

    #[test]
    fn a_box_the_buffer_hides_lies_behind_what_it_vouches_for_at_every_centre_and_that_no_nearer_than_the_occluders_merged()
     {
        use crate::rng::Rng;
        let mut rng = Rng::new(32);
        let target = Resolution { width: 31, height: 23 };
        // Cells of 10 or 11 pixels (8 groups of 1 or 2 a side), and of 4
        // or 5 (as many groups); the same occluders and boxes in buffers
        // of one layer a cell to four.
        let (mut hidden, mut by_both_layers) = ([0; 4], 0);
        for cells in [Resolution { width: 3, height: 2 }, Resolution { width: 7, height: 5 }] {
            let grid = Grid::new(target, cells);
            for _ in 0..300 {
                // Coverages: a rectangle of groups, some groups, or all.
                let coverages: Vec<(u32, u32, Coverage)> = (0..rng.int(1, 16))
                    .map(|_| {
                        let (column, row) = (rng.int(0, cells.width - 1), rng.int(0, cells.height - 1));
                        let full = grid.full_mask(column, row);
                        let mask = match rng.int(0, 2) {
                            0 => {
                                let (a, b) = (rng.int(0, 7), rng.int(0, 7));
                                let (c, d) = (rng.int(0, 7), rng.int(0, 7));
                                let bits = (1u64 << (a.max(b) + 1)) - (1 << a.min(b));
                                (c.min(d)..=c.max(d)).fold(0, |mask, k| mask | bits << (k * MASK_SIDE))
                            }
                            1 => rng.next_u64(),
                            _ => full,
                        };
                        let plane = ScreenPlane {
                            per_x: rng.range(-0.02, 0.02),
                            per_y: rng.range(-0.02, 0.02),
                            constant: rng.range(0.0, 0.9),
                        };
                        (
                            column,
                            row,
                            Coverage {
                                mask: mask & full,
                                depth: rng.range(0.1, 0.9),
                                plane,
                            },
                        )
                    })
                    .collect();
                // Boxes: a rectangle of pixels, and a plane the box's depth
                // is at most at each of its centres.
                let boxes: Vec<([u32; 2], [u32; 2], ScreenPlane)> = (0..40)
                    .map(|_| {
                        let first = [rng.int(0, 30), rng.int(0, 22)];
                        let last = [
                            rng.int(first[0], (first[0] + 12).min(30)),
                            rng.int(first[1], (first[1] + 12).min(22)),
                        ];
                        let entry = ScreenPlane {
                            per_x: rng.range(-0.02, 0.02),
                            per_y: rng.range(-0.02, 0.02),
                            constant: rng.range(0.0, 0.9),
                        };
                        (first, last, entry)
                    })
                    .collect();
                for layers in 1..=4 {
                    let mut buffer = OcclusionBuffer::with_layers(target, cells, layers);
                    {
                        let mut band = buffer.cleared_bands(cells.height).next().unwrap();
                        for (column, row, coverage) in &coverages {
                            band.merge(*column, *row, coverage);
                        }
                    }
                    buffer.build_pyramid();
                    let centres = |first: [u32; 2], last: [u32; 2]| {
                        (first[1]..=last[1]).flat_map(move |y| {
                            (first[0]..=last[0]).map(move |x| (f64::from(x) + 0.5, f64::from(y) + 0.5))
                        })
                    };
                    // What the buffer vouches for, no nearer than some
                    // coverage of that centre's group claims there.
                    for (x, y) in centres([0, 0], [30, 22]) {
                        let claimed = coverages
                            .iter()
                            .filter(|(column, row, c)| {
                                buffer
                                    .grid
                                    .groups_holding(*column, *row, [x, x], [y, y])
                                    .is_some_and(|g| g & c.mask != 0)
                            })
                            .map(|(_, _, c)| c.depth.max(c.plane.at(x, y)))
                            .fold(0.0, f64::max);
                        assert!(
                            buffer.vouched_at(x, y) <= claimed,
                            "({x}, {y}) {cells:?} {layers} layers"
                        );
                    }
                    for &(first, last, entry) in &boxes {
                        let rectangle = [first, last].map(|p| p.map(|v| f64::from(v) + 0.5));
                        let nearest =
                            entry.max_over([rectangle[0][0], rectangle[1][0]], [rectangle[0][1], rectangle[1][1]]);
                        if !buffer.hides(first, last, nearest, &BoxPlanes::entering_at(entry)) {
                            continue;
                        }
                        hidden[layers as usize - 1] += 1;
                        let mut needs = [false; 2];
                        for (x, y) in centres(first, last) {
                            let (reference, working) = buffer.layers_at(x, y);
                            assert!(
                                entry.at(x, y) < buffer.vouched_at(x, y),
                                "({x}, {y}) {cells:?} {layers} layers"
                            );
                            needs[usize::from(working.is_some())] |= entry.at(x, y) >= reference;
                            needs[0] |= working.is_none();
                        }
                        by_both_layers += usize::from(needs == [true, true]);
                    }
                }
            }
        }
        // More layers keep more of what the occluders vouch for.
        assert!(
            hidden[0] > 500 && by_both_layers > 30,
            "{hidden:?} hidden, {by_both_layers} by both layers"
        );
        assert!(
            hidden.windows(2).all(|pair| pair[0] < pair[1]),
            "hidden with 1 to 4 layers: {hidden:?}"
        );
    }

    #[test]
    fn a_cell_keeps_as_many_surfaces_apart_as_it_has_layers() {
        // Cell (2, 1) of 4 × 4 pixels: its left half at 0.25, its right
        // half's top at 0.75 and bottom at 0.5 (masks row by row, a byte a
        // row of four groups).
        let (left, right_top, right_bottom) = (0x0303_0303, 0x0c0c, 0x0c0c_0000);
        let merged = |layers: u32| {
            let mut buffer = OcclusionBuffer::with_layers(
                Resolution { width: 20, height: 12 },
                Resolution { width: 5, height: 3 },
                layers,
            );
            {
                let mut cells = buffer.cleared_bands(3).next().unwrap();
                for (depth, mask) in [(0.25, left), (0.75, right_top), (0.5, right_bottom)] {
                    cells.merge(2, 1, &flat(depth, mask));
                }
            }
            buffer.build_pyramid();
            buffer
        };
        let hides =
            |buffer: &OcclusionBuffer, first, last, nearest| buffer.hides(first, last, nearest, &BoxPlanes::default());
        // Three layers: the three parts fill the cell, which takes the
        // farthest, 0.25; the two nearer stay as working layers.
        let three = merged(3);
        assert!(hides(&three, [8, 4], [11, 7], 0.2), "behind the whole cell");
        assert!(hides(&three, [10, 4], [11, 5], 0.7), "behind the right half's top");
        assert!(hides(&three, [10, 4], [11, 7], 0.45), "behind the right half");
        assert!(!hides(&three, [8, 4], [11, 7], 0.3), "in front of the left half");
        // Two (MOC's): the right half's top lies so far before the left
        // half that it takes the working layer's place, and the bottom
        // joins it at the farther 0.5; the left half is lost and the cell
        // never filled.
        let two = merged(2);
        assert!(!hides(&two, [8, 4], [11, 7], 0.2), "the left half is not held");
        assert!(!hides(&two, [10, 4], [11, 5], 0.7), "the top is held at 0.5 only");
        assert!(hides(&two, [10, 4], [11, 7], 0.45), "behind the right half");
        // One: a reference only, which no part fills.
        let one = merged(1);
        assert!(!hides(&one, [10, 4], [11, 7], 0.2));
        let centres = [(9.5, 6.5), (10.5, 4.5), (10.5, 6.5)];
        assert_eq!(centres.map(|(x, y)| three.vouched_at(x, y)), [0.25, 0.75, 0.5]);
        assert_eq!(centres.map(|(x, y)| two.vouched_at(x, y)), [0.0, 0.5, 0.5]);
        assert_eq!(centres.map(|(x, y)| one.vouched_at(x, y)), [0.0; 3]);
    }

    #[test]
    fn a_filled_cell_takes_the_farthest_depth_of_the_nearest_layers_that_fill_it() {
        // Cell (2, 1) of 4 × 4 pixels, three layers: its left half at 0.25;
        // its right half's top at 0.75, which the left half at 0.875 then
        // joins (0.75 over both); its right half's bottom at 0.8125 fills
        // the cell. The nearer two fill it alone: the reference is 0.75,
        // not the far left half's 0.25, and the bottom keeps a layer.
        let (left, right_top, right_bottom) = (0x0303_0303, 0x0c0c, 0x0c0c_0000);
        let mut buffer = OcclusionBuffer::with_layers(
            Resolution { width: 20, height: 12 },
            Resolution { width: 5, height: 3 },
            3,
        );
        {
            let mut cells = buffer.cleared_bands(3).next().unwrap();
            for (depth, mask) in [(0.25, left), (0.75, right_top), (0.875, left), (0.8125, right_bottom)] {
                cells.merge(2, 1, &flat(depth, mask));
            }
            assert_eq!(cells.reference(2, 1), 0.75);
        }
        let centres = [(9.5, 6.5), (10.5, 4.5), (10.5, 6.5)];
        assert_eq!(centres.map(|(x, y)| buffer.vouched_at(x, y)), [0.75, 0.75, 0.8125]);
    }

    #[test]
    fn the_careless_buffer_takes_a_working_layer_that_is_not_full() {
        let mut buffer = OcclusionBuffer::new(Resolution { width: 20, height: 12 }, Resolution { width: 5, height: 3 });
        buffer.careless = true;
        let mut cells = buffer.cleared_bands(3).next().unwrap();
        cells.merge(2, 1, &flat(0.5, 0x0303_0303));
        assert_eq!(cells.reference(2, 1), 0.5);
    }

    #[test]
    fn each_pyramid_texel_holds_the_farthest_depth_of_the_texels_below_it() {
        // Odd sides at every level (7 × 5 → 4 × 3 → 2 × 2 → 1 × 1) and one
        // side of one texel (9 × 1 → … → 1 × 1).
        let mut rng = crate::rng::Rng::new(17);
        for cells in [Resolution { width: 7, height: 5 }, Resolution { width: 9, height: 1 }] {
            let mut buffer = OcclusionBuffer::new(Resolution { width: 28, height: 20 }, cells);
            for depth in &mut buffer.levels[0].depth {
                *depth = rng.range(0.0, 1.0) as f32;
            }
            buffer.build_pyramid();
            assert!(buffer.levels.last().is_some_and(|l| l.width == 1 && l.height == 1));
            for k in 1..buffer.levels.len() {
                let (below, level) = (&buffer.levels[k - 1], &buffer.levels[k]);
                for (y, x) in (0..level.height).flat_map(|y| (0..level.width).map(move |x| (y, x))) {
                    let children = (2 * y..(2 * y + 2).min(below.height))
                        .flat_map(|by| (2 * x..(2 * x + 2).min(below.width)).map(move |bx| (by, bx)));
                    let farthest = children
                        .map(|(by, bx)| below.depth[(by * below.width + bx) as usize])
                        .fold(f32::INFINITY, f32::min);
                    assert_eq!(
                        level.depth[(y * level.width + x) as usize],
                        farthest,
                        "level {k} texel ({x}, {y})"
                    );
                }
            }
        }
    }

    #[test]
    fn groups_split_a_cells_pixels_and_ranges_find_them_by_their_centres() {
        // 10 pixels in 3 cells: 4, 3 and 3 pixels (⌊p · 3 / 10⌋).
        let axis = Axis::new(3, 10);
        assert_eq!(axis.cells, [[0.5, 3.5], [4.5, 6.5], [7.5, 9.5]]);
        assert_eq!(axis.first_group, [0, 4, 7, 10]);
        let all = 0..3;
        // Centres 2.5 to 6.5: pixels 2 to 6.
        assert_eq!(axis.groups_reaching(2.2, 6.7, &all), 2..7);
        assert_eq!(axis.cells_reaching(2.2, 6.7), 0..2);
        assert_eq!(axis.cells_within(2.2, 6.7, &all), 1..2);
        // The narrowest cells' centres lie 2 apart: a range that wide may
        // hold one whole, a narrower one none.
        assert_eq!(axis.cells_within(4.5, 6.5, &all), 1..2);
        assert_eq!(axis.cells_within(7.5, 9.5, &all), 2..3);
        assert_eq!(axis.cells_within(4.6, 6.5, &all), 0..0);
        assert_eq!(axis.cells_within(f64::NAN, 9.5, &all), 0..0);
        assert_eq!(axis.cells_within(0.5, 9.5, &(1..2)), 1..2, "only the cells asked about");
        assert_eq!(axis.cells_within(0.5, 6.4, &(0..3)), 0..1);
        assert_eq!(axis.groups_reaching(2.6, 2.9, &all), 0..0, "no centre between");
        assert_eq!(axis.groups_reaching(f64::NAN, 3.0, &all), 0..0);
        assert_eq!(axis.groups_reaching(-1e300, 1e300, &(1..2)), 4..7);
        assert_eq!(
            axis.cells_of(2..8).collect::<Vec<_>>(),
            [(0, 0b1100), (1, 0b111), (2, 0b1)]
        );
        // 20 pixels in 2 cells: 10 each, in 8 groups of 1 or 2 pixels.
        let coarse = Axis::new(2, 20);
        assert_eq!(coarse.first_group, [0, 8, 16]);
        assert_eq!(coarse.group(0), (0, 0, [0.5, 1.5]));
        assert_eq!(coarse.group(1), (0, 1, [2.5, 2.5]));
        assert_eq!(coarse.group(12), (1, 4, [15.5, 16.5]));
        assert_eq!(coarse.groups_reaching(0.5, 1.0, &(0..2)), 0..1);
    }

    #[test]
    fn the_cells_within_a_range_are_those_whose_every_pixel_centre_it_holds() {
        // Cells of one to four pixels, of unlike widths, and ranges
        // ending on, beside and between centres, just below them by the
        // least step, beyond the side, infinite and NaN.
        let ends = [
            -1e300,
            -0.5,
            0.0,
            0.5,
            1.0,
            1.5,
            2.5,
            3.5,
            4.5,
            5.5,
            6.5,
            7.0,
            9.5,
            20.0,
            f64::INFINITY,
            f64::NAN,
        ]
        .into_iter()
        .flat_map(|v: f64| [v, v.next_down(), v.next_up()]);
        let ends: Vec<f64> = ends.collect();
        for (cells, pixels) in [(3, 10), (4, 6), (6, 6), (2, 7)] {
            let axis = Axis::new(cells, pixels);
            let held = |c: u32| {
                let [first, last] = held_pixels(c, cells, pixels);
                move |lo: f64, hi: f64| (first..=last).all(|p| lo <= f64::from(p) + 0.5 && f64::from(p) + 0.5 <= hi)
            };
            for from in 0..cells {
                for to in from + 1..=cells {
                    for &lo in &ends {
                        for &hi in &ends {
                            let got = axis.cells_within(lo, hi, &(from..to));
                            let expected: Vec<u32> = (from..to).filter(|&c| held(c)(lo, hi)).collect();
                            assert_eq!(
                                got.collect::<Vec<_>>(),
                                expected,
                                "{cells} cells over {pixels}: [{lo}, {hi}] in {from}..{to}"
                            );
                        }
                    }
                }
            }
        }
    }
}
