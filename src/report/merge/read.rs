//! The result folders a merge reads: each DIR resolved to its run folders
//! (a run's folder, or the folders in a matrix's), each read once, with the
//! result files to copy; an output that overlaps an input refused.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::error::MergeError;
use crate::report::charts::CHARTS;
use crate::report::files::ReportError;
use crate::report::summary::Summary;
use crate::report::{RESULT_FILES, read_results, where_written};

/// One result folder read for the merge.
pub(super) struct RunFolder {
    pub(super) dir: PathBuf,
    pub(super) summary: Summary,
    /// The result files it holds, to be copied.
    pub(super) files: Vec<&'static str>,
}

/// The run folders in `dirs` (each one, or the folders in it that hold a
/// run), each read once; refused when there are none, or when `out`
/// overlaps one of `dirs`.
pub(super) fn read_run_folders(dirs: &[PathBuf], out: &Path) -> Result<Vec<RunFolder>, MergeError> {
    if dirs.is_empty() {
        return Err(MergeError::NoFolders);
    }
    // A folder given twice (or as itself and inside its matrix folder) is
    // read once.
    let mut seen = BTreeSet::new();
    let mut folders = Vec::new();
    for dir in dirs {
        refuse_overlap(dir, out)?;
        for run_dir in run_folders(dir)? {
            let canonical = std::fs::canonicalize(&run_dir).map_err(ReportError::at(&run_dir))?;
            if !seen.insert(canonical) {
                continue;
            }
            let (summary, _) = read_results(&run_dir)?;
            let files = result_files(&run_dir)?;
            folders.push(RunFolder {
                dir: run_dir,
                summary,
                files,
            });
        }
    }
    Ok(folders)
}

/// Refuses an `out` that is `input`, lies inside it or holds it: the merge
/// would write over (or into) what it reads. `out` need not exist yet, so
/// it is taken where the system will put it ([`where_written`]: `..` after
/// a folder the merge makes goes back to where it was made).
fn refuse_overlap(input: &Path, out: &Path) -> Result<(), MergeError> {
    let input_path = std::fs::canonicalize(input).map_err(ReportError::at(input))?;
    let Some(out_path) = where_written(out) else {
        // No current folder to put a relative `out` in: nothing is written.
        return Ok(());
    };
    if out_path.starts_with(&input_path) || input_path.starts_with(&out_path) {
        return Err(MergeError::OutOverlapsInput {
            out: out.to_path_buf(),
            input: input.to_path_buf(),
        });
    }
    Ok(())
}

/// `dir` itself when it holds a run, else the folders in it (in name
/// order), each of which must hold a run: a folder without one is a run
/// that failed or is still running, and a matrix without it is not whole.
/// Hidden folders (`.occlu-staging-…`) are not runs and are passed over.
fn run_folders(dir: &Path) -> Result<Vec<PathBuf>, MergeError> {
    if dir.join("summary.json").exists() {
        return Ok(vec![dir.to_path_buf()]);
    }
    if dir.join("merged.json").exists() {
        return Err(MergeError::MergedFolder(dir.to_path_buf()));
    }
    let entries = std::fs::read_dir(dir).map_err(ReportError::at(dir))?;
    let mut runs = Vec::new();
    for entry in entries {
        let entry = entry.map_err(ReportError::at(dir))?;
        let path = entry.path();
        if entry.file_name().as_encoded_bytes().starts_with(b".") || !path.is_dir() {
            continue;
        }
        if !path.join("summary.json").exists() {
            return Err(MergeError::NotARun {
                matrix: dir.to_path_buf(),
                folder: path,
            });
        }
        runs.push(path);
    }
    if runs.is_empty() {
        return Err(MergeError::NoRuns(dir.to_path_buf()));
    }
    runs.sort();
    Ok(runs)
}

/// The result files a run folder holds (not its lock or anything else),
/// each a regular file: a link, device or pipe of one of their names is
/// refused by name, since copying it would put another file into the
/// merged artefact (or read forever).
fn result_files(dir: &Path) -> Result<Vec<&'static str>, ReportError> {
    let names = RESULT_FILES.into_iter().chain(CHARTS);
    let mut present = Vec::new();
    for name in names {
        let path = dir.join(name);
        match std::fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Ok(m) if m.is_file() => present.push(name),
            Ok(_) => {
                let error = std::io::Error::other(
                    "not a regular file (a link, a device or a pipe): merge copies a run's own files only",
                );
                return Err(ReportError::at(&path)(error));
            }
            Err(e) => return Err(ReportError::at(&path)(e)),
        }
    }
    Ok(present)
}
