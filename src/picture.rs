//! `occlu render`: a picture of one frame of one mode.
//!
//! The mode renders the frame through the same [`Session`] a benchmark
//! uses, after the two frames before it (so modes that carry state from
//! frame to frame, like omq's `max_tests` or ac's budget, are in their
//! usual state). The picture is what the mode drew, shaded; or, with
//! `heat`, its depth complexity: how many surfaces it drew over each pixel
//! (the IOC paper's Figure 1). With `overview`, a bird's-eye view of the
//! whole scene is placed beside it, with the mode's frustum in red and the
//! boxes of objects inside the frustum that the mode did not draw in yellow,
//! as the papers' figures mark culled bounding volumes. With `show_missed`,
//! the frame is compared with direct rendering: pixels whose depth differs
//! turn magenta and the boxes of the objects the mode got wrong are
//! outlined in magenta, so the picture shows a culling bug. With
//! `occluders`, the depth buffer a CPU culling mode culled the frame
//! with is laid over it: each cell holding an occluder's depth in a colour
//! from near (white) to far (deep blue), the frame dimmed where no cell
//! holds one, so the picture shows what could hide what.

use glam::DVec3;

use crate::bounds::Aabb;
use crate::camera::path::CameraPath;
use crate::camera::{Camera, Containment, Frustum, look_rotation};
use crate::cull::{Culler, OccluderDepths};
use crate::gpu::{
    Draws, GpuContext, GpuError, LinePainter, LineVertex, RenderTargets, Resolution, picture_target, read_rgb,
};
use crate::measure::MissedObject;
use crate::object_set::ObjectSet;
use crate::scene::{Focus, Object, Scene};
use crate::session::{RunOptions, Session};
use crate::world::World;

/// How a mode's frame is pictured: at what size, and what is added to it.
#[derive(Clone, Copy, Debug)]
pub struct Look {
    pub resolution: Resolution,
    pub overview: bool,
    pub heat: bool,
    pub show_missed: bool,
    pub occluders: bool,
}

/// What a mode got wrong in the pictured frame (with `show_missed`).
pub struct WrongInFrame {
    /// Pixels whose depth differs from direct rendering.
    pub pixels: u64,
    /// The objects missed or wrong there (missed.csv's rows for the frame).
    pub objects: Vec<MissedObject>,
}

/// An RGB image and what it shows.
pub struct Picture {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    /// Objects the mode drew in the frame.
    pub drawn: usize,
    /// Objects inside the frustum it did not draw (the yellow boxes).
    pub culled_in_frustum: usize,
    /// With `show_missed`: what it got wrong.
    pub wrong: Option<WrongInFrame>,
    /// With `occluders`: the pixels the mode's buffer holds an occluder's
    /// depth for, those occluders cover in part of their cell (its working
    /// layer), and all of them.
    pub occluder_pixels: Option<[usize; 3]>,
}

#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    #[error("--frame {frame} is beyond the path's {frames} frames (0..={})", frames - 1)]
    FrameOutOfRange { frame: u32, frames: u32 },
    #[error("--occluders: mode '{mode}' keeps no depth buffer on the CPU (CPU software occlusion culling does)")]
    NoOccluderDepths { mode: String },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl PictureError {
    /// Whether the user's input was at fault (as opposed to the GPU).
    pub fn is_input_error(&self) -> bool {
        match self {
            PictureError::Gpu(e) => e.is_input_error(),
            PictureError::FrameOutOfRange { .. } | PictureError::NoOccluderDepths { .. } => true,
        }
    }
}

/// Frames run before the pictured one, for the mode's temporal state.
pub const LEAD_IN: u32 = 2;

const YELLOW: [f32; 3] = [1.0, 0.85, 0.0];
const RED: [f32; 3] = [0.9, 0.1, 0.1];
const MAGENTA: [f32; 3] = [1.0, 0.0, 1.0];

/// Frame `frame` of `path` as `culler` draws it, after the [`LEAD_IN`]
/// frames before it.
pub fn render(
    gpu: &GpuContext,
    world: &mut World,
    path: &CameraPath,
    culler: Box<dyn Culler>,
    frame: u32,
    look: &Look,
) -> Result<Picture, PictureError> {
    if frame >= path.frames {
        return Err(PictureError::FrameOutOfRange {
            frame,
            frames: path.frames,
        });
    }
    let mut cullers = [culler];
    let mut session = session_for(gpu, world, &mut cullers, look)?;
    let mut painter = Painter::new(gpu, &mut session, &cullers, look)?;
    let aspect = look.resolution.aspect();
    for f in frame.saturating_sub(LEAD_IN)..frame {
        world.advance(f);
        session.warm_up_frame(f, &path.camera(f, aspect), world, &mut cullers, 0)?;
    }
    world.advance(frame);
    let camera = path.camera(frame, aspect);
    session.frame(frame, &camera, world, &mut cullers, 0)?;
    let [picture] = painter
        .paint(&mut session, world, frame, &camera, &cullers)?
        .try_into()
        .unwrap_or_else(|_| unreachable!("one picture for one mode"));
    Ok(picture)
}

