//! Result files of a bench run: frames.csv (one row per mode and frame),
//! summary.json (machine-readable, versioned) and report.md (for people);
//! `occlu compare` and `occlu merge` read them back.

pub mod charts;
pub mod compare;
mod files;
pub mod github;
mod markdown;
pub mod merge;
mod summary;
mod trace;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::measure::{FrameStats, MissedObject};

pub use files::{ReportError, check_writable, write_png, write_whole};
pub use markdown::render as render_markdown;
pub use summary::{
    AnimationFact, CameraFact, Fingerprint, MatrixIdentity, MissedSummary, PathSummary, SCHEMA_VERSION, SceneFacts,
    SceneSummary, SkippedMode, Summary, SweepSummary, ToolInfo, Verdict,
};
pub use trace::trace_json;

/// The animated flythrough of `bench --animate`, beside the charts.
pub const ANIMATION: &str = "flythrough.png";

/// The files a run wrote.
pub struct ResultFiles {
    pub frames_csv: PathBuf,
    pub summary_json: PathBuf,
    pub report_md: PathBuf,
    /// Written only when a mode got something wrong.
    pub missed_csv: Option<PathBuf>,
    pub charts: Vec<PathBuf>,
    /// With `--animate`.
    pub animation: Option<PathBuf>,
}

/// `rows` as CSV with a header of field names. Made in memory, so writing
/// the file keeps the I/O error's kind (a full disk stays one) and its
/// fingerprint needs no second read.
fn csv_bytes<T: Serialize>(path: &Path, rows: &[T]) -> Result<Vec<u8>, ReportError> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    for row in rows {
        csv.serialize(row).map_err(|e| ReportError::at(path)(e.into()))?;
    }
    csv.into_inner().map_err(|e| ReportError::at(path)(e.into_error()))
}

/// Writes `bytes` to `path` (a fresh file in a staging folder).
fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    std::fs::write(path, bytes).map_err(ReportError::at(path))
}

/// Reads a run directory's summary.json and frames.csv (for `occlu plot`
/// and `occlu compare`).
pub fn read_results(dir: &Path) -> Result<(Summary, Vec<FrameStats>), ReportError> {
    let io = ReportError::at;
    let json_path = dir.join("summary.json");
    let text = crate::input::read_text(&json_path, crate::input::TEXT_LIMIT).map_err(io(&json_path))?;
    let summary: Summary = serde_json::from_str(&text)
        .map_err(|e| io(&json_path)(std::io::Error::other(format!("not an occlu summary: {e}"))))?;
    if summary.schema_version != SCHEMA_VERSION {
        return Err(io(&json_path)(std::io::Error::other(format!(
            "schema_version {} is not the {SCHEMA_VERSION} this occlu reads",
            summary.schema_version
        ))));
    }
    let csv_path = dir.join("frames.csv");
    let bytes = crate::input::read_file(&csv_path, crate::input::MODEL_LIMIT).map_err(io(&csv_path))?;
    if let Some(expected) = summary.frames_csv
        && Fingerprint::of(&bytes) != expected
    {
        return Err(io(&csv_path)(std::io::Error::other(
            "does not match summary.json: written by another run, or changed or cut short since",
        )));
    }
    let mut reader = csv::Reader::from_reader(bytes.as_slice());
    let rows = reader
        .deserialize()
        .collect::<Result<Vec<FrameStats>, _>>()
        .map_err(|e| io(&csv_path)(std::io::Error::other(format!("not an occlu frames.csv: {e}"))))?;
    Ok((summary, rows))
}

/// A run's claim on its `--out` folder: an exclusive lock on
/// `.occlu.lock`, held by the operating system for as long as this value
/// lives, and released by it when the process ends however it ends (a kill
/// included), so no claim outlives its run and no run can take over a live
/// one. The file itself stays; it holds the last claimant's process id, for
/// the message a refused run prints.
#[must_use = "the folder is claimed only while the lock lives"]
pub struct OutputLock {
    file: Option<std::fs::File>,
}

impl OutputLock {
    /// Whether the lock is held (false on a file system without locks).
    fn held(&self) -> bool {
        self.file.is_some()
    }
}

/// The lock file a claimed results folder holds.
const LOCK: &str = ".occlu.lock";

/// Removes `out` when it holds nothing but its lock: what a run that made
/// it and then failed leaves, which would read as a run that never
/// finished. Called once the claim is released.
pub fn remove_unused_output(out: &Path) {
    let only_lock = std::fs::read_dir(out).is_ok_and(|entries| entries.flatten().all(|e| e.file_name() == LOCK));
    if only_lock {
        let _ = std::fs::remove_file(out.join(LOCK));
        let _ = std::fs::remove_dir(out);
    }
}

