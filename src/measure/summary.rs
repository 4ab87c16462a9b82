//! Summary statistics of each column per mode, for summary.json and
//! report.md.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::rows::FrameStats;
use crate::cull::TraversalStats;

/// The distribution of one column over the recorded frames.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Distribution {
    pub mean: f64,
    /// Sample standard deviation (0 for one frame).
    pub stddev: f64,
    pub median: f64,
    pub p95: f64,
    pub p99: f64,
    pub min: f64,
    pub max: f64,
    /// Median absolute deviation from the median (unscaled).
    pub mad: f64,
    /// Values summarised: the frames that have the column (0 in files
    /// written before it was recorded).
    #[serde(default)]
    pub count: usize,
}

impl Distribution {
    /// `None` for no values. Percentiles interpolate linearly between order
    /// statistics (Hyndman–Fan type 7, as numpy's default).
    pub fn of(values: &[f64]) -> Option<Distribution> {
        if values.is_empty() {
            return None;
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len() as f64;
        let mean = sorted.iter().sum::<f64>() / n;
        let var = if sorted.len() > 1 {
            sorted.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        let median = percentile(&sorted, 0.5);
        let mut deviations: Vec<f64> = sorted.iter().map(|v| (v - median).abs()).collect();
        deviations.sort_by(f64::total_cmp);
        Some(Distribution {
            mean,
            stddev: var.sqrt(),
            median,
            p95: percentile(&sorted, 0.95),
            p99: percentile(&sorted, 0.99),
            min: sorted[0],
            max: sorted[sorted.len() - 1],
            mad: percentile(&deviations, 0.5),
            count: values.len(),
        })
    }
}

/// Two-sided 95 % normal quantile.
const Z_95: f64 = 1.959_964;

/// Fewest pairs a [`PairedRatio`] is given for: with three degrees of
/// freedom its interval is already 1.6 times the normal one.
pub const LEAST_PAIRS: usize = 4;

/// The two-sided 95 % quantile of Student's t with `dof` degrees of
/// freedom, by the expansion of Abramowitz and Stegun 26.7.5 in powers of
/// 1/dof: within 0.15 % of the tables from 3 degrees of freedom on.
fn student_t_95(dof: f64) -> f64 {
    let z = Z_95;
    let terms = [
        (z.powi(3) + z) / 4.0,
        (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / 96.0,
        (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / 384.0,
        (79.0 * z.powi(9) + 776.0 * z.powi(7) + 1482.0 * z.powi(5) - 1920.0 * z.powi(3) - 945.0 * z) / 92160.0,
    ];
    z + terms.iter().zip(1..).map(|(g, k)| g / dof.powi(k)).sum::<f64>()
}

/// The ratio of the mean of the first values of `pairs` to the mean of the
/// second, with its 95 % interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairedRatio {
    pub ratio: f64,
    pub interval: [f64; 2],
}

impl PairedRatio {
    /// Over `pairs` (a mode's frame time and another's at the same place
    /// on the path), by the delta method: R = ā / b̄ has the standard error
    /// sd(aᵢ − R·bᵢ) / (√n · b̄), taken to Student's t with n − 1 degrees
    /// of freedom. What a pair shares, the cost of its view, cancels in
    /// aᵢ − R·bᵢ; along a path it varies far more than either mode's noise,
    /// and two unpaired means would count it in the interval (a test below
    /// shows a 5 % difference that they cannot tell and the pairs can).
    /// Frames are taken as independent: a mode's hiccup that lasts several
    /// frames makes the interval too narrow. `None` under [`LEAST_PAIRS`]
    /// pairs, or where a mean is not finite or the second not positive.
    pub fn of(pairs: &[(f64, f64)]) -> Option<PairedRatio> {
        let n = pairs.len() as f64;
        let mean = |side: fn(&(f64, f64)) -> f64| pairs.iter().map(side).sum::<f64>() / n;
        let (a, b) = (mean(|p| p.0), mean(|p| p.1));
        if pairs.len() < LEAST_PAIRS || !a.is_finite() || !b.is_finite() || b <= 0.0 {
            return None;
        }
        let ratio = a / b;
        let residual = |&(x, y): &(f64, f64)| x - ratio * y;
        let variance = pairs.iter().map(|p| residual(p).powi(2)).sum::<f64>() / (n - 1.0);
        let half = student_t_95(n - 1.0) * variance.sqrt() / (n.sqrt() * b);
        Some(PairedRatio {
            ratio,
            interval: [ratio - half, ratio + half],
        })
    }
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * q;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (h - lo as f64)
}

/// Reads one column of a row; `None` where the row has no value.
type Column = fn(&FrameStats) -> Option<f64>;

/// The summarised columns of frames.csv, with how to read each.
const COLUMNS: &[(&str, Column)] = &[
    ("frame_ms", |r| Some(r.frame_ms)),
    ("cpu_ms", |r| Some(r.cpu_ms)),
    ("maintenance_ms", |r| Some(r.maintenance_ms)),
    ("gpu_ms", |r| r.gpu_ms),
    ("objects_drawn", |r| Some(r.objects_drawn as f64)),
    ("triangles_drawn", |r| Some(r.triangles_drawn as f64)),
    ("queries", |r| Some(r.queries as f64)),
    ("query_batches", |r| Some(r.query_batches as f64)),
    ("query_wait_ms", |r| Some(r.query_wait_ms)),
    ("query_gpu_ms", |r| r.query_gpu_ms),
    ("pyramid_gpu_ms", |r| r.pyramid_gpu_ms),
    ("render_ms", |r| Some(r.render_ms())),
    ("error_pixels", |r| r.error_pixels.map(|v| v as f64)),
    ("max_depth_error", |r| r.max_depth_error),
    ("missed_objects", |r| r.missed_objects.map(|v| v as f64)),
];

/// One mode's summary in summary.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModeSummary {
    pub name: String,
    /// Whether the mode promises zero error.
    pub conservative: bool,
    pub parameters: serde_json::Value,
    pub frames: usize,
    pub stats: BTreeMap<String, Distribution>,
    /// Mean frame time of vfc over this mode's (> 1: faster than vfc).
    pub speedup_vs_vfc: Option<f64>,
    /// Mean frame time of this mode over the oracle's (≥ 1 for real modes).
    pub ratio_to_oracle: Option<f64>,
    pub error_pixels_total: Option<u64>,
    pub frames_with_error: Option<u64>,
    pub missed_objects_total: Option<u64>,
    /// Mean fraction of the frame's pixels that are wrong.
    pub error_fraction: Option<f64>,
    /// For a mode that runs others (`auto`), what each of them drew: in
    /// order of first use; empty for other modes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strategies: Vec<StrategyShare>,
}

/// The frames one of `auto`'s strategies drew, and what they cost.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrategyShare {
    pub strategy: String,
    pub frames: usize,
    /// Of them, probes (run to be measured).
    pub probes: usize,
    pub mean_frame_ms: f64,
}

impl StrategyShare {
    /// Per strategy named in `rows` (one mode's), in order of first use.
    fn of(rows: &[&FrameStats]) -> Vec<StrategyShare> {
        let mut shares: Vec<(StrategyShare, f64)> = Vec::new();
        for r in rows {
            let Some(name) = &r.strategy else { continue };
            let at = match shares.iter().position(|(s, _)| &s.strategy == name) {
                Some(at) => at,
                None => {
                    let share = StrategyShare {
                        strategy: name.clone(),
                        frames: 0,
                        probes: 0,
                        mean_frame_ms: 0.0,
                    };
                    shares.push((share, 0.0));
                    shares.len() - 1
                }
            };
            let (share, total) = &mut shares[at];
            share.frames += 1;
            share.probes += usize::from(r.probe == Some(true));
            *total += r.frame_ms;
        }
        shares
            .into_iter()
            .map(|(share, total)| StrategyShare {
                mean_frame_ms: total / share.frames as f64,
                ..share
            })
            .collect()
    }
}

/// What summarize needs to know of a mode besides its rows.
pub struct ModeDescription {
    pub name: String,
    pub conservative: bool,
    pub parameters: serde_json::Value,
}

/// Summaries in the order of `modes`; `pixels` is the frame size.
pub fn summarize(rows: &[FrameStats], modes: &[ModeDescription], pixels: u64) -> Vec<ModeSummary> {
    let mean_frame = |name: &str| {
        let v: Vec<f64> = rows.iter().filter(|r| r.mode == name).map(|r| r.frame_ms).collect();
        Distribution::of(&v).map(|d| d.mean)
    };
    let (vfc, oracle) = (mean_frame("vfc"), mean_frame("oracle"));
    modes
        .iter()
        .map(|m| {
            let mine: Vec<&FrameStats> = rows.iter().filter(|r| r.mode == m.name).collect();
            let columns = COLUMNS.iter().map(|&(name, get)| {
                let v: Vec<f64> = mine.iter().filter_map(|r| get(r)).collect();
                (name, v)
            });
            // The mode's counters, by name, whatever they are.
            let counters = TraversalStats::COUNTERS.iter().enumerate().map(|(k, &name)| {
                let v: Vec<f64> = mine
                    .iter()
                    .filter_map(|r| r.traversal.counts().nth(k))
                    .map(|c| c as f64)
                    .collect();
                (name, v)
            });
            let stats = columns
                .chain(counters)
                .filter_map(|(name, v)| Distribution::of(&v).map(|d| (name.to_string(), d)))
                .collect::<BTreeMap<_, _>>();
            let mean = stats.get("frame_ms").map(|d| d.mean);
            let errors: Option<Vec<u64>> = mine.iter().map(|r| r.error_pixels).collect();
            let missed: Option<Vec<u64>> = mine.iter().map(|r| r.missed_objects).collect();
            ModeSummary {
                name: m.name.clone(),
                conservative: m.conservative,
                parameters: m.parameters.clone(),
                frames: mine.len(),
                speedup_vs_vfc: vfc.zip(mean).map(|(v, x)| v / x),
                ratio_to_oracle: oracle.zip(mean).map(|(o, x)| x / o),
                error_pixels_total: errors.as_ref().map(|e| e.iter().sum()),
                frames_with_error: errors.as_ref().map(|e| e.iter().filter(|&&v| v > 0).count() as u64),
                missed_objects_total: missed.map(|m| m.iter().sum()),
                error_fraction: errors
                    .filter(|e| !e.is_empty())
                    .map(|e| e.iter().sum::<u64>() as f64 / (e.len() as f64 * pixels as f64)),
                strategies: StrategyShare::of(&mine),
                stats,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distribution_matches_hand_computed_values() {
        let d = Distribution::of(&[4.0, 1.0, 3.0, 2.0, 100.0]).unwrap();
        assert_eq!(d.mean, 22.0);
        assert_eq!(d.median, 3.0);
        assert_eq!((d.min, d.max), (1.0, 100.0));
        // |x - 3| = 1, 2, 0, 1, 97 → median 1.
        assert_eq!(d.mad, 1.0);
        // Type 7: h = 4·0.95 = 3.8 → 4 + 0.8·(100 − 4).
        assert!((d.p95 - 80.8).abs() < 1e-12);
        assert!(
            (d.stddev
                - (((18f64.powi(2) + 21f64.powi(2) + 19f64.powi(2) + 20f64.powi(2) + 78f64.powi(2)) / 4.0).sqrt()))
            .abs()
                < 1e-12
        );
        assert_eq!(Distribution::of(&[]), None);
        assert_eq!(Distribution::of(&[7.0]).unwrap().stddev, 0.0);
    }

    #[test]
    fn a_paired_ratio_matches_the_delta_method_worked_by_hand() {
        // ā = 5, b̄ = 2.575, R = 5 / 2.575; the residuals aᵢ − R·bᵢ, their
        // variance over n − 1 = 3, and Student's t of 3 degrees of freedom
        // from the tables, 3.1824.
        let pairs = [(2.0, 1.0), (4.0, 2.0), (6.0, 3.3), (8.0, 4.0)];
        let r = PairedRatio::of(&pairs).unwrap();
        let ratio = 5.0 / 2.575;
        let residuals = [2.0 - ratio, 4.0 - 2.0 * ratio, 6.0 - 3.3 * ratio, 8.0 - 4.0 * ratio];
        let sd = (residuals.iter().map(|e| e * e).sum::<f64>() / 3.0).sqrt();
        let half = 3.1824 * sd / (2.0 * 2.575);
        assert!((r.ratio - ratio).abs() < 1e-12);
        assert!(
            (r.interval[0] - (ratio - half)).abs() < 2e-3 * half,
            "{r:?} against ±{half}"
        );
        assert!(
            (r.interval[1] - (ratio + half)).abs() < 2e-3 * half,
            "{r:?} against ±{half}"
        );
        assert_eq!(PairedRatio::of(&pairs[..3]), None, "three pairs say too little");
        assert_eq!(PairedRatio::of(&[(2.0, 0.0); 4]), None);
        assert_eq!(PairedRatio::of(&[(f64::INFINITY, 1.0); 4]), None);
    }

    #[test]
    fn students_t_is_the_tables_within_a_fraction_of_a_percent() {
        // Two-sided 95 % quantiles from the tables.
        for (dof, table) in [
            (3.0, 3.1824),
            (5.0, 2.5706),
            (9.0, 2.2622),
            (29.0, 2.0452),
            (119.0, 1.9801),
        ] {
            let t = student_t_95(dof);
            assert!((t / table - 1.0).abs() < 1.5e-3, "{dof}: {t} against {table}");
        }
    }

    #[test]
    fn pairing_frames_tells_apart_modes_whose_difference_the_path_would_hide() {
        // Along a path the view's cost varies by ±40 %, and one mode costs
        // 5 % more than the other in 3 % noise.
        let mut rng = crate::rng::Rng::new(3);
        let pairs: Vec<(f64, f64)> = (0..120)
            .map(|i| {
                let view = 20.0 * (1.0 + 0.4 * (f64::from(i) / 9.0).sin());
                (1.05 * view * rng.range(0.97, 1.03), view * rng.range(0.97, 1.03))
            })
            .collect();
        let paired = PairedRatio::of(&pairs).unwrap();
        let [low, high] = paired.interval;
        assert!(1.0 < low && low < 1.05 && 1.05 < high, "{paired:?}");
        // The same frames as two unpaired means do not tell them apart.
        let [a, b] = [|p: &(f64, f64)| p.0, |p: &(f64, f64)| p.1]
            .map(|side| Distribution::of(&pairs.iter().map(side).collect::<Vec<_>>()).unwrap());
        let unpaired = 1.96 * (a.stddev.powi(2) + b.stddev.powi(2)).sqrt() / (120f64.sqrt() * b.mean);
        assert!(paired.ratio - unpaired < 1.0, "{unpaired}");
    }

    fn row(mode: &str, frame_ms: f64, error: Option<u64>) -> FrameStats {
        FrameStats {
            frame_ms,
            objects_drawn: 1,
            triangles_drawn: 10,
            error_pixels: error,
            max_depth_error: error.map(|_| 0.0),
            missed_objects: error.map(|_| 0),
            ..FrameStats::blank(mode)
        }
    }

    #[test]
    fn speedups_and_errors_are_relative_to_vfc_and_oracle() {
        let rows = vec![
            row("vfc", 30.0, Some(0)),
            row("vfc", 50.0, Some(0)),
            row("oracle", 10.0, Some(0)),
            row("dr", 80.0, Some(5)),
            row("dr", 80.0, Some(0)),
        ];
        let desc = |n: &str| ModeDescription {
            name: n.into(),
            conservative: true,
            parameters: serde_json::json!({}),
        };
        let s = summarize(&rows, &[desc("dr"), desc("vfc"), desc("oracle")], 100);
        assert_eq!(s[0].speedup_vs_vfc, Some(0.5));
        assert_eq!(s[0].ratio_to_oracle, Some(8.0));
        assert_eq!(s[0].error_pixels_total, Some(5));
        assert_eq!(s[0].frames_with_error, Some(1));
        assert_eq!(s[0].error_fraction, Some(5.0 / 200.0));
        assert_eq!(s[1].speedup_vs_vfc, Some(1.0));
        assert!(!s[0].stats.contains_key("gpu_ms"), "absent columns are left out");
    }

    #[test]
    fn every_counter_is_summarised_by_name() {
        let mut row = FrameStats::blank("vfc");
        row.traversal.queries_delayed = 7;
        let vfc = ModeDescription {
            name: "vfc".into(),
            conservative: true,
            parameters: serde_json::json!({}),
        };
        let summary = summarize(&[row], &[vfc], 100);
        for name in TraversalStats::COUNTERS {
            assert!(summary[0].stats.contains_key(*name), "{name}");
        }
        assert_eq!(summary[0].stats["queries_delayed"].mean, 7.0);
    }
}
