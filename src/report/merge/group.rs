//! Which folders are one run, and whether they agree: folders grouped by
//! run (refused when one run's folders measured different things, or one
//! adapter holds two results), runs named, a matrix's missing runs found,
//! and each run's table of modes by adapter, cross-checked between
//! adapters of one backend.

use std::collections::BTreeSet;

use super::error::MergeError;
use super::merged::{
    AdapterColumn, Disagreement, MergedRun, MissingRuns, ModeResult, ModeRow, adapter_label, column_folder, unique,
};
use super::read::RunFolder;
use crate::cull::{CountKind, ModeId};
use crate::gpu::AdapterReport;
use crate::report::summary::{Fingerprint, MatrixIdentity, Summary, same_count};

impl RunFolder {
    /// Which run it is: its matrix run's name, or its scene's and path's.
    fn run(&self) -> String {
        let s = &self.summary;
        s.run
            .clone()
            .unwrap_or_else(|| format!("{}, {}", s.scene.facts.source, s.path.source))
    }

    /// Whether `other` is the same run ([`one_run`]).
    fn same_run(&self, other: &RunFolder) -> bool {
        one_run(&self.summary, &other.summary)
    }

    /// The first thing `other`, the same run, measured differently, if
    /// any: what it is and each folder's value. What a user sets (frames,
    /// resolution, warmup, cluster size, mode parameters) comes before the
    /// fingerprints, which a different frame count changes too, so the
    /// message names the real difference.
    fn differs_from(&self, other: &RunFolder) -> Option<(&'static str, String, String)> {
        let (a, b) = (&self.summary, &other.summary);
        let identity = |what, (source_a, fa): (&String, Option<Fingerprint>), (source_b, fb)| {
            let show = |source: &String, f: Option<Fingerprint>| match f {
                Some(f) if source_a == source_b => format!("{source} #{:016x}", f.fnv1a),
                _ => source.clone(),
            };
            (!same_thing((source_a, fa), (source_b, fb))).then(|| (what, show(source_a, fa), show(source_b, fb)))
        };
        let plain = |what, x: String, y: String| (x != y).then_some((what, x, y));
        let matrices = match (a.matrix, b.matrix) {
            (Some(x), Some(y)) => plain("matrices", x.to_string(), y.to_string()),
            // A file from before matrices were recorded is judged by the rest.
            _ => None,
        };
        matrices
            .or_else(|| a.settings_differing_from(b))
            .or_else(|| {
                identity(
                    "scenes",
                    (&a.scene.facts.source, a.scene.facts.geometry),
                    (&b.scene.facts.source, b.scene.facts.geometry),
                )
            })
            .or_else(|| {
                identity(
                    "paths",
                    (&a.path.source, a.path.cameras),
                    (&b.path.source, b.path.cameras),
                )
            })
    }

    fn adapter(&self) -> (String, String) {
        (self.summary.adapter.name.clone(), self.summary.adapter.backend.clone())
    }
}

/// Whether the results `a` and `b` are of one run: the same matrix run by
/// name, or, outside a matrix, the same scene and path by their
/// fingerprints (by their sources' names for files from before
/// fingerprints, so that `held.json` and `/abs/held.json` are one path when
/// they can be told).
pub(crate) fn one_run(a: &Summary, b: &Summary) -> bool {
    match (&a.run, &b.run) {
        (Some(x), Some(y)) => x == y,
        (None, None) => {
            same_thing(
                (&a.scene.facts.source, a.scene.facts.geometry),
                (&b.scene.facts.source, b.scene.facts.geometry),
            ) && same_thing((&a.path.source, a.path.cameras), (&b.path.source, b.path.cameras))
        }
        _ => false,
    }
}

/// Whether two scenes or paths (a source's name and its fingerprint) are
/// one: by fingerprint when both have one, else by name.
fn same_thing((source_a, fa): (&String, Option<Fingerprint>), (source_b, fb): (&String, Option<Fingerprint>)) -> bool {
    match (fa, fb) {
        (Some(fa), Some(fb)) => fa == fb,
        _ => source_a == source_b,
    }
}

