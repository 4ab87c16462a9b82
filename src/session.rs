//! [`Session`]: the GPU resources of a run and one frame rendered in every
//! mode, timed, with its reference and error. `bench::run` drives it over a
//! path; `picture` and `stress` drive it frame by frame.

use std::collections::BTreeSet;
use std::time::{Duration, Instant};

use crate::balanced_order::balanced_order;
use crate::camera::Camera;
use crate::cull::{Culler, FrameInput, PreviousFrame};
use crate::gpu::{
    FrameCtx, FrameResources, GpuAudit, GpuContext, GpuError, GpuScene, GpuSetup, GpuTimer, OpSpan, QueryPool,
    RenderTargets, Resolution, SceneRenderer, picture_target, read_rgb,
};
use crate::measure::{CpuClock, ErrorMeter, FrameStats, FrameTimeline, GpuClock, MissedObject, ObjectError};
use crate::object_set::ObjectSet;
use crate::scene::Scene;
use crate::world::World;

#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    pub warmup: u32,
    pub resolution: Resolution,
    /// Render the reference and measure every mode's error.
    pub measure_error: bool,
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
    /// Scratch for each mode's log of GPU operations.
    ops: Vec<OpSpan>,
    /// What each mode drew in the last frame.
    pub(crate) drawn: Vec<ObjectSet>,
    previous: Vec<Option<PreviousFrame>>,
    options: RunOptions,
    pub upload_ms: f64,
    /// What the modes got wrong in the frames run so far (missed.csv's
    /// rows); [`Session::warm_up_frame`] drops its own.
    pub missed: Vec<MissedObject>,
    /// Scratch for [`ErrorMeter::attribute_wrong_pixels`].
    object_errors: Vec<ObjectError>,
    /// When the session was ready to run frames: where timelines start.
    started: Instant,
    /// The last frame's timeline of each mode, in the order of the cullers.
    pub timelines: Vec<FrameTimeline>,
    /// Each mode's colour target as its last frame left it, where kept
    /// ([`Session::keep_colours`]).
    colours: Vec<wgpu::Texture>,
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
            ops: Vec::new(),
            drawn: (0..modes).map(|_| ObjectSet::new(scene.objects.len())).collect(),
            previous: vec![None; modes],
            options: *options,
            upload_ms,
            missed: Vec::new(),
            object_errors: Vec::new(),
            started: Instant::now(),
            timelines: Vec::new(),
            colours: Vec::new(),
            renderer,
            targets,
        })
    }

    /// Renders one frame of `world` (its movers already placed) in every
    /// mode, in the [`balanced_order`] numbered `order`, and returns one row
    /// per mode in the order of `cullers`.
    ///
    /// Untimed: the per-object matrix upload (and each object's distance
    /// from the eye, which orders the draws), the reference, GPU times and
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
        order: usize,
    ) -> Result<Vec<FrameStats>, GpuError> {
        self.render(frame, camera, world, cullers, order, false)
    }

    /// [`Session::frame`] as a warm-up frame, whose rows are not kept
    /// ([`FrameInput::warm_up`]).
    pub fn warm_up_frame(
        &mut self,
        frame: u32,
        camera: &Camera,
        world: &mut World,
        cullers: &mut [Box<dyn Culler + '_>],
        order: usize,
    ) -> Result<(), GpuError> {
        let kept = self.missed.len();
        self.render(frame, camera, world, cullers, order, true)?;
        self.missed.truncate(kept);
        Ok(())
    }

    /// One frame in every mode: the reference first, then each mode in
    /// the balanced order numbered `order` (timed), then, untimed, every
    /// mode's GPU time and error.
    fn render(
        &mut self,
        frame: u32,
        camera: &Camera,
        world: &mut World,
        cullers: &mut [Box<dyn Culler + '_>],
        order: usize,
        warm_up: bool,
    ) -> Result<Vec<FrameStats>, GpuError> {
        let visible = self.begin_frame(camera, world);
        let mut ran: Vec<Option<(FrameStats, ModeClocks)>> = (0..cullers.len()).map(|_| None).collect();
        for k in balanced_order(order, cullers.len()) {
            let step = Step { frame, camera, warm_up };
            ran[k] = Some(self.run_mode(k, cullers[k].as_mut(), step, world, visible.as_ref()));
        }
        self.end_frame(ran, visible.as_ref(), &world.scene)
    }

    /// Places the camera, flushes the upload so that no mode's timed submit
    /// carries it, and renders the reference: the objects it shows, where
    /// errors are measured.
    fn begin_frame(&mut self, camera: &Camera, world: &World) -> Option<ObjectSet> {
        let gpu = self.gpu;
        self.renderer
            .set_camera(gpu, camera, self.options.resolution, &world.scene.objects);
        gpu.queue.submit([]);
        gpu.wait_idle();
        self.meter
            .as_mut()
            .map(|m| m.render_reference(gpu, &self.renderer, &self.targets))
    }

    /// Mode `k`'s frame, timed from the refit of the hierarchy (for a mode
    /// that traverses it) to the end of its GPU work; then, untimed, its
    /// audit and, where kept, its colour.
    fn run_mode(
        &mut self,
        k: usize,
        culler: &mut (dyn Culler + '_),
        step: Step<'_>,
        world: &mut World,
        visible: Option<&ObjectSet>,
    ) -> (FrameStats, ModeClocks) {
        let gpu = self.gpu;
        let frame_start = Instant::now();
        let refit_time = if culler.traverses_hierarchy() {
            world.refit()
        } else {
            Duration::ZERO
        };
        let input = FrameInput {
            frame: step.frame,
            camera: step.camera,
            resolution: self.options.resolution,
            scene: &world.scene,
            hierarchy: &world.hierarchy,
            moved: world.moved(),
            reference_visible: visible.filter(|_| culler.needs_reference()),
            previous: self.previous[k],
            warm_up: step.warm_up,
        };
        let resources = FrameResources {
            gpu,
            renderer: &self.renderer,
            targets: &self.targets,
            queries: &mut self.queries,
            timer: self.timer.as_ref(),
            draw_queue: &mut self.draw_queue,
            ops: &mut self.ops,
        };
        let mut ctx = FrameCtx::begin(resources, k, input.camera, &mut self.drawn[k]);
        let cull_start = Instant::now();
        let mut traversal = culler.frame(&mut ctx, &input);
        let cull_end = Instant::now();
        let cull_time = cull_end - cull_start;
        let mut outcome = ctx.finish();
        let frame_time = frame_start.elapsed();
        // Untimed: what the mode's own GPU work drew and tested.
        let audit = culler.audit(gpu, &input, &mut self.drawn[k]);
        if let Some(audit) = &audit {
            outcome.add_gpu_audit(audit);
            traversal.add_gpu_audit(audit);
        }
        // Untimed: the colour of a mode's frame, kept for a picture before
        // the next mode draws over it.
        if let Some(kept) = self.colours.get(k) {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let color = &self.targets.color_texture;
            encoder.copy_texture_to_texture(color.as_image_copy(), kept.as_image_copy(), color.size());
            gpu.queue.submit([encoder.finish()]);
            gpu.wait_idle();
        }
        let clocks = ModeClocks {
            frame_start,
            refit: refit_time,
            culling: cull_start..cull_end,
            ops: self.ops.clone(),
            audit,
        };
        let (eye, forward) = (input.camera.eye, input.camera.forward());
        let row = FrameStats {
            mode: culler.name().to_string(),
            frame: input.frame,
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
            visible_objects: visible.map(|v| v.len() as u64),
            strategy: culler.pick().map(|p| p.strategy.to_string()),
            probe: culler.pick().map(|p| p.probe),
            eye_x: Some(eye.x),
            eye_y: Some(eye.y),
            eye_z: Some(eye.z),
            forward_x: Some(forward.x),
            forward_y: Some(forward.y),
            forward_z: Some(forward.z),
        };
        (row, clocks)
    }

    /// Untimed, after every mode ran: each mode's GPU time, timeline and
    /// error against the reference (`visible`), and what it carries into
    /// the next frame.
    fn end_frame(
        &mut self,
        ran: Vec<Option<(FrameStats, ModeClocks)>>,
        visible: Option<&ObjectSet>,
        scene: &Scene,
    ) -> Result<Vec<FrameStats>, GpuError> {
        let gpu = self.gpu;
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
        let gpu_spans = self.timer.as_mut().map(|t| t.read_spans(gpu));
        self.timelines.clear();
        let rows = ran
            .into_iter()
            .enumerate()
            .map(|(k, ran)| {
                let (mut row, clocks) = ran.expect("every mode ran this frame");
                let gpu_frame = gpu_spans.as_ref().map(|spans| spans[k]);
                row.gpu_ms = gpu_frame.map(|span| span.ms());
                self.timelines
                    .push(clocks.timeline(self.started, gpu_frame, row.frame_ms));
                if let (Some(wrong), Some(visible)) = (&wrong, visible) {
                    row.error_pixels = Some(wrong[k].wrong_pixels);
                    row.max_depth_error = Some(f64::from(wrong[k].max_difference));
                    let missed = visible.count_missing_from(&self.drawn[k]) as u64;
                    row.missed_objects = Some(missed);
                    if wrong[k].wrong_pixels > 0 || missed > 0 {
                        self.name_what_was_missed(k, &row, visible, scene);
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

    /// From now on, keeps a copy of what each mode drew in each frame (the
    /// session's colour target is shared: each mode's frame draws over the
    /// last one's), for [`Session::colour`].
    pub fn keep_colours(&mut self) {
        let n = self.drawn.len();
        self.colours = (0..n)
            .map(|_| picture_target(self.gpu, self.options.resolution))
            .collect();
    }

    /// What mode `k` drew in the last frame, shaded, as RGB rows from the
    /// top left; `None` unless the session keeps colours.
    pub fn colour(&self, k: usize) -> Option<Vec<u8>> {
        let kept = self.colours.get(k)?;
        Some(read_rgb(self.gpu, kept, self.options.resolution))
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

/// Which frame a mode runs: its number, camera, and whether it is a
/// warm-up frame.
#[derive(Clone, Copy)]
struct Step<'c> {
    frame: u32,
    camera: &'c Camera,
    warm_up: bool,
}

/// When the parts of a mode's frame ran, until its GPU time is known.
struct ModeClocks {
    frame_start: Instant,
    refit: Duration,
    culling: std::ops::Range<Instant>,
    ops: Vec<OpSpan>,
    audit: Option<GpuAudit>,
}

impl ModeClocks {
    fn timeline(&self, run_start: Instant, gpu_frame: Option<crate::gpu::GpuSpan>, frame_ms: f64) -> FrameTimeline {
        let cpu = CpuClock {
            run_start,
            frame_start: self.frame_start,
            refit: self.refit,
            culling: self.culling.clone(),
            ops: &self.ops,
        };
        let gpu = gpu_frame.map(|frame| GpuClock {
            frame,
            walk: self.audit.and_then(|a| a.cull_gpu),
            pyramid: self.audit.and_then(|a| a.pyramid_gpu),
        });
        FrameTimeline::new(&cpu, gpu.as_ref(), frame_ms)
    }
}

/// Milliseconds, rounded to 0.1 µs (finer than any timer here resolves).
pub(crate) fn ms(d: Duration) -> f64 {
    (d.as_secs_f64() * 1e7).round() / 1e4
}
