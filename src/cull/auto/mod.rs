//! `auto`: the conservative mode that costs least on this adapter and view,
//! chosen frame by frame from measured frame times, so that a scene with
//! nothing to cull costs no more than `vfc` and one with much to cull no
//! more than its best occlusion culler.
//!
//! 002 §4.3 notes that culling "does not pay off" where little is hidden
//! and bounds culling time by the render time it saves (Eq. 2); engines
//! choose per scene by measurement. Here:
//!
//! - **Candidates** are the registry's modes whose entry allows it
//!   ([`Candidacy`]) and whose needs this adapter meets, each built with the
//!   run's parameters: `vfc`, the query-batching modes (`omq`, and `chc`
//!   where the adapter counts pixels), CPU occlusion culling, and the GPU
//!   walks where the adapter walks on the GPU. Which pays is measured, not
//!   assumed (those the warm-up calibration shows far dearer are not
//!   explored, only rechecked); but
//!   in a scene of one object only `vfc` runs, since occlusion culling
//!   hides an object only behind another one.
//! - **Choice** (choice.rs): one incumbent runs; the others are probed as
//!   a bandit does, each probe compared with the incumbent's frames on both
//!   sides; a rival takes over only when cheaper beyond the noise; rivals
//!   known to be dearer are rechecked within a time budget; where occlusion
//!   hides next to nothing, `vfc` runs and occlusion is checked again only
//!   when the view has changed materially.
//! - **Hand-over** ([`Carries`]): no strategy starts from nothing. The GPU
//!   walks share one set of visible lists, so a walk takes over the visible
//!   set the last one found, as if it had run all along; after a frame an
//!   occlusion culler drew on the CPU, the lists take what it drew, after
//!   the frame and untimed (not where it holds more triangles than the
//!   lists' last fresh writer drew, unless they would be stale by the
//!   next frame: [`lists_after`]); after `vfc` (everything in the
//!   frustum), the walks start from their own lists, even stale ones,
//!   but from everything in the frustum where the view has outgrown them
//!   (which their test against its depth sorts out in one frame); a walk's
//!   first frame from stale lists only settles it and is not measured. A
//!   culler that keeps its visible set on the CPU is handed the objects drawn
//!   last, unless it ran the frame before the last itself (its own state
//!   is then as fresh, and it keeps what it learned: `swr` its buffer's
//!   rest): `swr` takes them as occluders, `chc` as what it found visible
//!   (after `vfc`, everything in the frustum, which it draws once; that
//!   frame settles it and is not measured). A frame that
//!   started from stale lists, or from everything in the frustum, drew that
//!   set untested: it does not count towards what occlusion hides. A frame
//!   an occlusion culler ran as frustum culling's own (`swr` while its
//!   buffer rests: [`Culler::frustum_only`]) is handed over and read as
//!   `vfc`'s: it drew the whole frustum and says nothing of what occlusion
//!   hides.
//! - **Warm-up**: in a warm-up frame every candidate renders the frame in
//!   turn, from a cleared target, so none pays its first frame (pipelines
//!   compiled on first use) in a recorded one; each walk starts from the
//!   shared lists as the frame found them, as it would in a recorded frame,
//!   not from those a walk before it wrote in the frame (in the first
//!   warm-up frame a walk runs twice before any candidate renders it, so
//!   that the lists hold a visible set of a view, not everything in the
//!   frustum, which a walk finds visible from empty lists). From the third
//!   warm-up frame on (the first two pay for first uses), each is timed
//!   from its start to the GPU's end of its
//!   work, and the chooser is calibrated with these paired times, each
//!   frame's of one view: the cheapest runs from the first recorded frame,
//!   and a rival shown dearer is not explored in recorded frames, only
//!   rechecked within the budget (with the default warm-up's full window
//!   of calibrating frames, any rival shown dearer; with fewer, one shown
//!   far dearer). What each occlusion culler that draws on the CPU
//!   drew there says what it hides: the most any of them hid is the share
//!   of the view the calibration's samples are of, and where nothing seems
//!   hidden the culler that looks again is not one that hides nothing
//!   where another hides something.
//!
//! Every candidate is conservative, so `auto` is too.
//!
//! Departures: what a GPU walk drew (handed to the CPU cullers, and counted
//! for the hidden share that judges `vfc` before it runs) is taken from its
//! untimed audit; an engine reads it back a frame late, without waiting.
//! The frustum's triangles (what judges what occlusion hid) are counted
//! after the frame, untimed, and a CPU culler's drawn set goes into the
//! walks' lists there too: an engine takes the count from its culling's
//! frustum test, and uploads the set with the frame's other data.
//! The calibration uses the bench's warm-up frames, which no mode's figures
//! include, as an engine would calibrate in its loading frames. It times
//! each candidate's own work, without the refit of the hierarchy around
//! movers that every candidate would share, so with movers its ratios come
//! out a little wider than probes measure. Samples from the calibration
//! and from probes share a window, each read as having a probe's spread.
//! The default warm-up (`--warmup 10`) calibrates on the path's first
//! eight views, a full window; with fewer than three warm-up frames `auto`
//! learns by probing alone.

mod choice;

use std::rc::Rc;
use std::time::Instant;

use serde::Serialize;

use crate::balanced_order::balanced_order;
use crate::bounds::Aabb;
use crate::cull::culler::{Culler, FrameInput, Pick, TraversalStats};
use crate::cull::gpu_walk::VisibleLists;
use crate::cull::mode::{Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::cull::registry::auto_candidates;
use crate::cull::traversal::frustum_cull_subtree;
use crate::gpu::{BoxTest, BoxVisibility, Frame, GpuAudit, GpuContext, GpuError, GpuFrame, GpuSetup};
use crate::object_set::ObjectSet;
use crate::scene::Scene;
use choice::{Chooser, Cost, Family, Occluded, Turn, View};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Auto,
    summary: "per frame, the conservative mode measured cheapest here (vfc, the query-batching modes, CPU culling and, where the adapter culls on the GPU, the GPU walks): rivals probed as a bandit does and switched to only when cheaper beyond the noise; vfc where occlusion hides nothing",
    chart_colour: [255, 187, 120],
    conservative: true,
    draws_by_time: true,
    params: &[BUDGET],
    exercised_with: &[],
    needs: Needs::Nothing,
    carries: Carries::OwnState,
    auto: Candidacy::Never,
    check: |params| AutoParams::from_params(params).map(drop),
    build: |scene, params| Ok(Box::new(AutoCulling::new(scene, params)?)),
};

const BUDGET: ParamInfo = ParamInfo {
    key: "budget",
    default: "1.5",
    summary: "percent of the run's time that rechecks of strategies known to be no cheaper may cost",
};

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AutoParams {
    /// Share of the run's time (percent) for rechecks.
    pub budget: f64,
}

impl AutoParams {
    pub fn from_params(params: &ModeParams) -> Result<AutoParams, ModeError> {
        let budget: f64 = params.get(ModeId::Auto, &BUDGET)?;
        if !(budget > 0.0 && budget <= 100.0) {
            return Err(ModeError::bad(
                ModeId::Auto,
                &BUDGET,
                "must be a percentage above 0 and at most 100".into(),
            ));
        }
        Ok(AutoParams { budget })
    }
}

