//! `occlu bench`: the whole flow of DESIGN.md, load → hierarchy → GPU →
//! cull → measure → report, and the interleaved frame loop at its heart.
//!
//! The frame loop: for each frame of the path, the scene's movers are put in
//! place, the camera's per-object matrices are uploaded and the reference is
//! rendered (all untimed); then
//! every mode renders that frame (timed: from the start of its frame on the
//! CPU until the GPU finished it); then one pass measures every mode's error
//! (untimed). The order of the modes rotates from frame to frame, so no mode
//! always runs right after the reference (whose work warms caches). Warm-up
//! frames run the path's first frames and are not recorded.

use std::collections::BTreeSet;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use crate::camera::Camera;
use crate::camera::generate::{PLANNING_TESTS, default_path_heard};
use crate::camera::path::{CameraPath, PathError};
use crate::config::BenchPlan;
use crate::cull::{Culler, FrameInput, Labeled, ModeError, ModeId, PreviousFrame};
use crate::gpu::{
    AdapterReport, FrameCtx, FrameResources, GpuContext, GpuError, GpuScene, GpuSetup, GpuTimer, QueryPool,
    RenderTargets, Resolution, SceneRenderer,
};
use crate::hierarchy::{Hierarchy, HierarchyParams};
use crate::measure::{ErrorMeter, FrameStats, MissedObject, ModeDescription, ObjectError, summarize};
use crate::object_set::ObjectSet;
use crate::raycast::{Budget, RayCaster, Stopped};
use crate::report::{
    Fingerprint, MissedSummary, PathSummary, ReportError, ResultFiles, SCHEMA_VERSION, SceneFacts, SceneSummary,
    SkippedMode, Summary, SweepSummary, ToolInfo, Verdict, check_writable, prepare_output, refuse_input_as_output,
    refuse_result_file, write_results, write_whole,
};
use crate::scene::{Scene, SceneError};
use crate::world::World;

#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    pub warmup: u32,
    pub resolution: Resolution,
    /// Render the reference and measure every mode's error.
    pub measure_error: bool,
}

pub struct RunOutput {
    /// Frame-major, modes in the order given.
    pub rows: Vec<FrameStats>,
    /// What the modes got wrong, frame by frame (empty when every mode was
    /// exact or error was not measured).
    pub missed: Vec<MissedObject>,
    pub upload_ms: f64,
}

/// Runs `cullers` over every frame of `path`, moving `world`'s movers as
/// the frames go. `progress` is called after each frame with (frames done,
/// frames in all) including warm-up frames; when it breaks, the run stops
/// there with [`BenchError::Interrupted`].
pub fn run(
    gpu: &GpuContext,
    world: &mut World,
    path: &CameraPath,
    cullers: &mut [Box<dyn Culler + '_>],
    options: &RunOptions,
    progress: &mut dyn FnMut(u32, u32) -> ControlFlow<()>,
) -> Result<RunOutput, BenchError> {
    let mut session = Session::new(gpu, world, cullers, options.measure_error, options)?;
    let frames = path.frames;
    // Both are capped (MAX_FRAMES, MAX_WARMUP), so the sum cannot overflow.
    let total = options.warmup + frames;
    let mut rows = Vec::new();
    for step in 0..total {
        let recording = step >= options.warmup;
        let frame = if recording {
            step - options.warmup
        } else {
            step % frames
        };
        let camera = path.camera(frame, options.resolution.aspect());
        world.advance(frame);
        // Rotating the order from frame to frame: no mode always runs right
        // after the reference.
        if recording {
            rows.extend(session.frame(frame, &camera, world, cullers, step as usize)?);
        } else {
            session.warm_up_frame(frame, &camera, world, cullers, step as usize)?;
        }
        go_on(progress(step + 1, total))?;
    }
    Ok(RunOutput {
        rows,
        missed: std::mem::take(&mut session.missed),
        upload_ms: session.upload_ms,
    })
}

/// The GPU resources of a run, and what each mode carries from one frame to
/// the next (its drawn set, its previous frame's cost).
pub struct Session<'a> {
    gpu: &'a GpuContext,
    pub(crate) renderer: SceneRenderer,
    pub(crate) targets: RenderTargets,
    meter: Option<ErrorMeter>,
    timer: Option<GpuTimer>,
    queries: QueryPool,
    draw_queue: Vec<u32>,
    /// What each mode drew in the last frame.
    pub(crate) drawn: Vec<ObjectSet>,
    previous: Vec<Option<PreviousFrame>>,
    options: RunOptions,
    pub upload_ms: f64,
    /// What the modes got wrong in the frames run so far (missed.csv's
    /// rows); [`run`] drops the warm-up frames'.
    pub missed: Vec<MissedObject>,
    /// Scratch for [`ErrorMeter::attribute_wrong_pixels`].
    object_errors: Vec<ObjectError>,
}

