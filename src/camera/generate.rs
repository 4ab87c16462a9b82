//! Camera paths generated from a scene: used when `--path` is omitted and by
//! `occlu path gen`.

use std::fmt;
use std::ops::ControlFlow;
use std::str::FromStr;

use glam::DVec3;

use super::path::{CameraPath, DEFAULT_FOV_Y_DEG, Interpolation, KeyframeFile, NEAR_RANGE, PathError, PathFile};
use super::walk::{self, Through, Walk};
use crate::bounds::Aabb;
use crate::raycast::{Budget, Hit, RayCaster, Stopped};
use crate::scene::cameras::{CameraPose, FileAnimation, SAMPLES_PER_SECOND};
use crate::scene::{Focus, LeftOut, Scene};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// Circle the scene at 25° elevation, looking at its centre.
    Orbit,
    /// Eye height along the scene's streets (built-in scenes), or through a
    /// model's free space ([`walk`]): its streets, its interior, its open
    /// ground.
    Walk,
    /// Straight across above the scene, looking ahead and down.
    Flyover,
    /// The file's own cameras in order, one keyframe each (glTF).
    Cameras,
    /// An animation of the file that moves a camera, sampled (glTF).
    Animation,
}

impl fmt::Display for PathKind {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            PathKind::Orbit => "orbit",
            PathKind::Walk => "walk",
            PathKind::Flyover => "flyover",
            PathKind::Cameras => "cameras",
            PathKind::Animation => "animation",
        })
    }
}

impl FromStr for PathKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "orbit" => PathKind::Orbit,
            "walk" => PathKind::Walk,
            "flyover" => PathKind::Flyover,
            "cameras" => PathKind::Cameras,
            "animation" => PathKind::Animation,
            _ => {
                return Err(format!(
                    "unknown path kind '{s}' (orbit, walk, flyover, cameras, animation[=NAME])"
                ));
            }
        })
    }
}

/// The kinds made from the scene's shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shape {
    Orbit,
    Walk,
    Flyover,
}

impl PathKind {
    fn shape(self) -> Option<Shape> {
        match self {
            PathKind::Orbit => Some(Shape::Orbit),
            PathKind::Walk => Some(Shape::Walk),
            PathKind::Flyover => Some(Shape::Flyover),
            PathKind::Cameras | PathKind::Animation => None,
        }
    }
}

/// What `--kind` asks for: a kind, and for `animation=NAME` which one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PathRequest {
    pub kind: PathKind,
    pub animation: Option<String>,
}

impl FromStr for PathRequest {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (kind, name) = match s.split_once('=') {
            Some((kind, name)) => (kind.parse()?, Some(name.to_string())),
            None => (s.parse()?, None),
        };
        if name.is_some() && kind != PathKind::Animation {
            return Err(format!("only the animation kind takes a name ('{s}')"));
        }
        Ok(PathRequest { kind, animation: name })
    }
}

pub const DEFAULT_FRAMES: u32 = 120;

/// A generated path and why it is what it is (which kind, and for a walk
/// what it rests on), for the messages and summary.json.
#[derive(Clone, Debug, PartialEq)]
pub struct Generated {
    pub kind: PathKind,
    pub file: PathFile,
    pub why: String,
}

/// Told, now and then while a path is planned, the box and triangle tests
/// spent and allowed ([`Budget`]); breaking stops the planning
/// ([`PathError::Interrupted`]).
pub type PlanListener<'a> = Box<dyn FnMut(u64, u64) -> ControlFlow<()> + 'a>;

/// The box and triangle tests planning one path may spend (the orbit's
/// lines of sight and the walk's rays together): about 6 times what the
/// most planning of the models in ../shared/models needs
/// (two-cylinder-engine.glb, 91 M tests, 1.1 s on this project's 2-core
/// machine; den-haag.obj 40 M; `cargo bench --bench planning`), and 5 to
/// 12 s of work there. A model beyond it (thousands of instances of one
/// mesh in one place: every ray meets millions of triangles) gets the path
/// that needs no planning: an orbit by default, a straight line for a walk.
pub const PLANNING_TESTS: u64 = 1 << 29;