/// One strategy `auto` may run.
struct Candidate {
    id: ModeId,
    culler: Box<dyn Culler>,
    /// The frame it last ran (warm-up's included).
    last_ran: Option<u64>,
}

impl Candidate {
    fn carries(&self) -> Carries {
        self.id.info().carries
    }

    fn family(&self) -> Family {
        family(self.id)
    }
}

fn family(id: ModeId) -> Family {
    match id {
        ModeId::Vfc => Family::Frustum,
        _ => Family::Occlusion,
    }
}

/// The frame `auto` ran last.
#[derive(Clone, Copy, Debug)]
struct Ran {
    turn: Turn,
    view: View,
    /// The family it ran as: its strategy's, or [`Family::Frustum`] where
    /// the frame was frustum culling's own ([`Culler::frustum_only`]:
    /// `swr` while its buffer rests).
    family: Family,
    /// Whether the frustum's triangles were counted for it: after it,
    /// untimed ([`Ran::recount`]), or in a frame drawn as frustum
    /// culling's just before, whose drawn triangles are that count.
    counted: bool,
    /// Whether they are still to be counted after it
    /// ([`AutoCulling::after_frame`]): a count is a frustum traversal,
    /// which in the timed frame would weigh on every measured occlusion
    /// frame's time.
    recount: bool,
    /// Whether it started from a visible set of this view. A GPU walk that
    /// did not (its lists from another view, or everything in the frustum
    /// after `vfc`) draws that set before it tests anything, more than
    /// occlusion needs here, so what it drew says nothing of what
    /// occlusion hides.
    fresh: bool,
}

/// The frame that last wrote the visible lists the GPU walks share (a
/// walk's, or one whose drawn set they took: [`lists_take_drawn`]), where
/// it looked, and the bar a CPU culler's drawn set is held to: the
/// triangles the last writer that started from a visible set of its view
/// drew ([`lists_after`]; none counted in warm-up, whose walks draw
/// indirectly while the others draw on the CPU).
#[derive(Clone, Copy, Debug)]
struct Lists {
    frame: u64,
    view: View,
    drew: Option<u64>,
}

/// How a GPU walk starts a frame in `view` (frame number `frame`), its
/// shared lists as last `written`, handed the last frame's drawn set by a
/// frame of family `handed_by` ([`Ran::family`]; none where the walk ran
/// last itself, or nothing was drawn yet).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct WalkStart {
    /// No walk wrote the lists in the last two frames, or the last one
    /// that did looked at a frustum `view` outgrew (a camera turning from
    /// an empty edge into the city; an orbit's or a walk's lists from two
    /// frames ago still hold most of what is visible).
    stale: bool,
    /// The drawn set replaces stale lists: where an occlusion culler drew
    /// it, and after `vfc` (all in the frustum) only where the lists were
    /// written in a frustum `view` outgrew. A walk that starts from
    /// everything in the frustum tests against its depth and knows what is
    /// visible after one frame; one that starts from another view's lists
    /// needs two. (After a frame of a culler that draws on the CPU, the
    /// lists took its drawn set already, untimed, where it held no more
    /// triangles than they drew.)
    upload: bool,
    /// It starts from a visible set of this view ([`Ran::fresh`]).
    fresh: bool,
}

fn walk_start(written: Option<Lists>, frame: u64, view: &View, handed_by: Option<Family>) -> WalkStart {
    let outgrown = written.is_some_and(|w| view.outgrew(&w.view));
    let stale = outgrown || written.is_none_or(|w| frame - w.frame > 2);
    match handed_by {
        None => WalkStart {
            stale,
            upload: false,
            fresh: !stale,
        },
        Some(family) => WalkStart {
            stale,
            upload: stale && (family == Family::Occlusion || outgrown),
            fresh: !stale || family == Family::Occlusion,
        },
    }
}

/// Whether the walks' lists take the drawn set of a recorded frame that
/// ran a culler `carrying` its visible set as it does, as family `ran_as`
/// ([`Ran::family`]), `fresh` or not ([`Ran::fresh`]), which drew `drew`
/// triangles, against the lists' bar `lists_drew` ([`Lists`]; none
/// where no frame set one, or the lists are stale); after the frame and
/// untimed. Where an occlusion culler that draws on
/// the CPU drew it from a visible set of this view (not one that settled,
/// drawing everything in the frustum it was handed), the set is of this
/// view, and a walk that starts from it in the next frame draws no more
/// than it needs (on the two-cylinder engine's orbit, a walk started from
/// its own lists of two frames before, after an `omq` probe, drew 2.3 %
/// more triangles on average and up to 28 % more than where it had run
/// the frame before itself); but only where it holds no more triangles
/// than the lists drew, since a walk draws its lists before it tests
/// anything: with cars driving through the city on llvmpipe, `swr`'s
/// probes drew a median 1.3 times the triangles the walk drew the frame
/// before (0.1 to 3.8 times, over 74 probes of the city with and without
/// cars), and the walk's frame after each, started from what they drew,
/// drew 14 000 triangles more than its own run did at that frame, up to
/// 1.6 times its time. A walk writes
/// them itself; `vfc`'s set is the whole frustum, and so is a coarse
/// culler's (`chc`'s on a scan whose clusters its leaves join), which the
/// lists beat by their triangles.
fn lists_take_drawn(carrying: Carries, ran_as: Family, fresh: bool, drew: u64, lists_drew: Option<u64>) -> bool {
    carrying != Carries::VisibleOnGpu && ran_as == Family::Occlusion && fresh && lists_drew.is_none_or(|l| drew <= l)
}

/// The walks' lists after recorded frame `frame`, which `ran` a culler
/// `carrying` its visible set as it does and drew `drew` triangles, the
/// lists as last `written`: whether they take its drawn set
/// ([`lists_take_drawn`]), and what has then last written them.
fn lists_after(written: Option<Lists>, frame: u64, ran: &Ran, carrying: Carries, drew: u64) -> (bool, Option<Lists>) {
    // Lists stale by the next frame are replaced whatever they drew: kept,
    // a walk would upload the same set in its timed frame.
    let stale_next = walk_start(written, frame + 1, &ran.view, None).stale;
    let lists_drew = written.and_then(|l| l.drew).filter(|_| !stale_next);
    let take = lists_take_drawn(carrying, ran.family, ran.fresh, drew, lists_drew);
    if carrying != Carries::VisibleOnGpu && !take {
        return (false, written);
    }
    // A walk that did not start from a visible set of its view (everything
    // in the frustum after `vfc`, or lists gone stale) drew far more than
    // the visible lists it leaves: the bar stays the last fresh writer's,
    // though of an older view, until a fresh frame sets it again. (A
    // settling frame, `chc` drawing the whole frustum it was handed, is not
    // taken even where the lists are stale: the walk after it uploads that
    // set in its timed frame, as after `vfc`; a settling frame is followed
    // by its culler's measured one, so a walk seldom comes next.)
    let fresh = carrying != Carries::VisibleOnGpu || ran.fresh;
    let bar = if fresh {
        Some(drew)
    } else {
        written.and_then(|l| l.drew)
    };
    let lists = Lists {
        frame,
        view: ran.view,
        drew: bar,
    };
    (take, Some(lists))
}

