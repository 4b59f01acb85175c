//! A conformance run's second step: the plan executed, one group per backend, each on its
//! own worker sessions through the one scheduler ([`crate::harness::scheduler`]); a
//! failure rerun once (a changed result is a Flake); each backend's driver described from its
//! worker's hello, and its behaviour card measured once for its card row and calibration.

use std::collections::{BTreeMap, VecDeque};
use std::fmt::Write as _;
use std::sync::Mutex;
use std::time::Instant;

use super::{Planned, Settings, first_line};
use crate::exit::Error;
use crate::harness::scheduler::{Attempt, NotReady, Session};
use crate::harness::worker::Hello;
use crate::judge::expectations::Expectations;
use crate::judge::protocol::{JudgeRequest, Request};
use umbra_report::escape::shell_word;
use umbra_report::{RunResult, Status};

/// Runs the plan: its runs grouped by backend, each backend's rotated by its share (so
/// concurrent workers rarely reach a point whose judging basis is not cached yet at the same
/// moment; the second would wait for the first, see judge_cache), `jobs` threads each working
/// on one backend at a time ([`crate::harness::scheduler::run_queues`], [`run_group`]).
pub(crate) fn execute(
    plan: Vec<Planned>,
    results: Vec<RunResult>,
    settings: &Settings,
    jobs: usize,
) -> Result<Collected, Error> {
    let mut groups: BTreeMap<String, VecDeque<Planned>> = BTreeMap::new();
    for p in plan {
        groups.entry(p.backend.clone()).or_default().push_back(p);
    }
    let cards = if settings.cards.is_some() {
        groups.len()
    } else {
        0
    };
    let total = groups.values().map(VecDeque::len).sum::<usize>() + cards;
    let n = groups.len().max(1);
    for (k, runs) in groups.values_mut().enumerate() {
        let offset = k * runs.len() / n;
        runs.rotate_left(offset);
    }
    let done = Mutex::new(Collected {
        results,
        progress: crate::harness::progress::Progress::new(total),
        total,
        ..Default::default()
    });
    crate::harness::scheduler::run_queues(groups, jobs, |backend, first, next| {
        run_group(backend, next, first, settings, &done, total)
    });
    done.into_inner()
        .map_err(|_| Error::new("a worker thread panicked"))
}

/// What the backend groups collect while they run.
#[derive(Default)]
pub(crate) struct Collected {
    pub(crate) results: Vec<RunResult>,
    /// drivers.txt's lines of each backend.
    pub(crate) drivers: Vec<(String, String)>,
    /// report.json's `drivers`: per backend, the driver, the build and the expectation files
    /// that applied.
    pub(crate) driver_rows: Vec<umbra_report::DriverRow>,
    /// Backends whose worker refused the Mesa build (fell back, or its driver did not load).
    pub(crate) refused: Vec<String>,
    pub(crate) unavailable_runs: usize,
    pub(crate) finished: usize,
    /// Pictures that could not be written (a full disk), one line per run: the run's
    /// report would be incomplete, so it is not published.
    pub(crate) storage: Vec<String>,
    /// What the terminal shows while the run goes on.
    pub(crate) progress: crate::harness::progress::Progress,
    /// How many runs the plan holds.
    pub(crate) total: usize,
}

pub(crate) type Done = Mutex<Collected>;

