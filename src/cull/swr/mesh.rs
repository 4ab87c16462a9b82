//! One occluder rasterised into the buffer's cells: which pixel
//! groups of which cells the GPU is sure to draw it over, and a depth it
//! draws them at or nearer (buffer.rs merges them, MOC's way).
//!
//! Why a pixel centre is drawn. The GPU places each corner of a triangle
//! within some error of where the CPU projects it (sub-pixel snapping, at
//! the adapter's precision, [`ScreenMesh::snap`]; f32 vertices,
//! [`ScreenVertex::slack`]), and places equal positions of one mesh at one
//! point, so triangles sharing an edge stay joined. Call an edge **inner**
//! when exactly two of the mesh's drawn triangles share it, in opposite
//! directions, both turning one way on screen and neither a sliver, and the
//! GPU places both its ends (it clips neither triangle there); a **patch**
//! is such triangles joined by inner edges (the GPU draws either turn: the
//! scene renders without face culling), and each edge of its triangles that
//! is not inner is on its **border**. At a point p, the border winds round
//! p once for each patch triangle that holds p (they all turn one way). The
//! GPU's placement moves each point of a border edge by less than its
//! corners' error on each axis: the point is a weighted mean of the edge's
//! ends, each placed strictly within its error (which counts a whole step
//! of the sub-pixel grid, where snapping moves a vertex by less). Where p
//! lies at least that error from every border edge, the placed border winds
//! round p as often, so the placed triangles, counted with their turn,
//! still hold p at least once, and one that turns the patch's way holds p
//! (a rasteriser's fill rule counts a centre on a shared edge as the
//! winding does). So a pixel centre inside the patch and clear of its
//! border by that margin is drawn ([`Rasteriser::add_triangle`],
//! [`Rasteriser::erase`]), whatever the triangles' size: a mesh of
//! triangles far smaller than a cell covers the cell as one surface does. A
//! triangle is a patch of its own too, whose border is its three edges (a
//! fan triangle of a polygon clipped at the near plane as well: the GPU's
//! clipped polygon is convex and holds the points within the slack of its
//! corners, so it holds the placed fan triangle): so a centre within a
//! border's margin is still drawn where one of the patch's triangles holds
//! it clear of its own edges by that margin ([`Rasteriser::hold_alone`]),
//! as where a patch folds over itself and its near layer's outline crosses
//! the far layer. This is MOC's masked coverage made exact for a GPU that
//! rasterises the same triangles. Triangles of two objects join only where
//! the objects are clusters of one mesh under one transform (a
//! [`ScreenMesh`] of several [`DrawnPart`]s): the GPU places each object's
//! vertices through its own matrix, equal for those, and their vertices are
//! stored against one origin (scene/model.rs), so a position they share has
//! the same bits in each. Elsewhere the seam between two objects is a
//! border of both.
//!
//! Its depth there is that of a point of the triangle drawn, within that
//! error of p: at least the triangle's plane lowered by its greatest change
//! within the error, then moved farther by the GPU's depth rounding
//! ([`DEPTH_MARGIN`], and a fragment's error for the triangle's nearest
//! depth, [`DepthMargins::fragment_error`]: rule 1 of
//! gpu/conservative.rs); the triangle is one whose corners' bounds, grown by
//! the error, hold p. So each cell keeps the least of those planes over the
//! part of it each such triangle can reach ([`Rasteriser::add_depth`]),
//! and one plane below all of them there. The margins bound f32
//! interpolation over triangles that stand high over their edges; a
//! thinner one (a sliver, gpu/conservative.rs, rule 2) joins a patch only
//! where its interpolation is bounded too, its plane taken farther for it
//! ([`depth_slack`]); otherwise it is left out of the patches, and its
//! edges border them.
//!
//! Near the eye. A triangle with a corner the GPU may clip (at or behind
//! the near plane, within its error) is drawn in its part beyond the near
//! plane. Its part beyond a limit a little farther ([`Polygon::clip`],
//! clipped as Sutherland and Hodgman clip) is a polygon whose corners are
//! placed vertices or crossings of that limit; the GPU's own clipped polygon
//! runs on along the same edges to the near plane, so it holds ours. Its
//! cut sides are borders: the GPU clips each triangle on its own, so two
//! triangles cut on a shared edge may not meet exactly there, and a
//! crossing's error is that of the GPU's f32 clipping at the near plane,
//! larger than a vertex's.
//!
//! The GPU must also keep every fragment an occluder vouches for: the
//! scene's fragment stage discards fragments nearer than where the pixel's
//! ray enters the object's box (`FragmentLimit`, gpu/conservative.rs).
//! An occluder's triangles lie within its box (its mesh's bounds, placed),
//! but by a face of the box, where the limit lies only half the box's
//! growth in front of the surface, the depth the GPU draws a triangle at
//! may reach past it: one seen edge-on changes depth fast across the
//! error of its corners. That was measured on Vulkan (den-haag.obj, frame
//! 3 of its orbit, a building's corner: the surface seen instead lay three
//! steps of 2^-24 farther; tests/occluder_depth.rs). So a triangle the
//! GPU may draw past the limit anywhere within its error is in no patch
//! ([`kept`]).

use std::ops::Range;

use glam::{DVec2, DVec3};

use super::buffer::{Cells, Coverage, Grid, MASK_SIDE, below_both};
use crate::gpu::{DepthMargins, FacingFace, ScreenPlane};

/// A triangle at least [`LEAST_HEIGHT`] errors high over each edge at
/// this snap, the coarsest Vulkan allows (0.375 pixel at least), belongs
/// to a patch whatever its shape: the rule every earlier release held on
/// every model, measured exact. A thinner one joins only where the GPU's
/// f32 interpolation of its depth across it is bounded, its plane taken
/// farther for it ([`interpolation_slack`]).
const SLIVER_SNAP: f64 = 1.0 / 16.0;

/// A cell's depth is moved farther by this fraction of the triangle's
/// exact depth there, and by a fragment's error for the triangle's
/// nearest depth ([`DepthMargins::fragment_error`]: its interpolation
/// across the screen, and on GL the absolute precision its clip range
/// keeps): the GPU interpolates depth in f32.
const DEPTH_MARGIN: f64 = 1.0 / (1u32 << 18) as f64;

/// How high a patch triangle must stand over each of its edges, in
/// multiples of twice its corners' error (the adapter's snap and the f32
/// placement): so that placing its corners neither turns it over nor
/// thins it below half its height, and so tilts its depth plane by at
/// most a twelfth of its rise across it.
const LEAST_HEIGHT: f64 = 3.0;

/// One rounding step of f32 (2^-24 of the value rounded).
const F32_STEP: f64 = 1.0 / (1u32 << 24) as f64;

/// Steps of [`F32_STEP`] the GPU's depth plane of a thin triangle may err
/// by, in the terms [`interpolation_slack`] scales them by: its
/// gradient comes from products of corner differences (two roundings, and
/// the difference of the products one more) over the triangle's area (one
/// more), and the placed triangle is at least half as high as ours
/// ([`LEAST_HEIGHT`]): 4 steps, doubled.
const INTERPOLATION_STEPS: f64 = 8.0;

/// No triangle across this edge of a mesh triangle ([`super::neighbours`]).
pub(super) const NO_NEIGHBOUR: u32 = u32::MAX;

/// A vertex on screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenVertex {
    /// Pixel position (x, y) and depth (z).
    pub at: DVec3,
    /// How far the GPU may place it from `at`, in pixels on each axis.
    pub slack: f64,
    /// How far its depth may be from `at.z` as the GPU computes it, as a
    /// fraction of it (its f32 position's error).
    pub depth_error: f64,
}

/// An occluder on screen: the parts of a mesh the GPU draws this frame
/// (clusters drawn as objects of their own, under one transform).
pub struct ScreenMesh<'a> {
    /// The drawn parts' vertices, part after part; `None` for one the GPU
    /// may clip (at or behind the near plane) or not place at all.
    pub vertices: &'a [Option<ScreenVertex>],
    /// The parts drawn, in the order of their triangles in the mesh.
    pub parts: &'a [DrawnPart],
    /// Where the part of a triangle the GPU draws in front of the near
    /// plane ends; `None` leaves out every triangle with a vertex it does
    /// not place.
    pub near: Option<NearLimit<'a>>,
    /// Three indices per triangle of the whole mesh.
    pub indices: &'a [u32],
    /// Per triangle of the whole mesh, the triangle across each edge
    /// (corner k to k + 1), or [`NO_NEIGHBOUR`].
    pub neighbours: &'a [[u32; 3]],
    /// Whether it is part of a closed solid: its far side lies behind its
    /// near side wherever it is drawn.
    pub closed: bool,
    /// Pixels the GPU's sub-pixel snap (and its viewport rounding) may
    /// move a vertex on each axis (`SubpixelPrecision::vertex_error`): the
    /// part of every vertex's slack that its own f32 position's error does
    /// not make.
    pub snap: f64,
    /// The backend's depth margins (GL's keep an absolute part).
    pub depth: DepthMargins,
}

/// A part of a mesh the GPU draws: a run of its triangles, whose indices
/// reach a run of vertices of their own.
pub struct DrawnPart {
    /// Its triangles among the mesh's.
    pub triangles: Range<u32>,
    /// The least index its triangles hold.
    pub first_vertex: u32,
    /// Where its vertices, `first_vertex` first, and its triangles start
    /// among the drawn parts' ([`ScreenMesh::vertices`]; the drawn
    /// triangles are numbered part after part).
    pub vertex_slot: u32,
    pub triangle_slot: u32,
    /// The faces of its object's box that face the eye, with where the
    /// scene's fragment stage keeps the object's fragments
    /// (`FacingFace::of_object`).
    pub facing: [Option<FacingFace>; 3],
}

#[cfg(test)]
impl DrawnPart {
    /// All `indices`' triangles, whose least index is 0.
    pub(super) fn whole(indices: &[u32]) -> DrawnPart {
        DrawnPart {
            triangles: 0..(indices.len() / 3) as u32,
            first_vertex: 0,
            vertex_slot: 0,
            triangle_slot: 0,
            facing: [None; 3],
        }
    }
}

impl ScreenMesh<'_> {
    /// Per drawn triangle (numbered part after part), where its corners
    /// are among [`ScreenMesh::vertices`] in `corners`, and in `across` the
    /// drawn triangle across each of its edges, or [`NO_NEIGHBOUR`].
    fn drawn_triangles(&self, corners: &mut Vec<[u32; 3]>, across: &mut Vec<[u32; 3]>) {
        corners.clear();
        across.clear();
        for part in self.parts {
            for t in part.triangles.clone() {
                let indices = &self.indices[3 * t as usize..3 * t as usize + 3];
                corners.push([0, 1, 2].map(|k| part.vertex_slot + indices[k] - part.first_vertex));
                across.push(self.neighbours[t as usize].map(|n| self.slot(n, part).unwrap_or(NO_NEIGHBOUR)));
            }
        }
    }

    /// The drawn triangle that is the mesh's triangle `t` (mostly one of
    /// `near`'s), if one is.
    fn slot(&self, t: u32, near: &DrawnPart) -> Option<u32> {
        let part = if near.triangles.contains(&t) {
            near
        } else {
            self.parts.get(self.parts.partition_point(|p| p.triangles.end <= t))?
        };
        part.triangles
            .contains(&t)
            .then(|| part.triangle_slot + t - part.triangles.start)
    }
}

/// Where the GPU clips an occluder's triangles at the near plane.
pub struct NearLimit<'a> {
    /// The point on screen where the segment from a placed vertex to one
    /// that is not (each given by its place among the mesh's vertices) crosses the
    /// limit beyond which vertices are placed, with the error of the GPU's
    /// own crossing, which lies nearer the eye on the same line; `None`
    /// where it cannot be placed.
    pub crossing: &'a dyn Fn(usize, usize) -> Option<ScreenVertex>,
}

/// The part of a triangle the GPU draws, as a convex polygon on screen:
/// the triangle itself, or, where the near plane clips it, the part in
/// front of the near limit. Its sides (corner i to i + 1) are whole edges
/// of the triangle, or cut: a part of an edge, or the limit's.
#[derive(Clone, Copy, Debug)]
struct Polygon {
    corners: [ScreenVertex; 4],
    /// Per side, the triangle's edge it is whole (corner k to k + 1), or
    /// `None` where it is cut.
    sides: [Option<usize>; 4],
    count: usize,
}

impl Polygon {
    /// No polygon yet, for [`Polygon::clip`] to fill.
    const EMPTY: Polygon = Polygon {
        corners: [ScreenVertex {
            at: DVec3::ZERO,
            slack: 0.0,
            depth_error: 0.0,
        }; 4],
        sides: [None; 4],
        count: 0,
    };

