//! `occlu bench`: the whole flow of DESIGN.md, load → hierarchy → GPU →
//! cull → measure → report, and the interleaved frame loop at its heart.
//!
//! The frame loop: for each frame of the path, the scene's movers are put in
//! place, the camera's per-object matrices are uploaded and the reference is
//! rendered (all untimed); then
//! every mode renders that frame (timed: from the start of its frame on the
//! CPU until the GPU finished it); then one pass measures every mode's error
//! (untimed). The order of the modes changes from frame to frame, balanced
//! so that each mode runs first (right after the reference) and right after
//! each other mode equally often: what ran before a mode changes what its
//! frame costs. Warm-up frames run the path's first frames and are not
//! recorded.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::animation::{Animation, AnimationError, AnimationOptions, DEFAULT_SCALE, Filmstrip, FrameRange, Reel};
use crate::camera::generate::{PLANNING_TESTS, default_path_heard};
use crate::camera::path::{CameraPath, PathError};
use crate::config::{BenchPlan, ModeRun};
use crate::cull::{Culler, Labeled, ModeError, ModeId, ModeParams, unrunnable};
use crate::gpu::{AdapterReport, GpuContext, GpuError};
use crate::hierarchy::{Hierarchy, HierarchyParams};
use crate::measure::{FrameStats, FrameTimeline, MissedObject, ModeDescription, ModeSummary, summarize};
use crate::picture::Look;
use crate::raycast::{Budget, RayCaster, Stopped};
use crate::report::{
    Fingerprint, MatrixIdentity, MissedSummary, OutputLock, PathSummary, ReportError, ResultFiles, SCHEMA_VERSION,
    SceneFacts, SceneSummary, SkippedMode, Staged, Summary, SweepSummary, ToolInfo, Verdict, check_writable,
    prepare_output, refuse_input_among_results, refuse_input_as_output, refuse_result_file, stage_whole, trace_json,
    write_results,
};
use crate::scene::{Scene, SceneError, SceneSpec};
use crate::session::{RunOptions, Session, ms};
use crate::world::World;

pub struct RunOutput {
    /// Frame-major, modes in the order given.
    pub rows: Vec<FrameStats>,
    /// What the modes got wrong, frame by frame (empty when every mode was
    /// exact or error was not measured).
    pub missed: Vec<MissedObject>,
    /// When each part of each recorded frame ran, one for each of `rows`.
    pub timelines: Vec<FrameTimeline>,
    /// With an animation asked for, every recorded frame pictured.
    pub reel: Option<Reel>,
    pub upload_ms: f64,
}

