//! `umbra conformance`: every case point on every selected backend, each backend in worker
//! processes of its own ([`crate::harness::pool`]), judged, with expectations applied, and reported.
//!
//! - Plan: case points (`cases/**/*.json`, `--filter GLOB` on the point id or the full run
//!   name `backend/id`) × backends (`--backend ID`, default every known one), in a fixed
//!   order; `--shard I/N` keeps every N-th run starting at I (0-based), as deqp-runner's
//!   fractions do, so N CI jobs split a run deterministically.
//! - Execution: `--jobs` threads (default: the core count), each driving one worker process
//!   at a time and taking runs one by one; a thread whose backend has no runs left moves to
//!   the backend with the most left, sharing it once all are taken ([`crate::harness::scheduler::run_queues`]). A
//!   worker that dies costs its run (Crash), one that exceeds `--timeout` seconds costs its run
//!   (Timeout); a fresh worker takes the rest. Every failure is rerun once; a changed result
//!   is a Flake.
//! - Statuses and expectations: [`crate::judge::expectations`]. A case file that cannot be loaded fails the
//!   run under its own name.
//! - Reports in the run's own directory `OUT/runs/ID/` ([`crate::run_dir`]), shown by the link
//!   `OUT/latest` once complete: `results.csv` and `failures.csv` (deqp-runner's formats),
//!   `junit.xml`, `report.json`, `report.html` (self-contained), `errors.csv`, `drivers.txt`,
//!   the pictures of each failure under `failures/` and the gallery's under `pictures/`. An
//!   interrupted run (SIGINT, SIGTERM: [`crate::harness::interrupt`]) or one that cannot
//!   write its reports is not published and exits 130 ([`Exit::Interrupted`]) or 125,
//!   saying where it left what.
//! - Exit codes ([`Exit`]): 0 all as expected, 1 a regression (Fail, Crash, Timeout,
//!   UnexpectedPass), 125 nothing could run (no case, no available backend, bad arguments or
//!   expectations), so `git bisect run cargo xtask conformance --filter X` works.

use std::collections::{BTreeMap, VecDeque};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use crate::cli::ConformanceArgs;
use crate::exit::{Error, Exit, Outcome};
use crate::harness::scheduler::{Attempt, NotReady, Session};
use crate::harness::worker::{Hello, Request};
use crate::judge::expectations::Expectations;
use crate::judge::falls_along::FallsAlong;
use crate::run_dir::RunDir;
use umbra_report::escape::{shell_word, term};
use umbra_report::{RunResult, Status, TimeBudget};

/// A point's swept values, `(path, value)` in axis order.
type SweepValues = Vec<(String, serde_json::Value)>;

/// A loaded point: its id, its swept values and its case as JSON.
type PointPlan = (String, SweepValues, std::sync::Arc<serde_json::Value>);

/// One planned run.
#[derive(Clone, Debug)]
struct Planned {
    backend: String,
    file: PathBuf,
    index: usize,
    id: String,
    values: SweepValues,
    /// The point's case as JSON, defaults included: what expectations' `@when` conditions
    /// read (shared by the point's runs on every backend).
    case: std::sync::Arc<serde_json::Value>,
}

impl Planned {
    fn name(&self) -> String {
        format!("{}/{}", self.backend, self.id)
    }
}

struct Settings {
    /// Directory of the shared judging basis ([`crate::judge::judge_cache`]).
    judge_cache: String,
    timeout: Duration,
    golden: Option<PathBuf>,
    /// Backends with no goldens in `golden`: judged without a golden check.
    no_goldens: std::collections::BTreeSet<String>,
    failures: PathBuf,
    /// Every judged run's gallery pictures (report.html's gallery reads them).
    gallery: PathBuf,
    expectations: Expectations,
    verbose: bool,
    /// `--bless`: workers may write goldens.
    bless: bool,
    /// Check each backend's behaviour card against the one kept beside its goldens: a whole
    /// run (no `--filter`, no `--shard`) with goldens.
    cards: Option<PathBuf>,
    /// Judge every run against its backend's card too (calibrated judging; off with
    /// `--spec-only`).
    calibrate: bool,
    /// Each backend's live card, measured once for the card row and the calibration.
    live_cards: crate::commands::card::LiveCards,
}

/// Runs the command; returns its outcome.
pub fn main(args: &ConformanceArgs) -> Outcome {
    run(args).outcome
}

/// What a command built on a conformance run adds to its reports (`umbra soak`'s table),
/// written into the run's directory before it is published.
pub type Extra<'a> = &'a dyn Fn(&Path, &[RunResult]) -> std::io::Result<()>;

/// What a conformance run ended with: its outcome and every run's result (empty when it
/// could not start).
pub struct Finished {
    /// As expected, a regression, or why it could not run (or was interrupted).
    pub outcome: Outcome,
    /// Every run, sorted by name, with its final status.
    pub results: Vec<RunResult>,
}

impl From<Error> for Finished {
    fn from(e: Error) -> Finished {
        Finished {
            outcome: Err(e),
            results: Vec::new(),
        }
    }
}

/// Runs the conformance job as `main` does and returns its results too.
pub fn run(args: &ConformanceArgs) -> Finished {
    run_in(args, None, None)
}

/// [`run`] into `run_dir` when the caller made it (`umbra soak` writes its cases there
/// first), with `extra` reports. The steps, in order: read the options, plan the runs, settle
/// the goldens, execute the plan on the workers, gather what they found, write the reports,
/// print the summary, record blessings, and choose the outcome.
pub fn run_in(args: &ConformanceArgs, run_dir: Option<RunDir>, extra: Option<Extra>) -> Finished {
    crate::harness::interrupt::install();
    let mut opts = match Options::read(args) {
        Ok(o) => o,
        Err(e) => return e.into(),
    };
    // A caller with a run directory of its own runs cases it made (soak's generated ones),
    // which the catalogue's expectation lines do not name: none of them is stale there.
    opts.stale_check = run_dir.is_none();
    let planned = match plan_runs(&opts) {
        Ok(p) => p,
        Err(e) => return e.into(),
    };
    let no_goldens = match settle_goldens(&opts) {
        Ok(n) => n,
        Err(e) => return e.into(),
    };
    let run_dir = match run_dir.map_or_else(|| RunDir::create(&opts.out), Ok) {
        Ok(r) => r,
        Err(e) => {
            return Error::new(format!(
                "cannot create a run directory under {}: {e}; give --out a writable directory",
                opts.out.join("runs").display()
            ))
            .into();
        }
    };
    let started = Instant::now();
    let settings = settings(args, &opts, no_goldens, &run_dir);
    let Plan {
        results,
        falls_along,
        plan,
        names,
    } = planned;
    let collected = match execute(plan, results, &settings, opts.jobs) {
        Ok(c) => c,
        Err(e) => return e.into(),
    };
    let gathered = match gather(collected, &opts, &falls_along, &run_dir) {
        Ok(g) => g,
        Err(f) => return f,
    };
    let start_up = crate::harness::scheduler::start_up_time();
    let budget = TimeBudget::of(&gathered.results, started.elapsed(), start_up.0, start_up.1);
    let record = record(&opts, names, falls_along, &gathered, &budget);
    if let Err(e) = write_reports(&gathered, &settings, &budget, &run_dir, &record, extra) {
        return Finished {
            outcome: Err(e),
            results: gathered.results,
        };
    }
    let regressions = print_summary(
        &gathered.results,
        &budget,
        &opts.out,
        &run_dir,
        started.elapsed(),
    );
    if settings.bless {
        record_blessings(&gathered, &settings);
    }
    println!("{}", closing_line("conformance", &gathered.results));
    let outcome = outcome(
        &gathered.refused,
        gathered.unavailable_runs,
        gathered.results.len(),
        regressions,
    );
    Finished {
        outcome,
        results: gathered.results,
    }
}