    /// Becomes the part of a drawn triangle (its corners among the mesh's
    /// vertices) the GPU draws in front of the near limit (Sutherland and
    /// Hodgman's clipping, edge by edge); false where there is none, or
    /// where a crossing cannot be placed. Without `mesh.near`, only a
    /// triangle the GPU places whole. After false, what it holds means
    /// nothing. Filled in place, not returned: it is made twice for every
    /// occluder triangle a frame, and copying its 232 bytes back was 7 % of
    /// a one-thread buffer on the bunny (perf), 2–5 % of its time.
    fn clip(&mut self, mesh: &ScreenMesh, corners: [u32; 3]) -> bool {
        if let Some(placed) = placed_corners(mesh, corners) {
            self.corners[..3].copy_from_slice(&placed);
            self.sides[..3].copy_from_slice(&[Some(0), Some(1), Some(2)]);
            self.count = 3;
            return true;
        }
        self.count = 0;
        let Some(near) = mesh.near.as_ref() else { return false };
        let index = |k: usize| corners[k % 3] as usize;
        for edge in 0..3 {
            let (p, q) = (index(edge), index(edge + 1));
            let (first, crossing) = match (mesh.vertices[p], mesh.vertices[q]) {
                (Some(p), Some(_)) => (Some((p, Some(edge))), None),
                (Some(corner), None) => (Some((corner, None)), Some((p, q))),
                (None, Some(_)) => (None, Some((q, p))),
                (None, None) => (None, None),
            };
            if let Some((corner, side)) = first {
                self.push(corner, side);
            }
            if let Some((placed, not)) = crossing {
                let Some(corner) = (near.crossing)(placed, not) else {
                    return false;
                };
                self.push(corner, None);
            }
        }
        self.count >= 3
    }

    fn push(&mut self, corner: ScreenVertex, side: Option<usize>) {
        self.corners[self.count] = corner;
        self.sides[self.count] = side;
        self.count += 1;
    }

    /// Whether the GPU draws the whole triangle.
    fn whole(&self) -> bool {
        self.count == 3 && self.sides[..3].iter().all(Option::is_some)
    }

    /// Its triangles, fanned from its first corner (its diagonal is no
    /// side).
    fn triangles(&self) -> impl Iterator<Item = [ScreenVertex; 3]> + '_ {
        (1..self.count - 1).map(|i| [self.corners[0], self.corners[i], self.corners[i + 1]])
    }

    /// Its sides, each as its two corners and the edge it is whole.
    fn sides(&self) -> impl Iterator<Item = (ScreenVertex, ScreenVertex, Option<usize>)> + '_ {
        (0..self.count).map(|i| (self.corners[i], self.corners[(i + 1) % self.count], self.sides[i]))
    }

    /// Its turn as a part of `mesh` drawn as `part`: that of each of its
    /// triangles, or excluded where one is a sliver, may be drawn where
    /// the fragment stage discards it ([`kept`]), or they differ.
    fn turn(&self, mesh: &ScreenMesh, part: &DrawnPart) -> Turn {
        let error = mesh.depth.fragment_error(self.nearest_depth());
        let mut turns = self.triangles().map(|t| match depth_slack(&t, mesh.snap) {
            Some(slack) if kept(&t, slack, error, &part.facing) => area_turn(&t),
            _ => Turn::Excluded,
        });
        let first = turns.next().unwrap_or(Turn::Excluded);
        if turns.all(|t| t == first) {
            first
        } else {
            Turn::Excluded
        }
    }

    /// The nearest depth of what the GPU draws: its nearest corner's, or
    /// the near plane's (depth 1) where the GPU clips it there.
    fn nearest_depth(&self) -> f64 {
        if self.whole() {
            self.corners[..3]
                .iter()
                .map(|c| c.at.z)
                .fold(f64::NEG_INFINITY, f64::max)
        } else {
            1.0
        }
    }
}

/// Which way a triangle turns on screen (x right, y down), if it may
/// belong to a patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Turn {
    Counter,
    Clockwise,
    /// In no patch: nothing of it beyond the near plane, a sliver, or not
    /// a number.
    Excluded,
}

/// What one patch vouches for in one cell while it is rasterised: the
/// pixel groups it marks, and how near it is drawn there.
#[derive(Clone, Copy, Debug)]
struct CellCover {
    mask: u64,
    /// The groups the patch's border erased from the mask.
    erased: u64,
    depth: CellDepth,
}

#[derive(Clone, Copy, Debug)]
enum CellDepth {
    /// No triangle of the patch reaches the cell yet.
    Unreached,
    /// The least depth of the triangles that may be drawn over the cell,
    /// and a plane at most each of them where it may be drawn.
    AtLeast { least: f64, plane: ScreenPlane },
    /// The patch vouches for nothing here: one of its triangles that may
    /// be drawn here lies behind the cell's reference, or gave a NaN.
    Nothing,
}

const EMPTY: CellCover = CellCover {
    mask: 0,
    erased: 0,
    depth: CellDepth::Unreached,
};

/// Occluders made ready to rasterise: each object's patches, with their
/// triangles and border edges. Made by one thread for its share of the
/// objects; read by every thread rasterising its rows.
#[derive(Default)]
pub struct Patches {
    /// Scratch for one object: per triangle, its turn, and its patch as a
    /// tree of triangles (union-find: the root names the patch), then its
    /// root (none where it is left out); the patches' triangles, patch by
    /// patch, as (root, triangle), and per root where its patch ends among
    /// them.
    turns: Vec<Turn>,
    /// Per triangle, bit k set where its edge k is inner ([`Self::joined`]).
    inner_edges: Vec<u8>,
    corners: Vec<[u32; 3]>,
    across: Vec<[u32; 3]>,
    parent: Vec<u32>,
    roots: Vec<Option<u32>>,
    patch_ends: Vec<u32>,
    by_patch: Vec<(u32, u32)>,
    triangles: Vec<Triangle>,
    /// Per triangle of `triangles`, the y range it may reach (its corners'
    /// bounds grown by its slack): a band of rows passes over the
    /// triangles outside it reading these alone, not the triangles.
    reach_y: Vec<[f64; 2]>,
    borders: Vec<Border>,
    patches: Vec<Patch>,
}

/// An edge of a patch's border, and how far from it a pixel centre must
/// lie to count: its corners' error.
struct Border {
    p: DVec3,
    q: DVec3,
    margin: f64,
}

/// A patch: its triangles and border edges in [`Patches`], the bounds of
/// its triangles grown by their error (x, y), and its nearest and
/// farthest corners' depths.
struct Patch {
    triangles: Range<usize>,
    borders: Range<usize>,
    lo: DVec2,
    hi: DVec2,
    nearest: f64,
    farthest: f64,
}

impl Patches {
    pub fn clear(&mut self) {
        self.triangles.clear();
        self.reach_y.clear();
        self.borders.clear();
        self.patches.clear();
    }

    /// Adds `mesh`'s patches; returns which they are.
    pub fn add(&mut self, mesh: &ScreenMesh) -> Range<usize> {
        self.find_patches(mesh);
        let first = self.patches.len();
        let mut polygon = Polygon::EMPTY;
        let mut start = 0;
        while start < self.by_patch.len() {
            let root = self.by_patch[start].0;
            let end = self.patch_ends[root as usize] as usize;
            let (triangles, borders) = (self.triangles.len(), self.borders.len());
            let (mut lo, mut hi, mut nearest) = (DVec2::INFINITY, DVec2::NEG_INFINITY, f64::NEG_INFINITY);
            let mut farthest = f64::INFINITY;
            for k in start..end {
                let t = self.by_patch[k].1 as usize;
                if !polygon.clip(mesh, self.corners[t]) {
                    continue;
                }
                let error = mesh.depth.fragment_error(polygon.nearest_depth());
                for c in polygon.triangles() {
                    // A patch's triangles each have a depth slack (their
                    // turn was found with it); were one to lack it, its
                    // plane would lie infinitely far, vouching for nothing.
                    let depth = depth_slack(&c, mesh.snap).unwrap_or(f64::INFINITY);
                    let triangle = Triangle::new(c, mesh.snap, depth, error);
                    nearest = c.iter().fold(nearest, |n, c| n.max(c.at.z));
                    farthest = c.iter().fold(farthest, |n, c| n.min(c.at.z));
                    let reach = (triangle.lo - triangle.slack, triangle.hi + triangle.slack);
                    (lo, hi) = (lo.min(reach.0), hi.max(reach.1));
                    self.reach_y.push([reach.0.y, reach.1.y]);
                    self.triangles.push(triangle);
                }
                for (p, q, whole) in polygon.sides() {
                    if whole.is_none_or(|edge| self.inner_edges[t] >> edge & 1 == 0) {
                        self.borders.push(Border {
                            p: p.at,
                            q: q.at,
                            margin: p.slack.max(q.slack),
                        });
                    }
                }
            }
            self.patches.push(Patch {
                triangles: triangles..self.triangles.len(),
                borders: borders..self.borders.len(),
                lo,
                hi,
                nearest,
                farthest,
            });
            start = end;
        }
        // Nearest first by their farthest corner, so that a patch wholly
        // behind what the ones before it left in the buffer is passed over
        // (a cluster of a one-mesh building holds the near room's walls
        // and the far rooms' behind them, in no order), while a patch
        // running from the eye to the horizon (a ground) comes after what
        // stands on it: a cell's part of it then joins the nearer
        // facade's in the merge rather than being replaced by it. (On the
        // default city swr drew 23 275 triangles a frame in this order,
        // 23 384 in the mesh's, and 27 160 by nearest corner.) A wall receding to
        // the horizon comes after a far room's wall seen past it, and
        // may take from it the cells they share; of the two orders tried,
        // this one lost less. Equals stay in the mesh's order.
        self.patches[first..].sort_unstable_by(|a, b| {
            b.farthest
                .total_cmp(&a.farthest)
                .then(a.triangles.start.cmp(&b.triangles.start))
        });
        first..self.patches.len()
    }

    /// The drawn triangle across edge `edge` of drawn triangle `t`, where
    /// that edge is inner: the GPU draws it whole (both its vertices
    /// placed, so the triangles either side of it share it as placed), and
    /// the triangle across it is drawn and turns the same way. A cut edge
    /// never is: the GPU clips each triangle on its own.
    fn joined(&self, mesh: &ScreenMesh, t: usize, edge: usize) -> Option<usize> {
        let across = self.across[t][edge];
        let placed = |k: usize| mesh.vertices[self.corners[t][k % 3] as usize].is_some();
        (across != NO_NEIGHBOUR
            && self.turns[t] != Turn::Excluded
            && self.turns[across as usize] == self.turns[t]
            && placed(edge)
            && placed(edge + 1))
        .then_some(across as usize)
    }

    /// Sorts the drawn triangles into patches: those turning one way,
    /// joined by inner edges.
    fn find_patches(&mut self, mesh: &ScreenMesh) {
        mesh.drawn_triangles(&mut self.corners, &mut self.across);
        self.turns.clear();
        let mut clipped = false;
        // The drawn triangles are numbered part after part.
        let parts = mesh
            .parts
            .iter()
            .flat_map(|part| std::iter::repeat_n(part, part.triangles.len()));
        let mut polygon = Polygon::EMPTY;
        for (&corners, part) in self.corners.iter().zip(parts) {
            let turn = if polygon.clip(mesh, corners) {
                clipped |= !polygon.whole();
                polygon.turn(mesh, part)
            } else {
                Turn::Excluded
            };
            self.turns.push(turn);
        }
        self.parent.clear();
        self.parent.extend(0..self.turns.len() as u32);
        self.inner_edges.clear();
        for t in 0..self.turns.len() {
            let mut inner = 0;
            for edge in 0..3 {
                if let Some(across) = self.joined(mesh, t, edge) {
                    let (a, b) = (self.root(t as u32), self.root(across as u32));
                    self.parent[a.max(b) as usize] = a.min(b);
                    inner |= 1 << edge;
                }
            }
            self.inner_edges.push(inner);
        }
        // Where the near plane clips a closed solid, its near side has a
        // hole its far side may be seen through.
        let behind = if mesh.closed && !clipped {
            behind_turn(mesh, &self.corners, &self.turns)
        } else {
            None
        };
        // Patch by patch, each patch's triangles in order: sorted by root
        // (a triangle) by counting, in time linear in the triangles. The
        // entry after a root's counts its patch's triangles; summed, a
        // root's entry holds where its patch starts, and, once the
        // triangles are placed, where it ends.
        let count = self.turns.len();
        self.roots.clear();
        self.patch_ends.clear();
        self.patch_ends.resize(count + 1, 0);
        for t in 0..count as u32 {
            let kept = self.turns[t as usize] != Turn::Excluded && Some(self.turns[t as usize]) != behind;
            let root = kept.then(|| self.root(t));
            if let Some(root) = root {
                self.patch_ends[root as usize + 1] += 1;
            }
            self.roots.push(root);
        }
        for r in 0..count {
            self.patch_ends[r + 1] += self.patch_ends[r];
        }
        self.by_patch.clear();
        self.by_patch.resize(self.patch_ends[count] as usize, (0, 0));
        for (t, root) in self
            .roots
            .iter()
            .enumerate()
            .filter_map(|(t, root)| Some((t, (*root)?)))
        {
            let slot = &mut self.patch_ends[root as usize];
            self.by_patch[*slot as usize] = (root, t as u32);
            *slot += 1;
        }
    }

    /// The root of triangle `t`'s patch (halving the path on the way).
    fn root(&mut self, mut t: u32) -> u32 {
        while self.parent[t as usize] != t {
            let up = self.parent[self.parent[t as usize] as usize];
            self.parent[t as usize] = up;
            t = up;
        }
        t
    }
}

/// A thread's scratch for rasterising patches into its rows of cells,
/// reused so a frame allocates nothing once warm.
#[derive(Default)]
pub struct Rasteriser {
    /// The cells the current patch may reach, and what it vouches for in
    /// each (row by row over `columns`; [`EMPTY`] between patches, and
    /// beyond the current patch's cells).
    columns: Range<u32>,
    rows: Range<u32>,
    cover: Vec<CellCover>,
    /// Per row of the current patch's cells, the columns from the first to
    /// the last its triangles reached there (empty where none), so that
    /// only they are merged and emptied again: a patch reaches far fewer
    /// cells than its bounds hold.
    spans: Vec<Range<u32>>,
    /// Per row of the current patch's cells, the columns from the first to
    /// the last where its border erased a mark (empty where none).
    erased: Vec<Range<u32>>,
    /// The triangles of the current patch rasterised in these rows of
    /// cells, each with the rows and columns of the cells it reached.
    reached: Vec<(usize, [Range<u32>; 2])>,
}

