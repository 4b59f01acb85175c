//! `umbra conformance`: every case point on every selected backend, each backend in worker
//! processes of its own ([`crate::pool`]), judged, with expectations applied, and reported.
//!
//! - Plan: case points (`cases/**/*.json`, `--filter GLOB` on the point id or the full run
//!   name `backend/id`) × backends (`--backend ID`, default every known one), in a fixed
//!   order; `--shard I/N` keeps every N-th run starting at I (0-based), as deqp-runner's
//!   fractions do, so N CI jobs split a run deterministically.
//! - Execution: backend groups run in parallel up to `--jobs` (default: the core count). A
//!   worker that dies costs its run (Crash), one that exceeds `--timeout` seconds costs its run
//!   (Timeout); a fresh worker takes the rest. Every failure is rerun once; a changed result
//!   is a Flake.
//! - Statuses and expectations: [`crate::status`]. A case file that cannot be loaded fails the
//!   run under its own name.
//! - Reports in `OUT/latest/` and `OUT/runs/<unix time>/`: `results.csv` and `failures.csv`
//!   (deqp-runner's formats), `junit.xml`, `report.json`, `report.html` (self-contained),
//!   `errors.csv`, `drivers.txt`, and the pictures of each failure under `failures/`.
//! - Exit codes: 0 all as expected, 1 a regression (Fail, Crash, Timeout, UnexpectedPass),
//!   125 nothing could run (no case, no available backend, bad arguments or expectations), so
//!   `git bisect run cargo xtask conformance --filter X` works.

use std::collections::{BTreeMap, VecDeque};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::args::Args;
use crate::pool::{Reply, Worker};
use crate::status::{Expectations, Status};
use crate::worker::{Metrics, Request, RunReport};

/// Usage line.
pub const USAGE: &str = "umbra conformance [--cases DIR] [--filter GLOB] [--backend ID]... [--shard I/N] [--jobs N] [--timeout SECS] [--expectations DIR] [--golden DIR|none] [--out DIR] [--mesa PREFIX|BUILD_DIR|system] [--max-memory SIZE] [--verbose]";

/// A point's swept values, `(path, value)` in axis order.
type SweepValues = Vec<(String, serde_json::Value)>;

/// Worker start-up (spawn to hello) and, within it, context or device creation, summed over
/// every worker of the run, in µs: part of the harness overhead the summary reports.
static WORKER_START_US: AtomicU64 = AtomicU64::new(0);
static CONTEXT_US: AtomicU64 = AtomicU64::new(0);

/// Where a conformance run's time went, summed over its runs (worker time, not wall).
#[derive(Clone, Debug, Default, Serialize)]
pub struct TimeBudget {
    /// Wall time of the whole run, s.
    pub wall_s: f64,
    /// Σ per-run time measured by the parent (request to answer, retries included), s.
    pub runs_s: f64,
    /// Σ the backends' own frame time (both passes and readback), s.
    pub render_s: f64,
    /// Σ the metamorphic twins (their renders and comparisons), s.
    pub twins_s: f64,
    /// Σ judging: truth, reference with its ambiguity, error, agreement, s.
    pub judge_s: f64,
    /// Σ golden checks: PNG encoding and comparison, s.
    pub golden_s: f64,
    /// Σ worker start-up (spawn to hello), context creation included, s.
    pub worker_start_s: f64,
    /// Of that, context or device creation, s.
    pub context_s: f64,
    /// The rest of the per-run time: case loading, tessellation, protocol, retries, s.
    pub other_s: f64,
}

impl TimeBudget {
    /// Sums the budget of `results`.
    pub fn of(results: &[RunResult], wall: Duration) -> TimeBudget {
        let mut b = TimeBudget {
            wall_s: wall.as_secs_f64(),
            worker_start_s: WORKER_START_US.load(Ordering::Relaxed) as f64 / 1e6,
            context_s: CONTEXT_US.load(Ordering::Relaxed) as f64 / 1e6,
            ..Default::default()
        };
        for r in results {
            b.runs_s += r.time_s;
            if let Some(m) = &r.metrics {
                b.render_s += m.total_ms / 1e3;
                b.twins_s += m.twins_ms / 1e3;
                b.judge_s += m.judge_ms / 1e3;
                b.golden_s += m.golden_ms / 1e3;
            }
        }
        b.other_s = (b.runs_s - b.render_s - b.twins_s - b.judge_s - b.golden_s).max(0.0);
        b
    }

    /// Worker start, context creation, judging and PNG encoding, as a share of all worker time.
    pub fn overhead_share(&self) -> f64 {
        let total = self.runs_s + self.worker_start_s;
        if total == 0.0 {
            0.0
        } else {
            (self.worker_start_s + self.judge_s + self.golden_s) / total
        }
    }

