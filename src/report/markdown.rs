//! report.md: the table a person reads first.

use std::fmt::Write as _;

use super::summary::{Summary, SweepSummary, Verdict};
use crate::measure::ModeSummary;
use crate::text::markdown;

pub fn render(s: &Summary) -> String {
    let mut md = String::new();
    let w = &mut md;
    let _ = writeln!(w, "# occlu bench: {}\n", markdown(&s.scene.facts.source));
    let _ = writeln!(
        w,
        "{} objects, {} triangles, {} hierarchy nodes (depth {}); {} frames at {} after {} warm-up frames; path {}.\n",
        s.scene.facts.objects,
        group(s.scene.facts.triangles as f64),
        s.scene.facts.hierarchy.nodes,
        s.scene.facts.hierarchy.depth,
        s.frames,
        s.resolution,
        s.warmup,
        markdown(&s.path.source)
    );
    let _ = writeln!(w, "Adapter: {}.\n", s.adapter);
    if let Some(v) = &s.verdict {
        let _ = writeln!(w, "{}\n", verdict_line(v));
    }
    let _ = writeln!(
        w,
        "| mode | frame ms (mean ± σ) | median | p95 | triangles | queries | round trips | error px | missed | vs vfc | × oracle |"
    );
    let _ = writeln!(w, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for m in &s.modes {
        let _ = writeln!(w, "{}", row(m));
    }
    let _ = writeln!(
        w,
        "\nframe ms: wall time from the start of a mode's frame on the CPU until the GPU finished it. \
         triangles, queries and round trips are per-frame means. error px: pixels whose depth differs \
         from direct rendering, summed over all frames; missed: visible objects not drawn, summed. \
         vs vfc: mean frame time of vfc over the mode's; × oracle: the mode's over the oracle's."
    );
    let flagged: Vec<&str> = s
        .modes
        .iter()
        .filter(|m| {
            m.conservative
                && (m.error_pixels_total.is_some_and(|e| e > 0) || m.missed_objects_total.is_some_and(|e| e > 0))
        })
        .map(|m| m.name.as_str())
        .collect();
    if !flagged.is_empty() {
        let _ = writeln!(
            w,
            "\n**Conservative modes with image error or missed objects: {}.** A conservative mode must draw every visible object and never change a pixel; this is a bug.",
            flagged.join(", ")
        );
    }
    cost_split(w, &s.modes);
    strategies(w, &s.modes);
    missed_list(w, s);
    if let Some(sweep) = &s.sweep {
        sweep_table(w, s, sweep);
    }
    for skipped in &s.skipped {
        let _ = writeln!(w, "\nSkipped {}: {}.", skipped.mode, skipped.reason);
    }
    if !s.error_measured {
        let _ = writeln!(w, "\nImage error was not measured (--no-error).");
    }
    if !s.scene.facts.warnings.is_empty() {
        let _ = writeln!(w, "\nScene warnings:\n");
        for warning in &s.scene.facts.warnings {
            let _ = writeln!(w, "- {}", markdown(warning));
        }
    }
    let _ = writeln!(
        w,
        "\n## Charts\n\n![Frame time per frame](frame_time.png)\n\n![Triangles drawn per frame](triangles.png)\n\n\
         ![Box tests and round trips per frame](queries.png)\n\n![Run time against image error](time_vs_error.png)\n\n\
         ![Mean and p95 frame time per mode](summary.png)"
    );
    if let Some(file) = &s.animation {
        let _ = writeln!(
            w,
            "\n## Flythrough\n\n![Each mode's frames side by side]({file})\n\nEach frame of the run in every mode: what it drew, beside the scene from above (the frustum in red, the boxes of objects in it that the mode did not draw in yellow), with the frame's time."
        );
    }
    let _ = writeln!(
        w,
        "\nPer-frame figures: frames.csv. Every statistic: summary.json (schema {}).",
        s.schema_version
    );
    md
}

/// The run's answer in one line.
pub(super) fn verdict_line(v: &Verdict) -> String {
    let mut line = format!(
        "**Fastest conservative mode: {}**, {:.2} ms a frame",
        markdown(&v.fastest),
        v.frame_ms
    );
    if let Some(x) = v.speedup_vs_vfc {
        let _ = write!(line, ", {x:.2}× as fast as vfc");
    }
    if let Some(x) = v.ratio_to_oracle {
        let _ = write!(line, ", {x:.2}× the oracle's time");
    }
    if let Some(next) = &v.runner_up {
        let [low, high] = next.interval;
        let told = if low <= 1.0 && 1.0 <= high {
            "not told apart in this run"
        } else {
            "slower"
        };
        let _ = write!(
            line,
            "; {} takes {:.2}× its time ({}, {told})",
            markdown(&next.name),
            next.ratio,
            interval(next.interval)
        );
    }
    if let (Some(mean), Some(p95)) = (v.auto_ratio, v.auto_p95_ratio) {
        let _ = write!(line, "; auto takes {mean:.2}× its time (");
        if let Some(i) = v.auto_interval {
            let _ = write!(line, "{}, ", interval(i));
        }
        let _ = write!(line, "p95 {p95:.2}×)");
    }
    if v.runner_up.is_some() || v.auto_interval.is_some() {
        line += ". The intervals pair the frames by their place on the path";
    }
    line + "."
}

fn interval([low, high]: [f64; 2]) -> String {
    format!("95 % interval {low:.2}–{high:.2}")
}

/// For each mode that runs others (`auto`), the frames each of them drew
/// and what they cost.
fn strategies(w: &mut String, modes: &[ModeSummary]) {
    for m in modes.iter().filter(|m| !m.strategies.is_empty()) {
        let _ = writeln!(
            w,
            "\n## {}'s strategies\n\n| strategy | frames | of which probes | mean frame ms | share of the time |\n|---|---:|---:|---:|---:|",
            markdown(&m.name)
        );
        let total: f64 = m.strategies.iter().map(|s| s.mean_frame_ms * s.frames as f64).sum();
        for s in &m.strategies {
            let time = s.mean_frame_ms * s.frames as f64;
            let _ = writeln!(
                w,
                "| {} | {} | {} | {:.2} | {:.1} % |",
                markdown(&s.strategy),
                s.frames,
                s.probes,
                s.mean_frame_ms,
                100.0 * time / total.max(f64::MIN_POSITIVE)
            );
        }
        let _ = writeln!(
            w,
            "\nA probe runs a strategy to measure it; the others ran as the cheapest measured. frames.csv's `strategy` and `probe` columns say which, frame by frame."
        );
    }
}

/// Where each mode's frame went (004's Table 1 splits it the same way):
/// deciding on the CPU, testing boxes on the GPU (of which building a
/// depth pyramid), drawing, waiting for results; and for GPU walks the
/// objects drawn before and after the test. Only with GPU timestamps.
fn cost_split(w: &mut String, modes: &[ModeSummary]) {
    if !modes.iter().any(|m| m.stats.contains_key("gpu_ms")) {
        return;
    }
    let _ = writeln!(
        w,
        "\n## Cost split (means per frame)\n\n| mode | frame ms | culling CPU ms | box tests GPU ms | of which pyramid | drawing GPU ms | waits ms | drawn early | drawn late |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for m in modes {
        let mean = |col: &str| m.stats.get(col).map(|d| d.mean);
        // Per frame of the run: a frame without box tests (auto running
        // vfc) spent none on them.
        let per_frame = |col: &str| {
            let d = m.stats.get(col)?;
            Some(d.mean * d.count as f64 / m.frames.max(1) as f64)
        };
        let ms = |v: Option<f64>| v.map_or_else(|| "–".into(), |v| format!("{v:.2}"));
        // Only GPU walks draw early or late; every other mode shows "–".
        let walks = mean("drawn_early").unwrap_or(0.0) + mean("drawn_late").unwrap_or(0.0) > 0.0;
        let count = |col: &str| match mean(col) {
            Some(v) if walks => format!("{v:.1}"),
            _ => "–".into(),
        };
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            markdown(&m.name),
            ms(mean("frame_ms")),
            ms(mean("cpu_ms")),
            ms(per_frame("query_gpu_ms")),
            ms(per_frame("pyramid_gpu_ms")),
            ms(mean("render_ms")),
            ms(mean("query_wait_ms")),
            count("drawn_early"),
            count("drawn_late"),
        );
    }
    let _ = writeln!(
        w,
        "\nbox tests: GPU time of occlusion queries, pixel counts or a GPU walk's passes; drawing: the rest of the frame's GPU time. \
         On a software rasteriser (llvmpipe) the pyramid's time also holds finishing the draws before it."
    );
}