/// The folders of each run, runs in name order (a matrix's order), each
/// run's folders in adapter order; refuses folders of one run that differ
/// in what they measured, and two different results of one run on one
/// adapter (copies of one result count once).
pub(super) fn group(mut folders: Vec<RunFolder>) -> Result<Vec<Vec<RunFolder>>, MergeError> {
    folders.sort_by_key(|f| (f.run(), f.adapter()));
    let mut groups: Vec<Vec<RunFolder>> = Vec::new();
    for folder in folders {
        let Some(group) = groups.iter_mut().find(|g| g[0].same_run(&folder)) else {
            groups.push(vec![folder]);
            continue;
        };
        let first = &group[0];
        if let Some((what, first_value, second_value)) = first.differs_from(&folder) {
            return Err(MergeError::NotOneRun {
                run: folder.run(),
                folders: Box::new([first.dir.clone(), folder.dir]),
                what,
                values: Box::new([first_value, second_value]),
            });
        }
        if let Some(same_adapter) = group.iter().find(|f| f.adapter() == folder.adapter()) {
            let summary = &same_adapter.summary;
            let copies = summary.frames_csv.is_some() && summary.frames_csv == folder.summary.frames_csv;
            if copies {
                continue;
            }
            return Err(MergeError::Ambiguous {
                run: folder.run(),
                adapter: adapter_label(&folder.summary.adapter.name, &folder.summary.adapter.backend),
                first: same_adapter.dir.clone(),
                second: folder.dir,
            });
        }
        group.push(folder);
    }
    for group in &mut groups {
        group.sort_by_key(RunFolder::adapter);
    }
    Ok(groups)
}

/// Each run's folders under a name of its own, runs in name order. A run
/// is named by its matrix run's name, unique in its matrix (two matrices
/// are never merged), or by its scene's and path's; two runs outside a
/// matrix that measured other scenes or paths of one name (a changed file,
/// a generated path of other frames) get their fingerprints' hash after
/// it, so the name is the same whatever order the folders came in.
pub(super) fn named(groups: Vec<Vec<RunFolder>>) -> Vec<(String, Vec<RunFolder>)> {
    let plain: Vec<String> = groups.iter().map(|g| g[0].run()).collect();
    let mut named: Vec<(String, Vec<RunFolder>)> = groups
        .into_iter()
        .zip(&plain)
        .map(|(folders, name)| {
            if plain.iter().filter(|&n| n == name).count() == 1 {
                return (name.clone(), folders);
            }
            (format!("{name} {}", contents_tag(&folders[0].summary)), folders)
        })
        .collect();
    named.sort_by(|a, b| a.0.cmp(&b.0));
    named
}

/// What [`named`] puts after the name of a run whose name another run
/// shares: `#` and a hash of its scene's and path's fingerprints.
fn contents_tag(summary: &Summary) -> String {
    let identity = format!("{:?}\n{:?}", summary.scene.facts.geometry, summary.path.cameras);
    format!("#{:08x}", Fingerprint::of(identity.as_bytes()).fnv1a >> 32)
}

/// The runs of each matrix among `runs` that none of them is: by place
/// (`02`), as the matrix's run folders are named.
pub(super) fn missing_runs(runs: &[(String, Vec<RunFolder>)]) -> Vec<MissingRuns> {
    let mut matrices: Vec<(MatrixIdentity, BTreeSet<usize>)> = Vec::new();
    for (_, folders) in runs {
        let s = &folders[0].summary;
        let (Some(matrix), Some(name)) = (s.matrix, &s.run) else {
            continue;
        };
        let place = name.split('-').next().and_then(|digits| digits.parse::<usize>().ok());
        let at = match matrices.iter().position(|(m, _)| *m == matrix) {
            Some(at) => at,
            None => {
                matrices.push((matrix, BTreeSet::new()));
                matrices.len() - 1
            }
        };
        matrices[at].1.extend(place);
    }
    matrices
        .into_iter()
        .filter_map(|(matrix, present)| {
            let width = MatrixIdentity::place_width(matrix.runs);
            let absent: Vec<String> = (1..=matrix.runs)
                .filter(|p| !present.contains(p))
                .map(|p| format!("{p:0width$}"))
                .collect();
            (!absent.is_empty()).then_some(MissingRuns {
                matrix,
                present: matrix.runs - absent.len(),
                runs: absent,
            })
        })
        .collect()
}

