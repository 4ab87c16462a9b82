//! A run's claim on its `--out` folder: the operating system's lock on
//! `.occlu.lock`, the folder made when it was missing, and the folder taken
//! away again when the run ends without results (an error, Ctrl-C, SIGTERM),
//! so that no folder holding only a lock reads as a run that never finished
//! (a later merge of the matrix would refuse it).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::files::ReportError;

/// A run's claim on its `--out` folder: an exclusive lock on
/// `.occlu.lock`, held by the operating system for as long as this value
/// lives, and released by it when the process ends however it ends (a kill
/// included), so no claim outlives its run and no run can take over a live
/// one. The file itself stays; it holds the last claimant's process id, for
/// the message a refused run prints. When the claim made the folder (and
/// folders above it), dropping it while the folder holds nothing but the
/// lock removes what it made.
#[must_use = "the folder is claimed only while the lock lives"]
pub struct OutputLock {
    file: Option<std::fs::File>,
    out: PathBuf,
    /// The topmost folder the claim created, if it created `out`.
    made: Option<PathBuf>,
}

impl OutputLock {
    /// Whether the lock is held (false on a file system without locks).
    pub(super) fn held(&self) -> bool {
        self.file.is_some()
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        forget(&self.out);
        if let Some(made) = &self.made {
            // Still locked: no other run can claim the folder meanwhile.
            remove_unfinished(&self.out, made);
        }
    }
}

/// The folders this process claims, with the topmost folder each claim
/// made (if it made its folder): what ending the process at once (a second
/// Ctrl-C, or one before the work listens) leaves when no claim is dropped.
static CLAIMED: Mutex<Vec<(PathBuf, Option<PathBuf>)>> = Mutex::new(Vec::new());

fn forget(out: &Path) {
    if let Ok(mut claimed) = CLAIMED.lock() {
        claimed.retain(|(o, _)| o != out);
    }
}

/// Tidies every folder this process claims, for a process about to end at
/// once, which drops no claim: [`abandon`] each.
pub fn abandon_unfinished() {
    // A claim being dropped on another thread holds the list briefly.
    let Ok(claimed) = CLAIMED.lock() else {
        return;
    };
    for (out, made) in claimed.iter() {
        abandon(out, made.as_deref());
    }
}

/// Takes away this process's staging folder in `out` (results it was
/// writing, now never to be whole) and, when the claim made `out` (`made`
/// its topmost new folder) and no results were written, the folder too.
fn abandon(out: &Path, made: Option<&Path>) {
    match made {
        Some(made) => remove_unfinished(out, made),
        None => {
            let _ = std::fs::remove_dir_all(staging(out));
        }
    }
}

/// Removes `out` when it holds nothing but its lock and this process's
/// staging folder, then the folders above it up to `made` (the topmost one
/// the claim created) while they are empty.
fn remove_unfinished(out: &Path, made: &Path) {
    let ours = staging(out);
    let _ = std::fs::remove_dir_all(&ours);
    let unused = std::fs::read_dir(out).is_ok_and(|entries| entries.flatten().all(|e| e.file_name() == LOCK));
    if !unused {
        return;
    }
    let _ = std::fs::remove_file(out.join(LOCK));
    for folder in out.ancestors() {
        if std::fs::remove_dir(folder).is_err() || folder == made {
            break;
        }
    }
}

/// The lock file a claimed results folder holds.
pub(super) const LOCK: &str = ".occlu.lock";

/// The start of the name of the folder inside `--out` that a run writes its
/// results into before they are moved into place.
pub(super) const STAGING: &str = ".occlu-staging";

/// This process's staging folder in `out`: one per process, so that runs
/// on a file system without locks do not write into each other's.
pub(super) fn staging(out: &Path) -> PathBuf {
    out.join(format!("{STAGING}-{}", std::process::id()))
}

/// Creates `out` and takes the lock on it.
pub(super) fn claim(out: &Path) -> Result<OutputLock, ReportError> {
    let io = ReportError::at;
    if out.exists() && !out.is_dir() {
        let error = std::io::Error::other("exists and is not a directory: --out names the folder results go to");
        return Err(io(out)(error));
    }
    let made = out
        .ancestors()
        .take_while(|folder| !folder.as_os_str().is_empty() && !folder.exists())
        .last()
        .map(Path::to_path_buf);
    std::fs::create_dir_all(out).map_err(io(out))?;
    let mut lock = OutputLock {
        file: None,
        out: out.to_path_buf(),
        made,
    };
    if let Ok(mut claimed) = CLAIMED.lock() {
        claimed.push((out.to_path_buf(), lock.made.clone()));
    }
    // From here on, a failure drops `lock`, which removes what it made.
    let path = out.join(LOCK);
    let mut file = open_lock(&path).map_err(io(&path))?;
    match file.try_lock() {
        Ok(()) => {
            use std::io::{Seek as _, Write as _};
            file.set_len(0)
                .and_then(|()| file.rewind())
                .and_then(|()| write!(file, "{}", std::process::id()))
                .map_err(io(&path))?;
            lock.file = Some(file);
            Ok(lock)
        }
        Err(std::fs::TryLockError::WouldBlock) => {
            // Another run's folder: never this claim's to remove.
            lock.made = None;
            forget(out);
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
        Err(std::fs::TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => Ok(lock),
        Err(std::fs::TryLockError::Error(e)) => Err(io(&path)(e)),
    }
}

/// Opens (or creates) the lock file `path`, which must be a regular file of
/// its own: a link is never followed (an `--out` in a shared temporary
/// folder may hold one planted to make the run write its process id over
/// another file, or create one where the link points), nor is a device or
/// pipe opened for writing, nor a file with other names (a hard link)
/// truncated.
fn open_lock(path: &Path) -> std::io::Result<std::fs::File> {
    let refused = || {
        std::io::Error::other(
            "not a regular file of this folder's own (a link, a device, a pipe or a file with other names): occlu writes through none; remove it or write elsewhere",
        )
    };
    let mut options = std::fs::OpenOptions::new();
    options.read(true).write(true).create(true).truncate(false);
    let (file, metadata) = crate::input::open_regular(&mut options, path, false, &refused)?;
    #[cfg(unix)]
    let own = std::os::unix::fs::MetadataExt::nlink(&metadata) == 1;
    #[cfg(not(unix))]
    let own = true;
    if own { Ok(file) } else { Err(refused()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ending_at_once_takes_the_staging_folder_from_a_folder_that_was_there() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("report.md"), "earlier").unwrap();
        let claim = claim(&out).unwrap();
        // Part of a merge's copies, staged when the process is told to end.
        let staged = staging(&out);
        std::fs::create_dir_all(staged.join("runs")).unwrap();
        std::fs::write(staged.join("report.md"), "half").unwrap();
        // What `abandon_unfinished` does for this claim (the list holds
        // other tests' claims too, which this test must not touch).
        let listed = CLAIMED.lock().unwrap().iter().find(|(o, _)| *o == out).cloned();
        let (listed, made) = listed.expect("a folder that was there is listed too");
        abandon(&listed, made.as_deref());
        assert!(!staged.exists(), "the staging folder is gone");
        assert_eq!(std::fs::read_to_string(out.join("report.md")).unwrap(), "earlier");
        drop(claim);
        assert!(
            CLAIMED.lock().unwrap().iter().all(|(o, _)| *o != out),
            "forgotten once released"
        );
        assert!(out.join("report.md").exists());
    }
}
