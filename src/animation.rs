//! Animated flythroughs: what each mode drew, frame after frame, side by
//! side, in one animated PNG (APNG), which browsers, GitHub READMEs and
//! pull requests play.
//!
//! Each frame of the animation holds a panel per mode: the mode's picture
//! as `occlu render` paints it ([`Painter`]: shaded or its depth
//! complexity, the overview beside it on request), shrunk by `scale` (each
//! pixel the mean of the `scale` × `scale` pixels it covers, rounded), under
//! a caption with the mode, the frame and its frame time. Panels sit side by
//! side in the order of the modes, in rows at most [`ROW_WIDTH`] pixels
//! wide. Frames are kept deflated in memory until the last; then, unless
//! true colour is asked for, one palette of 256 colours is made for the
//! whole animation from a sample of every frame's pixels, which keeps 120
//! frames of two modes with their overviews at 800×600 under 10 MB.

use std::ops::ControlFlow;
use std::str::FromStr;

use crate::camera::Camera;
use crate::camera::path::CameraPath;
use crate::cull::Culler;
use crate::gpu::{GpuContext, GpuError};
use crate::measure::FrameStats;
use crate::picture::{LEAD_IN, Look, Painter, Picture, PictureError, session_for};
use crate::report::charts::{CAPTION_GREY, caption};
use crate::session::Session;
use crate::world::World;

/// The widest a row of panels gets, in pixels (at least one panel a row).
pub const ROW_WIDTH: u32 = 1600;
/// Caption height in pixels.
pub const CAPTION: u32 = 20;
/// Path frames a second: a path frame lasts 1/30 s, as `occlu export`
/// animates paths.
const FRAMES_A_SECOND: u16 = 30;
/// Palette pixels sampled over a whole animation, about.
const SAMPLES: u64 = 1 << 20;

/// Frames `start..end` of a path, every `step`-th of them pictured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub start: u32,
    pub end: u32,
    pub step: u32,
}

impl FrameRange {
    /// Every frame of a path of `frames`.
    pub fn all(frames: u32) -> FrameRange {
        FrameRange {
            start: 0,
            end: frames,
            step: 1,
        }
    }

    /// Whether `frame` is pictured.
    pub fn pictures(&self, frame: u32) -> bool {
        (self.start..self.end).contains(&frame) && (frame - self.start).is_multiple_of(self.step)
    }

    /// How many frames are pictured.
    pub fn pictured(&self) -> u32 {
        (self.end - self.start).div_ceil(self.step)
    }

    /// Whether the range lies within a path of `frames`.
    pub fn check(&self, frames: u32) -> Result<(), AnimationError> {
        if self.end > frames {
            return Err(AnimationError::RangeBeyondPath {
                range: format!("{}..{}", self.start, self.end),
                frames,
            });
        }
        Ok(())
    }
}

impl FromStr for FrameRange {
    type Err = String;

    /// `A..B` (frames A to B − 1) or `A..B:STEP`.
    fn from_str(s: &str) -> Result<FrameRange, String> {
        let bad = || format!("'{s}' is not A..B or A..B:STEP (frames A to B-1, every STEP-th)");
        let (range, step) = s.split_once(':').unwrap_or((s, "1"));
        let (start, end) = range.split_once("..").ok_or_else(bad)?;
        let number = |t: &str| t.trim().parse::<u32>().map_err(|_| bad());
        let range = FrameRange {
            start: number(start)?,
            end: number(end)?,
            step: number(step)?,
        };
        if range.start >= range.end || range.step == 0 {
            return Err(format!("'{s}' is empty: A..B needs A < B, and STEP at least 1"));
        }
        Ok(range)
    }
}

/// How an animation looks.
#[derive(Clone, Copy, Debug)]
pub struct AnimationOptions {
    /// How each mode's picture is painted.
    pub look: Look,
    /// Panels are the pictures shrunk by this (1 to [`MAX_SCALE`]).
    pub scale: u32,
    /// Every pixel as painted (24-bit) instead of one palette of 256
    /// colours: exact, and about three times larger.
    pub true_colour: bool,
}

pub const DEFAULT_SCALE: u32 = 2;
pub const MAX_SCALE: u32 = 8;

/// An animation, encoded.
pub struct Animation {
    /// The APNG file.
    pub png: Vec<u8>,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
}