/// The path used when none is given ([`DEFAULT_FRAMES`] frames): a walk
/// where the scene suggests one (the built-in scenes' streets), where
/// circling the model would show nothing but one object (a sky dome around
/// it, or a closed shell hiding everything else), through a place's open
/// ground, and through an interior (most of the walkable floor indoors,
/// in one roofed region, and most of the model's triangles unseen from the
/// orbit);
/// an orbit otherwise. Paths made from the scene's shape frame its focus
/// ([`Focus`]), not a ground plane or sky dome around it.
pub fn default_path(scene: &Scene) -> Result<(CameraPath, String), PathError> {
    default_path_heard(scene, Box::new(|_, _| ControlFlow::Continue(())))
}

/// [`default_path`], with `listener` told how the planning goes.
pub fn default_path_heard(scene: &Scene, listener: PlanListener) -> Result<(CameraPath, String), PathError> {
    let generated = plan_heard(None, scene, None, listener)?;
    let path = CameraPath::from_file(&generated.file, &format!("generated:{}", generated.kind))?;
    Ok((path, generated.why))
}

/// The path `request` asks for over `scene` (the default of
/// [`default_path`] when `None`), with why, in `frames` frames (default: one
/// per camera for `cameras`, the animation's own time at
/// [`SAMPLES_PER_SECOND`] for `animation`, [`DEFAULT_FRAMES`] otherwise).
pub fn plan(request: Option<&PathRequest>, scene: &Scene, frames: Option<u32>) -> Result<Generated, PathError> {
    plan_heard(request, scene, frames, Box::new(|_, _| ControlFlow::Continue(())))
}

/// [`plan`], with `listener` told how the planning goes. Planning spends
/// at most [`PLANNING_TESTS`]; past them the kinds that need planning fall
/// back to one that does not, and `why` says so.
pub fn plan_heard(
    request: Option<&PathRequest>,
    scene: &Scene,
    frames: Option<u32>,
    listener: PlanListener,
) -> Result<Generated, PathError> {
    let budget = Budget {
        tests: PLANNING_TESTS,
        listener,
    };
    let caster = RayCaster::with_budget(scene, budget);
    let mut focus = Focus::of(scene);
    let (kind, why, planned) = match request {
        Some(r) => (r.kind, "asked for".to_string(), None),
        None => match default_kind(scene, &caster, &mut focus) {
            Err(Stopped::Spent) => (PathKind::Orbit, format!("{}: circled from outside", spent()), None),
            chosen => chosen.map_err(interrupted)?,
        },
    };
    let walk = || walk::plan(scene, &focus.bounds, &caster);
    let shape_frames = frames.unwrap_or(DEFAULT_FRAMES);
    if kind.shape().is_some() {
        sized_for_a_path(scene, &focus)?;
    }
    let (file, note) = match (kind, kind.shape()) {
        (_, Some(shape)) => generate_with(shape, scene, &focus, shape_frames, || match planned {
            Some(planned) => Ok(Some(planned)),
            None => walk(),
        })
        .map_err(interrupted)?,
        (PathKind::Cameras, None) => (from_cameras(scene, frames)?, None),
        (_, None) => {
            let name = request.and_then(|r| r.animation.as_deref());
            let (file, animation) = from_animation(scene, name, frames)?;
            (file, Some(format!("animation '{animation}'")))
        }
    };
    let why = match note {
        Some(note) => format!("{why}; {note}"),
        None => why,
    };
    Ok(Generated { kind, file, why })
}

/// A path of `kind` over `scene` in `frames` frames: [`plan`] without the
/// why.
pub fn generate(kind: PathKind, scene: &Scene, frames: u32) -> Result<PathFile, PathError> {
    let request = PathRequest { kind, animation: None };
    plan(Some(&request), scene, Some(frames)).map(|generated| generated.file)
}