    /// One line for the terminal and the report.
    pub fn line(&self) -> String {
        let total = (self.runs_s + self.worker_start_s).max(1e-9);
        let pct = |x: f64| 100.0 * x / total;
        format!(
            "time: {:.1} s of worker time in {:.1} s wall: rendering {:.1} s ({:.0}%), twins {:.1} s ({:.0}%), judging {:.1} s ({:.0}%), goldens/PNG {:.1} s ({:.0}%), worker start {:.1} s ({:.0}%, context creation {:.1} s), other {:.1} s ({:.0}%); harness overhead (start, context, judging, PNG) {:.0}%",
            total,
            self.wall_s,
            self.render_s,
            pct(self.render_s),
            self.twins_s,
            pct(self.twins_s),
            self.judge_s,
            pct(self.judge_s),
            self.golden_s,
            pct(self.golden_s),
            self.worker_start_s,
            pct(self.worker_start_s),
            self.context_s,
            self.other_s,
            pct(self.other_s),
            100.0 * self.overhead_share()
        )
    }
}

/// One planned run.
#[derive(Clone, Debug)]
struct Planned {
    backend: String,
    file: PathBuf,
    index: usize,
    id: String,
    values: SweepValues,
}

impl Planned {
    fn name(&self) -> String {
        format!("{}/{}", self.backend, self.id)
    }
}

/// One finished run, as reported.
#[derive(Clone, Debug, Serialize)]
pub struct RunResult {
    /// `backend/case@sweep`.
    pub name: String,
    /// The backend id.
    pub backend: String,
    /// The case point id.
    pub case: String,
    /// The case file.
    pub file: String,
    /// The point's swept values, `(path, value)` in axis order.
    pub values: Vec<(String, serde_json::Value)>,
    /// Final status.
    pub status: Status,
    /// Why (failure problems, skip reason, crash status, expectation reason).
    pub reason: String,
    /// Figures of the judged run, when it was judged.
    pub metrics: Option<Metrics>,
    /// The checks a failing run failed (its signature).
    pub failed: Vec<crate::run::FailedCheck>,
    /// What became of its golden: `unchanged`, `written`, `changed`, or
    /// `changed-other-driver` (differs, and was blessed on another Mesa version: failed, with both versions named).
    pub golden: Option<String>,
    /// Wall time of the run including retries, seconds.
    pub time_s: f64,
    /// The command that reproduces this run alone.
    pub reproduce: String,
    #[serde(skip)]
    details: String,
}

struct Settings {
    /// Directory of the shared judging basis ([`crate::judge_cache`]).
    judge_cache: String,
    timeout: Duration,
    golden: Option<PathBuf>,
    failures: PathBuf,
    expectations: Expectations,
    verbose: bool,
}

