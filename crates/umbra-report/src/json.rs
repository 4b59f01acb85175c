//! `report.json` (schema 1) as one type, [`Report`], that the runner writes and reads back:
//! the run's header (command, wall time, time budget, the Mesa build and every driver) and
//! one [`ReportRun`] per run, the README's promised fields at top level, then everything
//! else; a merged run adds `shards`, one row per shard it was put together from.
//!
//! `umbra drivers` and `umbra bisect` read the reports of the conformance runs they start
//! through [`Report::read`]: a missing or mistyped field is an error that names the file and
//! the field's path (`runs[12].status`), not an empty string. The document is written through a `serde_json::Value`,
//! whose keys are sorted, so its text is what it always was.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::model::{Diagnosis, FailedCheck, Metrics, RunResult, TimeBudget};

/// The schema this umbra writes and reads.
pub const SCHEMA: u32 = 1;

/// The whole document.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// [`SCHEMA`].
    pub schema: u32,
    /// The run's wall time, seconds.
    pub wall_s: f64,
    /// Where the workers' time went.
    pub time_budget: TimeBudget,
    /// [`TimeBudget::overhead_share`].
    pub harness_overhead_share: f64,
    /// The command line that made the run.
    pub command: String,
    /// The Mesa build the run used (`--mesa`), as the runner describes it; null: the
    /// system's.
    pub mesa_build: serde_json::Value,
    /// Every backend's driver, by backend id.
    pub drivers: Vec<DriverRow>,
    /// Every run, sorted by name.
    pub runs: Vec<ReportRun>,
    /// A merged run (`umbra merge`): the shards it was put together from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shards: Option<Vec<ShardRow>>,
}

/// One shard a merged run was put together from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardRow {
    /// Its index I of `--shard I/N`.
    pub index: usize,
    /// N.
    pub count: usize,
    /// How the plan was split: `stride` or by durations.
    pub by: String,
    /// The runs it made.
    pub runs: usize,
    /// Its wall time, seconds.
    pub wall_s: f64,
    /// Its workers' time (runs and starts), seconds.
    pub worker_s: f64,
    /// Its directory, as given to `umbra merge`.
    pub dir: String,
}

/// What the orchestrator found out about the run besides the runs themselves.
#[derive(Clone, Debug, Default)]
pub struct Header {
    /// [`Report::mesa_build`].
    pub mesa_build: serde_json::Value,
    /// [`Report::drivers`].
    pub drivers: Vec<DriverRow>,
    /// [`Report::shards`].
    pub shards: Option<Vec<ShardRow>>,
}

/// One backend's driver (fields in the order the file has always listed them).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DriverRow {
    /// The backend id.
    pub backend: String,
    /// The Mesa build its worker ran on (a meson build or prefix); null: the system's.
    pub build: Option<String>,
    /// Expectation files whose range an earlier release closed, with their line counts.
    pub closed_expectations: Vec<String>,
    /// The device (EGL device, wgpu adapter), where the worker was ready.
    pub device: Option<String>,
    /// The expectation files that apply to this driver, with their line counts.
    pub expectations: Vec<String>,
    /// Set when the backend has no goldens yet (runs judged without a golden check).
    pub goldens: Option<String>,
    /// The Mesa version the driver reports, if it is Mesa.
    pub mesa: Option<String>,
    /// Why its worker refused the Mesa build, where it did.
    pub refused: Option<String>,
    /// The renderer string, where the worker was ready.
    pub renderer: Option<String>,
    /// Why the backend is unavailable here, where it is.
    pub unavailable: Option<String>,
    /// The vendor string, where the worker was ready.
    pub vendor: Option<String>,
    /// The version string, where the worker was ready.
    pub version: Option<String>,
}

/// One run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReportRun {
    /// `backend/case@sweep`.
    pub name: String,
    /// The case point id.
    pub case: String,
    /// The case file.
    pub file: String,
    /// The backend id.
    pub backend: String,
    /// What became of its golden ([`RunResult::golden`]).
    pub golden: Option<String>,
    /// The final status's name ([`crate::Status::name`]: `Pass`, `Fail`, `Skip`, …).
    pub status: String,
    /// Why (failure problems, skip reason, crash status, expectation reason).
    pub reason: String,
    /// False shadow over the judged pixels, a fraction; null: not judged.
    pub false_shadow: Option<f64>,
    /// False light over the judged pixels, a fraction; null: not judged.
    pub false_light: Option<f64>,
    /// [`Metrics::agreement`].
    pub agreement: Option<f64>,
    /// [`Metrics::ssim`].
    pub ssim: Option<f64>,
    /// [`Metrics::ssim_golden`].
    pub ssim_golden: Option<f64>,
    /// Wall time of the run including retries, milliseconds.
    pub time_ms: f64,
    /// Every figure of the judged run; null: not judged.
    pub metrics: Option<Metrics>,
    /// The checks a failing run failed (its signature).
    pub failed: Vec<FailedCheck>,
    /// [`RunResult::diagnosis`].
    pub diagnosis: Option<Diagnosis>,
    /// The command that reproduces this run alone.
    pub reproduce: String,
    /// [`RunResult::stderr`]; null when it wrote nothing.
    pub stderr: Option<String>,
}

