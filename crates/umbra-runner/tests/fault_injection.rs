//! Fault injection: umbra's results hold under faults in its own plumbing, or it says so.
//! Each test injects one fault from the outside, through the `umbra` binary, as a CI system
//! or a careless contributor would:
//!
//! - a damaged judging cache (bytes flipped, truncated, emptied) is recomputed with a warning
//!   naming the file, and the results are the clean run's; one that cannot be written is said
//!   once;
//! - two runs into one `--out` keep both their results; a run killed (SIGKILL) at several
//!   points or interrupted (SIGTERM) leaves the previous `latest` intact;
//! - a full disk (a small tmpfs where one can be mounted, and always a file-size limit) leaves
//!   the previous `latest` intact and no temporary file behind;
//! - report pictures are copies: editing them in place leaves the goldens as they were;
//! - insta's environment (`INSTA_UPDATE=always`, `INSTA_FORCE_PASS=1`) can neither write nor
//!   pass a golden, and under `CI=true` nothing under the golden directory changes, pending
//!   snapshots included;
//! - hostile text in a reason reaches neither the terminal nor junit.xml raw (the HTML page
//!   is checked in chromium by umbra-report's `gallery_browser`);
//! - configuration mistakes are usage errors (exit 125) naming the flag, and an empty shard
//!   is a successful one; `@when` terms the case format cannot satisfy, a UMBRA_FAULT naming
//!   no fault and `--out` inside `--cases` are refused; a stale expectation line is said;
//! - (issue 36) a GL error in one run's shadow pass stays in that run; a killed run's workers
//!   die with it, and an interrupted run keeps its finished verdicts; a crash leaves its
//!   stderr, signal and inherited driver variables with its run; a golden that cannot be
//!   written or decoded is said, and a case name longer than a file name still gets one.

mod common;

use common::{scratch, text};

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn command(args: &[&str], env: &[(&str, &str)]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_umbra"));
    c.args(args)
        .current_dir(repo())
        .env("UMBRA_FAKE_BACKENDS", "1")
        .env_remove("UMBRA_MESA");
    for (k, v) in env {
        c.env(k, v);
    }
    c
}

fn umbra(args: &[&str], env: &[(&str, &str)]) -> Output {
    command(args, env).output().expect("run umbra")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap_or_default()
}

/// A conformance run of the reference on one case point with goldens in `golden` (or
/// `none`).
fn ref_args<'a>(out: &'a Path, golden: &'a str) -> Vec<&'a str> {
    vec![
        "conformance",
        "--backend",
        "ref",
        "--filter",
        "square*",
        "--golden",
        golden,
        "--out",
        s(out),
    ]
}

/// [`ref_args`] judged alone, with the judging cache in `cache`.
fn ref_run<'a>(out: &'a Path, cache: &'a Path) -> Vec<&'a str> {
    let mut args = ref_args(out, "none");
    args.extend(["--judge-cache", s(cache)]);
    args
}

/// results.csv without its time column, and errors.csv: what a run judged.
fn judged(out: &Path) -> String {
    let results = std::fs::read_to_string(out.join("latest/results.csv")).expect("results.csv");
    let rows: Vec<String> = results
        .lines()
        .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string())
        .collect();
    let errors = std::fs::read_to_string(out.join("latest/errors.csv")).expect("errors.csv");
    let errors: Vec<String> = errors
        .lines()
        .map(|l| {
            // The time columns end each row; what was judged comes before them.
            l.split(',').take(12).collect::<Vec<_>>().join(",")
        })
        .collect();
    format!("{}\n{}", rows.join("\n"), errors.join("\n"))
}

/// Every file under `dir`, recursively.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                out.extend(walk(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// Temporary files of umbra's atomic writes (`.PID.NAME`) left anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    walk(dir)
        .into_iter()
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.strip_prefix('.'))
                .and_then(|n| n.split_once('.'))
                .is_some_and(|(pid, _)| pid.parse::<u32>().is_ok())
        })
        .collect()
}

fn latest_id(out: &Path) -> Option<String> {
    std::fs::read_link(out.join("latest"))
        .ok()
        .and_then(|t| t.file_name().map(|n| n.to_string_lossy().into_owned()))
}

/// Every report file is there and report.json is whole.
fn assert_complete(run: &Path) {
    for f in [
        "results.csv",
        "failures.csv",
        "errors.csv",
        "twins.csv",
        "drivers.txt",
        "report.json",
        "junit.xml",
        "report.html",
    ] {
        assert!(run.join(f).is_file(), "{} lacks {f}", run.display());
    }
    let json = std::fs::read_to_string(run.join("report.json")).expect("report.json");
    serde_json::from_str::<serde_json::Value>(&json).expect("report.json is whole JSON");
    assert!(!run.join("INCOMPLETE").exists(), "{}", run.display());
}

/// One way to damage a cache entry's bytes.
type Damage = fn(&mut Vec<u8>);

