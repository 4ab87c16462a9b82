//! `occlu stress`: numerically hard cameras and scenes, run through every
//! mode with each frame checked against the DR reference.
//!
//! A case passes for a conservative mode when no frame has a wrong pixel or
//! a missed object; modes that may trade error for speed (ac) are reported
//! but not judged. Cases with a `baseline` (the same shapes and cameras,
//! translated or scaled) must also render the baseline's image: their
//! reference depth is compared pixel by pixel, which shows that precision
//! does not depend on where in the world a scene lies.

mod case;
pub mod cases;

use std::cell::Cell;
use std::ops::ControlFlow;

use serde::Serialize;

use crate::camera::Camera;
use crate::cull::{Culler, ModeError, ModeId, ModeInfo, ModeParams, unrunnable};
use crate::gpu::{AdapterReport, GpuContext, GpuError, RenderTargets, Resolution};
use crate::hierarchy::{Hierarchy, HierarchyParams};
use crate::measure::{FrameStats, MissedObject};
use crate::report::SkippedMode;
use crate::session::{RunOptions, Session};
use crate::world::World;

pub use case::{Baseline, DepthTolerance, StressCase};

/// How one case's reference depth differs from its baseline's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct DepthDifference {
    /// Pixels beyond the tolerance, counting those covered on one side only.
    pub pixels_beyond: u64,
    /// Pixels covered on one side only (background on the other).
    pub coverage_changes: u64,
    /// Largest |a − b| and |a − b| / max(a, b) over pixels covered on both sides.
    pub max_absolute: f64,
    pub max_relative: f64,
}

impl DepthDifference {
    /// Compares two depth images of the same size.
    pub fn of(depth: &[f32], baseline: &[f32], tolerance: &DepthTolerance) -> DepthDifference {
        let mut d = DepthDifference::default();
        for (&a, &b) in depth.iter().zip(baseline) {
            let (a, b) = (f64::from(a), f64::from(b));
            if (a == 0.0) != (b == 0.0) {
                d.coverage_changes += 1;
                d.pixels_beyond += 1;
            } else if a != 0.0 {
                d.max_absolute = d.max_absolute.max((a - b).abs());
                d.max_relative = d.max_relative.max((a - b).abs() / a.max(b));
                d.pixels_beyond += u64::from(!tolerance.allows(a, b));
            }
        }
        d
    }

    fn merge(self, other: DepthDifference) -> DepthDifference {
        DepthDifference {
            pixels_beyond: self.pixels_beyond + other.pixels_beyond,
            coverage_changes: self.coverage_changes + other.coverage_changes,
            max_absolute: self.max_absolute.max(other.max_absolute),
            max_relative: self.max_relative.max(other.max_relative),
        }
    }
}

/// One mode over all frames of one case.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StressRow {
    pub case: String,
    pub mode: String,
    pub conservative: bool,
    pub frames: u32,
    pub error_pixels: u64,
    pub missed_objects: u64,
    /// Largest |depth − reference depth| over the case's frames.
    pub max_depth_error: f64,
    /// The size the case ran at where it has its own
    /// ([`StressCase::resolution`]); otherwise the report's.
    pub resolution: Option<Resolution>,
}

impl StressRow {
    /// Tallies a mode's frame rows.
    pub fn tally(case: &str, mode: &str, conservative: bool, rows: &[FrameStats]) -> StressRow {
        let mine = rows.iter().filter(|r| r.mode == mode);
        StressRow {
            case: case.to_string(),
            mode: mode.to_string(),
            conservative,
            frames: mine.clone().count() as u32,
            error_pixels: mine.clone().filter_map(|r| r.error_pixels).sum(),
            missed_objects: mine.clone().filter_map(|r| r.missed_objects).sum(),
            max_depth_error: mine.filter_map(|r| r.max_depth_error).fold(0.0, f64::max),
            resolution: None,
        }
    }

    /// `None` for modes that make no zero-error promise.
    pub fn passed(&self) -> Option<bool> {
        self.conservative
            .then_some(self.error_pixels == 0 && self.missed_objects == 0)
    }
}

