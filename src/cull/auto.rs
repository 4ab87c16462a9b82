//! `auto`: frustum culling where occlusion culling does not pay, occlusion
//! culling where it does, decided frame by frame from measured costs.
//!
//! 002 §4.3 notes that culling "does not pay off" where little is hidden
//! and bounds culling time by the render time it saves (Eq. 2); CHC++ and
//! NOHC decide per node from query statistics. Here the decision is per
//! frame and between whole strategies, from what each really cost:
//!
//! - the strategies are `vfc` and the occlusion cullers: `ioc` and `hiz`
//!   where the adapter culls on the GPU (no round trips; which is cheaper
//!   depends on the GPU: a software rasteriser draws boxes cheaply and
//!   builds a depth pyramid slowly), `omq` elsewhere, and `swr` on every
//!   adapter (it culls on the CPU: it pays where the CPU is fast beside the
//!   GPU, or the GPU is busy);
//! - each keeps a moving average of its measured frame times (this mode's
//!   previous frame, credited to the strategy that drew it);
//! - every frame runs the strategy with the lowest average, except that
//!   another one is measured again ("probed") when it has not run for
//!   `probe` × (its average / the chosen one's) frames: the dearer a
//!   strategy has been, the rarer its probes, so a probe costs at most
//!   about 1/`probe` of a frame on average per strategy;
//! - a probe of an occlusion culler runs three frames and keeps the last
//!   (see [`OCCLUSION_PROBE`]); a strategy's first measured frame after it
//!   did not run starts its average afresh; a probed culler is first told
//!   what the last frame drew ([`Culler::seed_visible`]) where the CPU knew
//!   it (`vfc`, `omq`, `swr`; a GPU walk's drawn set is read back only by
//!   the untimed audit, which an engine would pay for), so `swr` starts
//!   with today's occluders instead of those of its last run (or none);
//! - a GPU walk's very first frame has no occluders yet (no last visible
//!   set), so every box in the frustum tests visible against the cleared
//!   depth and it draws what frustum culling draws: its drawing time is
//!   frustum culling's first measurement, which spares a frame of `vfc` on
//!   scenes where it is dear. `omq` culls within its first frame, so beside
//!   it `vfc` is measured by running it.
//!
//! Every strategy is conservative, so `auto` is too.

use serde::Serialize;

use super::gpu_walk::depths::DepthRange;
use super::gpu_walk::hiz::{HizParams, hierarchical_depth_culling};
use super::gpu_walk::ioc::iterative_occlusion_culling;
use super::omq::{OccupancyMapQueries, OmqParams};
use super::swr::{SoftwareOcclusionCulling, SwrParams};
use super::vfc::FrustumCulling;
use crate::cull::culler::{Culler, FrameInput, PreviousFrame, TraversalStats};
use crate::cull::mode::{ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{Frame, GpuAudit, GpuContext, GpuError, GpuSetup};
use crate::object_set::ObjectSet;
use crate::scene::Scene;

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Auto,
    summary: "per frame, vfc or occlusion culling (ioc or hiz, or omq without GPU culling; swr on every adapter), whichever measured cheapest; the others re-measured now and then",
    conservative: true,
    params: &[PROBE],
    needs: Needs::Nothing,
    check: |params| AutoParams::from_params(params).map(drop),
    build: |scene, params| Ok(Box::new(AutoCulling::new(scene, AutoParams::from_params(params)?))),
};

const PROBE: ParamInfo = ParamInfo {
    key: "probe",
    default: "32",
    summary: "frames between re-measurements of a dearer strategy, times how much dearer it was",
};

/// Weight of the newest frame in a strategy's average.
const SMOOTHING: f64 = 0.3;

/// Frames a probe of an occlusion culler runs; only the last is measured.
/// After a stretch without it, its occluders (last visible set) are stale:
/// its first frame tests against them and marks too much, its second draws
/// that too-large set, and only the third costs what it costs in steady
/// state.
const OCCLUSION_PROBE: u32 = 3;

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AutoParams {
    /// Base period of probes, in frames.
    pub probe: u32,
}

impl AutoParams {
    pub fn from_params(params: &ModeParams) -> Result<AutoParams, ModeError> {
        let probe: u32 = params.get(ModeId::Auto, &PROBE)?;
        if probe == 0 {
            return Err(ModeError::bad(ModeId::Auto, &PROBE, "must be at least 1 frame".into()));
        }
        Ok(AutoParams { probe })
    }
}

