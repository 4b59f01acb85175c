//! `cargo xtask test`'s run of the test binaries: two at a time, where `cargo test` runs one
//! after another.
//!
//! Why: each test binary already runs its tests on every core, but many of umbra's tests wait
//! on child processes (umbra itself, a driver's worker) and the longest binaries hold one or
//! two long tests, so `cargo test --workspace` kept 1.6 of CI's 2 cores busy on average
//! (measured on a clean build: 538 s of CPU in 340 s of wall time). A second binary beside the
//! first fills those waits: 281 s for the same binaries (docs/performance.md, "The build and
//! the tests, faster").
//!
//! What it keeps of `cargo test`: the same binaries (cargo builds them and names them, with
//! `--no-run --message-format=json-render-diagnostics`), each run from its package's directory
//! with `CARGO_MANIFEST_DIR` and `CARGO_PKG_NAME` set as cargo sets them, the arguments after
//! `--` passed to every binary, and the doc tests (`cargo test --doc`, afterwards). Each
//! binary's output is printed whole when it ends, so two binaries' lines never interleave.
//! What it adds: the longest binaries of the last run start first (their durations are kept
//! in the target directory; a clean clone runs them in cargo's order), and a table of the
//! slowest binaries at the end.

use std::collections::{BTreeMap, VecDeque};
use std::io::{BufRead as _, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Test binaries run at once. Each runs its own tests on every core already; a second one
/// fills the first's waits (measured on 2 cores). More would only add contention there.
const LANES: usize = 2;

/// One test binary as cargo built it.
#[derive(Clone, Debug, PartialEq)]
pub struct TestBinary {
    /// The package it tests.
    pub package: String,
    /// Its target's source (`tests/merge.rs`, `src/lib.rs`), as cargo's "Running" line says.
    pub src: String,
    /// The executable.
    pub exe: PathBuf,
    /// The package's directory: the binary runs there, as under `cargo test`.
    pub dir: PathBuf,
}

impl TestBinary {
    /// The name its duration is kept under: package and source, stable across builds (the
    /// executable's name carries a hash).
    fn key(&self) -> String {
        format!("{} {}", self.package, self.src)
    }
}

/// The test binaries in one line of cargo's JSON messages, if the line names one: a
/// `compiler-artifact` built in test mode with an executable.
pub fn binary_of(line: &str) -> Option<TestBinary> {
    let v: serde_json::Value = serde_json::from_str(line).ok()?;
    if v["reason"] != "compiler-artifact" || v["profile"]["test"] != true {
        return None;
    }
    let exe = PathBuf::from(v["executable"].as_str()?);
    let manifest = PathBuf::from(v["manifest_path"].as_str()?);
    let dir = manifest.parent()?.to_path_buf();
    let src = Path::new(v["target"]["src_path"].as_str()?);
    Some(TestBinary {
        package: v["package_id"]
            .as_str()
            .and_then(package_name)
            .unwrap_or_default(),
        src: src
            .strip_prefix(&dir)
            .unwrap_or(src)
            .to_string_lossy()
            .into_owned(),
        exe,
        dir,
    })
}

/// The package's name in a cargo package id: `path+file:///…/crates/umbra-ref#0.1.0` (the
/// directory's name, when the id does not spell the name) or `…#umbra-ref@0.1.0`.
fn package_name(id: &str) -> Option<String> {
    let (path, tail) = id.rsplit_once('#')?;
    match tail.split_once('@') {
        Some((name, _)) => Some(name.to_string()),
        None => path.rsplit('/').next().map(str::to_string),
    }
}

/// Builds the test binaries (`cargo test --workspace --no-run` with `cargo_args`): the
/// binaries, or the exit code in umbra's four (a failed build could not run: 125).
pub fn build(cargo_args: &[String]) -> Result<Vec<TestBinary>, i32> {
    let mut cmd = crate::cargo_args(&[
        "test",
        "--workspace",
        "--no-run",
        "--message-format=json-render-diagnostics",
    ]);
    cmd.args(cargo_args).stdout(Stdio::piped());
    let mut child = cmd.spawn().map_err(|e| {
        eprintln!("error: cannot run {cmd:?}: {e}");
        crate::COULD_NOT_RUN
    })?;
    let mut binaries = Vec::new();
    if let Some(out) = child.stdout.take() {
        for line in std::io::BufReader::new(out).lines().map_while(Result::ok) {
            binaries.extend(binary_of(&line));
        }
    }
    let status = child.wait().map_err(|e| {
        eprintln!("error: cargo test --no-run: {e}");
        crate::COULD_NOT_RUN
    })?;
    match crate::four(status, "cargo test --no-run", false) {
        0 if binaries.is_empty() => {
            eprintln!("error: cargo test --no-run named no test binary: nothing to run");
            Err(crate::COULD_NOT_RUN)
        }
        0 => Ok(binaries),
        code => Err(code),
    }
}

/// What one binary did.
struct Ran {
    binary: TestBinary,
    took: Duration,
    /// Its exit code, or the signal that ended it (as text), or why it could not start.
    outcome: Result<(), String>,
}

/// Runs every binary, [`LANES`] at a time, the longest of the last run first, each with
/// `test_args`; then the doc tests. 0 when every test passed, 1 when one failed (a binary that
/// failed, crashed or could not start is a failed test, as under `cargo test`).
pub fn run(binaries: Vec<TestBinary>, cargo_args: &[String], test_args: &[String]) -> i32 {
    let record = crate::target_dir(&crate::workspace_root()).join("xtask/test-durations.tsv");
    let last = read_durations(&record);
    let order = longest_first(binaries, &last);
    let expected = order.len();
    let queue = Mutex::new(VecDeque::from(order));
    // Each lane hands back what it ran; a binary is never dropped unreported (a poisoned
    // queue is still a queue: taking from it cannot leave it half-changed).
    let ran: Vec<Ran> = std::thread::scope(|s| {
        let lanes: Vec<_> = (0..LANES)
            .map(|_| {
                s.spawn(|| {
                    let mut ran = Vec::new();
                    while let Some(b) = queue
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner)
                        .pop_front()
                    {
                        ran.push(run_one(b, test_args));
                    }
                    ran
                })
            })
            .collect();
        lanes
            .into_iter()
            .flat_map(|lane| lane.join().unwrap_or_default())
            .collect()
    });
    write_durations(&record, &ran, last);
    summary(&ran);
    let doc = {
        let mut cmd = crate::cargo_args(&["test", "--workspace", "--doc"]);
        cmd.args(cargo_args);
        if !test_args.is_empty() {
            cmd.arg("--").args(test_args);
        }
        crate::status_of(cmd, true)
    };
    if ran.len() != expected {
        eprintln!(
            "FAILED: {} of {expected} test binaries ran to an end (a lane of xtask stopped)",
            ran.len()
        );
        return 1;
    }
    if ran.iter().any(|r| r.outcome.is_err()) {
        return 1;
    }
    doc
}