/// What the command line asks for, checked: every bad value is a usage error (exit 125)
/// that names the flag and the fix.
struct Options {
    build: Option<&'static crate::harness::mesa_build::MesaBuild>,
    out: PathBuf,
    filter: String,
    backends: Vec<String>,
    shard: (usize, usize),
    /// How the plan is split over the shards (`--durations`).
    by: crate::shards::balance::By,
    /// Digests of the cases, expectations and goldens, for the run's record.
    inputs: crate::shards::record::Inputs,
    jobs: usize,
    timeout: Duration,
    golden: Option<PathBuf>,
    expectations: Expectations,
    files: Vec<PathBuf>,
    bless: bool,
    /// Whether expectation lines that match no loaded point are warned about.
    stale_check: bool,
}

impl Options {
    fn read(args: &ConformanceArgs) -> Result<Options, Error> {
        let fail = Error::new;
        let (selection, execution) = (&args.selection, &args.execution);
        let build = crate::harness::mesa_build::select(execution.mesa.as_deref()).map_err(fail)?;
        let named: Vec<&str> = selection.backend.iter().map(String::as_str).collect();
        let backends =
            crate::harness::registry::selected(&named, crate::harness::registry::known())
                .map_err(fail)?;
        let shard = args
            .shard
            .as_deref()
            .map(parse_shard)
            .transpose()
            .map_err(|e| crate::cli::usage_error("conformance", e))?
            .unwrap_or((0, 1));
        let (jobs, timeout) = crate::cli::limits("conformance", execution, 300)?;
        let golden = golden_dir(args.golden.as_deref())?;
        if let Some(warning) = golden
            .as_deref()
            .and_then(crate::judge::golden::check_manifest)
        {
            eprintln!("{}", term(&warning));
        }
        if let Some(dir) = golden.as_deref() {
            crate::judge::golden::check_confirmed(dir).map_err(fail)?;
        }
        let expectations_dir =
            Path::new(selection.expectations.as_deref().unwrap_or("expectations"));
        let expectations = Expectations::load(expectations_dir).map_err(fail)?;
        let by = match args.durations.as_deref() {
            None => crate::shards::balance::By::Stride,
            Some(_) if shard.1 == 1 => {
                return Err(crate::cli::usage_error(
                    "conformance",
                    "--durations balances shards: give it with --shard I/N (N > 1)",
                ));
            }
            Some(f) => crate::shards::balance::By::Durations(
                crate::shards::balance::Durations::read(Path::new(f))
                    .map_err(|e| crate::cli::usage_error("conformance", e))?,
            ),
        };
        let cases_dir = PathBuf::from(selection.cases.as_deref().unwrap_or("cases"));
        let out = PathBuf::from(args.output.out.as_deref().unwrap_or("target/umbra"));
        outside_cases(&out, &cases_dir).map_err(|e| {
            crate::cli::usage_error("conformance", format!("--out {}: {e}", out.display()))
        })?;
        let files = match umbra_case::case_files(&cases_dir) {
            Ok(f) if !f.is_empty() => f,
            Ok(_) => {
                return Err(fail(format!(
                    "no *.json case under {}",
                    cases_dir.display()
                )));
            }
            Err(e) => return Err(fail(format!("cannot read {}: {e}", cases_dir.display()))),
        };
        let digest = |d: &Path| {
            crate::shards::record::Digest::of(d)
                .map_err(|e| fail(format!("cannot read what the run's record names: {e}")))
        };
        let inputs = crate::shards::record::Inputs {
            cases: digest(&cases_dir)?,
            expectations: if expectations_dir.is_dir() {
                digest(expectations_dir)?
            } else {
                crate::shards::record::Digest {
                    dir: expectations_dir.display().to_string(),
                    files: 0,
                    digest: String::new(),
                }
            },
            golden: golden
                .as_deref()
                .map(|g| {
                    crate::shards::record::Digest::of_goldens(g)
                        .map_err(|e| fail(format!("cannot read what the run's record names: {e}")))
                })
                .transpose()?,
        };
        Ok(Options {
            build,
            out,
            filter: selection.filter.as_deref().unwrap_or("*").to_string(),
            backends,
            shard,
            by,
            inputs,
            jobs,
            timeout,
            golden,
            expectations,
            files,
            bless: args.bless,
            stale_check: true,
        })
    }
}

/// `--golden`: the golden directory (`golden` by default), or none (`--golden none`).
fn golden_dir(flag: Option<&str>) -> Result<Option<PathBuf>, Error> {
    Ok(match flag {
        Some("none") => None,
        Some(dir) if !Path::new(dir).is_dir() => {
            return Err(crate::cli::usage_error(
                "conformance",
                format!(
                    "--golden {dir}: no such directory; give the golden directory (golden/), or --golden none to run without golden checks"
                ),
            ));
        }
        Some(dir) => Some(PathBuf::from(dir)),
        None => Some(PathBuf::from("golden")),
    })
}

/// The runs to make: the case files that did not load (each a failed result already), the
/// `expect.error_falls_along` series, and this shard's runs.
struct Plan {
    results: Vec<RunResult>,
    falls_along: Vec<FallsAlong>,
    plan: Vec<Planned>,
    /// Every selected run's name before sharding, in plan order (the run's record).
    names: Vec<String>,
}

