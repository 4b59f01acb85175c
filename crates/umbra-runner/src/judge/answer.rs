//! What a worker answers each [`Request`] with, in the worker's process: the request's point
//! (loaded by the parent) refused if it cannot fit the memory budget; else judged (the frame
//! against truth, reference and twins, the golden, the gallery's and a failure's pictures, a
//! failing run judged again under its expectation's deviations), measured for a sweep, or
//! the backend's card measured. The worker loop ([`crate::harness::worker`]) only reads,
//! answers and restores.

use crate::judge::protocol::{JudgeRequest, Request, RunReport, RunVerdict};
use crate::judge::run::{Outcome, describe, run_point_as};
use umbra_report::Metrics;

/// The answer to `req` on `backend`: what the worker sends back. A point estimated above
/// `budget` bytes (the worker's memory budget) is refused before it is rendered.
pub fn answer(backend: &mut dyn umbra_case::Backend, req: &Request, budget: u64) -> RunReport {
    match req {
        Request::Card => card_of(backend),
        Request::Measure(m) => match fits(&m.point, budget) {
            Ok(()) => measured(backend, m.point.clone(), m.repeat),
            Err(report) => *report,
        },
        Request::Judge(j) => match fits(&j.point, budget) {
            Ok(()) => judged(backend, j.point.clone(), j),
            Err(report) => *report,
        },
    }
}

/// `Ok` when `point` fits in the memory budget; else the refused run's report, made before
/// anything is rendered.
fn fits(point: &umbra_case::CasePoint, budget: u64) -> Result<(), Box<RunReport>> {
    let triangles = umbra_case::tessellate(&point.case.scene).triangles.len();
    match umbra_case::memory::estimate(&point.case, triangles).refuse(budget) {
        None => Ok(()),
        Some(why) => Err(Box::new(RunReport {
            outcome: RunVerdict::Fail,
            reason: format!(
                "{} point {}: refused before rendering: {why}",
                point.file.display(),
                point.id()
            ),
            failed: vec![umbra_report::FailedCheck {
                check: umbra_report::check::Check::Memory,
                count: 1,
            }],
            ..Default::default()
        })),
    }
}

/// A sweep's measurement of `point` ([`crate::judge::measure`]).
fn measured(
    backend: &mut dyn umbra_case::Backend,
    point: umbra_case::CasePoint,
    n: u32,
) -> RunReport {
    use crate::judge::measure::{Measurement, measure};
    match measure(backend, point, n) {
        Measurement::Done(m) => RunReport {
            outcome: RunVerdict::Pass,
            measured: Some(m),
            ..Default::default()
        },
        Measurement::Skip(why) => RunReport {
            outcome: RunVerdict::Skip,
            reason: why,
            ..Default::default()
        },
        Measurement::Error(e) => RunReport {
            outcome: RunVerdict::Fail,
            reason: e,
            ..Default::default()
        },
    }
}

