//! Where a run's results live, and how `latest` comes to show them.
//!
//! Every run writes into a directory of its own, `OUT/runs/ID`, with ID the UTC start time,
//! the process id and a counter (`20261124T103000Z-4242-0`), created with `mkdir` (which
//! fails if the name exists), so two runs into one `--out` (two shards of a CI matrix started
//! in the same second) never share one. `OUT/latest` is a symbolic link, `runs/ID`,
//! replaced by `rename(2)` over it only once the run's reports are all written: a reader sees
//! the previous run's complete reports or this run's, never a mixture, and a run that is
//! interrupted, fails to write or fills the disk leaves `latest` as it was and its own
//! directory marked [`INCOMPLETE`], saying why. The newest [`KEEP`] runs are kept; only run
//! directories umbra made (each holds [`umbra_owned::MARKER`]) are ever pruned.

use std::io;
use std::path::{Path, PathBuf};

/// The file an unfinished run's directory holds: why it is not complete.
pub const INCOMPLETE: &str = "INCOMPLETE";

/// How many run directories are kept (the newest, by name), besides whatever `latest`
/// shows and any run still in progress.
pub const KEEP: usize = 5;

/// `umbra soak`'s default output directory (the self-test's generated cases go beside its
/// own, under `selftest-cases`).
pub const SOAK_OUT: &str = "target/umbra/soak";

/// A run's own directory.
#[derive(Debug)]
pub struct RunDir {
    /// The output root (`--out`).
    pub out: PathBuf,
    /// `runs/ID` under it.
    pub dir: PathBuf,
    /// ID.
    pub id: String,
}