/// The file's cameras in order, one keyframe each, with their fields of
/// view; the path's near plane is the nearest of theirs.
fn from_cameras(scene: &Scene, frames: Option<u32>) -> Result<PathFile, PathError> {
    if scene.cameras.is_empty() {
        return Err(PathError::NotInFile(
            "the model has no cameras (glTF files may carry them)".into(),
        ));
    }
    let keyframes = scene
        .cameras
        .iter()
        .enumerate()
        .map(|(k, c)| pose_key(k as f64, &c.pose))
        .collect();
    let near = scene.cameras.iter().filter_map(|c| c.pose.near).reduce(f64::min);
    let frames = frames.unwrap_or(scene.cameras.len() as u32);
    Ok(file_path(keyframes, near, Some(frames)))
}

/// The poses of the camera an animation moves (the one named, or the first
/// that moves a camera), at the animation's own times; and its name.
fn from_animation(scene: &Scene, name: Option<&str>, frames: Option<u32>) -> Result<(PathFile, String), PathError> {
    let moving: Vec<&FileAnimation> = scene.animations.iter().filter(|a| a.camera.is_some()).collect();
    let names = || {
        let list: Vec<&str> = moving.iter().map(|a| a.name.as_str()).collect();
        if list.is_empty() {
            "none".to_string()
        } else {
            list.join(", ")
        }
    };
    let chosen = match name {
        Some(name) => moving.iter().find(|a| a.name == name).ok_or_else(|| {
            PathError::NotInFile(format!(
                "no animation '{name}' moves a camera (those that do: {})",
                names()
            ))
        })?,
        None => moving
            .first()
            .ok_or_else(|| PathError::NotInFile("no animation of the model moves a camera".into()))?,
    };
    let camera = chosen.camera.as_ref().expect("filtered on a camera");
    let start = camera.poses[0].0;
    let keyframes = camera.poses.iter().map(|(t, pose)| pose_key(t - start, pose)).collect();
    let near = camera.poses.iter().filter_map(|(_, p)| p.near).reduce(f64::min);
    // The animation's own time at SAMPLES_PER_SECOND, both ends included
    // (counted, not derived from an fps: key times stored in f32 fall a
    // hair short of whole frames).
    let duration = camera.poses[camera.poses.len() - 1].0 - start;
    let own = (duration * SAMPLES_PER_SECOND).round().min(f64::from(u32::MAX - 1)) as u32 + 1;
    let file = file_path(keyframes, near, Some(frames.unwrap_or(own)));
    Ok((file, chosen.name.clone()))
}

/// A keyframe at `time` with a camera's pose.
fn pose_key(time: f64, pose: &CameraPose) -> KeyframeFile {
    KeyframeFile {
        orientation: Some(pose.rotation.to_array()),
        fov_y_deg: pose.fov_y_deg,
        ..key(time, pose.eye)
    }
}

/// A path through `keyframes` (linear between them: they are the file's
/// poses), of `frames` frames.
fn file_path(keyframes: Vec<KeyframeFile>, near: Option<f64>, frames: Option<u32>) -> PathFile {
    PathFile {
        frames,
        fps: None,
        near,
        fov_y_deg: None,
        up: None,
        interpolation: Interpolation::Linear,
        keyframes,
    }
}

/// The share of a walk's route that must be open to the sky for a model to
/// be a place to walk through (streets, a site) rather than an object to
/// circle (whose "ground" would be inside it).
const OPEN_PLACE: f64 = 0.75;

/// How long a walk must be, in its grid's cells, for a place to be walked
/// rather than circled.
const LONG_WALK: f64 = walk::LONG_ROUTE as f64;

/// The near plane of a path made from a scene's shape, as a share of the
/// scene's diagonal.
const NEAR_SHARE: f64 = 1e-4;

/// Refuses a scene whose size would give a path made from its shape a
/// near plane (a share of its focus) outside the range a path may have,
/// naming the model (not the path, which is not at fault).
fn sized_for_a_path(scene: &Scene, focus: &Focus) -> Result<(), PathError> {
    let diagonal = focus.bounds.extent().length();
    let near = diagonal * NEAR_SHARE;
    let (least, most) = (*NEAR_RANGE.start(), *NEAR_RANGE.end());
    let (size, bound, remedy) = if near < least {
        ("small", format!("below the {least:e}"), "scale the model up")
    } else if near > most {
        ("large", format!("above the {most:e}"), "scale the model down")
    } else {
        return Ok(());
    };
    Err(PathError::Invalid {
        path: scene.source.clone(),
        message: format!(
            "the model is {diagonal:.2e} units across, too {size} to make a path from: its near plane ({NEAR_SHARE:e} of that) would be {bound} a camera path may have; {remedy}, or write the path by hand"
        ),
    })
}