/// Run time against error, one row per swept value.
fn sweep_table(w: &mut String, s: &Summary, sweep: &SweepSummary) {
    let _ = writeln!(
        w,
        "\n## {}.{}: run time against error\n\n| {} | frame ms (mean) | triangles | wrong pixels (% of frame) | missed objects / frame |\n|---:|---:|---:|---:|---:|",
        sweep.mode, sweep.key, sweep.key
    );
    for value in &sweep.values {
        let label = sweep.label(value);
        let Some(m) = s.modes.iter().find(|m| m.name == label) else {
            continue;
        };
        let mean = |col: &str| m.stats.get(col).map(|d| d.mean);
        let opt = |v: Option<String>| v.unwrap_or_else(|| "–".into());
        let _ = writeln!(
            w,
            "| {value} | {} | {} | {} | {} |",
            opt(mean("frame_ms").map(|v| format!("{v:.2}"))),
            opt(mean("triangles_drawn").map(group)),
            opt(m.error_fraction.map(|f| format!("{:.4}", f * 100.0))),
            opt(mean("missed_objects").map(|v| format!("{v:.2}"))),
        );
    }
}

fn row(m: &ModeSummary) -> String {
    let stat = |col: &str| m.stats.get(col);
    let ms = |v: f64| format!("{v:.2}");
    let frame = stat("frame_ms");
    let opt = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    format!(
        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
        markdown(&m.name),
        opt(frame.map(|d| format!("{} ± {}", ms(d.mean), ms(d.stddev)))),
        opt(frame.map(|d| ms(d.median))),
        opt(frame.map(|d| ms(d.p95))),
        opt(stat("triangles_drawn").map(|d| group(d.mean))),
        opt(stat("queries").map(|d| format!("{:.1}", d.mean))),
        opt(stat("query_batches").map(|d| format!("{:.1}", d.mean))),
        opt(m.error_pixels_total.map(|e| e.to_string())),
        opt(m.missed_objects_total.map(|e| e.to_string())),
        opt(m.speedup_vs_vfc.map(|v| format!("{v:.2}×"))),
        opt(m.ratio_to_oracle.map(|v| format!("{v:.2}"))),
    )
}