/// Runs `backend`'s runs as `next` hands them out, one by one, in a session of this thread's
/// own; `first`: this is the backend's first worker, whose hello goes into drivers.txt and
/// the report.
pub(crate) fn run_group(
    backend: &str,
    next: &dyn Fn() -> Option<Planned>,
    first: bool,
    settings: &Settings,
    done: &Done,
    total: usize,
) {
    let env = group_env(backend, settings);
    let mut session = Session::start(backend, &env, settings.timeout);
    // A worker that cannot even be started (our own binary missing or replaced mid-run) is
    // the harness's failure, not the backend's: its runs crash rather than skip, so that it
    // can never read as a clean run.
    let hello = session.hello().clone();
    // Only the lines that can name this backend's runs, so drivers.txt counts its own.
    let own = settings.expectations.for_backend(backend);
    let facts = hello.facts();
    let mut group = Group {
        backend,
        calibration: None,
        not_ready: session.ready().err(),
        // Expectations for this backend's driver (`@applies`), and those a release before it
        // closed (their deviations were fixed: a failure they match may be one come back).
        expectations: own.for_driver(&facts),
        closed: own.closed_for(&facts),
        settings,
    };
    if let Some(mut d) = done.lock().ok().filter(|_| first) {
        let (line, row) = describe_driver(&group, &hello);
        d.drivers.push((backend.to_string(), line));
        d.driver_rows.push(row);
        if let Some(why) = group.refused() {
            d.refused.push(format!("{backend}: {why}"));
        }
    }
    // The live card, measured once per backend (by whichever of its threads comes first),
    // for the card row and for calibrated judging.
    let row_dir = settings.cards.as_deref().filter(|_| first);
    let live =
        (group.not_run().is_none() && (settings.calibrate || row_dir.is_some())).then(|| {
            settings
                .live_cards
                .measured(backend, &env, settings.timeout)
        });
    if settings.calibrate {
        group.calibration = crate::judge::card_row::calibration_of(backend, live.as_ref(), first);
    }
    if let Some(dir) = row_dir {
        let not_run = group.not_run().map(|a| (a.status, a.reason));
        let row =
            crate::judge::card_row::conformance_row(backend, live, dir, settings.bless, not_run);
        let unavailable = matches!(group.not_ready, Some(NotReady::Unavailable(_)));
        finished(done, row, None, total, settings.verbose, unavailable);
    }
    while let Some(p) = next() {
        let t0 = Instant::now();
        let outcome = group.attempt_point(&p, &mut session);
        let (result, storage) = group.result_of(&p, outcome, t0);
        let unavailable = matches!(group.not_ready, Some(NotReady::Unavailable(_)));
        finished(done, result, storage, total, settings.verbose, unavailable);
    }
}

/// Records a finished run and prints its progress line.
pub(crate) fn finished(
    done: &Done,
    result: RunResult,
    storage: Option<String>,
    total: usize,
    verbose: bool,
    unavailable: bool,
) {
    if let Ok(mut d) = done.lock() {
        d.finished += 1;
        let r = &result;
        let mut line = format!(
            "[{}/{total}] {} {} ({:.0} ms)",
            d.finished,
            r.status,
            r.name,
            r.time_s * 1e3
        );
        if !matches!(r.status, Status::Pass) && !r.reason.is_empty() {
            let _ = write!(line, ": {}", first_line(&r.reason));
        }
        d.progress.finished(r.status.name(), &line);
        if verbose && !r.details.is_empty() {
            println!("{}", r.details);
        }
        if unavailable {
            d.unavailable_runs += 1;
        }
        d.storage.extend(storage);
        d.results.push(result);
    }
}

/// A backend's workers' environment: the driver's ([`crate::harness::registry::worker_env`]),
/// the fakes' switch where enabled, the judging cache, and insta's when blessing.
pub(crate) fn group_env(backend: &str, settings: &Settings) -> Vec<(String, String)> {
    let mut env = crate::harness::registry::worker_env(backend);
    if crate::harness::fake::enabled() {
        env.push(("UMBRA_FAKE_BACKENDS".into(), "1".into()));
    }
    env.push((
        crate::judge::judge_cache::ENV.into(),
        settings.judge_cache.clone(),
    ));
    if settings.bless {
        env.extend(crate::judge::golden::insta_env(true));
    }
    env
}

/// One backend's group of runs, as its first worker left it: why it cannot run (refused the
/// Mesa build, unavailable, its worker would not start) and the expectations for its driver.
pub(crate) struct Group<'a> {
    pub(crate) backend: &'a str,
    /// Its card read as the judge's narrowing ([`umbra_case::Calibration::encode`]); none:
    /// judged by the spec alone.
    pub(crate) calibration: Option<String>,
    /// Why its runs cannot run, where they cannot ([`Session::ready`]).
    pub(crate) not_ready: Option<NotReady>,
    pub(crate) expectations: Expectations,
    /// Expectations whose range an earlier release closed ([`Expectations::closed_for`]).
    pub(crate) closed: Expectations,
    pub(crate) settings: &'a Settings,
}

