//! A conformance run's third step: what the workers found gathered into one sorted result
//! list with the cross-run checks (the consensus across drivers, `expect.error_falls_along`),
//! the run's record (what `umbra merge` checks shards against), every report written into
//! the run's directory, and blessings recorded.

use std::path::{Path, PathBuf};

use super::execute::Collected;
use super::plan::Options;
use super::summary::drivers_text;
use super::{Extra, Finished, Settings};
use crate::exit::{Error, Exit};
use crate::judge::falls_along::FallsAlong;
use crate::run_dir::RunDir;
use umbra_report::{RunResult, TimeBudget};

/// What the run found, put together: every result sorted by name and diagnosed (the
/// `expect.error_falls_along` series, the consensus), drivers.txt and report.json's driver rows.
pub(crate) struct Gathered {
    pub(crate) results: Vec<RunResult>,
    /// The results before the checks across runs (the run's record keeps them).
    pub(crate) before_cross: Vec<RunResult>,
    /// drivers.txt's lines of each backend, by backend.
    pub(crate) driver_lines: Vec<(String, String)>,
    pub(crate) driver_rows: Vec<umbra_report::DriverRow>,
    pub(crate) refused: Vec<String>,
    pub(crate) unavailable_runs: usize,
    pub(crate) build: Option<&'static crate::harness::mesa_build::MesaBuild>,
}

/// The verdicts of the runs that finished, for a run that will not be published
/// (interrupted, or a full disk): results.csv, failures.csv, errors.csv and junit.xml of those
/// runs, sorted by name, as far as they can be written. Their pictures are there already.
pub(crate) fn write_partial(dir: &Path, results: &mut [RunResult]) {
    results.sort_by(|a, b| a.name.cmp(&b.name));
    let tables = umbra_report::csv::tables(results);
    for (name, text) in [
        ("results.csv", tables.results),
        ("failures.csv", tables.failures),
        ("errors.csv", tables.errors),
        ("junit.xml", umbra_report::junit::junit(results)),
    ] {
        // A short file (a full disk) would read as fewer runs: none rather than that.
        if umbra_report::write_synced(&dir.join(name), text.as_bytes()).is_err() {
            let _ = std::fs::remove_file(dir.join(name));
        }
    }
}

/// Puts the workers' findings together. An interrupted run (130) or one whose pictures could
/// not be written (125, a full disk) is abandoned here, saying so: its report would be
/// incomplete, so `latest` keeps pointing at the last whole one.
pub(crate) fn gather(
    collected: Collected,
    opts: &Options,
    falls_along: &[FallsAlong],
    run_dir: &RunDir,
) -> Result<Gathered, Finished> {
    let Collected {
        mut results,
        drivers,
        mut driver_rows,
        refused,
        unavailable_runs,
        progress,
        storage,
        total,
        ..
    } = collected;
    progress.close();
    if crate::harness::interrupt::requested().is_some() || !storage.is_empty() {
        write_partial(&run_dir.dir, &mut results);
    }
    if let Some(sig) = crate::harness::interrupt::requested() {
        run_dir.abandon(&format!(
            "interrupted by {} after {} of {total} runs",
            crate::harness::interrupt::name(sig),
            results.len()
        ));
        return Err(Finished {
            outcome: Err(Error::said(Exit::Interrupted)),
            results,
        });
    }
    if let Some(first) = storage.first() {
        run_dir.abandon(&format!(
            "{} run(s) could not write their pictures ({first})",
            storage.len()
        ));
        return Err(Finished {
            outcome: Err(Error::said(Exit::CouldNotRun)),
            results,
        });
    }
    driver_rows.sort_by(|a, b| a.backend.cmp(&b.backend));
    let mut driver_lines = drivers;
    driver_lines.sort();
    results.sort_by(|a, b| a.name.cmp(&b.name));
    let before_cross = results.clone();
    for m in falls_along {
        m.judge(&mut results);
    }
    crate::judge::consensus::diagnose(&mut results);
    Ok(Gathered {
        results,
        before_cross,
        driver_lines,
        driver_rows,
        refused,
        unavailable_runs,
        build: opts.build,
    })
}

/// drivers.txt's first line: the Mesa build the run used.
pub(crate) fn mesa_line(build: Option<&crate::harness::mesa_build::MesaBuild>) -> String {
    format!(
        "Mesa: {}",
        build.map_or("the system's".to_string(), |b| b.describe())
    )
}