/// Runs the command; returns the process exit code.
pub fn main(argv: &[String]) -> i32 {
    let args = match Args::parse(
        argv,
        &[
            "cases",
            "filter",
            "backend",
            "out",
            "shard",
            "jobs",
            "timeout",
            "expectations",
            "golden",
            "mesa",
            "max-memory",
        ],
        &["verbose"],
    ) {
        Ok(a) => a,
        Err(e) => return usage(&e),
    };
    let build = match crate::mesa_build::select(args.value("mesa")) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            return 125;
        }
    };
    let cases_dir = PathBuf::from(args.value("cases").unwrap_or("cases"));
    let out = PathBuf::from(args.value("out").unwrap_or("target/umbra"));
    let filter = args.value("filter").unwrap_or("*").to_string();
    let backends =
        match crate::registry::selected(&args.values("backend"), crate::registry::known()) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("error: {e}");
                return 125;
            }
        };
    let shard = match args.value("shard").map(parse_shard).transpose() {
        Ok(s) => s.unwrap_or((0, 1)),
        Err(e) => return usage(&e),
    };
    let jobs = match args.value("jobs").map(str::parse::<usize>).transpose() {
        Ok(j) => j
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
            .max(1),
        Err(_) => return usage("--jobs takes a positive number"),
    };
    let timeout = match args.value("timeout").map(str::parse::<u64>).transpose() {
        Ok(t) => Duration::from_secs(t.unwrap_or(300)),
        Err(_) => return usage("--timeout takes whole seconds"),
    };
    if let Err(e) = crate::memory_limit::select(args.value("max-memory"), jobs) {
        return usage(&e);
    }
    let expectations = match Expectations::load(Path::new(
        args.value("expectations").unwrap_or("expectations"),
    )) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return 125;
        }
    };
    let files = match umbra_case::case_files(&cases_dir) {
        Ok(f) if !f.is_empty() => f,
        Ok(_) => {
            eprintln!("error: no *.json case under {}", cases_dir.display());
            return 125;
        }
        Err(e) => {
            eprintln!("error: cannot read {}: {e}", cases_dir.display());
            return 125;
        }
    };

    // Plan.
    let mut results: Vec<RunResult> = Vec::new();
    let mut points: Vec<(PathBuf, Vec<(String, SweepValues)>)> = Vec::new();
    let mut monotone: Vec<Monotone> = Vec::new();
    for f in &files {
        match umbra_case::load_file(f) {
            Ok(p) => {
                monotone.extend(Monotone::of(&p));
                points.push((
                    f.clone(),
                    p.iter().map(|p| (p.id(), p.values.clone())).collect(),
                ));
            }
            Err(e) => results.push(RunResult {
                name: format!("cases/{}", f.display()),
                backend: String::new(),
                case: f.display().to_string(),
                file: f.display().to_string(),
                values: Vec::new(),
                status: Status::Fail,
                reason: e.to_string(),
                metrics: None,
                failed: Vec::new(),
                golden: None,
                time_s: 0.0,
                reproduce: format!("cargo run --bin umbra -- render {}", f.display()),
                details: String::new(),
            }),
        }
    }
    let mut plan = Vec::new();
    for b in &backends {
        for (file, ids) in &points {
            for (index, (id, values)) in ids.iter().enumerate() {
                let p = Planned {
                    backend: b.clone(),
                    file: file.clone(),
                    index,
                    id: id.clone(),
                    values: values.clone(),
                };
                if crate::glob::matches(&filter, id) || crate::glob::matches(&filter, &p.name()) {
                    plan.push(p);
                }
            }
        }
    }
    let plan: Vec<Planned> = plan
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % shard.1 == shard.0)
        .map(|(_, p)| p)
        .collect();
    if plan.is_empty() && results.is_empty() {
        eprintln!(
            "error: --filter {filter:?} (shard {}/{}) selects no run",
            shard.0, shard.1
        );
        return 125;
    }

    // Execute.
    let started = Instant::now();
    let golden = match args.value("golden") {
        Some("none") => None,
        Some(dir) => Some(PathBuf::from(dir)),
        None => Some(PathBuf::from("golden")),
    };
    // Absolute, because workers may run with another working directory one day.
    let golden = golden.map(|g| std::fs::canonicalize(&g).unwrap_or(g));
    // The judging basis (truth and reference) of each point, shared by every backend's worker
    // through the cache; emptied so that nothing from an older build is read.
    let judge_cache = std::fs::canonicalize(&out)
        .unwrap_or(out.clone())
        .join("cache")
        .join("judge");
    let _ = std::fs::remove_dir_all(&judge_cache);
    let judge_cache = judge_cache.to_string_lossy().into_owned();
    let settings = Settings {
        judge_cache,
        timeout,
        golden,
        failures: out.join("latest").join("failures"),
        expectations,
        verbose: args.has("verbose"),
    };
    let _ = std::fs::remove_dir_all(&settings.failures);
    let mut groups: BTreeMap<String, Vec<Planned>> = BTreeMap::new();
    for p in plan {
        groups.entry(p.backend.clone()).or_default().push(p);
    }
    let total = groups.values().map(Vec::len).sum::<usize>();
    let queue = Mutex::new(groups.into_iter().collect::<VecDeque<_>>());
    let done = Mutex::new(Collected {
        results,
        progress: crate::progress::Progress::new(total),
        ..Default::default()
    });
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                // Take the next group in a function of its own, so the queue's lock is released
                // before the group runs (a `while let` on the lock would hold it throughout).
                let next = || queue.lock().ok().and_then(|mut q| q.pop_front());
                while let Some((backend, runs)) = next() {
                    run_group(&backend, runs, &settings, &done, total);
                }
            });
        }
    });
    let Collected {
        mut results,
        drivers,
        mut driver_rows,
        refused,
        unavailable_runs,
        progress,
        ..
    } = match done.into_inner() {
        Ok(d) => d,
        Err(_) => {
            eprintln!("error: a worker thread panicked");
            return 125;
        }
    };
    progress.close();
    driver_rows.sort_by(|a, b| a["backend"].as_str().cmp(&b["backend"].as_str()));
    let drivers = format!(
        "Mesa: {}\n{drivers}",
        build.map_or("the system's".to_string(), |b| b.describe())
    );
    results.sort_by(|a, b| a.name.cmp(&b.name));
    for m in &monotone {
        m.judge(&mut results);
    }

    // Report.
    let budget = TimeBudget::of(&results, started.elapsed());
    let header = serde_json::json!({
        "mesa_build": build,
        "drivers": driver_rows,
    });
    if let Err(e) = write_reports(&out, &results, &drivers, &header, &budget) {
        eprintln!("error: cannot write reports under {}: {e}", out.display());
        return 125;
    }
    let count = |name: &str| results.iter().filter(|r| r.status.name() == name).count();
    let regressions: Vec<&RunResult> = results
        .iter()
        .filter(|r| r.status.is_regression())
        .collect();
    println!(
        "\n{} runs in {:.1} s; reports in {}",
        results.len(),
        started.elapsed().as_secs_f64(),
        out.join("latest").display()
    );
    for r in &regressions {
        println!(
            "  regression: {} {}: {}",
            r.status,
            r.name,
            first_line(&r.reason)
        );
    }
    let passed = count("Pass") + count("ExpectedFail") + count("Flake");
    println!("{}", budget.line());
    if let Some((median, max, above, runs)) = crate::html::blind_stats(&results) {
        println!(
            "check strength: blind area median {:.3}%, max {:.2}%, {above} of {runs} judged runs above {:.0}% (report.html, Check strength)",
            100.0 * median,
            100.0 * max,
            100.0 * crate::html::BLIND_FLAG
        );
    }
    println!("statuses: {}", breakdown(&results));
    let foreign = results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("changed-other-driver"))
        .count();
    if foreign > 0 {
        println!(
            "goldens: {foreign} differ and were blessed on another driver version (golden/{}); each run's reason names both versions",
            crate::golden::MANIFEST
        );
    }
    // Blessing (`cargo xtask bless`): record the driver each backend's goldens now match.
    if std::env::var("INSTA_UPDATE").is_ok_and(|v| v == "always") {
        if let Some(dir) = &settings.golden {
            let version_of = |b: &str| {
                driver_rows
                    .iter()
                    .find(|r| r["backend"].as_str() == Some(b))
                    .and_then(|r| r["mesa"].as_str())
                    .map(str::to_string)
            };
            // Each backend (kept if already recorded), then each golden written now.
            let mut entries: Vec<(String, String)> = Vec::new();
            for r in &results {
                let Some(v) = version_of(&r.backend) else {
                    continue;
                };
                if r.golden.is_some() && !entries.iter().any(|(k, _)| *k == r.backend) {
                    entries.push((r.backend.clone(), v.clone()));
                }
                // A golden gets its own entry only where its version differs from what the
                // manifest already says for it (its backend's, usually).
                if r.golden.as_deref() == Some("written")
                    && crate::golden::blessed_on(dir, &r.backend, &r.name).as_deref()
                        != Some(v.as_str())
                {
                    entries.push((crate::golden::stem(&r.name), v));
                }
            }
            if entries.is_empty() {
                // Nothing Mesa-backed was blessed: the manifest stays as it is.
            } else if let Err(e) = crate::golden::record_blessed(dir, &entries) {
                eprintln!(
                    "error: cannot record the blessed drivers in {}: {e}",
                    dir.display()
                );
            }
        }
    }
    // The closing line, alone, in the form CI tools read.
    println!(
        "conformance: {passed} passed, {} failed, {} skipped",
        regressions.len(),
        count("Skip")
    );
    if !refused.is_empty() {
        for r in &refused {
            eprintln!("error: {r}");
        }
        eprintln!(
            "error: {} backend(s) did not run on the Mesa build asked for; their runs were not judged",
            refused.len()
        );
        125
    } else if !regressions.is_empty() {
        1
    } else if unavailable_runs == results.len() && !results.is_empty() {
        eprintln!("error: no selected backend is available here, nothing ran");
        125
    } else {
        0
    }
}

