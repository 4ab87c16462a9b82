//! `auto`: frustum culling where occlusion culling does not pay, occlusion
//! culling where it does, decided frame by frame from measured costs.
//!
//! 002 §4.3 notes that culling "does not pay off" where little is hidden
//! and bounds culling time by the render time it saves (Eq. 2); CHC++ and
//! NOHC decide per node from query statistics. Here the decision is per
//! frame and between whole strategies, from what each really cost:
//!
//! - the two strategies are `vfc` and an occlusion culler: `ioc` where the
//!   adapter culls on the GPU (no round trips), `omq` elsewhere;
//! - each keeps a moving average of its measured frame times (this mode's
//!   previous frame, credited to the strategy that drew it);
//! - every frame runs the strategy with the lower average, except that the
//!   other one is measured again ("probed") when it has not run for
//!   `probe` × (its average / the chosen one's) frames: the dearer a
//!   strategy has been, the rarer its probes, so a probe costs at most
//!   about 1/`probe` of a frame on average;
//! - a probe of the occlusion culler runs three frames and keeps the last
//!   (see [`OCCLUSION_PROBE`]); a strategy's first measured frame after it
//!   did not run starts its average afresh;
//! - `ioc`'s very first frame has no occluders yet (no last visible set), so
//!   every box in the frustum tests visible against the cleared depth and
//!   it draws what frustum culling draws: its drawing time is frustum
//!   culling's first measurement, which spares a frame of `vfc` on scenes
//!   where it is dear. `omq` culls within its first frame, so beside it
//!   `vfc` is measured by running it.
//!
//! Both strategies are conservative, so `auto` is too.

use serde::Serialize;

use super::gpu_walk::ioc::{DepthRange, iterative_occlusion_culling};
use super::omq::{OccupancyMapQueries, OmqParams};
use super::vfc::FrustumCulling;
use crate::cull::culler::{Culler, FrameInput, PreviousFrame, TraversalStats};
use crate::cull::mode::{ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{Frame, GpuAudit, GpuContext, GpuSetup};
use crate::object_set::ObjectSet;
use crate::scene::Scene;

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Auto,
    summary: "per frame, vfc or occlusion culling (ioc, or omq without GPU culling), whichever measured cheaper; the other re-measured now and then",
    conservative: true,
    params: &[PROBE],
    needs: Needs::Nothing,
    check: |params| AutoParams::from_params(params).map(drop),
    build: |scene, params| Ok(Box::new(AutoCulling::new(scene, AutoParams::from_params(params)?))),
};

const PROBE: ParamInfo = ParamInfo {
    key: "probe",
    default: "32",
    summary: "frames between re-measurements of the dearer strategy, times how much dearer it was",
};

/// Weight of the newest frame in a strategy's average.
const SMOOTHING: f64 = 0.3;

/// Frames a probe of the occlusion culler runs; only the last is measured.
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Strategy {
    Frustum,
    Occlusion,
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
    /// Whether its drawing time measures frustum culling: the GPU-driven
    /// occlusion culler's first frame, which draws everything in the
    /// frustum.
    draws_frustum: bool,
}

pub struct AutoCulling {
    params: AutoParams,
    frustum: FrustumCulling,
    /// `omq` until `prepare` finds an adapter that culls on the GPU, then
    /// `ioc`.
    occlusion: Box<dyn Culler>,
    records: [Record; 2],
    previous: Option<Turn>,
    /// Frames run so far (the path's frame numbers repeat after warm-up).
    frames_run: u64,
    /// Frames left in a probe of the occlusion culler.
    probing: u32,
    /// Whether the occlusion culler culls on the GPU (`ioc`); set by
    /// `prepare`, when the adapter is known.
    gpu_culling: bool,
}

impl AutoCulling {
    pub fn new(scene: &Scene, params: AutoParams) -> Self {
        AutoCulling {
            params,
            frustum: FrustumCulling::new(scene),
            occlusion: occlusion_culler(false),
            records: [Record::default(); 2],
            previous: None,
            frames_run: 0,
            probing: 0,
            gpu_culling: false,
        }
    }

