//! What a command says on stderr while it works: [`Progress`] (a bar in a
//! terminal, a line every few seconds in a log), the time left at the pace
//! of recorded frames ([`Pace`]), and what bench says of each
//! [`BenchEvent`] ([`heard`]).

use std::io::IsTerminal as _;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use occlu::bench::BenchEvent;

use super::output::say;
use super::signals::go_on;

/// Progress of a bench run on stderr: a bar over the recorded frames in a
/// terminal (warm-up frames first show as such), and outside one (a CI log)
/// a line every few seconds; nothing when quiet. Both say which frame of
/// how many, the time spent and, once it can tell, how long is left.
pub struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
    warmup: u32,
    prefix: String,
    started: Instant,
    last_line: Option<Instant>,
    pace: Pace,
    /// The step of ray casts under way (planning a path), and when it began.
    step: Option<(&'static str, Instant)>,
}

/// Seconds between progress lines outside a terminal.
const PROGRESS_EVERY: f64 = 5.0;

impl Progress {
    pub fn new(quiet: bool, warmup: u32, prefix: String) -> Progress {
        Progress {
            bar: None,
            quiet,
            warmup,
            prefix,
            started: Instant::now(),
            last_line: None,
            pace: Pace::default(),
            step: None,
        }
    }

    /// A step of ray casts, `what`, has spent `spent` of its `budget` box
    /// and triangle tests.
    pub fn work(&mut self, what: &'static str, spent: u64, budget: u64) {
        self.report_step(what, || {
            format!(
                "{} M of at most {} M box and triangle tests",
                spent / 1_000_000,
                budget / 1_000_000
            )
        });
    }

    /// `done` of an animation's `total` frames are encoded.
    pub fn encoding(&mut self, done: u32, total: u32) {
        self.report_step("encoding the animation", || format!("frame {done} of {total}"));
    }

    /// A step before or after the frames, `what`, has got as far as
    /// `so_far` says: said once the step has taken a second (most take
    /// less), then every few seconds.
    fn report_step(&mut self, what: &'static str, so_far: impl FnOnce() -> String) {
        if self.quiet {
            return;
        }
        let now = Instant::now();
        let began = match self.step {
            Some((step, began)) if step == what => began,
            _ => {
                self.step = Some((what, now));
                self.last_line = None;
                now
            }
        };
        let taken = now.duration_since(began).as_secs_f64();
        let due = self
            .last_line
            .map_or(taken >= 1.0, |t| now.duration_since(t).as_secs_f64() >= PROGRESS_EVERY);
        if due {
            self.last_line = Some(now);
            say!("{what}: {taken:.0} s, {}", so_far());
        }
    }