/// 1234567.8 → "1 234 568": thousands grouped with thin spaces.
fn group(v: f64) -> String {
    let digits = format!("{:.0}", v.max(0.0));
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

/// The first objects the modes got wrong, and where the rest are.
fn missed_list(w: &mut String, s: &Summary) {
    let missed = &s.missed;
    if missed.rows == 0 {
        return;
    }
    let _ = writeln!(
        w,
        "\nWhat the modes got wrong (the first {} of {} rows of missed.csv). `occlu render` with this run's model, `--path`, `--frames`, `--resolution` and `--param`, and `--frame K --mode M --show-missed`, paints them (it replays the two frames before K, so a mode carrying state over more frames may miss differently):\n",
        missed.first.len(),
        missed.rows
    );
    let _ = writeln!(w, "| mode | frame | object | name | drawn | wrong px | first pixel |");
    let _ = writeln!(w, "|---|---:|---:|---|---|---:|---|");
    for m in &missed.first {
        let first = match (m.first_x, m.first_y) {
            (Some(x), Some(y)) => format!("({x}, {y})"),
            _ => "–".to_string(),
        };
        let drawn = if m.drawn { "yes" } else { "no" };
        let name = markdown(&m.name);
        let _ = writeln!(
            w,
            "| {} | {} | {} | {name} | {drawn} | {} | {first} |",
            m.mode, m.frame, m.object, m.wrong_pixels
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cost_split_spreads_box_tests_over_every_frame() {
        use crate::measure::{FrameStats, ModeDescription, summarize};
        // auto: two frames of a pyramid test (10 ms of GPU, 4 of box tests,
        // 3 of them the pyramid) and two of vfc (10 ms of drawing, no tests).
        let rows: Vec<FrameStats> = (0..4)
            .map(|frame| {
                let tested = frame < 2;
                FrameStats {
                    frame,
                    gpu_ms: Some(10.0),
                    query_gpu_ms: tested.then_some(4.0),
                    pyramid_gpu_ms: tested.then_some(3.0),
                    ..FrameStats::blank("auto")
                }
            })
            .collect();
        let mode = ModeDescription {
            name: "auto".into(),
            conservative: true,
            parameters: serde_json::json!({}),
        };
        let mut w = String::new();
        cost_split(&mut w, &summarize(&rows, &[mode], 100));
        let row = w.lines().find(|l| l.starts_with("| auto |")).unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        // Box tests 2 and pyramid 1.5 a frame; drawing (6 + 6 + 10 + 10) / 4.
        assert_eq!(cells[4..7], ["2.00", "1.50", "8.00"], "{row}");
    }

    #[test]
    fn numbers_are_grouped_by_thousands() {
        assert_eq!(group(0.0), "0");
        assert_eq!(group(999.4), "999");
        assert_eq!(group(1234567.8), "1\u{2009}234\u{2009}568");
    }
}
