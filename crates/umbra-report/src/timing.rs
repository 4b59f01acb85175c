//! `umbra timing`: where a run's worker time went, per kind of run and per stage of
//! judging, from a report.json's per-run `stages_ms` (measured by the worker's stage clock,
//! the runner's `judge::stages`). The table docs/performance.md keeps is this output.
//!
//! A run's time (request to answer) is its backend's frame, its twins' renders, and the
//! harness's stages; "harness" here is every stage but the twins' renders: the truth, the
//! judged reference, waiting for another worker's entry, the comparisons, the card, the
//! twins' judging and the golden. What is left of the run's time (`other`: case loading,
//! tessellation, the protocol) is shown too, so the columns add up to the run's time.

use std::collections::BTreeMap;

use crate::json::Report;

/// Stage names in the order the table prints them (the worker's own names).
const STAGES: [&str; 13] = [
    "truth_rays",
    "truth_read",
    "judged_map",
    "judged_lookups",
    "judged_render",
    "judged_read",
    "wait",
    "cache_write",
    "compare",
    "card",
    "twin_render",
    "twin_judge",
    "golden",
];

#[derive(Default)]
struct Row {
    runs: usize,
    time: f64,
    render: f64,
    stages: BTreeMap<&'static str, f64>,
}

impl Row {
    fn add(&mut self, time_ms: f64, render_ms: f64, stages: &BTreeMap<String, f64>) {
        self.runs += 1;
        self.time += time_ms / 1e3;
        self.render += render_ms / 1e3;
        for s in STAGES {
            *self.stages.entry(s).or_default() += stages.get(s).copied().unwrap_or(0.0) / 1e3;
        }
    }

    fn stage(&self, s: &str) -> f64 {
        self.stages.get(s).copied().unwrap_or(0.0)
    }

    fn harness(&self) -> f64 {
        STAGES
            .iter()
            .filter(|s| **s != "twin_render")
            .map(|s| self.stage(s))
            .sum()
    }

    fn line(&self, name: &str) -> String {
        let pct = |v: f64| {
            if self.time > 0.0 {
                100.0 * v / self.time
            } else {
                0.0
            }
        };
        let accounted = self.render + STAGES.iter().map(|s| self.stage(s)).sum::<f64>();
        let mut cells = vec![
            name.to_string(),
            self.runs.to_string(),
            format!("{:.1}", self.time),
            format!("{:.1} ({:.0} %)", self.render, pct(self.render)),
        ];
        cells.extend(STAGES.iter().map(|s| format!("{:.1}", self.stage(s))));
        cells.push(format!("{:.1}", (self.time - accounted).max(0.0)));
        cells.push(format!("{:.0} %", pct(self.harness())));
        format!("| {} |", cells.join(" | "))
    }
}

/// What a row of the table gathers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum By {
    /// The run's kind (light count, map shape, placement, filter, mips).
    Kind,
    /// The backend.
    Backend,
}

/// The table of `report`'s judged runs: one row per run kind or backend, then all runs;
/// seconds summed over the runs (worker time, not wall time).
pub fn table(report: &Report, by: By) -> Result<String, String> {
    let mut rows: BTreeMap<String, Row> = BTreeMap::new();
    let mut all = Row::default();
    let mut unmeasured = 0usize;
    for run in &report.runs {
        let Some(m) = &run.metrics else { continue };
        if m.stages_ms.is_empty() {
            unmeasured += 1;
            continue;
        }
        let key = match by {
            By::Kind => m.kind.clone(),
            By::Backend => run.backend.clone(),
        };
        rows.entry(key)
            .or_default()
            .add(run.time_ms, m.total_ms, &m.stages_ms);
        all.add(run.time_ms, m.total_ms, &m.stages_ms);
    }
    if all.runs == 0 {
        return Err(format!(
            "no judged run has stage times ({unmeasured} judged runs without): the report was written by an umbra older than its stage clock, or judged nothing"
        ));
    }
    let mut out = String::new();
    let by_name = match by {
        By::Kind => "run kind",
        By::Backend => "backend",
    };
    let mut head = vec![by_name, "runs", "run time s", "render s"];
    head.extend(STAGES.iter().map(|s| match *s {
        "truth_rays" => "truth rays",
        "truth_read" => "truth read",
        "judged_map" => "judged map",
        "judged_lookups" => "judged lookups",
        "judged_render" => "judged, rest",
        "judged_read" => "judged read",
        "cache_write" => "cache write",
        "twin_render" => "twin renders",
        "twin_judge" => "twin judging",
        other => other,
    }));
    head.extend(["other", "harness"]);
    out += &format!("| {} |\n", head.join(" | "));
    out += &format!("|{}\n", "---|".repeat(head.len()));
    for (name, row) in &rows {
        out += &row.line(name);
        out.push('\n');
    }
    out += &all.line("**all**");
    out.push('\n');
    if unmeasured > 0 {
        out += &format!("\n{unmeasured} judged runs carry no stage times and are left out.\n");
    }
    Ok(out)
}

