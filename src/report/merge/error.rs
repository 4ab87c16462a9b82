//! Why a merge is refused: folders that hold no run or a partial matrix,
//! one run's folders that measured different things, an output that would
//! overwrite what the merge reads.

use std::path::PathBuf;

use super::merged::MissingRuns;
use crate::report::files::ReportError;

#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error(transparent)]
    Read(#[from] ReportError),
    #[error("no result folders to merge: give one or more DIRs")]
    NoFolders,
    #[error("{}: not a result folder (no summary.json) and holds none", .0.display())]
    NoRuns(PathBuf),
    #[error("{}: a merged folder (merged.json), not a result folder: merge the run folders in its runs/ instead", .0.display())]
    MergedFolder(PathBuf),
    #[error(
        "{}: a folder of the matrix folder {} without summary.json (a run that failed or still runs?): a partial matrix is not merged; remove it or finish the run",
        folder.display(), matrix.display()
    )]
    NotARun { matrix: PathBuf, folder: PathBuf },
    #[error("a partial matrix: {}: merge every shard's folder, or give --allow-partial to merge these alone", .0.describe())]
    Partial(MissingRuns),
    #[error("--out {} holds a bench run: merging into it would replace its report.md; choose another --out", .0.display())]
    OutHoldsRun(PathBuf),
    #[error("--out {} is, holds or lies in the input {}: the merge would write over what it reads; choose another --out", out.display(), input.display())]
    OutOverlapsInput { out: PathBuf, input: PathBuf },
    #[error(
        "{} and {} are both run {run} but measured different {what} ({} vs {}): not one run (from two matrices?), so not merged",
        folders[0].display(), folders[1].display(), values[0], values[1]
    )]
    NotOneRun {
        run: String,
        folders: Box<[PathBuf; 2]>,
        what: &'static str,
        /// What each folder measured.
        values: Box<[String; 2]>,
    },
    #[error(
        "{} and {} both hold run {run} on {adapter} with different results: which one counts is ambiguous, so merge one of them",
        first.display(), second.display()
    )]
    Ambiguous {
        run: String,
        adapter: String,
        first: PathBuf,
        second: PathBuf,
    },
}

impl MergeError {
    /// Whether the user's input was at fault (as opposed to a full disk).
    pub fn is_input_error(&self) -> bool {
        match self {
            MergeError::Read(e) => e.is_input_error(),
            _ => true,
        }
    }
}
