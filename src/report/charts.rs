//! The five PNG charts of a run, drawn with plotters from frames.csv and
//! summary.json (so `occlu plot RUN_DIR` redraws them from the files alone):
//!
//! - `frame_time.png`: frame time per frame, one line per mode (the papers'
//!   Figures 5–8);
//! - `triangles.png`: triangles drawn per frame (log scale);
//! - `queries.png`: box tests and round trips per frame;
//! - `time_vs_error.png`: mean frame time against the fraction of wrong
//!   pixels, one point per mode and swept value, the Pareto front marked;
//! - `summary.png`: mean and p95 frame time per mode, with the speed-up over
//!   vfc and the ratio to the oracle written on the bars.
//!
//! `occlu merge` draws one more per run, [`ratio_to_oracle_bars`]: each
//! mode's ratio to the oracle on each adapter; an animation's panels take
//! their [`caption`]s in the same font.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::{RangedCoordf64, RangedCoordu32};
use plotters::prelude::*;

use super::files::{ReportError, write_png};
use super::summary::Summary;
use crate::cull::ModeId;
use crate::measure::{FrameStats, ModeSummary};

pub const WIDTH: u32 = 1200;
pub const HEIGHT: u32 = 700;
pub const CHARTS: [&str; 5] = [
    "frame_time.png",
    "triangles.png",
    "queries.png",
    "time_vs_error.png",
    "summary.png",
];

const FONT: &str = "sans-serif";

/// Writes every chart into `dir`; returns their paths.
pub fn write_charts(dir: &Path, summary: &Summary, rows: &[FrameStats]) -> Result<Vec<PathBuf>, ReportError> {
    let series = Series::of(summary, rows);
    let draw: [(&str, ChartFn); 5] = [
        (CHARTS[0], frame_time),
        (CHARTS[1], triangles),
        (CHARTS[2], queries),
        (CHARTS[3], time_vs_error),
        (CHARTS[4], summary_bars),
    ];
    draw.iter()
        .map(|&(name, chart)| {
            let path = dir.join(name);
            draw_png(&path, |root| chart(root, summary, &series))?;
            Ok(path)
        })
        .collect()
}

/// Draws one chart with `draw` and writes it to `path` as a PNG.
fn draw_png(path: &Path, draw: impl FnOnce(&Area) -> DrawResult) -> Result<(), ReportError> {
    register_font();
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root).map_err(|e| ReportError {
            path: path.to_path_buf(),
            error: std::io::Error::other(format!("drawing the chart failed: {e}")),
        })?;
    }
    write_png(path, WIDTH, HEIGHT, &rgb)
}

/// One bar group of [`ratio_to_oracle_bars`]: a mode, and its mean frame
/// time over the oracle's on each adapter (`None` where it did not run or
/// the adapter ran no oracle).
pub struct RatioBars {
    pub mode: String,
    pub ratios: Vec<Option<f64>>,
}

/// `occlu merge`'s chart of one run: for each mode, a bar per adapter of
/// its ratio to the oracle (1 is the oracle itself, the floor of any
/// object-level culler), adapters side by side in the colours of
/// [`OTHER_COLOURS`], never averaged.
pub fn ratio_to_oracle_bars(
    path: &Path,
    caption: &str,
    adapters: &[String],
    modes: &[RatioBars],
) -> Result<(), ReportError> {
    draw_png(path, |area| {
        area.fill(&WHITE)?;
        let y_max = modes
            .iter()
            .flat_map(|m| m.ratios.iter().flatten())
            .fold(1.0, |a: f64, &b| a.max(b))
            * 1.2;
        let n = modes.len().max(1) as f64;
        let names: Vec<&str> = modes.iter().map(|m| m.mode.as_str()).collect();
        let mut chart = mode_axes(area, caption, &names, y_max, "mean frame time / oracle's")?;
        chart.draw_series(LineSeries::new([(-0.5, 1.0), (n - 0.5, 1.0)], BLACK.mix(0.5)))?;
        let width = 0.8 / adapters.len().max(1) as f64;
        for (a, adapter) in adapters.iter().enumerate() {
            let c = OTHER_COLOURS[a % OTHER_COLOURS.len()];
            // Each mode's bar for this adapter: its left edge and its ratio.
            let placed: Vec<(f64, f64)> = modes
                .iter()
                .enumerate()
                .filter_map(|(i, m)| Some((i as f64 - 0.4 + width * a as f64, m.ratios.get(a).copied().flatten()?)))
                .collect();
            let bars = placed
                .iter()
                .map(|&(left, ratio)| Rectangle::new([(left, 0.0), (left + width * 0.9, ratio)], c.filled()));
            chart
                .draw_series(bars)?
                .label(adapter.as_str())
                .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], c.filled()));
            let values = placed
                .iter()
                .map(|&(left, ratio)| Text::new(format!("{ratio:.2}×"), (left, ratio + y_max * 0.03), (FONT, 14)));
            chart.draw_series(values)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        area.present()?;
        Ok(())
    })
}

