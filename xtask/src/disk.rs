//! Free space under the target directory, checked before `cargo xtask test` starts.
//!
//! A full run from a clean clone writes several GiB (the workspace's build, the rendered and
//! judged runs of three catalogue passes, sid's unpacked Mesa). When the disk fills half-way,
//! the failure is a linker's "No space left on device" ten minutes in, on whichever step
//! happened to write next. This says it first, with the numbers, and goes on: `df` is an
//! estimate of what others on a shared machine will leave free, not a promise either way.

use std::path::Path;
use std::process::Command;

/// What a clean clone's `cargo xtask test` peaked at under `target/`: 5.9 GiB measured with
/// `du` every 20 s through `.ci/run` (`CARGO_INCREMENTAL=0`, November 2026), rounded up; with
/// cargo's incremental caches (a developer's default) about 3 GiB more.
pub fn test_peak_gib() -> u64 {
    if std::env::var("CARGO_INCREMENTAL").is_ok_and(|v| v == "0") {
        6
    } else {
        9
    }
}

/// Free bytes on the filesystem that holds `path` (POSIX `df -Pk`), or `None` when `df` is
/// missing or says something else.
pub fn free_bytes(path: &Path) -> Option<u64> {
    let out = Command::new("df").arg("-Pk").arg(path).output().ok()?;
    if !out.status.success() {
        return None;
    }
    parse_df(&String::from_utf8_lossy(&out.stdout))
}

/// The "Available" column (KiB) of `df -Pk`'s one data line, in bytes.
fn parse_df(text: &str) -> Option<u64> {
    let line = text.lines().nth(1)?;
    let kib: u64 = line.split_whitespace().nth(3)?.parse().ok()?;
    Some(kib * 1024)
}

/// Warns on stderr when the disk under `root` has less than `need_gib` free.
pub fn warn_if_short(root: &Path, need_gib: u64, what: &str) {
    if let Some(warning) = free_bytes(root).and_then(|free| shortfall(free, need_gib, root, what)) {
        eprintln!("{warning}");
    }
}

/// The warning for `free` bytes against `need_gib`, or `None` when there is room.
fn shortfall(free: u64, need_gib: u64, root: &Path, what: &str) -> Option<String> {
    let gib = 1u64 << 30;
    (free < need_gib * gib).then(|| {
        format!(
            "warning: {:.1} GiB free under {}; {what} peaks at about {need_gib} GiB there. \
             Free space (`target/umbra`: its last runs and judge cache; `cargo clean`) or expect \"No space left on device\" part-way",
            free as f64 / gib as f64,
            root.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn df_s_available_column_is_read_in_kib() {
        let text = "Filesystem     1024-blocks     Used Available Capacity Mounted on\n\
                    /dev/vda         264000000 91000000   4400000      96% /\n";
        assert_eq!(parse_df(text), Some(4_400_000 * 1024));
        assert_eq!(parse_df("Filesystem\n"), None);
    }

    #[test]
    fn short_space_is_named_with_both_numbers_and_enough_is_quiet() {
        let root = Path::new("/w");
        let short = shortfall(3 << 30, 8, root, "the test").unwrap_or_default();
        assert!(short.contains("3.0 GiB free under /w"), "{short}");
        assert!(short.contains("about 8 GiB"), "{short}");
        assert_eq!(shortfall(8 << 30, 8, root, "the test"), None);
    }

    #[test]
    fn the_workspace_s_disk_has_a_size() {
        // `df` is in coreutils on every machine the README supports.
        assert!(free_bytes(Path::new(env!("CARGO_MANIFEST_DIR"))).is_some());
    }
}