/// A case's `expect.error_falls_along`: runs of one backend that differ only in that axis,
/// in sweep order, whose error against the truth must not rise.
struct Monotone {
    path: String,
    /// Per series (the other axes' values): the point ids in the axis's order.
    series: Vec<Vec<String>>,
}

impl Monotone {
    fn of(points: &[umbra_case::CasePoint]) -> Option<Monotone> {
        let path = points.first()?.case.expect.error_falls_along.clone()?;
        let mut series: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for p in points {
            let others: Vec<String> = p
                .values
                .iter()
                .filter(|(k, _)| *k != path)
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            series.entry(others.join(",")).or_default().push(p.id());
        }
        Some(Monotone {
            path,
            series: series.into_values().collect(),
        })
    }

    /// Fails every judged run whose error exceeds its predecessor's on the same backend.
    fn judge(&self, results: &mut [RunResult]) {
        let error = |m: &Metrics| m.false_shadow + m.false_light;
        let mut backends: Vec<String> = results.iter().map(|r| r.backend.clone()).collect();
        backends.sort();
        backends.dedup();
        for backend in &backends {
            for ids in &self.series {
                let mut previous: Option<(String, u64)> = None;
                for id in ids {
                    let Some(r) = results
                        .iter_mut()
                        .find(|r| &r.backend == backend && &r.case == id)
                    else {
                        continue;
                    };
                    let Some(e) = r.metrics.as_ref().map(error) else {
                        continue;
                    };
                    if let Some((prev_id, prev)) = &previous {
                        if e > *prev && !r.status.is_regression() {
                            r.status = Status::Fail;
                            r.failed.push(crate::run::FailedCheck {
                                check: "falls-along".into(),
                                count: 1,
                            });
                            r.reason = format!(
                                "expect.error_falls_along {}: the error against the truth rose to {e} px from {prev} px at {prev_id}",
                                self.path
                            );
                        }
                    }
                    previous = Some((id.clone(), e));
                }
            }
        }
    }
}