/// A strip of `width` × `height` pixels (RGB) holding `text` in white on
/// dark grey, in the charts' font: the captions of an animation's panels.
pub fn caption(width: u32, height: u32, text: &str) -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    register_font();
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        root.fill(&CAPTION_GREY)?;
        let style = (FONT, f64::from(height) * 0.7).into_font().color(&WHITE);
        root.draw_text(text, &style, (4, (height / 8) as i32))?;
        root.present()?;
    }
    Ok(rgb)
}

/// The background of captions.
pub const CAPTION_GREY: RGBColor = RGBColor(40, 40, 40);

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;
type ChartFn = fn(&Area, &Summary, &Series) -> DrawResult;

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font always parses; a failure here is a build error.
        let _ = plotters::style::register_font(
            FONT,
            FontStyle::Normal,
            include_bytes!("../../assets/fonts/DejaVuSans.ttf"),
        );
    });
}

/// Per-frame values of each mode, in the order of the summary, with the
/// colour each mode keeps in every chart.
struct Series<'a> {
    modes: Vec<(&'a ModeSummary, Vec<&'a FrameStats>, RGBColor)>,
    frames: u32,
}

impl<'a> Series<'a> {
    fn of(summary: &'a Summary, rows: &'a [FrameStats]) -> Series<'a> {
        let mut others = 0;
        let modes = summary
            .modes
            .iter()
            .map(|m| {
                let mut mine: Vec<&FrameStats> = rows.iter().filter(|r| r.mode == m.name).collect();
                mine.sort_by_key(|r| r.frame);
                let c = colour(&m.name).unwrap_or_else(|| {
                    others += 1;
                    OTHER_COLOURS[(others - 1) % OTHER_COLOURS.len()]
                });
                (m, mine, c)
            })
            .collect();
        let frames = rows.iter().map(|r| r.frame + 1).max().unwrap_or(1);
        Series { modes, frames }
    }

    fn max(&self, f: fn(&FrameStats) -> f64) -> f64 {
        self.modes
            .iter()
            .flat_map(|(_, rows, _)| rows.iter().map(|r| f(r)))
            .fold(0.0, f64::max)
    }
}

/// The colour a mode keeps in every chart and run, from its registry entry;
/// labels of other runs (sweep values) take [`OTHER_COLOURS`] in order.
fn colour(name: &str) -> Option<RGBColor> {
    let [r, g, b] = name.parse::<ModeId>().ok()?.info().chart_colour;
    Some(RGBColor(r, g, b))
}

/// Colours apart from every mode's: for sweep values and adapters.
const OTHER_COLOURS: [RGBColor; 8] = [
    RGBColor(57, 59, 121),
    RGBColor(140, 162, 82),
    RGBColor(189, 158, 57),
    RGBColor(173, 73, 74),
    RGBColor(165, 81, 148),
    RGBColor(107, 110, 207),
    RGBColor(206, 109, 189),
    RGBColor(99, 121, 57),
];

fn title(summary: &Summary, what: &str) -> String {
    format!("{what} — {} at {}", summary.scene.facts.source, summary.resolution)
}

/// Lines of `f` per frame for every mode, on a linear or log y axis.
fn per_frame_lines(
    area: &Area,
    series: &Series,
    caption: &str,
    y_desc: &str,
    f: fn(&FrameStats) -> f64,
    log: bool,
) -> DrawResult {
    let max = series.max(f).max(1.0) * 1.08;
    let x = 0u32..series.frames.max(2) - 1;
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(caption, (FONT, 26))
        .margin(18)
        .x_label_area_size(48)
        .y_label_area_size(90);
    if log {
        let chart = builder.build_cartesian_2d(x, (1f64..max).log_scale())?;
        draw_lines(chart, series, y_desc, |r| f(r).max(1.0))?;
    } else {
        let chart = builder.build_cartesian_2d(x, 0f64..max)?;
        draw_lines(chart, series, y_desc, f)?;
    }
    area.present()?;
    Ok(())
}

