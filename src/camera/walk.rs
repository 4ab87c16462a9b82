//! A walk through a model's free space, for models that suggest none (the
//! built-in scenes do): at eye height above its ground, along its open
//! corridors (streets, naves, rooms), never through geometry.
//!
//! The ground plane (the scene's up axis) is laid with a grid. Down each
//! cell's vertical line a ray cast finds every surface; a surface with room
//! for an eye above it (eye height and a margin up to the next surface) is
//! a floor, unless that room lies inside a closed mesh (the ray has crossed
//! its surface an odd number of times: inside a thick ground slab, a closed
//! building; a closed hall or sky box around everything is space, not a
//! solid). The ground is the lowest level that holds a good share of the
//! floors, with something rising above it; cells with a floor there are
//! walkable. Cells whose four
//! neighbours are all walkable are kept (so the eye stays a cell from every
//! wall), and two neighbours are joined when a ray at eye height passes
//! between them. The walk is the longest of the shortest routes through the
//! largest joined region (two breadth-first searches), in cell steps, of
//! the streets (open cells with walls near in half the directions) when they
//! hold a long enough one, else of all open cells.

use std::collections::{HashMap, VecDeque};

use glam::DVec3;

use crate::raycast::{Hit, RayCaster};
use crate::scene::Scene;

/// A planned walk: eye positions along the route, and what it rests on.
#[derive(Clone, Debug, PartialEq)]
pub struct Walk {
    /// Eye positions, one per cell of the route, turns kept.
    pub line: Vec<DVec3>,
    pub eye_height: f64,
    /// The grid's cell size: the route keeps at least this much from walls.
    pub cell: f64,
    /// The share of the ground's cells with room to walk at its level.
    pub walkable: f64,
    /// The share of the route's cells open to the sky (nothing above the
    /// eye): streets are, the inside of an object is not.
    pub open_sky: f64,
}

impl Walk {
    /// The route's length, in the model's units.
    pub fn length(&self) -> f64 {
        self.line.windows(2).map(|p| p[0].distance(p[1])).sum()
    }
}

/// Cells along the ground's longer side.
const CELLS: usize = 160;

/// Models at least this wide (in their units) are taken to be in metres,
/// with an eye [`METRES_EYE_HEIGHT`] above the ground; smaller ones get an
/// eye at [`EYE_FRACTION`] of their height.
const METRE_SCALE_WIDTH: f64 = 30.0;
const METRES_EYE_HEIGHT: f64 = 1.7;
const EYE_FRACTION: f64 = 0.05;

/// The eye height for a model `width` wide and `height` tall, as the
/// module says: metres assumed for city-sized models, a fraction of the
/// height otherwise (of the width for a model with no height).
fn eye_height(width: f64, height: f64) -> f64 {
    if width >= METRE_SCALE_WIDTH && height > METRES_EYE_HEIGHT {
        METRES_EYE_HEIGHT
    } else {
        (EYE_FRACTION * height).max(FLAT_EYE_FRACTION * width)
    }
}

/// The eye height over a flat model's width.
const FLAT_EYE_FRACTION: f64 = 0.01;