/// `binaries` in the order to start them: the longest in `last` first, the ones it does not
/// know (new, or a clean clone's) in cargo's order before those it does (one of them may be
/// long, and nothing says otherwise).
fn longest_first(mut binaries: Vec<TestBinary>, last: &BTreeMap<String, f64>) -> Vec<TestBinary> {
    binaries.sort_by(|a, b| {
        let (x, y) = (last.get(&a.key()), last.get(&b.key()));
        match (x, y) {
            (None, None) => std::cmp::Ordering::Equal,
            (None, Some(_)) => std::cmp::Ordering::Less,
            (Some(_), None) => std::cmp::Ordering::Greater,
            (Some(x), Some(y)) => y.total_cmp(x),
        }
    });
    binaries
}

/// Runs one binary from its package's directory, its output kept and printed whole.
fn run_one(b: TestBinary, test_args: &[String]) -> Ran {
    let t0 = Instant::now();
    let out = Command::new(&b.exe)
        .args(test_args)
        .current_dir(&b.dir)
        .env("CARGO_MANIFEST_DIR", &b.dir)
        .env("CARGO_PKG_NAME", &b.package)
        .stdin(Stdio::null())
        .output();
    let took = t0.elapsed();
    let outcome = match &out {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(ended(o.status)),
        Err(e) => Err(format!("could not start: {e}")),
    };
    // Printed when it ends (cargo says "Running" when one starts): with its time.
    let mut text = format!(
        "     Ran {} ({}) [{}] in {:.1} s\n",
        b.src,
        b.exe.display(),
        b.package,
        took.as_secs_f64()
    );
    if let Ok(o) = &out {
        text.push_str(&String::from_utf8_lossy(&o.stdout));
        text.push_str(&String::from_utf8_lossy(&o.stderr));
    }
    if let Err(why) = &outcome {
        text.push_str(&format!("error: {} {}: {why}\n", b.package, b.src));
    }
    // One binary's whole output at once: the other lane's never cuts into it.
    let mut stdout = std::io::stdout().lock();
    let _ = stdout.write_all(text.as_bytes());
    let _ = stdout.flush();
    Ran {
        binary: b,
        took,
        outcome,
    }
}

/// How a binary that failed ended: its code, or the signal that killed it.
fn ended(status: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt as _;
    match (status.code(), status.signal()) {
        (Some(101), _) => "a test failed (exit 101)".to_string(),
        (Some(c), _) => format!("exit code {c}"),
        (None, s) => format!("killed by signal {}", s.unwrap_or(0)),
    }
}

