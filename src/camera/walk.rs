//! A walk through a model's free space, for models that suggest none (the
//! built-in scenes do): at eye height above its ground, along its open
//! corridors (streets, naves, rooms), never through geometry.
//!
//! The ground plane (the scene's up axis) is laid with a grid of cells no
//! wider than the eye is high, within bounds on the work, over the model's
//! focus (its bounds without a huge ground plane or sky dome,
//! [`crate::scene::Focus`]). Down each cell's vertical line a ray cast finds
//! every surface; a surface with room for an eye above it (eye height and a
//! margin up to the next surface: under a door's lintel at a person's sizes)
//! is a floor, unless that room lies inside a closed part (the ray has
//! crossed its surface an odd number of times: inside a thick ground slab, a
//! closed building; a closed hall or sky box around everything is space, not
//! a solid), or the floor is the model's top (nothing rises the room above
//! it: 1.95 m at a person's sizes, two eye heights where the unit is not
//! known; a tower's roof). Floors of neighbouring cells within a step (half
//! the eye height; at a person's sizes at most [`PERSON_STEP`] and a slope
//! of one across a cell) of each other are linked, so the ground may slope,
//! climb stairs and lie at several levels (an island and the sea, storeys).
//! A floor linked on all four sides, with a clear ray at eye height to each,
//! is open (the eye stays a cell from every wall, however thin), unless it
//! is a roof (at a person's sizes, a linked region of floors open to the
//! sky, most of them over another floor, or nine tenths for the largest such
//! region: a roof over rooms, not streets over a metro); linked open floors
//! are joined. The walk is the longest of the shortest routes through the
//! largest joined region (two breadth-first searches), in cell steps, of the
//! interior (open floors indoors: a ray up meets the model, and level rays
//! meet it in six of eight directions) when it holds at least half of the
//! open floors, or, where indoor floors are most but no joined part of them
//! is (doors in line let rays out of the floors joining rooms), the longest
//! route from indoor floor to indoor floor through the roofed ones; else of
//! the streets (open floors with walls near in half the directions) when
//! they hold a long enough one and a quarter of the open ground joined to
//! them; else of all open floors. The eye is a person's in a model whose
//! unit is known: metres by its width (a town, a building), or metres,
//! centimetres or millimetres by the height of its rooms (a flat, a room);
//! elsewhere a share of the model's height.

use std::collections::VecDeque;

use glam::DVec3;

use crate::bounds::Aabb;
use crate::raycast::{Hit, RayCaster, Stopped};
use crate::scene::Scene;

/// What a walk's route goes through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Through {
    /// Open floors indoors: under a roof, with walls around ([`plan`]).
    Interior,
    /// Open floors with walls near in half the directions.
    Streets,
    /// Any open floors.
    OpenGround,
}

impl std::fmt::Display for Through {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Through::Interior => "the interior",
            Through::Streets => "the streets",
            Through::OpenGround => "the open ground",
        })
    }
}

/// A planned walk: eye positions along the route, and what it rests on.
#[derive(Clone, Debug, PartialEq)]
pub struct Walk {
    /// Eye positions, one per cell of the route, turns kept.
    pub line: Vec<DVec3>,
    pub eye_height: f64,
    /// The grid's cell size: the route keeps at least this much from walls.
    pub cell: f64,
    /// The share of the grid's cells in the joined region the route was
    /// taken from.
    pub region: f64,
    /// The share of the route's cells open to the sky (nothing above the
    /// eye): streets are, the inside of an object is not.
    pub open_sky: f64,
    /// What the route goes through.
    pub through: Through,
    /// The share of the open floors under a roof and joined (the largest
    /// region of them): most of an interior's, none of a town's.
    pub roofed: f64,
    /// The share of the open floors indoors (under a roof, walls around),
    /// of the roofed ones joined; judged only where the roofed share is at
    /// least half, 0 otherwise.
    pub indoors: f64,
    /// The unit its sizes are a person's in ("metres", "centimetres" or
    /// "millimetres"); `None` where they are a share of the model's height.
    pub unit: Option<&'static str>,
    /// Where the route goes through an interior whose median headroom is a
    /// room's in `unit` ([`ROOM_HEIGHTS`]): that headroom, in metres.
    pub rooms: Option<f64>,
    /// Whether `unit` was found from `rooms`, not from the model's width
    /// ([`plan`]).
    pub unit_from_rooms: bool,
}