/// Plans a walk through `scene`, or `None` when it has no ground with room
/// to walk (fewer than [`MIN_CELLS`] joined cells).
pub fn plan(scene: &Scene, caster: &RayCaster) -> Option<Walk> {
    let up = scene.up.axis.vector();
    let (right, ahead) = scene.up.axis.ground_axes();
    let b = scene.bounds;
    let (low, high) = b.span_along(up);
    let ((x0, x1), (y0, y1)) = (b.span_along(right), b.span_along(ahead));
    let (width, depth) = (x1 - x0, y1 - y0);
    let eye = eye_height(width.max(depth), high - low);
    let cell = width.max(depth) / CELLS as f64;
    if !(cell > 0.0 && cell.is_finite()) {
        return None;
    }
    let (nx, ny) = (
        ((width / cell).ceil() as usize).max(1),
        ((depth / cell).ceil() as usize).max(1),
    );
    let at = |i: usize, j: usize, height: f64| {
        right * (x0 + (i as f64 + 0.5) * cell) + ahead * (y0 + (j as f64 + 0.5) * cell) + up * height
    };

    // Floors: surfaces with room for the eye and a margin above them.
    let room = eye * 1.5;
    // Closed solids, not shells: a closed mesh as tall as half the model
    // that covers most of its ground (a hall, a sky box) is space to walk
    // in, not a solid.
    let footprint = |b: &crate::bounds::Aabb| {
        let e = b.extent();
        (e.dot(right.abs()), e.dot(ahead.abs()), e.dot(up.abs()))
    };
    let (model_w, model_d, model_h) = footprint(&scene.bounds);
    let closed: Vec<bool> = (0..scene.meshes.len()).map(|m| is_closed(scene, m)).collect();
    let solid: Vec<bool> = scene
        .objects
        .iter()
        .map(|o| {
            let (w, d, h) = footprint(&o.bounds);
            let shell = h >= 0.5 * model_h && w * d >= 0.5 * model_w * model_d;
            closed[o.mesh as usize] && !shell
        })
        .collect();
    let mut floors: Vec<Vec<f64>> = vec![Vec::new(); nx * ny];
    let mut hits: Vec<Hit> = Vec::new();
    let mut inside: Vec<u32> = Vec::new();
    let top = high + cell;
    for j in 0..ny {
        for i in 0..nx {
            caster.all_hits(at(i, j, top), -up, top - low + cell, &mut hits);
            // A ray through an edge meets both triangles at one point: one
            // crossing.
            hits.dedup_by(|b, a| a.object == b.object && (b.t - a.t).abs() <= 1e-9 * a.t.abs().max(1.0));
            inside.clear();
            let mut above = f64::INFINITY;
            for hit in &hits {
                let h = top - hit.t;
                if above - h >= room && inside.is_empty() {
                    floors[j * nx + i].push(h);
                }
                if solid[hit.object as usize] {
                    match inside.iter().position(|&o| o == hit.object) {
                        Some(k) => {
                            inside.swap_remove(k);
                        }
                        None => inside.push(hit.object),
                    }
                }
                above = h;
            }
        }
    }
    let ground = ground_level(&floors, eye, high)?;
    // Walkable: a floor near the ground level (steps of up to half the eye
    // height), the eye above the highest such floor.
    let eye_at: Vec<Option<f64>> = floors
        .iter()
        .map(|f| {
            f.iter()
                .copied()
                .filter(|h| (h - ground).abs() <= 0.5 * eye)
                .reduce(f64::max)
                .map(|h| h + eye)
        })
        .collect();
    let walkable = |i: usize, j: usize| eye_at[j * nx + i].is_some();
    let clear = |i: usize, j: usize| {
        i > 0
            && j > 0
            && i + 1 < nx
            && j + 1 < ny
            && walkable(i, j)
            && walkable(i - 1, j)
            && walkable(i + 1, j)
            && walkable(i, j - 1)
            && walkable(i, j + 1)
    };
    let open: Vec<bool> = (0..nx * ny).map(|k| clear(k % nx, k / nx)).collect();
    let point = |k: usize| at(k % nx, k / nx, eye_at[k].expect("open cells are walkable"));
    let joined = |a: usize, b: usize| {
        let (p, q) = (point(a), point(b));
        caster.first_hit(p, q - p, 1.0).is_none()
    };
    // The longest shortest route through the largest joined region of
    // `cells`.
    let longest_route = |cells: &[bool]| -> Option<Vec<usize>> {
        let edges: Vec<Vec<usize>> = (0..nx * ny)
            .map(|k| {
                if !cells[k] {
                    return Vec::new();
                }
                let (i, j) = (k % nx, k / nx);
                [
                    (i > 0).then(|| k - 1),
                    (i + 1 < nx).then(|| k + 1),
                    (j > 0).then(|| k - nx),
                    (j + 1 < ny).then(|| k + nx),
                ]
                .into_iter()
                .flatten()
                .filter(|&n| cells[n] && joined(k, n))
                .collect()
            })
            .collect();
        let start = largest_region(&edges, cells)?;
        let (far, _) = farthest(&edges, start);
        let (end, parents) = farthest(&edges, far);
        let mut route = vec![end];
        while let Some(previous) = parents[route[route.len() - 1]] {
            route.push(previous);
        }
        Some(route)
    };
    // Streets: open cells with walls around, where at least half of eight
    // level rays meet something within [`STREET_REACH`] cells; a walk along them
    // sees occlusion, one round the open outskirts does not.
    let walled = |k: usize| {
        let p = point(k);
        let reach = STREET_REACH * cell;
        let walls = (0..8)
            .filter(|&a| {
                let angle = std::f64::consts::TAU * f64::from(a) / 8.0;
                let direction = right * angle.cos() + ahead * angle.sin();
                caster.first_hit(p, direction, reach).is_some()
            })
            .count();
        // At a crossing only the four diagonals meet walls.
        walls >= 4
    };
    let streets: Vec<bool> = (0..nx * ny).map(|k| open[k] && walled(k)).collect();
    let route = longest_route(&streets)
        .filter(|r| r.len() >= LONG_ROUTE)
        .or_else(|| longest_route(&open))?;
    if route.len() < MIN_CELLS {
        return None;
    }
    let points: Vec<DVec3> = route.iter().map(|&k| point(k)).collect();
    let sky = points
        .iter()
        .filter(|&&p| caster.first_hit(p, up, f64::INFINITY).is_none())
        .count();
    let walkable = eye_at.iter().filter(|e| e.is_some()).count() as f64 / eye_at.len() as f64;
    Some(Walk {
        line: turns(&points),
        eye_height: eye,
        cell,
        walkable,
        open_sky: sky as f64 / points.len() as f64,
    })
}

