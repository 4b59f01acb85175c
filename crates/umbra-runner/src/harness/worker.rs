//! `umbra worker --backend ID`: one backend in one process, fed runs on stdin.
//!
//! Protocol, one JSON object per line:
//! - worker → parent, once: a [`Hello`] (`{"ready": {...}}`, `{"unavailable": "reason"}` or
//!   `{"refused": "reason"}`);
//! - parent → worker: `{"file": "cases/x.json", "index": 3, "failures": "target/umbra/..."}`;
//! - worker → parent: a [`RunReport`].
//!
//! The context or device is created once and reused. The parent owns timeouts and crashes: a
//! worker that stops answering is killed, one that dies is noticed at end of input, and a
//! fresh worker takes the remaining runs.

use std::io::{BufRead, Write};
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::exit::Exit;
use crate::judge::run::{Outcome, describe, run_point_as};
use umbra_report::Metrics;

/// What a worker says once, when it has started: its driver, or why it cannot run. On the
/// wire, `{"ready": {...}}`, `{"unavailable": "why"}` or `{"refused": "why"}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hello {
    /// The backend came up on this driver.
    Ready(Ready),
    /// The backend cannot run here (a missing driver or device): its runs are skips.
    Unavailable(String),
    /// The `--mesa` build asked for lacks the driver, or it loaded from elsewhere: never a
    /// silent run on the system's Mesa.
    Refused(String),
}

/// The driver a ready worker runs on.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Ready {
    /// GL_VENDOR, or the adapter's vendor.
    pub vendor: String,
    /// GL_RENDERER, or the adapter's name.
    pub renderer: String,
    /// GL_VERSION, or the adapter's driver version.
    pub version: String,
    /// What the backend reports beside them (extensions, wgpu's driver notes).
    pub extensions: Vec<String>,
    /// The device and how it is reached.
    pub device: String,
    /// How long creating the context or device took, ms.
    pub create_ms: f64,
    /// The `--mesa` build it runs on, described.
    pub build: Option<String>,
    /// The Mesa libraries the process loaded.
    pub mesa_libs: Vec<PathBuf>,
}

impl Hello {
    /// The driver, when the worker is ready.
    pub fn ready(&self) -> Option<&Ready> {
        match self {
            Hello::Ready(r) => Some(r),
            _ => None,
        }
    }

    /// Why the backend cannot run here, when it cannot.
    pub fn unavailable(&self) -> Option<&str> {
        match self {
            Hello::Unavailable(why) => Some(why),
            _ => None,
        }
    }

    /// The driver's facts that select expectations (none where it did not come up).
    pub fn facts(&self) -> crate::judge::expectations::DriverFacts {
        self.ready().map_or_else(Default::default, |r| {
            crate::judge::expectations::DriverFacts::from_driver(
                &r.version,
                &r.renderer,
                &r.extensions,
            )
        })
    }

    /// Why the Mesa build was refused, when it was.
    pub fn refused(&self) -> Option<&str> {
        match self {
            Hello::Refused(why) => Some(why),
            _ => None,
        }
    }
}

/// A request for one run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Request {
    /// The case file.
    pub file: PathBuf,
    /// The sweep point's index in the file's expansion.
    pub index: usize,
    /// Where to write the pictures of a failing run (none: do not write).
    pub failures: Option<PathBuf>,
    /// The golden directory (none: no golden check).
    pub golden: Option<PathBuf>,
    /// For `umbra sweep`: render 1 + N times and report timings and error only (no
    /// reference, twins or goldens).
    #[serde(default)]
    pub repeat: Option<u32>,
    /// Skip the metamorphic twins (the self-test judges the frame alone).
    #[serde(default)]
    pub no_twins: bool,
    /// Where to write every judged run's gallery pictures (thumbnail, colour, heat map,
    /// reference, truth, golden; none: do not write).
    #[serde(default)]
    pub gallery: Option<PathBuf>,
    /// Modelled driver deviations ([`umbra_case::Deviation`] names joined by `+`): a failing
    /// run is judged again with them allowed, and the checks that still fail are reported
    /// ([`RunReport::under_deviation`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deviation: Option<String>,
    /// Measure the backend's behaviour card instead (`file` and `index` unused): the probes
    /// of [`crate::judge::card_probes`], answered in [`RunReport::card`].
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub card: bool,
    /// The backend's card read as a narrowing ([`umbra_case::Calibration::encode`]): the run
    /// is judged a second time against it (calibrated judging); none: by the spec alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<String>,
}

impl Request {
    /// A request for the backend's behaviour card.
    pub fn card() -> Request {
        Request {
            file: PathBuf::new(),
            index: 0,
            failures: None,
            golden: None,
            repeat: None,
            no_twins: true,
            gallery: None,
            deviation: None,
            card: true,
            calibration: None,
        }
    }
}

