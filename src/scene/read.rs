//! Reading the files a scene names. Only regular files are read: a device, FIFO or
//! directory would be read forever (`/dev/zero`), block (a FIFO) or fail obscurely, so
//! it is refused by its metadata before it is opened. Each kind of file has a size cap
//! so that a wrong path cannot exhaust memory.
use std::io::Read;
use std::path::Path;

/// Largest scene file read (TOML text).
pub const MAX_SCENE_BYTES: u64 = 16 << 20;
/// Largest OBJ mesh file read.
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// `Ok` if `path` (after following links) is a regular file.
pub(crate) fn regular_file(path: &Path) -> std::io::Result<()> {
    if std::fs::metadata(path)?.is_file() {
        Ok(())
    } else {
        Err(std::io::Error::other("not a regular file"))
    }
}

/// The text of the regular file at `path`, refused if longer than `max` bytes.
pub(crate) fn read_text(path: &Path, max: u64) -> std::io::Result<String> {
    regular_file(path)?;
    let mut text = String::new();
    std::fs::File::open(path)?.take(max + 1).read_to_string(&mut text)?;
    if text.len() as u64 > max {
        return Err(std::io::Error::other(format!("longer than the limit of {} MiB", max >> 20)));
    }
    Ok(text)
}
