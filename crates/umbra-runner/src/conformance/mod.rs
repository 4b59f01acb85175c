//! A conformance run as a library: every case point on every selected backend, each backend
//! in worker processes of its own ([`crate::harness::pool`]), judged, with expectations
//! applied, and reported. `umbra conformance` is [`run`]; `umbra soak` runs its generated
//! cases through [`run_in`]; `merge` and `deqp` reuse its summary ([`summary`]) and its
//! refusal of an output directory inside the cases ([`plan::outside_cases`]). No command is
//! imported here: the commands sit above this module (`tests/layers.rs`).
//!
//! Its steps, a file each: [`plan`] (the options checked, the runs planned, the goldens
//! settled), [`execute`] (each backend's group on its workers), [`gather`] (the results
//! collected, the consensus and the record, the reports written, blessings recorded) and
//! [`summary`] (what the terminal shows, and the exit code).
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

pub mod execute;
pub mod gather;
pub mod plan;
pub mod summary;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::cli::ConformanceArgs;
use crate::exit::{Error, Outcome};
use crate::judge::expectations::Expectations;
use crate::run_dir::RunDir;
use execute::execute;
use gather::{gather, record, record_blessings, write_reports};
use plan::{Options, Plan, plan_runs, settle_goldens};
use summary::{closing_line, outcome, print_summary};
use umbra_report::{RunResult, TimeBudget};

/// A loaded point: its id, the point as loaded (sent whole to the worker) and its case as
/// JSON (what expectations' conditions read).
pub(crate) type PointPlan = (
    String,
    std::sync::Arc<umbra_case::CasePoint>,
    std::sync::Arc<serde_json::Value>,
);

/// One planned run.
#[derive(Clone, Debug)]
pub(crate) struct Planned {
    pub(crate) backend: String,
    pub(crate) id: String,
    /// The case point, loaded once here and sent whole in the worker's request (shared by the
    /// point's runs on every backend).
    pub(crate) point: std::sync::Arc<umbra_case::CasePoint>,
    /// The point's case as JSON, defaults included: what expectations' `@when` conditions
    /// read (shared by the point's runs on every backend).
    pub(crate) case: std::sync::Arc<serde_json::Value>,
}

impl Planned {
    fn name(&self) -> String {
        format!("{}/{}", self.backend, self.id)
    }
}

pub(crate) struct Settings {
    /// Directory of the shared judging basis ([`crate::judge::judge_cache`]).
    pub(crate) judge_cache: String,
    pub(crate) timeout: Duration,
    pub(crate) golden: Option<PathBuf>,
    /// Backends with no goldens in `golden`: judged without a golden check.
    pub(crate) no_goldens: std::collections::BTreeSet<String>,
    pub(crate) failures: PathBuf,
    /// Every judged run's gallery pictures (report.html's gallery reads them).
    pub(crate) gallery: PathBuf,
    pub(crate) expectations: Expectations,
    pub(crate) verbose: bool,
    /// `--bless`: workers may write goldens.
    pub(crate) bless: bool,
    /// Check each backend's behaviour card against the one kept beside its goldens: a whole
    /// run (no `--filter`, no `--shard`) with goldens.
    pub(crate) cards: Option<PathBuf>,
    /// Judge every run against its backend's card too (calibrated judging; off with
    /// `--spec-only`).
    pub(crate) calibrate: bool,
    /// Each backend's live card, measured once for the card row and the calibration.
    pub(crate) live_cards: crate::harness::cards::LiveCards,
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
    // The tier run is kept with the run: the same file runs it again.
    if let Some(t) = &opts.tier {
        if let Err(e) = t.write(&run_dir.dir.join("tier.json")) {
            return Error::new(format!("cannot keep the tier with the run: {e}")).into();
        }
    }
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

/// What every worker thread shares: the judging cache (prepared here: the judging basis of
/// each point, shared by every backend's worker and kept for the next run, see
/// judge_cache), the goldens (absolute, since workers may run with another working directory
/// one day), where pictures go, the expectations.
pub(crate) fn settings(
    args: &ConformanceArgs,
    opts: &Options,
    no_goldens: std::collections::BTreeSet<String>,
    run_dir: &RunDir,
) -> Settings {
    let judge_cache = crate::judge::judge_cache::prepare(
        &args
            .execution
            .judge_cache
            .clone()
            .unwrap_or_else(|| opts.out.join("cache").join("judge")),
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

pub(crate) use umbra_report::summary::first_line;