/// How a culler that keeps its visible set on the CPU (`carries`, one of
/// [`Carries::OccludersOnCpu`] and [`Carries::VisibleOnCpu`]) starts a
/// frame, handed the last frame's drawn set by a frame of family
/// `handed_by` ([`Ran::family`]; none where it ran that frame or the one
/// before itself, [`AutoCulling::cpu_handed_to`], or every candidate did,
/// in a warm-up frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct CpuStart {
    /// It is handed the drawn set ([`Culler::seed_visible`]).
    seed: bool,
    /// Its first frame only settles it: one that draws what it is handed,
    /// handed everything in the frustum by `vfc`, draws it all once.
    settles: bool,
    /// It starts from a visible set of this view ([`Ran::fresh`]): a seed
    /// of occluders, which the culler's own test sorts, always does.
    fresh: bool,
}

fn cpu_start(carries: Carries, handed_by: Option<Family>) -> CpuStart {
    let everything = carries == Carries::VisibleOnCpu && handed_by == Some(Family::Frustum);
    CpuStart {
        seed: handed_by.is_some(),
        settles: everything,
        fresh: !everything,
    }
}

/// A frame that counts the triangles of the objects drawn through it, as
/// a culler drawing on the CPU draws them: in a warm-up frame, what each
/// candidate hid.
struct Counting<'a> {
    frame: &'a mut dyn Frame,
    scene: &'a Scene,
    triangles: u64,
}

impl Frame for Counting<'_> {
    fn draw(&mut self, objects: &[u32]) {
        let triangles = objects
            .iter()
            .map(|&o| u64::from(self.scene.objects[o as usize].triangles));
        self.triangles += triangles.sum::<u64>();
        self.frame.draw(objects);
    }
    fn test_boxes(&mut self, boxes: &[Aabb], kind: BoxTest, out: &mut Vec<BoxVisibility>) {
        self.frame.test_boxes(boxes, kind, out);
    }
    fn test_boxes_with_totals(
        &mut self,
        boxes: &[Aabb],
        sampling: u32,
        out: &mut Vec<BoxVisibility>,
        totals: &mut Vec<u64>,
    ) {
        self.frame.test_boxes_with_totals(boxes, sampling, out, totals);
    }
    fn on_gpu(&mut self) -> Option<&mut dyn GpuFrame> {
        self.frame.on_gpu()
    }
}

/// How far a view's eye may move before it is another view, as a share of
/// the diagonal of the scene's bounds ([`View::differs`]).
const REACH: f64 = 0.1;

/// Warm-up frames that do not calibrate the chooser: in the first every
/// candidate compiles its pipelines, and the second still pays for first
/// uses. Timed in the second, each candidate's time over `roc`'s differed
/// from the same ratio in the modes' own recorded frames of that view by
/// +1.0 to +1.7 (log) for the modes that draw on the CPU (`vfc`, `omq`,
/// `chc`) in the default city and with `--movers 200`, on llvmpipe and
/// lavapipe; from the third on by −0.3 to +0.4 either way, as much as two
/// single frames' noise (`--warmup 6`, six runs).
const UNCALIBRATED_WARM_UPS: usize = 2;

/// Warm-up frames that calibrate the chooser fully: those it does not
/// time, then a window of calibrating frames, the path's first views (the
/// bench's default warm-up). Which mode is cheapest over a path's first
/// views foretells the path better the more views: over 168 recorded runs,
/// the cheapest over the first 3 frames was a geometric 1.031 times the
/// fastest mode's mean, over the first 8, 1.024; the chooser replayed on
/// 308 runs' recorded costs came to 1.023 calibrated on 3 views, 1.016 on
/// 8; and in live runs of every scene and backend of issue 31, ten warm-up
/// frames against five brought `auto` nearer the fastest mode by 1.08 % ±
/// 0.66 % (42 pairs, run in turn scene by scene).
pub const FULL_CALIBRATION_WARM_UPS: u32 = (UNCALIBRATED_WARM_UPS + choice::WINDOW) as u32;

pub struct AutoCulling {
    params: AutoParams,
    /// The run's parameters, those of its candidates recorded with its own
    /// ([`Culler::parameters`]), so that a run of tuned candidates is not
    /// compared with one of default candidates as the same work.
    run_params: ModeParams,
    /// Every candidate built; `prepare` keeps those this adapter runs.
    candidates: Vec<Candidate>,
    /// Made in `prepare`, once the candidates are known.
    chooser: Option<Chooser>,
    /// The visible lists the GPU walks share.
    lists: Option<Rc<VisibleLists>>,
    /// Frames run, warm-up included.
    frames: u64,
    /// Warm-up frames run.
    warm_ups: usize,
    /// The frame that last wrote the walks' lists.
    lists_written: Option<Lists>,
    /// The last recorded frame; `None` after a warm-up frame.
    ran: Option<Ran>,
    /// The candidates that ran in the current frame (all of them in a
    /// warm-up frame).
    running: Vec<usize>,
    /// The objects the last frame drew, and the family it ran as
    /// ([`Ran::family`]; `None` before the first recorded frame: in a
    /// warm-up frame every candidate ran).
    last_drawn: Vec<u32>,
    last_drawn_by: Option<Family>,
    /// Triangles in the frustum as last counted.
    frustum_triangles: u64,
    /// Scratch: the frustum's objects, a traversal stack, and whether each
    /// candidate would settle.
    in_frustum: Vec<u32>,
    stack: Vec<u32>,
    settles: Vec<bool>,
}

impl AutoCulling {
    /// Builds every mode that may be a candidate, with the run's `params`:
    /// frustum culling alone where the scene holds one object, which
    /// nothing else can hide.
    pub fn new(scene: &Scene, params: &ModeParams) -> Result<AutoCulling, ModeError> {
        let something_may_hide = scene.objects.len() >= 2;
        let candidates = auto_candidates()
            .filter(|&id| something_may_hide || family(id) == Family::Frustum)
            .map(|id| {
                Ok(Candidate {
                    id,
                    culler: id.create(scene, params)?,
                    last_ran: None,
                })
            })
            .collect::<Result<_, ModeError>>()?;
        Ok(AutoCulling {
            params: AutoParams::from_params(params)?,
            run_params: params.clone(),
            candidates,
            chooser: None,
            lists: None,
            frames: 0,
            warm_ups: 0,
            lists_written: None,
            ran: None,
            running: Vec::new(),
            last_drawn: Vec::new(),
            last_drawn_by: None,
            frustum_triangles: 0,
            in_frustum: Vec::new(),
            stack: Vec::new(),
            settles: Vec::new(),
        })
    }

    /// Whether the walks' lists are stale in `view` ([`walk_start`]).
    fn lists_stale(&self, view: &View) -> bool {
        walk_start(self.lists_written, self.frames, view, None).stale
    }