/// A session of `cullers` that renders what `look` needs: the reference
/// only to show what was missed.
pub fn session_for<'g>(
    gpu: &'g GpuContext,
    world: &World,
    cullers: &mut [Box<dyn Culler + '_>],
    look: &Look,
) -> Result<Session<'g>, GpuError> {
    let run = RunOptions {
        warmup: 0,
        resolution: look.resolution,
        measure_error: look.show_missed,
    };
    Session::new(gpu, world, cullers, look.show_missed, &run)
}

/// Paints what each mode of a [`Session`] showed in its last frame, as
/// `occlu render` does for one: what it drew, shaded (or its depth
/// complexity), with what the [`Look`] adds.
pub struct Painter<'g> {
    gpu: &'g GpuContext,
    look: Look,
    lines: LinePainter,
    /// The overview's targets: the scene from above, drawn once a frame,
    /// and a copy each mode's lines are drawn over.
    overview: Option<(RenderTargets, wgpu::Texture)>,
    /// Where the overview looks from, found once, on the first frame
    /// painted: the scene's focus reads every triangle of a large one-mesh
    /// model, and what moves (a city's cars) is too small to change it.
    above: Option<Camera>,
}

impl<'g> Painter<'g> {
    /// A painter of `session`'s frames (which from now on keeps each mode's
    /// colour). Fails on `occluders` for a mode that keeps no CPU depth
    /// buffer.
    pub fn new(
        gpu: &'g GpuContext,
        session: &mut Session,
        cullers: &[Box<dyn Culler + '_>],
        look: &Look,
    ) -> Result<Painter<'g>, PictureError> {
        // A mode keeps its buffer from `prepare` on, before any frame is spent.
        if let Some(mode) = cullers.iter().find(|c| look.occluders && c.occluder_depths().is_none()) {
            return Err(PictureError::NoOccluderDepths {
                mode: mode.name().to_string(),
            });
        }
        session.keep_colours();
        let resolution = look.resolution;
        Ok(Painter {
            gpu,
            look: *look,
            lines: LinePainter::new(gpu, session.renderer.camera_uniform()),
            overview: look
                .overview
                .then(|| (RenderTargets::new(gpu, resolution, 1), picture_target(gpu, resolution))),
            above: None,
        })
    }

