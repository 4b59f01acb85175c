//! `umbra timing [REPORT]`: where a conformance run's worker time went, per kind of run (or
//! per backend) and per stage of judging ([`umbra_report::timing`], from the stage clock of
//! [`crate::judge::stages`]). The profile table of docs/performance.md is its output.

use crate::cli::{TimingArgs, TimingBy};
use crate::exit::{Error, Exit, Outcome};

/// Runs `umbra timing`; returns its outcome.
pub fn main(args: &TimingArgs) -> Outcome {
    let path = if args.report.is_dir() {
        args.report.join("report.json")
    } else {
        args.report.clone()
    };
    let report = umbra_report::json::Report::read(&path).map_err(|e| {
        Error::new(format!(
            "{e} (umbra timing reads the report.json of a conformance or soak run: give the file or its run directory)"
        ))
    })?;
    let by = match args.by {
        TimingBy::Kind => umbra_report::timing::By::Kind,
        TimingBy::Backend => umbra_report::timing::By::Backend,
    };
    let table = umbra_report::timing::table(&report, by)
        .map_err(|e| Error::new(format!("{}: {e}", path.display())))?;
    print!("{table}");
    print!("\n{}", umbra_report::timing::twins_table(&report));
    let b = &report.time_budget;
    println!(
        "\n{} runs; {:.1} s of worker time in {:.1} s wall (worker start {:.1} s, not in any row)",
        report.runs.len(),
        b.runs_s,
        b.wall_s,
        b.worker_start_s
    );
    Ok(Exit::Pass)
}