impl RunDir {
    /// Creates a new, unique run directory under `out/runs`, marked [`INCOMPLETE`] until
    /// [`RunDir::publish`].
    pub fn create(out: &Path) -> io::Result<RunDir> {
        let runs = out.join("runs");
        std::fs::create_dir_all(&runs)?;
        let stamp = utc_stamp(
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        );
        for n in 0.. {
            let id = format!("{stamp}-{}-{n}", std::process::id());
            let dir = runs.join(&id);
            match std::fs::create_dir(&dir) {
                Ok(()) => {
                    let run = RunDir {
                        out: out.to_path_buf(),
                        dir,
                        id,
                    };
                    let marked = umbra_owned::mark(&run.dir, "an umbra run");
                    if let Err(e) = marked
                        .and_then(|()| std::fs::write(run.dir.join(INCOMPLETE), "in progress\n"))
                    {
                        let _ = std::fs::remove_dir_all(&run.dir);
                        return Err(e);
                    }
                    return Ok(run);
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(e),
            }
        }
        unreachable!("an unbounded counter finds a free name")
    }

    /// Makes `out/latest` show this run (its reports must be complete): a link made beside it
    /// and renamed over it. A `latest` that is a directory (umbra before run directories) is
    /// moved to `runs/` first. Then old runs are pruned to [`KEEP`].
    pub fn publish(&self) -> io::Result<()> {
        std::fs::remove_file(self.dir.join(INCOMPLETE))?;
        let latest = self.out.join("latest");
        // `latest` is replaced only when it is umbra's link (or a run directory of before):
        // a file of the user's by that name is kept, and the run is said to be left unpublished.
        if std::fs::symlink_metadata(&latest).is_ok_and(|m| m.is_file()) {
            return Err(io::Error::other(format!(
                "{} is a file umbra did not write; this run stays in {} (move that file away to publish runs there)",
                latest.display(),
                self.dir.display()
            )));
        }
        if std::fs::symlink_metadata(&latest).is_ok_and(|m| m.is_dir()) {
            std::fs::rename(
                &latest,
                self.out.join("runs").join("before-run-directories"),
            )?;
        }
        let tmp = self.out.join(format!(".latest.{}", self.id));
        let _ = std::fs::remove_file(&tmp);
        std::os::unix::fs::symlink(Path::new("runs").join(&self.id), &tmp)?;
        if let Err(e) = std::fs::rename(&tmp, &latest) {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        prune(&self.out);
        Ok(())
    }

    /// Marks this run as not published (`why`, in [`INCOMPLETE`]) and says on stderr what
    /// it left where and what `latest` still shows.
    pub fn abandon(&self, why: &str) {
        let _ = std::fs::write(self.dir.join(INCOMPLETE), format!("{why}\n"));
        let latest = match shown(&self.out) {
            Some(id) => format!(
                "{} still shows runs/{id}",
                self.out.join("latest").display()
            ),
            None => format!("{} was not written", self.out.join("latest").display()),
        };
        eprintln!(
            "error: {why}: this run's partial results ({}) are in {} (not published; remove it when done); {latest}",
            self.holds(),
            self.dir.display()
        );
    }

    /// What the run's directory holds, said as it is (`results.csv, junit.xml, pictures/`, or
    /// `nothing`), so the message never promises verdicts that are not there.
    fn holds(&self) -> String {
        let mut names: Vec<String> = std::fs::read_dir(&self.dir)
            .map(|d| {
                d.flatten()
                    .filter(|e| e.file_name() != INCOMPLETE)
                    .map(|e| {
                        let n = e.file_name().to_string_lossy().into_owned();
                        if e.path().is_dir() {
                            format!("{n}/")
                        } else {
                            n
                        }
                    })
                    .collect()
            })
            .unwrap_or_default();
        names.sort();
        if names.is_empty() {
            "nothing".into()
        } else {
            names.join(", ")
        }
    }
}

/// The run `out/latest` shows, if it is a link to one.
pub fn shown(out: &Path) -> Option<String> {
    let target = std::fs::read_link(out.join("latest")).ok()?;
    Some(target.file_name()?.to_string_lossy().into_owned())
}

/// Removes all but the newest [`KEEP`] run directories, never the one `latest` shows nor
/// an unfinished one whose process is alive (another run in progress).
fn prune(out: &Path) {
    let runs = out.join("runs");
    let Ok(entries) = std::fs::read_dir(&runs) else {
        return;
    };
    let mut ids: Vec<String> = entries
        .flatten()
        .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    ids.sort();
    let shown = shown(out);
    let excess = ids.len().saturating_sub(KEEP);
    for id in &ids[..excess] {
        let dir = runs.join(id);
        let live = dir.join(INCOMPLETE).is_file()
            && id
                .split('-')
                .nth(1)
                .and_then(|pid| pid.parse().ok())
                .is_some_and(crate::atomic_file::process_alive);
        // Only a run umbra made (its marker inside) is pruned: a directory a user keeps
        // under runs/ is theirs.
        if Some(id) != shown.as_ref() && !live {
            let _ = umbra_owned::remove(&dir);
        }
    }
}

/// `YYYYMMDDTHHMMSSZ` of a Unix time (the proleptic Gregorian calendar, from days since
/// 1970-01-01 by Howard Hinnant's `civil_from_days`).
fn utc_stamp(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}T{:02}{:02}{:02}Z",
        rem / 3_600,
        rem / 60 % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_are_utc_calendar_times() {
        assert_eq!(utc_stamp(0), "19700101T000000Z");
        assert_eq!(utc_stamp(951_782_400), "20000229T000000Z");
        assert_eq!(utc_stamp(1_795_513_286), "20261124T094126Z");
    }

    #[test]
    fn runs_in_one_second_get_their_own_directories_and_latest_moves_only_on_publish() {
        let out = std::env::temp_dir().join(format!("umbra-run-dir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let a = RunDir::create(&out).expect("a");
        let b = RunDir::create(&out).expect("b");
        assert_ne!(a.dir, b.dir);
        assert!(shown(&out).is_none());
        a.publish().expect("publish a");
        assert_eq!(shown(&out).as_deref(), Some(a.id.as_str()));
        b.abandon("interrupted");
        assert_eq!(shown(&out).as_deref(), Some(a.id.as_str()), "latest kept");
        assert!(b.dir.join(INCOMPLETE).is_file() && !a.dir.join(INCOMPLETE).exists());
        // The old layout's `latest` directory is moved aside, not mixed with.
        let _ = std::fs::remove_file(out.join("latest"));
        std::fs::create_dir_all(out.join("latest")).expect("old latest");
        let c = RunDir::create(&out).expect("c");
        c.publish().expect("publish c");
        assert_eq!(shown(&out).as_deref(), Some(c.id.as_str()));
        assert!(out.join("runs/before-run-directories").is_dir());
        let _ = std::fs::remove_dir_all(&out);
    }

    /// Only runs umbra made are pruned: a directory of the user's under `runs/` (no marker)
    /// stays however many runs come after it, and a `latest` that is a user's file is kept
    /// (the run stays unpublished, said).
    #[test]
    fn pruning_removes_only_umbras_runs() {
        let out = std::env::temp_dir().join(format!("umbra-run-prune-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let mine = out.join("runs").join("00000000-mine");
        std::fs::create_dir_all(&mine).expect("a user's directory");
        std::fs::write(mine.join("notes.txt"), "mine").expect("write");
        let mut ids = Vec::new();
        for _ in 0..KEEP + 3 {
            let r = RunDir::create(&out).expect("run");
            r.publish().expect("publish");
            ids.push(r.id);
        }
        assert!(
            mine.join("notes.txt").is_file(),
            "a user's directory was pruned"
        );
        let kept = std::fs::read_dir(out.join("runs")).expect("runs").count();
        assert_eq!(kept, KEEP + 1, "KEEP runs and the user's directory");
        let _ = std::fs::remove_file(out.join("latest"));
        std::fs::write(out.join("latest"), "a user's file").expect("write");
        let r = RunDir::create(&out).expect("run");
        let e = r.publish().expect_err("a user's latest");
        assert!(e.to_string().contains("umbra did not write"), "{e}");
        assert_eq!(
            std::fs::read_to_string(out.join("latest")).expect("kept"),
            "a user's file"
        );
        let _ = std::fs::remove_dir_all(&out);
    }
}