#[derive(Debug, thiserror::Error)]
pub enum AnimationError {
    #[error("--range {range}: the path has {frames} frames (0..{frames})")]
    RangeBeyondPath { range: String, frames: u32 },
    #[error("--scale must be in 1..={MAX_SCALE}")]
    Scale,
    #[error("writing a caption failed: {0}")]
    Caption(String),
    #[error("encoding the animation failed: {0}")]
    Encoding(String),
    #[error(transparent)]
    Picture(#[from] PictureError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The caller asked the flythrough to stop (Ctrl-C); nothing was written.
    #[error("interrupted: no animation written")]
    Interrupted,
}

impl AnimationError {
    /// Whether the user's input was at fault (as opposed to the GPU).
    pub fn is_input_error(&self) -> bool {
        match self {
            AnimationError::RangeBeyondPath { .. } | AnimationError::Scale => true,
            AnimationError::Picture(e) => e.is_input_error(),
            AnimationError::Gpu(e) => e.is_input_error(),
            AnimationError::Caption(_) | AnimationError::Encoding(_) | AnimationError::Interrupted => false,
        }
    }
}

/// `occlu flythrough`: the frames of `range` in every one of `cullers`,
/// after the [`LEAD_IN`] frames before its first (as `occlu render` runs
/// one), every frame of the range run and every `step`-th pictured; the
/// pictures, to be encoded. `progress` hears (frames done, frames in all),
/// the lead-in first; when it breaks, the flythrough stops with
/// [`AnimationError::Interrupted`].
pub fn flythrough(
    gpu: &GpuContext,
    world: &mut World,
    path: &CameraPath,
    cullers: &mut [Box<dyn Culler + '_>],
    options: &AnimationOptions,
    range: FrameRange,
    progress: &mut dyn FnMut(u32, u32) -> ControlFlow<()>,
) -> Result<Reel, AnimationError> {
    range.check(path.frames)?;
    let mut session = session_for(gpu, world, cullers, &options.look)?;
    let mut film = Filmstrip::new(gpu, &mut session, cullers, options, range)?;
    let aspect = options.look.resolution.aspect();
    let lead_in = range.start.saturating_sub(LEAD_IN)..range.start;
    let total = lead_in.len() as u32 + (range.end - range.start);
    for (done, frame) in lead_in.clone().chain(range.start..range.end).enumerate() {
        world.advance(frame);
        let camera = path.camera(frame, aspect);
        // The modes take turns at going first, as in a bench.
        if lead_in.contains(&frame) {
            session.warm_up_frame(frame, &camera, world, cullers, done)?;
        } else {
            let rows = session.frame(frame, &camera, world, cullers, done)?;
            film.capture(&mut session, world, &camera, cullers, &rows)?;
        }
        if progress(done as u32 + 1, total).is_break() {
            return Err(AnimationError::Interrupted);
        }
    }
    Ok(film.reel)
}

/// An animation being recorded from a session's frames.
pub struct Filmstrip<'g> {
    painter: Painter<'g>,
    /// What it recorded so far.
    pub reel: Reel,
}

/// The pictured frames of an animation, to be encoded.
pub struct Reel {
    options: AnimationOptions,
    range: FrameRange,
    /// Each pictured frame so far, deflated (an RGB PNG).
    frames: Vec<Vec<u8>>,
    /// The frames' size, once the first is made.
    size: Option<(u32, u32)>,
    /// Pixels for the palette (RGBA, as NeuQuant takes them), one every
    /// `sample_every` of every frame.
    sample: Vec<u8>,
    sample_every: usize,
}

impl<'g> Filmstrip<'g> {
    /// An animation of the frames of `range` that [`Filmstrip::capture`]
    /// is given, from `session` (which from now on keeps each mode's
    /// colour).
    pub fn new(
        gpu: &'g GpuContext,
        session: &mut Session,
        cullers: &[Box<dyn Culler + '_>],
        options: &AnimationOptions,
        range: FrameRange,
    ) -> Result<Filmstrip<'g>, AnimationError> {
        if !(1..=MAX_SCALE).contains(&options.scale) {
            return Err(AnimationError::Scale);
        }
        Ok(Filmstrip {
            painter: Painter::new(gpu, session, cullers, &options.look)?,
            reel: Reel {
                options: *options,
                range,
                frames: Vec::new(),
                size: None,
                sample: Vec::new(),
                sample_every: 1,
            },
        })
    }