/// A run's raw verdict, before expectations (the parent's business).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunVerdict {
    /// Every check held.
    Pass,
    /// A check failed, or the run could not be made (the reason says which).
    #[default]
    Fail,
    /// The backend cannot run this case (the reason says why).
    Skip,
}

impl std::fmt::Display for RunVerdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RunVerdict::Pass => "pass",
            RunVerdict::Fail => "fail",
            RunVerdict::Skip => "skip",
        })
    }
}

/// What one run produced (the raw outcome; expectations are the parent's business).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunReport {
    /// Pass, fail or skip (`"pass"`, `"fail"`, `"skip"` on the wire).
    pub outcome: RunVerdict,
    /// Why, for fail and skip.
    pub reason: String,
    /// The multi-line description of a judged run.
    pub details: String,
    /// Error figures and timings of a judged run.
    pub metrics: Option<Metrics>,
    /// `unchanged`, `written` or `changed` when a golden was checked.
    pub golden: Option<String>,
    /// A sweep measurement (requests with `repeat`).
    #[serde(default)]
    pub measured: Option<crate::harness::measure::Measured>,
    /// The checks a failing run failed, with their pixel counts (what expectations match).
    #[serde(default)]
    pub failed: Vec<umbra_report::FailedCheck>,
    /// Where a judged run broke the model, when it did anywhere (the consensus diagnosis
    /// compares it across drivers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fingerprint: Option<umbra_compare::consensus::Fingerprint>,
    /// For a failing run of a request with a deviation: the checks that still fail when it is
    /// judged with the deviation allowed (empty: the deviation explains the failure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub under_deviation: Option<Vec<umbra_report::FailedCheck>>,
    /// A picture of the run that could not be written (a full disk): the run's judgement
    /// stands, but its report would be incomplete, so the conformance run is not published.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub storage: Option<String>,
    /// Set when the run failed and the backend could not be returned to a fresh state
    /// ([`umbra_case::Backend::restore`]): why. The worker exits after this answer and the
    /// parent starts a fresh one for the next run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retired: Option<String>,
    /// The behaviour card, for a card request.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub card: Option<crate::judge::card::Card>,
}

/// Runs the worker loop; returns its outcome (it passes when the backend could not come up
/// too: the hello says so, and the parent reads it).
/// `id`: the backend it hosts (`umbra worker --backend ID`).
pub fn main(id: &str) -> crate::exit::Outcome {
    crate::harness::orphan::watch();
    // A fault in the driver (or here) names its address's mapping and the faulting library
    // on stderr before the signal ends the worker: the crash's reason says whose it is.
    crate::harness::crash_report::install();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let created = std::time::Instant::now();
    // On a Mesa build (`--mesa`), a backend whose driver the build lacks is a skip, and one
    // whose driver does not load, or loads from elsewhere, is refused: never a silent run
    // on the system's Mesa.
    let build = std::env::var(crate::harness::mesa_build::ENV)
        .ok()
        .filter(|_| crate::harness::mesa_build::is_mesa_backed(id))
        .map(|root| crate::harness::mesa_build::MesaBuild::open(std::path::Path::new(&root)));
    let say = |out: &mut std::io::StdoutLock, hello: Hello| {
        let _ = writeln!(out, "{}", serde_json::to_string(&hello).unwrap_or_default());
        let _ = out.flush();
    };
    let build = match build {
        Some(Err(e)) => {
            say(&mut out, Hello::Refused(format!("--mesa: {e}")));
            return Ok(Exit::Pass);
        }
        Some(Ok(b)) => {
            if let Some(why) = b.lacks(id) {
                say(&mut out, Hello::Unavailable(why.to_string()));
                return Ok(Exit::Pass);
            }
            // A build with its own C library: this process continues on it (re-executed).
            if let Err(e) = b.enter() {
                say(&mut out, Hello::Refused(format!("{id}: {e}")));
                return Ok(Exit::Pass);
            }
            Some(b)
        }
        None => None,
    };
    let mut backend = match crate::harness::registry::create(id) {
        Ok(b) => {
            let i = b.info();
            let create_ms = created.elapsed().as_secs_f64() * 1e3;
            let libs = crate::harness::mesa_build::loaded_libs();
            if let Some(build) = &build {
                if build.layout != "fake (tests)" {
                    if let Err(e) = crate::harness::mesa_build::check_loaded(&build.root, &libs) {
                        say(&mut out, Hello::Refused(format!("{id}: {e}")));
                        return Ok(Exit::Pass);
                    }
                }
            }
            let hello = Hello::Ready(Ready {
                vendor: i.vendor,
                renderer: i.renderer,
                version: i.version,
                extensions: i.extensions,
                device: i.device,
                create_ms,
                build: build.as_ref().map(|b| b.describe()),
                mesa_libs: libs,
            });
            say(&mut out, hello);
            b
        }
        Err(e) => {
            let v = match &build {
                // The build has the driver (lacks() said so), yet it did not come up.
                Some(b) => Hello::Refused(format!(
                    "{id}: the driver of the Mesa build in {} did not load: {e}",
                    b.root.display()
                )),
                None => Hello::Unavailable(e.to_string()),
            };
            say(&mut out, v);
            return Ok(Exit::Pass);
        }
    };
    for line in std::io::stdin().lock().lines() {
        let Ok(line) = line else { break };
        let mut report = match serde_json::from_str::<Request>(&line) {
            Ok(req) => handle(backend.as_mut(), &req),
            Err(e) => RunReport {
                outcome: RunVerdict::Fail,
                reason: format!("bad request: {e}"),
                ..Default::default()
            },
        };
        // A failed run's errors stay in that run: the backend restores its state (GL errors
        // drained, queries ended, defaults bound), or this worker retires.
        if report.outcome == RunVerdict::Fail {
            report.retired = backend.restore().err();
        }
        // The end of this run's stderr, before its answer (the parent waits for it).
        eprintln!("{}", crate::harness::stderr_log::MARK);
        let _ = writeln!(
            out,
            "{}",
            serde_json::to_string(&report).unwrap_or_default()
        );
        let _ = out.flush();
        if report.retired.is_some() {
            break;
        }
    }
    Ok(Exit::Pass)
}

