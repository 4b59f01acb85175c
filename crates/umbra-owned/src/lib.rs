//! What umbra may remove or replace: only what it can prove it wrote.
//!
//! Several commands take a path and replace what is there: `cargo xtask gpu-bundle --out`,
//! `cargo xtask fetch-mesa --dir`, `umbra bisect --work`, `umbra drivers --out`, the run
//! directories that conformance prunes. Each once removed whatever it found: `cargo xtask
//! gpu-bundle --out victim` deleted a user's `victim/precious.txt` and exited 0. Now every
//! directory umbra makes holds a [`MARKER`] file, written the moment it is made, and umbra
//! removes or empties a directory only when that marker is in it (a regular file, in a
//! directory that is not a symbolic link). An empty directory is taken over (nothing is
//! lost), and anything else is refused with a [`Refused`] that says how to proceed; the
//! commands exit 125 on it.
//!
//! This crate sits on the ground floor with no dependencies, so that `xtask` (which depends
//! on clap and serde_json only) and the `umbra` binary share one rule.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// The file that marks a directory as umbra's: its text says which command made it.
pub const MARKER: &str = ".umbra-owned";

/// A path umbra will not remove or replace, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused {
    /// The path.
    pub path: PathBuf,
    /// What is there (`holds files umbra did not write`, `is a symbolic link`).
    pub why: String,
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {}; umbra removes or replaces only a directory it made (one holding its {MARKER} file), so it left it as it is: give a new or empty directory, or remove this one yourself if nothing in it is yours",
            self.path.display(),
            self.why
        )
    }
}

impl std::error::Error for Refused {}

/// Whether `dir` is a directory umbra made: a real directory (not a symbolic link) that
/// holds a regular [`MARKER`] file.
pub fn owned(dir: &Path) -> bool {
    std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir())
        && std::fs::symlink_metadata(dir.join(MARKER)).is_ok_and(|m| m.is_file())
}

/// Writes `dir`'s [`MARKER`], naming `what` made it (`cargo xtask gpu-bundle`).
pub fn mark(dir: &Path, what: &str) -> io::Result<()> {
    std::fs::write(
        dir.join(MARKER),
        format!("made by {what}: umbra may empty, replace or remove this directory\n"),
    )
}

/// What is at `dir` when it is not umbra's: `None` when it is umbra's or not there or an
/// empty directory, else the refusal.
fn foreign(dir: &Path) -> Option<Refused> {
    let refuse = |why: &str| {
        Some(Refused {
            path: dir.to_path_buf(),
            why: why.to_string(),
        })
    };
    match std::fs::symlink_metadata(dir) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => None,
        Err(e) => refuse(&format!("cannot be read ({e})")),
        Ok(m) if m.file_type().is_symlink() => refuse("is a symbolic link"),
        Ok(m) if !m.is_dir() => refuse("is a file, not a directory"),
        Ok(_) if owned(dir) => None,
        Ok(_) => match std::fs::read_dir(dir).map(|mut d| d.next().is_none()) {
            Ok(true) => None,
            Ok(false) => refuse("holds files umbra did not write"),
            Err(e) => refuse(&format!("cannot be read ({e})")),
        },
    }
}

/// An empty directory at `dir` that umbra owns, for a command that replaces its output
/// whole: made (with its parents) when it is not there, emptied when umbra made it, taken
/// over when it is empty; refused otherwise.
pub fn fresh(dir: &Path, what: &str) -> Result<(), Refused> {
    if let Some(r) = foreign(dir) {
        return Err(r);
    }
    let failed = |e: io::Error| Refused {
        path: dir.to_path_buf(),
        why: format!("cannot be made afresh ({e})"),
    };
    if owned(dir) {
        std::fs::remove_dir_all(dir).map_err(failed)?;
    }
    std::fs::create_dir_all(dir).map_err(failed)?;
    mark(dir, what).map_err(failed)
}

/// A directory at `dir` that umbra owns, its contents kept, for a command that writes into
/// it over several runs and removes only what it wrote there: made when it is not there,
/// taken over when empty, kept when umbra made it; refused otherwise.
pub fn claim(dir: &Path, what: &str) -> Result<(), Refused> {
    if let Some(r) = foreign(dir) {
        return Err(r);
    }
    if owned(dir) {
        return Ok(());
    }
    let failed = |e: io::Error| Refused {
        path: dir.to_path_buf(),
        why: format!("cannot be made ({e})"),
    };
    std::fs::create_dir_all(dir).map_err(failed)?;
    mark(dir, what).map_err(failed)
}

/// Removes `dir` and everything in it when umbra made it; a path that is not there is
/// already gone. Anything else is refused and left as it is.
pub fn remove(dir: &Path) -> Result<(), Refused> {
    match std::fs::symlink_metadata(dir) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        _ if owned(dir) => {}
        _ => {
            return Err(foreign(dir).unwrap_or(Refused {
                path: dir.to_path_buf(),
                why: format!("has no {MARKER} file"),
            }));
        }
    }
    std::fs::remove_dir_all(dir).map_err(|e| Refused {
        path: dir.to_path_buf(),
        why: format!("could not be removed ({e})"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("umbra-owned-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    /// The reproducer of integrity round three: a user's directory with a file in it is
    /// neither emptied, claimed nor removed, and the refusal says how to proceed.
    #[test]
    fn a_users_files_are_never_removed() {
        let root = scratch("victim");
        let victim = root.join("victim");
        std::fs::create_dir_all(&victim).expect("mkdir");
        std::fs::write(victim.join("precious.txt"), "precious\n").expect("write");
        let e = fresh(&victim, "test").expect_err("a user's directory");
        assert!(
            e.to_string().contains("did not write")
                && e.to_string().contains("give a new or empty directory"),
            "{e}"
        );
        claim(&victim, "test").expect_err("claim");
        remove(&victim).expect_err("remove");
        assert_eq!(
            std::fs::read_to_string(victim.join("precious.txt")).expect("still there"),
            "precious\n"
        );
        // A file, and a link to umbra's own directory, are refused too.
        let file = root.join("file");
        std::fs::write(&file, "x").expect("write");
        assert!(fresh(&file, "test").is_err() && remove(&file).is_err());
        let mine = root.join("mine");
        fresh(&mine, "test").expect("new");
        let link = root.join("link");
        std::os::unix::fs::symlink(&mine, &link).expect("symlink");
        assert!(fresh(&link, "test").is_err() && remove(&link).is_err());
        assert!(owned(&mine));
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn what_umbra_made_it_replaces_and_removes() {
        let root = scratch("mine");
        let out = root.join("a/b");
        fresh(&out, "test").expect("made with its parents");
        std::fs::write(out.join("old.txt"), "old").expect("write");
        fresh(&out, "test").expect("emptied");
        assert!(owned(&out) && !out.join("old.txt").exists());
        let empty = root.join("empty");
        std::fs::create_dir_all(&empty).expect("mkdir");
        claim(&empty, "test").expect("an empty directory is taken over");
        std::fs::write(empty.join("kept"), "k").expect("write");
        claim(&empty, "test").expect("kept");
        assert!(empty.join("kept").exists());
        remove(&empty).expect("removed");
        assert!(!empty.exists());
        remove(&empty).expect("a path that is not there is gone");
        // A marker that is a directory proves nothing.
        let fake = root.join("fake");
        std::fs::create_dir_all(fake.join(MARKER)).expect("mkdir");
        std::fs::write(fake.join("x"), "x").expect("write");
        assert!(!owned(&fake) && remove(&fake).is_err());
        let _ = std::fs::remove_dir_all(&root);
    }
}