    /// A listener for a step of ray casts, `what`: progress as [`Progress::work`]
    /// says it, and Ctrl-C heard.
    pub fn listener(&mut self, what: &'static str) -> occlu::camera::generate::PlanListener<'_> {
        Box::new(move |spent, budget| {
            self.work(what, spent, budget);
            go_on()
        })
    }

    /// `done` of `total` frames, warm-up frames included, have run.
    pub fn frame(&mut self, done: u32, total: u32) {
        if self.quiet {
            return;
        }
        let now = Instant::now();
        let status = self.status(done, total, now);
        let recorded = total.saturating_sub(self.warmup);
        if std::io::stderr().is_terminal() {
            // Created with its length known, so it never shows 0/0.
            let bar = self.bar.get_or_insert_with(|| {
                ProgressBar::new(u64::from(recorded)).with_style(
                    ProgressStyle::with_template("{prefix} [{bar:32}] {msg}")
                        .expect("static template")
                        .progress_chars("=> "),
                )
            });
            bar.set_prefix(self.prefix.clone());
            bar.set_position(u64::from(done.saturating_sub(self.warmup)));
            bar.set_message(status);
        } else {
            let due = self
                .last_line
                .is_none_or(|t| now.duration_since(t).as_secs_f64() >= PROGRESS_EVERY);
            if due || done == total {
                self.last_line = Some(now);
                say!("{}: {status}", self.prefix);
            }
        }
    }

    /// Which frame of how many is done, the time spent and the time left.
    fn status(&mut self, done: u32, total: u32, now: Instant) -> String {
        let (phase, at, of) = if done <= self.warmup {
            ("warm-up frame", done, self.warmup)
        } else {
            ("frame", done - self.warmup, total - self.warmup)
        };
        let elapsed = now.duration_since(self.started).as_secs_f64();
        let left = match self.pace.seconds_left(done, total, self.warmup, now) {
            Some(left) => format!("about {left:.0} s left"),
            None => "estimating the time left".into(),
        };
        format!("{phase} {at} of {of}, {elapsed:.0} s elapsed, {left}")
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// How long a run has left, at the pace of its recorded frames alone: the
/// first frames, on a cold shader cache, take tens of seconds each on a
/// software rasteriser and say nothing of the rest. So the pace is taken
/// from the end of warm-up (or of the first frame, without warm-up on).
#[derive(Default)]
struct Pace {
    /// When the pace is taken from, and the frames done by then.
    from: Option<(Instant, u32)>,
}

impl Pace {
    /// Notes that `done` of `total` frames, the first `warmup` of them
    /// warm-up, have run at `now`; the seconds left, once a frame has run
    /// since the pace is taken from.
    fn seconds_left(&mut self, done: u32, total: u32, warmup: u32, now: Instant) -> Option<f64> {
        if done < warmup.max(1) {
            return None;
        }
        let (from, done_then) = *self.from.get_or_insert((now, done));
        let paced = done - done_then;
        (paced > 0)
            .then(|| now.duration_since(from).as_secs_f64() / f64::from(paced) * f64::from(total.saturating_sub(done)))
    }
}

/// What bench says on stderr as its run goes.
pub fn heard(progress: &mut Progress, event: BenchEvent, note: &dyn Fn(String)) {
    match event {
        BenchEvent::Loaded {
            scene,
            hierarchy,
            load_ms,
            build_ms,
        } => {
            note(format!(
                "scene: {}: {} objects, {} triangles (load {load_ms:.0} ms, hierarchy of {} nodes {build_ms:.0} ms)",
                scene.source,
                scene.objects.len(),
                scene.triangles(),
                hierarchy.nodes.len()
            ));
            for w in &scene.warnings {
                note(format!("warning: {w}"));
            }
        }
        BenchEvent::Skipped { mode, reason } => note(format!("skipped: {mode}: {reason}")),
        BenchEvent::Work { what, spent, budget } => progress.work(what, spent, budget),
        BenchEvent::Adapter(adapter) => note(format!("adapter: {adapter}")),
        BenchEvent::Path(path, frames) => {
            let why = path.generated.as_ref().map(|w| format!(" ({w})")).unwrap_or_default();
            note(format!("path: {}{why}", path.source));
            match path.frames_with_geometry_within_near {
                Some(0) => {}
                Some(n) => note(format!(
                    "warning: {n} of {frames} frames have geometry nearer than the near plane's corners ({}): it may be clipped",
                    path.near
                )),
                None => note(near_not_counted()),
            }
        }
        BenchEvent::Frame { done, total } => progress.frame(done, total),
        BenchEvent::Encoding { done, total } => {
            if done == 0 {
                progress.finish();
                note(format!("encoding the animation's {total} frames"));
            }
            progress.encoding(done, total);
        }
        BenchEvent::NothingVisible => note(
            "warning: no object was visible in any frame (the reference drew nothing): check the camera path, and the model's place and size".into(),
        ),
    }
}

/// What a run says when counting frames with geometry within the near
/// plane spent its budget of ray casts.
pub fn near_not_counted() -> String {
    format!(
        "note: frames with geometry nearer than the near plane were not counted: the count spent its budget of {} M box and triangle tests",
        occlu::camera::generate::PLANNING_TESTS / 1_000_000
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// The seconds left after each frame of a run whose frames took
    /// `seconds` each, `warmup` of them warm-up.
    fn estimates(seconds: &[u64], warmup: u32) -> Vec<Option<f64>> {
        let mut pace = Pace::default();
        let mut now = Instant::now();
        let total = seconds.len() as u32;
        (1..=total)
            .map(|done| {
                now += Duration::from_secs(seconds[done as usize - 1]);
                pace.seconds_left(done, total, warmup, now)
            })
            .collect()
    }

    #[test]
    fn the_time_left_comes_from_recorded_frames_not_warm_up() {
        // Three warm-up frames compiling shaders for 100 s each, then 100
        // frames of 2 s.
        let seconds: Vec<u64> = [100; 3].into_iter().chain([2; 100]).collect();
        let left = estimates(&seconds, 3);
        assert_eq!(left[..3], [None; 3], "estimating during warm-up");
        assert_eq!(left[3], Some(2.0 * 99.0), "after the first recorded frame");
        assert_eq!(left[52], Some(2.0 * 50.0));
        assert_eq!(left[102], Some(0.0));
        // Without warm-up the first frame compiles the shaders: the pace
        // starts after it.
        let seconds: Vec<u64> = [100].into_iter().chain([2; 9]).collect();
        let left = estimates(&seconds, 0);
        assert_eq!(left[..2], [None, Some(2.0 * 8.0)]);
    }
}