/// The backend's lines for drivers.txt (driver strings, device, goldens, build and the
/// expectation files that apply) and its row in report.json's `drivers`.
pub(crate) fn describe_driver(g: &Group, hello: &Hello) -> (String, umbra_report::DriverRow) {
    let (backend, settings) = (g.backend, g.settings);
    let files = g.expectations.file_counts();
    let ready = hello.ready();
    let facts = hello.facts();
    let build = ready.and_then(|r| r.build.clone());
    let driver_line = match hello {
        Hello::Ready(r) => format!(
            "{backend}: {} | {} | {} | {}\n",
            r.vendor,
            r.renderer,
            r.version,
            r.extensions.join(" ")
        ),
        Hello::Unavailable(u) => format!("{backend}: unavailable: {u}\n"),
        Hello::Refused(why) => format!("{backend}: refused: {why}\n"),
    };
    let mut device = ready
        .map(|r| r.device.as_str())
        .filter(|d| !d.is_empty())
        .map_or(String::new(), |d| format!("  device: {d}\n"));
    let no_goldens = settings.no_goldens.contains(backend);
    if no_goldens {
        device.push_str(&format!(
            "  goldens: {} (`cargo xtask bless --backend {backend}` starts them)\n",
            crate::judge::golden::NONE_FOR_BACKEND
        ));
    }
    // Deviations a release before this driver fixed: their runs are held to pass here.
    let closed = g.closed.file_counts();
    let closed_line = if closed.is_empty() {
        String::new()
    } else {
        format!(
            "  closed before this release (deviations fixed; their runs must pass): {}\n",
            closed.join(", ")
        )
    };
    let line = format!(
        "{}{device}{}{closed_line}",
        driver_line,
        match (&build, files.is_empty()) {
            (Some(b), true) => format!("  build: {b}; expectations: none\n"),
            (Some(b), false) => format!("  build: {b}; expectations: {}\n", files.join(", ")),
            (None, false) => format!("  expectations: {}\n", files.join(", ")),
            (None, true) => String::new(),
        }
    );
    let row = umbra_report::DriverRow {
        backend: backend.to_string(),
        vendor: ready.map(|r| r.vendor.clone()),
        renderer: ready.map(|r| r.renderer.clone()),
        version: ready.map(|r| r.version.clone()),
        device: ready.map(|r| r.device.clone()),
        goldens: no_goldens.then(|| crate::judge::golden::NONE_FOR_BACKEND.to_string()),
        mesa: facts.mesa,
        build,
        unavailable: hello.unavailable().map(str::to_string),
        refused: g.refused().map(str::to_string),
        expectations: files,
        closed_expectations: closed,
    };
    (line, row)
}

