//! Writing a file whole or not at all, and the one error of the result
//! files ([`ReportError`]: the path and what went wrong).

use std::io::Write as _;
use std::path::{Component, Path, PathBuf};

#[derive(Debug, thiserror::Error)]
#[error("{}: {error}", path.display())]
pub struct ReportError {
    pub path: PathBuf,
    pub error: std::io::Error,
}

impl ReportError {
    /// A maker of errors about `path`, for `map_err`.
    pub fn at(path: &Path) -> impl Fn(std::io::Error) -> ReportError + use<> {
        let path = path.to_path_buf();
        move |error| ReportError {
            path: path.clone(),
            error,
        }
    }

    /// Whether the user's input was at fault (a missing run, a bad --out),
    /// as opposed to the machine failing while running (a full disk).
    pub fn is_input_error(&self) -> bool {
        !matches!(
            self.error.kind(),
            std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded | std::io::ErrorKind::WriteZero
        )
    }
}

/// Writes `bytes` to `path` whole or not at all: into a temporary file
/// beside it, then renamed over it. A link is followed (the file it names
/// is replaced, with its permissions; the link stays; a link leading
/// nowhere is refused, [`landing`]), and a path that is not a regular file
/// (`/dev/stdout`, a pipe) is written in place.
pub fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    stage_whole(path, bytes)?.publish()
}

/// [`write_whole`]'s first half: `bytes` written whole beside `path`, to be
/// put in place by [`Staged::publish`] once the rest of a run's output is
/// (dropped unpublished, the file is removed and `path` left as it was).
/// A path that is not a regular file (`/dev/stdout`, a pipe) has nothing
/// to stand in for it: it is written now, so that a fault there (a full
/// device) comes before the rest is written.
pub fn stage_whole(path: &Path, bytes: &[u8]) -> Result<Staged, ReportError> {
    let fail = ReportError::at(path);
    let target = landing(path).map_err(&fail)?;
    let existing = std::fs::metadata(&target).ok();
    if existing.as_ref().is_some_and(|m| !m.is_file()) {
        std::fs::write(&target, bytes).map_err(&fail)?;
        return Ok(Staged {
            path: path.to_path_buf(),
            target,
            temporary: None,
        });
    }
    let temporary = partial(&target);
    let written = create_partial(&temporary)
        .and_then(|mut file| file.write_all(bytes))
        .and_then(|()| match &existing {
            Some(m) => std::fs::set_permissions(&temporary, m.permissions()),
            None => Ok(()),
        });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temporary);
        return Err(fail(e));
    }
    Ok(Staged {
        path: path.to_path_buf(),
        target,
        temporary: Some(temporary),
    })
}

/// A file [`stage_whole`] wrote, not yet in place.
pub struct Staged {
    /// As the caller named it, for errors.
    path: PathBuf,
    target: PathBuf,
    /// Written beside the target, to be renamed over it (`None` where the
    /// target was written in place, and once it is renamed).
    temporary: Option<PathBuf>,
}

impl Staged {
    /// Puts the file in place.
    pub fn publish(mut self) -> Result<(), ReportError> {
        let Some(temporary) = self.temporary.take() else {
            return Ok(());
        };
        std::fs::rename(&temporary, &self.target).map_err(|e| {
            let _ = std::fs::remove_file(&temporary);
            ReportError::at(&self.path)(e)
        })
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(temporary) = &self.temporary {
            let _ = std::fs::remove_file(temporary);
        }
    }
}

/// Where writing `path` lands: where it leads, if it exists (through
/// links); itself, if it does not. A link that leads nowhere (its target
/// missing, or a loop) is refused: the file written would replace the
/// link, where a link to a file is written through.
fn landing(path: &Path) -> std::io::Result<PathBuf> {
    match std::fs::canonicalize(path) {
        Ok(target) => Ok(target),
        Err(e) if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) => {
            Err(std::io::Error::new(
                e.kind(),
                format!("is a link that leads nowhere ({e}): give the file it should lead to, or another name"),
            ))
        }
        Err(_) => Ok(path.to_path_buf()),
    }
}

/// Checks that [`write_whole`] could write `path`, so that a bad output
/// file is refused before a long run rather than after it.
pub fn check_writable(path: &Path) -> Result<(), ReportError> {
    let fail = ReportError::at(path);
    let target = landing(path).map_err(&fail)?;
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => Err(fail(std::io::Error::other("is a directory: a file name is needed"))),
        // Written in place later; opening it now could end a pipe's stream.
        Ok(m) if !m.is_file() => Ok(()),
        _ => {
            let temporary = partial(&target);
            create_partial(&temporary).map_err(&fail)?;
            std::fs::remove_file(&temporary).map_err(fail)
        }
    }
}

/// Refuses an `output` that is one of `inputs` (the same file, however
/// named: by device and inode), so that writing it cannot destroy what the
/// command reads (`occlu render model.obj -o model.obj`).
pub fn refuse_input_as_output<P: AsRef<Path>>(output: &Path, inputs: &[P]) -> Result<(), ReportError> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        let identity = |p: &Path| std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()));
        // Where it would be written: through folders the run has yet to
        // make too (`--trace OUT/../path.json` before OUT exists).
        let Some(written) = where_written(output).and_then(|p| identity(&p)) else {
            return Ok(());
        };
        if let Some(input) = inputs.iter().find(|i| identity(i.as_ref()) == Some(written)) {
            return Err(ReportError::at(output)(std::io::Error::other(format!(
                "is an input of this command ({}): writing it would destroy what it reads; choose another output file",
                input.as_ref().display()
            ))));
        }
    }
    Ok(())
}