    /// The picture of each mode (in the order of `cullers`, the session's)
    /// in the session's last frame, `frame`, seen from `camera` in `world`.
    pub fn paint(
        &mut self,
        session: &mut Session,
        world: &World,
        frame: u32,
        camera: &Camera,
        cullers: &[Box<dyn Culler + '_>],
    ) -> Result<Vec<Picture>, GpuError> {
        // Each mode's own view first: the frame's camera is still in the
        // uniform that depth complexity and outlines are drawn with.
        let mut pictures = Vec::with_capacity(cullers.len());
        for (k, culler) in cullers.iter().enumerate() {
            pictures.push(self.mode_view(session, &world.scene, frame, camera, k, culler.as_ref()));
        }
        self.add_overviews(session, &world.scene, camera, &mut pictures);
        // A picture the GPU failed in shows nothing true.
        self.gpu.check()?;
        Ok(pictures)
    }

    /// The session's mode `k` (`culler`) in its last frame, `frame`, as
    /// seen from `camera`: what it drew, shaded or by depth complexity,
    /// with the occluders and the pixels and objects it got wrong when the
    /// look asks for them.
    fn mode_view(
        &self,
        session: &mut Session,
        scene: &Scene,
        frame: u32,
        camera: &Camera,
        k: usize,
        culler: &dyn Culler,
    ) -> Picture {
        let (gpu, look, resolution) = (self.gpu, self.look, self.look.resolution);
        let drawn: Vec<u32> = session.drawn[k].iter().collect();
        let culled = culled_in_frustum(scene, &session.drawn[k], &camera.frustum()).count();
        let mut rgb = if look.heat {
            let target = picture_target(gpu, resolution);
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let view = target.create_view(&Default::default());
            session.renderer.encode_depth_complexity(&mut encoder, &view, &drawn);
            gpu.queue.submit([encoder.finish()]);
            heat_colours(&read_rgb(gpu, &target, resolution))
        } else {
            session.colour(k).expect("the painter keeps every mode's colour")
        };
        let occluders = look.occluders.then(|| culler.occluder_depths()).flatten();
        if let Some(depths) = &occluders {
            paint_occluder_depths(depths, &mut rgb);
        }
        let wrong = look.show_missed.then(|| {
            let objects: Vec<MissedObject> = session
                .missed
                .iter()
                .filter(|m| m.mode == culler.name() && m.frame == frame)
                .cloned()
                .collect();
            self.mark_wrong(session, scene, camera, k, objects, &mut rgb)
        });
        Picture {
            width: resolution.width,
            height: resolution.height,
            rgb,
            drawn: drawn.len(),
            culled_in_frustum: culled,
            wrong,
            occluder_pixels: occluders.map(|d| {
                let written = d.depths.iter().filter(|&&c| c > 0.0).count();
                [written, d.partial.iter().filter(|&&p| p).count(), d.depths.len()]
            }),
        }
    }

    /// Marks on `rgb` what the session's mode `k` got wrong in its last
    /// frame: its wrong pixels in magenta, and the boxes of `objects` (the
    /// objects it got wrong there) outlined in magenta as seen from
    /// `camera`.
    fn mark_wrong(
        &self,
        session: &mut Session,
        scene: &Scene,
        camera: &Camera,
        k: usize,
        objects: Vec<MissedObject>,
        rgb: &mut [u8],
    ) -> WrongInFrame {
        let (gpu, resolution) = (self.gpu, self.look.resolution);
        let pixels = paint_wrong_pixels(session, k, rgb);
        let mut lines = Vec::new();
        for m in &objects {
            box_lines(
                &scene.objects[m.object as usize].bounds,
                camera.eye,
                MAGENTA,
                &mut lines,
            );
        }
        let target = picture_target(gpu, resolution);
        self.lines.draw(gpu, &target.create_view(&Default::default()), &lines);
        let outlines = read_rgb(gpu, &target, resolution);
        for (pixel, line) in rgb.chunks_mut(3).zip(outlines.chunks(3)) {
            if line != [0, 0, 0] {
                pixel.copy_from_slice(line);
            }
        }
        WrongInFrame { pixels, objects }
    }

    /// With the overview asked for, puts the scene from above beside each
    /// of `pictures` (the session's modes'), with the mode's frustum from
    /// `camera` and the boxes it culled inside it: the scene drawn once,
    /// each mode's lines over a copy of it.
    fn add_overviews(&mut self, session: &mut Session, scene: &Scene, camera: &Camera, pictures: &mut [Picture]) {
        let Some((targets, picture)) = &self.overview else {
            return;
        };
        let (gpu, resolution) = (self.gpu, self.look.resolution);
        let frustum = camera.frustum();
        let above = *self.above.get_or_insert_with(|| overview_camera(scene, resolution));
        session.renderer.set_camera(gpu, &above, resolution, &scene.objects);
        let all: Vec<u32> = (0..scene.objects.len() as u32).collect();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        session.renderer.encode_shaded(
            &mut encoder,
            targets,
            &targets.mode_depths[0],
            true,
            Draws::Objects(&all),
        );
        gpu.queue.submit([encoder.finish()]);
        // The frustum has no far plane: draw it out to the farthest
        // corner of the scene, so every yellow box lies inside the red
        // lines.
        let reach = scene
            .bounds
            .corners()
            .iter()
            .map(|c| c.distance(camera.eye))
            .fold(0.0, f64::max);
        for (k, main) in pictures.iter_mut().enumerate() {
            let mut lines = Vec::new();
            for o in culled_in_frustum(scene, &session.drawn[k], &frustum) {
                box_lines(&o.bounds, above.eye, YELLOW, &mut lines);
            }
            frustum_lines(camera, reach, above.eye, &mut lines);
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_texture_to_texture(
                targets.color_texture.as_image_copy(),
                picture.as_image_copy(),
                picture.size(),
            );
            gpu.queue.submit([encoder.finish()]);
            self.lines.draw(gpu, &picture.create_view(&Default::default()), &lines);
            let side = read_rgb(gpu, picture, resolution);
            main.rgb = side_by_side(&main.rgb, &side, resolution);
            main.width = 2 * resolution.width;
        }
    }
}

/// The objects of `scene` inside `frustum` (or crossing it) that a mode
/// did not draw (`drawn`): the ones it culled, in id order.
fn culled_in_frustum<'s>(scene: &'s Scene, drawn: &ObjectSet, frustum: &Frustum) -> impl Iterator<Item = &'s Object> {
    scene
        .objects
        .iter()
        .enumerate()
        .filter(|&(i, o)| !drawn.contains(i as u32) && frustum.classify(&o.bounds) != Containment::Outside)
        .map(|(_, o)| o)
}