/// `point` rendered and judged as `req` asks: the frame against truth, reference and twins;
/// then the golden, the gallery's and a failure's pictures, and a failing run judged again
/// under the deviations its expectation names.
fn judged(
    backend: &mut dyn umbra_case::Backend,
    point: umbra_case::CasePoint,
    req: &JudgeRequest,
) -> RunReport {
    let name = format!("{}/{}", backend.id(), point.id());
    let (deviations, calibration) = match judging_of(req) {
        Ok(j) => j,
        Err(reason) => {
            return RunReport {
                outcome: RunVerdict::Fail,
                reason,
                ..Default::default()
            };
        }
    };
    let again = (!deviations.is_empty()).then(|| (deviations, point.clone()));
    // The stages of this run alone (the card's probes, or an earlier request, left nothing
    // that is this run's).
    crate::judge::stages::take();
    match run_point_as(
        backend,
        point,
        !req.no_twins,
        umbra_case::Deviations::NONE,
        calibration,
    ) {
        Outcome::Skip(why) => RunReport {
            outcome: RunVerdict::Skip,
            reason: why,
            ..Default::default()
        },
        Outcome::Error(e) => RunReport {
            outcome: RunVerdict::Fail,
            reason: e,
            ..Default::default()
        },
        Outcome::Done(j) => {
            let mut metrics = metrics_of(backend, &j);
            let mut problems = j.problems.clone();
            let mut failed = j.failed.clone();
            let golden_start = std::time::Instant::now();
            let mut identical_to_golden = false;
            let mut held = None;
            let golden_stage = crate::judge::stages::Stage::Golden;
            let (golden, mut storage) = crate::judge::stages::time(golden_stage, || {
                let golden = req.golden.as_ref().map(|dir| {
                    let (word, checked_held, identical) = golden_of(
                        backend,
                        dir,
                        &name,
                        &j,
                        &mut problems,
                        &mut failed,
                        &mut metrics,
                    );
                    identical_to_golden = identical;
                    held = Some(checked_held);
                    word
                });
                let storage = gallery_of(req, &name, &j, held.as_ref(), identical_to_golden);
                (golden, storage)
            });
            // Goldens and pictures: the PNG share of the time budget.
            let failing = !problems.is_empty();
            if let Some(dir) = req.failures.as_ref().filter(|_| failing) {
                let at = dir.join(umbra_report::names::file_name(&name));
                let written = crate::judge::stages::time(golden_stage, || {
                    crate::judge::pictures::write_images(&at, &j)
                });
                if let Err(e) = written {
                    storage = Some(format!("cannot write pictures under {}: {e}", at.display()));
                }
            }
            metrics.golden_ms = golden_start.elapsed().as_secs_f64() * 1e3;
            // Judged again under its expectation's deviations: judging time too (the same
            // frames, nothing rendered).
            let again_start = std::time::Instant::now();
            let under_deviation = again
                .filter(|_| failing)
                .map(|(d, point)| judged_again(backend, point, !req.no_twins, d, &j));
            metrics.judge_ms += again_start.elapsed().as_secs_f64() * 1e3;
            metrics.stages_ms = crate::judge::stages::take();
            RunReport {
                under_deviation,
                storage,
                outcome: if failing {
                    RunVerdict::Fail
                } else {
                    RunVerdict::Pass
                },
                reason: problems.join("; "),
                details: describe(&j),
                metrics: Some(metrics),
                golden,
                measured: None,
                failed,
                fingerprint: (!j.fingerprint.is_empty()).then(|| j.fingerprint.clone()),
                retired: None,
                card: None,
            }
        }
    }
}

/// The checks a failing run still fails judged again under the deviations `d` its
/// expectation names: what the deviation does not explain. By the spec and the deviation
/// alone: a modelled deviation is where the driver departs from what its card's probes read
/// (softpipe's Z16 span stepping is not its probed rounding), so no card narrows it. The
/// frames judged are the run's own (`j`'s, its twins' too): nothing is rendered again.
fn judged_again(
    backend: &mut dyn umbra_case::Backend,
    point: umbra_case::CasePoint,
    twins: bool,
    d: umbra_case::Deviations,
    j: &crate::judge::run::Judged,
) -> Vec<umbra_report::FailedCheck> {
    match crate::judge::run::judge_again(backend, point, twins, d, j) {
        Outcome::Done(j) => j.failed,
        // Judged again, it did not render: the check that fails is rendering.
        Outcome::Skip(_) | Outcome::Error(_) => vec![umbra_report::FailedCheck {
            check: umbra_report::check::Check::Render,
            count: 1,
        }],
    }
}

/// The deviations and the calibration a request names, or why they are not ones.
fn judging_of(
    req: &JudgeRequest,
) -> Result<(umbra_case::Deviations, umbra_case::Calibration), String> {
    let deviations = umbra_case::Deviations::parse(req.deviation.as_deref().unwrap_or(""))
        .map_err(|d| format!("unknown deviation {d:?} in the request"))?;
    let calibration = umbra_case::Calibration::parse(req.calibration.as_deref().unwrap_or(""))
        .map_err(|bad| format!("bad calibration in the request: {bad}"))?;
    Ok((deviations, calibration))
}

/// Writes the run's gallery pictures (`req.gallery`, beside its golden and any pending one);
/// what could not be written.
/// The backend's behaviour card, measured now.
fn card_of(backend: &mut dyn umbra_case::Backend) -> RunReport {
    let t0 = std::time::Instant::now();
    let info = backend.info();
    let facts = crate::judge::expectations::DriverFacts::from_driver(
        &info.version,
        &info.renderer,
        &info.extensions,
    );
    let (entries, renders) = crate::judge::card_probes::measure(backend);
    RunReport {
        outcome: RunVerdict::Pass,
        card: Some(crate::judge::card::Card {
            backend: backend.id().0,
            driver: format!("{} | {}", info.renderer, info.version),
            release: crate::judge::card::release_of(&backend.id().0, &facts, &info.version),
            entries,
            renders,
            seconds: t0.elapsed().as_secs_f64(),
        }),
        ..Default::default()
    }
}