/// Refuses a `file` that is, or would be, one of `names` in the folder
/// `dir` (a run's own files, which the run writes itself), saying `why`.
pub fn refuse_own_file(file: &Path, dir: &Path, names: &[&str], why: &str) -> Result<(), ReportError> {
    let own = where_written(file).is_some_and(|t| {
        t.parent() == where_written(dir).as_deref() && t.file_name().is_some_and(|n| names.iter().any(|own| n == *own))
    });
    match own {
        true => Err(ReportError::at(file)(std::io::Error::other(why.to_string()))),
        false => Ok(()),
    }
}

/// Refuses two outputs of one command that are, or would be, one file:
/// the second written would replace the first.
pub fn refuse_one_file_twice(first: &Path, second: &Path) -> Result<(), ReportError> {
    match (where_written(first), where_written(second)) {
        (Some(a), Some(b)) if a == b => Err(ReportError::at(second)(std::io::Error::other(format!(
            "is also {}, another output of this command: one would replace the other; choose another file",
            first.display()
        )))),
        _ => Ok(()),
    }
}

/// Where `output` is or would be written, as the system will resolve it
/// when the run writes it: component by component, each that exists taken
/// where it leads (a link to what it names), each that does not, which a
/// run may yet make (its --out), taken as written, `..` going back a
/// folder from where the path has led.
pub(super) fn where_written(output: &Path) -> Option<PathBuf> {
    let mut resolved = PathBuf::new();
    for part in std::path::absolute(output).ok()?.components() {
        match part {
            Component::ParentDir => {
                resolved.pop();
            }
            Component::CurDir => {}
            part => {
                resolved.push(part);
                if let Ok(real) = std::fs::canonicalize(&resolved) {
                    resolved = real;
                }
            }
        }
    }
    Some(resolved)
}

/// Creates the temporary twin `temporary` anew: whatever has its name (a
/// file left by an earlier run, or a link, FIFO or hard link planted there)
/// is unlinked, never opened or written through, and the file is created
/// exclusively, so a name planted again in between is refused.
fn create_partial(temporary: &Path) -> std::io::Result<std::fs::File> {
    match std::fs::symlink_metadata(temporary) {
        Ok(m) if m.is_dir() => {
            return Err(std::io::Error::other(format!(
                "{} is a folder where occlu writes its temporary file",
                temporary.display()
            )));
        }
        Ok(_) => std::fs::remove_file(temporary).map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!(
                    "cannot remove {}, where occlu writes its temporary file: {e}",
                    temporary.display()
                ),
            )
        })?,
        Err(_) => {}
    }
    std::fs::OpenOptions::new().write(true).create_new(true).open(temporary)
}

/// The temporary twin [`write_whole`] writes `path` into first.
fn partial(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".occlu-partial");
    PathBuf::from(name)
}

/// Writes an 8-bit RGB image as PNG, whole or not at all.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ReportError> {
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()
        .and_then(|mut writer| writer.write_image_data(rgb).and_then(|()| writer.finish()))
        .map_err(|e| ReportError::at(path)(std::io::Error::other(format!("encoding the picture failed: {e}"))))?;
    write_whole(path, &png)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hostile-input review's finding: through a folder the run had yet
    /// to make (`--trace OUT/../path.json`), an output named an input, or
    /// another output, without being seen as one.
    #[test]
    fn outputs_through_folders_yet_to_be_made_are_seen_for_the_files_they_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("path.json");
        std::fs::write(&path, "{}").unwrap();
        let out = dir.path().join("out");
        let through = out.join("..").join("path.json");
        let real = std::fs::canonicalize(&path).unwrap();
        assert_eq!(where_written(&through), Some(real.clone()));
        assert_eq!(
            where_written(&out.join("x").join(".").join("y.json")),
            Some(real.with_file_name("out/x/y.json"))
        );
        let error = refuse_input_as_output(&through, &[&path]).unwrap_err().to_string();
        assert!(error.contains("is an input of this command"), "{error}");
        let twice = refuse_one_file_twice(&out.join("x.json"), &out.join("x.json")).unwrap_err();
        assert!(twice.to_string().contains("another output of this command"), "{twice}");
        assert!(refuse_one_file_twice(&out.join("x.json"), &out.join("y.json")).is_ok());
        let own = refuse_own_file(&out.join("sub/../summary.json"), &out, &["summary.json"], "own");
        assert_eq!(own.unwrap_err().error.to_string(), "own");
        assert!(!out.exists(), "nothing made");
        // `..` after a link goes back from where the link leads, as the
        // system takes it.
        #[cfg(unix)]
        {
            std::fs::create_dir_all(dir.path().join("real/sub")).unwrap();
            std::os::unix::fs::symlink(dir.path().join("real/sub"), dir.path().join("link")).unwrap();
            let through_link = out.join("../link/../x.json");
            assert_eq!(where_written(&through_link), Some(real.with_file_name("real/x.json")));
        }
    }

    /// A hostile-input review's finding: an output that is a link to
    /// nothing was replaced by a file, where a link to a file is written
    /// through.
    #[cfg(unix)]
    #[test]
    fn a_link_that_leads_nowhere_is_refused_as_an_output_and_left_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let dangling = dir.path().join("dangling.png");
        std::os::unix::fs::symlink(dir.path().join("nowhere/x.png"), &dangling).unwrap();
        for refused in [check_writable(&dangling), write_whole(&dangling, b"png")] {
            assert!(
                refused
                    .unwrap_err()
                    .to_string()
                    .contains("is a link that leads nowhere")
            );
        }
        assert!(std::fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
        let file = dir.path().join("x.png");
        std::fs::write(&file, "old").unwrap();
        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        write_whole(&link, b"new").unwrap();
        assert_eq!(std::fs::read(&file).unwrap(), b"new");
    }
}