    /// Adds the frame `session` just ran (seen from `camera`, measured as
    /// `rows`, one per mode) when the range pictures it.
    pub fn capture(
        &mut self,
        session: &mut Session,
        world: &World,
        camera: &Camera,
        cullers: &[Box<dyn Culler + '_>],
        rows: &[FrameStats],
    ) -> Result<(), AnimationError> {
        let Some(frame) = rows.first().map(|r| r.frame) else {
            return Ok(());
        };
        if !self.reel.range.pictures(frame) {
            return Ok(());
        }
        let pictures = self.painter.paint(session, world, frame, camera, cullers)?;
        self.reel.add(&pictures, rows)
    }
}

impl Reel {
    /// Frames pictured so far.
    pub fn frames(&self) -> u32 {
        self.frames.len() as u32
    }

    /// Adds a frame: one picture per mode, measured as `rows`.
    fn add(&mut self, pictures: &[Picture], rows: &[FrameStats]) -> Result<(), AnimationError> {
        let (width, height, rgb) = self.compose(pictures, rows)?;
        if self.size.is_none() {
            let pixels = u64::from(width) * u64::from(height) * u64::from(self.range.pictured());
            self.sample_every = (pixels / SAMPLES).max(1) as usize;
            self.size = Some((width, height));
        }
        for pixel in rgb.chunks_exact(3).step_by(self.sample_every) {
            self.sample.extend_from_slice(&[pixel[0], pixel[1], pixel[2], 255]);
        }
        let still = PngFormat {
            width,
            height,
            colour: png::ColorType::Rgb,
            palette: None,
            compression: png::Compression::Fast,
        };
        let deflated = encode(&still, None, [Ok(rgb)])?;
        self.frames.push(deflated);
        Ok(())
    }

    /// The panels of one frame side by side: each picture shrunk, under its
    /// caption.
    fn compose(&self, pictures: &[Picture], rows: &[FrameStats]) -> Result<(u32, u32, Vec<u8>), AnimationError> {
        // A picture smaller than the scale is shrunk to one pixel, not none.
        let (picture_w, picture_h) = (pictures[0].width, pictures[0].height);
        let scale = self.options.scale.min(picture_w).min(picture_h).max(1);
        let (panel_w, picture_h) = (picture_w / scale, picture_h / scale);
        let panel_h = CAPTION + picture_h;
        let columns = (ROW_WIDTH / panel_w).clamp(1, pictures.len() as u32);
        let lines = (pictures.len() as u32).div_ceil(columns);
        let (width, height) = (columns * panel_w, lines * panel_h);
        let grey = [CAPTION_GREY.0, CAPTION_GREY.1, CAPTION_GREY.2];
        let mut rgb: Vec<u8> = grey.repeat((width * height) as usize);
        for (k, (picture, row)) in pictures.iter().zip(rows).enumerate() {
            let (x, y) = ((k as u32 % columns) * panel_w, (k as u32 / columns) * panel_h);
            let text = format!("{}   frame {}   {:.2} ms", row.mode, row.frame, row.frame_ms);
            let strip = caption(panel_w, CAPTION, &text).map_err(|e| AnimationError::Caption(e.to_string()))?;
            blit(&mut rgb, width, (x, y), &strip, panel_w);
            let small = shrink(&picture.rgb, picture.width, picture.height, scale);
            blit(&mut rgb, width, (x, y + CAPTION), &small, panel_w);
        }
        Ok((width, height, rgb))
    }