/// Whether mesh `m` is a closed solid: welded by position, every edge is
/// walked once in each direction (watertight and consistently wound), and
/// it encloses a volume (a surface stored twice, once per side, encloses
/// none). A line then crosses its surface an even number of times, and an
/// odd count means "inside".
fn is_closed(scene: &Scene, m: usize) -> bool {
    let mesh = &scene.meshes[m];
    let indices = &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    let mut id = |v: u32| {
        let key = scene.vertices[v as usize].map(f32::to_bits);
        let next = welded.len() as u32;
        *welded.entry(key).or_insert(next)
    };
    let mut edges: HashMap<(u32, u32), i64> = HashMap::new();
    let mut volume = 0.0;
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [id(t[0]), id(t[1]), id(t[2])];
        for (u, v) in [(a, b), (b, c), (c, a)] {
            // +1 one way, -1 the other: a closed, consistently wound
            // surface sums to 0 on every edge.
            *edges.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
        }
        let [p, q, r] = [t[0], t[1], t[2]].map(|i| DVec3::from(scene.vertices[i as usize].map(f64::from)));
        volume += p.dot(q.cross(r)) / 6.0;
    }
    let e = mesh.bounds.extent();
    !edges.is_empty() && edges.values().all(|&n| n == 0) && volume.abs() >= 0.01 * e.x * e.y * e.z
}

/// How far (in cells) a street's walls may lie.
const STREET_REACH: f64 = 16.0;

/// Cells a route through the streets needs, or the walk takes the open
/// ground as a whole; and a place's walk, to be its default path.
pub const LONG_ROUTE: usize = 4 * MIN_CELLS;

/// Joined cells a walk needs at least.
pub const MIN_CELLS: usize = 8;

/// The ground: the lowest floor level (in bins of half the eye height)
/// holding at least a fiftieth of all floors (so a few pits or basements do
/// not count, while a town's streets under a sky dome, a few percent of the
/// dome's roof, do), or failing that the most common one. Something must
/// rise at least two eye heights above it (the model's top is `high`): a
/// tower's roof is no ground.
fn ground_level(floors: &[Vec<f64>], eye: f64, high: f64) -> Option<f64> {
    let all: Vec<f64> = floors.iter().flatten().copied().collect();
    let lowest = all.iter().copied().fold(f64::INFINITY, f64::min);
    if !lowest.is_finite() {
        return None;
    }
    let bin = 0.5 * eye;
    let mut counts: std::collections::BTreeMap<i64, usize> = Default::default();
    for h in &all {
        *counts.entry(((h - lowest) / bin).floor() as i64).or_default() += 1;
    }
    let wanted = all.len().div_ceil(50).max(4 * MIN_CELLS);
    let (&level, _) = counts
        .iter()
        .find(|&(_, &n)| n >= wanted)
        .or_else(|| counts.iter().max_by_key(|&(_, &n)| n))?;
    // The highest floor in that bin: the eye stands on it.
    let ground = all
        .iter()
        .copied()
        .filter(|h| ((h - lowest) / bin).floor() as i64 == level)
        .reduce(f64::max)?;
    // Something must rise above the eye: the top of a model is no ground.
    (ground + 2.0 * eye <= high).then_some(ground)
}

/// A cell of the largest connected region of open cells.
fn largest_region(edges: &[Vec<usize>], open: &[bool]) -> Option<usize> {
    let mut region = vec![usize::MAX; edges.len()];
    let mut best: Option<(usize, usize)> = None;
    for seed in (0..edges.len()).filter(|&k| open[k]) {
        if region[seed] != usize::MAX {
            continue;
        }
        let mut size = 0;
        let mut queue = VecDeque::from([seed]);
        region[seed] = seed;
        while let Some(k) = queue.pop_front() {
            size += 1;
            for &n in &edges[k] {
                if region[n] == usize::MAX {
                    region[n] = seed;
                    queue.push_back(n);
                }
            }
        }
        if best.is_none_or(|(_, s)| size > s) {
            best = Some((seed, size));
        }
    }
    best.map(|(seed, _)| seed)
}

/// The cell farthest from `start` in steps, and each reached cell's parent
/// on a shortest route from `start`.
fn farthest(edges: &[Vec<usize>], start: usize) -> (usize, Vec<Option<usize>>) {
    let mut parent = vec![None; edges.len()];
    let mut seen = vec![false; edges.len()];
    seen[start] = true;
    let mut last = start;
    let mut queue = VecDeque::from([start]);
    while let Some(k) = queue.pop_front() {
        last = k;
        for &n in &edges[k] {
            if !seen[n] {
                seen[n] = true;
                parent[n] = Some(k);
                queue.push_back(n);
            }
        }
    }
    (last, parent)
}

/// `points` without those in the middle of a straight run: the ends and the
/// turns.
fn turns(points: &[DVec3]) -> Vec<DVec3> {
    let mut out: Vec<DVec3> = Vec::new();
    for (k, &p) in points.iter().enumerate() {
        let straight = k > 0
            && k + 1 < points.len()
            && (p - points[k - 1]).normalize().dot((points[k + 1] - p).normalize()) > 1.0 - 1e-9;
        if !straight {
            out.push(p);
        }
    }
    out
}