/// Loads every case file, plans every backend × point the filter selects, checks the
/// expectations against the plan, and keeps this shard's share.
fn plan_runs(opts: &Options) -> Result<Plan, Error> {
    let mut results: Vec<RunResult> = Vec::new();
    let mut points: Vec<(PathBuf, Vec<PointPlan>)> = Vec::new();
    let mut falls_along: Vec<FallsAlong> = Vec::new();
    for f in &opts.files {
        match umbra_case::load_file(f) {
            Ok(p) => {
                falls_along.extend(FallsAlong::of(&p));
                points.push((
                    f.clone(),
                    p.iter()
                        .map(|p| {
                            let case = umbra_case::schema::condition_json(&p.case);
                            (p.id(), p.values.clone(), std::sync::Arc::new(case))
                        })
                        .collect(),
                ));
            }
            Err(e) => results.push(unloadable(f, &e.to_string())),
        }
    }
    if let Some(e) = duplicate_names(&points) {
        return Err(crate::cli::usage_error("conformance", e));
    }
    let mut plan = Vec::new();
    for b in &opts.backends {
        for (file, ids) in &points {
            for (index, (id, values, case)) in ids.iter().enumerate() {
                let p = Planned {
                    backend: b.clone(),
                    file: file.clone(),
                    index,
                    id: id.clone(),
                    values: values.clone(),
                    case: case.clone(),
                };
                if crate::glob::matches(&opts.filter, id)
                    || crate::glob::matches(&opts.filter, &p.name())
                {
                    plan.push(p);
                }
            }
        }
    }
    validate_expectations(opts, &plan)?;
    if opts.stale_check {
        warn_stale_expectations(opts, &points);
    }
    let selected = plan.len();
    if selected == 0 && results.is_empty() {
        return Err(Error::new(format!(
            "--filter {:?} selects no run",
            opts.filter
        )));
    }
    let names: Vec<String> = plan.iter().map(Planned::name).collect();
    let (index, count) = opts.shard;
    let shard_of = crate::shards::balance::assign(&names, count, &opts.by);
    let plan: Vec<Planned> = plan
        .into_iter()
        .zip(&shard_of)
        .filter(|(_, s)| **s == index)
        .map(|(p, _)| p)
        .collect();
    if count > 1 {
        println!(
            "shard {index}/{count}: {} of the {selected} selected runs",
            plan.len()
        );
        if let crate::shards::balance::By::Durations(d) = &opts.by {
            println!("{}", crate::shards::balance::report(&names, count, d));
        }
    }
    if plan.is_empty() && results.is_empty() {
        // More shards than runs (a CI matrix sized for a larger plan): an empty shard is a
        // successful one, and leaves its (empty) reports and record for the merge.
        println!(
            "note: shard {index}/{count} holds none of the {selected} selected runs (there are more shards than runs); nothing to do"
        );
    }
    Ok(Plan {
        results,
        falls_along,
        plan,
        names,
    })
}

/// A case file that did not load, as a failed result naming the error.
fn unloadable(f: &Path, why: &str) -> RunResult {
    RunResult {
        name: format!("cases/{}", f.display()),
        backend: String::new(),
        case: f.display().to_string(),
        file: f.display().to_string(),
        values: Vec::new(),
        status: Status::Fail,
        reason: why.to_string(),
        metrics: None,
        failed: Vec::new(),
        golden: None,
        time_s: 0.0,
        reproduce: format!("cargo run --bin umbra -- render {}", f.display()),
        diagnosis: None,
        stderr: String::new(),
        fingerprint: None,
        details: String::new(),
    }
}

/// The expectations checked against the planned runs ([`Expectations::validate`]).
fn validate_expectations(opts: &Options, plan: &[Planned]) -> Result<(), Error> {
    let known = crate::harness::registry::known();
    let mut ids: Vec<&str> = known.iter().map(String::as_str).collect();
    ids.extend(opts.backends.iter().map(String::as_str));
    if crate::harness::fake::enabled() {
        ids.extend(crate::harness::fake::IDS);
    }
    let runs: Vec<(String, &serde_json::Value)> =
        plan.iter().map(|p| (p.name(), &*p.case)).collect();
    opts.expectations.validate(&ids, &runs).map_err(Error::new)
}

/// Says each expectation line that matches no run of every case point loaded on any of this
/// build's backends (whatever --filter, --backend and --shard select): stale or mistyped.
fn warn_stale_expectations(opts: &Options, points: &[(PathBuf, Vec<PointPlan>)]) {
    let known = crate::harness::registry::known();
    let ids: Vec<&str> = known.iter().map(String::as_str).collect();
    let all: Vec<(String, &serde_json::Value)> = points
        .iter()
        .flat_map(|(_, ids)| ids.iter().map(|(id, _, case)| (id.clone(), &**case)))
        .collect();
    // A line for a device this build does not list (gl33/radeonsi/*) is not stale here.
    let on_device = |e: &&crate::judge::expectations::Expectation| {
        let mut parts = e.pattern.splitn(3, '/');
        let backend = format!(
            "{}/{}",
            parts.next().unwrap_or(""),
            parts.next().unwrap_or("")
        );
        !backend.contains(['*', '?']) && crate::harness::registry::is_device_id(&backend)
    };
    for e in opts
        .expectations
        .stale(&ids, &all)
        .iter()
        .filter(|e| !on_device(e))
    {
        eprintln!(
            "warning: expectation {} ({}) matches no run of the {} case points loaded on any of this build's backends: stale (its case renamed or removed) or mistyped; it expects nothing",
            e.source,
            e.pattern,
            all.len()
        );
    }
}

/// Blessing's preconditions, and the backends judged without goldens: a device umbra has
/// never seen, without goldens, is judged by the specs and the reference; blessing starts
/// its goldens. This build's own ids always have goldens: a missing one (an empty or missing
/// golden directory included) is a change to review, never a check switched off.
fn settle_goldens(opts: &Options) -> Result<std::collections::BTreeSet<String>, Error> {
    if opts.bless && crate::judge::golden::under_ci() {
        return Err(crate::cli::usage_error(
            "conformance",
            "--bless: CI=true: goldens change only through review (`cargo xtask bless` or `cargo insta review` on a desk), never in CI",
        ));
    }
    if opts.bless && opts.golden.is_none() {
        return Err(crate::cli::usage_error(
            "conformance",
            "--bless with --golden none: there are no goldens to bless",
        ));
    }
    let no_goldens: std::collections::BTreeSet<String> = match (&opts.golden, opts.bless) {
        (Some(dir), false) => opts
            .backends
            .iter()
            .filter(|b| {
                crate::harness::registry::is_device_id(b)
                    && !crate::judge::golden::has_goldens(dir, b)
            })
            .cloned()
            .collect(),
        _ => Default::default(),
    };
    for b in &no_goldens {
        println!(
            "{b}: {} (`cargo xtask bless --backend {b}` starts them)",
            crate::judge::golden::NONE_FOR_BACKEND
        );
    }
    let inherited = crate::judge::golden::inherited_insta();
    if !inherited.is_empty() {
        eprintln!(
            "note: ignored {} from the environment: umbra sets insta's environment itself; goldens change only through `cargo xtask bless` or `cargo insta review`",
            term(&inherited.join(" "))
        );
    }
    Ok(no_goldens)
}