/// Runs `cullers` over every frame of `path`, moving `world`'s movers as
/// the frames go, and with `animation` pictures every recorded frame
/// (untimed). `progress` is called after each frame with (frames done,
/// frames in all) including warm-up frames; when it breaks, the run stops
/// there with [`BenchError::Interrupted`].
pub fn run(
    gpu: &GpuContext,
    world: &mut World,
    path: &CameraPath,
    cullers: &mut [Box<dyn Culler + '_>],
    options: &RunOptions,
    animation: Option<&AnimationOptions>,
    progress: &mut dyn FnMut(u32, u32) -> ControlFlow<()>,
) -> Result<RunOutput, BenchError> {
    let mut session = Session::new(gpu, world, cullers, options.measure_error, options)?;
    let mut film = animation
        .map(|a| Filmstrip::new(gpu, &mut session, cullers, a, FrameRange::all(path.frames)))
        .transpose()?;
    let frames = path.frames;
    // Both are capped (MAX_FRAMES, MAX_WARMUP), so the sum cannot overflow.
    let total = options.warmup + frames;
    let mut rows = Vec::new();
    let mut timelines = Vec::new();
    for step in 0..total {
        let recording = step >= options.warmup;
        let frame = if recording {
            step - options.warmup
        } else {
            warm_up_frame(step, options.warmup, frames)
        };
        let camera = path.camera(frame, options.resolution.aspect());
        world.advance(frame);
        if recording {
            let these = session.frame(frame, &camera, world, cullers, step as usize)?;
            if let Some(film) = &mut film {
                film.capture(&mut session, world, &camera, cullers, &these)?;
            }
            rows.extend(these);
            timelines.append(&mut session.timelines);
        } else {
            session.warm_up_frame(frame, &camera, world, cullers, step as usize)?;
        }
        go_on(progress(step + 1, total))?;
    }
    Ok(RunOutput {
        rows,
        missed: std::mem::take(&mut session.missed),
        timelines,
        reel: film.map(|f| f.reel),
        upload_ms: session.upload_ms,
    })
}

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Path(#[from] PathError),
    #[error(transparent)]
    Mode(#[from] ModeError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Report(#[from] ReportError),
    #[error(transparent)]
    Animation(AnimationError),
    /// The caller asked the run to stop (Ctrl-C); nothing was written.
    #[error("interrupted: no results written, --out left as it was before the run")]
    Interrupted,
}

impl From<AnimationError> for BenchError {
    /// An animation stopped by the caller stops the run, as a frame does.
    fn from(e: AnimationError) -> BenchError {
        match e {
            AnimationError::Interrupted => BenchError::Interrupted,
            e => BenchError::Animation(e),
        }
    }
}

impl BenchError {
    /// Whether the user's input was at fault (as opposed to the GPU).
    pub fn is_input_error(&self) -> bool {
        match self {
            BenchError::Gpu(e) => e.is_input_error(),
            BenchError::Interrupted => false,
            BenchError::Report(e) => e.is_input_error(),
            BenchError::Animation(e) => e.is_input_error(),
            _ => true,
        }
    }
}

/// The path frame that warm-up frame `step` of `warmup` renders on a path
/// of `frames`: the path's first frames, last to first, so that warm-up
/// ends on the first recorded view, as an engine's loading frames look
/// from where the player starts. Run first to last, the last would be
/// `warmup` − 1 frames along the path, and every mode that carries state
/// from frame to frame (`chc`, the GPU walks, `swr`, `auto`'s calibrated
/// view) would start recording from a view the path has not reached: on
/// the engine's 40-frame orbit, 36° away with five warm-up frames.
fn warm_up_frame(step: u32, warmup: u32, frames: u32) -> u32 {
    (warmup - 1 - step) % frames
}

/// Whether the caller let the run go on: [`BenchError::Interrupted`] when
/// it asked to stop.
fn go_on(flow: ControlFlow<()>) -> Result<(), BenchError> {
    match flow {
        ControlFlow::Continue(()) => Ok(()),
        ControlFlow::Break(()) => Err(BenchError::Interrupted),
    }
}

/// What `execute` reports as it goes.
pub enum BenchEvent<'a> {
    Loaded {
        scene: &'a Scene,
        hierarchy: &'a Hierarchy,
        load_ms: f64,
        build_ms: f64,
    },
    Adapter(&'a AdapterReport),
    /// The camera path, and its frame count.
    Path(&'a PathSummary, u32),
    /// A mode the adapter cannot run; the run goes on without it.
    Skipped {
        mode: &'a str,
        reason: &'a str,
    },
    /// A step of ray casts (planning the path, counting frames with
    /// geometry within the near plane) has spent `spent` of its `budget`
    /// box and triangle tests; said every few milliseconds while it works.
    Work {
        what: &'static str,
        spent: u64,
        budget: u64,
    },
    Frame {
        done: u32,
        total: u32,
    },
    /// The reference showed no object in any frame: every mode's numbers
    /// are those of an empty picture.
    NothingVisible,
    /// The run is over and its animation is being encoded: `done` of its
    /// `total` frames so far.
    Encoding {
        done: u32,
        total: u32,
    },
}

pub struct BenchOutcome {
    pub summary: Summary,
    pub files: ResultFiles,
}

/// Loads the scene, builds the hierarchy, runs every mode and writes the
/// result files. `events` hears how it goes; when it breaks, the run stops
/// there with [`BenchError::Interrupted`] and writes nothing. A run that
/// fails leaves no folder behind that it made (its claim takes it away: a
/// matrix's run folder with only a lock in it would read as a run still
/// going).
pub fn execute(
    plan: &BenchPlan,
    events: &mut dyn FnMut(BenchEvent) -> ControlFlow<()>,
) -> Result<BenchOutcome, BenchError> {
    // A bad path file, WGPU_BACKEND or output directory is reported before
    // a long scene load, not after the run.
    let path_file = plan.path.as_deref().map(CameraPath::load).transpose()?;
    plan.backend.backends()?;
    // Held until the results are written: no second run writes here.
    let _claim = claim_outputs(plan)?;
    let params = HierarchyParams::default();
    let (mut world, load_ms, build_ms) = load_world(plan, &params)?;
    let (scene, hierarchy) = (&world.scene, &world.hierarchy);
    go_on(events(BenchEvent::Loaded {
        scene,
        hierarchy,
        load_ms,
        build_ms,
    }))?;
    let (path, path_summary) = camera_path(plan, path_file, scene, events)?;
    go_on(events(BenchEvent::Path(&path_summary, path.frames)))?;
    let gpu = GpuContext::new(plan.backend)?;
    go_on(events(BenchEvent::Adapter(&gpu.adapter)))?;
    let (runs, skipped) = runs_on(plan, &gpu);
    for s in &skipped {
        go_on(events(BenchEvent::Skipped {
            mode: &s.mode,
            reason: &s.reason,
        }))?;
    }
    let mut cullers = create_cullers(&runs, scene)?;
    let facts = SceneFacts::of(scene, hierarchy, load_ms, build_ms);
    let (output, animation) = record(plan, &gpu, &mut world, &path, &mut cullers, events)?;
    let (modes, verdict) = mode_summaries(plan, &runs, &cullers, &output.rows);
    let mut summary = Summary {
        schema_version: SCHEMA_VERSION,
        tool: ToolInfo::current(),
        run: plan.run.clone(),
        matrix: plan.matrix,
        adapter: gpu.adapter.clone(),
        scene: SceneSummary {
            facts,
            hierarchy_params: params,
            upload_ms: output.upload_ms,
            cluster_triangles: Some(plan.load.cluster_triangles),
        },
        path: path_summary,
        resolution: plan.resolution,
        frames: path.frames,
        warmup: plan.warmup,
        error_measured: plan.measure_error,
        verdict,
        modes,
        skipped,
        sweep: plan.sweep.as_ref().map(|s| SweepSummary {
            mode: s.mode.to_string(),
            key: s.key.clone(),
            values: s.values.clone(),
        }),
        missed: MissedSummary::of(&output.missed),
        frames_csv: None,
        animation: None,
    };
    // The extras are written first and put in place last: a run that
    // cannot write one (a full disk) fails with the results folder as it
    // was, and one whose results cannot be written with the extras as they
    // were.
    let extras = extras(plan, &summary, &output);
    let staged = extras
        .iter()
        .map(|(path, bytes)| stage_whole(path, bytes))
        .collect::<Result<Vec<Staged>, ReportError>>()?;
    let png = animation.as_ref().map(|a| a.png.as_slice());
    let files = write_results(&plan.out, &mut summary, &output.rows, &output.missed, png)?;
    for extra in staged {
        extra.publish()?;
    }
    Ok(BenchOutcome { summary, files })
}

/// Claims `plan`'s --out for the run (refused when it holds a merged
/// result, or, for a run outside a matrix, a matrix's run folders) and
/// checks that --export-github-benchmark and --trace can be written, and
/// not over one of the run's own result files.
fn claim_outputs(plan: &BenchPlan) -> Result<OutputLock, BenchError> {
    // A merged folder's report.md and this run's would share a name.
    let merged = plan.out.join("merged.json");
    if merged.exists() {
        return Err(refused(
            &merged,
            "--out holds a merged result: a run there would replace its report.md; choose another --out",
        ));
    }
    // Merge reads a folder that holds a run as that run alone: the
    // matrix's runs beside it would be left out.
    if plan.matrix.is_none()
        && let Some((folder, _)) = run_folders_in(&plan.out).find(|(_, matrix)| matrix.is_some())
    {
        return Err(refused(
            &folder,
            "is a matrix's run folder in --out: a single run's results beside it would hide the matrix's runs from merge; choose another --out",
        ));
    }
    let model = match &plan.scene {
        SceneSpec::File(model) => Some(model),
        SceneSpec::Builtin(_) => None,
    };
    for input in [model, plan.path.as_ref()].into_iter().flatten() {
        refuse_input_among_results(input, &plan.out)?;
    }
    let claim = prepare_output(&plan.out)?;
    for path in [&plan.export_github_benchmark, &plan.trace].into_iter().flatten() {
        refuse_result_file(path, &plan.out)?;
        check_writable(path)?;
    }
    Ok(claim)
}

/// Refuses a matrix's --out (`out`, for the matrix `matrix`) that holds a
/// merged result, a single run's results (which merge would read instead
/// of the matrix's run folders), or run folders of another matrix (one
/// whose runs, or their order, have changed since; merge would count them
/// besides this one's). Run once before a matrix's runs (reading every
/// run folder's summary.json), not by each run.
pub fn refuse_other_results_in_matrix_out(out: &Path, matrix: MatrixIdentity) -> Result<(), BenchError> {
    // A merged folder's runs/ and charts/ are no matrix's run folders.
    let merged = out.join("merged.json");
    if merged.exists() {
        return Err(refused(
            &merged,
            "--out holds a merged result: a matrix's runs there would be read as part of it; choose another --out",
        ));
    }
    let single = out.join("summary.json");
    if single.exists() {
        return Err(refused(
            &single,
            "is a single run's result in the matrix's --out: merge would read it alone and leave the matrix's runs out; choose another --out",
        ));
    }
    for (folder, theirs) in run_folders_in(out) {
        let why = match theirs {
            Some(theirs) if theirs == matrix => continue,
            Some(_) => {
                "is a run of another matrix (its runs, or their order, differ from this one's) in --out: merge would count its runs besides this matrix's; empty --out or choose another"
            }
            None => {
                "is a single run's folder in the matrix's --out: merge would take it for one of the matrix's runs; empty --out or choose another"
            }
        };
        return Err(refused(&folder, why));
    }
    Ok(())
}

/// The folders directly in `dir` that hold a run's summary.json (hidden
/// ones, a run's staging, left out), each with the matrix its summary
/// names (`None` for a single run); none where `dir` cannot be read. A
/// summary.json that cannot be read (damaged, or of another schema) is
/// passed over: merge refuses it by name, and a run of this matrix
/// replaces it.
fn run_folders_in(dir: &Path) -> impl Iterator<Item = (PathBuf, Option<MatrixIdentity>)> {
    /// A summary's `matrix` alone, read whatever else it holds.
    #[derive(serde::Deserialize)]
    struct MatrixOf {
        matrix: Option<MatrixIdentity>,
    }
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .filter_map(Result::ok)
        .filter(|entry| !entry.file_name().as_encoded_bytes().starts_with(b"."))
        .map(|entry| entry.path())
        .filter_map(|path| {
            let text = crate::input::read_text(&path.join("summary.json"), crate::input::TEXT_LIMIT).ok()?;
            let summary: MatrixOf = serde_json::from_str(&text).ok()?;
            Some((path, summary.matrix))
        })
}

/// A bench refused at `path`, saying `why`.
fn refused(path: &Path, why: &str) -> BenchError {
    ReportError::at(path)(std::io::Error::other(why.to_string())).into()
}

/// The scene loaded and its hierarchy built with `params`, and how many
/// milliseconds each took; an extra output that is one of the files the
/// scene was read from is refused.
fn load_world(plan: &BenchPlan, params: &HierarchyParams) -> Result<(World, f64, f64), BenchError> {
    let start = Instant::now();
    let scene = crate::scene::load(&plan.scene, &plan.load)?;
    let load_ms = ms(start.elapsed());
    // The model and path are checked before: a glTF file's buffer files
    // are known now.
    for path in [&plan.export_github_benchmark, &plan.trace].into_iter().flatten() {
        refuse_input_as_output(path, &scene.files)?;
    }
    for file in &scene.files {
        refuse_input_among_results(file, &plan.out)?;
    }
    let start = Instant::now();
    let hierarchy = Hierarchy::build(&scene.objects, params);
    let build_ms = ms(start.elapsed());
    Ok((World::new(scene, hierarchy), load_ms, build_ms))
}

/// The run's camera path (`path_file`, or the default path planned for
/// `scene`, resampled to --frames) and its summary, with the frames whose
/// geometry reaches within the near plane counted (not counted when the
/// count spent its budget).
fn camera_path(
    plan: &BenchPlan,
    path_file: Option<CameraPath>,
    scene: &Scene,
    events: &mut dyn FnMut(BenchEvent) -> ControlFlow<()>,
) -> Result<(CameraPath, PathSummary), BenchError> {
    let (path, generated) = match path_file {
        Some(path) => (path, None),
        None => {
            let heard = |spent, budget| {
                events(BenchEvent::Work {
                    what: "planning the path",
                    spent,
                    budget,
                })
            };
            match default_path_heard(scene, Box::new(heard)) {
                Err(PathError::Interrupted) => return Err(BenchError::Interrupted),
                planned => planned.map(|(path, why)| (path, Some(why)))?,
            }
        }
    };
    let path = match plan.frames {
        Some(n) => path.with_frames(n)?,
        None => path,
    };
    let heard = |spent, budget| {
        events(BenchEvent::Work {
            what: "counting frames with geometry within the near plane",
            spent,
            budget,
        })
    };
    let caster = RayCaster::with_budget(
        scene,
        Budget {
            tests: PLANNING_TESTS,
            listener: Box::new(heard),
        },
    );
    // Not counted (None) when it spent its budget.
    let within_near = match path.frames_with_geometry_within_near(&caster, plan.resolution.aspect()) {
        Err(Stopped::Interrupted) => return Err(BenchError::Interrupted),
        counted => counted.ok(),
    };
    drop(caster);
    let summary = PathSummary {
        source: path.source.clone(),
        keyframes: path.keyframes.len(),
        near: path.near,
        generated,
        frames_with_geometry_within_near: within_near,
        cameras: Some(Fingerprint::of_path(&path, scene.up.axis)),
    };
    Ok((path, summary))
}

/// The plan's runs the adapter can run, and the modes it cannot, each once
/// with why ([`unrunnable`]: an `auto` candidate too, where it was given
/// parameters).
fn runs_on(plan: &BenchPlan, gpu: &GpuContext) -> (Vec<ModeRun>, Vec<SkippedMode>) {
    let unsupported = |mode: ModeId| mode.info().unsupported_on(gpu);
    let mut runs = plan.runs();
    let named: Vec<(ModeId, &ModeParams)> = runs.iter().map(|run| (run.mode, &run.params)).collect();
    let skipped = unrunnable(&named, unsupported)
        .into_iter()
        .map(SkippedMode::from)
        .collect();
    runs.retain(|run| unsupported(run.mode).is_none());
    (runs, skipped)
}

/// A culler for each run, under the run's label when it is not the mode's
/// name (a sweep's value).
fn create_cullers(runs: &[ModeRun], scene: &Scene) -> Result<Vec<Box<dyn Culler>>, ModeError> {
    runs.iter()
        .map(|run| {
            let culler = run.mode.create(scene, &run.params)?;
            Ok(if run.label == run.mode.name() {
                culler
            } else {
                Box::new(Labeled {
                    label: run.label.clone(),
                    inner: culler,
                }) as Box<dyn Culler>
            })
        })
        .collect()
}

/// Runs `cullers` over `path` (the frame loop, [`run`]), says when nothing
/// was visible, and encodes the animation when `plan` asks for one.
fn record(
    plan: &BenchPlan,
    gpu: &GpuContext,
    world: &mut World,
    path: &CameraPath,
    cullers: &mut [Box<dyn Culler>],
    events: &mut dyn FnMut(BenchEvent) -> ControlFlow<()>,
) -> Result<(RunOutput, Option<Animation>), BenchError> {
    let options = RunOptions {
        warmup: plan.warmup,
        resolution: plan.resolution,
        measure_error: plan.measure_error,
    };
    // The overview shows what each mode culled: the point of the animation.
    let animation = plan.animate.then_some(AnimationOptions {
        look: Look {
            resolution: plan.resolution,
            overview: true,
            heat: false,
            show_missed: false,
            occluders: false,
        },
        scale: DEFAULT_SCALE,
        true_colour: false,
    });
    let mut output = run(
        gpu,
        world,
        path,
        cullers,
        &options,
        animation.as_ref(),
        &mut |done, total| events(BenchEvent::Frame { done, total }),
    )?;
    if plan.measure_error && output.rows.iter().all(|r| r.visible_objects == Some(0)) {
        go_on(events(BenchEvent::NothingVisible))?;
    }
    let animation = output
        .reel
        .take()
        .map(|reel| reel.encode(&mut |done, total| events(BenchEvent::Encoding { done, total })))
        .transpose()?;
    Ok((output, animation))
}

/// Each run's statistics over `rows`, and the verdict on them.
fn mode_summaries(
    plan: &BenchPlan,
    runs: &[ModeRun],
    cullers: &[Box<dyn Culler>],
    rows: &[FrameStats],
) -> (Vec<ModeSummary>, Option<Verdict>) {
    let descriptions: Vec<ModeDescription> = runs
        .iter()
        .zip(cullers)
        .map(|(run, culler)| ModeDescription {
            name: run.label.clone(),
            conservative: run.mode.info().conservative,
            parameters: culler.parameters(),
        })
        .collect();
    let modes = summarize(rows, &descriptions, plan.resolution.pixels());
    let ids: Vec<ModeId> = runs.iter().map(|run| run.mode).collect();
    let verdict = Verdict::of(&modes, &ids, rows);
    (modes, verdict)
}

/// The files `plan` asks for beside the results, each with its contents:
/// github-action-benchmark's entries and the trace.
fn extras(plan: &BenchPlan, summary: &Summary, output: &RunOutput) -> Vec<(PathBuf, Vec<u8>)> {
    let mut extras = Vec::new();
    if let Some(path) = &plan.export_github_benchmark {
        let entries = crate::report::github::entries(summary);
        let json = serde_json::to_string_pretty(&entries).expect("entries serialise: strings and numbers") + "\n";
        extras.push((path.clone(), json.into_bytes()));
    }
    if let Some(path) = &plan.trace {
        let run = format!(
            "{} along {}, {} frames at {}",
            summary.scene.facts.source, summary.path.source, summary.frames, summary.resolution
        );
        let trace = trace_json(&summary.adapter, &run, &output.rows, &output.timelines);
        extras.push((path.clone(), trace.into_bytes()));
    }
    extras
}

#[cfg(test)]
mod tests {
    use super::warm_up_frame;

    #[test]
    fn warm_up_runs_the_path_s_first_frames_last_to_first_ending_on_the_first_recorded_view() {
        let order = |warmup: u32, frames: u32| {
            (0..warmup)
                .map(|s| warm_up_frame(s, warmup, frames))
                .collect::<Vec<_>>()
        };
        assert_eq!(order(5, 40), [4, 3, 2, 1, 0]);
        assert_eq!(order(1, 40), [0]);
        // A path shorter than warm-up goes round it.
        assert_eq!(order(5, 2), [0, 1, 0, 1, 0]);
    }
}
