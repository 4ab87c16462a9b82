//! Result files of a bench run: frames.csv (one row per mode and frame),
//! summary.json (machine-readable, versioned) and report.md (for people);
//! `occlu compare` and `occlu merge` read them back.

pub mod charts;
mod claim;
pub mod compare;
mod files;
pub mod github;
mod markdown;
pub mod merge;
mod summary;
mod trace;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::cull::ModeId;
use crate::measure::{FrameStats, MissedObject, ModeDescription, RowLimits, summarize};
use crate::text;

use claim::{LOCK, STAGING, claim, staging};
pub use claim::{OutputLock, abandon_unfinished};
use files::where_written;
pub use files::{
    ReportError, Staged, check_writable, refuse_input_as_output, refuse_one_file_twice, stage_whole, write_png,
    write_whole,
};
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

/// Reads a run directory's summary.json alone, checked as
/// [`read_results`] checks it (its statistics as written, not recomputed).
pub fn read_summary(dir: &Path) -> Result<Summary, ReportError> {
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
    // A matrix's run count bounds what merge counts through for its
    // missing runs.
    if let Some(matrix) = summary.matrix
        && !(1..=MatrixIdentity::MAX_RUNS).contains(&matrix.runs)
    {
        return Err(io(&json_path)(std::io::Error::other(format!(
            "its matrix lists {} runs, not 1 to the {} a matrix may",
            matrix.runs,
            MatrixIdentity::MAX_RUNS
        ))));
    }
    Ok(summary)
}

/// Reads a run directory's summary.json and frames.csv (for `occlu plot`,
/// `occlu compare` and `occlu merge`): the rows checked against the
/// summary (every mode's every frame once, every value one a run can
/// measure), and the summary's statistics recomputed from them, so that
/// every command that reads a folder judges it by the same numbers.
pub fn read_results(dir: &Path) -> Result<(Summary, Vec<FrameStats>), ReportError> {
    let io = ReportError::at;
    let summary = read_summary(dir)?;
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
    check_rows(&summary, &rows).map_err(|e| io(&csv_path)(std::io::Error::other(e)))?;
    let modes: Vec<ModeDescription> = summary
        .modes
        .iter()
        .map(|m| ModeDescription {
            name: m.name.clone(),
            conservative: m.conservative,
            parameters: m.parameters.clone(),
        })
        .collect();
    let modes = summarize(&rows, &modes, summary.resolution.pixels());
    let ids: Option<Vec<ModeId>> = modes.iter().map(|m| ModeId::of_label(&m.name)).collect();
    let summary = Summary {
        // A summary naming a mode this occlu does not know (an older
        // one's) keeps its own verdict.
        verdict: match ids {
            Some(ids) => Verdict::of(&modes, &ids, &rows),
            None => summary.verdict.clone(),
        },
        modes,
        ..summary
    };
    Ok((summary, rows))
}

/// Whether `rows` are what a run of `summary` measured: each of its modes
/// (named once) with one row for each of its frames, and no value a run
/// cannot measure ([`FrameStats::implausible`]); else what is wrong.
fn check_rows(summary: &Summary, rows: &[FrameStats]) -> Result<(), String> {
    let frames = summary.frames;
    if frames == 0 || frames > crate::camera::path::MAX_FRAMES {
        return Err(format!("summary.json's frames {frames} is not a frame count a run has"));
    }
    let limits = RowLimits {
        pixels: summary.resolution.pixels(),
        objects: summary.scene.facts.objects as u64,
        triangles: summary.scene.facts.triangles,
    };
    // Each mode's frames seen so far, by the mode's place in the summary.
    let mut seen: Vec<Vec<bool>> = Vec::with_capacity(summary.modes.len());
    for (k, mode) in summary.modes.iter().enumerate() {
        if summary.modes[..k].iter().any(|m| m.name == mode.name) {
            return Err(format!("summary.json names mode {} twice", mode.name));
        }
        seen.push(vec![false; frames as usize]);
    }
    for (k, row) in rows.iter().enumerate() {
        let at = || format!("row {} ({}, frame {})", k + 1, row.mode, row.frame);
        let Some(mode) = summary.modes.iter().position(|m| m.name == row.mode) else {
            return Err(format!("{}: a mode summary.json does not list", at()));
        };
        match seen[mode].get_mut(row.frame as usize) {
            None => return Err(format!("{}: beyond the run's {frames} frames", at())),
            Some(true) => return Err(format!("{}: the frame's second row", at())),
            Some(first) => *first = true,
        }
        if let Some(fault) = row.implausible(limits) {
            return Err(format!("{}: {fault}", at()));
        }
    }
    for (mode, frames_seen) in summary.modes.iter().zip(&seen) {
        let count = frames_seen.iter().filter(|&&s| s).count();
        if count != frames as usize {
            return Err(format!(
                "mode {} has {}, not one for each of the run's {}",
                mode.name,
                text::count(count, "row"),
                text::count(frames as usize, "frame")
            ));
        }
    }
    Ok(())
}