fn handle(backend: &mut dyn umbra_case::Backend, req: &Request) -> RunReport {
    if req.card {
        return card_of(backend);
    }
    let points = match umbra_case::load_file(&req.file) {
        Ok(p) => p,
        Err(e) => {
            return RunReport {
                outcome: RunVerdict::Fail,
                reason: e.to_string(),
                ..Default::default()
            };
        }
    };
    let Some(point) = points.into_iter().nth(req.index) else {
        return RunReport {
            outcome: RunVerdict::Fail,
            reason: format!("{} has no sweep point {}", req.file.display(), req.index),
            ..Default::default()
        };
    };
    let name = format!("{}/{}", backend.id(), point.id());
    // Refuse, before rendering, a run whose case cannot fit in the memory budget.
    let triangles = umbra_case::tessellate(&point.case.scene).triangles.len();
    if let Some(why) = umbra_case::memory::estimate(&point.case, triangles)
        .refuse(crate::harness::memory_limit::budget())
    {
        return RunReport {
            outcome: RunVerdict::Fail,
            reason: format!(
                "{} point {}: refused before rendering: {why}",
                req.file.display(),
                point.id()
            ),
            failed: vec![umbra_report::FailedCheck {
                check: umbra_report::check::Check::Memory,
                count: 1,
            }],
            ..Default::default()
        };
    }
    if let Some(n) = req.repeat {
        use crate::harness::measure::{Measurement, measure};
        return match measure(backend, point, n) {
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
        };
    }
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
            let mut storage = gallery_of(req, &name, &j, held.as_ref(), identical_to_golden);
            // Goldens and pictures: the PNG share of the time budget.
            metrics.golden_ms = golden_start.elapsed().as_secs_f64() * 1e3;
            let failing = !problems.is_empty();
            if let Some(dir) = req.failures.as_ref().filter(|_| failing) {
                let at = dir.join(umbra_report::names::file_name(&name));
                if let Err(e) = crate::judge::pictures::write_images(&at, &j) {
                    storage = Some(format!("cannot write pictures under {}: {e}", at.display()));
                }
            }
            let under_deviation = again
                .filter(|_| failing)
                .map(|(d, point)| judged_again(backend, point, !req.no_twins, d));
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
/// (softpipe's Z16 span stepping is not its probed rounding), so no card narrows it.
fn judged_again(
    backend: &mut dyn umbra_case::Backend,
    point: umbra_case::CasePoint,
    twins: bool,
    d: umbra_case::Deviations,
) -> Vec<umbra_report::FailedCheck> {
    match run_point_as(backend, point, twins, d, Default::default()) {
        Outcome::Done(j) => j.failed,
        // Judged again, it did not render: the check that fails is rendering.
        Outcome::Skip(_) | Outcome::Error(_) => vec![umbra_report::FailedCheck {
            check: umbra_report::check::Check::Render,
            count: 1,
        }],
    }
}

/// The deviations and the calibration a request names, or why they are not ones.
fn judging_of(req: &Request) -> Result<(umbra_case::Deviations, umbra_case::Calibration), String> {
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
    req: &Request,
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