impl<'a> Session<'a> {
    /// Uploads `world`'s scene, creates targets for every one of `cullers`
    /// and lets each prepare its own GPU resources. The reference is
    /// rendered each frame when `reference` or a culler needs it.
    pub fn new(
        gpu: &'a GpuContext,
        world: &World,
        cullers: &mut [Box<dyn Culler + '_>],
        reference: bool,
        options: &RunOptions,
    ) -> Result<Session<'a>, GpuError> {
        let (scene, modes) = (&world.scene, cullers.len());
        let needs_reference = reference || cullers.iter().any(|c| c.needs_reference());
        gpu.check()?;
        RenderTargets::check(gpu, options.resolution)?;
        let start = Instant::now();
        let renderer = SceneRenderer::new(gpu, GpuScene::upload(gpu, scene)?);
        let targets = RenderTargets::new(gpu, options.resolution, modes);
        gpu.wait_idle();
        let upload_ms = ms(start.elapsed());
        // The modes' own resources (pipelines, trees) are not the scene's
        // upload.
        for (culler, depth) in cullers.iter_mut().zip(&targets.mode_depths) {
            culler.prepare(&GpuSetup {
                gpu,
                camera: renderer.camera_uniform(),
                draws: &renderer.scene.draws,
                scene,
                hierarchy: &world.hierarchy,
                depth,
                resolution: options.resolution,
            })?;
        }
        gpu.wait_idle();
        Ok(Session {
            gpu,
            meter: needs_reference.then(|| ErrorMeter::new(gpu, &targets, scene.objects.len())),
            timer: GpuTimer::new(gpu, modes),
            queries: QueryPool::new(gpu, renderer.camera_uniform()),
            draw_queue: Vec::new(),
            drawn: (0..modes).map(|_| ObjectSet::new(scene.objects.len())).collect(),
            previous: vec![None; modes],
            options: *options,
            upload_ms,
            missed: Vec::new(),
            object_errors: Vec::new(),
            renderer,
            targets,
        })
    }