    /// The family the last frame ran as, where candidate `k` did not run
    /// it: what `k` is handed ([`Self::hand_over`]).
    fn handed_to(&self, k: usize) -> Option<Family> {
        self.last_drawn_by
            .filter(|_| self.ran.is_none_or(|r| r.turn.strategy != k))
    }

    /// What CPU culler `k` is handed ([`Self::handed_to`]) where it did not
    /// run the frame before the last either: one that did starts from its
    /// own state, as fresh, and keeps what it learned (`swr` a rest of its
    /// buffer, `chc` what it found visible, not everything in the frustum
    /// after a `vfc` probe).
    fn cpu_handed_to(&self, k: usize) -> Option<Family> {
        let ran_lately = self.candidates[k].last_ran.is_some_and(|f| self.frames - f <= 2);
        self.handed_to(k).filter(|_| !ran_lately)
    }

    /// Whether candidate `k` must first settle in `view`: a walk whose lists
    /// are stale, a culler that draws the set it is handed when that is
    /// everything in the frustum, or a culler whose own state went stale.
    fn settles(&self, k: usize, view: &View) -> bool {
        let ran_last = self.ran.is_some_and(|r| r.turn.strategy == k);
        match self.candidates[k].carries() {
            Carries::VisibleOnGpu => self.lists_stale(view),
            carries @ (Carries::OccludersOnCpu | Carries::VisibleOnCpu) => {
                cpu_start(carries, self.cpu_handed_to(k)).settles
            }
            Carries::OwnState => !ran_last,
            Carries::Nothing => false,
        }
    }

    /// Before candidate `k` runs in `view`: hands it what the last frame
    /// drew, where it did not run then. Whether it then starts from a
    /// visible set of this view ([`Ran::fresh`]).
    fn hand_over(&mut self, k: usize, ctx: &mut dyn Frame, view: &View) -> bool {
        match self.candidates[k].carries() {
            Carries::VisibleOnGpu => {
                let start = walk_start(self.lists_written, self.frames, view, self.handed_to(k));
                if let (true, Some(lists), Some(gpu)) = (start.upload, &self.lists, ctx.on_gpu()) {
                    lists.upload(gpu.gpu(), &self.last_drawn);
                }
                start.fresh
            }
            carries @ (Carries::OccludersOnCpu | Carries::VisibleOnCpu) => {
                let start = cpu_start(carries, self.cpu_handed_to(k));
                if start.seed {
                    self.candidates[k].culler.seed_visible(&self.last_drawn);
                }
                start.fresh
            }
            Carries::Nothing | Carries::OwnState => true,
        }
    }

    /// After a frame (`input`), untimed: remembers what it drew, `drawn`,
    /// and the family that drew it, for the next hand-over; counts the
    /// frustum's triangles where a recorded frame was to be counted
    /// ([`Ran::recount`]); and notes what the walks' lists then hold
    /// ([`lists_after`]). Whether the lists take its drawn set.
    /// After a warm-up frame, which every candidate ran from its own state,
    /// none is handed what they drew together.
    fn after_frame(&mut self, input: &FrameInput, drawn: &ObjectSet) -> bool {
        self.last_drawn.clear();
        self.last_drawn.extend(drawn.iter());
        self.last_drawn_by = self.ran.map(|r| r.family);
        let Some(mut ran) = self.ran else {
            return false;
        };
        if ran.recount {
            self.frustum_triangles = self.count_frustum_triangles(input);
            ran.view.frustum_triangles = self.frustum_triangles;
            ran.recount = false;
            self.ran = Some(ran);
        }
        if self.lists.is_none() {
            return false;
        }
        let carries = self.candidates[ran.turn.strategy].carries();
        let objects = &input.scene.objects;
        let drew = drawn.iter().map(|o| u64::from(objects[o as usize].triangles)).sum();
        let (take, written) = lists_after(self.lists_written, self.frames, &ran, carries, drew);
        self.lists_written = written;
        take
    }

    /// Triangles of the objects in the frustum.
    fn count_frustum_triangles(&mut self, input: &FrameInput) -> u64 {
        self.in_frustum.clear();
        frustum_cull_subtree(
            input.scene,
            input.hierarchy,
            0,
            &input.camera.frustum(),
            &mut self.stack,
            &mut self.in_frustum,
            &mut TraversalStats::default(),
        );
        input.scene.triangles_of(&self.in_frustum)
    }

    /// A warm-up frame: every candidate renders the frame from a cleared
    /// target, in turn, in an order that changes from one warm-up frame to
    /// the next ([`balanced_order`]). After the first
    /// [`UNCALIBRATED_WARM_UPS`], each one's time, from its start to the
    /// GPU's end of its work, calibrates the chooser; without a GPU (a test
    /// double) nothing is timed. Each walk starts from the shared lists as
    /// the frame found them, not as a walk before it in the frame left
    /// them ([`VisibleLists::keep`]), and they hold a visible set of a view
    /// from the first warm-up frame on.
    fn warm_up(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let warm_ups = self.warm_ups;
        self.warm_ups += 1;
        let view = View {
            eye: input.camera.eye,
            forward: input.camera.forward(),
            frustum_triangles: self.count_frustum_triangles(input),
        };
        self.frustum_triangles = view.frustum_triangles;
        self.running.clear();
        self.running.extend(balanced_order(warm_ups, self.candidates.len()));
        let mut log_ms = vec![f64::NAN; self.candidates.len()];
        let mut stats = TraversalStats::default();
        // Lists to put back only where a walk may follow another.
        let walks_on_gpu = |c: &Candidate| c.carries() == Carries::VisibleOnGpu;
        let several_walks = self.candidates.iter().filter(|c| walks_on_gpu(c)).count() > 1;
        // Lists that hold no visible set of the view would have every walk
        // timed from them draw the whole frustum before it tests anything,
        // as after `vfc`: from the empty lists a run starts with, a walk
        // finds everything in the frustum visible (nothing is drawn yet to
        // hide it), and from that, what is. So in the first warm-up frame,
        // before any candidate renders it, the first walk runs twice, and
        // the GPU finishes that before `keep` copies the lists on its queue.
        // Left to the timed walks, the first calibrating frame timed every
        // walk at about `vfc`'s frame (117–132 ms, against 35–38 ms for
        // `swr`, with `--movers 200` on lavapipe and llvmpipe), and `roc`,
        // as cheap as `swr` there, looked 1.6 times dearer and was never
        // probed.
        let seeding_walk = match (warm_ups, ctx.on_gpu().is_some()) {
            (0, true) => self.candidates.iter().position(walks_on_gpu),
            _ => None,
        };
        if let Some(k) = seeding_walk {
            for _ in 0..2 {
                self.candidates[k].culler.frame(ctx, input);
            }
            if let Some(gpu) = ctx.on_gpu() {
                gpu.wait_for_gpu();
            }
        }
        let mut kept = false;
        for (place, &k) in self.running.iter().enumerate() {
            if let (true, Some(gpu)) = (place > 0 || seeding_walk.is_some(), ctx.on_gpu()) {
                gpu.clear();
            }
            let walk = several_walks && walks_on_gpu(&self.candidates[k]);
            if let (true, Some(lists), Some(gpu)) = (walk, &self.lists, ctx.on_gpu()) {
                match kept {
                    false => lists.keep(gpu.gpu()),
                    true => lists.restore(gpu.gpu()),
                }
                kept = true;
            }
            let start = Instant::now();
            let mut counting = Counting {
                frame: &mut *ctx,
                scene: input.scene,
                triangles: 0,
            };
            stats = self.candidates[k].culler.frame(&mut counting, input);
            let drawn = counting.triangles;
            if let Some(gpu) = ctx.on_gpu() {
                gpu.wait_for_gpu();
                log_ms[k] = (start.elapsed().as_secs_f64() * 1e3).ln();
            }
            let chooser = self.chooser.as_mut().expect("the session prepared the mode");
            self.candidates[k].last_ran = Some(self.frames);
            // What a culler that draws on the CPU hid (a walk's indirect
            // draws are not counted here).
            if self.candidates[k].carries() == Carries::VisibleOnGpu {
                self.lists_written = Some(Lists {
                    frame: self.frames,
                    view,
                    drew: None,
                });
            } else if view.frustum_triangles > 0 {
                chooser.calibrate_hidden(k, 1.0 - drawn as f64 / view.frustum_triangles as f64, &view);
            }
        }
        if warm_ups >= UNCALIBRATED_WARM_UPS {
            self.chooser
                .as_mut()
                .expect("the session prepared the mode")
                .calibrate(&log_ms, &view);
        }
        self.ran = None;
        stats
    }
}