#[test]
fn damaged_cache_entries_are_recomputed_with_a_warning_and_judge_as_a_clean_run() {
    let (out, cache) = (scratch("fi-cache-out"), scratch("fi-cache"));
    let o = umbra(&ref_run(&out, &cache), &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let clean = judged(&out);
    let entries: Vec<PathBuf> = walk(&cache)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|x| x == "bin"))
        .collect();
    assert!(entries.len() >= 2, "truth and judged entries: {entries:?}");
    let damages: [(&str, Damage); 4] = [
        ("flipped", |b| {
            let mid = b.len() / 2;
            for k in 0..4 {
                b[mid + 97 * k] ^= 0x5a;
            }
        }),
        ("one bit", |b| b[30] ^= 0x01),
        ("truncated", |b| b.truncate(b.len() / 3)),
        ("empty", Vec::clear),
    ];
    for (what, damage) in damages {
        for e in &entries {
            let mut bytes = std::fs::read(e).expect("entry");
            damage(&mut bytes);
            std::fs::write(e, bytes).expect("damage");
        }
        let o = umbra(&ref_run(&out, &cache), &[]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(0), "{what}: {t}");
        for e in &entries {
            let name = e.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            assert!(
                t.lines()
                    .any(|l| l.contains("warning: judging cache entry") && l.contains(name)),
                "{what}: no warning naming {name}:\n{t}"
            );
        }
        assert_eq!(judged(&out), clean, "{what}: judged differently");
    }
    // The recomputed entries are whole again: a further run says nothing.
    let o = umbra(&ref_run(&out, &cache), &[]);
    assert!(!text(&o).contains("warning:"), "{}", text(&o));
    assert_eq!(judged(&out), clean);
}

