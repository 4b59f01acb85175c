//! `umbra soak --seed S --count N`: the judge on scenes it was not developed against.
//!
//! The catalogue is the set the tolerance model was built around; a model too tight for
//! some technique can pass all of it and fail a correct driver on the first case a user
//! writes. The soak draws `N` valid cases from seed `S` ([`umbra_case::generate`]), writes
//! them under the run's own directory (`OUT/runs/ID/cases/`), and runs them on every selected backend as a conformance run does
//! with the judge alone (no goldens: generated cases have none), expectations applied. It
//! prints, per backend, the runs, passes, skips, diagnosed deviations (expected failures,
//! matched by cause on cases that have never been seen) and failures by class, counting
//! those the consensus diagnosis marks as suspected model errors apart. Reports go where a
//! conformance run puts them ([`crate::run_dir`]: `OUT/latest` shows the run once complete),
//! and `soak.csv` beside them holds the table.
//!
//! The outcome is the conformance run's: exit 0 when every run is as expected, 1 on any
//! failure, 125 when nothing could run.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::cli::{ConformanceArgs, Output, Selection, SoakArgs};
use crate::exit::{Error, Exit, Outcome};
use umbra_report::{RunResult, Status};

/// Runs the command; returns its outcome.
pub fn main(args: &SoakArgs) -> Outcome {
    let (seed, count) = (args.seed, args.count.get());
    let out = args
        .output
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(crate::run_dir::SOAK_OUT));
    // The cases live in the run's own directory: two soaks into one --out never share them,
    // and the report's reproduce commands keep pointing at them.
    let run_dir = match crate::run_dir::RunDir::create(&out) {
        Ok(r) => r,
        Err(e) => {
            return Err(Error::new(format!(
                "cannot create a run directory under {}: {e}; give --out a writable directory",
                out.join("runs").display()
            )));
        }
    };
    let dir = run_dir.dir.join("cases");
    if let Err(e) = umbra_case::generate::write_cases(&dir, seed, count) {
        run_dir.abandon(&format!(
            "cannot write the generated cases under {}: {e}",
            dir.display()
        ));
        return Err(Error::said(Exit::CouldNotRun));
    }
    let run_path = run_dir.dir.clone();
    println!(
        "soak: {count} cases of seed {seed} under {} (umbra_case::generate)",
        dir.display()
    );
    let run_args = ConformanceArgs {
        selection: Selection {
            cases: dir.clone(),
            filter: args.filter.clone(),
            backend: args.backend.clone(),
            expectations: args.expectations.clone(),
        },
        execution: args.execution.clone(),
        golden: "none".into(),
        output: Output {
            out: Some(out.clone()),
            verbose: args.output.verbose,
        },
        ..Default::default()
    };
    let started = std::time::Instant::now();
    let soak_csv = |dir: &Path, results: &[RunResult]| {
        std::fs::write(dir.join("soak.csv"), Table::of(results).csv())
    };
    let finished = crate::conformance::run_in(&run_args, Some(run_dir), Some(&soak_csv));
    // An error is said here, where the conformance run ends, before the soak's table.
    let outcome = finished.outcome.map_err(|e| Error::said(e.report()));
    if finished.results.is_empty() {
        // Nothing ran (a usage error, said above): the run's directory holds only the cases.
        let _ = std::fs::remove_dir_all(&run_path);
        return outcome;
    }
    let table = Table::of(&finished.results);
    print!(
        "{}",
        table.text(seed, count, started.elapsed().as_secs_f64())
    );
    outcome
}

/// The soak's counts per backend, and its failures by class.
#[derive(Default)]
pub struct Table {
    /// Per backend: runs, passes, skips, diagnosed (expected failures), failures, of which
    /// suspected model errors.
    pub rows: BTreeMap<String, [usize; 6]>,
    /// Per class (`Fail value+twin:bias-order`, `skip: …`, `diagnosed: …`), per backend.
    pub classes: BTreeMap<String, BTreeMap<String, usize>>,
}

