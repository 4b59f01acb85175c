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

pub mod check;
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
pub mod summary;
pub mod timing;

pub use json::{DriverRow, Header, Report, ReportRun};
pub use model::{
    Diagnosis, FailedCheck, GoldenChange, Metrics, RunResult, Status, TimeBudget, TwinMetric,
};

/// Writes a conformance run's reports into its directory `dir`: results.csv, failures.csv,
/// errors.csv, twins.csv, goldens.csv, drivers.txt, report.json, junit.xml, report.html (the runner
/// publishes the directory as `latest` once this succeeds).
/// `failures` is where the workers wrote each failing run's pictures, `pictures` every judged
/// run's gallery pictures (one directory per run in each).
pub fn write_conformance(
    dir: &Path,
    failures: &Path,
    pictures: &Path,
    results: &[RunResult],
    drivers: &str,
    header: json::Header,
    budget: &TimeBudget,
) -> std::io::Result<()> {
    let tables = csv::tables(results);
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let report = json::Report::new(results, header, budget, command.clone());
    let junit = junit::junit(results);
    let html = html::report(results, drivers, failures, pictures, &command, budget);
    let json = report.to_json().map_err(std::io::Error::other)?;
    std::fs::create_dir_all(dir)?;
    for (name, text) in [
        ("results.csv", tables.results.as_str()),
        ("failures.csv", &tables.failures),
        ("errors.csv", &tables.errors),
        ("twins.csv", &tables.twins),
        ("goldens.csv", &tables.goldens),
        ("drivers.txt", drivers),
        ("report.json", &json),
        ("junit.xml", &junit),
        ("report.html", &html),
    ] {
        write_synced(&dir.join(name), text.as_bytes())?;
    }
    Ok(())
}

/// Writes `bytes` to `path`, flushed and synced: a full disk shows here, as an error, not
/// later as a short file.
pub fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(path)?;
    std::io::Write::write_all(&mut f, bytes)?;
    f.sync_all()
}