    /// Renders one frame of `world` (its movers already placed) in every
    /// mode, starting with mode `first % n`, and returns one row per mode in
    /// the order of `cullers`.
    ///
    /// Untimed: the per-object matrix upload, the reference, GPU times and
    /// errors. Timed, per mode: from the start of its frame on the CPU until
    /// the GPU finished it, including the refit of the hierarchy around
    /// moved objects for modes that traverse it.
    ///
    /// `cullers` are the ones this session was made with (and prepared), in
    /// the same order.
    pub fn frame(
        &mut self,
        frame: u32,
        camera: &Camera,
        world: &mut World,
        cullers: &mut [Box<dyn Culler + '_>],
        first: usize,
    ) -> Result<Vec<FrameStats>, GpuError> {
        self.render(frame, camera, world, cullers, first, false)
    }

    /// [`Session::frame`] as a warm-up frame, whose rows are not kept
    /// ([`FrameInput::warm_up`]).
    pub fn warm_up_frame(
        &mut self,
        frame: u32,
        camera: &Camera,
        world: &mut World,
        cullers: &mut [Box<dyn Culler + '_>],
        first: usize,
    ) -> Result<(), GpuError> {
        self.render(frame, camera, world, cullers, first, true)?;
        self.missed.clear();
        Ok(())
    }

    fn render(
        &mut self,
        frame: u32,
        camera: &Camera,
        world: &mut World,
        cullers: &mut [Box<dyn Culler + '_>],
        first: usize,
        warm_up: bool,
    ) -> Result<Vec<FrameStats>, GpuError> {
        let gpu = self.gpu;
        self.renderer
            .set_camera(gpu, camera, self.options.resolution, &world.scene.objects);
        // Flush the upload now, so no mode's timed submit carries it.
        gpu.queue.submit([]);
        gpu.wait_idle();
        let visible = self
            .meter
            .as_mut()
            .map(|m| m.render_reference(gpu, &self.renderer, &self.targets));

        let mut rows: Vec<Option<FrameStats>> = vec![None; cullers.len()];
        for turn in 0..cullers.len() {
            let k = (turn + first) % cullers.len();
            let culler = &mut cullers[k];
            let frame_start = Instant::now();
            let refit_time = if culler.traverses_hierarchy() {
                world.refit()
            } else {
                Duration::ZERO
            };
            let input = FrameInput {
                frame,
                camera,
                resolution: self.options.resolution,
                scene: &world.scene,
                hierarchy: &world.hierarchy,
                moved: world.moved(),
                reference_visible: if culler.needs_reference() {
                    visible.as_ref()
                } else {
                    None
                },
                previous: self.previous[k],
                warm_up,
            };
            let resources = FrameResources {
                gpu,
                renderer: &self.renderer,
                targets: &self.targets,
                queries: &mut self.queries,
                timer: self.timer.as_ref(),
                draw_queue: &mut self.draw_queue,
            };
            let mut ctx = FrameCtx::begin(resources, k, camera, &mut self.drawn[k]);
            let cull_start = Instant::now();
            let mut traversal = culler.frame(&mut ctx, &input);
            let cull_time = cull_start.elapsed();
            let mut outcome = ctx.finish();
            let frame_time = frame_start.elapsed();
            // Untimed: what the mode's own GPU work drew and tested.
            if let Some(audit) = culler.audit(gpu, &mut self.drawn[k]) {
                outcome.add_gpu_audit(&audit);
                traversal.add_gpu_audit(&audit);
            }
            rows[k] = Some(FrameStats {
                mode: culler.name().to_string(),
                frame,
                frame_ms: ms(frame_time),
                cpu_ms: ms(refit_time + cull_time.saturating_sub(outcome.gpu_ops)),
                maintenance_ms: ms(refit_time + traversal.maintenance),
                gpu_ms: None,
                objects_drawn: outcome.counters.objects_drawn,
                triangles_drawn: outcome.counters.triangles_drawn,
                queries: outcome.counters.queries,
                query_batches: outcome.counters.query_batches,
                traversal,
                query_wait_ms: ms(outcome.counters.query_wait),
                query_gpu_ms: outcome.counters.query_gpu.map(ms),
                pyramid_gpu_ms: outcome.counters.pyramid_gpu.map(ms),
                error_pixels: None,
                max_depth_error: None,
                missed_objects: None,
                visible_objects: visible.as_ref().map(|v| v.len() as u64),
                strategy: culler.pick().map(|p| p.strategy.to_string()),
                probe: culler.pick().map(|p| p.probe),
            });
        }

        // End of frame, untimed: GPU times and errors of every mode.
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        if let Some(t) = &self.timer {
            t.resolve(&mut encoder);
        }
        let wrong = match (&mut self.meter, self.options.measure_error) {
            (Some(m), true) => Some(m.count_wrong_pixels(gpu, &self.targets, encoder)),
            _ => {
                gpu.queue.submit([encoder.finish()]);
                None
            }
        };
        let gpu_ms = self.timer.as_mut().map(|t| t.read_ms(gpu));
        let rows = rows
            .into_iter()
            .enumerate()
            .map(|(k, row)| {
                let mut row = row.expect("every mode ran this frame");
                row.gpu_ms = gpu_ms.as_ref().map(|t| t[k]);
                if let (Some(wrong), Some(visible)) = (&wrong, &visible) {
                    row.error_pixels = Some(wrong[k].wrong_pixels);
                    row.max_depth_error = Some(f64::from(wrong[k].max_difference));
                    let missed = visible.count_missing_from(&self.drawn[k]) as u64;
                    row.missed_objects = Some(missed);
                    if wrong[k].wrong_pixels > 0 || missed > 0 {
                        self.name_what_was_missed(k, &row, visible, &world.scene);
                    }
                }
                self.previous[k] = Some(PreviousFrame {
                    frame_ms: row.frame_ms,
                    render_ms: row.render_ms(),
                    triangles_drawn: row.triangles_drawn,
                });
                row
            })
            .collect();
        // A frame the GPU failed in measured nothing.
        gpu.check()?;
        Ok(rows)
    }

    /// Appends to [`Session::missed`] what mode `k` got wrong in this frame
    /// (`row`): the objects the reference shows (`visible`) that it did not
    /// draw, and the objects owning pixels it got wrong.
    fn name_what_was_missed(&mut self, k: usize, row: &FrameStats, visible: &ObjectSet, scene: &Scene) {
        let meter = self.meter.as_mut().expect("errors were measured");
        meter.attribute_wrong_pixels(self.gpu, &self.targets, k, &mut self.object_errors);
        let drawn = &self.drawn[k];
        let errors = &self.object_errors;
        let objects: BTreeSet<u32> = visible
            .iter()
            .filter(|&o| !drawn.contains(o))
            .chain(errors.iter().map(|e| e.object))
            .collect();
        for object in objects {
            // `errors` ascends by object id.
            let error = errors
                .binary_search_by_key(&object, |e| e.object)
                .ok()
                .map(|i| errors[i]);
            self.missed.push(MissedObject {
                mode: row.mode.clone(),
                frame: row.frame,
                object,
                name: scene.objects[object as usize].name.clone(),
                drawn: drawn.contains(object),
                wrong_pixels: error.map_or(0, |e| e.wrong_pixels),
                first_x: error.map(|e| e.first_pixel.0),
                first_y: error.map(|e| e.first_pixel.1),
            });
        }
    }

    /// The reference depth of the last frame, row-major from the top-left
    /// pixel; `None` when the session renders no reference.
    pub fn reference_depth(&mut self) -> Option<Vec<f32>> {
        self.depth(None)
    }

    /// The depth mode `k` drew in the last frame, as
    /// [`Session::reference_depth`]; `None` without a reference.
    pub fn mode_depth(&mut self, k: usize) -> Option<Vec<f32>> {
        self.depth(Some(k))
    }

    fn depth(&mut self, mode: Option<usize>) -> Option<Vec<f32>> {
        let meter = self.meter.as_mut()?;
        let mut depth = Vec::new();
        meter.read_depth(self.gpu, &self.targets, mode, &mut depth);
        Some(depth)
    }
}

/// Milliseconds, rounded to 0.1 µs (finer than any timer here resolves).
fn ms(d: Duration) -> f64 {
    (d.as_secs_f64() * 1e7).round() / 1e4
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
    /// The caller asked the run to stop (Ctrl-C); nothing was written.
    #[error("interrupted: no results written, --out left as it was before the run")]
    Interrupted,
}

impl BenchError {
    /// Whether the user's input was at fault (as opposed to the GPU).
    pub fn is_input_error(&self) -> bool {
        match self {
            BenchError::Gpu(e) => e.is_input_error(),
            BenchError::Interrupted => false,
            BenchError::Report(e) => e.is_input_error(),
            _ => true,
        }
    }
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
    // A merged folder's report.md and this run's would share a name.
    let merged = plan.out.join("merged.json");
    if merged.exists() {
        let error = std::io::Error::other(
            "--out holds a merged result: a run there would replace its report.md; choose another --out",
        );
        return Err(ReportError::at(&merged)(error).into());
    }
    // Held until the results are written: no second run writes here.
    let _claim = prepare_output(&plan.out)?;
    if let Some(path) = &plan.export_github_benchmark {
        refuse_result_file(path, &plan.out)?;
        check_writable(path)?;
    }
    let start = Instant::now();
    let scene = crate::scene::load(&plan.scene, &plan.load)?;
    let load_ms = ms(start.elapsed());
    if let Some(path) = &plan.export_github_benchmark {
        // The model and path are checked before: a glTF file's buffer
        // files are known now.
        refuse_input_as_output(path, &scene.files)?;
    }
    let start = Instant::now();
    let params = HierarchyParams::default();
    let hierarchy = Hierarchy::build(&scene.objects, &params);
    let build_ms = ms(start.elapsed());
    let mut world = World::new(scene, hierarchy);
    let (scene, hierarchy) = (&world.scene, &world.hierarchy);
    go_on(events(BenchEvent::Loaded {
        scene,
        hierarchy,
        load_ms,
        build_ms,
    }))?;

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
    let path_summary = PathSummary {
        source: path.source.clone(),
        keyframes: path.keyframes.len(),
        near: path.near,
        generated,
        frames_with_geometry_within_near: within_near,
        cameras: Some(Fingerprint::of_path(&path)),
    };
    go_on(events(BenchEvent::Path(&path_summary, path.frames)))?;
    let gpu = GpuContext::new(plan.backend)?;
    go_on(events(BenchEvent::Adapter(&gpu.adapter)))?;
    let mut skipped: Vec<SkippedMode> = Vec::new();
    let mut runs = plan.runs();
    runs.retain(|run| {
        let Some(reason) = run.mode.info().unsupported_on(&gpu) else {
            return true;
        };
        if !skipped.iter().any(|s| s.mode == run.mode.name()) {
            skipped.push(SkippedMode {
                mode: run.mode.to_string(),
                reason: reason.to_string(),
            });
        }
        false
    });
    for s in &skipped {
        go_on(events(BenchEvent::Skipped {
            mode: &s.mode,
            reason: &s.reason,
        }))?;
    }
    let mut cullers = runs
        .iter()
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
        .collect::<Result<Vec<_>, ModeError>>()?;
    let options = RunOptions {
        warmup: plan.warmup,
        resolution: plan.resolution,
        measure_error: plan.measure_error,
    };
    let facts = SceneFacts::of(scene, hierarchy, load_ms, build_ms);
    let output = run(&gpu, &mut world, &path, &mut cullers, &options, &mut |done, total| {
        events(BenchEvent::Frame { done, total })
    })?;
    if plan.measure_error && output.rows.iter().all(|r| r.visible_objects == Some(0)) {
        go_on(events(BenchEvent::NothingVisible))?;
    }

    let descriptions: Vec<ModeDescription> = runs
        .iter()
        .zip(&cullers)
        .map(|(run, culler)| ModeDescription {
            name: run.label.clone(),
            conservative: run.mode.info().conservative,
            parameters: culler.parameters(),
        })
        .collect();
    let modes = summarize(&output.rows, &descriptions, plan.resolution.pixels());
    let ids: Vec<ModeId> = runs.iter().map(|run| run.mode).collect();
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
        },
        path: path_summary,
        resolution: plan.resolution,
        frames: path.frames,
        warmup: plan.warmup,
        error_measured: plan.measure_error,
        verdict: Verdict::of(&modes, &ids),
        modes,
        skipped,
        sweep: plan.sweep.as_ref().map(|s| SweepSummary {
            mode: s.mode.to_string(),
            key: s.key.clone(),
            values: s.values.clone(),
        }),
        missed: MissedSummary::of(&output.missed),
        frames_csv: None,
    };
    let files = write_results(&plan.out, &mut summary, &output.rows, &output.missed)?;
    if let Some(path) = &plan.export_github_benchmark {
        let entries = crate::report::github::entries(&summary);
        let json = serde_json::to_string_pretty(&entries).expect("entries serialise: strings and numbers") + "\n";
        write_whole(path, json.as_bytes())?;
    }
    Ok(BenchOutcome { summary, files })
}