impl Culler for AutoCulling {
    fn name(&self) -> &str {
        ModeId::Auto.name()
    }

    /// Its budget, its candidates, and, where any were given, the
    /// parameters of the candidates it kept (none where none were, so
    /// that a run with default candidates reads as one before them).
    fn parameters(&self) -> serde_json::Value {
        let candidates: Vec<&str> = self.candidates.iter().map(|c| c.id.name()).collect();
        let mut recorded = serde_json::json!({ "budget": self.params.budget, "candidates": candidates });
        let given: serde_json::Map<String, serde_json::Value> = self
            .candidates
            .iter()
            .flat_map(|c| self.run_params.given_for(c.id))
            .map(|(key, value)| (key.to_string(), value.into()))
            .collect();
        if !given.is_empty() {
            recorded["candidate_params"] = given.into();
        }
        recorded
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        let gpu = setup.gpu;
        self.candidates.retain(|c| {
            let info = c.id.info();
            info.auto == Candidacy::Always && info.unsupported_on(gpu).is_none()
        });
        if self.candidates.iter().any(|c| c.carries() == Carries::VisibleOnGpu) {
            let lists = Rc::new(VisibleLists::new(gpu, setup.draws)?);
            for c in &mut self.candidates {
                c.culler.share_visible_lists(&lists);
            }
            self.lists = Some(lists);
        }
        for c in &mut self.candidates {
            c.culler.prepare(setup)?;
        }
        let families: Vec<Family> = self.candidates.iter().map(Candidate::family).collect();
        // The first occlusion culler starts: most scenes hide something,
        // and its first frame tells how much.
        let incumbent = families.iter().position(|&f| f == Family::Occlusion).unwrap_or(0);
        let root = setup.hierarchy.root().bounds;
        let reach = REACH * (root.max - root.min).length();
        self.chooser = Some(Chooser::new(&families, incumbent, reach, self.params.budget / 100.0));
        Ok(())
    }