/// How many runs ended in each status, in one line (the terminal summary and report.html).
pub fn breakdown(results: &[RunResult]) -> String {
    let count = |n: &str| results.iter().filter(|r| r.status.name() == n).count();
    format!(
        "pass {}, expected fail {}, flake {}, skip {}; fail {}, crash {}, timeout {}, unexpected pass {}",
        count("Pass"),
        count("ExpectedFail"),
        count("Flake"),
        count("Skip"),
        count("Fail"),
        count("Crash"),
        count("Timeout"),
        count("UnexpectedPass"),
    )
}

fn usage(msg: &str) -> i32 {
    eprintln!("error: {msg}\nusage: {USAGE}");
    125
}

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("--shard takes I/N with 0 ≤ I < N, got {s:?}");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (i.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or("")
}

/// What the backend groups collect while they run.
#[derive(Default)]
struct Collected {
    results: Vec<RunResult>,
    /// drivers.txt: one line per backend.
    drivers: String,
    /// report.json's `drivers`: per backend, the driver, the build and the expectation files
    /// that applied.
    driver_rows: Vec<serde_json::Value>,
    /// Backends whose worker refused the Mesa build (fell back, or its driver did not load).
    refused: Vec<String>,
    unavailable_runs: usize,
    finished: usize,
    /// What the terminal shows while the run goes on.
    progress: crate::progress::Progress,
}

type Done = Mutex<Collected>;