/// What a path says when its planning spent [`PLANNING_TESTS`].
fn spent() -> String {
    format!(
        "planning a walk stopped at its budget of {} M box and triangle tests (its rays met too much geometry)",
        PLANNING_TESTS / 1_000_000
    )
}

/// A stopped caster as the planner's error: only an interruption gets
/// here (a spent budget falls back to a simpler path).
fn interrupted(_: Stopped) -> PathError {
    PathError::Interrupted
}

/// The default kind for `scene`, why, and the walk planned to decide it
/// over `focus`. A part the focus left out that encloses the rest and that
/// the rest stands on may be its room's shell, not a sky: `focus` takes it
/// back where the walk inside it goes through rooms.
fn default_kind(
    scene: &Scene,
    caster: &RayCaster,
    focus: &mut Focus,
) -> Result<(PathKind, String, Option<Walk>), Stopped> {
    if scene.walk_hint.is_some() {
        return Ok((PathKind::Walk, "the walk the scene was built with".into(), None));
    }
    if let Some(camera) = scene.animations.iter().find_map(|a| a.camera.as_ref()) {
        return Ok((
            PathKind::Animation,
            format!("the file's animated camera '{}'", camera.name),
            None,
        ));
    }
    let circle = "circled from outside";
    let sight = Sight::from_orbit(scene, caster)?;
    let mut enclosed = sight.enclosure(scene);
    let mut planned = walk::plan(scene, &focus.bounds, caster)?;
    if let Some((shell, _)) = sight.encloser()
        && focus.left_out.contains(&LeftOut::Part(shell))
        && rest_stands_on(scene, caster, focus, shell)?
    {
        let room = focus.taking_back(scene, shell);
        // Walked inside, it must be a room in a person's unit, the one the
        // rest was read in where that was known: a town standing on a
        // sky box's floor is in metres, and inside the box reads as rooms
        // in centimetres.
        let read_in = planned.as_ref().and_then(|walk| walk.unit);
        let inside = walk::plan(scene, &room.bounds, caster)?
            .filter(|walk| walk.rooms.is_some() && read_in.is_none_or(|unit| walk.unit == Some(unit)));
        if inside.is_some() {
            (*focus, planned) = (room, inside);
            enclosed = enclosed.map(|why| format!("{why}, which stand on it"));
        }
    }
    let Some(planned) = planned else {
        let why = enclosed.map_or("a model".to_string(), |e| format!("{e}, but"));
        return Ok((PathKind::Orbit, format!("{why} with no ground to walk: {circle}"), None));
    };
    let length = planned.length();
    let long = length >= LONG_WALK * planned.cell;
    let (open, roofed, indoors) = (
        100.0 * planned.open_sky,
        100.0 * planned.roofed,
        100.0 * planned.indoors,
    );
    let unseen = sight.unseen_note();
    Ok(match enclosed {
        Some(why) => (PathKind::Walk, why, Some(planned)),
        None if planned.open_sky >= OPEN_PLACE && long => (
            PathKind::Walk,
            format!("a place with open ground ({open:.0}% of the walk under the sky)"),
            Some(planned),
        ),
        None if planned.through == Through::Interior && long && sight.misses_most() => (
            PathKind::Walk,
            format!(
                "an interior ({indoors:.0}% of the walkable floor indoors, under a roof with walls around, in one roofed region; {unseen})"
            ),
            Some(planned),
        ),
        None => {
            // Where most of the floor is roofed, the indoors share (walls
            // around) is judged too: it tells whether this was near an
            // interior.
            let indoors = match planned.roofed >= 0.5 {
                true => format!(", {indoors:.0}% indoors (walls around in six of eight directions)"),
                false => String::new(),
            };
            (
                PathKind::Orbit,
                format!(
                    "an object (its longest walk {length:.1} units over {:.0} cells, {open:.0}% under the sky; {roofed:.0}% of the walkable floor under a roof and joined{indoors}; {unseen}): {circle}",
                    length / planned.cell,
                ),
                None,
            )
        }
    })
}