/// What every worker thread shares: the judging cache (prepared here: the judging basis of
/// each point, shared by every backend's worker and kept for the next run, see
/// judge_cache), the goldens (absolute, since workers may run with another working directory
/// one day), where pictures go, the expectations.
fn settings(
    args: &ConformanceArgs,
    opts: &Options,
    no_goldens: std::collections::BTreeSet<String>,
    run_dir: &RunDir,
) -> Settings {
    let judge_cache = crate::judge::judge_cache::prepare(
        &args
            .execution
            .judge_cache
            .as_deref()
            .map_or_else(|| opts.out.join("cache").join("judge"), PathBuf::from),
    );
    Settings {
        judge_cache: judge_cache.to_string_lossy().into_owned(),
        timeout: opts.timeout,
        golden: opts
            .golden
            .clone()
            .map(|g| std::fs::canonicalize(&g).unwrap_or(g)),
        no_goldens,
        failures: run_dir.dir.join("failures"),
        gallery: run_dir.dir.join("pictures"),
        expectations: opts.expectations.clone(),
        verbose: args.output.verbose,
        bless: opts.bless,
        cards: opts
            .golden
            .clone()
            .filter(|_| opts.filter == "*" && opts.shard.1 == 1),
        calibrate: !args.execution.spec_only,
        live_cards: Default::default(),
    }
}

/// Runs the plan: its runs grouped by backend, each backend's rotated by its share (so
/// concurrent workers rarely reach a point whose judging basis is not cached yet at the same
/// moment; the second would wait for the first, see judge_cache), `jobs` threads each working
/// on one backend at a time ([`crate::harness::scheduler::run_queues`], [`run_group`]).
fn execute(
    plan: Vec<Planned>,
    results: Vec<RunResult>,
    settings: &Settings,
    jobs: usize,
) -> Result<Collected, Error> {
    let mut groups: BTreeMap<String, VecDeque<Planned>> = BTreeMap::new();
    for p in plan {
        groups.entry(p.backend.clone()).or_default().push_back(p);
    }
    let cards = if settings.cards.is_some() {
        groups.len()
    } else {
        0
    };
    let total = groups.values().map(VecDeque::len).sum::<usize>() + cards;
    let n = groups.len().max(1);
    for (k, runs) in groups.values_mut().enumerate() {
        let offset = k * runs.len() / n;
        runs.rotate_left(offset);
    }
    let done = Mutex::new(Collected {
        results,
        progress: crate::harness::progress::Progress::new(total),
        total,
        ..Default::default()
    });
    crate::harness::scheduler::run_queues(groups, jobs, |backend, first, next| {
        run_group(backend, next, first, settings, &done, total)
    });
    done.into_inner()
        .map_err(|_| Error::new("a worker thread panicked"))
}

/// What the run found, put together: every result sorted by name and diagnosed (the
/// `expect.error_falls_along` series, the consensus), drivers.txt and report.json's driver rows.
struct Gathered {
    results: Vec<RunResult>,
    /// The results before the checks across runs (the run's record keeps them).
    before_cross: Vec<RunResult>,
    /// drivers.txt's lines of each backend, by backend.
    driver_lines: Vec<(String, String)>,
    driver_rows: Vec<serde_json::Value>,
    refused: Vec<String>,
    unavailable_runs: usize,
    build: Option<&'static crate::harness::mesa_build::MesaBuild>,
}

/// The verdicts of the runs that finished, for a run that will not be published
/// (interrupted, or a full disk): results.csv, failures.csv, errors.csv and junit.xml of those
/// runs, sorted by name, as far as they can be written. Their pictures are there already.
fn write_partial(dir: &Path, results: &mut [RunResult]) {
    results.sort_by(|a, b| a.name.cmp(&b.name));
    let tables = umbra_report::csv::tables(results);
    for (name, text) in [
        ("results.csv", tables.results),
        ("failures.csv", tables.failures),
        ("errors.csv", tables.errors),
        ("junit.xml", umbra_report::junit::junit(results)),
    ] {
        // A short file (a full disk) would read as fewer runs: none rather than that.
        if umbra_report::write_synced(&dir.join(name), text.as_bytes()).is_err() {
            let _ = std::fs::remove_file(dir.join(name));
        }
    }
}

/// Puts the workers' findings together. An interrupted run (130) or one whose pictures could
/// not be written (125, a full disk) is abandoned here, saying so: its report would be
/// incomplete, so `latest` keeps pointing at the last whole one.
fn gather(
    collected: Collected,
    opts: &Options,
    falls_along: &[FallsAlong],
    run_dir: &RunDir,
) -> Result<Gathered, Finished> {
    let Collected {
        mut results,
        drivers,
        mut driver_rows,
        refused,
        unavailable_runs,
        progress,
        storage,
        total,
        ..
    } = collected;
    progress.close();
    if crate::harness::interrupt::requested().is_some() || !storage.is_empty() {
        write_partial(&run_dir.dir, &mut results);
    }
    if let Some(sig) = crate::harness::interrupt::requested() {
        run_dir.abandon(&format!(
            "interrupted by {} after {} of {total} runs",
            crate::harness::interrupt::name(sig),
            results.len()
        ));
        return Err(Finished {
            outcome: Err(Error::said(Exit::Interrupted)),
            results,
        });
    }
    if let Some(first) = storage.first() {
        run_dir.abandon(&format!(
            "{} run(s) could not write their pictures ({first})",
            storage.len()
        ));
        return Err(Finished {
            outcome: Err(Error::said(Exit::CouldNotRun)),
            results,
        });
    }
    driver_rows.sort_by(|a, b| a["backend"].as_str().cmp(&b["backend"].as_str()));
    let mut driver_lines = drivers;
    driver_lines.sort();
    results.sort_by(|a, b| a.name.cmp(&b.name));
    let before_cross = results.clone();
    for m in falls_along {
        m.judge(&mut results);
    }
    crate::judge::consensus::diagnose(&mut results);
    Ok(Gathered {
        results,
        before_cross,
        driver_lines,
        driver_rows,
        refused,
        unavailable_runs,
        build: opts.build,
    })
}

/// drivers.txt: the Mesa build, then each backend's lines in backend order.
pub(crate) fn drivers_text(head: &str, lines: &[(String, String)]) -> String {
    let mut text = format!("{head}\n");
    for (_, l) in lines {
        text.push_str(l);
    }
    text
}