/// Runs one backend's runs in its workers.
fn run_group(backend: &str, runs: Vec<Planned>, settings: &Settings, done: &Done, total: usize) {
    let mut env = crate::registry::worker_env(backend);
    if crate::fake::enabled() {
        env.push(("UMBRA_FAKE_BACKENDS".into(), "1".into()));
    }
    env.push((crate::judge_cache::ENV.into(), settings.judge_cache.clone()));
    let start_worker = || {
        let t = Instant::now();
        let w = Worker::start(backend, &env, settings.timeout);
        WORKER_START_US.fetch_add(t.elapsed().as_micros() as u64, Ordering::Relaxed);
        if let Some(ms) = w
            .as_ref()
            .ok()
            .and_then(|w| w.hello["ready"]["create_ms"].as_f64())
        {
            CONTEXT_US.fetch_add((ms * 1e3) as u64, Ordering::Relaxed);
        }
        w
    };
    let mut worker = start_worker();
    // A worker that cannot even be started (our own binary missing or replaced mid-run) is
    // the harness's failure, not the backend's: its runs crash rather than skip, so that it
    // can never read as a clean run.
    let (hello, start_error) = match &worker {
        Ok(w) => (w.hello.clone(), None),
        Err(e) => (serde_json::json!({ "unavailable": e }), Some(e.clone())),
    };
    let refused = hello
        .get("refused")
        .and_then(|u| u.as_str())
        .map(str::to_string);
    // Expectations for this backend's driver (`@applies`), and which files they come from.
    let facts = crate::status::DriverFacts::from_hello(&hello["ready"]);
    let expectations = settings.expectations.for_driver(&facts);
    let files: Vec<String> = expectations
        .files()
        .iter()
        .map(|(f, n)| format!("{f} ({n})"))
        .collect();
    let build = hello["ready"]["build"].as_str().map(str::to_string);
    let driver_line = match (hello.get("ready"), hello.get("unavailable")) {
        (Some(r), _) => format!(
            "{backend}: {} | {} | {} | {}\n",
            r["vendor"].as_str().unwrap_or(""),
            r["renderer"].as_str().unwrap_or(""),
            r["version"].as_str().unwrap_or(""),
            r["extensions"]
                .as_array()
                .map(|v| v
                    .iter()
                    .filter_map(|x| x.as_str())
                    .collect::<Vec<_>>()
                    .join(" "))
                .unwrap_or_default()
        ),
        (_, Some(u)) => format!("{backend}: unavailable: {}\n", u.as_str().unwrap_or("")),
        _ => match &refused {
            Some(why) => format!("{backend}: refused: {why}\n"),
            None => format!("{backend}: said {hello}\n"),
        },
    };
    let driver_line = format!(
        "{}{}",
        driver_line,
        match (&build, files.is_empty()) {
            (Some(b), _) => format!("  build: {b}; expectations: {}\n", files.join(", ")),
            (None, false) => format!("  expectations: {}\n", files.join(", ")),
            (None, true) => String::new(),
        }
    );
    let row = serde_json::json!({
        "backend": backend,
        "vendor": hello["ready"]["vendor"],
        "renderer": hello["ready"]["renderer"],
        "version": hello["ready"]["version"],
        "mesa": facts.mesa,
        "build": build,
        "unavailable": hello.get("unavailable"),
        "refused": refused,
        "expectations": files,
    });
    let unavailable = hello
        .get("unavailable")
        .and_then(|u| u.as_str())
        .map(str::to_string);
    if let Ok(mut d) = done.lock() {
        d.drivers.push_str(&driver_line);
        d.driver_rows.push(row);
        if let Some(why) = &refused {
            d.refused.push(format!("{backend}: {why}"));
        }
    }
    for p in runs {
        let name = p.name();
        let t0 = Instant::now();
        let outcome = match (&start_error, &unavailable) {
            _ if refused.is_some() => Attempt::bare(
                Status::Crash,
                format!(
                    "not run: the worker refused the Mesa build: {}",
                    refused.as_deref().unwrap_or("")
                ),
            ),
            (Some(e), _) => Attempt::bare(
                Status::Crash,
                format!("the harness could not start its worker process: {e}"),
            ),
            (None, Some(why)) => Attempt::bare(Status::Skip(why.clone()), why.clone()),
            (None, None) => {
                let req = Request {
                    file: p.file.clone(),
                    index: p.index,
                    failures: Some(settings.failures.clone()),
                    golden: settings.golden.clone(),
                    repeat: None,
                    no_twins: false,
                };
                let first = attempt(&mut worker, &start_worker, &req, settings.timeout);
                if first.status.is_failure() {
                    // Rerun once: a different answer is a flake.
                    let second = attempt(&mut worker, &start_worker, &req, settings.timeout);
                    if second.status == Status::Pass {
                        let why = format!(
                            "failed first ({}: {}), passed on rerun",
                            first.status, first.reason
                        );
                        Attempt {
                            status: Status::Flake,
                            reason: why,
                            ..second
                        }
                    } else {
                        first
                    }
                } else {
                    first
                }
            }
        };
        let Attempt {
            status: raw,
            reason,
            metrics,
            details,
            failed,
            golden,
        } = outcome;
        let (status, expected) = expectations.apply(&name, raw, &failed);
        let reason = match (&status, expected) {
            (Status::ExpectedFail | Status::UnexpectedPass, Some(why)) => {
                format!("expected: {why}; got: {reason}")
            }
            (_, Some(why)) => format!("{reason} (expectation: {why})"),
            (_, None) => reason,
        };
        let result = RunResult {
            name: name.clone(),
            backend: p.backend.clone(),
            case: p.id.clone(),
            file: p.file.display().to_string(),
            values: p.values.clone(),
            status,
            reason,
            metrics,
            failed,
            golden,
            time_s: t0.elapsed().as_secs_f64(),
            reproduce: format!(
                "cargo run --bin umbra -- render {} --backend {} --point '{}'",
                p.file.display(),
                p.backend,
                p.id
            ),
            details,
        };
        if let Ok(mut d) = done.lock() {
            d.finished += 1;
            let r = &result;
            let mut line = format!(
                "[{}/{total}] {} {} ({:.0} ms)",
                d.finished,
                r.status,
                r.name,
                r.time_s * 1e3
            );
            if !matches!(r.status, Status::Pass) && !r.reason.is_empty() {
                let _ = write!(line, ": {}", first_line(&r.reason));
            }
            let status = r.status.name();
            d.progress.finished(status, &line);
            if settings.verbose && !r.details.is_empty() {
                println!("{}", r.details);
            }
            if unavailable.is_some() && start_error.is_none() {
                d.unavailable_runs += 1;
            }
            d.results.push(result);
        }
    }
}