impl Rasteriser {
    /// Rasterises the patches `which` of `patches` into `cells` (only the
    /// rows of cells they hold).
    pub fn rasterise(&mut self, cells: &mut Cells, patches: &Patches, which: Range<usize>) {
        for patch in &patches.patches[which] {
            self.rasterise_patch(cells, patches, patch);
        }
    }

    fn rasterise_patch(&mut self, cells: &mut Cells, patches: &Patches, patch: &Patch) {
        let grid = cells.grid();
        let columns = grid.across.cells_reaching(patch.lo.x, patch.hi.x);
        let rows = clamp(grid.down.cells_reaching(patch.lo.y, patch.hi.y), &cells.rows());
        // Nothing to do where it lies behind every cell it reaches (its
        // triangles' depths, not their margins, suffice: they are nearer).
        if columns.is_empty() || rows.is_empty() || cells.cells_behind(columns.clone(), rows.clone(), patch.nearest) {
            return;
        }
        self.begin_patch(columns, rows);
        // A patch of many triangles spans many bands of rows: each band
        // takes those whose y range meets its pixel centres' (a NaN range
        // meets none: such a triangle reaches no cell).
        let [top, bottom] = [grid.down.cell(self.rows.start)[0], grid.down.cell(self.rows.end - 1)[1]];
        for t in patch.triangles.clone() {
            let [lo, hi] = patches.reach_y[t];
            if lo <= bottom && hi >= top {
                self.add_triangle(cells, t, &patches.triangles[t]);
            }
        }
        for border in &patches.borders[patch.borders.clone()] {
            self.erase(grid, border);
        }
        if self.erased.iter().any(|columns| !columns.is_empty()) {
            for k in 0..self.reached.len() {
                let (t, [rows, columns]) = self.reached[k].clone();
                self.hold_alone(grid, &patches.triangles[t], rows, columns);
            }
        }
        for (row, span) in self.rows.clone().zip(&self.spans) {
            if span.is_empty() {
                continue;
            }
            let first = self.cover_index(span.start, row);
            for (column, cover) in span.clone().zip(&mut self.cover[first..first + span.len()]) {
                let cover = std::mem::replace(cover, EMPTY);
                if let (true, CellDepth::AtLeast { least, plane }) = (cover.mask != 0, cover.depth) {
                    cells.merge(
                        column,
                        row,
                        &Coverage {
                            mask: cover.mask,
                            depth: least,
                            plane,
                        },
                    );
                }
            }
        }
    }

    /// Makes ready for a patch over the cells `columns` × `rows`.
    fn begin_patch(&mut self, columns: Range<u32>, rows: Range<u32>) {
        debug_assert!(
            self.cover
                .iter()
                .all(|c| c.mask == 0 && c.erased == 0 && matches!(c.depth, CellDepth::Unreached)),
            "every entry of the last patch emptied"
        );
        let cells_held = columns.len() * rows.len();
        if self.cover.len() < cells_held {
            self.cover.resize(cells_held, EMPTY);
        }
        self.spans.clear();
        self.spans.resize(rows.len(), 0..0);
        self.erased.clear();
        self.erased.resize(rows.len(), 0..0);
        self.reached.clear();
        (self.columns, self.rows) = (columns, rows);
    }

    /// Where in `cover` cell (`column`, `row`) lies, which must lie within
    /// the current patch's cells.
    fn cover_index(&self, column: u32, row: u32) -> usize {
        let width = self.columns.len() as u32;
        ((row - self.rows.start) * width + column - self.columns.start) as usize
    }

    /// Rasterises `triangle` (triangle `t` of the patches) into the current
    /// patch's cells, row of cells by row of cells: first its depth over
    /// the cells it may reach ([`Self::add_depth`]), then, in a row where it vouches for a depth,
    /// its mark: every group of the cells whose every centre it marks,
    /// and the groups it marks in the cells on either side of them
    /// ([`Self::mark_sides`]), each from the x range it marks in each row
    /// of the row's groups ([`Triangle::marked_x_range`]; the cells it
    /// marks whole are those within all of them). The cells it marks lie
    /// among those it reaches (a narrower region, at both ends of the
    /// rows), so a cell it marks has its depth, and only such cells are
    /// marked.
    fn add_triangle(&mut self, cells: &Cells, t: usize, triangle: &Triangle) {
        let grid = cells.grid();
        let (lo, hi) = (triangle.lo - triangle.slack, triangle.hi + triangle.slack);
        let mut group_row_ranges = [[0.0; 2]; MASK_SIDE as usize];
        let rows = clamp(grid.down.cells_reaching(lo.y, hi.y), &self.rows);
        let mut columns = 0..0;
        for row in rows.clone() {
            let [y0, y1] = grid.down.cell(row);
            let ys = [y0.max(lo.y), y1.min(hi.y)];
            let xs = triangle.reached_x_range(ys);
            let reached = clamp(grid.across.cells_reaching(xs[0], xs[1]), &self.columns);
            if reached.is_empty() {
                continue;
            }
            columns = widened(&columns, &reached);
            // Each group row's x range, and their intersection, which is
            // the range over the whole row: a limit is linear in y, so its
            // bound over the row is at an end of the row, an end of a
            // group row too.
            let group_rows = grid.down.group_centres(row);
            let (mut from, mut to) = (f64::NEG_INFINITY, f64::INFINITY);
            for (range, &ys) in group_row_ranges.iter_mut().zip(group_rows) {
                *range = triangle.marked_x_range(ys);
                // No NaN: a mark's range is empty where an edge gives none.
                (from, to) = (
                    if range[0] > from { range[0] } else { from },
                    if range[1] < to { range[1] } else { to },
                );
            }
            let whole = grid.across.cells_within(from, to, &reached);
            // The cells it marks whole lie among those it reaches.
            debug_assert!({
                let anywhere = grid.across.cells_within(from, to, &self.columns);
                anywhere.is_empty() || anywhere == whole
            });
            let in_patch = (row - self.rows.start) as usize;
            self.spans[in_patch] = widened(&self.spans[in_patch], &reached);
            if self.add_depth(cells, row, reached.clone(), &whole, (xs, ys), &triangle.plane) {
                self.mark_sides(grid, row, &reached, &whole, &group_row_ranges[..group_rows.len()]);
            }
        }
        self.reached.push((t, [rows, columns]));
    }

    /// Lowers the depth and plane of each cell of `reached` in `row`, where
    /// the GPU may draw the triangle of `plane` within `xs` × `ys`, to what
    /// it vouches for there: at the pixel centres within its error of the
    /// triangle (on each axis); and marks every group of the cells `whole`
    /// where it does. A cell where the triangle lies nowhere nearer than
    /// the cell's reference layer is left to the patch no more: whatever
    /// the patch vouches for there, the least of its triangles' depths, the
    /// reference holds already (MOC's depth test of occluders against the
    /// buffer, which front-to-back occluders make pay). Returns whether a
    /// cell of them vouches for a depth.
    fn add_depth(
        &mut self,
        cells: &Cells,
        row: u32,
        reached: Range<u32>,
        whole: &Range<u32>,
        (xs, ys): ([f64; 2], [f64; 2]),
        plane: &ScreenPlane,
    ) -> bool {
        let grid = cells.grid();
        let first = self.cover_index(reached.start, row);
        let covers = &mut self.cover[first..first + reached.len()];
        let references = &cells.reference_row(row)[reached.start as usize..reached.end as usize];
        let centres = grid.across.centres(reached.clone());
        // The plane's greatest and least over a cell's rectangle, each at
        // the corner it rises or falls towards, as `ScreenPlane::max_over`
        // takes it (the same products and sums), with what stays the same
        // along the row taken once.
        let rising = plane.per_x > 0.0;
        let (y_high, y_low) = if plane.per_y > 0.0 {
            (ys[1], ys[0])
        } else {
            (ys[0], ys[1])
        };
        let (high_by_y, low_by_y) = (plane.per_y * y_high, plane.per_y * y_low);
        let mut vouched = false;
        for (k, ((cover, &reference), &[x0, x1])) in covers.iter_mut().zip(references).zip(centres).enumerate() {
            let column = reached.start + k as u32;
            if let CellDepth::Nothing = cover.depth {
                continue;
            }
            // The cell's centres within the row's reach (`xs` bounds
            // cells that reach it, so neither is a NaN).
            let (x0, x1) = (if x0 > xs[0] { x0 } else { xs[0] }, if x1 < xs[1] { x1 } else { xs[1] });
            let (x_high, x_low) = if rising { (x1, x0) } else { (x0, x1) };
            let nearest = plane.per_x * x_high + high_by_y + plane.constant;
            // Not nearer (or a NaN).
            let behind = nearest.partial_cmp(&f64::from(reference)).is_none_or(|o| o.is_le());
            let least = plane.per_x * x_low + low_by_y + plane.constant;
            if behind || least.is_nan() {
                cover.depth = CellDepth::Nothing;
                continue;
            }
            cover.depth = match cover.depth {
                CellDepth::AtLeast {
                    least: held,
                    plane: below,
                } => CellDepth::AtLeast {
                    least: if least < held { least } else { held },
                    plane: below_both(below, plane, ([x0, x1], ys)),
                },
                // Unreached (a cell the patch vouches nothing for was
                // passed over above).
                _ => CellDepth::AtLeast { least, plane: *plane },
            };
            if whole.contains(&column) {
                cover.mask |= grid.full_mask(column, row);
            }
            vouched = true;
        }
        vouched
    }

    /// Marks, in the cells of `reached` on either side of the cells
    /// `whole` (marked whole) that vouch for a depth, each group whose
    /// every centre lies within its group row's x range (one per row of
    /// `row`'s groups, in `group_row_ranges`).
    fn mark_sides(
        &mut self,
        grid: &Grid,
        row: u32,
        reached: &Range<u32>,
        whole: &Range<u32>,
        group_row_ranges: &[[f64; 2]],
    ) {
        let sides = match whole.is_empty() {
            true => [reached.clone(), 0..0],
            false => [reached.start..whole.start, whole.end..reached.end],
        };
        self.mark_groups(grid, row, sides.into_iter().flatten(), group_row_ranges);
    }

    /// Marks, in the cells `columns` of `row` that vouch for a depth, each
    /// group whose every centre lies within its group row's x range (as
    /// [`Self::mark_sides`]).
    fn mark_groups(
        &mut self,
        grid: &Grid,
        row: u32,
        columns: impl Iterator<Item = u32>,
        group_row_ranges: &[[f64; 2]],
    ) {
        for column in columns {
            let i = self.cover_index(column, row);
            let cover = &mut self.cover[i];
            if let CellDepth::AtLeast { .. } = cover.depth {
                let groups = grid.across.group_centres(column);
                for (k, &range) in group_row_ranges.iter().enumerate() {
                    cover.mask |= groups_within(groups, range) << (k as u32 * MASK_SIDE);
                }
            }
        }
    }

    /// Marks again, in the cells where the patch's border erased marks,
    /// the groups this triangle holds alone: those whose every centre lies
    /// inside it by a border's margin ([`Triangle::held_x_range`]). The
    /// triangle is a patch of its own whose border is its edges, so the
    /// GPU draws those centres whatever it does with the rest of the
    /// patch's border. Only the cells `rows` × `columns` that it reached
    /// ([`Self::add_triangle`]) are looked at, and its x ranges are solved
    /// only in rows where it reaches such a cell.
    fn hold_alone(&mut self, grid: &Grid, triangle: &Triangle, rows: Range<u32>, columns: Range<u32>) {
        let mut group_row_ranges = [[0.0; 2]; MASK_SIDE as usize];
        for row in rows {
            let erased = &self.erased[(row - self.rows.start) as usize];
            let group_rows = grid.down.group_centres(row);
            let mut solved = false;
            for column in clamp(columns.clone(), erased) {
                if self.cover[self.cover_index(column, row)].erased == 0 {
                    continue;
                }
                if !solved {
                    for (range, &ys) in group_row_ranges.iter_mut().zip(group_rows) {
                        *range = triangle.held_x_range(ys);
                    }
                    solved = true;
                }
                self.mark_groups(
                    grid,
                    row,
                    std::iter::once(column),
                    &group_row_ranges[..group_rows.len()],
                );
            }
        }
    }

    /// Clears the mark of every pixel group with a centre within the
    /// border edge's margin of it on each axis.
    fn erase(&mut self, grid: &Grid, border: &Border) {
        let Border { p, q, margin } = *border;
        // The x range an edge reaches in one group row is most often the
        // last one's (an upright edge: a facade's corner seen level is
        // most of the city's), so its groups are found again only when
        // it changes.
        let mut found: Option<([f64; 2], Range<u32>)> = None;
        for g in grid
            .down
            .groups_reaching(p.y.min(q.y) - margin, p.y.max(q.y) + margin, &self.rows)
        {
            let (row, k, [y0, y1]) = grid.down.group(g);
            // The edge's part within the margin of the group's rows, and
            // its x range.
            let [from, to] = if p.y == q.y {
                [0.0, 1.0]
            } else {
                let at = |y: f64| (y - p.y) / (q.y - p.y);
                let (s, t) = (at(y0 - margin), at(y1 + margin));
                [s.min(t).max(0.0), s.max(t).min(1.0)]
            };
            let (xa, xb) = (p.x + (q.x - p.x) * from, p.x + (q.x - p.x) * to);
            let reach = [xa.min(xb) - margin, xa.max(xb) + margin];
            let groups = match &found {
                Some((last, groups)) if *last == reach => groups.clone(),
                _ => {
                    let groups = grid.across.groups_reaching(reach[0], reach[1], &self.columns);
                    found = Some((reach, groups.clone()));
                    groups
                }
            };
            for (column, bits) in grid.across.cells_of(groups) {
                let i = self.cover_index(column, row);
                let bits = bits << (k * MASK_SIDE);
                if self.cover[i].mask & bits != 0 {
                    self.cover[i].erased |= self.cover[i].mask & bits;
                    self.cover[i].mask &= !bits;
                    let in_patch = (row - self.rows.start) as usize;
                    self.erased[in_patch] = widened(&self.erased[in_patch], &(column..column + 1));
                }
            }
        }
    }
}