/// The column names of [`Table::rows`].
pub const COLUMNS: [&str; 6] = [
    "runs",
    "pass",
    "skip",
    "diagnosed",
    "fail",
    "suspected model",
];

impl Table {
    /// Counts `results`.
    pub fn of(results: &[RunResult]) -> Table {
        let mut t = Table::default();
        for r in results {
            let row = t.rows.entry(r.backend.clone()).or_default();
            row[0] += 1;
            let model = r.diagnosis.as_ref().is_some_and(|d| d.suspect_model());
            let class = match &r.status {
                Status::Pass | Status::Flake => {
                    row[1] += 1;
                    None
                }
                Status::Skip(why) => {
                    row[2] += 1;
                    Some(format!("skip: {}", short(why)))
                }
                Status::ExpectedFail => {
                    row[3] += 1;
                    let why = r
                        .reason
                        .strip_prefix("expected: ")
                        .and_then(|s| s.split("; got:").next())
                        .unwrap_or(&r.reason);
                    Some(format!("diagnosed: {}", short(why)))
                }
                other => {
                    row[4] += 1;
                    if model {
                        row[5] += 1;
                    }
                    let checks: Vec<String> = r.failed.iter().map(|c| c.check.name()).collect();
                    let what = if checks.is_empty() {
                        short(&r.reason)
                    } else {
                        checks.join("+")
                    };
                    Some(format!(
                        "{}{other} {what}",
                        if model { "suspected model error: " } else { "" }
                    ))
                }
            };
            if let Some(c) = class {
                *t.classes
                    .entry(c)
                    .or_default()
                    .entry(r.backend.clone())
                    .or_default() += 1;
            }
        }
        t
    }

    /// The table as the terminal shows it.
    pub fn text(&self, seed: u64, count: usize, seconds: f64) -> String {
        let mut s = format!("\nsoak of {count} generated cases (seed {seed}) in {seconds:.0} s\n");
        let _ = writeln!(
            s,
            "{:<20} {:>6} {:>6} {:>6} {:>9} {:>6} {:>15}",
            "backend", COLUMNS[0], COLUMNS[1], COLUMNS[2], COLUMNS[3], COLUMNS[4], COLUMNS[5]
        );
        for (b, r) in &self.rows {
            let _ = writeln!(
                s,
                "{b:<20} {:>6} {:>6} {:>6} {:>9} {:>6} {:>15}",
                r[0], r[1], r[2], r[3], r[4], r[5]
            );
        }
        if !self.classes.is_empty() {
            s.push_str("by class (runs per backend):\n");
            for (class, per) in &self.classes {
                let total: usize = per.values().sum();
                let backends: Vec<String> = per.iter().map(|(b, n)| format!("{b} {n}")).collect();
                let _ = writeln!(s, "  {total:>5}  {class}\n         {}", backends.join(", "));
            }
        }
        s
    }

    /// `backend,runs,pass,skip,diagnosed,fail,suspected_model`, then the classes as
    /// `class,backend,count`.
    pub fn csv(&self) -> String {
        let mut s = String::from("backend,runs,pass,skip,diagnosed,fail,suspected_model\n");
        for (b, r) in &self.rows {
            let _ = writeln!(
                s,
                "{b},{},{},{},{},{},{}",
                r[0], r[1], r[2], r[3], r[4], r[5]
            );
        }
        s.push_str("\nclass,backend,runs\n");
        for (class, per) in &self.classes {
            for (b, n) in per {
                let _ = writeln!(s, "{},{b},{n}", umbra_report::csv::csv_field(class));
            }
        }
        s
    }
}

/// The first line of a reason, numbers kept, cut at 100 characters.
fn short(s: &str) -> String {
    let line = s.lines().next().unwrap_or("");
    let mut out: String = line.chars().take(100).collect();
    if line.chars().count() > 100 {
        out.push('…');
    }
    out
}