    /// The animation of every frame pictured. `progress` hears (frames
    /// encoded, frames in all) as each frame is written; when it breaks,
    /// encoding stops with [`AnimationError::Interrupted`].
    pub fn encode(self, progress: &mut dyn FnMut(u32, u32) -> ControlFlow<()>) -> Result<Animation, AnimationError> {
        let Some((width, height)) = self.size else {
            return Err(AnimationError::Encoding("no frame was pictured".into()));
        };
        let count = self.frames();
        let delay = Some((u16::try_from(self.range.step).unwrap_or(u16::MAX), FRAMES_A_SECOND));
        // One frame at a time: all frames' pixels at once would take 1.5 GB
        // for a default bench --animate (120 frames of twelve modes).
        let rgb_frames = self.frames.iter().enumerate().map(|(done, deflated)| {
            if progress(done as u32, count).is_break() {
                return Err(AnimationError::Interrupted);
            }
            decode_png(deflated)
        });
        let png = if self.options.true_colour {
            let format = PngFormat {
                width,
                height,
                colour: png::ColorType::Rgb,
                palette: None,
                compression: png::Compression::Best,
            };
            encode(&format, delay, rgb_frames)?
        } else {
            let palette = color_quant::NeuQuant::new(10, 256, &self.sample);
            let mut lookup: foldhash::HashMap<[u8; 3], u8> = foldhash::HashMap::default();
            let indexed = rgb_frames.map(|rgb| {
                Ok(rgb?
                    .chunks_exact(3)
                    .map(|p| {
                        *lookup
                            .entry([p[0], p[1], p[2]])
                            .or_insert_with(|| palette.index_of(&[p[0], p[1], p[2], 255]) as u8)
                    })
                    .collect::<Vec<u8>>())
            });
            let format = PngFormat {
                width,
                height,
                colour: png::ColorType::Indexed,
                palette: Some(palette.color_map_rgb()),
                compression: png::Compression::Best,
            };
            encode(&format, delay, indexed)?
        };
        if progress(count, count).is_break() {
            return Err(AnimationError::Interrupted);
        }
        Ok(Animation {
            png,
            width,
            height,
            frames: count,
        })
    }
}

/// `rgb` (`width` × `height`) shrunk by `scale`: each pixel the mean of
/// the `scale` × `scale` pixels it covers, rounded half up (columns and
/// rows beyond the last whole block are dropped).
pub fn shrink(rgb: &[u8], width: u32, height: u32, scale: u32) -> Vec<u8> {
    let (w, h, s) = (width / scale, height / scale, scale as usize);
    let (row, n) = (width as usize * 3, (s * s) as u32);
    let mut out = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h as usize {
        for x in 0..w as usize {
            for c in 0..3 {
                let sum: u32 = (0..s)
                    .flat_map(|dy| (0..s).map(move |dx| (y * s + dy) * row + (x * s + dx) * 3 + c))
                    .map(|i| u32::from(rgb[i]))
                    .sum();
                out.push(((sum + n / 2) / n) as u8);
            }
        }
    }
    out
}

/// Copies `part` (rows of `part_width` RGB pixels) into `rgb` (rows of
/// `width`) with its top left at `at`.
fn blit(rgb: &mut [u8], width: u32, at: (u32, u32), part: &[u8], part_width: u32) {
    let (row, part_row) = (width as usize * 3, part_width as usize * 3);
    for (dy, line) in part.chunks_exact(part_row).enumerate() {
        let start = (at.1 as usize + dy) * row + at.0 as usize * 3;
        rgb[start..start + part_row].copy_from_slice(line);
    }
}

fn encoding(e: impl std::fmt::Display) -> AnimationError {
    AnimationError::Encoding(e.to_string())
}

/// How a PNG's pixels are stored.
struct PngFormat {
    width: u32,
    height: u32,
    colour: png::ColorType,
    palette: Option<Vec<u8>>,
    compression: png::Compression,
}

/// A PNG of `frames`, each made as it is written (the first error ends
/// it): one, a still; with a `delay` = (numerator, denominator) seconds a
/// frame, an animation that loops.
fn encode(
    format: &PngFormat,
    delay: Option<(u16, u16)>,
    frames: impl IntoIterator<Item = Result<Vec<u8>, AnimationError>, IntoIter: ExactSizeIterator>,
) -> Result<Vec<u8>, AnimationError> {
    let frames = frames.into_iter();
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, format.width, format.height);
        encoder.set_color(format.colour);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(format.compression);
        if let Some(palette) = &format.palette {
            encoder.set_palette(palette.clone());
        }
        if let Some((numerator, denominator)) = delay {
            encoder.set_animated(frames.len() as u32, 0).map_err(encoding)?;
            encoder.set_frame_delay(numerator, denominator).map_err(encoding)?;
        }
        let mut writer = encoder.write_header().map_err(encoding)?;
        for frame in frames {
            writer.write_image_data(&frame?).map_err(encoding)?;
        }
        writer.finish().map_err(encoding)?;
    }
    Ok(out)
}