impl Walk {
    /// The route's length, in the model's units.
    pub fn length(&self) -> f64 {
        self.line.windows(2).map(|p| p[0].distance(p[1])).sum()
    }
}

/// Cells along the ground's longer side: one per eye height, so that a
/// street three cells wide (the narrowest walked) is a few metres in a
/// city, but at least [`MIN_SIDE_CELLS`] (small models) and at most
/// [`MAX_SIDE_CELLS`] (the rays cast grow with the square).
const MIN_SIDE_CELLS: usize = 160;
const MAX_SIDE_CELLS: usize = 512;

/// Models at least this wide (in their units) are taken to be in metres,
/// with an eye [`METRES_EYE_HEIGHT`] above the ground; smaller ones get an
/// eye at [`EYE_FRACTION`] of their height; either unless their rooms say
/// their unit ([`plan`]).
const METRE_SCALE_WIDTH: f64 = 30.0;
const METRES_EYE_HEIGHT: f64 = 1.7;
const EYE_FRACTION: f64 = 0.05;

/// The eye height for a model `width` wide and `height` tall, as the
/// module says (metres assumed for city-sized models, a fraction of the
/// height otherwise, of the width for a model with no height); the room a
/// floor needs above it; and how far below the model's top a floor must
/// lie not to be its top (a tower's roof). In metres: [`METRES_ROOM`] for
/// both (a single storey 3 m tall is walked inside); otherwise
/// [`ROOM_OVER_EYE`] and two eye heights.
fn scale_of(width: f64, height: f64) -> Scale {
    if width >= METRE_SCALE_WIDTH && height > METRES_EYE_HEIGHT {
        Scale::person(UNITS[0])
    } else {
        let eye = (EYE_FRACTION * height).max(FLAT_EYE_FRACTION * width);
        Scale {
            eye,
            room: eye * ROOM_OVER_EYE,
            below_top: 2.0 * eye,
            unit: None,
        }
    }
}

/// A walk's sizes, in the model's units ([`scale_of`]), and the unit (of
/// [`UNITS`]) where they are a person's sizes.
#[derive(Clone, Copy)]
struct Scale {
    eye: f64,
    room: f64,
    below_top: f64,
    unit: Option<Unit>,
}

impl Scale {
    /// A person's sizes, in `unit`.
    fn person(unit: Unit) -> Scale {
        let (per_metre, _) = unit;
        Scale {
            eye: METRES_EYE_HEIGHT * per_metre,
            room: METRES_ROOM * per_metre,
            below_top: METRES_ROOM * per_metre,
            unit: Some(unit),
        }
    }
}

/// The units a model of rooms may be in, with how many of each make a
/// metre: metres (glTF's unit, and the common one for architecture),
/// centimetres and millimetres (many modelling tools' and CAD's). In
/// feet a room 8 to 10 high is taken for a room in metres (walked higher
/// than a share of its height, still below a person's eye); inches are
/// not recognised (rooms 96 to 120 high are too low for centimetres).
const UNITS: [Unit; 3] = [(1.0, "metres"), (100.0, "centimetres"), (1000.0, "millimetres")];