/// The files a run writes into its folder (its charts, [`charts::CHARTS`],
/// besides), in the order merge copies them.
pub const RESULT_FILES: [&str; 5] = ["summary.json", "frames.csv", "missed.csv", "report.md", ANIMATION];

/// The files a run writes into its folder, all told: its results, its
/// charts and its lock.
fn run_files() -> Vec<&'static str> {
    RESULT_FILES.into_iter().chain(charts::CHARTS).chain([LOCK]).collect()
}

/// Refuses an `output` that is one of the files a run writes into `out`
/// (`--export-github-benchmark OUT/summary.json` would replace the run's
/// own), its lock included.
pub fn refuse_result_file(output: &Path, out: &Path) -> Result<(), ReportError> {
    let why = "is one of the run's own files in --out: writing it there would replace what the run wrote; choose another file";
    files::refuse_own_file(output, out, &run_files(), why)
}

/// Refuses an `input` of a run that is one of the files the run writes
/// into `out` (`--path OUT/summary.json`, a configuration or a glTF
/// buffer so named): the run would replace it.
pub fn refuse_input_among_results(input: &Path, out: &Path) -> Result<(), ReportError> {
    let why = "is an input of this command and one of the files the run writes into --out: the run would replace it; choose another --out";
    files::refuse_own_file(input, out, &run_files(), why)
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
        // A name that holds what the staged one cannot replace (a folder,
        // or a link to one, where a file goes, or the reverse) is refused
        // before anything moves, so `out` is left as it was, not half
        // replaced.
        for name in &names {
            let (staged, target) = (staging.join(name), out.join(name));
            if let Ok(held) = std::fs::metadata(&target)
                && held.is_dir() != staged.is_dir()
            {
                let what = match held.is_dir() {
                    true => "is a folder where occlu writes a file",
                    false => "is not a folder, where occlu writes one",
                };
                return Err(ReportError::at(&target)(std::io::Error::other(what)));
            }
        }
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

/// Writes `files` (names and contents) into `out` as [`publish`] does:
/// each whole or absent, a file or link of the same name replaced, never
/// written through.
pub fn publish_files(out: &Path, files: &[(&str, &[u8])]) -> Result<(), ReportError> {
    publish(out, &[], |staging| {
        for (name, bytes) in files {
            write_file(&staging.join(name), bytes)?;
        }
        Ok(files.iter().map(|(name, _)| name.to_string()).collect())
    })
    .map(drop)
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

/// `missed` with object names as a spreadsheet should show them: on one
/// line, with nothing that reorders or hides text ([`text::one_line`]),
/// and prefixed by `'` (which spreadsheets read as "text follows") where
/// it would run as a formula (starting with `=`, `+`, `-`, `@`, as OWASP
/// lists them). Names come from model files, which may come from anyone.
fn escape_formulas(missed: &[MissedObject]) -> Vec<MissedObject> {
    missed
        .iter()
        .map(|m| MissedObject {
            name: text::spreadsheet_safe(&text::one_line(&m.name)),
            ..m.clone()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hostile-input review's finding: a run's path file inside its --out,
    /// named as one of the files the run writes, was replaced by the run.
    #[test]
    fn an_input_named_as_one_of_the_runs_files_in_its_out_is_refused() {
        let out = tempfile::tempdir().unwrap();
        let path = out.path().join("summary.json");
        std::fs::write(&path, "{}").unwrap();
        let refused = refuse_input_among_results(&path, out.path()).unwrap_err().to_string();
        assert!(
            refused.contains("one of the files the run writes into --out"),
            "{refused}"
        );
        assert!(refuse_input_among_results(&out.path().join("walk.json"), out.path()).is_ok());
    }

    #[test]
    fn missed_csv_names_run_no_formula_and_hide_nothing() {
        let missed = MissedObject {
            mode: "vfc".into(),
            frame: 0,
            object: 3,
            name: "=wall\u{202E}gpj.exe\n".into(),
            drawn: false,
            wrong_pixels: 0,
            first_x: None,
            first_y: None,
        };
        let written = escape_formulas(std::slice::from_ref(&missed));
        assert_eq!(written[0].name, "'=wall\\u{202e}gpj.exe\\n");
    }

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