fn gallery_of(
    req: &JudgeRequest,
    name: &str,
    j: &crate::judge::run::Judged,
    held: Option<&crate::judge::golden::Held>,
    identical_to_golden: bool,
) -> Option<String> {
    let mut storage = None;
    if let Some(dir) = &req.gallery {
        let golden = held.map(|h| {
            let stem = crate::judge::golden::stem(name);
            (
                h.file
                    .clone()
                    .unwrap_or_else(|| h.write_dir.join(format!("{stem}.snap.png"))),
                h.write_dir.join(format!("{stem}.snap.new.png")),
            )
        });
        let at = dir.join(umbra_report::names::file_name(name));
        if let Err(e) = crate::judge::pictures::write_gallery(
            &at,
            j,
            golden.as_ref().map(|(a, b)| (a.as_path(), b.as_path())),
            identical_to_golden,
        ) {
            storage = Some(format!("cannot write pictures under {}: {e}", at.display()));
        }
    }
    storage
}

/// The figures of a judged run (report.json's `metrics`), before its golden check.
fn metrics_of(backend: &dyn umbra_case::Backend, j: &crate::judge::run::Judged) -> Metrics {
    let e = &j.error;
    let t = &j.frame.timings;
    Metrics {
        judged: e.all.judged,
        false_shadow: e.all.false_shadow,
        false_light: e.all.false_light,
        interior_judged: e.away_from_edges.judged,
        interior_false_shadow: e.away_from_edges.false_shadow,
        interior_false_light: e.away_from_edges.false_light,
        edge_px: e.edge_pixels,
        silhouette: e.silhouette,
        faces_away: e.faces_away,
        outside: e.outside,
        agreement: j.agreement.as_ref().map(|a| {
            if a.compared == 0 {
                1.0
            } else {
                1.0 - a.differ as f64 / a.compared as f64
            }
        }),
        illegal: j.agreement.as_ref().map(|a| a.illegal),
        reference: j.agreement.clone(),
        reference_card: j.card.as_ref().map(|c| c.agreement.clone()),
        judged_as_card: j
            .card
            .as_ref()
            .map_or_else(String::new, |c| c.judged_as.clone()),
        profile: backend.profile().name(),
        judged_as: backend.profile().effective_for(j.prepared.case()).name(),
        visibility_storage: j.frame.visibility_storage.name().into(),
        ssim: j.ssim,
        ssim_golden: None,
        golden_change: None,
        shadow_ms: t.shadow_pass.as_secs_f64() * 1e3,
        lit_ms: t.lit_pass.as_secs_f64() * 1e3,
        total_ms: t.total.as_secs_f64() * 1e3,
        clock: if t.clock == Some(umbra_case::Clock::Gpu) {
            "gpu".into()
        } else {
            "cpu-wall".into()
        },
        twins: j.twins.clone(),
        judge_ms: j.judge_time.as_secs_f64() * 1e3,
        twins_ms: j.twins_time.as_secs_f64() * 1e3,
        golden_ms: 0.0,
        kind: crate::judge::stages::run_kind(j.prepared.case()),
        stages_ms: Default::default(),
        color_hash: umbra_report::names::fnv64(j.frame.color.iter().copied()),
        // Every light's visibility, light after light (one light's is the light's alone).
        visibility_hash: umbra_report::names::fnv64(
            j.frame
                .lights
                .iter()
                .flat_map(|p| &p.visibility)
                .flat_map(|v| v.to_bits().to_le_bytes()),
        ),
    }
}

/// Checks the run's colour against its golden in `dir` ([`crate::judge::golden::check`]): its
/// word for the report, the golden that held and whether the frame is that golden pixel for
/// pixel; a change to review adds its problem and a failed `golden` check.
fn golden_of(
    backend: &dyn umbra_case::Backend,
    dir: &std::path::Path,
    name: &str,
    j: &crate::judge::run::Judged,
    problems: &mut Vec<String>,
    failed: &mut Vec<umbra_report::FailedCheck>,
    metrics: &mut Metrics,
) -> (String, crate::judge::golden::Held, bool) {
    let info = backend.info();
    let driver = crate::judge::expectations::reported_version(
        [info.version.as_str(), info.renderer.as_str()]
            .into_iter()
            .chain(info.extensions.iter().map(String::as_str)),
    );
    let checked = crate::judge::golden::check(
        dir,
        &crate::judge::golden::Subject {
            backend: &backend.id().0,
            name,
            driver: driver.as_deref(),
        },
        &j.frame,
        &j.legal,
        &j.pixels,
        problems.is_empty(),
    );
    metrics.ssim_golden = checked.ssim;
    metrics.golden_change = checked.change.clone();
    let foreign = !checked.held.strict;
    if checked.golden == crate::judge::golden::Golden::Changed {
        problems.push(checked.message);
        failed.push(umbra_report::FailedCheck {
            check: umbra_report::check::Check::Golden,
            count: 1,
        });
    }
    (
        checked.golden.word(foreign).to_string(),
        checked.held,
        checked.identical,
    )
}
