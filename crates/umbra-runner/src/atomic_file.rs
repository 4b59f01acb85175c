//! Files that several processes write and read at once (the judging cache's entries, the
//! Mesa loader files every worker writes, the gallery's shared pictures): each writer writes
//! a name of its own process beside the target and renames it over the target, so a reader
//! sees a whole file, old or new, never a truncated one.

use std::io;
use std::path::{Path, PathBuf};

/// Writes `path` through `write`, which is handed a temporary path in the same directory
/// with the same extension (`.PID.NAME`), then renamed over `path`.
pub fn replace(path: &Path, write: impl FnOnce(&Path) -> io::Result<()>) -> io::Result<()> {
    let tmp = temporary(path);
    write(&tmp)?;
    std::fs::rename(&tmp, path)
}

/// Writes `bytes` to `path` as [`replace`] does.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    replace(path, |tmp| std::fs::write(tmp, bytes))
}

fn temporary(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    path.with_file_name(format!(".{}.{name}", std::process::id()))
}
