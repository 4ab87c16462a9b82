//! Reading input files (models, glTF buffers, camera paths, configs) with
//! bounds: a file that is not a regular file (a device such as /dev/zero, a
//! FIFO) or that is, or grows, larger than its limit is refused before it
//! can fill memory.

use std::io::Read;
use std::path::Path;

/// Largest model or glTF buffer file read: beyond any model a 24 GiB
/// machine can render here.
pub const MODEL_LIMIT: u64 = 4 << 30;

/// Largest camera path or configuration file read (JSON text).
pub const TEXT_LIMIT: u64 = 64 << 20;

/// A size in bytes as a person writes it: a whole number, optionally
/// followed by K, M, G or T (powers of 1024), e.g. `512M` or `8G`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ByteSize(pub u64);

impl std::str::FromStr for ByteSize {
    type Err = String;

    fn from_str(text: &str) -> Result<ByteSize, String> {
        let malformed = || format!("'{text}' is not a size (a whole number of bytes, or with K, M, G or T: 512M, 8G)");
        let trimmed = text.trim();
        let (digits, shift) = match trimmed.char_indices().last() {
            Some((i, unit)) if unit.is_ascii_alphabetic() => {
                let shift = match unit.to_ascii_uppercase() {
                    'K' => 10,
                    'M' => 20,
                    'G' => 30,
                    'T' => 40,
                    _ => return Err(malformed()),
                };
                (&trimmed[..i], shift)
            }
            _ => (trimmed, 0),
        };
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(malformed());
        }
        let number: u64 = digits.parse().map_err(|_| malformed())?;
        number
            .checked_mul(1 << shift)
            .filter(|&bytes| bytes > 0)
            .map(ByteSize)
            .ok_or_else(malformed)
    }
}

impl std::fmt::Display for ByteSize {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self.0.trailing_zeros() {
            30.. => write!(f, "{} GiB", self.0 >> 30),
            20.. => write!(f, "{} MiB", self.0 >> 20),
            _ => write!(f, "{} bytes", self.0),
        }
    }
}

impl serde::Serialize for ByteSize {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.0.to_string())
    }
}

/// In a config file: a number of bytes, or a string as on the command line.
/// Anything else (a fraction, a negative number) is refused by what it is,
/// against what a size may be.
impl<'de> serde::Deserialize<'de> for ByteSize {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ByteSize, D::Error> {
        struct Size;
        impl serde::de::Visitor<'_> for Size {
            type Value = ByteSize;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a whole number of bytes, or a size with K, M, G or T such as \"512M\" or \"8G\"")
            }
            fn visit_u64<E: serde::de::Error>(self, bytes: u64) -> Result<ByteSize, E> {
                self.visit_str(&bytes.to_string())
            }
            fn visit_str<E: serde::de::Error>(self, text: &str) -> Result<ByteSize, E> {
                text.parse().map_err(E::custom)
            }
        }
        d.deserialize_any(Size)
    }
}

/// The folder the file `path` names lies in: its parent, or `.` for a bare
/// file name (whose parent is the empty path, which names no folder and
/// cannot be resolved).
pub fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// Reads all of `path`, a regular file of at most `limit` bytes (or a link
/// to one).
pub fn read_file(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    read_regular(path, limit, true)
}

/// Reads all of `path` as [`read_file`] does, but refuses a link: for a
/// folder's own files, where a link could bring any file the user may read
/// (`/etc/passwd`) into what occlu copies on (a merged artefact).
pub fn read_unlinked(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    read_regular(path, limit, false)
}

/// Opens `path` with `options`, non-blocking (opening a pipe waits for its
/// other end) and, unless `follow_links`, without following a link; what
/// was opened must be a regular file. A link or anything else fails as
/// `refused` says. Checked on what was opened, so the path cannot be
/// swapped between a check and the open.
pub fn open_regular(
    options: &mut std::fs::OpenOptions,
    path: &Path,
    follow_links: bool,
    refused: &dyn Fn() -> std::io::Error,
) -> std::io::Result<(std::fs::File, std::fs::Metadata)> {
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(
        options,
        libc::O_NONBLOCK | if follow_links { 0 } else { libc::O_NOFOLLOW },
    );
    let file = options.open(path).map_err(|e| {
        #[cfg(unix)]
        if e.raw_os_error() == Some(libc::ELOOP) {
            return refused();
        }
        e
    })?;
    let metadata = file.metadata()?;
    if !metadata.is_file() {
        return Err(refused());
    }
    Ok((file, metadata))
}

fn read_regular(path: &Path, limit: u64, follow_links: bool) -> std::io::Result<Vec<u8>> {
    let not_regular = || {
        let what = if follow_links {
            ""
        } else {
            " (a link, a device or a pipe)"
        };
        std::io::Error::other(format!("not a regular file{what}"))
    };
    // Checked before opening, since opening some devices acts on them, and
    // again on what was opened (non-blocking, since opening a FIFO waits for
    // a writer), so the path cannot be swapped between check and open.
    let metadata = if follow_links {
        std::fs::metadata(path)
    } else {
        std::fs::symlink_metadata(path)
    };
    if !metadata?.is_file() {
        return Err(not_regular());
    }
    let (file, metadata) = open_regular(std::fs::OpenOptions::new().read(true), path, follow_links, &not_regular)?;
    let too_large = || {
        std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("larger than the {} occlu reads", ByteSize(limit)),
        )
    };
    if metadata.len() > limit {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    // One byte past the limit tells a file that grew while being read.
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(bytes)
}

/// [`read_file`] as UTF-8 text, without the byte order mark some editors
/// on Windows put first (JSON parsers refuse it as a value).
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    let text = String::from_utf8(read_file(path, limit)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_files_past_the_limit_are_refused() {
        let e = read_file(Path::new("/dev/zero"), MODEL_LIMIT).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file");
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, [7u8; 100]).unwrap();
        assert_eq!(read_file(&file, 100).unwrap(), vec![7u8; 100]);
        assert!(read_file(&file, 99).unwrap_err().to_string().starts_with("larger than"));
        std::fs::write(&file, [0xFFu8; 4]).unwrap();
        assert_eq!(
            read_text(&file, 100).unwrap_err().kind(),
            std::io::ErrorKind::InvalidData
        );
    }

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!("512M".parse(), Ok(ByteSize(512 << 20)));
        assert_eq!("8g".parse(), Ok(ByteSize(8 << 30)));
        assert_eq!("1000".parse(), Ok(ByteSize(1000)));
        let most: ByteSize = "18446744073709551615".parse().unwrap();
        assert_eq!(most, ByteSize(u64::MAX));
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, [7u8; 10]).unwrap();
        assert_eq!(
            read_file(&file, most.0).unwrap().len(),
            10,
            "no overflow past the largest limit"
        );
        for bad in ["", "0", "-1", "+5", "1.5G", "4X", "G", "99999999999T"] {
            assert!(bad.parse::<ByteSize>().is_err(), "{bad}");
        }
    }
}
