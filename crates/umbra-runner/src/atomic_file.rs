//! Files that several processes write and read at once (the judging cache's entries, the
//! Mesa loader files every worker writes, the gallery's shared pictures): each writer writes
//! a name of its own process beside the target and renames it over the target, so a reader
//! sees a whole file, old or new, never a truncated one.

use std::io;
use std::path::{Path, PathBuf};

/// Writes `path` through `write`, which is handed a temporary path in the same directory
/// with the same extension (`.PID.NAME`), then renamed over `path`.
/// On any error (a full disk, a read-only directory) the temporary file is removed and
/// `path` is as it was.
pub fn replace(path: &Path, write: impl FnOnce(&Path) -> io::Result<()>) -> io::Result<()> {
    let tmp = temporary(path);
    let done = write(&tmp).and_then(|()| std::fs::rename(&tmp, path));
    if done.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    done
}

/// Writes `bytes` to `path` as [`replace`] does.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    replace(path, |tmp| std::fs::write(tmp, bytes))
}

fn temporary(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    path.with_file_name(format!(".{}.{name}", std::process::id()))
}

/// Whether process `pid` is alive on this machine (it has a `/proc` entry): the test every
/// clean-up of what a dead process left uses (temporaries here, the judging cache's locks,
/// unfinished run directories).
pub fn process_alive(pid: u32) -> bool {
    Path::new(&format!("/proc/{pid}")).exists()
}

/// Removes from `dir` the temporary files of [`replace`] whose process has ended (killed
/// before it could rename or remove them); returns how many. A live process's are left.
pub fn sweep(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix('.'))
            .and_then(|n| n.split_once('.'))
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if !process_alive(pid) && std::fs::remove_file(e.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_failed_write_leaves_no_temporary_and_the_old_file() {
        let dir = std::env::temp_dir().join(format!("umbra-atomic-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let target = dir.join("entry.bin");
        super::write(&target, b"old").expect("write");
        let failed = super::replace(&target, |tmp| {
            std::fs::write(tmp, b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&target).expect("kept"), b"old");
        let names: Vec<_> = std::fs::read_dir(&dir).expect("list").flatten().collect();
        assert_eq!(names.len(), 1, "the temporary file is removed");
        // A dead process's temporary is swept; a live one's (this process's) is kept.
        std::fs::write(dir.join(".4194303999.entry.bin"), b"x").expect("stale");
        std::fs::write(dir.join(format!(".{}.other.bin", std::process::id())), b"x").expect("live");
        assert_eq!(super::sweep(&dir), 1);
        assert_eq!(std::fs::read_dir(&dir).expect("list").count(), 2);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