fn draw_lines<'a, 'b: 'a, Y>(
    mut chart: ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordu32, Y>>,
    series: &Series,
    y_desc: &str,
    f: impl Fn(&FrameStats) -> f64,
) -> DrawResult
where
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc(y_desc)
        .label_style((FONT, 16))
        .axis_desc_style((FONT, 18))
        .draw()?;
    for &(mode, ref rows, c) in &series.modes {
        chart
            .draw_series(LineSeries::new(rows.iter().map(|r| (r.frame, f(r))), c.stroke_width(2)))?
            .label(mode.name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
    }
    // The frames a mode that runs others (auto) spent measuring one: a
    // ring on its line.
    let probes: Vec<(u32, f64, RGBColor)> = series
        .modes
        .iter()
        .flat_map(|(_, rows, c)| {
            rows.iter()
                .filter(|r| r.probe == Some(true))
                .map(|r| (r.frame, f(r), *c))
        })
        .collect();
    if !probes.is_empty() {
        chart
            .draw_series(
                probes
                    .iter()
                    .map(|&(x, y, c)| Circle::new((x, y), 5, c.stroke_width(2))),
            )?
            .label("probe frame")
            .legend(|(x, y)| Circle::new((x + 12, y), 5, BLACK.stroke_width(2)));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    Ok(())
}

fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .draw()
}

fn frame_time(area: &Area, summary: &Summary, series: &Series) -> DrawResult {
    area.fill(&WHITE)?;
    per_frame_lines(
        area,
        series,
        &title(summary, "Frame time per frame"),
        "frame time (ms)",
        |r| r.frame_ms,
        false,
    )
}

fn triangles(area: &Area, summary: &Summary, series: &Series) -> DrawResult {
    area.fill(&WHITE)?;
    let caption = title(summary, "Triangles drawn per frame");
    per_frame_lines(
        area,
        series,
        &caption,
        "triangles drawn (log scale)",
        |r| r.triangles_drawn as f64,
        true,
    )
}

fn queries(area: &Area, summary: &Summary, series: &Series) -> DrawResult {
    area.fill(&WHITE)?;
    let (top, bottom) = area.split_vertically(HEIGHT / 2);
    let testing = Series {
        modes: series
            .modes
            .iter()
            .filter(|(m, _, _)| m.stats.get("queries").is_some_and(|d| d.max > 0.0))
            .cloned()
            .collect(),
        frames: series.frames,
    };
    if testing.modes.is_empty() {
        area.draw(&Text::new(
            "No mode in this run tests boxes: no queries to show.",
            (60, 300),
            (FONT, 24),
        ))?;
        area.present()?;
        return Ok(());
    }
    let caption = title(summary, "Box tests per frame (occlusion queries or pixel counts)");
    per_frame_lines(&top, &testing, &caption, "boxes tested", |r| r.queries as f64, false)?;
    per_frame_lines(
        &bottom,
        &testing,
        "GPU→CPU round trips per frame",
        "round trips",
        |r| r.query_batches as f64,
        false,
    )
}

fn time_vs_error(area: &Area, summary: &Summary, series: &Series) -> DrawResult {
    area.fill(&WHITE)?;
    if !summary.error_measured {
        area.draw(&Text::new(
            "Image error was not measured in this run (--no-error).",
            (60, 300),
            (FONT, 24),
        ))?;
        area.present()?;
        return Ok(());
    }
    let points: Vec<(RGBColor, &str, f64, f64)> = series
        .modes
        .iter()
        .filter_map(|&(m, _, c)| Some((c, m.name.as_str(), m.stats.get("frame_ms")?.mean, m.error_fraction?)))
        .collect();
    // Zero error cannot sit on a log axis: exact modes go on a floor line a
    // decade below the smallest error seen.
    let smallest = points
        .iter()
        .map(|p| p.3)
        .filter(|&e| e > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if smallest.is_finite() { smallest / 10.0 } else { 1e-6 };
    let top = points.iter().map(|p| p.3).fold(floor * 100.0, f64::max) * 10.0;
    let x_max = points.iter().map(|p| p.2).fold(1.0, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(title(summary, "Run time against image error"), (FONT, 26))
        .margin(18)
        .x_label_area_size(48)
        .y_label_area_size(110)
        .build_cartesian_2d(0f64..x_max, (floor / 2.0..top).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("mean frame time (ms)")
        .y_desc("wrong pixels (fraction of the frame, log scale)")
        .y_label_formatter(&|v| {
            // A tick on the floor line is the exact modes' row: 0, not a ratio.
            if (v / floor - 1.0).abs() < 1e-9 {
                "0".into()
            } else {
                format!("{v:.0e}")
            }
        })
        .label_style((FONT, 16))
        .axis_desc_style((FONT, 18))
        .draw()?;
    chart.draw_series(LineSeries::new(
        [(0.0, floor), (x_max, floor)],
        BLACK.mix(0.25).stroke_width(1),
    ))?;
    chart.draw_series(std::iter::once(Text::new(
        "0 wrong pixels (exact)",
        (x_max * 0.8, floor * 0.75),
        (FONT, 15),
    )))?;
    let shown = |e: f64| if e > 0.0 { e } else { floor };
    // Pareto front: the modes no other beats in both time and error. The
    // oracle is left out: it is the floor, not a mode one can choose.
    let choices: Vec<_> = points.iter().filter(|p| p.1 != "oracle").collect();
    let dominated = |p: &&(RGBColor, &str, f64, f64)| {
        choices
            .iter()
            .any(|q| q.2 <= p.2 && q.3 <= p.3 && (q.2 < p.2 || q.3 < p.3))
    };
    let mut front: Vec<(f64, f64)> = choices
        .iter()
        .filter(|p| !dominated(p))
        .map(|p| (p.2, shown(p.3)))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let front_style = RED.mix(0.7).stroke_width(2);
    chart
        .draw_series(LineSeries::new(front.clone(), front_style))?
        .label("Pareto front (oracle excluded)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], front_style));
    chart.draw_series(front.iter().map(|&p| Circle::new(p, 13, front_style)))?;
    for &(c, name, time, error) in &points {
        chart
            .draw_series(std::iter::once(Circle::new((time, shown(error)), 7, c.filled())))?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 12, y), 6, c.filled()));
        chart.draw_series(std::iter::once(Text::new(
            name.to_string(),
            (time, shown(error) * 1.6),
            (FONT, 15),
        )))?;
    }
    // Upper left: fast but inaccurate is the rare corner.
    legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    area.present()?;
    Ok(())
}

/// Axes for bars per mode: mode `names` at x = 0, 1, …, values from 0 to
/// `y_max` up the side, the mesh drawn.
fn mode_axes<'a, 'b>(
    area: &'a Area<'b>,
    caption: &str,
    names: &[&str],
    y_max: f64,
    y_desc: &str,
) -> Result<ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>, Box<dyn std::error::Error>>
{
    let n = names.len().max(1) as f64;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 26))
        .margin(18)
        .x_label_area_size(48)
        .y_label_area_size(90)
        .build_cartesian_2d(-0.5f64..n - 0.5, 0f64..y_max)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(names.len().max(1))
        .x_label_formatter(&|x| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                names.get(i as usize).map_or(String::new(), |n| n.to_string())
            } else {
                String::new()
            }
        })
        .x_desc("mode")
        .y_desc(y_desc)
        .x_label_style((FONT, 13))
        .label_style((FONT, 16))
        .axis_desc_style((FONT, 18))
        .draw()?;
    Ok(chart)
}

