//! What a conformance run (or a merge of its shards) prints at its end and exits with: the
//! summary of regressions and golden changes, the closing line, `drivers.txt`'s text, and
//! the outcome ([`outcome`]: 0 as expected, 1 a regression, 125 nothing could run).

use std::path::Path;
use std::time::Duration;

use super::first_line;
use crate::exit::{Error, Exit, Outcome};
use crate::run_dir::RunDir;
use umbra_report::escape::term;
use umbra_report::{RunResult, Status, TimeBudget};

/// drivers.txt: the Mesa build, then each backend's lines in backend order.
pub(crate) fn drivers_text(head: &str, lines: &[(String, String)]) -> String {
    let mut text = format!("{head}\n");
    for (_, l) in lines {
        text.push_str(l);
    }
    text
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
pub(crate) fn print_golden_changes(results: &[RunResult]) {
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