/// Creates `out`, claims it (a second run into the same folder is refused
/// while the first holds it) and checks that files can be written there, so
/// a bad `--out` fails before a long run rather than after it.
pub fn prepare_output(out: &Path) -> Result<OutputLock, ReportError> {
    let claim = claim(out)?;
    let io = ReportError::at;
    let probe = staging(out);
    std::fs::create_dir_all(&probe).map_err(io(&probe))?;
    std::fs::remove_dir(&probe).map_err(io(&probe))?;
    if claim.held() {
        // Folders of runs that were killed while staging: no live run can
        // own one while this one holds the claim.
        for entry in std::fs::read_dir(out).into_iter().flatten().flatten() {
            if entry.file_name().to_string_lossy().starts_with(STAGING) {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
    Ok(claim)
}

/// Creates `out` and takes the lock on it.
fn claim(out: &Path) -> Result<OutputLock, ReportError> {
    let io = ReportError::at;
    if out.exists() && !out.is_dir() {
        let error = std::io::Error::other("exists and is not a directory: --out names the folder results go to");
        return Err(io(out)(error));
    }
    std::fs::create_dir_all(out).map_err(io(out))?;
    let path = out.join(LOCK);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(io(&path))?;
    match file.try_lock() {
        Ok(()) => {
            use std::io::{Seek as _, Write as _};
            file.set_len(0)
                .and_then(|()| file.rewind())
                .and_then(|()| write!(file, "{}", std::process::id()))
                .map_err(io(&path))?;
            Ok(OutputLock { file: Some(file) })
        }
        Err(std::fs::TryLockError::WouldBlock) => {
            use std::io::Read as _;
            let mut holder = String::new();
            let _ = (&file).take(32).read_to_string(&mut holder);
            let last = holder
                .trim()
                .parse::<u32>()
                .map_or(String::new(), |pid| format!(" (occlu process {pid} claimed it last)"));
            Err(io(&path)(std::io::Error::other(format!(
                "another occlu run{last} is writing results into this folder; wait for it, or write elsewhere"
            ))))
        }
        // A file system without locks (some network mounts) cannot hold a
        // claim; the run goes on unclaimed rather than not at all.
        Err(std::fs::TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
            Ok(OutputLock { file: None })
        }
        Err(std::fs::TryLockError::Error(e)) => Err(io(&path)(e)),
    }
}

/// Writes a set of result files (or folders of them) into `out` so that each is whole or absent:
/// `write` puts them into a fresh staging folder inside `out` and returns
/// their names in the order they are moved into place, and nothing is moved
/// until all are complete, so a failure (a full disk) leaves `out`'s
/// earlier contents as they were. `stale` names files an earlier run may
/// have left that this one does not write; they go first, so a reader never
/// takes an earlier run's file for this one's.
fn publish(
    out: &Path,
    stale: &[&str],
    write: impl FnOnce(&Path) -> Result<Vec<String>, ReportError>,
) -> Result<Vec<String>, ReportError> {
    let staging = staging(out);
    let _ = std::fs::remove_dir_all(&staging);
    let staged = std::fs::create_dir(&staging)
        .map_err(ReportError::at(&staging))
        .and_then(|()| write(&staging));
    let moved = staged.and_then(|names| {
        for name in stale {
            let path = out.join(name);
            match std::fs::remove_file(&path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(ReportError::at(&path)(e)),
                _ => {}
            }
        }
        for name in &names {
            let (staged, target) = (staging.join(name), out.join(name));
            // A folder replaces the earlier one whole (rename cannot
            // replace a folder that holds files).
            if staged.is_dir() && target.is_dir() {
                std::fs::remove_dir_all(&target).map_err(ReportError::at(&target))?;
            }
            std::fs::rename(&staged, &target).map_err(ReportError::at(&target))?;
        }
        Ok(names)
    });
    let _ = std::fs::remove_dir_all(&staging);
    moved
}

/// Writes a run's result files into `out` (see [`publish`]), with its
/// `animation` (an APNG) where there is one. summary.json records
/// frames.csv's fingerprint and is moved into place last, so
/// [`read_results`] refuses a folder caught between two runs' files.
pub fn write_results(
    out: &Path,
    summary: &mut Summary,
    rows: &[FrameStats],
    missed: &[MissedObject],
    animation: Option<&[u8]>,
) -> Result<ResultFiles, ReportError> {
    debug_assert_eq!(summary.missed, MissedSummary::of(missed), "the summary heads this list");
    summary.animation = animation.map(|_| ANIMATION.to_string());
    // An earlier run's list or animation must not pass for this run's.
    let stale: Vec<&str> = [(missed.is_empty(), "missed.csv"), (animation.is_none(), ANIMATION)]
        .into_iter()
        .filter_map(|(gone, name)| gone.then_some(name))
        .collect();
    let names = publish(out, &stale, |staging| {
        let frames_csv = csv_bytes(&staging.join("frames.csv"), rows)?;
        summary.frames_csv = Some(Fingerprint::of(&frames_csv));
        write_file(&staging.join("frames.csv"), &frames_csv)?;
        let mut names = vec!["frames.csv".to_string()];
        if !missed.is_empty() {
            let path = staging.join("missed.csv");
            write_file(&path, &csv_bytes(&path, &escape_formulas(missed))?)?;
            names.push("missed.csv".into());
        }
        if let Some(png) = animation {
            write_file(&staging.join(ANIMATION), png)?;
            names.push(ANIMATION.into());
        }
        names.extend(write_report_and_charts(staging, summary, rows)?);
        let json = serde_json::to_string_pretty(summary).expect("summary serialises: no maps with non-string keys");
        write_file(&staging.join("summary.json"), (json + "\n").as_bytes())?;
        names.push("summary.json".into());
        Ok(names)
    })?;
    let path = |name: &str| out.join(name);
    Ok(ResultFiles {
        frames_csv: path("frames.csv"),
        summary_json: path("summary.json"),
        report_md: path("report.md"),
        missed_csv: (!missed.is_empty()).then(|| path("missed.csv")),
        charts: names
            .iter()
            .filter(|n| n.ends_with(".png") && *n != ANIMATION)
            .map(|n| path(n))
            .collect(),
        animation: animation.map(|_| path(ANIMATION)),
    })
}

/// Draws a run's report.md and charts again from its summary and rows
/// (`occlu plot`), into `out` as [`write_results`] writes them; returns the
/// charts' paths.
pub fn rewrite_report(out: &Path, summary: &Summary, rows: &[FrameStats]) -> Result<Vec<PathBuf>, ReportError> {
    let names = publish(out, &[], |staging| write_report_and_charts(staging, summary, rows))?;
    Ok(names
        .iter()
        .filter(|n| n.ends_with(".png"))
        .map(|n| out.join(n))
        .collect())
}

/// Writes report.md and the charts into `dir`; returns their names.
fn write_report_and_charts(dir: &Path, summary: &Summary, rows: &[FrameStats]) -> Result<Vec<String>, ReportError> {
    write_file(&dir.join("report.md"), render_markdown(summary).as_bytes())?;
    let mut names = vec!["report.md".to_string()];
    for chart in charts::write_charts(dir, summary, rows)? {
        names.push(
            chart
                .file_name()
                .expect("a chart is a file")
                .to_string_lossy()
                .into_owned(),
        );
    }
    Ok(names)
}

/// The start of the name of the folder inside `--out` that a run writes its
/// results into before they are moved into place.
const STAGING: &str = ".occlu-staging";

/// This process's staging folder in `out`: one per process, so that runs
/// on a file system without locks do not write into each other's.
fn staging(out: &Path) -> PathBuf {
    out.join(format!("{STAGING}-{}", std::process::id()))
}

/// `missed` with object names that a spreadsheet would run as a formula
/// (starting with `=`, `+`, `-`, `@`, a tab or a carriage return, as OWASP
/// lists them) prefixed by `'`, which spreadsheets read as "text follows".
/// Names come from model files, which may come from anyone.
fn escape_formulas(missed: &[MissedObject]) -> Vec<MissedObject> {
    missed
        .iter()
        .map(|m| MissedObject {
            name: crate::text::spreadsheet_safe(&m.name),
            ..m.clone()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_files_follow_links_and_write_devices_in_place() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.json");
        std::fs::write(&target, "old").unwrap();
        std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_whole(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink(), "the link stays");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
        let mode = std::fs::metadata(&target).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o640, "the file keeps its permissions");
        // A pipe (as /dev/stdout may be) is written, not replaced.
        use std::os::unix::fs::FileTypeExt as _;
        let pipe = dir.path().join("pipe");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&pipe)
                .status()
                .unwrap()
                .success()
        );
        let reader = {
            let pipe = pipe.clone();
            std::thread::spawn(move || std::fs::read(pipe).unwrap())
        };
        check_writable(&pipe).unwrap();
        write_whole(&pipe, b"through").unwrap();
        assert!(std::fs::metadata(&pipe).unwrap().file_type().is_fifo(), "still a pipe");
        assert_eq!(reader.join().unwrap(), b"through");
        assert!(check_writable(dir.path()).is_err(), "a folder is no file");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 3, "no temporary file left");
    }
}