    fn record(&mut self, s: Strategy) -> &mut Record {
        &mut self.records[s as usize]
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

    /// This frame's plan, from the records: measure both strategies first
    /// (occlusion, then frustum), then run the cheaper one and probe the
    /// other when it is due.
    fn plan(&mut self) -> Turn {
        use Strategy::{Frustum, Occlusion};
        let turn = |strategy, measured, fresh| Turn {
            strategy,
            measured,
            fresh,
            draws_frustum: false,
        };
        if self.probing > 0 {
            self.probing -= 1;
            return turn(Occlusion, self.probing == 0, true);
        }
        let [f, o] = self.records.map(|r| r.average_ms);
        let (chosen, other) = match (f, o) {
            (_, None) => return self.start_probe(),
            (None, _) => return turn(Frustum, true, true),
            (Some(f), Some(o)) if f <= o => ((Frustum, f), (Occlusion, o)),
            (Some(f), Some(o)) => ((Occlusion, o), (Frustum, f)),
        };
        let since = self.frames_run - self.record(other.0).last_run;
        let period = f64::from(self.params.probe) * other.1 / chosen.1.max(f64::MIN_POSITIVE);
        match other.0 {
            Occlusion if since as f64 >= period => self.start_probe(),
            Frustum if since as f64 >= period => turn(Frustum, true, true),
            _ => {
                let continuing = self.record(chosen.0).last_run + 1 == self.frames_run;
                turn(chosen.0, true, !continuing)
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

    fn start_probe(&mut self) -> Turn {
        self.probing = OCCLUSION_PROBE - 1;
        Turn {
            strategy: Strategy::Occlusion,
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

    fn prepare(&mut self, setup: &GpuSetup) {
        self.gpu_culling = setup.gpu.gpu_driven;
        self.occlusion = occlusion_culler(self.gpu_culling);
        self.occlusion.prepare(setup);
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let turn = self.next_turn(input.previous);
        match turn.strategy {
            Strategy::Frustum => self.frustum.frame(ctx, input),
            Strategy::Occlusion => self.occlusion.frame(ctx, input),
        }
    }

    fn audit(&mut self, gpu: &GpuContext, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        self.occlusion.audit(gpu, drawn)
    }
}

/// `ioc` where the adapter culls on the GPU, `omq` elsewhere, each with
/// its default parameters.
fn occlusion_culler(gpu_culling: bool) -> Box<dyn Culler> {
    let defaults = ModeParams::default();
    if gpu_culling {
        Box::new(iterative_occlusion_culling(
            DepthRange::from_params(ModeId::Ioc, &defaults).expect("ioc's defaults parse"),
        ))
    } else {
        Box::new(OccupancyMapQueries::new(
            OmqParams::from_params(&defaults).expect("omq's defaults parse"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{LoadOptions, SceneSpec, load};
    use Strategy::{Frustum, Occlusion};

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
        let scene = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
        let mut auto = AutoCulling::new(&scene, AutoParams { probe: 8 });
        auto.gpu_culling = gpu_culling;
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
        assert_eq!(s[..4], [Occlusion, Occlusion, Occlusion, Frustum]);
        let probes: Vec<usize> = (1..s.len())
            .filter(|&k| s[k] == Occlusion && s[k - 1] == Frustum)
            .collect();
        assert_eq!(probes, [26, 52, 78], "{s:?}");
        assert_eq!(s.iter().filter(|&&x| x == Occlusion).count(), 3 * 4);
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
                (Occlusion, 0) => 45.0,
                (Occlusion, _) => 10.0,
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
        assert_eq!(s[..5], [Occlusion, Occlusion, Occlusion, Frustum, Occlusion]);
        // A frustum estimate below the occlusion culler's cost is checked by
        // running frustum culling at once.
        let s = run_with(10, true, |k, s| PreviousFrame {
            render_ms: 5.0,
            ..frame(k, s)
        });
        assert_eq!(s[..4], [Occlusion, Occlusion, Occlusion, Frustum]);
    }

    #[test]
    fn a_change_in_costs_is_followed_at_the_next_probe() {
        // Occlusion culling pays until frame 40, then costs 5× more.
        let s = run(120, |k, s| match (s, k < 40) {
            (Frustum, _) => 20.0,
            (Occlusion, true) => 10.0,
            (Occlusion, false) => 100.0,
        });
        assert!(s[4..40].iter().filter(|&&x| x == Occlusion).count() > 30, "{s:?}");
        assert!(
            s[41..55].iter().all(|&x| x == Frustum),
            "frustum culling from frame 41: {s:?}"
        );
        let probes = s[41..].iter().filter(|&&x| x == Occlusion).count();
        assert!(
            probes <= 6,
            "then occlusion culling only in probes, every 8 × 5 frames: {s:?}"
        );
    }
}