impl Group<'_> {
    /// Why its worker refused the Mesa build, where it did.
    fn refused(&self) -> Option<&str> {
        match &self.not_ready {
            Some(NotReady::Refused(why)) => Some(why),
            _ => None,
        }
    }

    /// What a run of a group that cannot run is: a crash (the worker refused the Mesa build,
    /// or could not be started) or a skip (the backend is unavailable here), with the reason.
    fn not_run(&self) -> Option<Attempt> {
        Some(match self.not_ready.as_ref()? {
            NotReady::Refused(why) => Attempt::bare(
                Status::Crash,
                format!("not run: the worker refused the Mesa build: {why}"),
            ),
            NotReady::NoWorker(e) => Attempt::bare(
                Status::Crash,
                format!("the harness could not start its worker process: {e}"),
            ),
            NotReady::Unavailable(why) => Attempt::bare(Status::Skip(why.clone()), why.clone()),
        })
    }

    /// Runs point `p` on the group's worker (started again if it died), once more if it
    /// failed (a different answer is a flake); a group that cannot run crashes or skips each
    /// point with the reason.
    fn attempt_point(&self, p: &Planned, session: &mut Session) -> Attempt {
        let settings = self.settings;
        match self.not_run() {
            Some(a) => a,
            None => {
                let req = Request::Judge(JudgeRequest {
                    point: (*p.point).clone(),
                    failures: Some(settings.failures.clone()),
                    golden: settings
                        .golden
                        .clone()
                        .filter(|_| !settings.no_goldens.contains(self.backend)),
                    no_twins: false,
                    gallery: Some(settings.gallery.clone()),
                    deviation: Some(self.expectations.deviations(&p.name(), &p.case).names())
                        .filter(|n| !n.is_empty()),
                    calibration: self.calibration.clone(),
                });
                session.attempt_or_rerun(&req, &p.name())
            }
        }
    }

    /// The run's result: its raw outcome under the driver's expectations (an expectation
    /// naming only checks this run did not make does not apply), with the command that
    /// reproduces it; and the storage problem its pictures met, if any.
    fn result_of(&self, p: &Planned, outcome: Attempt, t0: Instant) -> (RunResult, Option<String>) {
        let settings = self.settings;
        let name = p.name();
        let Attempt {
            status: raw,
            reason,
            metrics,
            details,
            failed,
            golden,
            fingerprint,
            under_deviation,
            storage,
            stderr,
        } = outcome;
        let unchecked: &[umbra_report::check::Check] =
            if settings.golden.is_none() || settings.no_goldens.contains(&p.backend) {
                &[umbra_report::check::Check::Golden]
            } else {
                &[]
            };
        let (status, expected) = self.expectations.apply(
            &name,
            &p.case,
            raw,
            &failed,
            under_deviation.as_deref(),
            unchecked,
        );
        let got = if reason.is_empty() {
            "a pass, every check inside what the specs allow".to_string()
        } else {
            reason.clone()
        };
        let reason = match (&status, expected) {
            (Status::ExpectedFail | Status::UnexpectedPass, Some(why)) => {
                format!("expected: {why}; got: {got}")
            }
            (_, Some(why)) if reason.is_empty() => format!("expectation: {why}"),
            (_, Some(why)) => format!("{reason} (expectation: {why})"),
            (s, None) if s.is_regression() => match self.closed.come_back(&name, &p.case) {
                Some(back) => format!("{reason} ({back})"),
                None => reason,
            },
            (_, None) => reason,
        };
        let passes = result_passes(&status);
        let result = RunResult {
            name,
            backend: p.backend.clone(),
            case: p.id.clone(),
            file: p.point.file.display().to_string(),
            values: p.point.values.clone(),
            status,
            reason,
            metrics,
            failed,
            golden,
            time_s: t0.elapsed().as_secs_f64(),
            reproduce: reproduce_command(p),
            diagnosis: None,
            // A pass's stderr is noise; any other status keeps it as evidence.
            stderr: if passes { String::new() } else { stderr },
            fingerprint,
            details,
        };
        (result, storage)
    }
}

/// The command that renders run `p` again, on the run's Mesa build when it used one.
pub(crate) fn reproduce_command(p: &Planned) -> String {
    // The driver variables the run inherited go first: without them it may not reproduce.
    let env: String = crate::harness::registry::inherited_driver_env(&p.backend)
        .iter()
        .map(|(k, v)| format!("{k}={} ", shell_word(v)))
        .collect();
    // Values as `--flag=VALUE` and the file as an operand: nothing a case or a path is
    // called can be read as an option.
    format!(
        "{env}cargo run --bin umbra -- render {} --backend={} --point={}{}",
        umbra_report::escape::operand(&p.point.file.display().to_string()),
        shell_word(&p.backend),
        shell_word(&p.id),
        crate::harness::mesa_build::selected()
            .filter(|_| crate::harness::mesa_build::is_mesa_backed(&p.backend))
            .map_or(String::new(), |b| format!(
                " --mesa={}",
                shell_word(&b.root.display().to_string())
            ))
    )
}

/// Whether a run's status is a plain pass (its stderr is not kept).
pub(crate) fn result_passes(status: &Status) -> bool {
    matches!(status, Status::Pass)
}