/// What circling the whole scene sees from its orbit (outside the
/// scene's bounds, ground planes and sky domes included): which object
/// lines of sight to a sample of the others meet first, and how much of
/// the model no eye of the orbit sees at all.
struct Sight {
    /// Lines of sight cast to the sampled objects.
    rays: usize,
    /// The part that hid the most of them (met first on the way to an
    /// object of another part), and how many.
    hider: Option<(u32, usize)>,
    /// Objects aimed at.
    targets: usize,
    /// Triangles sampled, and those seen from no eye of the orbit.
    sampled: u64,
    unseen: u64,
}

/// Triangles sampled to judge how much of a model its orbit sees.
const SIGHT_TRIANGLES: u64 = 256;

/// A surface met this close before a sampled triangle's centroid (a share
/// of the line of sight) is the triangle itself, or one lying on it.
const SAME_SURFACE: f64 = 1e-6;

impl Sight {
    fn from_orbit(scene: &Scene, caster: &RayCaster) -> Result<Sight, Stopped> {
        let b = scene.bounds;
        let ground = Ground::of(scene, &b);
        let keys = orbit(&ground, b.center(), b.extent().length().max(1e-6));
        // The orbit ends where it starts: its last eye is its first.
        let eyes: Vec<DVec3> = keys[..keys.len() - 1].iter().map(|k| DVec3::from(k.position)).collect();
        // Clusters of one split mesh ("dome#0", "dome#1") are one part.
        let part = |object: usize| scene.objects[object].part;
        let targets: Vec<usize> = (0..scene.objects.len())
            .step_by(scene.objects.len().div_ceil(64))
            .collect();
        let mut first: std::collections::HashMap<u32, usize> = Default::default();
        let mut rays = 0;
        for eye in eyes.iter().step_by(4) {
            caster.searching()?;
            for &t in &targets {
                let to = scene.objects[t].bounds.center() - *eye;
                if let Some(hit) = caster.first_hit(*eye, to, 1.0)
                    && part(hit.object as usize) != part(t)
                {
                    *first.entry(part(hit.object as usize)).or_default() += 1;
                }
                rays += 1;
            }
        }
        // Every `stride`-th triangle in the scene's order (a sample weighed
        // by triangles, whatever the objects): seen when the line from
        // some eye to its centroid meets nothing before it.
        let stride = scene.triangles().div_ceil(SIGHT_TRIANGLES).max(1);
        let (mut sampled, mut unseen) = (0, 0);
        let mut before = 0;
        for object in &scene.objects {
            caster.searching()?;
            let end = before + u64::from(object.triangles);
            for index in (before.next_multiple_of(stride)..end).step_by(stride as usize) {
                let corners = scene.triangle(object.mesh, (index - before) as u32);
                let centroid = object
                    .transform
                    .transform_point3((corners[0] + corners[1] + corners[2]) / 3.0);
                let seen = eyes.iter().step_by(2).any(|&eye| {
                    caster
                        .first_hit(eye, centroid - eye, 1.0)
                        .is_none_or(|hit| hit.t >= 1.0 - SAME_SURFACE)
                });
                sampled += 1;
                unseen += u64::from(!seen);
            }
            before = end;
        }
        caster.searching()?;
        Ok(Sight {
            rays,
            hider: first
                .iter()
                .max_by_key(|&(p, n)| (*n, std::cmp::Reverse(*p)))
                .map(|(&p, &n)| (p, n)),
            targets: targets.len(),
            sampled,
            unseen,
        })
    }