/// What a frame runs: frustum culling, or one of the occlusion cullers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Strategy {
    Frustum,
    Occlusion(usize),
}

impl Strategy {
    /// Where its [`Record`] is.
    fn index(self) -> usize {
        match self {
            Strategy::Frustum => 0,
            Strategy::Occlusion(k) => k + 1,
        }
    }
}

/// What one strategy has cost.
#[derive(Clone, Copy, Debug, Default)]
struct Record {
    /// Moving average of its measured frame times.
    average_ms: Option<f64>,
    /// The frame (this mode's count) it last ran.
    last_run: u64,
}

/// The plan for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Turn {
    strategy: Strategy,
    /// Whether its time is measured (not a probe's warm-up frame).
    measured: bool,
    /// Whether it starts a new average (the first measured frame after the
    /// strategy did not run: the old average describes another view).
    fresh: bool,
    /// Whether its drawing time measures frustum culling: a GPU walk's
    /// first frame, which draws everything in the frustum.
    draws_frustum: bool,
}

pub struct AutoCulling {
    params: AutoParams,
    frustum: FrustumCulling,
    /// `omq` and `swr` until `prepare` finds an adapter that culls on the
    /// GPU, then `ioc`, `hiz` and `swr`.
    occlusion: Vec<Box<dyn Culler>>,
    /// One per strategy, in [`Strategy::index`] order.
    records: Vec<Record>,
    previous: Option<Turn>,
    /// Frames run so far (the path's frame numbers repeat after warm-up).
    frames_run: u64,
    /// The occlusion culler being probed, and the frames left in its probe.
    probing: Option<(usize, u32)>,
    /// Whether the occlusion cullers cull on the GPU; set by `prepare`,
    /// when the adapter is known.
    gpu_culling: bool,
    /// The objects drawn in the last frame, when the CPU decided them (not
    /// a GPU walk); `None` also where frames run without their audit.
    last_drawn: Option<Vec<u32>>,
}

impl AutoCulling {
    pub fn new(scene: &Scene, params: AutoParams) -> Self {
        let occlusion = occlusion_cullers(false);
        AutoCulling {
            params,
            frustum: FrustumCulling::new(scene),
            records: vec![Record::default(); occlusion.len() + 1],
            occlusion,
            previous: None,
            frames_run: 0,
            probing: None,
            gpu_culling: false,
            last_drawn: None,
        }
    }

    fn record(&mut self, s: Strategy) -> &mut Record {
        &mut self.records[s.index()]
    }

    /// Every strategy, in [`Strategy::index`] order.
    fn strategies(&self) -> Vec<Strategy> {
        let occlusion = (0..self.occlusion.len()).map(Strategy::Occlusion);
        std::iter::once(Strategy::Frustum).chain(occlusion).collect()
    }

    /// Credits the previous frame's time to the strategy that drew it, and
    /// its drawing time to frustum culling when it drew what that draws.
    fn learn(&mut self, turn: Turn, previous: PreviousFrame) {
        if turn.draws_frustum {
            let frame = self.frames_run;
            let r = self.record(Strategy::Frustum);
            r.average_ms = Some(previous.render_ms);
            r.last_run = frame;
        }
        if !turn.measured {
            return;
        }
        let r = self.record(turn.strategy);
        r.average_ms = Some(match r.average_ms {
            Some(a) if !turn.fresh => a + SMOOTHING * (previous.frame_ms - a),
            _ => previous.frame_ms,
        });
    }