    /// # Panics
    /// Before `prepare`: a session prepares every mode first.
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        self.frames += 1;
        if input.warm_up {
            return self.warm_up(ctx, input);
        }
        if let (Some(ran), Some(previous)) = (self.ran, input.previous) {
            let mut view = ran.view;
            let occluded = match ran.family {
                Family::Frustum => {
                    view.frustum_triangles = previous.triangles_drawn;
                    self.frustum_triangles = previous.triangles_drawn;
                    None
                }
                Family::Occlusion => (ran.counted && ran.fresh && view.frustum_triangles > 0).then(|| Occluded {
                    hidden: (1.0 - previous.triangles_drawn as f64 / view.frustum_triangles as f64).max(0.0),
                    drawing: previous.render_ms / previous.frame_ms,
                }),
            };
            let chooser = self.chooser.as_mut().expect("the session prepared the mode");
            let cost = Cost {
                frame_ms: previous.frame_ms,
                triangles: previous.triangles_drawn,
            };
            chooser.learn(ran.turn, cost, occluded, &view);
        }
        let view = View {
            eye: input.camera.eye,
            forward: input.camera.forward(),
            frustum_triangles: self.frustum_triangles,
        };
        let mut settles = std::mem::take(&mut self.settles);
        settles.clear();
        settles.extend((0..self.candidates.len()).map(|k| self.settles(k, &view)));
        let chooser = self.chooser.as_mut().expect("the session prepared the mode");
        let turn = chooser.plan(&view, &settles);
        self.settles = settles;
        let k = turn.strategy;
        let fresh = self.hand_over(k, ctx, &view);
        let stats = self.candidates[k].culler.frame(ctx, input);
        let family = match self.candidates[k].culler.frustum_only() {
            true => Family::Frustum,
            false => self.candidates[k].family(),
        };
        self.candidates[k].last_ran = Some(self.frames);
        // What occlusion hides is counted after every measured occlusion
        // frame, untimed (a frustum traversal in a timed frame would weigh on
        // its time: `vfc`'s traversal of the default city takes 0.05–0.08 ms
        // here, 4–8 % of a frame of 1–2 ms on a fast GPU, worked out, not
        // timed; an engine takes the count from its culling's frustum test);
        // after a frame drawn as frustum culling's, whose triangles are the
        // count already, it is not counted again. Counted only on probes and
        // every eighth frame, what occlusion hides was known late where it
        // changes early: in the forest, whose first view `roc` hid a fifth of
        // and the next ones 2–9 %, the median of its last five counts fell
        // under a tenth at frame 13, and `vfc`, 0.82–0.83 of `roc`'s time
        // over the path (one run on each backend), was first probed after it
        // (at frame 14 in the run); counted every frame, at frame 3 (both
        // worked out from `roc`'s own recorded frames), and `vfc` was probed
        // from frame 4 in the next run. Replayed on the recorded costs of 336
        // runs, 1.0151 against 1.0156; on the replay test's 32, 1.0107 (worst
        // 1.051) against 1.0130 (worst 1.056), and 1.0104 once the shares
        // were kept with their views.
        let after_frustum = self.ran.is_some_and(|r| r.family == Family::Frustum);
        let counted = turn.measured && family == Family::Occlusion;
        self.running.clear();
        self.running.push(k);
        self.ran = Some(Ran {
            turn,
            view,
            family,
            counted,
            recount: counted && !after_frustum,
            fresh,
        });
        stats
    }

    /// Audits what ran this frame, then what follows it untimed
    /// ([`Self::after_frame`]): a walk's drawn set is as its audit reads it
    /// back after the frame (an engine reads it back a frame late, without
    /// waiting), and the walks' lists take a CPU culler's drawn set here.
    fn audit(&mut self, gpu: &GpuContext, input: &FrameInput, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        let mut audit = None;
        for &k in &self.running {
            audit = self.candidates[k].culler.audit(gpu, input, drawn).or(audit);
        }
        if let (true, Some(lists)) = (self.after_frame(input, drawn), &self.lists) {
            lists.upload(gpu, &self.last_drawn);
            // Sent now, untimed: left for the next submit, the writes would
            // land in the next mode's timed frame.
            gpu.queue.submit([]);
            gpu.wait_idle();
        }
        audit
    }

    fn pick(&self) -> Option<Pick> {
        let ran = self.ran?;
        Some(Pick {
            strategy: self.candidates[ran.turn.strategy].id.name(),
            probe: ran.turn.probe,
        })
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::camera::Camera;
    use crate::hierarchy::Hierarchy;

    /// A view from `eye` looking along `forward` at `triangles` triangles.
    fn view(eye: f64, forward: DVec3, triangles: u64) -> View {
        View {
            eye: DVec3::new(eye, 0.0, 0.0),
            forward,
            frustum_triangles: triangles,
        }
    }

    /// Three cubes side by side, all in view of
    /// [`crate::cull::recording::camera_down_z`]: 36 triangles.
    fn three_cubes_in_view() -> (Scene, Hierarchy) {
        let corners = [-2.5, -0.5, 1.5].map(|x| DVec3::new(x, -0.5, -10.0));
        crate::cull::recording::cubes(&corners)
    }

    /// `auto`'s recorded frame `frame` of `scene` seen by `camera`, on the
    /// recording double (every box visible), after a frame that took 10 ms
    /// and drew `drawn` triangles, with its untimed work after it: what it
    /// ran.
    fn record_frame(
        auto: &mut AutoCulling,
        frame: u32,
        camera: &Camera,
        (scene, hierarchy): (&Scene, &Hierarchy),
        drawn: u64,
    ) -> Ran {
        use crate::cull::PreviousFrame;
        use crate::cull::recording::{Recording, input};
        let previous = (frame > 0).then_some(PreviousFrame {
            frame_ms: 10.0,
            render_ms: 9.0,
            triangles_drawn: drawn,
        });
        let frame_input = FrameInput {
            previous,
            ..input(frame, camera, scene, hierarchy)
        };
        let mut calls = Recording::new(|_: &Aabb| true);
        auto.frame(&mut calls, &frame_input);
        let mut objects = ObjectSet::new(scene.objects.len());
        calls.drawn().into_iter().for_each(|o| objects.insert(o));
        auto.after_frame(&frame_input, &objects);
        auto.ran.expect("a recorded frame ran")
    }

    #[test]
    fn a_counting_frame_counts_the_triangles_drawn_through_it_and_passes_everything_on() {
        use crate::cull::recording::{Call, Recording, cubes};
        let (scene, _) = cubes(&[DVec3::ZERO, DVec3::X * 3.0, DVec3::X * 6.0]);
        let mut double = Recording::new(|_: &Aabb| true);
        let mut counting = Counting {
            frame: &mut double,
            scene: &scene,
            triangles: 0,
        };
        counting.draw(&[0, 2]);
        let mut out = Vec::new();
        counting.test_boxes(&[scene.objects[1].bounds], BoxTest::Occlusion, &mut out);
        counting.draw(&[1]);
        assert_eq!(counting.triangles, 3 * u64::from(scene.objects[0].triangles));
        assert_eq!(double.calls.len(), 3);
        assert_eq!(double.calls[0], Call::Draw(vec![0, 2]));
        assert_eq!(out.len(), 1);
    }

    #[test]
    fn in_warm_up_every_walk_starts_from_a_visible_set_and_the_third_frame_calibrates_first() {
        use crate::camera::generate::default_path;
        use crate::gpu::Resolution;
        use crate::hierarchy::HierarchyParams;
        use crate::scene::{LoadOptions, SceneSpec, load};
        use crate::session::{RunOptions, Session};
        use crate::world::World;
        // The city's first view, where occlusion hides nine tenths of what
        // is in the frustum.
        let scene = load(&SceneSpec::Builtin("city:blocks=2".into()), &LoadOptions::default()).unwrap();
        let (path, _) = default_path(&scene).unwrap();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        let options = RunOptions {
            warmup: 1,
            resolution: Resolution {
                width: 160,
                height: 120,
            },
            measure_error: false,
        };
        let camera = path.camera(0, options.resolution.aspect());
        let mut in_frustum = Vec::new();
        let mut stats = TraversalStats::default();
        frustum_cull_subtree(
            &scene,
            &hierarchy,
            0,
            &camera.frustum(),
            &mut Vec::new(),
            &mut in_frustum,
            &mut stats,
        );
        for gpu in &GpuContext::every_gpu_driven_adapter() {
            let mut world = World::new(scene.clone(), hierarchy.clone());
            let mut auto = AutoCulling::new(&scene, &ModeParams::default()).unwrap();
            let mut session = Session::new(gpu, &world, &mut [Box::new(&mut auto)], false, &options).unwrap();
            // The first warm-up frame: the lists it leaves are those the
            // next one's walks are timed from.
            session
                .warm_up_frame(0, &camera, &mut world, &mut [Box::new(&mut auto)], 0)
                .unwrap();
            let lists = auto
                .lists
                .as_ref()
                .expect("an adapter that culls on the GPU runs the walks");
            gpu.check().expect("no GPU error");
            let [_, _, lengths] = lists.read_back(gpu);
            let visible = lengths[0] as usize;
            assert!(
                visible > 0 && 3 * visible < in_frustum.len(),
                "{visible} of the {} objects in the frustum on {}",
                in_frustum.len(),
                gpu.adapter.backend
            );
            let calibrating_frames = |auto: &AutoCulling| auto.chooser.as_ref().map(Chooser::calibrating_frames);
            for frame in 1..=2 {
                assert_eq!(calibrating_frames(&auto), Some(0), "before warm-up frame {frame}");
                let camera = path.camera(frame, options.resolution.aspect());
                session
                    .warm_up_frame(frame, &camera, &mut world, &mut [Box::new(&mut auto)], frame as usize)
                    .unwrap();
            }
            assert_eq!(calibrating_frames(&auto), Some(1), "{}", gpu.adapter.backend);
        }
    }

    #[test]
    fn the_parameters_given_for_its_candidates_are_recorded_with_its_own_and_none_where_none_were() {
        use crate::cull::recording::cubes;
        let (scene, _) = cubes(&[DVec3::ZERO, DVec3::X * 3.0]);
        let default = AutoCulling::new(&scene, &ModeParams::default()).unwrap().parameters();
        assert_eq!(default.get("candidate_params"), None, "{default}");
        let items = ["swr.threads=1".to_string(), "omq.factor=0.5".to_string()];
        let tuned = ModeParams::parse(&items, &[ModeId::Auto]).unwrap();
        let recorded = AutoCulling::new(&scene, &tuned).unwrap().parameters();
        let given = serde_json::json!({ "omq.factor": "0.5", "swr.threads": "1" });
        assert_eq!(recorded["candidate_params"], given, "{recorded}");
        assert_eq!(recorded["budget"], default["budget"]);
    }

    #[test]
    fn a_culler_that_draws_what_it_is_handed_settles_on_vfc_s_set_and_one_that_tests_it_does_not() {
        let start = |seed, settles, fresh| CpuStart { seed, settles, fresh };
        let (occluders, visible) = (Carries::OccludersOnCpu, Carries::VisibleOnCpu);
        // swr takes any set as occluders, and draws only what passes.
        assert_eq!(cpu_start(occluders, Some(Family::Frustum)), start(true, false, true));
        assert_eq!(cpu_start(occluders, Some(Family::Occlusion)), start(true, false, true));
        // chc draws what it is handed: all of the frustum after vfc.
        assert_eq!(cpu_start(visible, Some(Family::Frustum)), start(true, true, false));
        assert_eq!(cpu_start(visible, Some(Family::Occlusion)), start(true, false, true));
        // It ran the last frame itself (or every candidate did).
        for carries in [occluders, visible] {
            assert_eq!(cpu_start(carries, None), start(false, false, true));
        }
    }

    /// `vfc` under another name that says its frames were frustum
    /// culling's own, as `swr` says of a frame its buffer rests in, but
    /// every fourth (a try, as `swr` tries a buffer again after a rest).
    /// Unlike `swr`, a seed does not end its rest.
    struct Resting {
        vfc: crate::cull::FrustumCulling,
        rested: bool,
    }

    impl Culler for Resting {
        fn name(&self) -> &str {
            "resting"
        }
        fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
            self.rested = input.frame % 4 != 1;
            self.vfc.frame(ctx, input)
        }
        fn frustum_only(&self) -> bool {
            self.rested
        }
    }

    #[test]
    fn a_frame_an_occlusion_culler_ran_as_frustum_culling_is_read_as_vfc_s_and_its_next_try_tells_what_is_hidden() {
        use crate::cull::FrustumCulling;
        use crate::cull::recording::camera_down_z;
        // Nothing hidden: three cubes side by side, all in view.
        let (scene, hierarchy) = three_cubes_in_view();
        let camera = camera_down_z();
        let params = ModeParams::default();
        let mut auto = AutoCulling::new(&scene, &params).unwrap();
        // The occlusion culler (in swr's place) is the incumbent.
        auto.candidates = vec![
            Candidate {
                id: ModeId::Vfc,
                culler: Box::new(FrustumCulling::new(&scene)),
                last_ran: None,
            },
            Candidate {
                id: ModeId::Swr,
                culler: Box::new(Resting {
                    vfc: FrustumCulling::new(&scene),
                    rested: false,
                }),
                last_ran: None,
            },
            Candidate {
                id: ModeId::Chc,
                culler: ModeId::Chc.create(&scene, &params).unwrap(),
                last_ran: None,
            },
        ];
        let families: Vec<Family> = auto.candidates.iter().map(Candidate::family).collect();
        auto.chooser = Some(Chooser::new(&families, 1, 1.0, 0.015));
        let all_in_frustum = 3 * u64::from(scene.objects[0].triangles);
        let (mut rested, mut tried, mut settling) = (0, 0, 0);
        for frame in 0..24 {
            let before = auto.ran;
            let ran = record_frame(&mut auto, frame, &camera, (&scene, &hierarchy), all_in_frustum);
            if ran.turn.strategy != 1 {
                continue;
            }
            if frame % 4 != 1 {
                rested += 1;
                // Not counted as an occlusion frame (it drew the frustum,
                // and hid nothing because it tested nothing), and `chc`,
                // handed everything in the frustum, first settles, as
                // after `vfc` (where it did not run lately: then it keeps
                // its own state).
                assert!(!ran.counted, "frame {frame}");
                assert_eq!(auto.last_drawn_by, Some(Family::Frustum), "frame {frame}");
                // Asked as the next frame plans.
                auto.frames += 1;
                let chc_lately = auto.candidates[2].last_ran.is_some_and(|f| auto.frames - f <= 2);
                if !chc_lately {
                    settling += 1;
                    assert!(auto.settles(2, &ran.view), "frame {frame}");
                }
                auto.frames -= 1;
            } else if before.is_some_and(|b| b.family == Family::Frustum) {
                // A try after a rest tells what occlusion hides.
                tried += 1;
                assert!(ran.counted, "frame {frame}");
                assert_eq!(auto.last_drawn_by, Some(Family::Occlusion), "frame {frame}");
            }
        }
        assert!(
            rested >= 6 && tried >= 3,
            "the incumbent rested {rested} and tried {tried} of 24 frames"
        );
        assert!(
            settling > 0,
            "chc, not run lately, was looked at after no resting frame"
        );
    }

    #[test]
    fn every_measured_frame_of_an_occlusion_culler_tells_what_occlusion_hides() {
        let (scene, hierarchy) = three_cubes_in_view();
        let camera = crate::cull::recording::camera_down_z();
        let params = ModeParams::default();
        let mut auto = AutoCulling::new(&scene, &params).unwrap();
        auto.candidates.retain(|c| [ModeId::Vfc, ModeId::Chc].contains(&c.id));
        let families: Vec<Family> = auto.candidates.iter().map(Candidate::family).collect();
        let chc = families.iter().position(|&f| f == Family::Occlusion).unwrap();
        let mut chooser = Chooser::new(&families, chc, 1.0, 0.015);
        // Warm-up showed `vfc` far dearer: it is only rechecked, so `chc`
        // runs frame after frame, not after a frame of `vfc`'s.
        let view = View {
            eye: camera.eye,
            forward: camera.forward(),
            frustum_triangles: 36,
        };
        for _ in 0..3 {
            let log_ms = families.iter().map(|&f| if f == Family::Frustum { 1.0 } else { 0.0 });
            chooser.calibrate(&log_ms.collect::<Vec<f64>>(), &view);
        }
        auto.chooser = Some(chooser);
        let mut measured = 0;
        for frame in 0..16 {
            let ran = record_frame(&mut auto, frame, &camera, (&scene, &hierarchy), 36);
            if ran.turn.strategy == chc && ran.turn.measured {
                measured += 1;
                // What the next frame tells the chooser it hid, as
                // `frame` reads it.
                assert!(ran.counted && ran.fresh, "frame {frame}: {ran:?}");
                assert_eq!(ran.view.frustum_triangles, 36, "frame {frame}");
            }
        }
        assert_eq!(measured, 16, "chc measured in {measured} of 16 frames");
    }

    #[test]
    fn a_walk_s_lists_go_stale_with_time_or_where_the_view_outgrew_them_not_where_it_moved() {
        let streets = view(0.0, DVec3::NEG_Z, 10_000);
        let start = |frame, view, handed_by| {
            walk_start(
                Some(Lists {
                    frame,
                    view,
                    drew: None,
                }),
                10,
                &streets,
                handed_by,
            )
        };
        let walk = |stale, upload, fresh| WalkStart { stale, upload, fresh };
        // An orbit: written two frames ago, far away and turned 45°, over as
        // many triangles. The lists are kept after vfc, and what the walk
        // draws from them counts.
        let orbit = view(500.0, DVec3::new(1.0, 0.0, -1.0).normalize(), 9_000);
        assert_eq!(start(8, orbit, Some(Family::Frustum)), walk(false, false, true));
        // A turn from an empty edge into the streets: replaced even after
        // vfc, and the walk's first frame there does not count.
        let edge = view(0.0, DVec3::X, 20);
        assert_eq!(start(8, edge, Some(Family::Frustum)), walk(true, true, false));
        assert_eq!(start(9, edge, None), walk(true, false, false));
        // Old lists of this view: replaced by what an occlusion culler drew
        // (which counts), kept after vfc (which does not).
        assert_eq!(start(5, streets, Some(Family::Occlusion)), walk(true, true, true));
        assert_eq!(start(5, streets, Some(Family::Frustum)), walk(true, false, false));
        assert_eq!(walk_start(None, 10, &streets, None), walk(true, false, false));
    }

    #[test]
    fn a_cpu_culler_that_ran_the_frame_before_the_last_keeps_its_own_state_after_a_probe() {
        use crate::cull::recording::cubes;
        let (scene, _) = cubes(&[DVec3::ZERO, DVec3::X * 3.0]);
        let mut auto = AutoCulling::new(&scene, &ModeParams::default()).unwrap();
        let at = |auto: &AutoCulling, id| auto.candidates.iter().position(|c| c.id == id).unwrap();
        let (chc, swr) = (at(&auto, ModeId::Chc), at(&auto, ModeId::Swr));
        // Frame 11 is planned; a vfc probe drew frame 10.
        auto.frames = 11;
        auto.last_drawn_by = Some(Family::Frustum);
        let still = view(0.0, DVec3::NEG_Z, 1_000);
        // Running in frame 9, chc and swr keep what they learned: chc what
        // it found visible (not everything in the frustum, which it would
        // draw), swr its occluders and its buffer's rest.
        auto.candidates[chc].last_ran = Some(9);
        auto.candidates[swr].last_ran = Some(9);
        assert_eq!(auto.cpu_handed_to(chc), None);
        assert_eq!(auto.cpu_handed_to(swr), None);
        assert!(!auto.settles(chc, &still));
        // Probed after longer, each is handed the drawn set (chc settles
        // on everything in the frustum).
        auto.candidates[chc].last_ran = Some(8);
        auto.candidates[swr].last_ran = None;
        assert_eq!(auto.cpu_handed_to(chc), Some(Family::Frustum));
        assert_eq!(auto.cpu_handed_to(swr), Some(Family::Frustum));
        assert!(auto.settles(chc, &still));
    }

    #[test]
    fn the_lists_bar_is_what_their_last_fresh_writer_drew_and_lists_stale_by_the_next_frame_take_any_fresh_occlusion_set()
     {
        use Carries::*;
        let here = view(0.0, DVec3::NEG_Z, 10_000);
        let ran = |family, fresh| Ran {
            turn: Turn {
                strategy: 0,
                probe: true,
                measured: true,
                recheck: false,
            },
            view: here,
            family,
            counted: true,
            recount: false,
            fresh,
        };
        let (occlusion, settling, frustum) = (
            ran(Family::Occlusion, true),
            ran(Family::Occlusion, false),
            ran(Family::Frustum, true),
        );
        let written = |frame, view, drew| {
            Some(Lists {
                frame,
                view,
                drew: Some(drew),
            })
        };
        let after = |written, ran: &Ran, carrying, drew| {
            let (take, lists) = lists_after(written, 9, ran, carrying, drew);
            (take, lists.map(|l: Lists| (l.frame, l.drew)))
        };
        // A walk's frame from a visible set of this view: what it drew is
        // the bar. One that started from everything in the frustum (after
        // `vfc`, its lists stale: written three frames before) keeps the
        // bar there was.
        assert_eq!(
            after(written(8, here, 1_000), &occlusion, VisibleOnGpu, 1_200),
            (false, Some((9, Some(1_200))))
        );
        assert_eq!(
            after(written(6, here, 1_000), &settling, VisibleOnGpu, 9_000),
            (false, Some((9, Some(1_000))))
        );
        // A swr probe that drew more than the lists of the frame before:
        // they stay as they are. An omq probe that drew fewer: taken, and
        // the new bar.
        assert_eq!(
            after(written(8, here, 1_000), &occlusion, OccludersOnCpu, 1_300),
            (false, Some((8, Some(1_000))))
        );
        assert_eq!(
            after(written(8, here, 1_000), &occlusion, Nothing, 900),
            (true, Some((9, Some(900))))
        );
        // Lists stale by the next frame, written three frames before it or
        // in a view this one outgrew (four times the triangles): replaced
        // whatever they drew; and where none were written yet.
        let small = view(0.0, DVec3::NEG_Z, 1_000);
        for stale in [written(7, here, 1_000), written(8, small, 1_000), None] {
            assert_eq!(
                after(stale, &occlusion, OccludersOnCpu, 1_300),
                (true, Some((9, Some(1_300))))
            );
            // But not by a set drawn as frustum culling's, nor by chc
            // settling on everything in the frustum it was handed.
            assert_eq!(
                after(stale, &frustum, OccludersOnCpu, 1_300),
                (false, stale.map(|l| (l.frame, l.drew)))
            );
            assert_eq!(
                after(stale, &settling, VisibleOnCpu, 1_300),
                (false, stale.map(|l| (l.frame, l.drew)))
            );
        }
    }

    #[test]
    fn the_walks_lists_take_what_a_cpu_culler_drew_unless_it_drew_the_whole_frustum_or_more_than_they_did() {
        use Carries::*;
        use Family::*;
        // omq decides afresh, chc carries what it found visible, swr its
        // occluders: each drew a visible set of this view.
        for carrying in [Nothing, VisibleOnCpu, OccludersOnCpu] {
            assert!(
                lists_take_drawn(carrying, Occlusion, true, 900, Some(1_000)),
                "{carrying:?}"
            );
            assert!(
                lists_take_drawn(carrying, Occlusion, true, 1_000, Some(1_000)),
                "{carrying:?}"
            );
            // Lists whose triangles no frame counted (warm-up's).
            assert!(lists_take_drawn(carrying, Occlusion, true, 1_000, None), "{carrying:?}");
            // Not a set of more triangles than the lists drew (swr's,
            // coarser than the walks'), nor a frame drawn as vfc's (swr
            // resting), nor vfc's own, nor a frame that settled (chc
            // drawing the whole frustum it was handed).
            assert!(
                !lists_take_drawn(carrying, Occlusion, true, 1_001, Some(1_000)),
                "{carrying:?}"
            );
            assert!(
                !lists_take_drawn(carrying, Frustum, true, 900, Some(1_000)),
                "{carrying:?}"
            );
            assert!(
                !lists_take_drawn(carrying, Occlusion, false, 900, Some(1_000)),
                "{carrying:?}"
            );
        }
        // A walk's frame wrote the lists itself.
        assert!(!lists_take_drawn(VisibleOnGpu, Occlusion, true, 900, Some(1_000)));
    }
}