/// The twins of `report`'s judged runs by twin: how many were rendered in full, over the
/// case's kept shadow map (lit pass only), or not at all (the case's own frame by
/// construction, or skipped), and the render time of those rendered, summed (the frames'
/// own clock: GPU timers where the backend has them).
pub fn twins_table(report: &Report) -> String {
    #[derive(Default)]
    struct Twin {
        full: usize,
        shared: usize,
        by_construction: usize,
        skipped: usize,
        full_ms: f64,
        shared_ms: f64,
    }
    let mut twins: BTreeMap<&str, Twin> = BTreeMap::new();
    for t in report
        .runs
        .iter()
        .filter_map(|r| r.metrics.as_ref())
        .flat_map(|m| &m.twins)
    {
        let e = twins.entry(t.name.as_str()).or_default();
        if t.skipped.is_some() {
            e.skipped += 1;
        } else if t.by_construction {
            e.by_construction += 1;
        } else if t.shared_shadow_pass {
            e.shared += 1;
            e.shared_ms += t.render_ms;
        } else {
            e.full += 1;
            e.full_ms += t.render_ms;
        }
    }
    let mut out = String::from(
        "| twin | rendered in full | their render s | lit pass only (kept map) | their render s | by construction | skipped |\n|---|---|---|---|---|---|---|\n",
    );
    for (name, t) in &twins {
        out += &format!(
            "| {name} | {} | {:.1} | {} | {:.1} | {} | {} |\n",
            t.full,
            t.full_ms / 1e3,
            t.shared,
            t.shared_ms / 1e3,
            t.by_construction,
            t.skipped
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::json::Header;
    use crate::model::{Metrics, RunResult, Status, TimeBudget};

    fn run(name: &str, kind: &str, time_s: f64, stages: &[(&str, f64)]) -> RunResult {
        RunResult {
            metrics: Some(Metrics {
                kind: kind.into(),
                total_ms: 100.0,
                stages_ms: stages.iter().map(|(s, v)| (s.to_string(), *v)).collect(),
                ..Metrics::default()
            }),
            time_s,
            ..RunResult::of_test(name, Status::Pass)
        }
    }

    #[test]
    fn stages_add_up_per_kind_and_the_rest_is_other() {
        let results = [
            run(
                "ref/a",
                "1 light, 2d, nearest",
                1.0,
                &[("judged_lookups", 600.0)],
            ),
            run(
                "ref/b",
                "1 light, 2d, nearest",
                0.5,
                &[("twin_render", 100.0), ("compare", 40.0)],
            ),
            run("ref/c", "1 light, cube, pcf", 0.3, &[("truth_rays", 100.0)]),
            // A run of an older umbra: no stages, left out and said.
            run("ref/d", "", 0.2, &[]),
        ];
        let report = Report::new(
            &results,
            Header::default(),
            &TimeBudget::default(),
            String::new(),
        );
        let t = table(&report, By::Kind).expect("a table");
        let row = |name: &str| {
            t.lines()
                .find(|l| l.starts_with(&format!("| {name} |")))
                .expect(name)
                .to_string()
        };
        // 1.5 s of run time: 0.2 s render, 0.6 lookups, 0.1 twin renders, 0.04 compare; other
        // 0.56; harness (every stage but the twins' renders) 0.64 s = 43 %.
        let nearest = row("1 light, 2d, nearest");
        assert!(
            nearest.starts_with("| 1 light, 2d, nearest | 2 | 1.5 | 0.2 (13 %) |"),
            "{nearest}"
        );
        assert!(nearest.ends_with("| 0.6 | 43 % |"), "{nearest}");
        assert!(row("1 light, cube, pcf").ends_with("| 0.1 | 33 % |"), "{t}");
        assert!(row("**all**").contains("| 3 | 1.8 |"), "{t}");
        assert!(t.contains("1 judged runs carry no stage times"), "{t}");
        let by_backend = table(&report, By::Backend).expect("a table");
        assert!(by_backend.contains("| ref | 3 |"), "{by_backend}");
        let none = Report::new(
            &results[3..],
            Header::default(),
            &TimeBudget::default(),
            String::new(),
        );
        assert!(table(&none, By::Kind).is_err());
    }
}
