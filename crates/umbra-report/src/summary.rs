//! What a conformance run (or a merge of its shards) says at its end, as text: the summary
//! of regressions, consensus, time, check strength, statuses and golden changes
//! ([`summary`]), the closing line CI tools read ([`closing_line`]) and `drivers.txt`'s text
//! ([`drivers_text`]). The runner prints them and decides the exit code.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

use crate::escape::term;
use crate::model::{RunResult, Status, TimeBudget};

/// The first line of a reason (a run's reason may hold its whole description).
pub fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or("")
}

/// drivers.txt: the Mesa build, then each backend's lines in backend order.
pub fn drivers_text(head: &str, lines: &[(String, String)]) -> String {
    let mut text = format!("{head}\n");
    for (_, l) in lines {
        text.push_str(l);
    }
    text
}

/// The terminal's summary: where the reports are, every regression with its diagnosis, the
/// consensus, the time budget, the check strength, the statuses and goldens blessed on
/// another driver (`manifest`: the golden directory's record of where each was blessed).
/// Returns the text and the number of regressions.
pub fn summary(
    results: &[RunResult],
    budget: &TimeBudget,
    out: &Path,
    run_id: &str,
    elapsed: Duration,
    manifest: &str,
) -> (String, usize) {
    let mut o = String::new();
    let regressions: Vec<&RunResult> = results
        .iter()
        .filter(|r| r.status.is_regression())
        .collect();
    let _ = writeln!(
        o,
        "\n{} runs in {:.1} s; reports in {} (-> runs/{})",
        results.len(),
        elapsed.as_secs_f64(),
        out.join("latest").display(),
        run_id
    );
    for r in &regressions {
        let _ = writeln!(
            o,
            "  regression: {} {}: {}",
            r.status,
            term(&r.name),
            term(first_line(&r.reason))
        );
        if let Some(d) = &r.diagnosis {
            let _ = writeln!(o, "    {}", term(&d.message));
        }
    }
    let suspects = results
        .iter()
        .filter(|r| r.diagnosis.as_ref().is_some_and(|d| d.suspect_model()))
        .count();
    if suspects > 0 {
        let _ = writeln!(
            o,
            "consensus: {suspects} failing run(s) fail the same way on every driver judged against the same intervals: suspect umbra's model there before the drivers"
        );
    }
    let _ = writeln!(o, "{}", budget.line());
    use crate::html::{Under, blind_stats};
    if let Some(b) = blind_stats(results, Under::Spec) {
        let _ = writeln!(
            o,
            "check strength: blind area under the specs: {} (report.html, Check strength)",
            b.line()
        );
    }
    if let Some(b) = blind_stats(results, Under::Card).filter(|b| b.calibrated > 0) {
        let _ = writeln!(
            o,
            "check strength: blind area under each backend's card: {} ({} runs judged against a card)",
            b.line(),
            b.calibrated
        );
    }
    let _ = writeln!(o, "statuses: {}", crate::model::breakdown(results));
    o.push_str(&golden_changes(results, manifest));
    (o, regressions.len())
}

