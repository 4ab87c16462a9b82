//! When each part of a mode's frame ran, for `bench --trace`: on the CPU
//! the refit, the culling, the commands encoded and submitted and the waits;
//! on the GPU, where the adapter has timestamps, the box tests (and within
//! them a depth pyramid's build) and the drawing.
//!
//! The CPU's stretches are measured on its clock. The GPU's are measured on
//! the GPU's, which no CPU clock shares, so they are placed by what the
//! waits tell: the frame's GPU work ended before the CPU's wait for it
//! returned, and each batch of box tests ended before the wait for its
//! results returned; the GPU's stretches are placed as late as all of these
//! allow (their lengths and the gaps between them are the GPU's own).

use std::ops::Range;
use std::time::{Duration, Instant};

use crate::gpu::{GpuSpan, OpKind, OpSpan};

/// What a stretch of a frame was spent on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// The CPU refitting the shared hierarchy around moved objects.
    Refit,
    /// The CPU deciding what to draw: the mode's frame outside GPU
    /// operations (`cpu_ms`, with the queueing of draws).
    Culling,
    /// The CPU encoding and submitting commands.
    Commands,
    /// The CPU waiting for box tests' results or a mode's read-back.
    WaitForResults,
    /// The CPU waiting for the GPU to finish the frame.
    WaitForGpu,
    /// The GPU testing boxes: query passes, or a GPU walk's passes.
    BoxTests,
    /// The GPU building a depth pyramid, within its box tests.
    Pyramid,
    /// The GPU's frame outside its box tests: drawing, clears and copies.
    Drawing,
}

impl Work {
    pub fn name(self) -> &'static str {
        match self {
            Work::Refit => "refit",
            Work::Culling => "culling",
            Work::Commands => "commands",
            Work::WaitForResults => "wait for results",
            Work::WaitForGpu => "wait for the GPU",
            Work::BoxTests => "box tests",
            Work::Pyramid => "pyramid",
            Work::Drawing => "drawing",
        }
    }
}

/// A stretch of a frame, in milliseconds from the frame's start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stretch {
    pub work: Work,
    pub start_ms: f64,
    pub end_ms: f64,
}

/// One mode's frame, stretch by stretch.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTimeline {
    /// The frame's start, in milliseconds from the run's.
    pub start_ms: f64,
    /// The CPU's stretches: disjoint, in order, within the frame.
    pub cpu: Vec<Stretch>,
    /// The frame's work on the GPU, from its first command to its last
    /// (`gpu_ms` long, where the clocks allow); `None` without timestamps.
    pub gpu_frame: Option<Range<f64>>,
    /// Within it, in order: box tests and drawing, disjoint, and the
    /// pyramid within the box tests it belongs to.
    pub gpu: Vec<Stretch>,
}

/// What a mode's frame did on the CPU's clock.
pub struct CpuClock<'a> {
    pub run_start: Instant,
    pub frame_start: Instant,
    /// The refit at the frame's start.
    pub refit: Duration,
    /// The mode's `frame` call: outside its GPU operations, culling.
    pub culling: Range<Instant>,
    /// Its GPU operations, in order.
    pub ops: &'a [OpSpan],
}

/// What a mode's frame did on the GPU's clock.
pub struct GpuClock {
    /// From the frame's first command to its last.
    pub frame: GpuSpan,
    /// A GPU walk's passes, and within them its pyramid.
    pub walk: Option<GpuSpan>,
    pub pyramid: Option<GpuSpan>,
}