/// The slowest binaries, and every failure, printed after the run.
fn summary(ran: &[Ran]) {
    let mut by_time: Vec<&Ran> = ran.iter().collect();
    by_time.sort_by_key(|r| std::cmp::Reverse(r.took));
    let total: Duration = ran.iter().map(|r| r.took).sum();
    eprintln!(
        "test binaries: {} run, {LANES} at a time, {:.1} s of their wall times in all; the slowest:",
        ran.len(),
        total.as_secs_f64()
    );
    for r in by_time.iter().take(8) {
        eprintln!(
            "  {:>7.1} s  {} {}",
            r.took.as_secs_f64(),
            r.binary.package,
            r.binary.src
        );
    }
    for r in ran {
        if let Err(why) = &r.outcome {
            eprintln!(
                "FAILED: {} {} ({}): {why}",
                r.binary.package,
                r.binary.src,
                r.binary.exe.display()
            );
        }
    }
}

/// The last run's duration of each binary ([`TestBinary::key`] → seconds); none when there
/// was no run (a clean clone) or the file cannot be read.
fn read_durations(path: &Path) -> BTreeMap<String, f64> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| {
            let (secs, key) = l.split_once('\t')?;
            Some((key.to_string(), secs.parse().ok()?))
        })
        .collect()
}

/// Keeps this run's durations (the ones it did not run, from the last), for the next run's
/// order. Only an ordering hint: a file that cannot be written costs speed, not a result.
fn write_durations(path: &Path, ran: &[Ran], mut last: BTreeMap<String, f64>) {
    for r in ran {
        last.insert(r.binary.key(), r.took.as_secs_f64());
    }
    let text: String = last.iter().map(|(k, s)| format!("{s:.2}\t{k}\n")).collect();
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let _ = std::fs::write(path, text);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cargo's JSON names a test binary by its package, source and executable; a library
    /// built for linking, or a build script, is not one.
    #[test]
    fn cargos_messages_name_the_test_binaries_and_nothing_else() {
        let test = r#"{"reason":"compiler-artifact","package_id":"path+file:///w/crates/umbra-runner#0.1.0","manifest_path":"/w/crates/umbra-runner/Cargo.toml","target":{"kind":["test"],"name":"merge","src_path":"/w/crates/umbra-runner/tests/merge.rs"},"profile":{"test":true},"executable":"/w/target/debug/deps/merge-ab12"}"#;
        assert_eq!(
            binary_of(test),
            Some(TestBinary {
                package: "umbra-runner".into(),
                src: "tests/merge.rs".into(),
                exe: "/w/target/debug/deps/merge-ab12".into(),
                dir: "/w/crates/umbra-runner".into(),
            })
        );
        let named = test.replace("umbra-runner#0.1.0", "umbra-runner#umbra-runner@0.1.0");
        assert_eq!(
            binary_of(&named).map(|b| b.package),
            Some("umbra-runner".into())
        );
        let lib = test
            .replace(r#""test":true"#, r#""test":false"#)
            .replace(r#""/w/target/debug/deps/merge-ab12""#, "null");
        assert_eq!(binary_of(&lib), None);
        let built_not_test = test.replace(r#""test":true"#, r#""test":false"#);
        assert_eq!(binary_of(&built_not_test), None);
        assert_eq!(
            binary_of(r#"{"reason":"build-finished","success":true}"#),
            None
        );
        assert_eq!(binary_of("Compiling umbra"), None);
    }

    /// The longest of the last run start first; one the last run did not see starts before
    /// every known one, in cargo's order.
    #[test]
    fn the_longest_and_the_unknown_start_first() {
        let b = |src: &str| TestBinary {
            package: "p".into(),
            src: src.into(),
            exe: src.into(),
            dir: ".".into(),
        };
        let last = BTreeMap::from([
            ("p short".to_string(), 1.0),
            ("p long".to_string(), 80.0),
            ("p middle".to_string(), 20.0),
        ]);
        let order: Vec<String> = longest_first(
            vec![b("short"), b("new1"), b("long"), b("middle"), b("new2")],
            &last,
        )
        .into_iter()
        .map(|b| b.src)
        .collect();
        assert_eq!(order, ["new1", "new2", "long", "middle", "short"]);
    }

    /// The durations survive a write and a read, and a run that did not run a binary keeps
    /// its last duration.
    #[test]
    fn durations_are_kept_for_the_next_run() {
        let dir = std::env::temp_dir().join(format!("xtask-durations-{}", std::process::id()));
        let path = dir.join("test-durations.tsv");
        let ran = vec![Ran {
            binary: TestBinary {
                package: "p".into(),
                src: "tests/a.rs".into(),
                exe: "a".into(),
                dir: ".".into(),
            },
            took: Duration::from_millis(2500),
            outcome: Ok(()),
        }];
        write_durations(&path, &ran, BTreeMap::from([("p tests/b.rs".into(), 7.0)]));
        let read = read_durations(&path);
        assert_eq!(read.get("p tests/a.rs"), Some(&2.5));
        assert_eq!(read.get("p tests/b.rs"), Some(&7.0));
        let _ = std::fs::remove_dir_all(dir);
    }
}