    /// The part circling the scene would show alone, if one would: it is
    /// the first thing met on the way to nearly every other object (a sky
    /// dome or a closed shell around the rest), and the lines of sight it
    /// hides.
    fn encloser(&self) -> Option<(u32, usize)> {
        let (hider, n) = self.hider?;
        (self.targets > 1 && 10 * n >= 9 * self.rays).then_some((hider, n))
    }

    /// Why circling `scene` would show one part only ([`Self::encloser`]),
    /// if it would.
    fn enclosure(&self, scene: &Scene) -> Option<String> {
        let (hider, n) = self.encloser()?;
        let name = &scene.parts[hider as usize].name;
        Some(format!(
            "from the orbit, '{name}' hides {n} of {} lines of sight to the other objects",
            self.rays
        ))
    }

    /// Whether the orbit would miss most of the model: most of its
    /// triangles are seen from no eye of it (what an interior holds; an
    /// empty shell shows most of its triangles outside).
    fn misses_most(&self) -> bool {
        2 * self.unseen > self.sampled
    }

    /// The share of the model no eye of the orbit sees, for a reason.
    fn unseen_note(&self) -> String {
        format!(
            "{:.0}% of its triangles unseen from the orbit",
            100.0 * self.unseen as f64 / self.sampled.max(1) as f64
        )
    }
}

/// How far from an object's box's bottom a surface may lie for the object
/// to stand on it, as a share of the focus's height.
const STANDING_GAP: f64 = 0.01;

/// Whether most of the objects in `focus` that stand on something (the
/// nearest surface of another part within [`STANDING_GAP`] above or below
/// the middle of their box's bottom; a tie goes to a part other than
/// `part`) stand on `part`: the floor of a room whose shell is one part
/// with its walls and ceiling, where a town stands on its ground, not on
/// the sky box around it. Up to 64 objects are tried, spread over the
/// scene's order.
fn rest_stands_on(scene: &Scene, caster: &RayCaster, focus: &Focus, part: u32) -> Result<bool, Stopped> {
    let up = scene.up.axis.vector();
    let (low, high) = focus.bounds.span_along(up);
    let gap = STANDING_GAP * (high - low);
    let in_focus: Vec<usize> = (0..scene.objects.len())
        .filter(|&o| !focus.left_out.contains(&LeftOut::Part(scene.objects[o].part)))
        .collect();
    let part_of = |hit: &Hit| scene.objects[hit.object as usize].part;
    let (mut standing, mut on_part) = (0, 0);
    let mut hits = Vec::new();
    for &o in in_focus.iter().step_by(in_focus.len().div_ceil(64).max(1)) {
        let object = &scene.objects[o];
        let b = object.bounds;
        let (bottom, _) = b.span_along(up);
        let middle = b.center() + up * (bottom + gap - b.center().dot(up));
        caster.all_hits(middle, -up, 2.0 * gap, &mut hits);
        let mut under = hits.iter().filter(|hit| part_of(hit) != object.part).peekable();
        if let Some(&&nearest) = under.peek() {
            standing += 1;
            let tied = |hit: &&Hit| hit.t <= nearest.t + TIED * gap;
            on_part += usize::from(under.take_while(tied).all(|hit| part_of(hit) == part));
        }
    }
    caster.searching()?;
    Ok(2 * on_part > standing)
}

/// Surfaces this share of [`STANDING_GAP`] apart are equally near.
const TIED: f64 = 1e-6;

