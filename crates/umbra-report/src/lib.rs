//! umbra's reporting layer: the results model and the writers that turn it into files.
//!
//! Layers depend one way only (no module of this crate knows how runs are scheduled or
//! judged):
//!
//! ```text
//! umbra-case (conventions, case format) ← umbra-ref, umbra-compare (reference, truth, judging)
//!     ← umbra-report (model → csv, junit, json, html, error_curves, pareto)
//!     ← umbra-runner (orchestration: workers, pool, expectations; commands)
//! ```
//!
//! [`model`] is what a run produced; each writer is a function of the model and nothing else
//! (pictures are read from the directory the orchestrator wrote them to, named by
//! [`names::file_name`]). [`write_conformance`] writes the whole set for a conformance run.

use std::path::Path;

pub mod csv;
pub mod error_curves;
pub mod escape;
pub mod gallery;
pub mod html;
pub mod json;
pub mod junit;
pub mod model;
pub mod names;
pub mod pareto;

pub use model::{Diagnosis, FailedCheck, Metrics, RunResult, Status, TimeBudget, TwinMetric};

/// Writes a conformance run's reports into `out/latest` and `out/runs/STAMP`: results.csv,
/// failures.csv, errors.csv, twins.csv, drivers.txt, report.json, junit.xml, report.html.
/// `failures` is where the workers wrote each failing run's pictures, `pictures` every judged
/// run's gallery pictures (one directory per run in each).
pub fn write_conformance(
    out: &Path,
    failures: &Path,
    pictures: &Path,
    results: &[RunResult],
    drivers: &str,
    header: &serde_json::Value,
    budget: &TimeBudget,
) -> std::io::Result<()> {
    let tables = csv::tables(results);
    let report = json::report(results, header, budget);
    let junit = junit::junit(results);
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let html = html::report(results, drivers, failures, pictures, &command, budget);
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    for dir in [out.join("latest"), out.join("runs").join(stamp.to_string())] {
        std::fs::create_dir_all(&dir)?;
        std::fs::write(dir.join("results.csv"), &tables.results)?;
        std::fs::write(dir.join("failures.csv"), &tables.failures)?;
        std::fs::write(dir.join("errors.csv"), &tables.errors)?;
        std::fs::write(dir.join("twins.csv"), &tables.twins)?;
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
