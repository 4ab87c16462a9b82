//! `merge`: the command's flow. The folders are read, grouped and checked
//! before anything is written; then the merged folder is claimed and
//! filled (copies of the run folders, charts, report.md, merged.json last)
//! and published whole.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::error::MergeError;
use super::group::{group, merged_run, missing_runs, named};
use super::merged::{MERGED_SCHEMA_VERSION, Merged};
use super::read::{RunFolder, read_run_folders};
use super::render::{draw_chart, render};
use crate::report::files::ReportError;
use crate::report::summary::ToolInfo;
use crate::report::{prepare_output, publish, where_written};

/// Reads every run folder in `dirs` (each one, or the folders in it that
/// hold a run), checks that the folders of each run agree, and writes the
/// merged report into `out` (claimed while it is written, each file whole).
///
/// A matrix's runs must all be there: the runs a matrix lists and no folder
/// holds (a shard not merged, a run that failed) are refused by place
/// unless `allow_partial`, which merges the rest and names them in the
/// report and merged.json.
pub fn merge(dirs: &[PathBuf], out: &Path, allow_partial: bool) -> Result<Merged, MergeError> {
    let folders = read_run_folders(dirs, out)?;
    // A run's report.md and the merged one would share a name (a merged
    // folder, which holds neither of these, may be merged into again).
    let lands = where_written(out).unwrap_or_else(|| out.to_path_buf());
    if ["summary.json", "frames.csv"].iter().any(|f| lands.join(f).exists()) {
        return Err(MergeError::OutHoldsRun(out.to_path_buf()));
    }
    let groups = named(group(folders)?);
    let missing = missing_runs(&groups);
    if let Some(partial) = missing.first().filter(|_| !allow_partial) {
        return Err(MergeError::Partial(partial.clone()));
    }
    let _claim = prepare_output(out)?;
    let mut used = BTreeSet::new();
    let mut merged = Merged {
        schema_version: MERGED_SCHEMA_VERSION,
        tool: ToolInfo::current(),
        runs: groups
            .iter()
            .map(|(name, folders)| merged_run(name, folders, &mut used))
            .collect(),
        missing,
    };
    publish(out, &[], |staging| {
        for dir in ["runs", "charts"] {
            let path = staging.join(dir);
            std::fs::create_dir(&path).map_err(ReportError::at(&path))?;
        }
        for ((_, group), run) in groups.iter().zip(&mut merged.runs) {
            for (folder, column) in group.iter().zip(&run.adapters) {
                copy_run(folder, &staging.join(&column.folder))?;
            }
            draw_chart(staging, run, &mut used)?;
        }
        let write = |name: &str, text: String| {
            let path = staging.join(name);
            std::fs::write(&path, text).map_err(ReportError::at(&path))
        };
        write("report.md", render(&merged))?;
        let json = serde_json::to_string_pretty(&merged).map_err(|e| ReportError::at(staging)(e.into()))?;
        write("merged.json", json + "\n")?;
        // merged.json last: a reader never finds it beside older files.
        Ok(["runs", "charts", "report.md", "merged.json"]
            .map(String::from)
            .to_vec())
    })?;
    Ok(merged)
}

/// Copies a run folder's result files.
fn copy_run(run: &RunFolder, to: &Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(to).map_err(ReportError::at(to))?;
    for name in &run.files {
        let (source, target) = (run.dir.join(name), to.join(name));
        // Read, then written: an error names the file at fault.
        let bytes =
            crate::input::read_unlinked(&source, crate::input::MODEL_LIMIT).map_err(ReportError::at(&source))?;
        std::fs::write(&target, bytes).map_err(ReportError::at(&target))?;
    }
    Ok(())
}