/// What one attempt at a run gave.
struct Attempt {
    status: Status,
    reason: String,
    metrics: Option<Metrics>,
    details: String,
    failed: Vec<crate::run::FailedCheck>,
    golden: Option<String>,
}

impl Attempt {
    fn bare(status: Status, reason: String) -> Attempt {
        Attempt {
            status,
            reason,
            metrics: None,
            details: String::new(),
            failed: Vec::new(),
            golden: None,
        }
    }
}

/// One attempt at a run, restarting the worker first if the last one died.
fn attempt(
    worker: &mut Result<Worker, String>,
    start: &dyn Fn() -> Result<Worker, String>,
    req: &Request,
    limit: Duration,
) -> Attempt {
    if worker.is_err() {
        *worker = start();
    }
    let w = match worker {
        Ok(w) => w,
        Err(e) => return Attempt::bare(Status::Crash, format!("no worker: {e}")),
    };
    match w.run(req, limit) {
        Reply::Report(r) => from_report(*r),
        Reply::Crashed(how) => {
            *worker = Err(how.clone());
            Attempt::bare(Status::Crash, format!("the worker died: {how}"))
        }
        Reply::TimedOut => {
            *worker = Err("timed out".into());
            Attempt::bare(
                Status::Timeout,
                format!(
                    "no answer within {} s; the worker was killed",
                    limit.as_secs()
                ),
            )
        }
    }
}

fn from_report(r: RunReport) -> Attempt {
    let status = match r.outcome.as_str() {
        "pass" => Status::Pass,
        "skip" => Status::Skip(r.reason.clone()),
        _ => Status::Fail,
    };
    let mut reason = r.reason;
    if status == Status::Fail && !r.failed.is_empty() {
        let _ = write!(reason, " [failed: {}]", crate::status::signature(&r.failed));
    }
    Attempt {
        status,
        reason,
        metrics: r.metrics,
        details: r.details,
        failed: r.failed,
        golden: r.golden,
    }
}

