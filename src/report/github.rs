//! `bench --export-github-benchmark FILE`: the run in the format of
//! github-action-benchmark's `customSmallerIsBetter` tool, a JSON array of
//! `{"name", "unit", "value"}` entries (with optional `"extra"`), so a CI
//! job can chart a branch's runs and alert on regressions.

use serde::Serialize;

use super::summary::Summary;

/// One point of the chart github-action-benchmark draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Entry {
    pub name: String,
    pub unit: &'static str,
    pub value: f64,
    pub extra: String,
}

/// Per mode: mean and p95 frame time, mean triangles drawn, and (where the
/// error was measured) wrong pixels over the run. Smaller is better for all.
pub fn entries(summary: &Summary) -> Vec<Entry> {
    let extra = format!(
        "{} on {}, {} frames at {}",
        summary.scene.facts.source, summary.adapter, summary.frames, summary.resolution
    );
    let mut out = Vec::new();
    for mode in &summary.modes {
        let mut push = |metric: &str, unit, value: Option<f64>| {
            if let Some(value) = value {
                out.push(Entry {
                    name: format!("{} {metric}", mode.name),
                    unit,
                    value,
                    extra: extra.clone(),
                });
            }
        };
        let frame = mode.stats.get("frame_ms");
        push("frame_ms mean", "ms", frame.map(|d| d.mean));
        push("frame_ms p95", "ms", frame.map(|d| d.p95));
        push(
            "triangles_drawn mean",
            "triangles",
            mode.stats.get("triangles_drawn").map(|d| d.mean),
        );
        push("error_pixels", "pixels", mode.error_pixels_total.map(|v| v as f64));
    }
    out
}