#[test]
fn a_cache_that_cannot_be_written_is_said_once_and_the_run_is_the_same() {
    let (out, dir) = (scratch("fi-ro-out"), scratch("fi-ro"));
    let o = umbra(&ref_run(&out, &dir.join("c")), &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let clean = judged(&out);
    // A regular file where the cache directory should be: nothing can be written under it
    // (a read-only mount would be the same; a chmod is no test when the tests run as root).
    let blocked = dir.join("blocked");
    std::fs::write(&blocked, b"not a directory").expect("file");
    let o = umbra(&ref_run(&out, &blocked), &[]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert_eq!(t.matches("cannot be written").count(), 1, "said once:\n{t}");
    assert!(t.contains("warning: the judging cache"), "{t}");
    assert_eq!(judged(&out), clean);
}

#[test]
fn two_runs_into_one_out_both_keep_their_results() {
    let (out, cache) = (scratch("fi-two"), scratch("fi-two-cache"));
    let start = || {
        command(&ref_run(&out, &cache), &[])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn")
    };
    let (a, b) = (start(), start());
    let (a, b) = (
        a.wait_with_output().expect("a"),
        b.wait_with_output().expect("b"),
    );
    assert_eq!(a.status.code(), Some(0), "{}", text(&a));
    assert_eq!(b.status.code(), Some(0), "{}", text(&b));
    let runs: Vec<PathBuf> = std::fs::read_dir(out.join("runs"))
        .expect("runs")
        .flatten()
        .map(|e| e.path())
        .collect();
    assert_eq!(runs.len(), 2, "{runs:?}");
    for r in &runs {
        assert_complete(r);
        let id = r.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        assert!(
            text(&a).contains(id) || text(&b).contains(id),
            "each run names its own directory ({id})"
        );
        // Each run's pictures are its own: one run, one picture directory.
        assert_eq!(
            std::fs::read_dir(r.join("pictures"))
                .expect("pictures")
                .flatten()
                .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
                .count(),
            1
        );
    }
    let shown = latest_id(&out).expect("latest is a link to a run");
    assert!(runs.iter().any(|r| r.ends_with(&shown)));
}

/// Waits for `child` up to `limit`; kills it if it is still running then.
fn wait_for(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let t = Instant::now();
    while t.elapsed() < limit {
        if let Ok(Some(st)) = child.try_wait() {
            return Some(st);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// The live processes whose environment names judging cache `cache` or a directory in it
/// (the workers of the runs given it).
fn workers_of(cache: &Path) -> Vec<u32> {
    let needle = format!("UMBRA_JUDGE_CACHE={}", cache.display());
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    procs
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            let env = std::fs::read(format!("/proc/{pid}/environ")).unwrap_or_default();
            let zombie = std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
                s.rsplit_once(')')
                    .is_some_and(|(_, r)| r.trim_start().starts_with('Z'))
            });
            !zombie
                && env
                    .split(|b| *b == 0)
                    .any(|v| v.starts_with(needle.as_bytes()))
        })
        .collect()
}

/// `umbra args` started, once its stdout has printed a line containing `line` (at most 120 s);
/// with the thread that gathers all it prints.
fn spawn_until(args: &[&str], line: &str) -> (Child, std::thread::JoinHandle<String>) {
    let mut child = command(args, &[])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let stdout = child.stdout.take().expect("stdout");
    let (seen, printed) = std::sync::mpsc::channel();
    let wanted = line.to_string();
    let all = std::thread::spawn(move || {
        use std::io::BufRead as _;
        let mut all = String::new();
        for line in std::io::BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
        {
            if line.contains(&wanted) {
                let _ = seen.send(());
            }
            all += &line;
            all.push('\n');
        }
        all
    });
    printed
        .recv_timeout(Duration::from_secs(120))
        .unwrap_or_else(|_| panic!("umbra {args:?} never printed {line:?}"));
    (child, all)
}

#[test]
fn a_killed_or_interrupted_run_leaves_the_previous_latest_intact() {
    let (out, cache) = (scratch("fi-kill"), scratch("fi-kill-cache"));
    let o = umbra(&ref_run(&out, &cache), &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let before = latest_id(&out).expect("published");
    let report = std::fs::read(out.join("latest/report.json")).expect("report");
    // A run that lasts: the reference, then a backend that hangs until its timeout.
    let long = [
        "conformance",
        "--backend",
        "ref",
        "--backend",
        "fake/hang",
        "--filter",
        "*occluder",
        "--golden",
        "none",
        "--timeout",
        "60",
        "--out",
        s(&out),
        "--judge-cache",
        s(&cache),
    ];
    for at in [50, 400, 1500, 3000] {
        let mut child = command(&long, &[])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn");
        std::thread::sleep(Duration::from_millis(at));
        let _ = child.kill();
        let _ = child.wait();
        // Its workers die with it, the one hanging in fake/hang included (issue 36: they
        // lived on, parent PID 1, after every CI run).
        // (A deadline, not a wait: they go within a watchdog tick, 100 ms, when nothing stalls.)
        let deadline = Instant::now() + Duration::from_secs(10);
        while !workers_of(&cache).is_empty() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(50));
        }
        assert_eq!(
            workers_of(&cache),
            Vec::<u32>::new(),
            "killed at {at} ms: workers outlived it"
        );
        assert_eq!(
            latest_id(&out).as_deref(),
            Some(before.as_str()),
            "killed at {at} ms"
        );
        assert_eq!(
            std::fs::read(out.join("latest/report.json")).expect("report"),
            report,
            "killed at {at} ms: the previous report changed"
        );
    }
    // SIGTERM: an orderly stop, now, not after the hang's timeout. Sent once the reference's
    // last run has printed its verdict (not after a fixed sleep, which a slow machine
    // outlasts): its verdict must be among the partial results.
    let (mut child, printed) = spawn_until(&long, "Pass ref/square-occluder");
    let t = Instant::now();
    let kill = Command::new("sh")
        .args(["-c", &format!("kill -TERM {}", child.id())])
        .status()
        .expect("kill");
    assert!(kill.success());
    let status = wait_for(&mut child, Duration::from_secs(20)).expect("stopped on SIGTERM");
    let o = child.wait_with_output().expect("output");
    let t_stop = t.elapsed();
    let said = printed.join().expect("stdout") + &text(&o);
    assert_eq!(status.code(), Some(130), "{said}");
    assert!(t_stop < Duration::from_secs(15), "took {t_stop:?}");
    assert!(
        said.contains("interrupted by SIGTERM") && said.contains("not published"),
        "{said}"
    );
    assert!(
        said.contains(&format!("still shows runs/{before}")),
        "{said}"
    );
    assert_eq!(latest_id(&out).as_deref(), Some(before.as_str()));
    let unfinished = std::fs::read_dir(out.join("runs"))
        .expect("runs")
        .flatten()
        .filter(|e| e.path().join("INCOMPLETE").is_file())
        .count();
    assert!(unfinished >= 1, "the interrupted run is marked");
    // The verdicts of the runs that finished are there, as the message says (issue 36: it
    // said "partial results" of a directory holding pictures only).
    assert!(
        said.contains("results.csv") && said.contains("junit.xml"),
        "{said}"
    );
    let partial = std::fs::read_dir(out.join("runs"))
        .expect("runs")
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            std::fs::read_to_string(p.join("INCOMPLETE")).is_ok_and(|w| w.contains("SIGTERM"))
        })
        .expect("the interrupted run's directory");
    let verdicts = std::fs::read_to_string(partial.join("results.csv")).expect("results.csv");
    assert!(verdicts.contains("ref/square-occluder,Pass"), "{verdicts}");
    // The next run publishes, and sweeps what killed processes left in the cache: a worker
    // killed while computing an entry leaves its lock (a parent's SIGKILL alone does not: its
    // workers see their input close and finish), and one killed mid-write its temporary.
    let build = std::fs::read_dir(&cache)
        .expect("cache")
        .flatten()
        .find(|e| e.path().is_dir())
        .expect("this build's directory")
        .path();
    std::fs::write(build.join("truth-00000000deadbeef.lock"), "4194303999").expect("lock");
    std::fs::write(
        build.join(".4194303999.truth-00000000deadbeef.bin"),
        b"half",
    )
    .expect("tmp");
    let o = umbra(&ref_run(&out, &cache), &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_complete(&out.join("latest"));
    assert_eq!(temporaries(&cache), Vec::<PathBuf>::new());
    assert_eq!(temporaries(&out.join("latest")), Vec::<PathBuf>::new());
    let locks: Vec<PathBuf> = walk(&cache)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|x| x == "lock"))
        .collect();
    assert_eq!(locks, Vec::<PathBuf>::new(), "locks of killed processes");
}