/// `span` grown to hold `by` too (either may be empty).
fn widened(span: &Range<u32>, by: &Range<u32>) -> Range<u32> {
    match (span.is_empty(), by.is_empty()) {
        (true, _) => by.clone(),
        (_, true) => span.clone(),
        _ => span.start.min(by.start)..span.end.max(by.end),
    }
}

/// The bits of one row of a cell's groups (`groups`, each its first and
/// last centre) whose every centre lies within `[from, to]`.
fn groups_within(groups: &[[f64; 2]], [from, to]: [f64; 2]) -> u64 {
    groups
        .iter()
        .rev()
        .fold(0, |bits, &[g0, g1]| bits << 1 | u64::from(from <= g0 && g1 <= to))
}

/// One edge of a triangle as a limit on x along rows of pixel centres:
/// where its inward edge function e(x, y) = ex · x + ey · y + ec
/// ([`inward_edges`]) is at least minus a margin, the margin being its
/// |ex| + |ey| times the triangle's slack ([`REACHED`]), its snap
/// ([`MARKED`]) or minus a border's margin ([`HELD`]). Solved for x once
/// per triangle, so a row takes a product and a sum per edge.
#[derive(Clone, Copy, Debug)]
enum Limit {
    /// x at least `slope · y + offsets[margin]` (ex > 0).
    From { slope: f64, offsets: [f64; 3] },
    /// x at most `slope · y + offsets[margin]` (ex < 0).
    To { slope: f64, offsets: [f64; 3] },
    /// A horizontal edge (ex = 0): e(x, y) = ey · y + ec, whatever x,
    /// against `margins`.
    Level { ey: f64, ec: f64, margins: [f64; 3] },
}

/// The margins of a [`Limit`]: the triangle's slack, where it may reach a
/// centre; its snap, where it marks one; inside by its slack, where
/// it holds one alone.
const REACHED: usize = 0;
const MARKED: usize = 1;
const HELD: usize = 2;

impl Limit {
    fn new([ex, ey, ec]: [f64; 3], margins: [f64; 3]) -> Limit {
        let offsets = margins.map(|m| -(m + ec) / ex);
        let slope = -ey / ex;
        if ex > 0.0 {
            Limit::From { slope, offsets }
        } else if ex < 0.0 {
            Limit::To { slope, offsets }
        } else {
            Limit::Level { ey, ec, margins }
        }
    }
}

/// The x range in which each edge of `limits` is within its margin
/// `margin` at some point of the rows `ys` (`[low, high]`), for `every` =
/// false, or at every point of them, for `every` = true (edges are
/// linear, so at both ends). Empty when there is none.
///
/// An edge so near level that solving it for x overflows (ex below about
/// 1e-308) gives no number at some rows: the reach passes it over there
/// (it may only grow), and the mark holds nothing (it may only shrink).
fn x_range(limits: &[Limit; 3], ys: [f64; 2], margin: usize, every: bool) -> [f64; 2] {
    debug_assert!(
        ys[0].partial_cmp(&ys[1]).is_none_or(|o| o.is_le()),
        "rows {ys:?} out of order"
    );
    const NONE: [f64; 2] = [f64::INFINITY, f64::NEG_INFINITY];
    let (mut from, mut to) = (f64::NEG_INFINITY, f64::INFINITY);
    // The ends of `ys` where a line of `slope` is least, and greatest.
    let lower = |slope: f64| if slope > 0.0 { ys[0] } else { ys[1] };
    let upper = |slope: f64| if slope > 0.0 { ys[1] } else { ys[0] };
    // For every point of the rows, x at least a line takes the line's
    // rightmost end (x at most one, its leftmost); for some point, the other
    // end. (Two arms rather than one with a flag: 1 % fewer instructions in
    // the frame.)
    for limit in limits {
        match *limit {
            Limit::From { slope, offsets } => {
                let x = slope * if every { upper(slope) } else { lower(slope) } + offsets[margin];
                if every && x.is_nan() {
                    return NONE;
                }
                from = from.max(x);
            }
            Limit::To { slope, offsets } => {
                let x = slope * if every { lower(slope) } else { upper(slope) } + offsets[margin];
                if every && x.is_nan() {
                    return NONE;
                }
                to = to.min(x);
            }
            Limit::Level { ey, ec, margins } => {
                let at = |y: f64| ey * y + ec + margins[margin];
                let (first, last) = (at(ys[0]), at(ys[1]));
                let within = if every { first.min(last) } else { first.max(last) };
                if within.partial_cmp(&0.0).is_none_or(|o| o.is_lt()) {
                    to = f64::NEG_INFINITY;
                }
            }
        }
    }
    [from, to]
}

/// A patch triangle, with what rasterising it takes.
struct Triangle {
    /// The bounds of its corners (x, y).
    lo: DVec2,
    hi: DVec2,
    /// Its corners' error ([`slack_of`]), the part of it the GPU's snap
    /// makes ([`ScreenMesh::snap`]), its edges as limits on x (margins
    /// scaled by each edge's |ex| + |ey|: what a distance on each axis
    /// scales it by), and the plane it vouches for ([`bounding`]).
    slack: f64,
    snap: f64,
    limits: [Limit; 3],
    plane: ScreenPlane,
}

impl Triangle {
    /// The triangle of `corners` (`snap` as [`ScreenMesh::snap`]), its
    /// plane taken `depth_slack` from each point ([`depth_slack`]) and
    /// `error` farther ([`DepthMargins::fragment_error`]).
    fn new(corners: [ScreenVertex; 3], snap: f64, depth_slack: f64, error: f64) -> Triangle {
        let (slack, edges) = (slack_of(&corners), inward_edges(&corners));
        // What it reaches holds what it marks (add_triangle).
        debug_assert!(
            slack.partial_cmp(&snap).is_none_or(|o| o.is_ge()),
            "slack {slack} below the snap {snap}"
        );
        let at = corners.map(|c| c.at.truncate());
        Triangle {
            lo: at[0].min(at[1]).min(at[2]),
            hi: at[0].max(at[1]).max(at[2]),
            slack,
            snap,
            limits: edges.map(|edge| {
                let reach = edge[0].abs() + edge[1].abs();
                Limit::new(edge, [slack * reach, snap * reach, -slack * reach])
            }),
            plane: bounding(plane_of(&corners), &corners, depth_slack, error, Bound::Farther),
        }
    }

    /// Where in x some point of the rows `ys` lies within the slack of the
    /// triangle on each axis: within its corners' bounds grown by the
    /// slack, and within the slack of every edge's half-plane (there an
    /// edge function is at least −slack · (|ex| + |ey|)).
    fn reached_x_range(&self, ys: [f64; 2]) -> [f64; 2] {
        let [from, to] = x_range(&self.limits, ys, REACHED, false);
        [from.max(self.lo.x - self.slack), to.min(self.hi.x + self.slack)]
    }

    /// Where in x every centre of the rows `ys` lies inside the triangle
    /// or within its snap of it on each axis (at most any border's
    /// margin, a corner's error, which holds the snap; a border erases
    /// the centres at its margin too, so a centre outside the patch it
    /// marks is erased). That
    /// region is the triangle grown by a square: inside each edge moved
    /// out by the snap and inside its bounds grown by it (without the
    /// bounds, the moved edges of a sharp corner meet far beyond it). None
    /// for rows reaching outside the bounds.
    fn marked_x_range(&self, ys: [f64; 2]) -> [f64; 2] {
        let (lo, hi) = (self.lo - self.snap, self.hi + self.snap);
        if lo.y <= ys[0] && ys[1] <= hi.y {
            let [from, to] = x_range(&self.limits, ys, MARKED, true);
            [from.max(lo.x), to.min(hi.x)]
        } else {
            [f64::INFINITY, f64::NEG_INFINITY]
        }
    }

    /// Where in x every centre of the rows `ys` lies inside the triangle
    /// by its slack on each axis, a border's margin ([`Border`]):
    /// wherever the GPU places its corners, it holds those centres.
    fn held_x_range(&self, ys: [f64; 2]) -> [f64; 2] {
        x_range(&self.limits, ys, HELD, true)
    }
}

/// A drawn triangle's corners (where they are among the mesh's vertices),
/// when the GPU places them all.
fn placed_corners(mesh: &ScreenMesh, corners: [u32; 3]) -> Option<[ScreenVertex; 3]> {
    let vertex = |k: usize| mesh.vertices[corners[k] as usize];
    Some([vertex(0)?, vertex(1)?, vertex(2)?])
}

/// The error of a triangle's corners: the largest.
fn slack_of(corners: &[ScreenVertex; 3]) -> f64 {
    corners.iter().map(|c| c.slack).fold(0.0, f64::max)
}

/// The turn of a closed solid's triangles that lies behind the other
/// turn's and covers no more of the screen (its far side), if one does: it
/// is left out, since the other turn's triangles hide it wherever it would
/// be drawn (leaving out a patch is always safe).
fn behind_turn(mesh: &ScreenMesh, corners: &[[u32; 3]], turns: &[Turn]) -> Option<Turn> {
    // Per turn: screen area, and area times mean depth.
    let mut sums = [[0.0f64; 2]; 2];
    for (t, &turn) in turns.iter().enumerate() {
        if let (Turn::Counter | Turn::Clockwise, Some(c)) = (turn, placed_corners(mesh, corners[t])) {
            let area = twice_area(c[0].at, c[1].at, c[2].at).abs();
            let sum = &mut sums[usize::from(turn == Turn::Clockwise)];
            sum[0] += area;
            sum[1] += area * (c[0].at.z + c[1].at.z + c[2].at.z);
        }
    }
    let [[counter, counter_depth], [clockwise, clockwise_depth]] = sums;
    // Nearer means a greater mean depth (reverse-Z); areas a twentieth
    // apart count as alike (slivers left out of the nearer side).
    if clockwise <= counter * 1.05 && clockwise_depth * counter < counter_depth * clockwise {
        Some(Turn::Clockwise)
    } else if counter <= clockwise * 1.05 && counter_depth * clockwise < clockwise_depth * counter {
        Some(Turn::Counter)
    } else {
        None
    }
}

/// The way a triangle turns on screen by its signed area, or none where
/// that is 0 or not a number.
fn area_turn(corners: &[ScreenVertex; 3]) -> Turn {
    let [a, b, c] = corners.map(|c| c.at);
    let area = twice_area(a, b, c);
    if !area.is_finite() || area == 0.0 {
        Turn::Excluded
    } else if area > 0.0 {
        Turn::Counter
    } else {
        Turn::Clockwise
    }
}

/// How far from a point the triangle's plane is taken, at least, to bound
/// the depth the GPU draws it at there ([`bounding`]): its corners'
/// error (`snap` as [`ScreenMesh::snap`]), and more for one thinner than
/// [`LEAST_HEIGHT`] errors at [`SLIVER_SNAP`] ([`interpolation_slack`]).
/// None for a sliver, in no patch: less than [`LEAST_HEIGHT`] errors high
/// over an edge at its own snap, thinner than that at [`SLIVER_SNAP`]
/// where its interpolation is not bounded, or not a number.
fn depth_slack(corners: &[ScreenVertex; 3], snap: f64) -> Option<f64> {
    let [a, b, c] = corners.map(|c| c.at);
    let twice_area = twice_area(a, b, c).abs();
    let longest_squared = [(a, b), (b, c), (c, a)]
        .iter()
        .map(|(p, q)| (q.truncate() - p.truncate()).length_squared())
        .fold(0.0, f64::max);
    // Twice the area over the longest edge is the least height; squared,
    // to spare the roots (false for a NaN).
    let high = |least: f64| twice_area * twice_area >= least * least * longest_squared;
    let slack = slack_of(corners);
    if !high(LEAST_HEIGHT * 2.0 * slack) {
        None
    } else if high(LEAST_HEIGHT * 2.0 * (slack - snap + SLIVER_SNAP)) {
        Some(slack)
    } else {
        interpolation_slack(corners, twice_area, longest_squared.sqrt(), slack, snap)
    }
}