/// Lays `depths` over `rgb` (the pictured frame, of the same size): a
/// pixel the buffer holds a depth for takes that depth's colour, on a ramp
/// over the logarithm of the depths the buffer holds (reverse-Z depth is
/// near / distance, so equal steps are equal ratios of distance), mixed
/// half and half with orange where that depth is a working layer's (a
/// cell occluders cover only in part); the others are dimmed to a third.
fn paint_occluder_depths(depths: &OccluderDepths, rgb: &mut [u8]) {
    let written = || depths.depths.iter().filter(|&&d| d > 0.0).map(|&d| f64::from(d).log2());
    let (farthest, nearest) = written().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
    let span = (nearest - farthest).max(1e-9);
    for ((pixel, &depth), &partial) in rgb.chunks_mut(3).zip(&depths.depths).zip(&depths.partial) {
        if depth > 0.0 {
            let t = (f64::from(depth).log2() - farthest) / span;
            let ramp = [0.1 + 0.9 * t, 0.25 + 0.75 * t, 0.6 + 0.4 * t].map(|c| (c * 255.0).round() as u8);
            match partial {
                true => pixel.copy_from_slice(&[0, 1, 2].map(|c| ramp[c] / 2 + PARTIAL_TINT[c] / 2)),
                false => pixel.copy_from_slice(&ramp),
            }
        } else {
            pixel.iter_mut().for_each(|c| *c /= 3);
        }
    }
}

/// Mixed half and half with a working layer's depth colour: an orange
/// apart from the ramp's blues.
const PARTIAL_TINT: [u8; 3] = [255, 128, 0];

/// Paints magenta the pixels of `rgb` (the pictured frame) whose depth in
/// the session's mode `k` differs from the reference's in any bit; returns
/// how many there are.
fn paint_wrong_pixels(session: &mut Session, k: usize, rgb: &mut [u8]) -> u64 {
    let (Some(reference), Some(mode)) = (session.reference_depth(), session.mode_depth(k)) else {
        return 0;
    };
    let mut wrong = 0;
    for ((pixel, r), m) in rgb.chunks_mut(3).zip(&reference).zip(&mode) {
        if r.to_bits() != m.to_bits() {
            pixel.copy_from_slice(&[255, 0, 255]);
            wrong += 1;
        }
    }
    wrong
}

/// Straight down the scene's up axis on the scene's detail (for +Y up, −Z
/// at the top of the picture), far enough that its focus (the bounds
/// without a huge ground plane or sky dome) fits the view.
fn overview_camera(scene: &Scene, resolution: Resolution) -> Camera {
    let b = Focus::of(scene).bounds;
    let (c, e) = (b.center(), b.extent());
    let up = scene.up.axis.vector();
    let (right, ahead) = scene.up.axis.ground_axes();
    let fov_y = 60f64.to_radians();
    let t = (fov_y / 2.0).tan();
    let (wide, deep) = (e.dot(right.abs()), e.dot(ahead.abs()));
    let height = (deep / (2.0 * t)).max(wide / (2.0 * t * resolution.aspect())).max(1e-3) * 1.1;
    let (_, top) = b.span_along(up);
    Camera {
        eye: c + up * (top - c.dot(up) + height),
        rotation: look_rotation(-up, ahead),
        fov_y,
        near: height * 1e-3,
        aspect: resolution.aspect(),
    }
}

fn line(a: DVec3, b: DVec3, eye: DVec3, colour: [f32; 3], out: &mut Vec<LineVertex>) {
    for p in [a, b] {
        out.push(LineVertex {
            position: (p - eye).as_vec3().to_array(),
            colour,
        });
    }
}

/// The twelve edges of a box.
fn box_lines(b: &Aabb, eye: DVec3, colour: [f32; 3], out: &mut Vec<LineVertex>) {
    let c = b.corners();
    // Corners differing in one bit share an edge.
    for i in 0..8 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                line(c[i], c[i | bit], eye, colour, out);
            }
        }
    }
}