/// A disk-full run: exit 125, said, the previous `latest` whole, no temporary file.
fn assert_full_disk_is_contained(out: &Path, cache: &Path, before: &str, o: &Output) {
    let t = text(o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("not published") || t.contains("cannot create a run directory"),
        "{t}"
    );
    assert_eq!(latest_id(out).as_deref(), Some(before), "{t}");
    assert_complete(&out.join("latest"));
    assert_eq!(temporaries(out), Vec::<PathBuf>::new(), "{t}");
    assert_eq!(temporaries(cache), Vec::<PathBuf>::new(), "{t}");
}

#[test]
fn a_full_disk_leaves_the_previous_latest_intact_and_no_temporary_file() {
    // A file-size limit (`ulimit -f`, in 512-byte blocks), which every machine has: the
    // report page (pictures inlined) cannot be written, the small files can.
    let (out, cache) = (scratch("fi-full"), scratch("fi-full-cache"));
    let o = umbra(&ref_run(&out, &cache), &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let before = latest_id(&out).expect("published");
    let args = ref_run(&out, &cache).join(" ");
    let o = Command::new("sh")
        .args([
            "-c",
            &format!("ulimit -f 40; exec {} {args}", env!("CARGO_BIN_EXE_umbra")),
        ])
        .current_dir(repo())
        .output()
        .expect("run");
    assert!(
        text(&o).contains("File too large"),
        "the limit bit: {}",
        text(&o)
    );
    assert_full_disk_is_contained(&out, &cache, &before, &o);

    // A real ENOSPC on a small tmpfs, where this process may mount one (root with
    // CAP_SYS_ADMIN, as in CI's container and on a developer's machine under sudo): the disk
    // filled to within one 64 KiB chunk (the run gets part way), then to the last block.
    let mnt = scratch("fi-tmpfs");
    let Some(_mounted) = Tmpfs::mount(&mnt, "16m") else {
        eprintln!(
            "note: cannot mount a tmpfs here; ENOSPC was tested through the file-size limit above"
        );
        return;
    };
    let (out, cache) = (mnt.join("out"), mnt.join("cache"));
    let o = umbra(&ref_run(&out, &cache), &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let before = latest_id(&out).expect("published");
    for left in [1, 0] {
        let fill = mnt.join("fill");
        std::fs::create_dir_all(&fill).expect("fill dir");
        let mut chunks = 0;
        while std::fs::write(fill.join(chunks.to_string()), vec![0u8; 64 << 10]).is_ok() {
            chunks += 1;
        }
        for k in 0..left {
            let _ = std::fs::remove_file(fill.join((chunks - 1 - k).to_string()));
        }
        let o = umbra(&ref_run(&out, &cache), &[]);
        let t = text(&o);
        assert!(
            t.contains("No space left on device"),
            "{left} chunk(s) free: {t}"
        );
        assert_full_disk_is_contained(&out, &cache, &before, &o);
        std::fs::remove_dir_all(&fill).expect("unfill");
    }
}

/// A tmpfs mounted for one test, unmounted when dropped (also when the test fails).
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(at: &Path, size: &str) -> Option<Tmpfs> {
        Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs", s(at)])
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|st| st.success())
            .then(|| Tmpfs(at.to_path_buf()))
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// A conformance run of the reference on one case point against the goldens in `golden`.
fn golden_run(golden: &Path, out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Output {
    let mut args = ref_args(out, s(golden));
    args.extend(extra);
    umbra(&args, env)
}

#[test]
fn report_pictures_are_copies_and_editing_them_leaves_the_goldens() {
    let root = scratch("fi-links");
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("golden");
    let run = |extra: &[&str], env: &[(&str, &str)]| golden_run(&golden, &out, extra, env);
    let o = run(&["--bless"], &[("CI", "false")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let o = run(&[], &[("CI", "true")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let goldens: Vec<(PathBuf, Vec<u8>)> = walk(&golden)
        .into_iter()
        .map(|p| {
            let b = std::fs::read(&p).expect("golden");
            (p, b)
        })
        .collect();
    assert!(
        goldens
            .iter()
            .any(|(p, _)| p.to_string_lossy().ends_with(".snap.png"))
    );
    let pictures = walk(&out.join("latest/pictures"));
    assert!(
        pictures.iter().any(|p| p.ends_with("golden.png")),
        "{pictures:?}"
    );
    // An in-place optimiser: every report picture rewritten through its own path.
    for p in &pictures {
        std::fs::OpenOptions::new()
            .write(true)
            .truncate(true)
            .open(p)
            .and_then(|mut f| std::io::Write::write_all(&mut f, b"optimised"))
            .expect("edit in place");
    }
    for (p, b) in &goldens {
        assert_eq!(
            &std::fs::read(p).expect("golden"),
            b,
            "{} changed",
            p.display()
        );
    }
}

#[test]
fn insta_environment_can_neither_write_nor_pass_a_golden_and_ci_changes_nothing() {
    let root = scratch("fi-insta");
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("golden");
    // The backend has goldens; this run's is missing.
    let seeded = common::seed_goldens(&golden);
    let own = |p: &PathBuf| !p.to_string_lossy().contains(seeded);
    let run = |extra: &[&str], env: &[(&str, &str)]| golden_run(&golden, &out, extra, env);
    // No golden yet: the environment asks insta to write it, and to pass whatever happens.
    let hostile = [
        ("INSTA_UPDATE", "always"),
        ("INSTA_FORCE_PASS", "1"),
        ("INSTA_FORCE_UPDATE", "1"),
    ];
    for ci in ["true", "false"] {
        let mut env = hostile.to_vec();
        env.push(("CI", ci));
        let o = run(&[], &env);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "CI={ci}: {t}");
        assert!(t.contains("note: ignored INSTA_"), "{t}");
        assert!(
            !walk(&golden)
                .iter()
                .filter(|p| own(p))
                .any(|p| p.to_string_lossy().ends_with(".snap.png")),
            "CI={ci}: a golden was written: {:?}",
            walk(&golden)
        );
    }
    // Outside CI that left a pending snapshot for review; under CI=true it must stay as it is,
    // byte for byte, and nothing else may appear.
    let listing = |d: &Path| -> Vec<(PathBuf, Vec<u8>)> {
        let mut v: Vec<(PathBuf, Vec<u8>)> = walk(d)
            .into_iter()
            .map(|p| {
                let b = std::fs::read(&p).expect("file");
                (p, b)
            })
            .collect();
        v.sort();
        v
    };
    let pending = listing(&golden);
    assert!(
        pending
            .iter()
            .any(|(p, _)| p.to_string_lossy().ends_with(".snap.new.png")),
        "{pending:?}"
    );
    let o = run(&[], &[("CI", "true")]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert_eq!(listing(&golden), pending, "CI changed the golden directory");
    // Blessing is a flag, refused under CI.
    let o = run(&["--bless"], &[("CI", "true")]);
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
    assert_eq!(listing(&golden), pending);
    let o = run(&["--bless"], &[("CI", "false")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let blessed = walk(&golden)
        .into_iter()
        .filter(|p| own(p))
        .find(|p| p.to_string_lossy().ends_with(".snap.png"))
        .expect("blessed");
    // A pending snapshot beside a golden the run matches: outside CI a match clears it (as
    // insta would), under CI=true it stays, with its .snap.new.
    let stem = blessed
        .to_string_lossy()
        .trim_end_matches(".png")
        .to_string();
    std::fs::write(format!("{stem}.new"), "pending review\n").expect("pending");
    std::fs::copy(&blessed, format!("{stem}.new.png")).expect("pending png");
    let pending = listing(&golden);
    let o = run(&[], &[("CI", "true")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(listing(&golden), pending, "CI changed the golden directory");
}

#[test]
fn hostile_text_reaches_neither_the_terminal_nor_junit_raw() {
    let (out, exp) = (scratch("fi-hostile"), scratch("fi-hostile-exp"));
    let reason =
        "<!-- <script>x</script> \u{1b}[2K\rconformance: 0 failed, 0 skipped\u{7}\u{2028}\u{202e}";
    std::fs::write(
        exp.join("hostile.txt"),
        format!("fake/crash/square*,Crash,{reason}\n"),
    )
    .expect("expectations");
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "fake/crash",
            "--filter",
            "square*",
            "--golden",
            "none",
            "--expectations",
            s(&exp),
            "--out",
            s(&out),
        ],
        &[("CI", "true")],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(stdout.contains("ExpectedFail"), "{stdout}");
    assert!(
        !stdout
            .chars()
            .any(|c| (c.is_control() && c != '\n') || ('\u{202a}'..='\u{202e}').contains(&c)),
        "a control character reached the terminal: {stdout:?}"
    );
    assert!(stdout.contains("\\u{1b}[2K\\r"), "{stdout}");
    assert_eq!(
        stdout
            .lines()
            .filter(|l| l.starts_with("conformance:"))
            .count(),
        1,
        "{stdout}"
    );
    let junit = std::fs::read_to_string(out.join("latest/junit.xml")).expect("junit");
    assert!(
        !junit.chars().any(|c| c.is_control() && c != '\n'),
        "{junit:?}"
    );
}

#[test]
fn configuration_mistakes_are_usage_errors_that_name_the_flag() {
    let out = scratch("fi-usage");
    let exp = scratch("fi-usage-exp");
    flags_out_of_range_are_usage_errors(&out);
    expectations_that_can_never_match_are_usage_errors(&out, &exp);
    a_stale_expectation_line_is_said(&out, &exp);
    let cases = two_case_files_with_one_name_are_refused(&out);
    a_fault_name_must_name_a_fault_and_an_empty_one_is_none(&out);
    reports_inside_the_case_directory_are_refused(&cases);
    an_empty_shard_succeeds_with_a_note(&out);
}

/// A conformance run of the reference on one case point under CI, into `out`, with `extra`
/// flags.
fn usage_run(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "conformance",
        "--backend",
        "ref",
        "--filter",
        "square*",
        "--out",
        s(out),
    ];
    args.extend(extra);
    umbra(&args, &[("CI", "true")])
}

/// A flag's value out of its range, or a directory that is not there, is a usage error that
/// names the flag; `--golden DIR` is not created.
fn flags_out_of_range_are_usage_errors(out: &Path) {
    let nowhere = out.join("nowhere");
    for (extra, says) in [
        (
            vec!["--timeout", "0"],
            "invalid value '0' for '--timeout <SECS>'",
        ),
        (
            vec!["--timeout", "10m"],
            "invalid value '10m' for '--timeout <SECS>'",
        ),
        (vec!["--jobs", "0"], "invalid value '0' for '--jobs <N>'"),
        (vec!["--jobs", "99999"], "--jobs 99999"),
        (vec!["--max-memory", "1KiB"], "--max-memory"),
        (vec!["--expectations", s(&nowhere)], "--expectations"),
        (vec!["--golden", s(&nowhere)], "--golden"),
    ] {
        let o = usage_run(out, &extra);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(125), "{extra:?}: {t}");
        assert!(t.contains(says), "{extra:?} must name {says}: {t}");
    }
    assert!(!nowhere.exists(), "--golden DIR must not be created");
}

/// Expectation lines that can never match, or that claim one run twice, are usage errors
/// that name the file and line.
fn expectations_that_can_never_match_are_usage_errors(out: &Path, exp: &Path) {
    // Expectation lines that can never match, or that claim one run twice.
    for (lines, says) in [
        ("ref/square-occluder[,Crash,typo\n", "can never match"),
        (
            "[z-a]*,Crash,a class umbra globs do not have\n",
            "can never match",
        ),
        (
            "@applies renderer=[\nref/*,Crash,x\n",
            "can never match a renderer",
        ),
        (
            "ref/square*,Crash,one\nref/*,Timeout,two\n",
            "both match run ref/square-occluder",
        ),
        // Conditions the case format cannot satisfy (issue 36): they once never applied.
        (
            "@when shadow.bais.constant>0\nref/*,Fail,typo\n",
            "names no field",
        ),
        ("@when shadow.bias.constant>>0\nref/*,Fail,typo\n", "\">0\""),
        ("@when shadow.format=depth17\nref/*,Fail,x\n", "depth17"),
        // A check no run names: the nearest is offered.
        ("ref/*,Fail:color<=3,typo\n", "did you mean colour?"),
    ] {
        std::fs::write(exp.join("e.txt"), lines).expect("expectations");
        let o = usage_run(out, &["--expectations", s(exp), "--golden", "none"]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(125), "{lines:?}: {t}");
        assert!(t.contains(says) && t.contains("e.txt:"), "{lines:?}: {t}");
    }
}

/// A line that matches no run of the catalogue on any backend is said, and only that line.
fn a_stale_expectation_line_is_said(out: &Path, exp: &Path) {
    // A line that matches no run of the catalogue on any backend is said (issue 36).
    std::fs::write(
        exp.join("e.txt"),
        "ref/square-occluder,Crash,live\nref/no-such-case,Crash,a renamed case\n",
    )
    .expect("expectations");
    let o = usage_run(out, &["--expectations", s(exp), "--golden", "none"]);
    let t = text(&o);
    assert!(
        t.contains("warning: expectation") && t.contains("e.txt:2") && t.contains("stale"),
        "{t}"
    );
    assert!(!t.contains("e.txt:1 "), "{t}");
}

/// Two case files with one name are refused, naming both; the case directory, which
/// [`reports_inside_the_case_directory_are_refused`] reuses.
fn two_case_files_with_one_name_are_refused(out: &Path) -> PathBuf {
    // Two case files with one name.
    let cases = scratch("fi-usage-cases");
    let square =
        std::fs::read_to_string(repo().join("cases/basics/square-occluder.json")).expect("case");
    std::fs::write(cases.join("a.json"), &square).expect("a");
    std::fs::write(cases.join("b.json"), &square).expect("b");
    let o = usage_run(out, &["--cases", s(&cases), "--golden", "none"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("a.json") && t.contains("b.json") && t.contains("name"),
        "{t}"
    );
    cases
}

/// A UMBRA_FAULT that names no fault is refused with the nearest name; an empty one is no
/// fault.
fn a_fault_name_must_name_a_fault_and_an_empty_one_is_none(out: &Path) {
    // A fault name no fault has once ran no fault, silently.
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "ref",
            "--filter",
            "square*",
            "--out",
            s(out),
        ],
        &[
            ("UMBRA_SELFTEST", "1"),
            ("UMBRA_FAULT", "offset-units-lowe"),
        ],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("\"offset-units-lowe\" names no fault") && t.contains("offset-units-low"),
        "{t}"
    );

    // An empty UMBRA_FAULT (a CI matrix's blank entry) is no fault, not an error.
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "ref",
            "--filter",
            "square*",
            "--golden",
            "none",
            "--out",
            s(out),
        ],
        &[("UMBRA_FAULT", "")],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

/// Reports inside the case directory would be read as cases by the next run: refused, and
/// nothing written.
fn reports_inside_the_case_directory_are_refused(cases: &Path) {
    // Reports inside the case directory would be read as cases by the next run.
    let inside = cases.join("reports");
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "ref",
            "--cases",
            s(cases),
            "--out",
            s(&inside),
        ],
        &[("CI", "true")],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("--out") && t.contains("inside the case directory"),
        "{t}"
    );
    assert!(!inside.exists(), "a refused run writes nothing");
}

/// More shards than runs: an empty shard succeeds, with a note.
fn an_empty_shard_succeeds_with_a_note(out: &Path) {
    // More shards than runs: an empty shard succeeds, with a note.
    let o = usage_run(out, &["--golden", "none", "--shard", "5/9"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("shard 5/9 holds none"), "{t}");
}

#[test]
fn a_damaged_blessed_on_manifest_is_said_and_not_used() {
    let root = scratch("fi-manifest");
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("golden");
    let o = golden_run(&golden, &out, &["--bless"], &[("CI", "false")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // A hand edit that does not update the checksum (or a damaged file).
    std::fs::write(
        golden.join("blessed-on.json"),
        "{\n  \"#fnv1a64\": \"0000000000000000\",\n  \"ref\": \"9.9\"\n}\n",
    )
    .expect("manifest");
    let o = golden_run(&golden, &out, &[], &[("CI", "true")]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert_eq!(
        t.lines()
            .filter(|l| l.contains("blessed-on.json") && l.contains("fails its checksum"))
            .count(),
        1,
        "said once: {t}"
    );
}

/// A GL error in one run's shadow pass stays in that run (issue 36: the timer query it had
/// begun stayed open, and every later run on that worker failed in glBeginQuery): the
/// injected error fails its own run, naming the stage, and the run after it on the same
/// worker passes.
#[test]
fn a_gl_error_stays_in_its_run() {
    let out = scratch("fi-gl-error");
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "gl33/llvmpipe",
            "--cases",
            "cases/basics",
            "--golden",
            "none",
            "--jobs",
            "1",
            "--out",
            s(&out),
        ],
        &[("UMBRA_INJECT_GL_ERROR", "l-occluder")],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("Fail gl33/llvmpipe/l-occluder") && t.contains("GL_INVALID_ENUM"),
        "{t}"
    );
    assert!(t.contains("Pass gl33/llvmpipe/square-occluder"), "{t}");
    assert!(t.contains("1 passed, 1 failed"), "{t}");
}

/// A golden that cannot be written is said, never reported as a pending snapshot that does
/// not exist, and `--bless` that blesses nothing fails (issue 36): here insta's files are
/// blocked by directories of their names (what a read-only golden directory does for a user
/// who is not root). A case name far longer than a file name may be still gets its golden:
/// the stem keeps the name's first 160 characters and the hash of all of it.
#[test]
fn a_golden_that_cannot_be_written_is_said() {
    let root = scratch("fi-unwritable");
    let (golden, out) = (root.join("golden"), root.join("out"));
    let stem = umbra_runner::judge::golden::stem("ref/square-occluder");
    // The backend's folder of the golden directory holds them.
    let folder = umbra_runner::judge::golden::folder("ref");
    for blocker in [format!("{stem}.snap"), format!("{stem}.snap.new")] {
        std::fs::create_dir_all(golden.join(&folder).join(blocker)).expect("blocker");
    }
    for (extra, env) in [
        (vec!["--bless"], ("CI", "false")),
        (vec![], ("CI", "false")),
    ] {
        let o = golden_run(&golden, &out, &extra, &[env]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {t}");
        assert!(t.contains("could not be written"), "{extra:?}: {t}");
        assert!(!t.contains("pending"), "{extra:?}: {t}");
    }

    let cases = root.join("cases");
    std::fs::create_dir_all(&cases).expect("cases");
    let long = "l".repeat(240);
    let square =
        std::fs::read_to_string(repo().join("cases/basics/square-occluder.json")).expect("case");
    std::fs::write(
        cases.join("long.json"),
        square.replace("\"square-occluder\"", &format!("\"{long}\"")),
    )
    .expect("case");
    let golden = root.join("golden-long");
    std::fs::create_dir_all(&golden).expect("golden");
    let args = [
        "conformance",
        "--backend",
        "ref",
        "--cases",
        s(&cases),
        "--golden",
        s(&golden),
        "--out",
        s(&out),
        "--bless",
    ];
    let o = umbra(&args, &[("CI", "false")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let written = umbra_runner::judge::golden::stem(&format!("ref/{long}"));
    assert!(written.len() < 200, "{written}");
    assert!(
        golden
            .join(&folder)
            .join(format!("{written}.snap"))
            .is_file(),
        "{}",
        text(&o)
    );
}

/// A crash leaves its evidence with its run (issue 36): the worker's stderr (the C library's
/// or the driver's last words) in the reason, report.json, junit.xml and the HTML report, the
/// signal, and the driver variables the run inherited in its reproduce command, so that it
/// reproduces (LP_NATIVE_VECTOR_WIDTH=128 made lavapipe corrupt its heap on Mesa 22.3.6).
#[test]
fn a_crash_leaves_its_evidence_with_its_run() {
    let out = scratch("fi-crash-evidence");
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "fake/crash",
            "--filter",
            "square*",
            "--golden",
            "none",
            "--out",
            s(&out),
        ],
        &[("LP_NATIVE_VECTOR_WIDTH", "128")],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("SIGABRT") && t.contains("its last stderr line: corrupted size"),
        "{t}"
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json")).expect("report.json"),
    )
    .expect("JSON");
    let run = report["runs"]
        .as_array()
        .and_then(|r| r.iter().find(|r| r["name"] == "fake/crash/square-occluder"))
        .unwrap_or_else(|| panic!("the run in {report}"));
    assert_eq!(run["status"], "Crash", "{run}");
    assert!(
        run["stderr"]
            .as_str()
            // Read past a line that is not UTF-8 (kept lossily), to the last words.
            .is_some_and(|e| e.contains("\u{fffd}\u{fffd} bytes") && e.contains("corrupted size")),
        "{run}"
    );
    assert!(
        run["reproduce"]
            .as_str()
            .is_some_and(|c| c.starts_with("LP_NATIVE_VECTOR_WIDTH=128 ")),
        "{run}"
    );
    let junit = std::fs::read_to_string(out.join("latest/junit.xml")).expect("junit.xml");
    assert!(
        junit.contains("<system-err>") && junit.contains("corrupted size"),
        "{junit}"
    );
    let html = std::fs::read_to_string(out.join("latest/report.html")).expect("report.html");
    assert!(
        html.contains("corrupted size"),
        "report.html lacks the stderr"
    );
}

/// A worker killed by a fault says where (issue 55, "whose SIGBUS"): the signal's code, the
/// mapping its address lies in and the faulting instruction's library, in the run's reason;
/// the worker still dies by the same signal, and the run is the same Crash.
#[test]
fn a_fault_names_its_mapping_and_the_faulting_library() {
    let out = scratch("fi-sigbus");
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "fake/sigbus",
            "--filter",
            "square-occluder",
            "--golden",
            "none",
            "--out",
            s(&out),
        ],
        &[],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json")).expect("report.json"),
    )
    .expect("JSON");
    let run = report["runs"]
        .as_array()
        .and_then(|r| {
            r.iter()
                .find(|r| r["name"] == "fake/sigbus/square-occluder")
        })
        .unwrap_or_else(|| panic!("the run in {report}"));
    assert_eq!(run["status"], "Crash", "{run}");
    let reason = run["reason"].as_str().unwrap_or_default();
    assert!(reason.contains("SIGBUS"), "{reason}");
    assert!(
        reason.contains("umbra: fatal SIGBUS (BUS_ADRERR")
            && reason.contains("umbra-fake-sigbus-")
            && reason.contains("(file offset 0x0)"),
        "{reason}"
    );
    // The faulting instruction is umbra's own (the fake reads the mapping): named with its
    // offset into the executable.
    let (exe, offset) = reason
        .split("; instruction 0x")
        .nth(1)
        .and_then(|r| r.split_once(" in "))
        .and_then(|(_, r)| r.split_once("+0x"))
        .unwrap_or_else(|| panic!("no instruction in {reason}"));
    let offset: String = offset.chars().take_while(char::is_ascii_hexdigit).collect();
    assert!(exe.ends_with("/umbra"), "{reason}");
    // The address is what addr2line takes (binutils comes with the C compiler the test
    // set-up installs): it names the fake's own function.
    let symbol = Command::new("addr2line")
        .args(["-f", "-i", "-C", "-e", exe, &format!("0x{offset}")])
        .output()
        .expect("addr2line (binutils)");
    let symbol = String::from_utf8_lossy(&symbol.stdout);
    assert!(symbol.contains("fake::sigbus"), "{reason}\n{symbol}");
}

/// A damaged golden PNG is said to be one, naming the file, not "differs" (issue 36).
#[test]
fn a_golden_that_cannot_be_decoded_is_said() {
    let root = scratch("fi-damaged-golden");
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("golden");
    let o = golden_run(&golden, &out, &["--bless"], &[("CI", "false")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let png = walk(&golden)
        .into_iter()
        .find(|p| p.to_string_lossy().ends_with(".snap.png"))
        .expect("a blessed golden");
    std::fs::write(&png, b"<<<<<<< HEAD\nnot a PNG\n").expect("damage");
    let o = golden_run(&golden, &out, &[], &[("CI", "true")]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("cannot be decoded as a PNG") && t.contains(".snap.png"),
        "{t}"
    );
    assert!(!t.contains("differs from its golden"), "{t}");
}

/// `umbra selftest --seed S --count N --out DIR` writes its generated cases into
/// `DIR/selftest-cases` only where umbra made that directory: a user's files there are left
/// as they are and the command cannot run (it once removed every `*.json` there).
#[test]
fn generated_cases_never_empty_a_directory_umbra_did_not_make() {
    let root = scratch("fi-selftest-out");
    let dir = root.join("selftest-cases");
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::write(dir.join("mine.json"), "{}").expect("a user's file");
    let o = umbra(
        &[
            "selftest",
            "--seed",
            "1",
            "--count",
            "1",
            "--backend",
            "gl33/llvmpipe",
            "--out",
            s(&root),
        ],
        &[],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("selftest-cases") && t.contains("only a directory it made"),
        "{t}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("mine.json"))
            .ok()
            .as_deref(),
        Some("{}"),
        "the user's file is untouched"
    );
}