/// A transformed case's reference depth against its baseline's, over all
/// frames.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InvarianceCheck {
    pub case: String,
    pub baseline: String,
    pub frames: u32,
    pub tolerance: DepthTolerance,
    pub difference: DepthDifference,
}

impl InvarianceCheck {
    pub fn passed(&self) -> bool {
        self.difference.pixels_beyond == 0
    }
}

/// Everything `occlu stress` found.
#[derive(Clone, Debug, Serialize)]
pub struct StressReport {
    pub adapter: AdapterReport,
    pub resolution: Resolution,
    /// The parameters the user set over those the modes ran with
    /// (`--param`, MODE.KEY=VALUE).
    pub params: Vec<String>,
    pub rows: Vec<StressRow>,
    pub invariance: Vec<InvarianceCheck>,
    pub skipped: Vec<SkippedMode>,
    /// Cases whose own target size the adapter cannot hold.
    pub skipped_cases: Vec<SkippedCase>,
}

/// A case not run, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SkippedCase {
    pub case: String,
    pub reason: String,
}

impl StressReport {
    /// (passed, failed) over conservative rows and invariance checks.
    pub fn verdicts(&self) -> (usize, usize) {
        let all: Vec<bool> = self
            .rows
            .iter()
            .filter_map(StressRow::passed)
            .chain(self.invariance.iter().map(InvarianceCheck::passed))
            .collect();
        let passed = all.iter().filter(|&&p| p).count();
        (passed, all.len() - passed)
    }
}

/// What a stress run reports as it goes.
pub enum StressEvent<'a> {
    Skipped { mode: &'a str, reason: &'a str },
    CaseSkipped { case: &'a str, reason: &'a str },
    Case { case: &'a StressCase },
    Frame { done: u32, total: u32 },
}