impl FrameTimeline {
    /// The timeline of a frame `frame_ms` long.
    pub fn new(cpu: &CpuClock, gpu: Option<&GpuClock>, frame_ms: f64) -> FrameTimeline {
        let at = |t: Instant| ((t - cpu.frame_start).as_secs_f64() * 1e3).min(frame_ms);
        let mut stretches = Vec::with_capacity(2 * cpu.ops.len() + 2);
        let mut push = |work: Work, start_ms: f64, end_ms: f64| {
            if end_ms > start_ms {
                stretches.push(Stretch { work, start_ms, end_ms });
            }
        };
        push(Work::Refit, 0.0, at(cpu.frame_start + cpu.refit));
        let (culling_start, culling_end) = (at(cpu.culling.start), at(cpu.culling.end));
        let mut culled_to = culling_start;
        for op in cpu.ops {
            let (start, end) = (at(op.start), at(op.end));
            push(Work::Culling, culled_to.max(culling_start), start.min(culling_end));
            culled_to = culled_to.max(end);
            let work = match op.kind {
                OpKind::Commands => Work::Commands,
                OpKind::WaitForResults => Work::WaitForResults,
                OpKind::WaitForGpu => Work::WaitForGpu,
            };
            push(work, start, end);
        }
        push(Work::Culling, culled_to.max(culling_start), culling_end);
        let (gpu_frame, gpu) = match gpu {
            Some(clock) => place_gpu(
                clock,
                cpu.ops.iter().filter_map(|op| Some((op.tests?, at(op.end)))),
                frame_ms,
            ),
            None => (None, Vec::new()),
        };
        FrameTimeline {
            start_ms: (cpu.frame_start - cpu.run_start).as_secs_f64() * 1e3,
            cpu: stretches,
            gpu_frame,
            gpu,
        }
    }
}