/// [`generate`], with `walk` planning the walk a scene without streets
/// gets; for such a walk also what it rests on. A planning that spent its
/// budget walks a straight line, as one that found no ground does.
fn generate_with(
    kind: Shape,
    scene: &Scene,
    focus: &Focus,
    frames: u32,
    walk: impl FnOnce() -> Result<Option<Walk>, Stopped>,
) -> Result<(PathFile, Option<String>), Stopped> {
    let b = focus.bounds;
    let ground = Ground::of(scene, &b);
    let diagonal = b.extent().length().max(1e-6);
    let mut note = None;
    let keyframes = match kind {
        Shape::Orbit => orbit(&ground, b.center(), diagonal),
        Shape::Walk => match &scene.walk_hint {
            Some(line) if line.len() >= 2 => walk_along(line, (diagonal * 0.02).max(1.0)),
            _ => match walk() {
                Ok(Some(w)) => {
                    let length = w.length();
                    let unit = match (w.unit_from_rooms, w.unit, w.rooms) {
                        (true, Some(unit), Some(headroom)) => format!(", in {unit} for rooms {headroom:.2} m high"),
                        _ => String::new(),
                    };
                    note = Some(format!(
                        "a walk along the longest route through {}, {length:.1} units at eye height {:.3}{unit} (cells of {:.3}, {:.0}% of them joined to it)",
                        w.through,
                        w.eye_height,
                        w.cell,
                        100.0 * w.region
                    ));
                    walk_along(&w.line, w.cell)
                }
                Err(Stopped::Interrupted) => return Err(Stopped::Interrupted),
                found => {
                    let why = match found {
                        Err(_) => spent(),
                        Ok(_) => "no ground with room to walk was found".into(),
                    };
                    note = Some(format!("{why}: a straight line through the middle"));
                    let (axis, length) = ground.longer_axis();
                    let height = ground.lowest + 0.05 * ground.height();
                    let at = |t: f64| ground.lift(b.center() + axis * length * t, height);
                    walk_along(&[at(-0.45), at(0.45)], diagonal * 0.05)
                }
            },
        },
        Shape::Flyover => {
            let (axis, length) = ground.longer_axis();
            let c = ground.lift(b.center(), ground.highest + 0.25 * length);
            let pitch = 35f64.to_radians();
            let direction = axis * pitch.cos() - ground.up * pitch.sin();
            [(0.0, c - axis * length * 0.6), (1.0, c + axis * length * 0.6)]
                .map(|(time, position)| KeyframeFile {
                    time,
                    position: position.to_array(),
                    direction: Some(direction.to_array()),
                    ..key(time, position)
                })
                .to_vec()
        }
    };
    let note = match (note, focus.note(scene)) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    };
    let file = PathFile {
        frames: Some(frames),
        fps: None,
        near: Some(diagonal * NEAR_SHARE),
        fov_y_deg: Some(DEFAULT_FOV_Y_DEG),
        up: Some(ground.up.to_array()),
        interpolation: Interpolation::CatmullRom,
        keyframes,
    };
    Ok((file, note))
}

fn key(time: f64, position: DVec3) -> KeyframeFile {
    KeyframeFile {
        time,
        position: position.to_array(),
        target: None,
        direction: None,
        orientation: None,
        up: None,
        fov_y_deg: None,
    }
}

/// The ground plane under a box of the scene (its bounds, or its focus),
/// as the scene's up axis defines it.
struct Ground {
    up: DVec3,
    /// The two axes spanning the ground, and the box's extent along each.
    across: [(DVec3, f64); 2],
    /// The box's lowest and highest points along `up`.
    lowest: f64,
    highest: f64,
}

impl Ground {
    fn of(scene: &Scene, b: &Aabb) -> Ground {
        let up = scene.up.axis.vector();
        let (right, ahead) = scene.up.axis.ground_axes();
        let along = |axis: DVec3| {
            let (least, greatest) = b.span_along(axis);
            greatest - least
        };
        let (lowest, highest) = b.span_along(up);
        Ground {
            up,
            across: [(right, along(right)), (ahead, along(ahead))],
            lowest,
            highest,
        }
    }

    fn height(&self) -> f64 {
        self.highest - self.lowest
    }

    /// The longer ground axis (pointing to its positive side) and the
    /// scene's extent along it.
    fn longer_axis(&self) -> (DVec3, f64) {
        let [a, b] = self.across;
        let (axis, length) = if a.1 >= b.1 { a } else { b };
        (axis.abs(), length)
    }

    /// `point` moved along `up` to `height`.
    fn lift(&self, point: DVec3, height: f64) -> DVec3 {
        point + self.up * (height - point.dot(self.up))
    }
}