/// The goldens' part of the summary: pictures that changed on another driver release,
/// legally (reported, not failed; `goldens.csv` and report.html list them) or not (failed,
/// each run's reason names both versions).
pub fn golden_changes(results: &[RunResult], manifest: &str) -> String {
    let mut o = String::new();
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
        let _ = writeln!(
            o,
            "goldens: {} picture(s) changed on this driver inside what the specs allow ({new} of them new, with no golden on any release): reported, not failed; goldens.csv and report.html (gallery, status \"changed picture\") show each beside its golden",
            legal.len()
        );
        for ((blessed, driver), backends) in &by {
            let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
            for b in backends {
                *counts.entry(b).or_default() += 1;
            }
            let _ = writeln!(
                o,
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
                let _ = writeln!(o, "    {}: {}", term(&r.name), c.pixels_phrase());
            }
        }
        if legal.len() > 5 {
            let _ = writeln!(o, "    … {} more in goldens.csv", legal.len() - 5);
        }
        let _ = writeln!(
            o,
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
        let _ = writeln!(
            o,
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
        let _ = writeln!(
            o,
            "goldens: {foreign} differ where the judge does not look (the background, the frame's size), and were blessed on another driver version (golden/{}); each run's reason names both versions",
            manifest
        );
    }
    o
}

/// The closing line, alone, in the form CI tools read: `COMMAND: P passed, F failed, S
/// skipped` (passed counts expected failures and flakes; failed, the regressions).
pub fn closing_line(command: &str, results: &[RunResult]) -> String {
    closing_of(command, results.iter().map(|r| r.status.clone()))
}

/// [`closing_line`] of a run read back from its report.json (`umbra drivers` reads each
/// side's this way rather than from the child's terminal output). A status name the
/// report should not hold counts as a failure.
pub fn closing_line_of(command: &str, report: &crate::json::Report) -> String {
    closing_of(
        command,
        report
            .runs
            .iter()
            .map(|r| Status::of_name(&r.status).unwrap_or(Status::Fail)),
    )
}

fn closing_of(command: &str, statuses: impl Iterator<Item = Status>) -> String {
    let (mut passed, mut failed, mut skipped) = (0, 0, 0);
    for s in statuses {
        match s {
            Status::Pass | Status::ExpectedFail | Status::Flake => passed += 1,
            Status::Skip(_) => skipped += 1,
            s if s.is_regression() => failed += 1,
            _ => {}
        }
    }
    format!("{command}: {passed} passed, {failed} failed, {skipped} skipped")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(name: &str, status: Status, reason: &str) -> RunResult {
        RunResult {
            reason: reason.into(),
            ..RunResult::of_test(name, status)
        }
    }

    /// The text the terminal shows names each regression by its reason's first line, counts
    /// them, and closes with the line CI tools read (expected failures count as passed).
    #[test]
    fn the_summary_names_each_regression_and_the_closing_line_counts() {
        let results = vec![
            result("gl33/llvmpipe/a", Status::Pass, ""),
            result("gl33/llvmpipe/b", Status::Fail, "value: 3 px\nthe details"),
            result("gl33/llvmpipe/c", Status::ExpectedFail, "known"),
            result("gl33/llvmpipe/d", Status::Skip("no driver".into()), ""),
        ];
        let budget = TimeBudget::default();
        let (text, regressions) = summary(
            &results,
            &budget,
            Path::new("target/umbra"),
            "RUN",
            Duration::from_secs(2),
            "blessed-on.json",
        );
        assert_eq!(regressions, 1);
        assert!(
            text.starts_with("\n4 runs in 2.0 s; reports in target/umbra/latest (-> runs/RUN)\n"),
            "{text}"
        );
        assert!(
            text.contains("  regression: Fail gl33/llvmpipe/b: value: 3 px\n"),
            "{text}"
        );
        assert!(!text.contains("the details"), "{text}");
        assert_eq!(
            closing_line("conformance", &results),
            "conformance: 2 passed, 1 failed, 1 skipped"
        );
        let report = crate::json::Report::new(
            &results,
            crate::json::Header::default(),
            &budget,
            "umbra conformance".into(),
        );
        let report =
            crate::json::Report::parse(&report.to_json().expect("writes")).expect("reads back");
        assert_eq!(
            closing_line_of("conformance", &report),
            closing_line("conformance", &results)
        );
        for s in [
            Status::Pass,
            Status::Fail,
            Status::Crash,
            Status::Timeout,
            Status::Skip("why".into()),
            Status::ExpectedFail,
            Status::UnexpectedPass,
            Status::OrderDependent,
            Status::Flake,
        ] {
            assert_eq!(Status::of_name(s.name()).map(|b| b.name()), Some(s.name()));
        }
        assert_eq!(
            drivers_text("Mesa: system", &[("ref".into(), "ref: umbra\n".into())]),
            "Mesa: system\nref: umbra\n"
        );
    }
}
