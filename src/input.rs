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

/// Reads all of `path`, a regular file of at most `limit` bytes.
pub fn read_file(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    // Checked before opening: opening a FIFO waits for a writer.
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        return Err(std::io::Error::other("not a regular file"));
    }
    let file = std::fs::File::open(path)?;
    let too_large = || std::io::Error::other(format!("larger than the {} MiB occlu reads", limit >> 20));
    if metadata.len() > limit {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    // One byte past the limit tells a file that grew while being read.
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(bytes)
}

/// [`read_file`] as UTF-8 text.
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_file(path, limit)?).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
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
}