    /// This frame's plan, from the records: measure every strategy first
    /// (the occlusion cullers in turn, then frustum culling), then run the
    /// cheapest and probe another when it is due (the most overdue).
    fn plan(&mut self) -> Turn {
        let turn = |strategy, measured, fresh| Turn {
            strategy,
            measured,
            fresh,
            draws_frustum: false,
        };
        if let Some((k, left)) = self.probing {
            self.probing = (left > 1).then_some((k, left - 1));
            return turn(Strategy::Occlusion(k), left == 1, true);
        }
        let strategies = self.strategies();
        let unmeasured: Vec<Strategy> = strategies
            .iter()
            .copied()
            .filter(|s| self.records[s.index()].average_ms.is_none())
            .collect();
        // The occlusion cullers first, in order: a GPU walk's first frame
        // measures frustum culling too.
        let first_occlusion = unmeasured.iter().find_map(|&s| match s {
            Strategy::Occlusion(k) => Some(k),
            Strategy::Frustum => None,
        });
        if let Some(k) = first_occlusion {
            return self.start_probe(k);
        }
        if unmeasured.contains(&Strategy::Frustum) {
            return turn(Strategy::Frustum, true, true);
        }
        let average = |s: Strategy| self.records[s.index()].average_ms.unwrap_or(f64::INFINITY);
        let chosen = strategies
            .iter()
            .copied()
            .min_by(|&a, &b| average(a).total_cmp(&average(b)))
            .expect("frustum culling is always a strategy");
        // How far past its probe each other strategy is.
        let overdue = |s: Strategy| {
            let since = (self.frames_run - self.records[s.index()].last_run) as f64;
            let period = f64::from(self.params.probe) * average(s) / average(chosen).max(f64::MIN_POSITIVE);
            since / period
        };
        let due = strategies
            .iter()
            .copied()
            .filter(|&s| s != chosen && overdue(s) >= 1.0)
            .max_by(|&a, &b| overdue(a).total_cmp(&overdue(b)));
        match due {
            Some(Strategy::Occlusion(k)) => self.start_probe(k),
            Some(Strategy::Frustum) => turn(Strategy::Frustum, true, true),
            None => {
                let continuing = self.record(chosen).last_run + 1 == self.frames_run;
                turn(chosen, true, !continuing)
            }
        }
    }

    /// Learns from the previous frame (`None` in the first frame) and plans
    /// this one.
    fn next_turn(&mut self, previous: Option<PreviousFrame>) -> Turn {
        if let (Some(turn), Some(frame)) = (self.previous, previous) {
            self.learn(turn, frame);
        }
        self.frames_run += 1;
        let turn = self.plan();
        self.previous = Some(turn);
        let frames_run = self.frames_run;
        self.record(turn.strategy).last_run = frames_run;
        turn
    }

    /// Remembers the objects the last frame drew, or that they are unknown.
    fn remember_drawn(&mut self, drawn: Option<&ObjectSet>) {
        match (drawn, &mut self.last_drawn) {
            (None, last) => *last = None,
            (Some(drawn), Some(last)) => {
                last.clear();
                last.extend(drawn.iter());
            }
            (Some(drawn), last) => *last = Some(drawn.iter().collect()),
        }
    }

    /// The first frame of a probe of occlusion culler `k`.
    fn start_probe(&mut self, k: usize) -> Turn {
        self.probing = Some((k, OCCLUSION_PROBE - 1));
        if let Some(drawn) = &self.last_drawn {
            self.occlusion[k].seed_visible(drawn);
        }
        Turn {
            strategy: Strategy::Occlusion(k),
            measured: false,
            fresh: true,
            draws_frustum: self.gpu_culling && self.frames_run == 1,
        }
    }
}

impl Culler for AutoCulling {
    fn name(&self) -> &str {
        "auto"
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::json!(self.params)
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        self.gpu_culling = setup.gpu.gpu_driven;
        self.occlusion = occlusion_cullers(self.gpu_culling);
        self.records = vec![Record::default(); self.occlusion.len() + 1];
        self.occlusion.iter_mut().try_for_each(|c| c.prepare(setup))
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let turn = self.next_turn(input.previous);
        match turn.strategy {
            Strategy::Frustum => self.frustum.frame(ctx, input),
            Strategy::Occlusion(k) => self.occlusion[k].frame(ctx, input),
        }
    }

    /// Only the culler that ran this frame has a walk to audit. Where none
    /// had (the CPU decided the frame), `drawn` is what it drew, remembered
    /// for the next probe.
    fn audit(&mut self, gpu: &GpuContext, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        let audit = self.occlusion.iter_mut().find_map(|c| c.audit(gpu, drawn));
        self.remember_drawn(audit.is_none().then_some(drawn));
        audit
    }
}