#[derive(Debug, thiserror::Error)]
pub enum StressError {
    #[error(transparent)]
    Mode(#[from] ModeError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("unknown stress case '{name}' (cases: {known})")]
    UnknownCase { name: String, known: String },
    /// Every mode asked for is one the adapter cannot run: the run would
    /// check nothing.
    #[error("no mode of --modes runs on {adapter} ({skipped}): nothing would be checked")]
    NoModeRuns { adapter: String, skipped: String },
    /// The caller asked the run to stop (Ctrl-C).
    #[error("interrupted: no results written")]
    Interrupted,
}

impl StressError {
    /// Whether the user's input was at fault (as opposed to the GPU).
    pub fn is_input_error(&self) -> bool {
        match self {
            StressError::Gpu(e) => e.is_input_error(),
            StressError::Interrupted => false,
            StressError::Mode(_) | StressError::UnknownCase { .. } | StressError::NoModeRuns { .. } => true,
        }
    }
}

/// The cases named in `names` (all of them when empty), in run order, with
/// the baselines they need.
pub fn select(names: &[String]) -> Result<Vec<StressCase>, StressError> {
    let all = cases::all();
    if names.is_empty() {
        return Ok(all);
    }
    for name in names {
        if !all.iter().any(|c| &c.name == name) {
            let known: Vec<&str> = all.iter().map(|c| c.name.as_str()).collect();
            return Err(StressError::UnknownCase {
                name: name.clone(),
                known: known.join(", "),
            });
        }
    }
    let wanted = |c: &StressCase| names.contains(&c.name);
    let needed: Vec<String> = all
        .iter()
        .filter(|c| wanted(c))
        .filter_map(|c| c.baseline.as_ref().map(|b| b.case.clone()))
        .collect();
    Ok(all
        .into_iter()
        .filter(|c| wanted(c) || needed.contains(&c.name))
        .collect())
}

/// Runs `modes` over `cases` (baselines before the cases that name them),
/// with the parameters that exercise every frame and, over them, those
/// `given`.
/// When `events` breaks, the run stops at the end of the case it is in with
/// [`StressError::Interrupted`].
pub fn run(
    gpu: &GpuContext,
    cases: &[StressCase],
    modes: &[ModeId],
    given: &ModeParams,
    resolution: Resolution,
    events: &mut dyn FnMut(StressEvent) -> ControlFlow<()>,
) -> Result<StressReport, StressError> {
    let stop = Cell::new(false);
    let mut events = |event: StressEvent<'_>| {
        if events(event).is_break() {
            stop.set(true);
        }
    };
    let unsupported = |mode: ModeId| mode.info().unsupported_on(gpu);
    let named: Vec<(ModeId, &ModeParams)> = modes.iter().map(|&mode| (mode, given)).collect();
    let skipped: Vec<SkippedMode> = unrunnable(&named, unsupported)
        .into_iter()
        .map(SkippedMode::from)
        .collect();
    for s in &skipped {
        events(StressEvent::Skipped {
            mode: &s.mode,
            reason: &s.reason,
        });
    }
    let modes: Vec<&'static ModeInfo> = modes
        .iter()
        .filter(|&&mode| unsupported(mode).is_none())
        .map(|&mode| mode.info())
        .collect();
    if modes.is_empty() {
        let skipped = skipped.iter().map(|s| format!("{}: {}", s.mode, s.reason));
        return Err(StressError::NoModeRuns {
            adapter: gpu.adapter.to_string(),
            skipped: skipped.collect::<Vec<_>>().join("; "),
        });
    }
    // The run's own size must fit the adapter where a case is drawn at it
    // (every case but those at a size of their own).
    if cases.iter().any(|c| c.resolution.is_none()) {
        RenderTargets::check(gpu, resolution)?;
    }
    // Every frame exercised, but for what the user set.
    let params = ModeParams::exercising_every_frame().overridden_by(given);
    let total: u32 = cases.iter().map(|c| c.cameras.len() as u32).sum();
    let mut done = 0;
    let mut rows = Vec::new();
    let mut invariance = Vec::new();
    let mut baseline_depths: Vec<(String, Vec<Vec<f32>>)> = Vec::new();
    let is_baseline = |c: &StressCase| {
        cases
            .iter()
            .any(|d| d.baseline.as_ref().is_some_and(|b| b.case == c.name))
    };
    let mut skipped_cases = Vec::new();
    for case in cases {
        events(StressEvent::Case { case });
        if stop.get() {
            return Err(StressError::Interrupted);
        }
        let size = case.resolution.unwrap_or(resolution);
        // A case at a size of its own (8191×3) may exceed a small adapter
        // (the run's own size was checked above): that case is skipped,
        // the run goes on.
        if let Err(e) = RenderTargets::check(gpu, size) {
            if e.is_input_error() {
                let reason = format!("{size}: {e}");
                events(StressEvent::CaseSkipped {
                    case: &case.name,
                    reason: &reason,
                });
                skipped_cases.push(SkippedCase {
                    case: case.name.clone(),
                    reason,
                });
                continue;
            }
            return Err(e.into());
        }
        let mut cullers = modes
            .iter()
            .map(|m| m.id.create(&case.scene, &params))
            .collect::<Result<Vec<_>, _>>()?;
        let keep_depth = case.baseline.is_some() || is_baseline(case);
        let hierarchy = HierarchyParams::default();
        let outcome = run_case(gpu, case, &hierarchy, &mut cullers, size, keep_depth, &mut |_| {
            done += 1;
            events(StressEvent::Frame { done, total });
        })?;
        rows.extend(modes.iter().map(|m| StressRow {
            resolution: case.resolution,
            ..StressRow::tally(&case.name, m.id.name(), m.conservative, &outcome.rows)
        }));
        if let Some(baseline) = &case.baseline {
            let (_, base) = baseline_depths
                .iter()
                .find(|(name, _)| name == &baseline.case)
                .expect("select() runs every baseline before the cases naming it");
            let difference = outcome
                .depths
                .iter()
                .zip(base)
                .map(|(depth, base)| DepthDifference::of(depth, base, &baseline.tolerance))
                .fold(DepthDifference::default(), DepthDifference::merge);
            invariance.push(InvarianceCheck {
                case: case.name.clone(),
                baseline: baseline.case.clone(),
                frames: outcome.depths.len() as u32,
                tolerance: baseline.tolerance,
                difference,
            });
        }
        if is_baseline(case) {
            baseline_depths.push((case.name.clone(), outcome.depths));
        }
    }
    if stop.get() {
        return Err(StressError::Interrupted);
    }
    Ok(StressReport {
        adapter: gpu.adapter.clone(),
        resolution,
        params: given.entries().map(|(key, value)| format!("{key}={value}")).collect(),
        rows,
        invariance,
        skipped,
        skipped_cases,
    })
}