impl ReportRun {
    /// The run as the document has it.
    pub fn of(r: &RunResult) -> ReportRun {
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
        ReportRun {
            name: r.name.clone(),
            case: r.case.clone(),
            file: r.file.clone(),
            backend: r.backend.clone(),
            golden: r.golden.clone(),
            status: r.status.name().to_string(),
            reason: r.reason.clone(),
            false_shadow: rate(|m| m.false_shadow),
            false_light: rate(|m| m.false_light),
            agreement: m.and_then(|m| m.agreement),
            ssim: m.and_then(|m| m.ssim),
            ssim_golden: m.and_then(|m| m.ssim_golden),
            time_ms: r.time_s * 1e3,
            metrics: r.metrics.clone(),
            failed: r.failed.clone(),
            diagnosis: r.diagnosis.clone(),
            reproduce: r.reproduce.clone(),
            stderr: (!r.stderr.is_empty()).then(|| r.stderr.clone()),
        }
    }
}

impl Report {
    /// The document of `results`, with the orchestrator's `header`, `budget` and `command`.
    pub fn new(
        results: &[RunResult],
        header: Header,
        budget: &TimeBudget,
        command: String,
    ) -> Report {
        Report {
            schema: SCHEMA,
            wall_s: budget.wall_s,
            time_budget: budget.clone(),
            harness_overhead_share: budget.overhead_share(),
            command,
            mesa_build: header.mesa_build,
            drivers: header.drivers,
            runs: results.iter().map(ReportRun::of).collect(),
            shards: header.shards,
        }
    }

    /// The document's text: pretty JSON, keys sorted (as through a `serde_json::Value`).
    pub fn to_json(&self) -> serde_json::Result<String> {
        serde_json::to_string_pretty(&serde_json::to_value(self)?)
    }

    /// Reads a report.json; an error names the file, and the path of the field where one is
    /// wrong (`runs[12].status: invalid type …`), or the schema it has.
    pub fn read(path: &Path) -> Result<Report, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Report::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// [`Report::read`] of a text.
    pub fn parse(text: &str) -> Result<Report, String> {
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("not JSON ({e})"))?;
        match v.get("schema").and_then(serde_json::Value::as_u64) {
            Some(s) if s == u64::from(SCHEMA) => {}
            other => {
                return Err(format!(
                    "report schema {} where this umbra reads {SCHEMA}: read it with the umbra that wrote it",
                    other.map_or("missing".to_string(), |s| s.to_string())
                ));
            }
        }
        // The path to a wrong field (`runs[12].status`), as case files name theirs.
        serde_path_to_error::deserialize(&v).map_err(|e| format!("{}: {}", e.path(), e.inner()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Status;

    fn result(name: &str, status: Status) -> RunResult {
        RunResult {
            file: "cases/c.json".into(),
            metrics: Some(Metrics {
                judged: 4,
                false_shadow: 1,
                ..Metrics::default()
            }),
            time_s: 0.5,
            reproduce: "umbra render c.json".into(),
            ..RunResult::of_test(name, status)
        }
    }

    #[test]
    fn a_report_reads_back_as_written() {
        let header = Header {
            drivers: vec![DriverRow {
                backend: "ref".into(),
                mesa: Some("22.3.6".into()),
                ..DriverRow::default()
            }],
            ..Header::default()
        };
        let results = [result("ref/c", Status::Pass), result("ref/d", Status::Fail)];
        let report = Report::new(&results, header, &TimeBudget::default(), "umbra x".into());
        let text = report.to_json().expect("writes");
        let back = Report::parse(&text).expect("reads back");
        assert_eq!(back.runs.len(), 2);
        assert_eq!(back.runs[1].status, "Fail");
        assert_eq!(back.runs[0].false_shadow, Some(0.25));
        assert_eq!(back.drivers, report.drivers);
        assert_eq!(
            back.to_json().expect("writes"),
            text,
            "a second write changes nothing"
        );
        // Keys sorted, nulls kept, as the file has always had them.
        let at = |k: &str| text.find(&format!("\"{k}\"")).expect(k);
        assert!(at("command") < at("drivers") && at("drivers") < at("runs"));
        assert!(text.contains("\"stderr\": null"));
    }

    #[test]
    fn a_wrong_field_is_named_by_its_path() {
        let report = Report::new(
            &[result("ref/c", Status::Pass)],
            Header::default(),
            &TimeBudget::default(),
            String::new(),
        );
        let mut v = serde_json::to_value(&report).expect("value");
        v["runs"][0]["status"] = serde_json::json!(3);
        let e = Report::parse(&v.to_string()).expect_err("refused");
        assert!(
            e.starts_with("runs[0].status: invalid type") && e.contains("string"),
            "{e}"
        );
        v["schema"] = serde_json::json!(2);
        let e = Report::parse(&v.to_string()).expect_err("refused");
        assert!(e.contains("schema 2"), "{e}");
    }
}