/// drivers.txt's first line: the Mesa build the run used.
fn mesa_line(build: Option<&crate::harness::mesa_build::MesaBuild>) -> String {
    format!(
        "Mesa: {}",
        build.map_or("the system's".to_string(), |b| b.describe())
    )
}

/// The run's record for `umbra merge` ([`crate::shards::record`]).
fn record(
    opts: &Options,
    names: Vec<String>,
    falls_along: Vec<FallsAlong>,
    g: &Gathered,
    budget: &TimeBudget,
) -> crate::shards::record::Record {
    use crate::shards::record as rec;
    let drivers = g
        .driver_lines
        .iter()
        .map(|(backend, text)| rec::DriverRecord {
            backend: backend.clone(),
            text: text.clone(),
            row: g
                .driver_rows
                .iter()
                .find(|r| r["backend"].as_str() == Some(backend))
                .cloned()
                .unwrap_or_default(),
        })
        .collect();
    let fingerprints = g
        .before_cross
        .iter()
        .filter_map(|r| Some((r.name.clone(), r.fingerprint.clone()?)))
        .collect();
    rec::Record {
        schema: rec::SCHEMA,
        umbra: rec::Build::this(),
        inputs: opts.inputs.clone(),
        mesa_build: serde_json::to_value(g.build).unwrap_or_default(),
        mesa_line: mesa_line(g.build),
        shard: rec::ShardRecord {
            index: opts.shard.0,
            count: opts.shard.1,
            by: opts.by.describe(),
        },
        settings: rec::Settings {
            timeout_s: opts.timeout.as_secs(),
            bless: opts.bless,
        },
        plan: rec::PlanRecord {
            filter: opts.filter.clone(),
            backends: opts.backends.clone(),
            runs: names,
        },
        budget: budget.clone(),
        drivers,
        refused: g.refused.clone(),
        unavailable_runs: g.unavailable_runs,
        falls_along,
        runs: g.before_cross.clone(),
        fingerprints,
    }
}

/// Writes the reports and the run's record into the run directory and publishes it
/// (`latest`); when they cannot be written, the run directory is abandoned (saying so) and
/// the error is said (125).
fn write_reports(
    g: &Gathered,
    settings: &Settings,
    budget: &TimeBudget,
    run_dir: &RunDir,
    record: &crate::shards::record::Record,
    extra: Option<Extra>,
) -> Result<(), Error> {
    let header = serde_json::json!({
        "mesa_build": g.build,
        "drivers": g.driver_rows,
    });
    let written = umbra_report::write_conformance(
        &run_dir.dir,
        &settings.failures,
        &settings.gallery,
        &g.results,
        &drivers_text(&mesa_line(g.build), &g.driver_lines),
        &header,
        budget,
    )
    .and_then(|()| record.write(&run_dir.dir))
    .and_then(|()| extra.map_or(Ok(()), |f| f(&run_dir.dir, &g.results)))
    .and_then(|()| run_dir.publish());
    written.map_err(|e| {
        run_dir.abandon(&format!("cannot write the reports: {e}"));
        Error::said(Exit::CouldNotRun)
    })
}

/// The terminal's summary: where the reports are, every regression with its diagnosis, the
/// consensus, the time budget, the check strength, the statuses and goldens blessed on
/// another driver. Returns the number of regressions.
pub(crate) fn print_summary(
    results: &[RunResult],
    budget: &TimeBudget,
    out: &Path,
    run_dir: &RunDir,
    elapsed: Duration,
) -> usize {
    let regressions: Vec<&RunResult> = results
        .iter()
        .filter(|r| r.status.is_regression())
        .collect();
    println!(
        "\n{} runs in {:.1} s; reports in {} (-> runs/{})",
        results.len(),
        elapsed.as_secs_f64(),
        out.join("latest").display(),
        run_dir.id
    );
    for r in &regressions {
        println!(
            "  regression: {} {}: {}",
            r.status,
            term(&r.name),
            term(first_line(&r.reason))
        );
        if let Some(d) = &r.diagnosis {
            println!("    {}", term(&d.message));
        }
    }
    let suspects = results
        .iter()
        .filter(|r| r.diagnosis.as_ref().is_some_and(|d| d.suspect_model()))
        .count();
    if suspects > 0 {
        println!(
            "consensus: {suspects} failing run(s) fail the same way on every driver judged against the same intervals: suspect umbra's model there before the drivers"
        );
    }
    println!("{}", budget.line());
    use umbra_report::html::{Under, blind_stats};
    if let Some(b) = blind_stats(results, Under::Spec) {
        println!(
            "check strength: blind area under the specs: {} (report.html, Check strength)",
            b.line()
        );
    }
    if let Some(b) = blind_stats(results, Under::Card).filter(|b| b.calibrated > 0) {
        println!(
            "check strength: blind area under each backend's card: {} ({} runs judged against a card)",
            b.line(),
            b.calibrated
        );
    }
    println!("statuses: {}", umbra_report::model::breakdown(results));
    print_golden_changes(results);
    regressions.len()
}