/// The frustum of `camera` out to `reach`: four edges and the far rectangle.
fn frustum_lines(camera: &Camera, reach: f64, eye: DVec3, out: &mut Vec<LineVertex>) {
    let ty = (camera.fov_y / 2.0).tan();
    let tx = ty * camera.aspect;
    let far: Vec<DVec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(sx, sy)| camera.eye + camera.rotation * DVec3::new(sx * tx, sy * ty, -1.0) * reach)
        .collect();
    for k in 0..4 {
        line(camera.eye, far[k], eye, RED, out);
        line(far[k], far[(k + 1) % 4], eye, RED, out);
    }
}

/// Surfaces per pixel (red channel, one step per surface) to a colour ramp:
/// black for none, then blue, cyan, green, yellow, red and white for the
/// deepest pixel of the picture.
fn heat_colours(counts: &[u8]) -> Vec<u8> {
    const RAMP: [[f32; 3]; 7] = [
        [0.0, 0.0, 0.0],
        [0.1, 0.1, 0.6],
        [0.0, 0.6, 0.9],
        [0.1, 0.8, 0.2],
        [1.0, 0.9, 0.0],
        [0.9, 0.1, 0.1],
        [1.0, 1.0, 1.0],
    ];
    let deepest = counts.chunks(3).map(|p| p[0]).max().unwrap_or(0).max(1);
    counts
        .chunks(3)
        .flat_map(|p| {
            let t = (f32::from(p[0]) / f32::from(deepest)).sqrt() * (RAMP.len() - 1) as f32;
            let (i, f) = (t.floor() as usize, t.fract());
            let (a, b) = (RAMP[i.min(RAMP.len() - 1)], RAMP[(i + 1).min(RAMP.len() - 1)]);
            let c = |k: usize| ((a[k] + (b[k] - a[k]) * f) * 255.0).round() as u8;
            if p[0] == 0 { [0, 0, 0] } else { [c(0), c(1), c(2)] }
        })
        .collect()
}

fn side_by_side(left: &[u8], right: &[u8], r: Resolution) -> Vec<u8> {
    let row = (r.width * 3) as usize;
    left.chunks(row)
        .zip(right.chunks(row))
        .flat_map(|(a, b)| a.iter().chain(b).copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_has_twelve_edges_and_a_frustum_eight() {
        let mut lines = Vec::new();
        box_lines(&Aabb::new(DVec3::ZERO, DVec3::ONE), DVec3::ZERO, YELLOW, &mut lines);
        assert_eq!(lines.len(), 24);
        let cam = Camera {
            eye: DVec3::ZERO,
            rotation: look_rotation(DVec3::NEG_Z, DVec3::Y),
            fov_y: 1.0,
            near: 0.1,
            aspect: 1.0,
        };
        lines.clear();
        frustum_lines(&cam, 10.0, DVec3::ZERO, &mut lines);
        assert_eq!(lines.len(), 16);
    }

    #[test]
    fn the_overview_frames_a_room_not_the_huge_plane_it_stands_on() {
        use crate::scene::fixtures::{ROOM, boxes, ground, room};
        let scene = boxes(&[room(), vec![ground()]].concat());
        let resolution = Resolution {
            width: 160,
            height: 120,
        };
        let above = overview_camera(&scene, resolution);
        // The room's corners in the view, in units of its half-height.
        let t = (above.fov_y / 2.0).tan();
        let view = above.view_rotation();
        let (mut x, mut y) = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
        for corner in ROOM.corners() {
            let v = view * (corner - above.eye);
            let (cx, cy) = (v.x / (-v.z * t * above.aspect), v.y / (-v.z * t));
            (x, y) = ((x.0.min(cx), x.1.max(cx)), (y.0.min(cy), y.1.max(cy)));
        }
        assert!(
            x.0 >= -1.0 && x.1 <= 1.0 && y.0 >= -1.0 && y.1 <= 1.0,
            "in view: {x:?} {y:?}"
        );
        assert!(x.1 - x.0 >= 1.5 || y.1 - y.0 >= 1.5, "fills the view: {x:?} {y:?}");
    }

    #[test]
    fn heat_ramp_is_black_for_nothing_and_white_for_the_deepest() {
        let out = heat_colours(&[0, 0, 0, 1, 0, 0, 9, 0, 0]);
        assert_eq!(&out[0..3], &[0, 0, 0]);
        assert_ne!(&out[3..6], &[0, 0, 0]);
        assert_eq!(&out[6..9], &[255, 255, 255]);
    }
}