/// Circles the scene's centre `c` about its up axis at 25° elevation, far
/// enough that the bounding sphere (of diameter `diagonal`) fits the
/// vertical field of view, looking at `c`.
fn orbit(ground: &Ground, c: DVec3, diagonal: f64) -> Vec<KeyframeFile> {
    let radius = 0.5 * diagonal / (DEFAULT_FOV_Y_DEG.to_radians() / 2.0).sin();
    let elevation = 25f64.to_radians();
    let [(right, _), (ahead, _)] = ground.across;
    let steps = 24;
    (0..=steps)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(steps);
            // For +Y up, (+X, −Z): anticlockwise seen from above.
            let around = right * a.cos() - ahead * a.sin();
            let outward = around * elevation.cos() + ground.up * elevation.sin();
            // Looking back along the offset, not at the centre: far from
            // the origin, eye − centre would lose what f64 drops of both.
            KeyframeFile {
                direction: Some((-outward).to_array()),
                ..key(f64::from(k), c + radius * outward)
            }
        })
        .collect()
}

/// Keyframes every `spacing` units along a polyline, each looking at the
/// point `3·spacing` further on (past the end: straight ahead). Time is
/// arc length, so the walk has constant speed.
fn walk_along(line: &[DVec3], spacing: f64) -> Vec<KeyframeFile> {
    let lengths: Vec<f64> = line.windows(2).map(|w| (w[1] - w[0]).length()).collect();
    let total: f64 = lengths.iter().sum();
    let at = |s: f64| -> DVec3 {
        let mut s = s;
        for (w, &len) in line.windows(2).zip(&lengths) {
            if s <= len || len == 0.0 {
                return w[0] + (w[1] - w[0]) * (s / len.max(f64::MIN_POSITIVE)).min(1.0);
            }
            s -= len;
        }
        // Beyond the end: keep going in the last direction.
        let (a, b) = (line[line.len() - 2], line[line.len() - 1]);
        b + (b - a).normalize_or_zero() * s
    };
    let count = ((total / spacing).ceil() as usize).max(1);
    (0..=count)
        .map(|k| {
            let s = total * k as f64 / count as f64;
            KeyframeFile {
                target: Some(at(s + 3.0 * spacing).to_array()),
                ..key(s, at(s))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::path::CameraPath;
    use crate::scene::{LoadOptions, SceneSpec, load};

    fn city() -> Scene {
        load(&SceneSpec::Builtin("city:blocks=2".into()), &LoadOptions::default()).unwrap()
    }

    #[test]
    fn every_kind_gives_a_valid_path_inside_sensible_bounds() {
        let scene = city();
        for kind in [PathKind::Orbit, PathKind::Walk, PathKind::Flyover] {
            let file = generate(kind, &scene, 30).unwrap();
            let path = CameraPath::from_file(&file, "gen").unwrap();
            assert_eq!(path.frames, 30);
            for f in 0..30 {
                let c = path.camera(f, 4.0 / 3.0);
                assert!(c.eye.is_finite() && c.rotation.is_finite(), "{kind} frame {f}");
            }
        }
    }

    #[test]
    fn city_walk_stays_at_eye_height_on_the_streets() {
        let scene = city();
        let path = CameraPath::from_file(&generate(PathKind::Walk, &scene, 50).unwrap(), "walk").unwrap();
        for f in 0..50 {
            let c = path.camera(f, 1.0);
            assert!((c.eye.y - crate::scene::builtin::EYE_HEIGHT).abs() < 1e-6);
            // No building contains the eye.
            assert!(
                scene
                    .objects
                    .iter()
                    .filter(|o| o.name.ends_with("/shell"))
                    .all(|o| !o.bounds.contains_point(c.eye))
            );
            assert!(c.forward().y.abs() < 1e-6, "looks along the street");
        }
    }

    #[test]
    fn orbit_keeps_the_scene_centre_in_view() {
        let scene = city();
        let path = CameraPath::from_file(&generate(PathKind::Orbit, &scene, 40).unwrap(), "orbit").unwrap();
        let c = scene.bounds.center();
        for f in 0..40 {
            let cam = path.camera(f, 4.0 / 3.0);
            let to_centre = (c - cam.eye).normalize();
            assert!(cam.forward().dot(to_centre) > 0.999, "frame {f}");
        }
    }
}