/// The goldens' part of the summary: pictures that changed on another driver release,
/// legally (reported, not failed; `goldens.csv` and report.html list them) or not (failed,
/// each run's reason names both versions).
fn print_golden_changes(results: &[RunResult]) {
    let legal: Vec<&RunResult> = results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("changed-legal"))
        .collect();
    if !legal.is_empty() {
        let mut by: std::collections::BTreeMap<(String, String), Vec<&str>> = Default::default();
        for r in &legal {
            let c = r.metrics.as_ref().and_then(|m| m.golden_change.as_ref());
            let v = |x: Option<&Option<String>>| {
                x.and_then(|x| x.clone())
                    .unwrap_or_else(|| "unknown".into())
            };
            by.entry((v(c.map(|c| &c.blessed_on)), v(c.map(|c| &c.driver))))
                .or_default()
                .push(&r.backend);
        }
        let new = legal
            .iter()
            .filter(|r| {
                r.metrics
                    .as_ref()
                    .and_then(|m| m.golden_change.as_ref())
                    .is_some_and(|c| c.new)
            })
            .count();
        println!(
            "goldens: {} picture(s) changed on this driver inside what the specs allow ({new} of them new, with no golden on any release): reported, not failed; goldens.csv and report.html (gallery, status \"changed picture\") show each beside its golden",
            legal.len()
        );
        for ((blessed, driver), backends) in &by {
            let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
            for b in backends {
                *counts.entry(b).or_default() += 1;
            }
            println!(
                "  golden blessed on Mesa {blessed}, this driver Mesa {driver}: {}",
                counts
                    .iter()
                    .map(|(b, n)| format!("{b} {n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        for r in legal.iter().take(5) {
            if let Some(c) = r.metrics.as_ref().and_then(|m| m.golden_change.as_ref()) {
                println!("    {}: {}", term(&r.name), c.pixels_phrase());
            }
        }
        if legal.len() > 5 {
            println!("    … {} more in goldens.csv", legal.len() - 5);
        }
        println!(
            "  after review, `cargo xtask bless --mesa DIR` (the same build) records this release's pictures beside the old goldens (golden/mesa-RELEASE/), which then hold strictly on it"
        );
    }
    let judged: Vec<&RunResult> = results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("changed-judged"))
        .collect();
    if !judged.is_empty() {
        let statuses: std::collections::BTreeMap<String, usize> =
            judged.iter().fold(Default::default(), |mut m, r| {
                *m.entry(r.status.name().to_string()).or_default() += 1;
                m
            });
        println!(
            "goldens: {} picture(s) changed on another driver release where the judge finds pixels illegal: those runs stand on the judge's own checks ({}), not on the golden; goldens.csv lists them",
            judged.len(),
            statuses
                .iter()
                .map(|(s, n)| format!("{n} {s}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let foreign = results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("changed-other-driver"))
        .count();
    if foreign > 0 {
        println!(
            "goldens: {foreign} differ where the judge does not look (the background, the frame's size), and were blessed on another driver version (golden/{}); each run's reason names both versions",
            crate::judge::golden::MANIFEST
        );
    }
}

/// The closing line, alone, in the form CI tools read: `COMMAND: P passed, F failed, S
/// skipped` (passed counts expected failures and flakes; failed, the regressions).
pub(crate) fn closing_line(command: &str, results: &[RunResult]) -> String {
    let count = |f: fn(&Status) -> bool| results.iter().filter(|r| f(&r.status)).count();
    format!(
        "{command}: {} passed, {} failed, {} skipped",
        count(|s| matches!(s, Status::Pass | Status::ExpectedFail | Status::Flake)),
        count(Status::is_regression),
        count(|s| matches!(s, Status::Skip(_)))
    )
}

/// Blessing (`cargo xtask bless`): records the driver each backend's goldens now match, the
/// backend's entry (kept if already recorded), then each golden written now whose version
/// differs from what the manifest already says for it (its backend's, usually).
fn record_blessings(g: &Gathered, settings: &Settings) {
    let Some(dir) = &settings.golden else {
        return;
    };
    let version_of = |b: &str| {
        g.driver_rows
            .iter()
            .find(|r| r["backend"].as_str() == Some(b))
            .and_then(|r| r["mesa"].as_str())
            .map(str::to_string)
    };
    let mut entries: Vec<(String, String)> = Vec::new();
    for r in &g.results {
        let Some(v) = version_of(&r.backend) else {
            continue;
        };
        if r.golden.is_some() && !entries.iter().any(|(k, _)| *k == r.backend) {
            entries.push((r.backend.clone(), v.clone()));
        }
        if r.golden.as_deref() == Some("written")
            && crate::judge::golden::blessed_on(dir, &r.backend, &r.name).as_deref()
                != Some(v.as_str())
        {
            entries.push((crate::judge::golden::stem(&r.name), v));
        }
    }
    // Goldens of another release this bless compared and found unchanged: confirmed on this
    // one, so they hold strictly here too (exactly those: a filtered bless confirms what it
    // ran).
    let mut confirm: std::collections::BTreeMap<String, Vec<(String, PathBuf)>> =
        Default::default();
    for r in g
        .results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("unchanged"))
    {
        let Some(v) = version_of(&r.backend) else {
            continue;
        };
        let held = crate::judge::golden::held(
            dir,
            &crate::judge::golden::Subject {
                backend: &r.backend,
                name: &r.name,
                driver: Some(&v),
            },
        );
        let other_release = held
            .blessed_on
            .as_deref()
            .is_some_and(|b| !crate::judge::golden::same_release(b, &v));
        // A golden of another release is the golden directory's own (one in this release's
        // folder was blessed on this release: `held` says so).
        if let (true, Some(file)) = (other_release, held.file) {
            confirm
                .entry(v.clone())
                .or_default()
                .push((crate::judge::golden::stem(&r.name), file));
        }
    }
    for (v, goldens) in &confirm {
        if let Err(e) = crate::judge::golden::record_confirmed(dir, v, goldens) {
            eprintln!(
                "error: cannot record the goldens confirmed on Mesa {v} in {}: {e}",
                crate::judge::golden::release_dir(dir, v).display()
            );
        }
    }
    // Nothing Mesa-backed was blessed: the manifest stays as it is.
    if !entries.is_empty() {
        if let Err(e) = crate::judge::golden::record_blessed(dir, &entries) {
            eprintln!(
                "error: cannot record the blessed drivers in {}: {e}",
                dir.display()
            );
        }
    }
}

/// The run's outcome: could not run (125) when a backend refused the Mesa build asked for
/// (its runs were not judged, each said here) or nothing could run here; a failure on a
/// regression; a pass otherwise.
pub(crate) fn outcome(
    refused: &[String],
    unavailable_runs: usize,
    runs: usize,
    regressions: usize,
) -> Outcome {
    if !refused.is_empty() {
        for r in refused {
            eprintln!("error: {r}");
        }
        eprintln!(
            "error: {} backend(s) did not run on the Mesa build asked for; their runs were not judged",
            refused.len()
        );
        Err(Error::said(Exit::CouldNotRun))
    } else if regressions > 0 {
        Ok(Exit::Fail)
    } else if unavailable_runs == runs && runs > 0 {
        Err(Error::new(
            "no selected backend is available here, nothing ran",
        ))
    } else {
        Ok(Exit::Pass)
    }
}

/// Refuses an output directory inside the case directory: its reports (report.json,
/// shard.json) would be read as cases by the next run.
pub fn outside_cases(out: &Path, cases: &Path) -> Result<(), String> {
    // The deepest existing ancestor, resolved (the output may not exist yet).
    let resolve = |p: &Path| {
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut head = abs.clone();
        let mut tail = Vec::new();
        while !head.exists() {
            match (head.file_name().map(|n| n.to_os_string()), head.parent()) {
                (Some(n), Some(parent)) => {
                    tail.push(n);
                    head = parent.to_path_buf();
                }
                _ => return abs,
            }
        }
        let mut real = std::fs::canonicalize(&head).unwrap_or(head);
        real.extend(tail.iter().rev());
        real
    };
    let (out, cases) = (resolve(out), resolve(cases));
    if out.starts_with(&cases) {
        return Err(format!(
            "is inside the case directory {}: the next run would read its reports as cases; write them elsewhere (the default is target/umbra)",
            cases.display()
        ));
    }
    Ok(())
}

/// Two case files that give one case name (their runs would share a name, a row and a
/// golden): the error naming both.
fn duplicate_names(points: &[(PathBuf, Vec<PointPlan>)]) -> Option<String> {
    let mut seen: BTreeMap<String, &Path> = BTreeMap::new();
    for (file, ids) in points {
        let Some(name) = ids
            .first()
            .and_then(|(_, _, case)| case["name"].as_str().map(str::to_string))
        else {
            continue;
        };
        if let Some(first) = seen.insert(name.clone(), file) {
            return Some(format!(
                "{} and {} both have \"name\": {name:?}; their runs, rows and goldens would be one; rename one (the field `name`)",
                first.display(),
                file.display()
            ));
        }
    }
    None
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
    /// drivers.txt's lines of each backend.
    drivers: Vec<(String, String)>,
    /// report.json's `drivers`: per backend, the driver, the build and the expectation files
    /// that applied.
    driver_rows: Vec<serde_json::Value>,
    /// Backends whose worker refused the Mesa build (fell back, or its driver did not load).
    refused: Vec<String>,
    unavailable_runs: usize,
    finished: usize,
    /// Pictures that could not be written (a full disk), one line per run: the run's
    /// report would be incomplete, so it is not published.
    storage: Vec<String>,
    /// What the terminal shows while the run goes on.
    progress: crate::harness::progress::Progress,
    /// How many runs the plan holds.
    total: usize,
}

type Done = Mutex<Collected>;

/// Runs `backend`'s runs as `next` hands them out, one by one, in a session of this thread's
/// own; `first`: this is the backend's first worker, whose hello goes into drivers.txt and
/// the report.
fn run_group(
    backend: &str,
    next: &dyn Fn() -> Option<Planned>,
    first: bool,
    settings: &Settings,
    done: &Done,
    total: usize,
) {
    let env = group_env(backend, settings);
    let mut session = Session::start(backend, &env, settings.timeout);
    // A worker that cannot even be started (our own binary missing or replaced mid-run) is
    // the harness's failure, not the backend's: its runs crash rather than skip, so that it
    // can never read as a clean run.
    let hello = session.hello().clone();
    // Only the lines that can name this backend's runs, so drivers.txt counts its own.
    let own = settings.expectations.for_backend(backend);
    let facts = hello.facts();
    let mut group = Group {
        backend,
        calibration: None,
        not_ready: session.ready().err(),
        // Expectations for this backend's driver (`@applies`), and those a release before it
        // closed (their deviations were fixed: a failure they match may be one come back).
        expectations: own.for_driver(&facts),
        closed: own.closed_for(&facts),
        settings,
    };
    if let Some(mut d) = done.lock().ok().filter(|_| first) {
        let (line, row) = describe_driver(&group, &hello);
        d.drivers.push((backend.to_string(), line));
        d.driver_rows.push(row);
        if let Some(why) = group.refused() {
            d.refused.push(format!("{backend}: {why}"));
        }
    }
    // The live card, measured once per backend (by whichever of its threads comes first),
    // for the card row and for calibrated judging.
    let row_dir = settings.cards.as_deref().filter(|_| first);
    let live =
        (group.not_run().is_none() && (settings.calibrate || row_dir.is_some())).then(|| {
            settings
                .live_cards
                .measured(backend, &env, settings.timeout)
        });
    if settings.calibrate {
        group.calibration = crate::commands::card::calibration_of(backend, live.as_ref(), first);
    }
    if let Some(dir) = row_dir {
        let not_run = group.not_run().map(|a| (a.status, a.reason));
        let row =
            crate::commands::card::conformance_row(backend, live, dir, settings.bless, not_run);
        let unavailable = matches!(group.not_ready, Some(NotReady::Unavailable(_)));
        finished(done, row, None, total, settings.verbose, unavailable);
    }
    while let Some(p) = next() {
        let t0 = Instant::now();
        let outcome = group.attempt_point(&p, &mut session);
        let (result, storage) = group.result_of(&p, outcome, t0);
        let unavailable = matches!(group.not_ready, Some(NotReady::Unavailable(_)));
        finished(done, result, storage, total, settings.verbose, unavailable);
    }
}

/// Records a finished run and prints its progress line.
fn finished(
    done: &Done,
    result: RunResult,
    storage: Option<String>,
    total: usize,
    verbose: bool,
    unavailable: bool,
) {
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
        d.progress.finished(r.status.name(), &line);
        if verbose && !r.details.is_empty() {
            println!("{}", r.details);
        }
        if unavailable {
            d.unavailable_runs += 1;
        }
        d.storage.extend(storage);
        d.results.push(result);
    }
}

/// A backend's workers' environment: the driver's ([`crate::harness::registry::worker_env`]),
/// the fakes' switch where enabled, the judging cache, and insta's when blessing.
fn group_env(backend: &str, settings: &Settings) -> Vec<(String, String)> {
    let mut env = crate::harness::registry::worker_env(backend);
    if crate::harness::fake::enabled() {
        env.push(("UMBRA_FAKE_BACKENDS".into(), "1".into()));
    }
    env.push((
        crate::judge::judge_cache::ENV.into(),
        settings.judge_cache.clone(),
    ));
    if settings.bless {
        env.extend(crate::judge::golden::insta_env(true));
    }
    env
}

/// One backend's group of runs, as its first worker left it: why it cannot run (refused the
/// Mesa build, unavailable, its worker would not start) and the expectations for its driver.
struct Group<'a> {
    backend: &'a str,
    /// Its card read as the judge's narrowing ([`umbra_case::Calibration::encode`]); none:
    /// judged by the spec alone.
    calibration: Option<String>,
    /// Why its runs cannot run, where they cannot ([`Session::ready`]).
    not_ready: Option<NotReady>,
    expectations: Expectations,
    /// Expectations whose range an earlier release closed ([`Expectations::closed_for`]).
    closed: Expectations,
    settings: &'a Settings,
}

/// The backend's lines for drivers.txt (driver strings, device, goldens, build and the
/// expectation files that apply) and its row in report.json's `drivers`.
fn describe_driver(g: &Group, hello: &Hello) -> (String, serde_json::Value) {
    let (backend, settings) = (g.backend, g.settings);
    let files = g.expectations.file_counts();
    let ready = hello.ready();
    let facts = hello.facts();
    let build = ready.and_then(|r| r.build.clone());
    let driver_line = match hello {
        Hello::Ready(r) => format!(
            "{backend}: {} | {} | {} | {}\n",
            r.vendor,
            r.renderer,
            r.version,
            r.extensions.join(" ")
        ),
        Hello::Unavailable(u) => format!("{backend}: unavailable: {u}\n"),
        Hello::Refused(why) => format!("{backend}: refused: {why}\n"),
    };
    let mut device = ready
        .map(|r| r.device.as_str())
        .filter(|d| !d.is_empty())
        .map_or(String::new(), |d| format!("  device: {d}\n"));
    let no_goldens = settings.no_goldens.contains(backend);
    if no_goldens {
        device.push_str(&format!(
            "  goldens: {} (`cargo xtask bless --backend {backend}` starts them)\n",
            crate::judge::golden::NONE_FOR_BACKEND
        ));
    }
    // Deviations a release before this driver fixed: their runs are held to pass here.
    let closed = g.closed.file_counts();
    let closed_line = if closed.is_empty() {
        String::new()
    } else {
        format!(
            "  closed before this release (deviations fixed; their runs must pass): {}\n",
            closed.join(", ")
        )
    };
    let line = format!(
        "{}{device}{}{closed_line}",
        driver_line,
        match (&build, files.is_empty()) {
            (Some(b), true) => format!("  build: {b}; expectations: none\n"),
            (Some(b), false) => format!("  build: {b}; expectations: {}\n", files.join(", ")),
            (None, false) => format!("  expectations: {}\n", files.join(", ")),
            (None, true) => String::new(),
        }
    );
    let row = serde_json::json!({
        "backend": backend,
        "vendor": ready.map(|r| &r.vendor),
        "renderer": ready.map(|r| &r.renderer),
        "version": ready.map(|r| &r.version),
        "device": ready.map(|r| &r.device),
        "goldens": if no_goldens {
            serde_json::json!(crate::judge::golden::NONE_FOR_BACKEND)
        } else {
            serde_json::Value::Null
        },
        "mesa": facts.mesa,
        "build": build,
        "unavailable": hello.unavailable(),
        "refused": g.refused(),
        "expectations": files,
        "closed_expectations": closed,
    });
    (line, row)
}

impl Group<'_> {
    /// Why its worker refused the Mesa build, where it did.
    fn refused(&self) -> Option<&str> {
        match &self.not_ready {
            Some(NotReady::Refused(why)) => Some(why),
            _ => None,
        }
    }

    /// What a run of a group that cannot run is: a crash (the worker refused the Mesa build,
    /// or could not be started) or a skip (the backend is unavailable here), with the reason.
    fn not_run(&self) -> Option<Attempt> {
        Some(match self.not_ready.as_ref()? {
            NotReady::Refused(why) => Attempt::bare(
                Status::Crash,
                format!("not run: the worker refused the Mesa build: {why}"),
            ),
            NotReady::NoWorker(e) => Attempt::bare(
                Status::Crash,
                format!("the harness could not start its worker process: {e}"),
            ),
            NotReady::Unavailable(why) => Attempt::bare(Status::Skip(why.clone()), why.clone()),
        })
    }

    /// Runs point `p` on the group's worker (started again if it died), once more if it
    /// failed (a different answer is a flake); a group that cannot run crashes or skips each
    /// point with the reason.
    fn attempt_point(&self, p: &Planned, session: &mut Session) -> Attempt {
        let settings = self.settings;
        match self.not_run() {
            Some(a) => a,
            None => {
                let req = Request {
                    file: p.file.clone(),
                    index: p.index,
                    failures: Some(settings.failures.clone()),
                    golden: settings
                        .golden
                        .clone()
                        .filter(|_| !settings.no_goldens.contains(self.backend)),
                    repeat: None,
                    no_twins: false,
                    gallery: Some(settings.gallery.clone()),
                    deviation: Some(self.expectations.deviations(&p.name(), &p.case).names())
                        .filter(|n| !n.is_empty()),
                    card: false,
                    calibration: self.calibration.clone(),
                };
                session.attempt_or_rerun(&req, &p.name())
            }
        }
    }

    /// The run's result: its raw outcome under the driver's expectations (an expectation
    /// naming only checks this run did not make does not apply), with the command that
    /// reproduces it; and the storage problem its pictures met, if any.
    fn result_of(&self, p: &Planned, outcome: Attempt, t0: Instant) -> (RunResult, Option<String>) {
        let settings = self.settings;
        let name = p.name();
        let Attempt {
            status: raw,
            reason,
            metrics,
            details,
            failed,
            golden,
            fingerprint,
            under_deviation,
            storage,
            stderr,
        } = outcome;
        let unchecked: &[umbra_report::check::Check] =
            if settings.golden.is_none() || settings.no_goldens.contains(&p.backend) {
                &[umbra_report::check::Check::Golden]
            } else {
                &[]
            };
        let (status, expected) = self.expectations.apply(
            &name,
            &p.case,
            raw,
            &failed,
            under_deviation.as_deref(),
            unchecked,
        );
        let got = if reason.is_empty() {
            "a pass, every check inside what the specs allow".to_string()
        } else {
            reason.clone()
        };
        let reason = match (&status, expected) {
            (Status::ExpectedFail | Status::UnexpectedPass, Some(why)) => {
                format!("expected: {why}; got: {got}")
            }
            (_, Some(why)) if reason.is_empty() => format!("expectation: {why}"),
            (_, Some(why)) => format!("{reason} (expectation: {why})"),
            (s, None) if s.is_regression() => match self.closed.come_back(&name, &p.case) {
                Some(back) => format!("{reason} ({back})"),
                None => reason,
            },
            (_, None) => reason,
        };
        let passes = result_passes(&status);
        let result = RunResult {
            name,
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
            reproduce: reproduce_command(p),
            diagnosis: None,
            // A pass's stderr is noise; any other status keeps it as evidence.
            stderr: if passes { String::new() } else { stderr },
            fingerprint,
            details,
        };
        (result, storage)
    }
}

/// The command that renders run `p` again, on the run's Mesa build when it used one.
fn reproduce_command(p: &Planned) -> String {
    // The driver variables the run inherited go first: without them it may not reproduce.
    let env: String = crate::harness::registry::inherited_driver_env(&p.backend)
        .iter()
        .map(|(k, v)| format!("{k}={} ", shell_word(v)))
        .collect();
    // Values as `--flag=VALUE` and the file as an operand: nothing a case or a path is
    // called can be read as an option.
    format!(
        "{env}cargo run --bin umbra -- render {} --backend={} --point={}{}",
        umbra_report::escape::operand(&p.file.display().to_string()),
        shell_word(&p.backend),
        shell_word(&p.id),
        crate::harness::mesa_build::selected()
            .filter(|_| crate::harness::mesa_build::is_mesa_backed(&p.backend))
            .map_or(String::new(), |b| format!(
                " --mesa={}",
                shell_word(&b.root.display().to_string())
            ))
    )
}

/// Whether a run's status is a plain pass (its stderr is not kept).
fn result_passes(status: &Status) -> bool {
    matches!(status, Status::Pass)
}