/// Where the GPU's f32 interpolation of depth across a thin triangle
/// (`twice_area` and `longest` edge on screen, corners within `slack` of
/// where the GPU places them, `snap` of it the sub-pixel grid's) is
/// bounded, how far from a point its plane must be taken ([`depth_slack`]).
/// A rasteriser evaluates the placed triangle's depth plane, whose
/// gradient it divides by the triangle's area; where that is small
/// against the longest edge squared (its height h against its length L),
/// roundings are magnified by L / h. Each source of error gets its own
/// allowance, s being [`INTERPOLATION_STEPS`] steps of f32:
/// - placing the corners moves the point the plane is taken at by at most
///   the slack, as for every triangle;
/// - the area's rounding (its cancellation: of L², relatively) scales the
///   gradient by s · L / h relatively, which moves the point by
///   s · L² / h from the corner the plane is anchored at: allowed up to
///   the slack, and added to it;
/// - the rounding of the products of corner differences (of Δz · L for a
///   depth range Δz), s · Δz / h in the gradient and s · Δz · L / h in
///   depth over the triangle: allowed up to half of [`DEPTH_MARGIN`] of
///   the triangle's farthest depth (the other half holds the rounding of
///   an ordinary triangle's interpolation);
/// - a plane anchored at the screen's origin rounds by a few steps of
///   |∇z| · X more, X up to the target's size: the slack's part beyond the
///   snap (2^-21 of the target's size, eight steps) is added for it.
fn interpolation_slack(
    corners: &[ScreenVertex; 3],
    twice_area: f64,
    longest: f64,
    slack: f64,
    snap: f64,
) -> Option<f64> {
    let depths = corners.map(|c| c.at.z);
    let farthest = depths.iter().copied().fold(f64::INFINITY, f64::min);
    let range = depths.iter().copied().fold(f64::NEG_INFINITY, f64::max) - farthest;
    let steps = INTERPOLATION_STEPS * F32_STEP;
    let height = twice_area / longest;
    let moved = steps * longest * longest / height;
    // False for a NaN.
    let bounded = steps * range * longest <= DEPTH_MARGIN / 2.0 * farthest * height && moved <= slack;
    bounded.then_some(slack + moved + (slack - snap))
}

/// Twice the signed area of the screen triangle pqr: its sign is its
/// turn.
fn twice_area(p: DVec3, q: DVec3, r: DVec3) -> f64 {
    (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x)
}

/// The triangle's inward edge functions (ex, ey, ec): e(x, y) = ex · x +
/// ey · y + ec is positive inside. A point within d of an edge's line on
/// each axis has e at least −d · (|ex| + |ey|) (distances on each axis, as
/// the slacks are, need no square roots).
fn inward_edges(corners: &[ScreenVertex; 3]) -> [[f64; 3]; 3] {
    let [a, b, c] = corners.map(|c| c.at);
    let turn = twice_area(a, b, c).signum();
    [(a, b), (b, c), (c, a)].map(|(p, q)| {
        let (dx, dy) = (q.x - p.x, q.y - p.y);
        // inside(x, y) = turn · ((q − p) × ((x, y) − p))
        [-dy * turn, dx * turn, (dy * p.x - dx * p.y) * turn]
    })
}

/// Which way [`bounding`] moves a depth plane.
#[derive(Clone, Copy, PartialEq)]
enum Bound {
    /// At most every depth the GPU may draw it at: what it vouches for.
    Farther,
    /// At least every such depth: where the fragment stage must keep it.
    Nearer,
}

/// The plane of the triangle's depth on screen.
fn plane_of(corners: &[ScreenVertex; 3]) -> ScreenPlane {
    let [a, b, c] = corners.map(|c| c.at);
    let area = twice_area(a, b, c);
    let per_x = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) / area;
    let per_y = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / area;
    ScreenPlane {
        per_x,
        per_y,
        constant: a.z - per_x * a.x - per_y * a.y,
    }
}

/// `plane`, a depth the GPU draws the triangle of `corners` at from a point
/// within `slack` of each pixel centre it draws, moved to bound what it
/// draws there: by the plane's greatest change within the slack, then by
/// the depth margins ([`DEPTH_MARGIN`], the corners' depth error, and the
/// GPU's `error`), all affine.
fn bounding(plane: ScreenPlane, corners: &[ScreenVertex; 3], slack: f64, error: f64, bound: Bound) -> ScreenPlane {
    let depth_error = corners.iter().map(|c| c.depth_error).fold(0.0, f64::max);
    let toward = if bound == Bound::Nearer { 1.0 } else { -1.0 };
    let scale = 1.0 + toward * (DEPTH_MARGIN + depth_error);
    let change = slack * (plane.per_x.abs() + plane.per_y.abs());
    ScreenPlane {
        per_x: plane.per_x * scale,
        per_y: plane.per_y * scale,
        constant: (plane.constant + toward * change) * scale + toward * error,
    }
}

/// Whether the scene's fragment stage keeps every fragment the GPU may
/// draw of the triangle (its plane taken `slack` from each point, its
/// depth drawn within `error`), which lies in its object's box: below each
/// face of the box that faces the eye, the nearest depth it may draw it at
/// lies at or below what the face keeps ([`FacingFace`]), at every point
/// within the slack of it (false for a NaN). At a pixel centre p the GPU
/// draws the depth of a point q of our triangle within the slack of p
/// (p's weights in the placed triangle, taken in ours), and no point of
/// the box lies nearer than the face: so both the triangle's plane and
/// the face's, each moved as far as q may lie ([`bounding`]), bound it,
/// and either will do. Each gap is affine: its greatest value over the
/// triangle grown by the slack is at a corner, plus the slack times its
/// change per pixel on each axis. A sliver's own interpolation may take q
/// off the triangle (`interpolation_slack`), and out of the box: for a
/// sliver only its own plane bounds.
fn kept(corners: &[ScreenVertex; 3], slack: f64, error: f64, facing: &[Option<FacingFace>; 3]) -> bool {
    if facing.iter().all(Option::is_none) {
        return true;
    }
    let within = |nearest: ScreenPlane, kept_below: &ScreenPlane| {
        let gap = nearest.minus(kept_below);
        let reach = slack * (gap.per_x.abs() + gap.per_y.abs());
        corners.iter().all(|c| gap.at(c.at.x, c.at.y) + reach <= 0.0)
    };
    let own = bounding(plane_of(corners), corners, slack, error, Bound::Nearer);
    // `depth_slack` adds to the corners' error only for a sliver.
    let sliver = slack != slack_of(corners);
    facing.iter().flatten().all(|f| {
        within(own, &f.kept_below)
            || (!sliver && within(bounding(f.face, corners, slack, error, Bound::Nearer), &f.kept_below))
    })
}

/// `range` within `within`.
fn clamp(range: Range<u32>, within: &Range<u32>) -> Range<u32> {
    let start = range.start.max(within.start);
    start..range.end.min(within.end).max(start)
}

/// Rasterises `meshes` (each one object's screen vertices, all placed,
/// and three indices per triangle; equal indices are the only shared
/// positions) into `buffer`, cleared first, in order, on one thread. A
/// mesh's snap is its vertices' least slack: they have no f32 error.
/// Depth margins are GL's ([`larger_margins`]).
#[cfg(test)]
pub(super) fn rasterise_meshes(buffer: &mut super::buffer::OcclusionBuffer, meshes: &[(Vec<ScreenVertex>, Vec<u32>)]) {
    let rows = buffer.cells().height;
    let Some(mut cells) = buffer.cleared_bands(rows).next() else {
        return;
    };
    let (mut patches, mut rasteriser) = (Patches::default(), Rasteriser::default());
    for (vertices, indices) in meshes {
        patches.clear();
        let which = add_patches(&mut patches, vertices, indices);
        rasteriser.rasterise(&mut cells, &patches, which);
    }
}

/// Adds to `patches` the patches of one object's screen vertices, all
/// placed, and three indices per triangle, as [`rasterise_meshes`] takes
/// them; returns which they are.
#[cfg(test)]
fn add_patches(patches: &mut Patches, vertices: &[ScreenVertex], indices: &[u32]) -> Range<usize> {
    let placed: Vec<Option<ScreenVertex>> = vertices.iter().map(|&v| Some(v)).collect();
    let neighbours = super::neighbours::neighbours(indices, |i| [i as f32, 0.0, 0.0]);
    patches.add(&ScreenMesh {
        vertices: &placed,
        parts: &[DrawnPart::whole(indices)],
        indices,
        neighbours: &neighbours,
        closed: false,
        near: None,
        snap: vertices.iter().map(|v| v.slack).fold(f64::INFINITY, f64::min),
        depth: larger_margins(),
    })
}