/// The pixels of an RGB PNG this module made.
fn decode_png(bytes: &[u8]) -> Result<Vec<u8>, AnimationError> {
    let mut reader = png::Decoder::new(bytes).read_info().map_err(encoding)?;
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).map_err(encoding)?;
    rgb.truncate(info.buffer_size());
    Ok(rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_read_as_rust_writes_them_with_a_step() {
        let r: FrameRange = "10..20:3".parse().unwrap();
        assert_eq!((r.start, r.end, r.step), (10, 20, 3));
        assert_eq!(r.pictured(), 4, "10, 13, 16, 19");
        assert!(r.pictures(19) && !r.pictures(20) && !r.pictures(11) && !r.pictures(7));
        assert_eq!("0..120".parse::<FrameRange>().unwrap(), FrameRange::all(120));
        for bad in ["5..5", "7..3", "0..4:0", "0-4", "a..b", "1..2:x", ""] {
            assert!(bad.parse::<FrameRange>().is_err(), "{bad}");
        }
    }

    /// A reel of `n` frames of 4 × 2 pixels, frame k grey level 40 k.
    fn reel_of(n: u32, true_colour: bool) -> Reel {
        let still = PngFormat {
            width: 4,
            height: 2,
            colour: png::ColorType::Rgb,
            palette: None,
            compression: png::Compression::Fast,
        };
        let grey = |k: u32| vec![(40 * k) as u8; 4 * 2 * 3];
        Reel {
            options: AnimationOptions {
                look: Look {
                    resolution: crate::gpu::Resolution::DEFAULT,
                    overview: false,
                    heat: false,
                    show_missed: false,
                    occluders: false,
                },
                scale: 1,
                true_colour,
            },
            range: FrameRange::all(n),
            frames: (0..n).map(|k| encode(&still, None, [Ok(grey(k))]).unwrap()).collect(),
            size: Some((4, 2)),
            sample: (0..n)
                .flat_map(|k| [(40 * k) as u8, (40 * k) as u8, (40 * k) as u8, 255])
                .collect(),
            sample_every: 1,
        }
    }

    #[test]
    fn encoding_says_how_far_it_got_and_stops_when_asked() {
        for true_colour in [true, false] {
            let mut heard = Vec::new();
            let animation = reel_of(3, true_colour)
                .encode(&mut |done, total| {
                    heard.push((done, total));
                    ControlFlow::Continue(())
                })
                .unwrap();
            assert_eq!(heard, [(0, 3), (1, 3), (2, 3), (3, 3)]);
            assert_eq!((animation.width, animation.height, animation.frames), (4, 2, 3));
            let mut decoder = png::Decoder::new(animation.png.as_slice());
            decoder.set_transformations(png::Transformations::EXPAND);
            let mut reader = decoder.read_info().unwrap();
            assert_eq!(reader.info().animation_control.unwrap().num_frames, 3);
            for k in 0..3 {
                let mut rgb = vec![0; reader.output_buffer_size()];
                reader.next_frame(&mut rgb).unwrap();
                // Exact in true colour; the palette's nearest colour else.
                let off = if true_colour { 0 } else { 20 };
                assert!(
                    rgb.iter().all(|&c| c.abs_diff((40 * k) as u8) <= off),
                    "frame {k}: {rgb:?}"
                );
            }

            let mut heard = Vec::new();
            let stopped = reel_of(3, true_colour).encode(&mut |done, _| {
                heard.push(done);
                if done == 1 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
            assert!(matches!(stopped, Err(AnimationError::Interrupted)));
            assert_eq!(heard, [0, 1], "nothing encoded after the break");
            assert!(matches!(
                crate::bench::BenchError::from(AnimationError::Interrupted),
                crate::bench::BenchError::Interrupted
            ));
        }
    }

    #[test]
    fn shrinking_averages_each_block_and_drops_the_rest() {
        // 3 × 2 pixels, grey levels 0, 10, 20 over 30, 40, 50, shrunk by 2:
        // one pixel, the mean of 0, 10, 30, 40 (20); the third column goes.
        let rgb: Vec<u8> = [0u8, 10, 20, 30, 40, 50]
            .iter()
            .flat_map(|&v| [v, v, 255 - v])
            .collect();
        assert_eq!(shrink(&rgb, 3, 2, 2), [20, 20, 235]);
        // Halves round up: (1 + 2 + 2 + 2) / 4 = 1.75 → 2, (0 + 0 + 0 + 2) / 4 = 0.5 → 1.
        let rgb = [1, 0, 0, 2, 0, 0, 2, 0, 0, 2, 0, 2];
        assert_eq!(shrink(&rgb, 2, 2, 2), [2, 0, 1]);
        assert_eq!(shrink(&rgb, 2, 2, 1), rgb);
    }
}