/// The run's record for `umbra merge` ([`crate::shards::record`]).
pub(crate) fn record(
    opts: &Options,
    names: Vec<String>,
    falls_along: Vec<FallsAlong>,
    g: &Gathered,
    budget: &TimeBudget,
) -> crate::shards::record::Record {
    use crate::shards::record as rec;
    let drivers = g
        .driver_lines
        .iter()
        .map(|(backend, text)| rec::DriverRecord {
            backend: backend.clone(),
            text: text.clone(),
            row: g
                .driver_rows
                .iter()
                .find(|r| &r.backend == backend)
                .cloned()
                .unwrap_or_default(),
        })
        .collect();
    let fingerprints = g
        .before_cross
        .iter()
        .filter_map(|r| Some((r.name.clone(), r.fingerprint.clone()?)))
        .collect();
    rec::Record {
        schema: rec::SCHEMA,
        umbra: rec::Build::this(),
        inputs: opts.inputs.clone(),
        mesa_build: serde_json::to_value(g.build).unwrap_or_default(),
        mesa_line: mesa_line(g.build),
        shard: rec::ShardRecord {
            index: opts.shard.0,
            count: opts.shard.1,
            by: opts.by.describe(),
        },
        settings: rec::Settings {
            timeout_s: opts.timeout.as_secs(),
            bless: opts.bless,
        },
        plan: rec::PlanRecord {
            filter: opts.filter.clone(),
            backends: opts.backends.clone(),
            runs: names,
        },
        budget: budget.clone(),
        drivers,
        refused: g.refused.clone(),
        unavailable_runs: g.unavailable_runs,
        falls_along,
        runs: g.before_cross.clone(),
        fingerprints,
    }
}

/// Writes the reports and the run's record into the run directory and publishes it
/// (`latest`); when they cannot be written, the run directory is abandoned (saying so) and
/// the error is said (125).
pub(crate) fn write_reports(
    g: &Gathered,
    settings: &Settings,
    budget: &TimeBudget,
    run_dir: &RunDir,
    record: &crate::shards::record::Record,
    extra: Option<Extra>,
) -> Result<(), Error> {
    let header = umbra_report::Header {
        mesa_build: serde_json::json!(g.build),
        drivers: g.driver_rows.clone(),
        shards: None,
    };
    let written = umbra_report::write_conformance(
        &run_dir.dir,
        &settings.failures,
        &settings.gallery,
        &g.results,
        &drivers_text(&mesa_line(g.build), &g.driver_lines),
        header,
        budget,
    )
    .and_then(|()| record.write(&run_dir.dir))
    .and_then(|()| extra.map_or(Ok(()), |f| f(&run_dir.dir, &g.results)))
    .and_then(|()| run_dir.publish());
    written.map_err(|e| {
        run_dir.abandon(&format!("cannot write the reports: {e}"));
        Error::said(Exit::CouldNotRun)
    })
}

/// Blessing (`cargo xtask bless`): records the driver each backend's goldens now match, the
/// backend's entry (kept if already recorded), then each golden written now whose version
/// differs from what the manifest already says for it (its backend's, usually).
pub(crate) fn record_blessings(g: &Gathered, settings: &Settings) {
    let Some(dir) = &settings.golden else {
        return;
    };
    let version_of = |b: &str| {
        g.driver_rows
            .iter()
            .find(|r| r.backend == b)
            .and_then(|r| r.mesa.clone())
    };
    let mut entries: Vec<(String, String)> = Vec::new();
    for r in &g.results {
        let Some(v) = version_of(&r.backend) else {
            continue;
        };
        if r.golden.is_some() && !entries.iter().any(|(k, _)| *k == r.backend) {
            entries.push((r.backend.clone(), v.clone()));
        }
        if r.golden.as_deref() == Some("written")
            && crate::judge::golden::blessed_on(dir, &r.backend, &r.name).as_deref()
                != Some(v.as_str())
        {
            entries.push((crate::judge::golden::stem(&r.name), v));
        }
    }
    // Goldens of another release this bless compared and found unchanged: confirmed on this
    // one, so they hold strictly here too (exactly those: a filtered bless confirms what it
    // ran).
    let mut confirm: std::collections::BTreeMap<String, Vec<(String, PathBuf)>> =
        Default::default();
    for r in g
        .results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("unchanged"))
    {
        let Some(v) = version_of(&r.backend) else {
            continue;
        };
        let held = crate::judge::golden::held(
            dir,
            &crate::judge::golden::Subject {
                backend: &r.backend,
                name: &r.name,
                driver: Some(&v),
            },
        );
        let other_release = held
            .blessed_on
            .as_deref()
            .is_some_and(|b| !crate::judge::golden::same_release(b, &v));
        // A golden of another release is the golden directory's own (one in this release's
        // folder was blessed on this release: `held` says so).
        if let (true, Some(file)) = (other_release, held.file) {
            confirm
                .entry(v.clone())
                .or_default()
                .push((crate::judge::golden::stem(&r.name), file));
        }
    }
    for (v, goldens) in &confirm {
        if let Err(e) = crate::judge::golden::record_confirmed(dir, v, goldens) {
            eprintln!(
                "error: cannot record the goldens confirmed on Mesa {v} in {}: {e}",
                crate::judge::golden::release_dir(dir, v).display()
            );
        }
    }
    // Nothing Mesa-backed was blessed: the manifest stays as it is.
    if !entries.is_empty() {
        if let Err(e) = crate::judge::golden::record_blessed(dir, &entries) {
            eprintln!(
                "error: cannot record the blessed drivers in {}: {e}",
                dir.display()
            );
        }
    }
}
