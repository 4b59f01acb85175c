//! What a conformance run (or a merge of its shards) prints at its end and exits with: the
//! text is umbra-report's ([`umbra_report::summary`]: the summary, the closing line,
//! `drivers.txt`); here it is printed, and the outcome decided ([`outcome`]: 0 as expected,
//! 1 a regression, 125 nothing could run).

use std::path::Path;
use std::time::Duration;

use crate::exit::{Error, Exit, Outcome};
use crate::run_dir::RunDir;
use umbra_report::TimeBudget;
use umbra_report::summary::summary;
pub(crate) use umbra_report::summary::{closing_line, drivers_text};

/// Prints the run's summary ([`umbra_report::summary::summary`]); returns the number of
/// regressions.
pub(crate) fn print_summary(
    results: &[umbra_report::RunResult],
    budget: &TimeBudget,
    out: &Path,
    run_dir: &RunDir,
    elapsed: Duration,
) -> usize {
    let (text, regressions) = summary(
        results,
        budget,
        out,
        &run_dir.id,
        elapsed,
        crate::judge::golden::MANIFEST,
    );
    print!("{text}");
    regressions
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