/// One run's table, columns and cross-check (its chart comes later).
pub(super) fn merged_run(name: &str, folders: &[RunFolder], used: &mut BTreeSet<String>) -> MergedRun {
    let first = &folders[0].summary;
    let adapters: Vec<AdapterColumn> = folders
        .iter()
        .map(|f| {
            let a = &f.summary.adapter;
            let folder = unique(column_folder(name, &a.name, &a.backend), "", used);
            AdapterColumn {
                name: a.name.clone(),
                backend: a.backend.clone(),
                device_type: a.device_type.clone(),
                folder,
                merged_from: f.dir.to_string_lossy().into_owned(),
                skipped: f.summary.skipped.clone(),
                error_measured: f.summary.error_measured,
            }
        })
        .collect();
    let mut names: Vec<&str> = Vec::new();
    for m in folders.iter().flat_map(|f| &f.summary.modes) {
        if !names.contains(&m.name.as_str()) {
            names.push(&m.name);
        }
    }
    let modes: Vec<ModeRow> = names
        .iter()
        .map(|&mode| ModeRow {
            mode: mode.to_string(),
            results: folders
                .iter()
                .map(|f| f.summary.modes.iter().find(|m| m.name == mode).map(ModeResult::of))
                .collect(),
        })
        .collect();
    let reports: Vec<&AdapterReport> = folders.iter().map(|f| &f.summary.adapter).collect();
    let disagreements = cross_check(&reports, &modes);
    MergedRun {
        name: name.to_string(),
        scene: first.scene.facts.source.clone(),
        path: first.path.source.clone(),
        resolution: first.resolution,
        frames: first.frames,
        adapters,
        modes,
        disagreements,
        chart: None,
    }
}

/// Reads a counter of a [`ModeResult`].
type Counter = fn(&ModeResult) -> Option<f64>;

/// The counters every adapter of one backend must agree on, by name.
const SAME_ON_EVERY_ADAPTER: [(&str, Counter); 4] = [
    ("objects_drawn", |r| r.objects_drawn),
    ("triangles_drawn", |r| r.triangles_drawn),
    ("queries", |r| r.queries),
    ("error_pixels", |r| r.error_pixels.map(|v| v as f64)),
];

/// The counters of [`SAME_ON_EVERY_ADAPTER`] that differ between adapters
/// (`adapters`, in the columns' order) of one backend: what a mode got
/// wrong on every adapter of it, what it did on those that do alike work
/// ([`AdapterReport::work_differs_from`]: sub-pixel precision sets box
/// tests' margins).
fn cross_check(adapters: &[&AdapterReport], modes: &[ModeRow]) -> Vec<Disagreement> {
    // The adapters a counter of `kind` compares adapter `i` with, named
    // by the first of them.
    let group_of = |kind: CountKind, i: usize| {
        (0..i)
            .find(|&j| match kind {
                CountKind::Error => adapters[j].backend == adapters[i].backend,
                CountKind::Work => adapters[j].work_differs_from(adapters[i]).is_none(),
            })
            .unwrap_or(i)
    };
    let backends: BTreeSet<&str> = adapters.iter().map(|a| a.backend.as_str()).collect();
    let mut found = Vec::new();
    for row in modes {
        for &backend in &backends {
            // What follows a mode's measured times differs between adapters
            // as their times do.
            for (counter, value) in SAME_ON_EVERY_ADAPTER {
                let kind = if counter == "error_pixels" {
                    CountKind::Error
                } else {
                    CountKind::Work
                };
                if ModeId::counts_follow_time(&row.mode, kind) {
                    continue;
                }
                let groups: BTreeSet<usize> = (0..adapters.len())
                    .filter(|&i| adapters[i].backend == backend)
                    .map(|i| group_of(kind, i))
                    .collect();
                for group in groups {
                    let values: Vec<(String, f64)> = (0..adapters.len())
                        .filter(|&i| group_of(kind, i) == group)
                        .filter_map(|i| Some((adapters[i].name.clone(), value(row.results[i].as_ref()?)?)))
                        .collect();
                    if values.iter().any(|(_, v)| !same_count(values[0].1, *v)) {
                        found.push(Disagreement {
                            mode: row.mode.clone(),
                            counter: counter.into(),
                            backend: backend.into(),
                            values,
                        });
                    }
                }
            }
        }
    }
    found
}