/// The depth margins the tests take: GL's, the larger.
#[cfg(test)]
fn larger_margins() -> DepthMargins {
    DepthMargins::for_backend(wgpu::Backend::Gl)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::swr::buffer::OcclusionBuffer;
    use crate::gpu::Resolution;
    use crate::rng::Rng;

    /// The snap of Vulkan's coarsest sub-pixel grid, which most tests take,
    /// and that of the 8 bits adapters report here.
    const COARSE_SNAP: f64 = SLIVER_SNAP;
    const FINE_SNAP: f64 = 1.0 / 256.0;

    fn vertex(x: f64, y: f64, z: f64) -> ScreenVertex {
        ScreenVertex {
            at: DVec3::new(x, y, z),
            slack: COARSE_SNAP,
            depth_error: 0.0,
        }
    }

    /// A grid of `columns` × `rows` corners `step` pixels apart from
    /// `origin`, each quad split in two, turning the same way (reversed
    /// when `mirrored`), at depth `depth(x, y)`.
    fn grid(
        origin: DVec2,
        step: DVec2,
        [columns, rows]: [u32; 2],
        mirrored: bool,
        depth: impl Fn(f64, f64) -> f64,
    ) -> (Vec<ScreenVertex>, Vec<u32>) {
        let mut vertices = Vec::new();
        for j in 0..rows {
            for i in 0..columns {
                let p = origin + step * DVec2::new(f64::from(i), f64::from(j));
                vertices.push(vertex(p.x, p.y, depth(p.x, p.y)));
            }
        }
        let mut indices = Vec::new();
        for j in 0..rows - 1 {
            for i in 0..columns - 1 {
                let at = |di: u32, dj: u32| (j + dj) * columns + i + di;
                let (a, b, c, d) = (at(0, 0), at(1, 0), at(1, 1), at(0, 1));
                for t in [[a, b, c], [a, c, d]] {
                    indices.extend(if mirrored { [t[0], t[2], t[1]] } else { t });
                }
            }
        }
        (vertices, indices)
    }

    /// `pieces` (each its vertices and three indices a triangle) as one
    /// mesh, in their order: one object's disjoint patches.
    fn one_mesh(pieces: impl IntoIterator<Item = (Vec<ScreenVertex>, Vec<u32>)>) -> (Vec<ScreenVertex>, Vec<u32>) {
        let (mut vertices, mut indices) = (Vec::new(), Vec::new());
        for (piece, triangles) in pieces {
            let first = vertices.len() as u32;
            indices.extend(triangles.iter().map(|i| first + i));
            vertices.extend(piece);
        }
        (vertices, indices)
    }

    /// Meshes on screen, each as its vertices and three indices a
    /// triangle.
    type Meshes = Vec<(Vec<ScreenVertex>, Vec<u32>)>;

    /// Random meshes over a `size` target: grids of triangles from a third
    /// of a pixel to tens of pixels, curved in depth, some with corners
    /// moved far enough to fold them over themselves or squashed into
    /// slivers, and loose triangles.
    fn random_meshes(rng: &mut Rng, size: Resolution, count: usize) -> Meshes {
        let (w, h) = (f64::from(size.width), f64::from(size.height));
        (0..count)
            .map(|k| {
                let step = DVec2::new(rng.range(0.3, 12.0), rng.range(0.3, 12.0));
                let origin = DVec2::new(rng.range(-0.3 * w, w), rng.range(-0.3 * h, h));
                let counts = [rng.range(2.0, 24.0) as u32, rng.range(2.0, 24.0) as u32];
                let (z0, gx, gy, bend) = (
                    rng.range(0.2, 0.8),
                    rng.range(-0.3, 0.3) / w,
                    rng.range(-0.3, 0.3) / h,
                    rng.range(0.0, 0.1),
                );
                let depth = move |x: f64, y: f64| z0 + gx * x + gy * y + bend * ((x / 7.0).sin() * (y / 5.0).cos());
                let (mut vertices, mut indices) = grid(origin, step, counts, rng.range(0.0, 1.0) < 0.5, depth);
                match k % 4 {
                    // Folds: some corners moved by up to three steps.
                    0 => {
                        for v in vertices.iter_mut() {
                            if rng.range(0.0, 1.0) < 0.1 {
                                v.at.x += step.x * rng.range(-3.0, 3.0);
                                v.at.y += step.y * rng.range(-3.0, 3.0);
                            }
                        }
                    }
                    // Jitter, and now and then a row squashed to slivers.
                    1 => {
                        for v in vertices.iter_mut() {
                            v.at.x += step.x * rng.range(-0.3, 0.3);
                            v.at.y += if rng.range(0.0, 1.0) < 0.05 {
                                0.0
                            } else {
                                step.y * rng.range(-0.3, 0.3)
                            };
                        }
                    }
                    // Loose triangles: every corner its own.
                    2 => {
                        let corners: Vec<ScreenVertex> = indices.iter().map(|&i| vertices[i as usize]).collect();
                        indices = (0..corners.len() as u32).collect();
                        vertices = corners;
                    }
                    _ => {}
                }
                (vertices, indices)
            })
            .collect()
    }

    /// The nearest depth the GPU may draw at each pixel centre of `size`
    /// (0 where it draws nothing), with every corner placed its slack from
    /// where the mesh has it on each axis, either way at random (one
    /// placement per corner, for all its triangles), depths interpolated
    /// exactly.
    fn drawn(meshes: &[(Vec<ScreenVertex>, Vec<u32>)], size: Resolution, rng: &mut Rng) -> Vec<f64> {
        let mut nearest = vec![0.0f64; (size.width * size.height) as usize];
        for (vertices, indices) in meshes {
            let mut shift = |slack: f64| if rng.range(0.0, 1.0) < 0.5 { -slack } else { slack };
            let placed: Vec<DVec3> = vertices
                .iter()
                .map(|v| v.at + DVec3::new(shift(v.slack), shift(v.slack), 0.0))
                .collect();
            for t in indices.chunks_exact(3) {
                paint(&mut nearest, size, [0, 1, 2].map(|k| placed[t[k] as usize]));
            }
        }
        nearest
    }

    /// Asserts that at no pixel centre of the target `buffer` (of `cells`)
    /// vouches for a depth nearer than `nearest` (what the GPU may draw
    /// there, pixel by pixel).
    fn assert_vouches_no_nearer(buffer: &OcclusionBuffer, nearest: &[f64], cells: Resolution) {
        let size = buffer.target();
        for py in 0..size.height {
            for px in 0..size.width {
                let (x, y) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
                let holds = buffer.vouched_at(x, y);
                let shown = nearest[(py * size.width + px) as usize];
                assert!(
                    holds <= shown,
                    "{cells:?}: the buffer vouches for {holds} at ({x}, {y}), where the GPU may draw {shown}"
                );
            }
        }
    }

    /// Raises `nearest` to the depth triangle `[a, b, c]` (pixels and
    /// depth) is drawn at, at each pixel centre of `size` it holds, depth
    /// interpolated exactly.
    fn paint(nearest: &mut [f64], size: Resolution, [a, b, c]: [DVec3; 3]) {
        let area = twice_area(a, b, c);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        let ys =
            (lo.y - 0.5).ceil().max(0.0) as u32..((hi.y - 0.5).floor() + 1.0).clamp(0.0, f64::from(size.height)) as u32;
        let xs =
            (lo.x - 0.5).ceil().max(0.0) as u32..((hi.x - 0.5).floor() + 1.0).clamp(0.0, f64::from(size.width)) as u32;
        for py in ys {
            for px in xs.clone() {
                let p = DVec3::new(f64::from(px) + 0.5, f64::from(py) + 0.5, 0.0);
                let (wa, wb, wc) = (
                    twice_area(p, b, c) / area,
                    twice_area(a, p, c) / area,
                    twice_area(a, b, p) / area,
                );
                if wa >= 0.0 && wb >= 0.0 && wc >= 0.0 {
                    let depth = wa * a.z + wb * b.z + wc * c.z;
                    let at = &mut nearest[(py * size.width + px) as usize];
                    *at = at.max(depth);
                }
            }
        }
    }

    #[test]
    fn a_cell_vouches_for_no_depth_nearer_than_the_gpu_may_draw_at_any_pixel_centre_it_holds() {
        for snap in [COARSE_SNAP, FINE_SNAP] {
            assert_vouches_no_nearer_on_random_meshes(snap);
        }
    }

    /// Random meshes whose corners the GPU places within `snap`: what the
    /// buffer vouches for held against what it may draw, pixel by pixel.
    fn assert_vouches_no_nearer_on_random_meshes(snap: f64) {
        let mut rng = Rng::new(32);
        let size = Resolution {
            width: 160,
            height: 120,
        };
        let (mut vouched, mut small) = (0u64, 0u64);
        for cells in [
            Resolution { width: 53, height: 40 },
            Resolution {
                width: 160,
                height: 120,
            },
            Resolution { width: 16, height: 12 },
        ] {
            for _ in 0..6 {
                let mut meshes = random_meshes(&mut rng, size, 24);
                for vertex in meshes.iter_mut().flat_map(|(vertices, _)| vertices) {
                    vertex.slack = snap;
                }
                let mut buffer = OcclusionBuffer::new(size, cells);
                rasterise_meshes(&mut buffer, &meshes);
                for _ in 0..3 {
                    let nearest = drawn(&meshes, size, &mut rng);
                    assert_vouches_no_nearer(&buffer, &nearest, cells);
                }
                vouched += buffer.depths().iter().filter(|&&d| d > 0.0).count() as u64;
                small += u64::from(
                    meshes
                        .iter()
                        .any(|(v, _)| v.len() > 3 && (v[1].at - v[0].at).length() < 1.0),
                );
            }
        }
        assert!(vouched > 3000, "cells vouched for ({vouched})");
        assert!(small > 3, "meshes of sub-pixel triangles ({small})");
    }

    /// A pinhole view of eye-space points (x right, y up, w ahead) on a
    /// target of 160 × 120 pixels, 100 pixels at unit depth, reverse-Z.
    const NEAR: f64 = 0.1;
    fn on_screen(p: DVec3) -> DVec3 {
        DVec3::new(80.0 + 100.0 * p.x / p.z, 60.0 - 100.0 * p.y / p.z, NEAR / p.z)
    }

    /// Where segment `p` (at or beyond `limit` ahead) to `q` (nearer)
    /// crosses `limit`.
    fn crossing(p: DVec3, q: DVec3, limit: f64) -> DVec3 {
        p + (q - p) * ((p.z - limit) / (p.z - q.z))
    }

    /// Grids that run from behind the eye to 4 to 9 ahead (floors, walls
    /// and slants), jittered, vertices shared.
    fn grids_past_the_eye(rng: &mut Rng) -> Vec<(Vec<DVec3>, Vec<u32>)> {
        (0..10)
            .map(|_| {
                let ahead = DVec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), rng.range(4.0, 9.0));
                let across =
                    DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0).normalize() * rng.range(0.4, 3.0);
                let start = DVec3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), rng.range(-1.0, 0.05));
                let (n, m) = (rng.range(3.0, 16.0) as u32, rng.range(2.0, 8.0) as u32);
                let mut vertices = Vec::new();
                for i in 0..=n {
                    for j in 0..=m {
                        let jitter = DVec3::new(rng.range(-0.01, 0.01), rng.range(-0.01, 0.01), rng.range(-0.01, 0.01));
                        vertices.push(
                            start
                                + ahead * (f64::from(i) / f64::from(n))
                                + across * (f64::from(j) / f64::from(m))
                                + jitter,
                        );
                    }
                }
                let at = |i: u32, j: u32| i * (m + 1) + j;
                let mut indices = Vec::new();
                for i in 0..n {
                    for j in 0..m {
                        indices.extend([
                            at(i, j),
                            at(i + 1, j),
                            at(i + 1, j + 1),
                            at(i, j),
                            at(i + 1, j + 1),
                            at(i, j + 1),
                        ]);
                    }
                }
                (vertices, indices)
            })
            .collect()
    }

    #[test]
    fn a_mesh_the_near_plane_cuts_on_screen_vouches_for_no_depth_nearer_than_the_gpu_may_draw_its_clipped_part_at() {
        for snap in [COARSE_SNAP, FINE_SNAP] {
            assert_vouches_no_nearer_past_the_eye(snap);
        }
    }

    /// Grids the near plane cuts, their vertices and crossings placed by
    /// the GPU within `snap`: what the buffer vouches for held against what
    /// it may draw, pixel by pixel.
    fn assert_vouches_no_nearer_past_the_eye(snap: f64) {
        let mut rng = Rng::new(41);
        let size = Resolution {
            width: 160,
            height: 120,
        };
        let limit = NEAR * (1.0 + 1.0 / 1024.0);
        let placed = |p: DVec3| ScreenVertex {
            at: on_screen(p),
            slack: snap,
            depth_error: 0.0,
        };
        let mut vouched = 0;
        for cells in [size, Resolution { width: 53, height: 40 }] {
            for _ in 0..4 {
                let meshes = grids_past_the_eye(&mut rng);
                let mut buffer = OcclusionBuffer::new(size, cells);
                {
                    let Some(mut band) = buffer.cleared_bands(u32::MAX).next() else {
                        unreachable!()
                    };
                    let (mut patches, mut rasteriser) = (Patches::default(), Rasteriser::default());
                    for (points, indices) in &meshes {
                        let vertices: Vec<Option<ScreenVertex>> =
                            points.iter().map(|&p| (p.z >= limit).then(|| placed(p))).collect();
                        let cross = |p: usize, q: usize| Some(placed(crossing(points[p], points[q], limit)));
                        let neighbours =
                            super::super::neighbours::neighbours(indices, |i| points[i as usize].as_vec3().to_array());
                        let mesh = ScreenMesh {
                            vertices: &vertices,
                            parts: &[DrawnPart::whole(indices)],
                            indices,
                            neighbours: &neighbours,
                            closed: false,
                            near: Some(NearLimit { crossing: &cross }),
                            snap,
                            depth: larger_margins(),
                        };
                        patches.clear();
                        let which = patches.add(&mesh);
                        rasteriser.rasterise(&mut band, &patches, which);
                    }
                }
                // As the GPU may draw them: each triangle clipped on its own
                // at the near plane, its crossings placed on their own, every
                // corner up to a vertex's error from where it projects.
                for _ in 0..3 {
                    let mut nearest = vec![0.0f64; (size.width * size.height) as usize];
                    for (points, indices) in &meshes {
                        let mut shift = || DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0) * snap;
                        let moved: Vec<DVec3> = points.iter().map(|_| shift()).collect();
                        for t in indices.chunks_exact(3) {
                            let mut polygon = Vec::new();
                            for k in 0..3 {
                                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                                let (p, q) = (points[i], points[j]);
                                if p.z >= NEAR {
                                    polygon.push(on_screen(p) + moved[i]);
                                }
                                if (p.z >= NEAR) != (q.z >= NEAR) {
                                    let (inside, outside) = if p.z >= NEAR { (p, q) } else { (q, p) };
                                    polygon.push(on_screen(crossing(inside, outside, NEAR)) + shift());
                                }
                            }
                            for k in 1..polygon.len().saturating_sub(1) {
                                paint(&mut nearest, size, [polygon[0], polygon[k], polygon[k + 1]]);
                            }
                        }
                    }
                    assert_vouches_no_nearer(&buffer, &nearest, cells);
                }
                vouched += buffer.depths().iter().filter(|&&d| d > 0.0).count();
            }
        }
        assert!(vouched > 5000, "cells vouched for ({vouched})");
    }

    /// Whether the point (x, y) lies within `m` of triangle `t` on each
    /// axis: whether the square of half-side `m` round it meets the
    /// triangle (a corner of either inside the other, or crossing edges).
    fn within_square(t: [DVec2; 3], x: f64, y: f64, m: f64) -> bool {
        let (lo, hi) = (DVec2::new(x - m, y - m), DVec2::new(x + m, y + m));
        let square = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
        let inside_triangle = |p: DVec2| {
            let s = [cross(t[0], t[1], p), cross(t[1], t[2], p), cross(t[2], t[0], p)];
            s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
        };
        let crosses = |a: DVec2, b: DVec2, c: DVec2, d: DVec2| {
            cross(a, b, c) * cross(a, b, d) <= 0.0 && cross(c, d, a) * cross(c, d, b) <= 0.0
        };
        t.iter().any(|p| p.cmpge(lo).all() && p.cmple(hi).all())
            || square.iter().any(|&p| inside_triangle(p))
            || (0..3).any(|i| (0..4).any(|j| crosses(t[i], t[(i + 1) % 3], square[j], square[(j + 1) % 4])))
    }

    #[test]
    fn a_triangle_marks_no_pixel_centre_farther_than_its_snap_from_it() {
        // A finer snap marks fewer centres beside sharp corners.
        for (snap, least_sharp) in [(COARSE_SNAP, 1000), (FINE_SNAP, 900)] {
            assert_marks_within(snap, least_sharp);
        }
    }

    /// `least_sharp`: the fewest marks of sharp triangles the random
    /// triangles must make, so that they are tested.
    fn assert_marks_within(snap: f64, least_sharp: usize) {
        // Random triangles over 64 × 48 pixels in cells of 4 × 4, many of
        // them long and thin (sharp corners, where the edges moved out by
        // the snap meet far beyond the corner).
        let mut rng = Rng::new(41);
        let size = Resolution { width: 64, height: 48 };
        let mut buffer = OcclusionBuffer::new(size, Resolution { width: 16, height: 12 });
        let Some(cells) = buffer.cleared_bands(12).next() else {
            panic!("one band")
        };
        let mut rasteriser = Rasteriser::default();
        let (mut marked, mut sharp_checked, mut inside_checked) = (0, 0, 0);
        for k in 0..600 {
            let a = DVec2::new(rng.range(-8.0, 72.0), rng.range(-8.0, 56.0));
            let b = a + DVec2::new(rng.range(-30.0, 30.0), rng.range(-30.0, 30.0));
            let c = match k % 4 {
                // Within a pixel of the line ab, past b: a sharp corner at a.
                0 | 2 => b + (b - a).normalize_or_zero().perp() * rng.range(-1.0, 1.0),
                // Level with a: a horizontal edge.
                1 => DVec2::new(rng.range(-8.0, 72.0), a.y),
                _ => DVec2::new(rng.range(-8.0, 72.0), rng.range(-8.0, 56.0)),
            };
            let corners = [a, b, c].map(|p| ScreenVertex {
                slack: snap,
                ..vertex(p.x, p.y, 0.5)
            });
            if twice_area(corners[0].at, corners[1].at, corners[2].at) == 0.0 {
                continue;
            }
            rasteriser.begin_patch(0..16, 0..12);
            // Every cell vouching for a depth already (the triangle marks
            // only such cells; it lies nearer than the cleared cells).
            let reached = CellCover {
                depth: CellDepth::AtLeast {
                    least: 0.5,
                    plane: ScreenPlane::default(),
                },
                ..EMPTY
            };
            rasteriser.cover.clear();
            rasteriser.cover.resize(16 * 12, reached);
            rasteriser.add_triangle(&cells, 0, &Triangle::new(corners, snap, snap, 0.0));
            // Every pixel centre inside the triangle is marked (each cell's
            // groups here are single pixels).
            for (x, y) in (0..64).flat_map(|x| (0..48).map(move |y| (x, y))) {
                let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let inside = (0..3).all(|i| {
                    let (p, q, r) = ([a, b, c][i], [a, b, c][(i + 1) % 3], [a, b, c][(i + 2) % 3]);
                    let side = |z: DVec2| (q - p).perp_dot(z - p);
                    side(centre) * side(r).signum() > 1e-9 * (q - p).length()
                });
                let cover = &rasteriser.cover[x / 4 + 16 * (y / 4)];
                assert!(
                    !inside || cover.mask >> (x % 4 + 8 * (y % 4)) & 1 == 1,
                    "{:?} leaves {centre} unmarked",
                    [a, b, c]
                );
                inside_checked += usize::from(inside);
            }
            for (i, cover) in rasteriser.cover.iter().enumerate() {
                for bit in (0..64).filter(|b| cover.mask >> b & 1 == 1) {
                    let (x, y) = (4 * (i % 16) + bit % 8, 4 * (i / 16) + bit / 8);
                    let centre = (x as f64 + 0.5, y as f64 + 0.5);
                    assert!(
                        within_square([a, b, c], centre.0, centre.1, snap * (1.0 + 1e-9)),
                        "{:?} marks {centre:?}",
                        [a, b, c]
                    );
                    marked += 1;
                    sharp_checked += usize::from(k % 2 == 0);
                }
            }
            rasteriser.cover.fill(EMPTY);
        }
        assert!(
            marked > 10_000 && sharp_checked > least_sharp,
            "{marked} marks, {sharp_checked} of sharp triangles"
        );
        assert!(inside_checked > 10_000, "{inside_checked} centres inside");
    }

    #[test]
    fn an_edge_too_near_level_to_solve_for_x_marks_nothing_and_limits_no_reach() {
        // e(x, y) = 5e-324 · x + y − 10: level to within the least f64, so
        // its slope and offsets overflow, and at a row below y = 10 they
        // give no number.
        let level = Limit::new([5e-324, 1.0, -10.0], [0.25, 0.0625, -0.25]);
        let within = Limit::new([1.0, 0.0, 0.0], [0.25, 0.0625, -0.25]);
        let limits = [level, within, within];
        let ys = [4.5, 5.5];
        for margin in [MARKED, HELD] {
            let [from, to] = x_range(&limits, ys, margin, true);
            assert!(
                from.partial_cmp(&to).is_none_or(|o| o.is_gt()),
                "marks [{from}, {to}] below the edge"
            );
        }
        let [from, to] = x_range(&limits, ys, REACHED, false);
        assert!(from <= 0.0 && to == f64::INFINITY, "reaches only [{from}, {to}]");
    }

    #[test]
    fn a_closed_solids_far_side_is_the_turn_behind_the_other_and_no_larger() {
        // A box seen face on: its near face (10 × 10 pixels at depth 0.5)
        // turns one way, its far face (6 × 6 at 0.4) the other.
        let turns_of = |near: f64, far: f64| {
            let mut vertices: Vec<Option<ScreenVertex>> = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
                .iter()
                .map(|&(x, y)| Some(vertex(x, y, near)))
                .collect();
            vertices.extend(
                [(2.0, 2.0), (8.0, 2.0), (8.0, 8.0), (2.0, 8.0)]
                    .iter()
                    .map(|&(x, y)| Some(vertex(x, y, far))),
            );
            let indices = [0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6];
            let neighbours = super::super::neighbours::neighbours(&indices, |i| [i as f32, 0.0, 0.0]);
            let mesh = ScreenMesh {
                vertices: &vertices,
                parts: &[DrawnPart::whole(&indices)],
                indices: &indices,
                neighbours: &neighbours,
                closed: true,
                near: None,
                snap: COARSE_SNAP,
                depth: larger_margins(),
            };
            let corners: Vec<[u32; 3]> = indices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
            let turns: Vec<Turn> = corners
                .iter()
                .map(|&c| {
                    placed_corners(&mesh, c)
                        .filter(|c| depth_slack(c, COARSE_SNAP).is_some())
                        .map_or(Turn::Excluded, |c| area_turn(&c))
                })
                .collect();
            (turns.clone(), behind_turn(&mesh, &corners, &turns))
        };
        let (turns, behind) = turns_of(0.5, 0.4);
        assert_eq!(turns, [Turn::Counter, Turn::Counter, Turn::Clockwise, Turn::Clockwise]);
        assert_eq!(behind, Some(Turn::Clockwise));
        // The smaller face nearer: neither is left out.
        assert_eq!(turns_of(0.4, 0.5).1, None);
    }

    #[test]
    fn a_mesh_of_triangles_smaller_than_a_cell_fills_the_cells_it_covers() {
        // 1.5-pixel triangles over a 96 × 72 target in cells of 4 × 4
        // pixels, at depth 0.5: every cell but those within a border's
        // margin of the mesh's outline takes the depth, less its margins.
        let size = Resolution { width: 96, height: 72 };
        let mut buffer = OcclusionBuffer::new(size, Resolution { width: 24, height: 18 });
        let mesh = grid(DVec2::new(10.0, 10.0), DVec2::splat(1.5), [53, 37], false, |_, _| 0.5);
        rasterise_meshes(&mut buffer, &[mesh]);
        // The mesh spans pixels 10 to 88 across and 10 to 64 down: cells
        // 3 to 21 and 3 to 15 lie inside by more than the margin.
        for (i, &depth) in buffer.depths().iter().enumerate() {
            let (column, row) = (i % 24, i / 24);
            let inside = (3..=21).contains(&column) && (3..=15).contains(&row);
            if inside {
                assert!(depth > 0.499 && depth < 0.5, "cell ({column}, {row}) holds {depth}");
            } else if !(2..=22).contains(&column) || !(2..=16).contains(&row) {
                assert_eq!(depth, 0.0, "cell ({column}, {row}) lies outside the mesh");
            }
        }
        // The same triangles taken apart (no edge shared) leave the centres
        // near every edge unmarked: few cells fill.
        let (vertices, indices) = grid(DVec2::new(10.0, 10.0), DVec2::splat(1.5), [53, 37], false, |_, _| 0.5);
        let loose: Vec<ScreenVertex> = indices.iter().map(|&i| vertices[i as usize]).collect();
        let count = loose.len() as u32;
        let mut apart = OcclusionBuffer::new(size, Resolution { width: 24, height: 18 });
        rasterise_meshes(&mut apart, &[(loose, (0..count).collect())]);
        let filled = |b: &OcclusionBuffer| b.depths().iter().filter(|&&d| d > 0.0).count();
        assert!(
            filled(&apart) * 10 < filled(&buffer),
            "{} cells apart, {} joined",
            filled(&apart),
            filled(&buffer)
        );
    }

    /// The 1.5-pixel grid of the test above cut into three strips of
    /// columns as the scene cuts clusters (each with its own copy of the
    /// corners on its cuts, whose seams run through pixel centres), and
    /// `drawn` of them rasterised as one mesh into a buffer of `size` in
    /// cells of 4 × 4 pixels; with the strips drawn (vertices, indices).
    fn grid_in_strips(size: Resolution, drawn: &[usize]) -> (OcclusionBuffer, Meshes) {
        let (vertices, indices) = grid(DVec2::new(10.0, 10.0), DVec2::splat(1.5), [53, 37], false, |_, _| 0.5);
        // Cut after columns 17 and 35 of squares: at x = 35.5 and 62.5.
        let strip_of = |t: &[u32]| {
            let column = ((vertices[t[0] as usize].at.x.min(vertices[t[1] as usize].at.x) - 10.0) / 1.5).round();
            usize::from(column >= 17.0) + usize::from(column >= 35.0)
        };
        let (mut stored, mut all_indices, mut strips) = (Vec::new(), Vec::new(), Vec::new());
        for strip in 0..3 {
            let (first_vertex, first_triangle) = (stored.len() as u32, all_indices.len() as u32 / 3);
            let mut local = vec![u32::MAX; vertices.len()];
            let mut strip_indices = Vec::new();
            for t in indices.chunks_exact(3).filter(|t| strip_of(t) == strip) {
                for &i in t {
                    if local[i as usize] == u32::MAX {
                        local[i as usize] = stored.len() as u32;
                        stored.push(vertices[i as usize]);
                    }
                    all_indices.push(local[i as usize]);
                    strip_indices.push(local[i as usize] - first_vertex);
                }
            }
            let triangles = first_triangle..all_indices.len() as u32 / 3;
            strips.push((triangles, first_vertex..stored.len() as u32, strip_indices));
        }
        let (mut parts, mut on_screen, mut meshes) = (Vec::new(), Vec::new(), Vec::new());
        for &k in drawn {
            let (triangles, vertex_run, strip_indices) = &strips[k];
            parts.push(DrawnPart {
                triangles: triangles.clone(),
                first_vertex: vertex_run.start,
                vertex_slot: on_screen.len() as u32,
                triangle_slot: parts.iter().map(|p: &DrawnPart| p.triangles.len() as u32).sum(),
                facing: [None; 3],
            });
            let strip_vertices = &stored[vertex_run.start as usize..vertex_run.end as usize];
            on_screen.extend(strip_vertices.iter().map(|&v| Some(v)));
            meshes.push((strip_vertices.to_vec(), strip_indices.clone()));
        }
        let position = |i: u32| [stored[i as usize].at.x as f32, stored[i as usize].at.y as f32, 0.0];
        let neighbours = super::super::neighbours::neighbours(&all_indices, position);
        let mesh = ScreenMesh {
            vertices: &on_screen,
            parts: &parts,
            indices: &all_indices,
            neighbours: &neighbours,
            closed: false,
            near: None,
            snap: COARSE_SNAP,
            depth: larger_margins(),
        };
        let mut buffer = OcclusionBuffer::new(size, Resolution { width: 24, height: 18 });
        {
            let Some(mut cells) = buffer.cleared_bands(u32::MAX).next() else {
                unreachable!()
            };
            let (mut patches, mut rasteriser) = (Patches::default(), Rasteriser::default());
            let which = patches.add(&mesh);
            rasteriser.rasterise(&mut cells, &patches, which);
        }
        (buffer, meshes)
    }

    #[test]
    fn a_mesh_drawn_in_parts_joins_the_parts_drawn_and_borders_those_left_out() {
        let size = Resolution { width: 96, height: 72 };
        // All three strips drawn fill the same cells, at the same depth, as
        // the grid in one piece.
        let mut whole = OcclusionBuffer::new(size, Resolution { width: 24, height: 18 });
        rasterise_meshes(
            &mut whole,
            &[grid(
                DVec2::new(10.0, 10.0),
                DVec2::splat(1.5),
                [53, 37],
                false,
                |_, _| 0.5,
            )],
        );
        let (strips, _) = grid_in_strips(size, &[0, 1, 2]);
        assert_eq!(strips.depths(), whole.depths());
        // The outer strips alone vouch for nothing the GPU may leave undrawn
        // (each corner placed a vertex error off), though the middle one's
        // edges run through pixel centres.
        let (outer, meshes) = grid_in_strips(size, &[0, 2]);
        let mut rng = Rng::new(7);
        for _ in 0..8 {
            assert_vouches_no_nearer(
                &outer,
                &drawn(&meshes, size, &mut rng),
                Resolution { width: 24, height: 18 },
            );
        }
        let filled = outer.depths().iter().filter(|&&d| d > 0.0).count();
        assert!(filled > 100, "{filled} cells filled by the outer strips");
    }

    /// A buffer of 16 × 12 cells of 4 × 4 pixels with `walls` rasterised
    /// into it in their order: each from x = `x0` to `x1` at depth `z`,
    /// over the target's whole height.
    /// Walls from x0 to x1 at depth z over the whole height of a 64 × 48
    /// target (cells of 4 × 4 pixels), each an object of its own, whose
    /// corners the GPU places within `snap`.
    fn walls_at_snap(walls: &[(f64, f64, f64)], snap: f64) -> OcclusionBuffer {
        let mut buffer = OcclusionBuffer::new(
            Resolution { width: 64, height: 48 },
            Resolution { width: 16, height: 12 },
        );
        let mut meshes: Vec<_> = walls
            .iter()
            .map(|&(x0, x1, z)| {
                grid(
                    DVec2::new(x0, -5.0),
                    DVec2::new(x1 - x0, 60.0),
                    [2, 2],
                    false,
                    move |_, _| z,
                )
            })
            .collect();
        for vertex in meshes.iter_mut().flat_map(|(vertices, _)| vertices) {
            vertex.slack = snap;
        }
        rasterise_meshes(&mut buffer, &meshes);
        buffer
    }

    fn walls(walls: &[(f64, f64, f64)]) -> OcclusionBuffer {
        walls_at_snap(walls, COARSE_SNAP)
    }

    #[test]
    fn an_objects_patches_come_nearest_first_by_their_farthest_corner() {
        // One mesh of three walls apart, the farthest first among its
        // triangles and the nearest last, and a ground running from before
        // the nearest to behind the farthest, first of all.
        let ground = grid(DVec2::new(0.0, 40.0), DVec2::splat(40.0), [2, 2], false, |_, y| {
            0.1 + (y - 40.0) / 50.0
        });
        let walls =
            [0.2, 0.5, 0.8].map(|z| grid(DVec2::new(4.0, 4.0), DVec2::splat(20.0), [2, 2], false, move |_, _| z));
        let (vertices, indices) = one_mesh(std::iter::once(ground).chain(walls));
        let mut patches = Patches::default();
        let which = add_patches(&mut patches, &vertices, &indices);
        let depths: Vec<[f64; 2]> = patches.patches[which].iter().map(|p| [p.farthest, p.nearest]).collect();
        assert_eq!(depths, [[0.8, 0.8], [0.5, 0.5], [0.2, 0.2], [0.1, 0.9]]);
    }

    #[test]
    fn objects_meeting_at_a_seam_fill_the_cells_along_it_where_the_adapters_snap_is_fine_enough() {
        // Two walls at 0.5 meeting at x = 30.45, 0.05 pixel from the
        // centres at x = 30.5: within Vulkan's coarsest snap of the seam,
        // where the GPU may leave them undrawn, and clear of a snap of
        // 1/256 pixel. Cell column 7 holds pixels 28 to 31.
        let seam_cell = |snap| walls_at_snap(&[(-5.0, 30.45, 0.5), (30.45, 70.0, 0.5)], snap).depths()[5 * 16 + 7];
        assert_eq!(
            seam_cell(COARSE_SNAP),
            0.0,
            "a coarse snap leaves the seam's centres in doubt"
        );
        let fine = seam_cell(FINE_SNAP);
        assert!(
            fine > 0.499 && fine <= 0.5,
            "a fine snap fills the cell across the seam: {fine}"
        );
    }

    #[test]
    fn a_seam_leaves_in_doubt_only_the_centres_within_its_corners_error_of_it() {
        // Placing the corners moves each point of the seam by at most their
        // error on each axis (a point of an edge is a weighted mean of its
        // ends): centres farther from it are drawn by one wall or the other.
        // Cell column 7 holds the centres at x = 30.5.
        let seam_cell = |off: f64| {
            let seam = 30.5 - off * COARSE_SNAP;
            walls(&[(-5.0, seam, 0.5), (seam, 70.0, 0.5)]).depths()[5 * 16 + 7]
        };
        for off in [1.1, 1.5] {
            let clear = seam_cell(off);
            assert!(clear > 0.499 && clear <= 0.5, "{off} errors from the seam: {clear}");
        }
        assert_eq!(seam_cell(0.9), 0.0, "0.9 errors from the seam");
    }

    #[test]
    fn objects_that_each_cover_part_of_a_cell_fill_it_together_at_the_farther_depth() {
        // Two walls meeting at x = 30.2 (inside cells of 4 pixels), one at
        // 0.5, one at 0.4, overlapping by two pixels.
        let buffer = walls(&[(-5.0, 31.2, 0.5), (29.2, 70.0, 0.4)]);
        let depths = buffer.depths();
        let at = |column: usize| depths[5 * 16 + column];
        assert!(at(2) > 0.499 && at(2) <= 0.5, "{}", at(2));
        assert!(at(12) > 0.399 && at(12) <= 0.4, "{}", at(12));
        // The cells over the overlap hold the farther wall's depth.
        assert!(at(7) > 0.399 && at(7) <= 0.4, "{}", at(7));
        assert!(depths.iter().all(|&d| d > 0.0), "every cell covered");
    }

    #[test]
    fn a_ground_beside_a_nearer_wall_fills_the_cells_they_share_merged_after_it() {
        // As the test above, in one object: a wall at 0.8 ending at x =
        // 31.2, and a ground from x = 29.2, where it lies at 0.2, rising
        // towards the eye to 0.9 at x = 70 (its nearest corner nearer than
        // the wall, its part of the cells they share four times farther).
        // Merged first there, the ground's part would be taken by the
        // wall's rather than join it.
        let ground = |x: f64, _: f64| 0.2 + (x - 29.2) * 0.7 / 40.8;
        let (mut vertices, indices) = one_mesh([
            grid(DVec2::new(29.2, -5.0), DVec2::new(40.8, 60.0), [2, 2], false, ground),
            grid(DVec2::new(-5.0, -5.0), DVec2::new(36.2, 60.0), [2, 2], false, |_, _| {
                0.8
            }),
        ]);
        for vertex in &mut vertices {
            vertex.slack = COARSE_SNAP;
        }
        let mut buffer = OcclusionBuffer::new(
            Resolution { width: 64, height: 48 },
            Resolution { width: 16, height: 12 },
        );
        rasterise_meshes(&mut buffer, &[(vertices, indices)]);
        let depths = buffer.depths();
        // The cells of pixels 28 to 31, which both cover in part.
        let shared = depths[5 * 16 + 7];
        // (Its plane taken below the ground's over the whole cell.)
        assert!(shared > 0.15 && f64::from(shared) <= ground(32.0, 0.0), "{shared}");
        assert!(depths.iter().all(|&d| d > 0.0), "every cell covered");
    }

    #[test]
    fn a_box_behind_a_walls_outline_within_its_pixels_is_hidden_though_a_farther_wall_fills_the_cell() {
        // A wall at 0.5 ending at x = 30.2, inside the cells of pixels 28
        // to 31, rasterised first (nearest first), and a wall at 0.25
        // behind it from x = 29.8 on: together they fill those cells, whose
        // reference becomes the far wall's depth, and whose working layer
        // stays the near wall's pixels 28 and 29.
        let mut buffer = walls(&[(-5.0, 30.2, 0.5), (29.8, 70.0, 0.25)]);
        buffer.build_pyramid();
        let hides = |first, last, nearest| buffer.hides(first, last, nearest, &crate::gpu::BoxPlanes::default());
        assert!(
            hides([26, 20], [29, 27], 0.4),
            "just behind the near wall, within its pixels"
        );
        assert!(
            !hides([26, 20], [30, 27], 0.4),
            "reaching past its outline, in front of the far wall"
        );
        assert!(hides([26, 20], [34, 27], 0.2), "behind both");
    }

    #[test]
    fn the_picture_shows_the_pixels_an_occluder_covers_in_part_of_a_cell_as_the_working_layer() {
        // A wall ending at x = 30.2, inside the cells of pixels 28 to 31:
        // it covers their first two pixels, which the working layer holds
        // at the wall's depth.
        let picture = walls(&[(-5.0, 30.2, 0.5)]).per_pixel();
        assert_eq!((picture.width, picture.height), (64, 48));
        for y in 0..48 {
            let at = |x: usize| (picture.depths[y * 64 + x] > 0.0, picture.partial[y * 64 + x]);
            for x in 0..64 {
                let expected = match x {
                    0..28 => (true, false),
                    28 | 29 => (true, true),
                    _ => (false, false),
                };
                assert_eq!(at(x), expected, "pixel ({x}, {y})");
            }
        }
    }

    #[test]
    fn a_triangle_over_the_whole_screen_fills_every_cell_with_its_farthest_depth() {
        let size = Resolution { width: 64, height: 48 };
        let mut buffer = OcclusionBuffer::new(size, Resolution { width: 16, height: 12 });
        // A plane leaning in x: depth 0.5 at x = 0, 0.3 at x = 64.
        let at = |x: f64, y: f64| vertex(x, y, 0.5 - 0.2 * x / 64.0);
        rasterise_meshes(
            &mut buffer,
            &[(
                vec![at(-100.0, -100.0), at(300.0, -100.0), at(-100.0, 300.0)],
                vec![0, 1, 2],
            )],
        );
        // Column 0 holds pixels 0..=3, centres 0.5 to 3.5: its farthest is
        // where the GPU may sample beside 3.5.
        let x = 3.5 + COARSE_SNAP;
        // Moved farther by a fragment's error at its nearest corner, at
        // x = -100.
        let error = larger_margins().fragment_error(0.5 + 0.2 * 100.0 / 64.0);
        let expected = (0.5 - 0.2 * x / 64.0) * (1.0 - DEPTH_MARGIN) - error;
        assert!(buffer.depths().iter().all(|&d| d > 0.0));
        assert_eq!(buffer.depths()[0], super::super::buffer::f32_at_most(expected));
    }

    /// A grid of slivers 0.1 pixel high (squares of 4 × 0.1 pixels cut
    /// in two) over x 10 to 54 and y 10 to 30 of a 64 × 48 target in cells
    /// of 4 × 4 pixels, at depth `depth(x, y)`, whose corners the GPU
    /// places within `snap`; with the meshes. (What the GPU draws is
    /// interpolated exactly here ([`drawn`]): the f32 bound itself is held
    /// against the adapters by tests/real_models.rs and the stress cases.)
    fn slivers(snap: f64, depth: impl Fn(f64, f64) -> f64) -> (OcclusionBuffer, Meshes) {
        let size = Resolution { width: 64, height: 48 };
        let mut buffer = OcclusionBuffer::new(size, Resolution { width: 16, height: 12 });
        let mut mesh = grid(DVec2::new(10.0, 10.0), DVec2::new(4.0, 0.1), [12, 201], false, depth);
        for vertex in mesh.0.iter_mut() {
            vertex.slack = snap;
        }
        let meshes = vec![mesh];
        rasterise_meshes(&mut buffer, &meshes);
        (buffer, meshes)
    }

    #[test]
    fn slivers_thinner_than_the_coarsest_snap_allows_fill_the_cells_they_cover_where_their_interpolation_is_bounded() {
        // Cells 3 to 12 across and 3 to 6 down lie inside the grid.
        let inside = |i: usize| (3..=12).contains(&(i % 16)) && (3..=6).contains(&(i / 16));
        let held_inside = |buffer: &OcclusionBuffer| {
            let depths = buffer.depths();
            (0..depths.len()).filter(|&i| inside(i) && depths[i] > 0.0).count()
        };
        // Flat at 0.5, at the 1/256 pixel the adapters here report: every
        // cell inside holds the depth, and none nearer than the GPU may draw.
        let (flat, meshes) = slivers(FINE_SNAP, |_, _| 0.5);
        for (i, &depth) in flat.depths().iter().enumerate() {
            assert!(!inside(i) || (depth > 0.499 && depth <= 0.5), "cell {i} holds {depth}");
        }
        let mut rng = Rng::new(7);
        for _ in 0..4 {
            let nearest = drawn(&meshes, flat.target(), &mut rng);
            assert_vouches_no_nearer(&flat, &nearest, flat.cells());
        }
        // At Vulkan's coarsest snap, placing a corner may fold a sliver
        // over: none is in a patch.
        assert_eq!(held_inside(&slivers(COARSE_SNAP, |_, _| 0.5).0), 0);
        // Steep in depth (ninefold across the first square of slivers,
        // from 1e-4 to 9e-4), the rounding of the GPU's gradient, magnified
        // by the slivers' length over their height (40), outgrows half the
        // depth margin wherever the depth rises by more than a tenth across
        // a square: only the last square's slivers (x 50 to 54) stay in the
        // patch, and their pixels alone hold a depth.
        let (steep, meshes) = slivers(FINE_SNAP, |x, _| 0.0002 * (x - 9.5));
        let picture = steep.per_pixel();
        for y in 10..30 {
            for x in 10..54 {
                let held = picture.depths[y * 64 + x] > 0.0;
                assert_eq!(held, x >= 50, "pixel ({x}, {y})");
            }
        }
        for _ in 0..4 {
            let nearest = drawn(&meshes, steep.target(), &mut rng);
            assert_vouches_no_nearer(&steep, &nearest, steep.cells());
        }
    }

    #[test]
    fn a_patch_folded_over_itself_keeps_the_centres_its_near_layers_outline_crosses() {
        // Four triangles fanned round (32.5, 24.5), each turning 100
        // degrees the same way: the fourth (300 to 400 degrees) lies over
        // the first (0 to 100) from 0 to 40 degrees, so the first's free
        // edge, along the row of centres y = 24.5 from x = 32.5 to 52.5,
        // crosses the fourth's inside, which holds those centres up to
        // about 13 pixels from the fan's centre by more than a border's
        // margin. The fourth triangle lies farther (its outer corners at
        // 0.3, the rest at 0.5): where the GPU leaves the first's edge
        // undrawn, it draws the fourth there. Cells of a pixel each.
        let size = Resolution { width: 64, height: 48 };
        let centre = DVec2::new(32.5, 24.5);
        let corner = |degrees: f64| centre + 20.0 * DVec2::from_angle(degrees.to_radians());
        let mut vertices = vec![vertex(centre.x, centre.y, 0.5)];
        vertices.extend([0.0, 100.0, 200.0, 300.0, 400.0].map(|d| {
            let far = d >= 300.0;
            vertex(corner(d).x, corner(d).y, if far { 0.3 } else { 0.5 })
        }));
        let meshes = vec![(vertices, vec![0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5])];
        let mut buffer = OcclusionBuffer::new(size, size);
        rasterise_meshes(&mut buffer, &meshes);
        let depths = buffer.depths();
        // The fourth triangle's depth along the row, where the GPU may draw
        // it alone: 0.5 at the fan's centre, falling towards its far side,
        // 20 · cos 50° from the centre at 350 degrees, 10 off the row.
        for x in 34..45 {
            let depth = f64::from(depths[24 * 64 + x]);
            let along = (x as f64 + 0.5 - 32.5) * 10f64.to_radians().cos();
            let fourth = 0.5 - 0.2 * along / (20.0 * 50f64.to_radians().cos());
            assert!(
                depth > 0.3 && depth < fourth,
                "pixel ({x}, 24) holds {depth}, the fourth triangle {fourth}"
            );
        }
        let mut rng = Rng::new(7);
        for _ in 0..8 {
            assert_vouches_no_nearer(&buffer, &drawn(&meshes, size, &mut rng), size);
        }
    }
}