/// What one case produced.
pub struct CaseOutcome {
    /// Frame-major, one row per culler.
    pub rows: Vec<FrameStats>,
    /// What the cullers got wrong (missed.csv's rows).
    pub missed: Vec<MissedObject>,
    /// The reference depth of every frame, when asked for.
    pub depths: Vec<Vec<f32>>,
}

/// Runs `cullers` over one case's frames, on a hierarchy built with
/// `hierarchy`, with error measurement; `frame_done` is called after each
/// frame.
pub fn run_case(
    gpu: &GpuContext,
    case: &StressCase,
    hierarchy: &HierarchyParams,
    cullers: &mut [Box<dyn Culler + '_>],
    resolution: Resolution,
    keep_depth: bool,
    frame_done: &mut dyn FnMut(u32),
) -> Result<CaseOutcome, GpuError> {
    let options = RunOptions {
        warmup: 0,
        resolution,
        measure_error: true,
    };
    let hierarchy = Hierarchy::build(&case.scene.objects, hierarchy);
    let mut world = World::new(case.scene.clone(), hierarchy);
    let mut session = Session::new(gpu, &world, cullers, true, &options)?;
    let mut outcome = CaseOutcome {
        rows: Vec::new(),
        missed: Vec::new(),
        depths: Vec::new(),
    };
    for (frame, camera) in case.cameras.iter().enumerate() {
        let camera = Camera {
            aspect: resolution.aspect(),
            ..*camera
        };
        outcome
            .rows
            .extend(session.frame(frame as u32, &camera, &mut world, cullers, frame)?);
        if keep_depth {
            outcome
                .depths
                .push(session.reference_depth().expect("the session renders a reference"));
        }
        frame_done(frame as u32);
    }
    outcome.missed = std::mem::take(&mut session.missed);
    Ok(outcome)
}

/// The report as Markdown: the case × mode table, the invariance table and
/// the verdict line.
pub fn render_markdown(report: &StressReport) -> String {
    let params = match report.params.is_empty() {
        true => String::new(),
        false => format!("\nparameters set: {}\n", report.params.join(", ")),
    };
    let mut out = format!(
        "# occlu stress\n\nadapter: {}, {} (a case at a size of its own names it)\n{params}\n| case | mode | frames | error px | missed | max \\|Δdepth\\| | verdict |\n|---|---|---:|---:|---:|---:|---|\n",
        report.adapter, report.resolution
    );
    for r in &report.rows {
        let verdict = match r.passed() {
            Some(true) => "pass",
            Some(false) => "FAIL",
            None => "not judged",
        };
        let case = match r.resolution {
            Some(size) => format!("{} ({size})", r.case),
            None => r.case.clone(),
        };
        out += &format!(
            "| {case} | {} | {} | {} | {} | {:.3e} | {verdict} |\n",
            r.mode, r.frames, r.error_pixels, r.missed_objects, r.max_depth_error
        );
    }
    if !report.invariance.is_empty() {
        out += "\nSame image as the baseline: reference depth of every frame, pixel by pixel (a pixel passes when |Δ| ≤ max(relative · depth, absolute)):\n\n| case | baseline | frames | tolerance rel / abs | pixels beyond | coverage changes | max \\|Δdepth\\| | max relative | verdict |\n|---|---|---:|---:|---:|---:|---:|---:|---|\n";
        for c in &report.invariance {
            let (t, d) = (&c.tolerance, &c.difference);
            out += &format!(
                "| {} | {} | {} | {:e} / {:e} | {} | {} | {:.3e} | {:.3e} | {} |\n",
                c.case,
                c.baseline,
                c.frames,
                t.relative,
                t.absolute,
                d.pixels_beyond,
                d.coverage_changes,
                d.max_absolute,
                d.max_relative,
                if c.passed() { "pass" } else { "FAIL" }
            );
        }
    }
    for s in &report.skipped {
        out += &format!("\nskipped: {}: {}\n", s.mode, s.reason);
    }
    for s in &report.skipped_cases {
        out += &format!("\nskipped case: {}: {}\n", s.case, s.reason);
    }
    let (passed, failed) = report.verdicts();
    out += &format!("\n{passed} passed, {failed} failed\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(mode: &str, error: u64, missed: u64) -> FrameStats {
        FrameStats {
            frame_ms: 1.0,
            objects_drawn: 1,
            triangles_drawn: 1,
            error_pixels: Some(error),
            max_depth_error: Some(error as f64 * 1e-3),
            missed_objects: Some(missed),
            visible_objects: Some(1),
            ..FrameStats::blank(mode)
        }
    }

    #[test]
    fn any_error_fails_a_conservative_mode_and_only_it() {
        let rows = [row("vfc", 0, 0), row("sq", 0, 1), row("vfc", 3, 0), row("ac", 7, 2)];
        let vfc = StressRow::tally("c", "vfc", true, &rows);
        assert_eq!((vfc.frames, vfc.error_pixels, vfc.missed_objects), (2, 3, 0));
        assert_eq!(vfc.max_depth_error, 3e-3);
        assert_eq!(vfc.passed(), Some(false));
        assert_eq!(StressRow::tally("c", "sq", true, &rows).passed(), Some(false));
        assert_eq!(StressRow::tally("c", "ac", false, &rows).passed(), None);
        let clean = StressRow::tally("c", "vfc", true, &rows[..1]);
        assert_eq!(clean.passed(), Some(true));
    }

    #[test]
    fn depth_differences_are_judged_by_the_tolerance() {
        let base = [0.0, 0.5, 0.25, 0.1, 0.0];
        let same = DepthDifference::of(&base, &base, &DepthTolerance::EXACT);
        assert_eq!(same, DepthDifference::default());
        let nudged = [0.0, 0.5 * (1.0 + 4e-5), 0.25, 0.1 + 5e-7, 0.0];
        let exact = DepthDifference::of(&nudged, &base, &DepthTolerance::EXACT);
        assert_eq!((exact.pixels_beyond, exact.coverage_changes), (2, 0));
        assert!((exact.max_relative - 4e-5).abs() < 1e-7, "{exact:?}");
        assert!((exact.max_absolute - 2e-5).abs() < 1e-7, "{exact:?}");
        // Within 1e-4 relative; 5e-7 at depth 0.1 is 5e-6 relative.
        assert_eq!(
            DepthDifference::of(&nudged, &base, &DepthTolerance::SCALED).pixels_beyond,
            0
        );
        // Coverage lost and gained, and a surface moved by 1e-3.
        let moved = [0.3, 0.5, 0.25 * (1.0 + 1e-3), 0.0, 0.0];
        let d = DepthDifference::of(&moved, &base, &DepthTolerance::SCALED);
        assert_eq!((d.pixels_beyond, d.coverage_changes), (3, 2));
        let check = InvarianceCheck {
            case: "c".into(),
            baseline: "b".into(),
            frames: 1,
            tolerance: DepthTolerance::SCALED,
            difference: d,
        };
        assert!(!check.passed());
    }

    #[test]
    fn selecting_a_transformed_case_brings_its_baseline() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let picked: Vec<String> = select(&names(&["offset-1e7", "teleport"]))
            .unwrap()
            .into_iter()
            .map(|c| c.name)
            .collect();
        assert_eq!(picked, names(&["inside-root", "offset-1e7", "teleport"]));
        let err = select(&names(&["bogus"])).err().unwrap().to_string();
        assert!(
            err.contains("unknown stress case 'bogus'") && err.contains("near-far"),
            "{err}"
        );
    }
}