/// The GPU's stretches of a frame `frame_ms` long on the CPU's clock, placed
/// as late as the waits allow: the frame's work ends by the frame's end, and
/// each batch of `tests` by the end of the wait for its results (CPU
/// milliseconds from the frame's start).
fn place_gpu(
    clock: &GpuClock,
    tests: impl Iterator<Item = (GpuSpan, f64)> + Clone,
    frame_ms: f64,
) -> (Option<Range<f64>>, Vec<Stretch>) {
    let frame_end_ns = clock.frame.end_ns();
    // Where the GPU frame's end lies, in CPU milliseconds from the frame's start.
    let end_ms = tests
        .clone()
        .map(|(span, waited_until)| waited_until + (frame_end_ns - span.end_ns()) / 1e6)
        .fold(frame_ms, f64::min);
    let at = |ns: f64| (end_ms + (ns - frame_end_ns) / 1e6).clamp(0.0, frame_ms);
    let frame = at(clock.frame.start_ns)..at(frame_end_ns);
    let mut boxes: Vec<GpuSpan> = tests.map(|(span, _)| span).chain(clock.walk).collect();
    boxes.sort_by(|a, b| a.start_ns.total_cmp(&b.start_ns));
    let mut stretches = Vec::with_capacity(2 * boxes.len() + 2);
    let mut drawn_to = frame.start;
    for span in boxes {
        let (start, end) = (at(span.start_ns).max(drawn_to), at(span.end_ns()).min(frame.end));
        if start > drawn_to {
            stretches.push(Stretch {
                work: Work::Drawing,
                start_ms: drawn_to,
                end_ms: start,
            });
        }
        if end > start {
            stretches.push(Stretch {
                work: Work::BoxTests,
                start_ms: start,
                end_ms: end,
            });
            drawn_to = end;
        }
    }
    if frame.end > drawn_to {
        stretches.push(Stretch {
            work: Work::Drawing,
            start_ms: drawn_to,
            end_ms: frame.end,
        });
    }
    if let (Some(pyramid), Some(walk)) = (clock.pyramid, clock.walk) {
        let (start, end) = (
            at(pyramid.start_ns).max(at(walk.start_ns)),
            at(pyramid.end_ns()).min(at(walk.end_ns())),
        );
        if end > start {
            stretches.push(Stretch {
                work: Work::Pyramid,
                start_ms: start,
                end_ms: end,
            });
        }
    }
    (Some(frame), stretches)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gpu_span(start_ms: f64, end_ms: f64) -> GpuSpan {
        GpuSpan {
            start_ns: start_ms * 1e6,
            duration_ns: (end_ms - start_ms) * 1e6,
        }
    }

    #[test]
    fn culling_fills_the_gaps_and_the_gpu_ends_where_the_waits_let_it() {
        let t0 = Instant::now();
        let at = |ms: f64| t0 + Duration::from_secs_f64(ms / 1e3);
        let op = |kind, start: f64, end: f64, tests: Option<GpuSpan>| OpSpan {
            kind,
            start: at(start),
            end: at(end),
            tests,
        };
        // On the GPU's clock the frame runs from 100 to 106 ms, a batch of
        // box tests from 101 to 102 ms, whose results the CPU had at 4 ms.
        let ops = [
            op(OpKind::Commands, 1.0, 1.1, None),
            op(OpKind::Commands, 2.0, 2.5, None),
            op(OpKind::WaitForResults, 2.5, 4.0, Some(gpu_span(101.0, 102.0))),
            op(OpKind::Commands, 6.0, 6.2, None),
            op(OpKind::WaitForGpu, 6.2, 9.5, None),
        ];
        let cpu = CpuClock {
            run_start: t0 - Duration::from_millis(50),
            frame_start: t0,
            refit: Duration::from_millis(1),
            culling: at(1.2)..at(6.0),
            ops: &ops,
        };
        let gpu = GpuClock {
            frame: gpu_span(100.0, 106.0),
            walk: None,
            pyramid: None,
        };
        // The frame was measured 9 ms long: the last wait is cut there.
        let timeline = FrameTimeline::new(&cpu, Some(&gpu), 9.0);
        let round = |s: &Stretch| (s.work, (s.start_ms * 1e3).round() / 1e3, (s.end_ms * 1e3).round() / 1e3);
        let cpu: Vec<_> = timeline.cpu.iter().map(round).collect();
        assert_eq!(
            cpu,
            [
                (Work::Refit, 0.0, 1.0),
                (Work::Commands, 1.0, 1.1),
                (Work::Culling, 1.2, 2.0),
                (Work::Commands, 2.0, 2.5),
                (Work::WaitForResults, 2.5, 4.0),
                (Work::Culling, 4.0, 6.0),
                (Work::Commands, 6.0, 6.2),
                (Work::WaitForGpu, 6.2, 9.0),
            ]
        );
        assert!((timeline.start_ms - 50.0).abs() < 1e-6);
        // The batch ended by 4 ms, so the GPU frame by 8 ms (not 9): it ran
        // from 2 to 8 ms, its tests from 3 to 4.
        let frame = timeline.gpu_frame.clone().unwrap();
        assert!(
            (frame.start - 2.0).abs() < 1e-9 && (frame.end - 8.0).abs() < 1e-9,
            "{frame:?}"
        );
        let gpu: Vec<_> = timeline.gpu.iter().map(round).collect();
        assert_eq!(
            gpu,
            [
                (Work::Drawing, 2.0, 3.0),
                (Work::BoxTests, 3.0, 4.0),
                (Work::Drawing, 4.0, 8.0)
            ]
        );
    }

    #[test]
    fn a_walks_pyramid_lies_within_its_box_tests_and_nothing_outside_the_frame() {
        let t0 = Instant::now();
        let cpu = CpuClock {
            run_start: t0,
            frame_start: t0,
            refit: Duration::ZERO,
            culling: t0..t0 + Duration::from_millis(1),
            ops: &[],
        };
        // GPU work longer than the frame (clocks that disagree) is cut to it.
        let gpu = GpuClock {
            frame: gpu_span(0.0, 12.0),
            walk: Some(gpu_span(2.0, 6.0)),
            pyramid: Some(gpu_span(2.5, 3.0)),
        };
        let timeline = FrameTimeline::new(&cpu, Some(&gpu), 10.0);
        let frame = timeline.gpu_frame.unwrap();
        assert_eq!((frame.start, frame.end), (0.0, 10.0));
        let works: Vec<(Work, f64, f64)> = timeline.gpu.iter().map(|s| (s.work, s.start_ms, s.end_ms)).collect();
        assert_eq!(
            works,
            [
                (Work::BoxTests, 0.0, 4.0),
                (Work::Drawing, 4.0, 10.0),
                (Work::Pyramid, 0.5, 1.0)
            ]
        );
        assert_eq!(timeline.cpu.len(), 1, "culling alone: {:?}", timeline.cpu);
    }
}