fn summary_bars(area: &Area, summary: &Summary, series: &Series) -> DrawResult {
    area.fill(&WHITE)?;
    let bars: Vec<(RGBColor, &ModeSummary, f64, f64)> = series
        .modes
        .iter()
        .filter_map(|&(m, _, c)| {
            let d = m.stats.get("frame_ms")?;
            Some((c, m, d.mean, d.p95))
        })
        .collect();
    // The taller of each mode's two bars: a few stalls lift a mean above
    // its p95.
    let y_max = bars.iter().map(|b| b.2.max(b.3)).fold(1.0, f64::max) * 1.25;
    let names: Vec<&str> = bars.iter().map(|b| b.1.name.as_str()).collect();
    let caption = title(summary, "Mean and p95 frame time per mode");
    let mut chart = mode_axes(area, &caption, &names, y_max, "frame time (ms)")?;
    for (i, &(c, m, mean, p95)) in bars.iter().enumerate() {
        let x = i as f64;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x - 0.38, 0.0), (x - 0.02, mean)],
            c.filled(),
        )))?;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x + 0.02, 0.0), (x + 0.38, p95)],
            c.mix(0.4).filled(),
        )))?;
        let mut notes = vec![format!("{mean:.1} / {p95:.1} ms")];
        if let Some(s) = m.speedup_vs_vfc {
            notes.push(format!("{s:.2}× vs vfc"));
        }
        if let Some(r) = m.ratio_to_oracle {
            notes.push(format!("{r:.2}× oracle"));
        }
        for (k, note) in notes.iter().enumerate() {
            let y = p95.max(mean) + y_max * (0.07 - 0.035 * k as f64 + 0.035 * (notes.len() - 1) as f64);
            chart.draw_series(std::iter::once(Text::new(note.clone(), (x - 0.4, y), (FONT, 14))))?;
        }
    }
    area.draw(&Text::new(
        "solid: mean    light: p95",
        (WIDTH as i32 - 250, 60),
        (FONT, 16),
    ))?;
    area.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mode_keeps_a_colour_no_other_line_takes() {
        let mut taken: Vec<RGBColor> = OTHER_COLOURS.to_vec();
        for id in ModeId::ALL {
            let c = colour(id.name()).unwrap_or_else(|| panic!("{id} has no colour"));
            assert!(!taken.contains(&c), "{id}'s colour is taken");
            taken.push(c);
        }
        assert_eq!(
            colour("ac[threshold=50]"),
            None,
            "a sweep's label takes the next other colour"
        );
    }
}