fn opt(v: Option<u64>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

fn write_reports(
    out: &Path,
    results: &[RunResult],
    drivers: &str,
    header: &serde_json::Value,
    budget: &TimeBudget,
) -> std::io::Result<()> {
    let wall = Duration::from_secs_f64(budget.wall_s);
    let mut csv = String::new();
    let mut failures = String::new();
    let mut errors = String::from(
        "test,status,judged,false_shadow,false_light,interior_judged,interior_false_shadow,interior_false_light,edge_px,silhouette,faces_away,outside,agreement,illegal,compared,blind,blind_pct,value_checked,value_margin,illegal_value,illegal_nan,illegal_coverage,illegal_colour,profile,shadow_ms,lit_ms,total_ms,clock\n",
    );
    let mut twins = String::from(
        "test,twin,agree,skipped,differ,legal_tie,legal_coverage,legal_texel,legal_filter,legal_position,legal_surface,blind,illegal,illegal_value,illegal_coverage,illegal_colour,interior_error,twin_interior_error,render_ms,ok\n",
    );
    for r in results {
        for t in r.metrics.iter().flat_map(|m| &m.twins) {
            let _ = writeln!(
                twins,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{}",
                csv_field(&r.name),
                t.name,
                t.agree,
                t.skipped.is_some(),
                t.pair.differ,
                t.pair.legal_tie,
                t.pair.legal_coverage,
                t.pair.legal_texel,
                t.pair.legal_filter,
                t.pair.legal_position,
                t.pair.legal_surface,
                t.pair.blind,
                t.pair.illegal,
                t.pair.illegal_value,
                t.pair.illegal_coverage,
                t.pair.illegal_colour,
                t.interior_error,
                t.twin_interior_error
                    .map(|e| e.to_string())
                    .unwrap_or_default(),
                t.render_ms,
                t.ok
            );
        }
    }
    for r in results {
        let _ = writeln!(csv, "{},{},{:.3}", csv_field(&r.name), r.status, r.time_s);
        if r.status.is_regression() {
            let _ = writeln!(failures, "{},{}", csv_field(&r.name), r.status);
        }
        if let Some(m) = &r.metrics {
            let _ = writeln!(
                errors,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{}",
                csv_field(&r.name),
                r.status,
                m.judged,
                m.false_shadow,
                m.false_light,
                m.interior_judged,
                m.interior_false_shadow,
                m.interior_false_light,
                m.edge_px,
                m.silhouette,
                m.faces_away,
                m.outside,
                m.agreement.map(|a| format!("{a:.6}")).unwrap_or_default(),
                m.illegal.map(|a| a.to_string()).unwrap_or_default(),
                opt(m.reference.as_ref().map(|a| a.compared)),
                opt(m.reference.as_ref().map(|a| a.blind)),
                m.reference
                    .as_ref()
                    .map(|a| format!("{:.4}", 100.0 * a.blind_share()))
                    .unwrap_or_default(),
                opt(m.reference.as_ref().map(|a| a.value_checked)),
                m.reference
                    .as_ref()
                    .and_then(|a| a.value_margin)
                    .map(|v| format!("{v:.5}"))
                    .unwrap_or_default(),
                opt(m.reference.as_ref().map(|a| a.illegal_value)),
                opt(m.reference.as_ref().map(|a| a.illegal_nan)),
                opt(m.reference.as_ref().map(|a| a.illegal_coverage)),
                opt(m.reference.as_ref().map(|a| a.illegal_colour)),
                m.profile,
                m.shadow_ms,
                m.lit_ms,
                m.total_ms,
                m.clock
            );
        }
    }
    // Per run, the fields the README's schema promises at top level, then everything else.
    let runs: Vec<serde_json::Value> = results
        .iter()
        .map(|r| {
            let m = r.metrics.as_ref();
            let rate = |n: fn(&Metrics) -> u64| {
                m.map(|m| {
                    if m.judged == 0 {
                        0.0
                    } else {
                        n(m) as f64 / m.judged as f64
                    }
                })
            };
            serde_json::json!({
                "case": r.case,
                "file": r.file,
                "backend": r.backend,
                "golden": r.golden,
                "status": r.status.name(),
                "reason": r.reason,
                "false_shadow": rate(|m| m.false_shadow),
                "false_light": rate(|m| m.false_light),
                "agreement": m.and_then(|m| m.agreement),
                "ssim": m.and_then(|m| m.ssim),
                "ssim_golden": m.and_then(|m| m.ssim_golden),
                "time_ms": r.time_s * 1e3,
                "name": r.name,
                "metrics": r.metrics,
                "failed": r.failed,
                "reproduce": r.reproduce,
            })
        })
        .collect();
    let report = serde_json::json!({
        "schema": 1,
        "wall_s": wall.as_secs_f64(),
        "time_budget": budget,
        "harness_overhead_share": budget.overhead_share(),
        "command": std::env::args().collect::<Vec<_>>().join(" "),
        "mesa_build": header["mesa_build"],
        "drivers": header["drivers"],
        "runs": runs,
    });
    let junit = junit(results);
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let html = crate::html::report(
        results,
        drivers,
        &out.join("latest").join("failures"),
        &command,
        wall.as_secs_f64(),
        &budget.line(),
    );
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    for dir in [out.join("latest"), out.join("runs").join(stamp.to_string())] {
        std::fs::create_dir_all(&dir)?;
        std::fs::write(dir.join("results.csv"), &csv)?;
        std::fs::write(dir.join("failures.csv"), &failures)?;
        std::fs::write(dir.join("errors.csv"), &errors)?;
        std::fs::write(dir.join("twins.csv"), &twins)?;
        std::fs::write(dir.join("drivers.txt"), drivers)?;
        std::fs::write(
            dir.join("report.json"),
            serde_json::to_string_pretty(&report).unwrap_or_default(),
        )?;
        std::fs::write(dir.join("junit.xml"), &junit)?;
        std::fs::write(dir.join("report.html"), &html)?;
    }
    Ok(())
}

/// A CSV field, quoted (RFC 4180) when it holds a comma, a quote or a line break: point ids
/// of multi-axis sweeps hold commas.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn junit(results: &[RunResult]) -> String {
    let failures = results.iter().filter(|r| r.status.is_regression()).count();
    let skipped = results
        .iter()
        .filter(|r| matches!(r.status, Status::Skip(_)))
        .count();
    let time: f64 = results.iter().map(|r| r.time_s).sum();
    let mut s = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n<testsuite name=\"umbra conformance\" tests=\"{}\" failures=\"{failures}\" skipped=\"{skipped}\" time=\"{time:.3}\">\n",
        results.len()
    );
    for r in results {
        let _ = write!(
            s,
            "  <testcase classname=\"{}\" name=\"{}\" time=\"{:.3}\">",
            xml(&r.backend),
            xml(&r.case),
            r.time_s
        );
        match &r.status {
            st if st.is_regression() => {
                let _ = write!(
                    s,
                    "<failure type=\"{}\" message=\"{}\">{}</failure>",
                    st,
                    xml(first_line(&r.reason)),
                    xml(&r.reproduce)
                );
            }
            Status::Skip(why) => {
                let _ = write!(s, "<skipped message=\"{}\"/>", xml(why));
            }
            _ => {}
        }
        s.push_str("</testcase>\n");
    }
    s.push_str("</testsuite>\n</testsuites>\n");
    s
}