/// A unit: how many of it make a metre, and its name.
type Unit = (f64, &'static str);

/// The headroom over an interior's floors that is a room's, in metres:
/// from the room the eye needs under a door ([`METRES_ROOM`]) to a hall's,
/// below ten times the least, so that a headroom names one of [`UNITS`]
/// only (1 950 units is not a hall 19.5 m high in centimetres as well as a
/// room 1.95 m high in millimetres). Rooms this high in one of [`UNITS`]
/// tell the model's unit: an 8 m room in metres was walked at 5 % of its
/// height (a knee's), and a flat in centimetres, taken for metres by its
/// width, at 1.7 cm.
const ROOM_HEIGHTS: std::ops::RangeInclusive<f64> = METRES_ROOM..=19.0;

/// The most a person steps up between neighbouring cells, in metres,
/// besides a slope of one across a cell: a stair's riser or a kerb, not a
/// chair's seat (0.45 m) or a bed (0.5 m). At most half the eye height.
const PERSON_STEP: f64 = 0.3;

/// The eye height over a flat model's width.
const FLAT_EYE_FRACTION: f64 = 0.01;

/// The room a floor needs above it in metres: under a door 2 m tall (the
/// lowest usual) the eye passes. (At 1.5 eye heights, the rule for other
/// units, a building's 2.1 m doors held no floor and its rooms were never
/// joined.)
const METRES_ROOM: f64 = 1.95;

/// The room a floor needs above it in other units, in eye heights: the
/// eye and half again, so that the hollow inside a thin slab of an open
/// mesh (a pavement's kerb) is not taken for a storey.
const ROOM_OVER_EYE: f64 = 1.5;

/// A floor: a surface with room for the eye above it, in a grid cell.
#[derive(Clone, Copy, Debug)]
struct Floor {
    cell: usize,
    height: f64,
    /// The cell's ray met a surface above it (below the model's top): a
    /// roof.
    roofed: bool,
    /// How far above it that surface lies (+∞ where none does): its
    /// headroom.
    headroom: f64,
    /// At a person's sizes: open to the sky over another floor of its cell.
    over_floor: bool,
}

/// Plans a walk through the part of `scene` within `bounds` (its focus:
/// the grid covers that box), or `None` when it has no ground with room
/// to walk (fewer than [`MIN_CELLS`] joined cells); stopped when `caster`
/// stops (its budget spent, or Ctrl-C). The walk is planned at the scale
/// the model's size gives ([`scale_of`]); unless that scale's unit is
/// known (metres, by the width) and the walk goes through an interior
/// whose median headroom is a room's in it ([`ROOM_HEIGHTS`]), each unit
/// of [`UNITS`] it did not try, that its format allows (glTF: metres only)
/// and that it is tall enough for (a room's height in it) is tried in
/// turn, at a person's sizes in it, and the first whose walk goes through
/// such rooms in it is taken. Where none is, or the budget is spent trying
/// (the caster is then left spent), the first walk is.
pub fn plan(scene: &Scene, bounds: &Aabb, caster: &RayCaster) -> Result<Option<Walk>, Stopped> {
    let Some(grid) = Grid::over(scene, bounds) else {
        return Ok(None);
    };
    let first = plan_on(scene, bounds, &grid, caster)?;
    if first.as_ref().is_some_and(|walk| walk.rooms.is_some()) {
        return Ok(first);
    }
    for unit in UNITS {
        let (per_metre, _) = unit;
        let tried = grid.scale.unit == Some(unit);
        // A format in metres is read in metres only: a sky box 300 m high
        // over a town reads as a room 3 m high in centimetres too.
        let ruled_out = scene.in_metres && unit != UNITS[0];
        if tried || ruled_out || grid.high - grid.low < METRES_ROOM * per_metre {
            continue;
        }
        let planned = match plan_on(scene, bounds, &grid.at_scale(Scale::person(unit)), caster) {
            Err(Stopped::Spent) => break,
            planned => planned?,
        };
        if let Some(walk) = planned.filter(|walk| walk.rooms.is_some()) {
            return Ok(Some(Walk {
                unit_from_rooms: true,
                ..walk
            }));
        }
    }
    Ok(first)
}

/// The walk over `grid`, with the median headroom over its route's floors
/// where that is a room's in a person's unit.
fn plan_on(scene: &Scene, bounds: &Aabb, grid: &Grid, caster: &RayCaster) -> Result<Option<Walk>, Stopped> {
    let (floors, first) = find_floors(scene, bounds, grid, caster)?;
    let ground = Ground::link(*grid, floors, &first, caster)?;
    let streets = ground.street_route()?;
    let interior = ground.interior(bounds)?;
    let (through, found) = match (interior.route, streets) {
        (Some(interior), _) => (Through::Interior, Some(interior)),
        (None, Some(streets)) => (Through::Streets, Some(streets)),
        (None, None) => (Through::OpenGround, ground.longest_route(&ground.open, |_| true)),
    };
    let Some((route, region)) = found else {
        return Ok(None);
    };
    if route.len() < MIN_CELLS {
        return Ok(None);
    }
    let points: Vec<DVec3> = route.iter().map(|&f| ground.point(f)).collect();
    let sky = points
        .iter()
        .filter(|&&p| caster.first_hit(p, grid.up, f64::INFINITY).is_none())
        .count();
    caster.searching()?;
    // The median headroom (+∞ where at least half the floors have nothing
    // above them), in metres where the sizes are a person's.
    let mut headrooms: Vec<f64> = route.iter().map(|&f| ground.floors[f].headroom).collect();
    let middle = headrooms.len() / 2;
    let (_, &mut headroom, _) = headrooms.select_nth_unstable_by(middle, f64::total_cmp);
    let unit = grid.scale.unit;
    let rooms = unit
        .map(|(per_metre, _)| headroom / per_metre)
        .filter(|headroom| through == Through::Interior && ROOM_HEIGHTS.contains(headroom));
    Ok(Some(Walk {
        line: turns(&points),
        eye_height: grid.scale.eye,
        cell: grid.cell,
        region: cells_of(&ground.floors, &region) as f64 / grid.cells() as f64,
        open_sky: sky as f64 / points.len() as f64,
        through,
        roofed: interior.roofed,
        indoors: interior.indoors,
        unit: unit.map(|(_, name)| name),
        rooms,
        unit_from_rooms: false,
    }))
}

/// How many cells `floors` lie in (storeys share cells).
fn cells_of(all: &[Floor], floors: &[usize]) -> usize {
    let mut cells: Vec<usize> = floors.iter().map(|&f| all[f].cell).collect();
    cells.sort_unstable();
    cells.dedup();
    cells.len()
}

/// The ground grid: square cells about an eye height wide over the model's
/// focus, along its ground axes.
#[derive(Clone, Copy)]
struct Grid {
    up: DVec3,
    right: DVec3,
    ahead: DVec3,
    /// The grid's corner along `right` and `ahead`, and its extent along
    /// them.
    x0: f64,
    y0: f64,
    width: f64,
    depth: f64,
    cell: f64,
    /// Cells along `right` and `ahead`.
    nx: usize,
    ny: usize,
    scale: Scale,
    /// The model's bottom and top along `up`.
    low: f64,
    high: f64,
}

impl Grid {
    /// The grid over `bounds`, about `scene`'s up axis, at the scale the
    /// box's width and height give ([`scale_of`]); `None` when the box has
    /// no width to lay cells on.
    fn over(scene: &Scene, bounds: &Aabb) -> Option<Grid> {
        let up = scene.up.axis.vector();
        let (right, ahead) = scene.up.axis.ground_axes();
        let (low, high) = bounds.span_along(up);
        let ((x0, x1), (y0, y1)) = (bounds.span_along(right), bounds.span_along(ahead));
        let (width, depth) = (x1 - x0, y1 - y0);
        let grid = Grid {
            up,
            right,
            ahead,
            x0,
            y0,
            width,
            depth,
            cell: 0.0,
            nx: 0,
            ny: 0,
            scale: scale_of(width.max(depth), high - low),
            low,
            high,
        };
        let grid = grid.at_scale(grid.scale);
        (grid.cell > 0.0 && grid.cell.is_finite()).then_some(grid)
    }

    /// The same ground in cells for `scale`'s eye.
    fn at_scale(&self, scale: Scale) -> Grid {
        let longer = self.width.max(self.depth);
        let side = ((longer / scale.eye).ceil() as usize).clamp(MIN_SIDE_CELLS, MAX_SIDE_CELLS);
        let cell = longer / side as f64;
        Grid {
            cell,
            nx: ((self.width / cell).ceil() as usize).max(1),
            ny: ((self.depth / cell).ceil() as usize).max(1),
            scale,
            ..*self
        }
    }

    fn cells(&self) -> usize {
        self.nx * self.ny
    }

    /// The point `height` up over the centre of cell `k`.
    fn at(&self, k: usize, height: f64) -> DVec3 {
        let (i, j) = (k % self.nx, k / self.nx);
        self.right * (self.x0 + (i as f64 + 0.5) * self.cell)
            + self.ahead * (self.y0 + (j as f64 + 0.5) * self.cell)
            + self.up * height
    }
}

/// Floors, cell by cell: surfaces with room for the eye and a margin
/// above them, outside every solid, below the model's top; and where each
/// cell's floors start among them (and, last, where they end).
fn find_floors(
    scene: &Scene,
    bounds: &Aabb,
    grid: &Grid,
    caster: &RayCaster,
) -> Result<(Vec<Floor>, Vec<usize>), Stopped> {
    let Grid {
        up,
        cell,
        scale: Scale {
            room, below_top, unit, ..
        },
        low,
        high,
        ..
    } = *grid;
    let solid = solid_parts(scene, bounds, grid.right, grid.ahead, up);
    let mut floors: Vec<Floor> = Vec::new();
    let mut first = Vec::with_capacity(grid.cells() + 1);
    let mut hits: Vec<Hit> = Vec::new();
    let mut inside: Vec<u32> = Vec::new();
    let top = high + cell;
    for k in 0..grid.cells() {
        caster.searching()?;
        first.push(floors.len());
        caster.all_hits(grid.at(k, top), -up, top - low + cell, &mut hits);
        let part = |hit: &Hit| scene.objects[hit.object as usize].part;
        // A ray through an edge meets both triangles at one point, maybe
        // of two clusters of one part: one crossing.
        hits.dedup_by(|b, a| part(a) == part(b) && (b.t - a.t).abs() <= 1e-9 * a.t.abs().max(1.0));
        inside.clear();
        let mut above = f64::INFINITY;
        for hit in &hits {
            let height = top - hit.t;
            let roofed = above.is_finite();
            if above - height >= room && inside.is_empty() && height + below_top <= high {
                floors.push(Floor {
                    cell: k,
                    height,
                    roofed,
                    headroom: above - height,
                    over_floor: false,
                });
            }
            let part = part(hit);
            if solid[part as usize] {
                match inside.iter().position(|&p| p == part) {
                    Some(n) => {
                        inside.swap_remove(n);
                    }
                    None => inside.push(part),
                }
            }
            above = height;
        }
        // At a person's sizes, a floor open to the sky over another floor
        // may be a roof ([`roofs`]). (At a share of the model's height the
        // floor under it may be the hollow of an open mesh's slab: a
        // pavement tile's.)
        let start = first[k];
        if unit.is_some() && floors.len() - start >= 2 && !floors[start].roofed {
            floors[start].over_floor = true;
        }
    }
    first.push(floors.len());
    Ok((floors, first))
}

/// A route's floors, end to start, and the floors of the joined region it
/// was taken from.
type Route = (Vec<usize>, Vec<usize>);

/// The floors linked into ground to walk on: which are open, and the
/// links between them.
struct Ground<'c, 'a> {
    grid: Grid,
    floors: Vec<Floor>,
    /// Each floor's linked floor in the cells on its four sides.
    links: Vec<[Option<usize>; 4]>,
    /// Floors linked on all four sides, with a clear ray at eye height to
    /// each.
    open: Vec<bool>,
    /// The links between open floors (joined): every route takes them.
    open_edges: Vec<Vec<usize>>,
    caster: &'c RayCaster<'a>,
}

/// What the interior's search found: its route, when it is long and holds
/// most of the open floors, and [`Walk::roofed`] and [`Walk::indoors`].
struct Interior {
    route: Option<Route>,
    roofed: f64,
    indoors: f64,
}

impl<'c, 'a> Ground<'c, 'a> {
    /// Links each floor to the floor of each neighbouring cell within a
    /// step (floors of one cell lie at least the eye's room apart, so at
    /// most one is), and finds the open floors and joins them.
    fn link(
        grid: Grid,
        floors: Vec<Floor>,
        first: &[usize],
        caster: &'c RayCaster<'a>,
    ) -> Result<Ground<'c, 'a>, Stopped> {
        let (nx, ny) = (grid.nx, grid.ny);
        let step = match grid.scale.unit {
            Some((per_metre, _)) => (0.5 * grid.scale.eye).min(PERSON_STEP * per_metre + grid.cell),
            None => 0.5 * grid.scale.eye,
        };
        let links: Vec<[Option<usize>; 4]> = floors
            .iter()
            .map(|f| {
                let (i, j) = (f.cell % nx, f.cell / nx);
                [
                    (i > 0).then(|| f.cell - 1),
                    (i + 1 < nx).then(|| f.cell + 1),
                    (j > 0).then(|| f.cell - nx),
                    (j + 1 < ny).then(|| f.cell + nx),
                ]
                .map(|neighbour| {
                    let n = neighbour?;
                    (first[n]..first[n + 1]).find(|&g| (floors[g].height - f.height).abs() <= step)
                })
            })
            .collect();
        let mut ground = Ground {
            grid,
            floors,
            links,
            open: Vec::new(),
            open_edges: Vec::new(),
            caster,
        };
        // Open: no roof, linked on all four sides, with a clear line at eye
        // height to each (a wall thinner than a cell may stand between two
        // cells' centres, and only that line meets it).
        // Links are mutual (the neighbour's floor within a step is the only
        // one), so each line is cast once: from each floor to its links
        // towards +x and +y (sides 1 and 3), and read from the neighbour's
        // for sides 0 and 2.
        let clear = |a: usize, b: usize| {
            let (p, q) = (ground.point(a), ground.point(b));
            caster.first_hit(p, q - p, 1.0).is_none()
        };
        let clear_onwards: Vec<[bool; 2]> = (0..ground.floors.len())
            .map(|f| [1, 3].map(|side| ground.links[f][side].is_some_and(|g| clear(f, g))))
            .collect();
        let clear_to = |f: usize, side: usize| match side % 2 {
            1 => clear_onwards[f][side / 2],
            _ => ground.links[f][side].is_some_and(|g| clear_onwards[g][side / 2]),
        };
        let roof = roofs(&ground.floors, &ground.links);
        let open: Vec<bool> = (0..ground.floors.len())
            .map(|f| !roof[f] && (0..4).all(|side| clear_to(f, side)))
            .collect();
        let open_edges = (0..ground.floors.len())
            .map(|f| match open[f] {
                true => ground.links[f].iter().flatten().copied().filter(|&g| open[g]).collect(),
                false => Vec::new(),
            })
            .collect();
        (ground.open, ground.open_edges) = (open, open_edges);
        caster.searching()?;
        Ok(ground)
    }

    /// Floor `f`'s eye.
    fn point(&self, f: usize) -> DVec3 {
        self.grid
            .at(self.floors[f].cell, self.floors[f].height + self.grid.scale.eye)
    }

    /// The longest shortest route through the largest joined region of
    /// `chosen` open floors between two of its floors that `ends` allows
    /// (the farthest such from one, then the farthest from that), and the
    /// region's floors.
    fn longest_route(&self, chosen: &[bool], ends: impl Fn(usize) -> bool) -> Option<Route> {
        let edges: Vec<Vec<usize>> = self
            .open_edges
            .iter()
            .enumerate()
            .map(|(f, e)| match chosen[f] {
                true => e.iter().copied().filter(|&g| chosen[g]).collect(),
                false => Vec::new(),
            })
            .collect();
        let start = largest_region(&edges, chosen)?;
        let (far, _, _) = farthest(&edges, start, &ends);
        let (end, parents, region) = farthest(&edges, far, &ends);
        let mut route = vec![end];
        while let Some(previous) = parents[route[route.len() - 1]] {
            route.push(previous);
        }
        Some((route, region))
    }

    /// Of eight level rays from floor `f`'s eye, how many meet something
    /// within `reach`.
    fn walls(&self, f: usize, reach: f64) -> usize {
        let p = self.point(f);
        (0..8)
            .filter(|&a| {
                let angle = std::f64::consts::TAU * f64::from(a) / 8.0;
                let direction = self.grid.right * angle.cos() + self.grid.ahead * angle.sin();
                self.caster.first_hit(p, direction, reach).is_some()
            })
            .count()
    }

    /// The streets' route: through open floors with walls around, where at
    /// least half of eight level rays meet something within
    /// [`STREET_REACH`] cells (at a crossing only the four diagonals do); a
    /// walk along them sees occlusion, one round the open outskirts does
    /// not. Where a street meets a crossing, a cell or two see too few
    /// walls: streets take in the open floors that near. `None` unless the
    /// route is long, and its streets are a good part of the open ground
    /// around them, not a lane between a few walls in a park or a forest.
    fn street_route(&self) -> Result<Option<Route>, Stopped> {
        let walled: Vec<bool> = (0..self.floors.len())
            .map(|f| self.open[f] && self.walls(f, STREET_REACH * self.grid.cell) >= 4)
            .collect();
        self.caster.searching()?;
        let streets = widen(&walled, &self.links, &self.open, STREET_GAP);
        Ok(self.longest_route(&streets, |_| true).filter(|(route, region)| {
            let (_, _, around) = farthest(&self.open_edges, route[0], |_| true);
            route.len() >= LONG_ROUTE && region.len() as f64 >= STREET_SHARE * around.len() as f64
        }))
    }

    /// The interior: open floors indoors, under a roof (the cell's ray met
    /// the model above the floor) with walls around (level rays meet the
    /// model within its size, `bounds`, in six of eight directions), not
    /// under a porch or a canopy open at the sides. When their largest
    /// joined region holds most of the open floor, the walk goes through
    /// it; when they are most of it but no joined part of them is, it goes
    /// from indoor floor to indoor floor through the roofed ones. They lie
    /// in one joined region of roofed floors, so only one that large is
    /// searched for walls (the inside of an object is roofed, but seldom
    /// most).
    fn interior(&self, bounds: &Aabb) -> Result<Interior, Stopped> {
        let open_count = self.open.iter().filter(|&&o| o).count();
        let most = |floors: usize| 2 * floors >= open_count;
        let roofed: Vec<bool> = (0..self.floors.len())
            .map(|f| self.open[f] && self.floors[f].roofed)
            .collect();
        let roofed = self
            .longest_route(&roofed, |_| true)
            .map_or_else(Vec::new, |(_, region)| region);
        let mut in_roofed = vec![false; self.floors.len()];
        let mut indoors = vec![false; self.floors.len()];
        if most(roofed.len()) {
            let reach = bounds.extent().length();
            for &f in &roofed {
                in_roofed[f] = true;
                indoors[f] = self.walls(f, reach) >= INTERIOR_WALLS;
            }
            self.caster.searching()?;
        }
        let indoor_count = indoors.iter().filter(|&&i| i).count();
        // Through the indoor floors, where most of them are joined; where
        // most floors are indoors but no joined part of them is most (rooms
        // whose doors lie in lines from wall to wall: a doorway in line lets
        // level rays out along the line and, doors being at the middle of
        // square rooms' walls, along the diagonals too, so the floors that
        // join rooms are not indoors themselves), from indoor floor to
        // indoor floor through the roofed ones.
        let joined = self.longest_route(&indoors, |_| true);
        let interior = match joined {
            Some((_, ref region)) if !most(region.len()) && most(indoor_count) => {
                self.longest_route(&in_roofed, |f| indoors[f])
            }
            joined => joined,
        };
        let share = |floors: usize| floors as f64 / open_count.max(1) as f64;
        Ok(Interior {
            indoors: share(indoor_count),
            route: interior.filter(|(route, _)| route.len() >= LONG_ROUTE && most(indoor_count)),
            roofed: share(roofed.len()),
        })
    }
}

/// Which parts are solids to stand outside of: closed parts, but not a
/// shell as tall as half the model that covers most of its ground (a hall,
/// a sky box), which is space to walk in.
fn solid_parts(scene: &Scene, model: &Aabb, right: DVec3, ahead: DVec3, up: DVec3) -> Vec<bool> {
    let footprint = |b: &Aabb| {
        let e = b.extent();
        (e.dot(right.abs()), e.dot(ahead.abs()), e.dot(up.abs()))
    };
    let (model_w, model_d, model_h) = footprint(model);
    let mut bounds = vec![Aabb::EMPTY; scene.parts.len()];
    for o in &scene.objects {
        bounds[o.part as usize] = bounds[o.part as usize].union(o.bounds);
    }
    scene
        .parts
        .iter()
        .zip(&bounds)
        .map(|(part, b)| {
            let (w, d, h) = footprint(b);
            let shell = h >= 0.5 * model_h && w * d >= 0.5 * model_w * model_d;
            part.closed && !shell
        })
        .collect()
}

/// Of eight level rays from an interior's floor, how many must meet the
/// model.
const INTERIOR_WALLS: usize = 6;

/// How far (in cells) a street's walls may lie.
const STREET_REACH: f64 = 16.0;

/// The streets must hold at least this share of the open ground joined to
/// them.
const STREET_SHARE: f64 = 0.25;

/// Open cells this close (in steps) to a walled one are street too.
const STREET_GAP: usize = 2;

/// Roofs: the floors of each linked region of floors open to the sky most
/// of whose floors lie over another floor of their cell (in metres, as a
/// roof over rooms does), but of the largest such region only where nine
/// tenths of it do (a building's roof, standing alone): the walk keeps to
/// the floors below. Streets over a tunnel, a car park or a metro under
/// most of them lie in the largest region, and stay. (Without roofs, a
/// roof more than the room below a chimney's top was open ground, and a
/// storey of rooms was walked on its roof.)
fn roofs(floors: &[Floor], links: &[[Option<usize>; 4]]) -> Vec<bool> {
    let sky = |f: usize| !floors[f].roofed;
    let mut seen = vec![false; floors.len()];
    // The regions' floors one after another, and per region where its
    // floors lie there and how many of them lie over another floor.
    let mut members: Vec<usize> = Vec::new();
    let mut regions: Vec<(std::ops::Range<usize>, usize)> = Vec::new();
    for seed in (0..floors.len()).filter(|&f| sky(f)) {
        if seen[seed] {
            continue;
        }
        seen[seed] = true;
        let start = members.len();
        members.push(seed);
        let mut k = start;
        while let Some(&f) = members.get(k) {
            k += 1;
            for &g in links[f].iter().flatten() {
                if sky(g) && !seen[g] {
                    seen[g] = true;
                    members.push(g);
                }
            }
        }
        let over = members[start..].iter().filter(|&&f| floors[f].over_floor).count();
        regions.push((start..members.len(), over));
    }
    let largest = (0..regions.len()).max_by_key(|&r| regions[r].0.len());
    let mut roof = vec![false; floors.len()];
    for (r, (region, over)) in regions.into_iter().enumerate() {
        let share = match Some(r) == largest {
            true => LARGEST_ROOF_SHARE,
            false => 0.5,
        };
        if over as f64 > share * region.len() as f64 {
            members[region].iter().for_each(|&f| roof[f] = true);
        }
    }
    roof
}

/// The share of the largest region open to the sky that must lie over
/// other floors for it to be a roof ([`roofs`]).
const LARGEST_ROOF_SHARE: f64 = 0.9;

/// `chosen` floors and the `allowed` ones within `steps` links of them.
fn widen(chosen: &[bool], links: &[[Option<usize>; 4]], allowed: &[bool], steps: usize) -> Vec<bool> {
    let mut out = chosen.to_vec();
    let mut front: Vec<usize> = (0..chosen.len()).filter(|&f| chosen[f]).collect();
    for _ in 0..steps {
        let mut next = Vec::new();
        for &f in &front {
            for &g in links[f].iter().flatten() {
                if allowed[g] && !out[g] {
                    out[g] = true;
                    next.push(g);
                }
            }
        }
        front = next;
    }
    out
}

/// Cells a route through the streets needs, or the walk takes the open
/// ground as a whole; and a place's walk, to be its default path.
pub const LONG_ROUTE: usize = 4 * MIN_CELLS;

/// Joined cells a walk needs at least.
pub const MIN_CELLS: usize = 8;

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

/// The cell of `ends` farthest from `start` in steps (`start` where it
/// reaches none), each reached cell's parent on a shortest route from
/// `start`, and the cells reached.
fn farthest(
    edges: &[Vec<usize>],
    start: usize,
    ends: impl Fn(usize) -> bool,
) -> (usize, Vec<Option<usize>>, Vec<usize>) {
    let mut parent = vec![None; edges.len()];
    let mut seen = vec![false; edges.len()];
    seen[start] = true;
    let (mut last, mut reached) = (start, Vec::new());
    let mut queue = VecDeque::from([start]);
    while let Some(k) = queue.pop_front() {
        if ends(k) {
            last = k;
        }
        reached.push(k);
        for &n in &edges[k] {
            if !seen[n] {
                seen[n] = true;
                parent[n] = Some(k);
                queue.push_back(n);
            }
        }
    }
    (last, parent, reached)
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