/// `ioc` and `hiz` where the adapter culls on the GPU, `omq` elsewhere,
/// then `swr`, each with its default parameters.
fn occlusion_cullers(gpu_culling: bool) -> Vec<Box<dyn Culler>> {
    let defaults = ModeParams::default();
    let mut cullers: Vec<Box<dyn Culler>> = if gpu_culling {
        vec![
            Box::new(iterative_occlusion_culling(
                DepthRange::from_params(ModeId::Ioc, &defaults).expect("ioc's defaults parse"),
            )),
            Box::new(hierarchical_depth_culling(
                HizParams::from_params(&defaults).expect("hiz's defaults parse"),
            )),
        ]
    } else {
        vec![Box::new(OccupancyMapQueries::new(
            OmqParams::from_params(&defaults).expect("omq's defaults parse"),
        ))]
    };
    cullers.push(Box::new(SoftwareOcclusionCulling::new(
        SwrParams::from_params(&defaults).expect("swr's defaults parse"),
    )));
    cullers
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{LoadOptions, SceneSpec, load};
    use Strategy::Frustum;

    /// The first occlusion culler without GPU culling, omq; the tests that
    /// use it run one occlusion culler.
    const OMQ: Strategy = Strategy::Occlusion(0);

    /// An occlusion culler that draws nothing and keeps what it is told to
    /// start from.
    #[derive(Default)]
    struct Stand(std::rc::Rc<std::cell::RefCell<Vec<Vec<u32>>>>);

    impl Culler for Stand {
        fn name(&self) -> &str {
            "stand-in"
        }
        fn frame(&mut self, _: &mut dyn Frame, _: &FrameInput) -> TraversalStats {
            TraversalStats::default()
        }
        fn seed_visible(&mut self, visible: &[u32]) {
            self.0.borrow_mut().push(visible.to_vec());
        }
    }

    /// The strategies `auto` runs for `frames` frames beside `omq` (no GPU
    /// culling) when each costs what `cost(frame, strategy)` says.
    fn run(frames: u64, cost: impl Fn(u64, Strategy) -> f64) -> Vec<Strategy> {
        run_with(frames, false, |k, s| {
            let ms = cost(k, s);
            PreviousFrame {
                frame_ms: ms,
                render_ms: ms,
            }
        })
    }

    /// The same with the occlusion culler's frames as `frame` measures them.
    fn run_with(frames: u64, gpu_culling: bool, frame: impl Fn(u64, Strategy) -> PreviousFrame) -> Vec<Strategy> {
        run_cullers(1, frames, gpu_culling, frame)
    }

    /// The same beside `cullers` occlusion cullers.
    fn run_cullers(
        cullers: usize,
        frames: u64,
        gpu_culling: bool,
        frame: impl Fn(u64, Strategy) -> PreviousFrame,
    ) -> Vec<Strategy> {
        let scene = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
        let mut auto = AutoCulling::new(&scene, AutoParams { probe: 8 });
        auto.gpu_culling = gpu_culling;
        auto.occlusion = (0..cullers)
            .map(|_| Box::new(Stand::default()) as Box<dyn Culler>)
            .collect();
        auto.records = vec![Record::default(); cullers + 1];
        let mut previous = None;
        (0..frames)
            .map(|k| {
                let turn = auto.next_turn(previous);
                previous = Some(frame(k, turn.strategy));
                turn.strategy
            })
            .collect()
    }

    #[test]
    fn the_cheaper_strategy_runs_and_the_dearer_is_probed_the_rarer_the_dearer() {
        // Frustum culling at 10 ms, occlusion culling at 30: after measuring
        // both (three occlusion frames, one frustum), frustum culling runs,
        // and occlusion culling is probed 8 × 3 frames after it last ran,
        // three frames at a time.
        let s = run(100, |_, s| if s == Frustum { 10.0 } else { 30.0 });
        assert_eq!(s[..4], [OMQ, OMQ, OMQ, Frustum]);
        let probes: Vec<usize> = (1..s.len()).filter(|&k| s[k] == OMQ && s[k - 1] == Frustum).collect();
        assert_eq!(probes, [26, 52, 78], "{s:?}");
        assert_eq!(s.iter().filter(|&&x| x == OMQ).count(), 3 * 4);
        // Occlusion culling 4× cheaper: frustum culling is re-measured one
        // frame every 8 × 4 frames.
        let s = run(100, |_, s| if s == Frustum { 40.0 } else { 10.0 });
        let frustum: Vec<usize> = (4..s.len()).filter(|&k| s[k] == Frustum).collect();
        assert_eq!(frustum, [35, 67, 99], "{s:?}");
    }

    #[test]
    fn ioc_first_frame_measures_frustum_culling() {
        // Frame 0 of ioc draws everything in the frustum (40 ms of drawing,
        // 45 with its tests); its later frames cost 10 ms; frustum culling
        // would cost 40.
        let frame = |k, s| {
            let ms = match (s, k) {
                (Frustum, _) => 40.0,
                (Strategy::Occlusion(_), 0) => 45.0,
                (Strategy::Occlusion(_), _) => 10.0,
            };
            let render_ms = if k == 0 { 40.0 } else { ms };
            PreviousFrame {
                frame_ms: ms,
                render_ms,
            }
        };
        // No frame of frustum culling is spent measuring it: its first run
        // is the probe 8 × 4 frames after frame 0.
        let s = run_with(100, true, frame);
        let frustum: Vec<usize> = (0..s.len()).filter(|&k| s[k] == Frustum).collect();
        assert_eq!(frustum, [32, 64, 96], "{s:?}");
        // Beside omq the first frame says nothing of frustum culling, which
        // is run once to be measured.
        let s = run_with(100, false, frame);
        assert_eq!(s[..5], [OMQ, OMQ, OMQ, Frustum, OMQ]);
        // A frustum estimate below the occlusion culler's cost is checked by
        // running frustum culling at once.
        let s = run_with(10, true, |k, s| PreviousFrame {
            render_ms: 5.0,
            ..frame(k, s)
        });
        assert_eq!(s[..4], [OMQ, OMQ, OMQ, Frustum]);
    }

    #[test]
    fn the_cheapest_of_several_occlusion_cullers_runs_and_the_others_are_probed() {
        const IOC: Strategy = Strategy::Occlusion(0);
        const HIZ: Strategy = Strategy::Occlusion(1);
        // Frustum culling costs 40 ms, ioc 10 and hiz 20 until frame 60,
        // then 5; ioc's first frame draws what frustum culling draws.
        let s = run_cullers(2, 160, true, |k, s| {
            let ms = match s {
                Frustum => 40.0,
                IOC => 10.0,
                _ if k < 60 => 20.0,
                _ => 5.0,
            };
            PreviousFrame {
                frame_ms: ms,
                render_ms: if k == 0 { 40.0 } else { ms },
            }
        });
        assert_eq!(s[..6], [IOC, IOC, IOC, HIZ, HIZ, HIZ], "each measured first: {s:?}");
        let runs = |range: std::ops::Range<usize>, x: Strategy| s[range].iter().filter(|&&y| y == x).count();
        // Until frame 60 ioc runs, hiz is probed (three frames) about every
        // 8 × 2 frames and frustum culling about every 8 × 4.
        assert!(runs(6..60, IOC) > 40, "{s:?}");
        assert!((2..=3).contains(&(runs(6..60, HIZ) / 3)), "{s:?}");
        assert!((1..=2).contains(&runs(6..60, Frustum)), "{s:?}");
        // hiz's next probe finds it cheaper, and it runs from then on, ioc
        // being probed about every 8 × 2 frames.
        assert!(runs(100..160, HIZ) > 40, "{s:?}");
        assert!(runs(100..160, IOC) <= 4 * 3, "{s:?}");
    }

    #[test]
    fn a_change_in_costs_is_followed_at_the_next_probe() {
        // Occlusion culling pays until frame 40, then costs 5× more.
        let s = run(120, |k, s| match (s, k < 40) {
            (Frustum, _) => 20.0,
            (Strategy::Occlusion(_), true) => 10.0,
            (Strategy::Occlusion(_), false) => 100.0,
        });
        assert!(s[4..40].iter().filter(|&&x| x == OMQ).count() > 30, "{s:?}");
        assert!(
            s[41..55].iter().all(|&x| x == Frustum),
            "frustum culling from frame 41: {s:?}"
        );
        let probes = s[41..].iter().filter(|&&x| x == OMQ).count();
        assert!(
            probes <= 6,
            "then occlusion culling only in probes, every 8 × 5 frames: {s:?}"
        );
    }

    #[test]
    fn a_probed_culler_starts_from_what_the_cpu_last_drew_and_never_from_a_gpu_walks_read_back() {
        let scene = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
        let mut auto = AutoCulling::new(&scene, AutoParams { probe: 8 });
        let told = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
        auto.occlusion = vec![Box::new(Stand(told.clone()))];
        auto.records = vec![Record::default(); 2];
        let mut drawn = ObjectSet::new(8);
        drawn.insert(3);
        drawn.insert(5);
        // Known to the CPU: handed over at the probe's start.
        auto.remember_drawn(Some(&drawn));
        auto.start_probe(0);
        // A GPU walk's read-back: not handed over; the culler keeps its own.
        auto.remember_drawn(None);
        auto.start_probe(0);
        assert_eq!(*told.borrow(), [vec![3, 5]]);
    }
}
