//! `umbra selftest`: proves the harness can tell right from wrong, subtly wrong included.
//!
//! For every named fault ([`umbra_case::fault::Fault`]) and every backend it applies to, a
//! worker runs with the fault turned on (`UMBRA_SELFTEST=1`, `UMBRA_FAULT=name`) and is fed
//! the case points that exercise it ([`exercises`]), judged as in a conformance run (twins and
//! goldens aside, so a catch is the judge's: truth, reference, values, colour, map).
//!
//! - A catch counts only if the faulted run is a regression once the expectations
//!   (`expectations/`) are applied: a point expected to fail catches the fault only when the
//!   fault makes it fail *differently* (another check, or more pixels than its bound).
//! - Up to [`SAMPLE`] of the points built to see the fault ([`aimed_at`]) and up to
//!   [`SAMPLE`] others, each a spread, are run and every catch is counted, by the checks that
//!   failed; if none catches, the rest are tried until one does.
//! - Every fault × backend must be caught by at least [`MIN_POINTS`] points: a check that
//!   rests on one or two points is a case away from going blind. The hunt goes on past the
//!   sample until that many catch; a pair caught by fewer fails the self-test, unless fewer
//!   points than that exercise the fault on the backend at all (the output says so). One
//!   that no point catches is missed, and fails too.
//! - `--seed S --count N` runs the faults on N generated cases ([`umbra_case::generate`])
//!   instead, every exercising point of each, and reports the catch rate per fault: how far
//!   the judge's sensitivity carries beyond the cases it was developed against.

pub mod cards;
pub mod orientations;
pub mod thresholds;

use crate::harness::registry::Descriptor;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use umbra_case::fault::{Fault, Param};

use crate::cli::{SelftestArgs, SelftestMode};
use crate::exit::{Error, Exit, Outcome};
use crate::harness::pool::Reply;
use crate::harness::scheduler::{NotReady, Session};
use crate::judge::expectations::Expectations;
use crate::judge::protocol::{JudgeRequest, Request};

/// Runs `umbra selftest` in the mode asked for ([`SelftestArgs::mode`]) over one setup
/// ([`setup`]): the hunt of every fault on every backend (the default, `faults`),
/// `thresholds` (the smallest error of each parameter each backend's judge catches:
/// [`thresholds`]), `orientations` (the face/orientation table: [`orientations`]) and
/// `cards` (each card probe's fault caught: [`cards`]).
pub fn main(args: &SelftestArgs) -> Outcome {
    let setup = setup(args)?;
    match args.mode() {
        SelftestMode::Orientations => {
            let points: Vec<umbra_case::CasePoint> =
                setup.points.iter().map(|p| p.2.clone()).collect();
            orientations::main(&points)
        }
        SelftestMode::Thresholds => {
            let chosen = setup.chosen.then_some(&setup.backends[..]);
            thresholds::main(&setup.points, chosen, &setup.how(), setup.jobs)
        }
        SelftestMode::Faults => hunt_all(&setup),
        SelftestMode::Cards => cards::main(&setup.backends, setup.how().timeout),
    }
}

/// How many exercising points each fault × backend pair runs at least.
pub const SAMPLE: usize = 6;

/// How many points must catch each fault × backend pair.
pub const MIN_POINTS: usize = 3;

/// Whether `fault` means anything on backend `id`: asked of what the backend's family can do
/// ([`Descriptor::capabilities`], [`Fault::applies`]), never of the id's spelling.
pub fn applies(fault: Fault, id: &str) -> bool {
    Descriptor::of(id).is_some_and(|b| fault.applies(&b.capabilities()))
}

/// What one fault did on one backend.
#[derive(Clone, Debug, Default)]
pub struct Hunt {
    /// Points run.
    pub tried: usize,
    /// Points that caught the fault, each with its failed checks.
    pub caught: Vec<(String, String)>,
    /// Points that exercise the fault on the backend (the most that could catch it).
    pub exercising: usize,
    /// Points the backend skipped (it cannot run them: a driver without the extension),
    /// not counted as tried; the first skip's reason.
    pub skipped: usize,
    /// See `skipped`.
    pub skip_reason: Option<String>,
    /// Why nothing was run or caught, when so.
    pub note: Option<String>,
    /// The worker refused the Mesa build asked for (`--mesa`): the self-test cannot stand.
    pub refused: bool,
}

impl Hunt {
    /// Whether the backend ran none of the points it was given: every one a skip (an sRGB
    /// target on a GLES 2 driver without EXT_sRGB), so the pair says nothing either way.
    pub fn unrunnable(&self) -> bool {
        self.tried == 0 && self.skipped > 0
    }

    /// The checks that caught it, each with how many points.
    pub fn by_check(&self) -> BTreeMap<String, usize> {
        let mut m = BTreeMap::new();
        for (_, checks) in &self.caught {
            for c in checks.split('+').filter(|c| !c.is_empty()) {
                let name = c.split('=').next().unwrap_or(c).to_string();
                *m.entry(name).or_insert(0) += 1;
            }
        }
        m
    }
}

/// What every mode of the self-test works from: the command line checked, the case points
/// loaded, the expectations and the judging cache ready ([`setup`]).
pub(crate) struct Setup {
    /// The case points, with their file and index.
    pub(crate) points: Vec<(PathBuf, usize, umbra_case::CasePoint)>,
    /// The backends selected (every backend of the build but ref by default).
    pub(crate) backends: Vec<String>,
    /// Whether `--backend` chose them.
    pub(crate) chosen: bool,
    faults: Vec<Fault>,
    expectations: Expectations,
    cache: PathBuf,
    timeout: Duration,
    verbose: bool,
    /// The generated cases' directory (`--seed`/`--count`).
    generated: Option<PathBuf>,
    /// Worker processes at once.
    pub(crate) jobs: usize,
    /// `--tier`'s runs.
    tier: Option<std::collections::BTreeSet<String>>,
    /// `--catches`: where the catch matrix goes.
    catches: Option<PathBuf>,
    /// Each backend's calibration, from its card measured without a fault (none with
    /// `--spec-only`, or where the card could not be measured): a fault is a driver that
    /// changed since its card was taken, judged as conformance judges it.
    calibrations: BTreeMap<String, String>,
}

impl Setup {
    /// How every hunt of this setup runs.
    pub(crate) fn how(&self) -> How<'_> {
        How {
            expectations: &self.expectations,
            cache: &self.cache,
            timeout: self.timeout,
            verbose: self.verbose,
            every_point: self.generated.is_some(),
            calibrations: &self.calibrations,
            tier: self.tier.as_ref(),
        }
    }
}

/// Each backend's calibration from its card, measured on a worker without a fault, one
/// backend after another (a second or two each).
fn clean_calibrations(backends: &[String], timeout: Duration) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for b in backends {
        let env = crate::harness::registry::worker_env(b);
        let live = crate::harness::cards::measured_alone(b, &env, timeout);
        if let Some(c) = crate::judge::card_row::calibration_of(b, Some(&live), true) {
            out.insert(b.clone(), c);
        }
    }
    out
}

/// Checks the command line and loads what every mode needs; an error is what the command
/// ends with (could not run).
pub(crate) fn setup(args: &SelftestArgs) -> Result<Setup, Error> {
    conflicts(args).map_err(|e| crate::cli::usage_error("selftest", e))?;
    crate::harness::mesa_build::select(args.execution.mesa.as_ref()).map_err(Error::new)?;
    // `--seed S --count N`: the faults on generated cases, every exercising point run, and
    // the catch rate reported (how the judge's sensitivity holds off the catalogue).
    let generated = soak_cases(args).map_err(|e| crate::cli::usage_error("selftest", e))?;
    let cases = match &generated {
        Some(dir) => dir.clone(),
        None => args
            .cases
            .clone()
            .unwrap_or_else(|| PathBuf::from(crate::cli::CASES_DIR)),
    };
    let limits = args.execution.resolve("selftest")?;
    let (jobs, timeout) = (limits.jobs, limits.timeout);
    let expectations = Expectations::load(&args.expectations).map_err(Error::new)?;
    let default = crate::harness::registry::known()
        .into_iter()
        .filter(|b| b != "ref")
        .collect();
    let named = crate::cli::values::names(&args.backend);
    let backends = crate::harness::registry::selected(&named, default).map_err(Error::new)?;
    let mut faults: Vec<Fault> = Vec::new();
    for name in &args.fault {
        match Fault::parse(name) {
            Some(f) => faults.push(f),
            None => {
                let all: Vec<String> = Fault::ALL.iter().map(|f| f.name()).collect();
                return Err(Error::new(format!(
                    "--fault {name:?} is not a fault; the faults are {}, and any \
                     face<0-5>-<orientation> or map-<orientation> (orientations: {}), and \
                     PARAM@E (a parameter off by a relative error E, or E texels for a shift, held to the \
                     nearest millionth, at least one; \
                     parameters: {})",
                    all.join(", "),
                    umbra_case::fault::Orientation::ALL
                        .map(|o| o.name())
                        .join(", "),
                    Param::ALL.map(|p| p.name()).join(", ")
                )));
            }
        }
    }
    if faults.is_empty() {
        faults = Fault::ALL.to_vec();
    }
    let mut points = Vec::new();
    for f in umbra_case::case_files(&cases).unwrap_or_default() {
        let p = umbra_case::load_file(&f).map_err(|e| Error::new(e.to_string()))?;
        points.extend(p.into_iter().enumerate().map(|(i, p)| (f.clone(), i, p)));
    }
    if points.is_empty() {
        return Err(Error::new(format!("no case under {}", cases.display())));
    }
    // The judging basis of each point does not depend on the fault: the self-test shares
    // conformance's content-addressed cache (judge_cache), and so reads what a conformance run
    // of this build computed.
    // (The orientations mode judges nothing and touches no cache.)
    let cache = if args.mode() == SelftestMode::Orientations {
        PathBuf::new()
    } else {
        crate::judge::judge_cache::prepare(args.execution.judge_cache.as_deref().unwrap_or(
            std::path::Path::new(crate::judge::judge_cache::DEFAULT_ROOT),
        ))
    };
    if let Some(path) = &args.catches {
        crate::tier::replaceable(path, crate::tier::Catches::read, "a catch matrix")
            .map_err(|e| crate::cli::usage_error("selftest", format!("--catches {e}")))?;
    }
    let tier = args
        .tier
        .as_deref()
        .map(crate::tier::Tier::read)
        .transpose()
        .map_err(|e| crate::cli::usage_error("selftest", e))?
        .map(|t| t.runs.into_iter().collect());
    let calibrations = if args.execution.spec_only || args.mode() != SelftestMode::Faults {
        BTreeMap::new()
    } else {
        clean_calibrations(&backends, timeout)
    };
    Ok(Setup {
        calibrations,
        points,
        chosen: !args.backend.is_empty(),
        backends,
        faults,
        expectations,
        cache,
        timeout,
        verbose: args.output.verbose,
        generated,
        jobs,
        tier,
        catches: args.catches.clone(),
    })
}

/// Flags that would be ignored by the rest of the command line: refused, never dropped (a
/// `--cases` under `--seed` once ran the generated cases without a word, and `--fault` in the
/// thresholds, orientations and cards modes chose nothing).
fn conflicts(args: &SelftestArgs) -> Result<(), String> {
    if args.cases.is_some() && (args.seed.is_some() || args.count.is_some()) {
        return Err("--cases and --seed/--count each choose the cases (a directory, or generated ones): give one".into());
    }
    if !args.fault.is_empty() && args.mode() != SelftestMode::Faults {
        return Err(format!(
            "--fault chooses the faults the faults mode hunts; the {} mode injects its own: leave --fault out",
            format!("{:?}", args.mode()).to_lowercase()
        ));
    }
    Ok(())
}

/// The self-test proper: every fault hunted on every backend it applies to; it fails when
/// one goes unseen.
pub(crate) fn hunt_all(setup: &Setup) -> Outcome {
    let pairs: Vec<(String, Fault)> = setup
        .backends
        .iter()
        .flat_map(|b| {
            setup
                .faults
                .iter()
                .copied()
                .filter(|f| applies(*f, b))
                .map(move |f| (b.clone(), f))
        })
        .collect();
    let (points, how, jobs) = (&setup.points, setup.how(), setup.jobs);
    let results = crate::harness::scheduler::run_pool(pairs, jobs, |(backend, fault)| {
        let h = hunt(&backend, fault, points, &how);
        println!("{}", line(fault, &backend, &h));
        (backend, fault, h)
    });
    let mut results = results;
    results.sort_by(|a, b| (a.1.name(), &a.0).cmp(&(b.1.name(), &b.0)));
    if let Some(path) = &setup.catches {
        write_catches(path, &results).map_err(Error::new)?;
        println!("selftest: the catch matrix is in {}", path.display());
    }
    if setup.generated.is_some() {
        return rates(&results);
    }
    summary(&results)
}

/// `--catches`: every pair hunted and the points that caught it.
fn write_catches(path: &Path, results: &[(String, Fault, Hunt)]) -> Result<(), String> {
    let mesa = crate::harness::mesa_build::selected()
        .map_or("the system's Mesa".to_string(), |b| b.describe());
    let catches = crate::tier::Catches {
        measured: format!(
            "umbra {} on {mesa}",
            std::env::args().skip(1).collect::<Vec<_>>().join(" ")
        ),
        pairs: results
            .iter()
            .map(|(backend, fault, h)| crate::tier::Pair {
                fault: fault.name(),
                backend: backend.clone(),
                exercising: h.exercising,
                tried: h.tried,
                caught: h.caught.iter().map(|(p, _)| p.clone()).collect(),
            })
            .collect(),
    };
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|e| format!("--catches {}: {e}", d.display()))?;
    }
    let text = serde_json::to_string_pretty(&catches).unwrap_or_default();
    crate::atomic_file::write(path, text.as_bytes())
        .map_err(|e| format!("--catches {}: {e}", path.display()))
}

/// With `--seed` and `--count`, the directory the generated cases were written to.
fn soak_cases(args: &SelftestArgs) -> Result<Option<PathBuf>, String> {
    let (seed, count) = match (args.seed, args.count) {
        (None, None) => return Ok(None),
        // One given, the other has its default (the help says which).
        (s, c) => (s.unwrap_or(1), c.map_or(20, crate::cli::values::Count::get)),
    };
    let dir = args
        .output
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(crate::run_dir::SOAK_OUT))
        .join("selftest-cases");
    // A directory of umbra's own, emptied: one that holds anything umbra did not write (a
    // user's cases under a path they gave as --out) is refused, never emptied.
    umbra_owned::fresh(&dir, "umbra selftest --seed/--count (generated cases)")
        .map_err(|e| e.to_string())?;
    umbra_case::generate::write_cases(&dir, seed, count).map_err(|e| {
        format!(
            "cannot write the generated cases under {}: {e}",
            dir.display()
        )
    })?;
    println!(
        "selftest on {count} generated cases of seed {seed} ({}): every exercising point is run",
        dir.display()
    );
    Ok(Some(dir))
}

/// The catch rate per fault on generated cases: of the points that exercise it on each
/// backend, how many catch it. Generated scenes are not built to see a subtle fault (the
/// catalogue's magnified and exact-tie cases are), so a low rate is information, not a
/// failure; a fault no generated point catches anywhere is listed. Nothing run, or a Mesa
/// build refused, is could not run (the lines above say so).
fn rates(results: &[(String, Fault, Hunt)]) -> Outcome {
    println!(
        "\ncatch rate on generated cases, per fault: points that caught it / points run (all backends)"
    );
    let (mut caught_all, mut tried_all) = (0, 0);
    for f in faults_of(results) {
        let rs: Vec<_> = results.iter().filter(|r| r.1 == f).collect();
        if rs.is_empty() {
            continue;
        }
        let caught: usize = rs.iter().map(|r| r.2.caught.len()).sum();
        let tried: usize = rs.iter().map(|r| r.2.tried).sum();
        let blind: Vec<&str> = rs
            .iter()
            .filter(|r| r.2.caught.is_empty() && r.2.tried > 0)
            .map(|r| r.0.as_str())
            .collect();
        caught_all += caught;
        tried_all += tried;
        println!(
            "  {:<20} {:<16} {caught:>4} / {tried:<4} ({:>5.1}%){}",
            f.name(),
            f.subtlety().name(),
            100.0 * caught as f64 / tried.max(1) as f64,
            if blind.is_empty() {
                String::new()
            } else {
                format!("  caught by no generated point on {}", blind.join(", "))
            }
        );
    }
    println!(
        "selftest (generated cases): {caught_all} of {tried_all} faulted runs caught ({:.1}%)",
        100.0 * caught_all as f64 / tried_all.max(1) as f64
    );
    if tried_all == 0 || results.iter().any(|r| r.2.refused) {
        Err(Error::said(Exit::CouldNotRun))
    } else {
        Ok(Exit::Pass)
    }
}

/// The faults of `results`, each once, in the order of [`Fault::ALL`] and then of their names.
fn faults_of(results: &[(String, Fault, Hunt)]) -> Vec<Fault> {
    let mut faults: Vec<Fault> = Vec::new();
    for r in results {
        if !faults.contains(&r.1) {
            faults.push(r.1);
        }
    }
    let rank = |f: &Fault| Fault::ALL.iter().position(|a| a == f).unwrap_or(usize::MAX);
    faults.sort_by_key(|f| (rank(f), f.name()));
    faults
}

/// One line per fault × backend.
fn line(fault: Fault, backend: &str, h: &Hunt) -> String {
    let head = format!("{:<20} {:<18}", fault.name(), backend);
    if h.unrunnable() {
        return format!(
            "{head} not run: every one of its {} points is a skip on this driver ({})",
            h.skipped,
            h.skip_reason.as_deref().unwrap_or("no reason given")
        );
    }
    if h.caught.is_empty() {
        return format!(
            "{head} MISSED: {} ({} points tried)",
            h.note
                .clone()
                .unwrap_or_else(|| "no point caught it".into()),
            h.tried
        );
    }
    let checks: Vec<String> = h
        .by_check()
        .iter()
        .map(|(c, n)| format!("{c}×{n}"))
        .collect();
    format!(
        "{head} caught by {} of {} points ({}); e.g. {}{}",
        h.caught.len(),
        h.tried,
        checks.join(", "),
        h.caught[0].0,
        match h.short() {
            Short::No => String::new(),
            Short::Impossible => format!(
                "  (only {} points exercise it here: {MIN_POINTS} cannot catch it)",
                h.exercising
            ),
            Short::Yes => format!(
                "  SHORT: fewer than {MIN_POINTS} of its {} exercising points catch it",
                h.exercising
            ),
        }
    )
}

/// Whether a hunt fell short of [`MIN_POINTS`] catching points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Short {
    /// It did not.
    No,
    /// Fewer points than that exercise the fault on the backend at all.
    Impossible,
    /// It did: the check rests on too few points.
    Yes,
}

impl Hunt {
    fn short(&self) -> Short {
        if self.caught.len() >= MIN_POINTS || self.caught.is_empty() {
            Short::No
        } else if self.exercising < MIN_POINTS {
            Short::Impossible
        } else {
            Short::Yes
        }
    }
}

/// The per-fault table and the closing line; the outcome (nothing run, or a Mesa build
/// refused, is could not run: the lines above say so).
fn summary(results: &[(String, Fault, Hunt)]) -> Outcome {
    let (unrunnable, runnable): (Vec<_>, Vec<_>) = results.iter().partition(|r| r.2.unrunnable());
    let results: Vec<(String, Fault, Hunt)> = runnable.into_iter().cloned().collect();
    let results = &results[..];
    println!(
        "\nper fault: subtlety, backends caught / applicable, fewest catching points on a backend"
    );
    for f in faults_of(results) {
        let rs: Vec<_> = results.iter().filter(|r| r.1 == f).collect();
        let caught = rs.iter().filter(|r| !r.2.caught.is_empty()).count();
        let fewest = rs.iter().map(|r| r.2.caught.len()).min().unwrap_or(0);
        println!(
            "  {:<20} {:<16} {caught}/{} backends, fewest {fewest} points",
            f.name(),
            f.subtlety().name(),
            rs.len()
        );
    }
    let caught = results.iter().filter(|r| !r.2.caught.is_empty()).count();
    let missed: Vec<_> = results.iter().filter(|r| r.2.caught.is_empty()).collect();
    for (b, f, h) in &missed {
        println!(
            "  missed: {} on {b}: {}",
            f.name(),
            h.note.clone().unwrap_or_default()
        );
    }
    let short: Vec<_> = results
        .iter()
        .filter(|r| r.2.short() == Short::Yes)
        .collect();
    for (b, f, h) in &short {
        println!(
            "  short: {} on {b}: caught by {} of {} exercising points, fewer than {MIN_POINTS}",
            f.name(),
            h.caught.len(),
            h.exercising
        );
    }
    let impossible: Vec<_> = results
        .iter()
        .filter(|r| r.2.short() == Short::Impossible)
        .collect();
    for (b, f, h) in &impossible {
        println!(
            "  by fewer than {MIN_POINTS} points, as it must be: {} on {b}: only {} points exercise it",
            f.name(),
            h.exercising
        );
    }
    for (b, f, h) in &unrunnable {
        println!(
            "  not run, and not counted: {} on {b}: its {} points are skips on this driver ({})",
            f.name(),
            h.skipped,
            h.skip_reason.as_deref().unwrap_or("no reason given")
        );
    }
    println!(
        "selftest: {caught} of {} fault × backend pairs caught; {} by at least {MIN_POINTS} points, {} short, {} exercised by fewer than {MIN_POINTS} points",
        results.len(),
        caught - short.len() - impossible.len(),
        short.len(),
        impossible.len()
    );
    println!(
        "selftest: {} passed, {} failed",
        caught - short.len(),
        missed.len() + short.len()
    );
    if results.is_empty() || results.iter().any(|r| r.2.refused) {
        Err(Error::said(Exit::CouldNotRun))
    } else {
        Ok(Exit::pass_if(missed.is_empty() && short.is_empty()))
    }
}

/// How every hunt runs.
pub(crate) struct How<'a> {
    pub(crate) expectations: &'a Expectations,
    /// The shared judging cache.
    pub(crate) cache: &'a Path,
    pub(crate) timeout: Duration,
    pub(crate) verbose: bool,
    /// Run every exercising point (the catch rate on generated cases), not just until one
    /// catches after the sample.
    pub(crate) every_point: bool,
    /// Each backend's calibration ([`Setup`]'s).
    pub(crate) calibrations: &'a BTreeMap<String, String>,
    /// `--tier`: the only runs (`backend/Case@point`) a hunt may make (it runs them as it
    /// runs the catalogue's: a sample, then on until enough catch).
    pub(crate) tier: Option<&'a std::collections::BTreeSet<String>>,
}

/// A worker running `backend` with one fault on, and the expectations of its driver.
pub(crate) struct Faulted {
    backend: String,
    session: Session,
    expectations: Expectations,
    verbose: bool,
    fault: Fault,
    calibration: Option<String>,
}

/// What one faulted point did.
pub(crate) enum Seen {
    /// The judge caught it: the failed checks (or the crash or timeout).
    Caught(String),
    /// It passed (or failed only as expected).
    Passed,
    /// The backend cannot run the point (a skip, with its reason): not a try.
    Skipped(String),
    /// No worker could be started for the point (after a crash: it did not run): stop.
    Gone,
}

impl Faulted {
    /// Starts the worker; `Err((why, refused))` when it cannot run (refused: the Mesa build
    /// asked for was refused, and the self-test cannot stand).
    pub(crate) fn start(backend: &str, fault: Fault, how: &How) -> Result<Faulted, (String, bool)> {
        let mut env = crate::harness::registry::worker_env(backend);
        env.extend([
            ("UMBRA_SELFTEST".into(), "1".into()),
            ("UMBRA_FAULT".into(), fault.name()),
            (
                crate::judge::judge_cache::ENV.into(),
                how.cache.to_string_lossy().into_owned(),
            ),
        ]);
        let session = Session::start(backend, &env, how.timeout);
        match session.ready() {
            Ok(()) => {}
            Err(NotReady::NoWorker(e)) => return Err((format!("no worker: {e}"), false)),
            Err(NotReady::Unavailable(u)) => {
                return Err((format!("backend unavailable: {u}"), false));
            }
            Err(NotReady::Refused(why)) => {
                return Err((format!("refused the Mesa build: {why}"), true));
            }
        }
        let expectations = how.expectations.for_driver(&session.hello().facts());
        Ok(Faulted {
            backend: backend.to_string(),
            session,
            expectations,
            verbose: how.verbose,
            fault,
            calibration: how.calibrations.get(backend).cloned(),
        })
    }

    /// Runs `point` and judges it as a conformance run would.
    pub(crate) fn run(&mut self, point: &umbra_case::CasePoint) -> Seen {
        let name = format!("{}/{}", self.backend, point.id());
        let case = umbra_case::schema::condition_json(&point.case);
        let req = Request::Judge(JudgeRequest {
            deviation: Some(self.expectations.deviations(&name, &case).names())
                .filter(|n| !n.is_empty()),
            calibration: self.calibration.clone(),
            ..JudgeRequest::bare(point.clone(), true)
        });
        // A crash or a timeout is a catch; the session starts a fresh worker for the next
        // point, and one that does not come up ends the hunt.
        let reply = match self.session.reply(&req) {
            Ok((reply, _)) => reply,
            Err(_) => return Seen::Gone,
        };
        match reply {
            Reply::Report(r) if r.outcome == crate::judge::protocol::RunVerdict::Fail => {
                let (status, _) = self.expectations.apply(
                    &name,
                    &case,
                    umbra_report::Status::Fail,
                    &r.failed,
                    r.under_deviation.as_deref(),
                    // The self-test runs without goldens.
                    &[umbra_report::check::Check::Golden],
                );
                let checks = crate::judge::expectations::signature(&r.failed);
                if self.verbose {
                    println!(
                        "  {} {name}: {status:?} [{checks}] {}",
                        self.fault.name(),
                        r.reason
                    );
                }
                // A run that failed with no check failed broke (a shader the driver refused,
                // a GL error): the judge did not see the fault, so it is not a catch.
                // umbra's own memory refusal saw nothing of the fault either.
                let judged = r
                    .failed
                    .iter()
                    .any(|c| c.check != umbra_report::check::Check::Memory);
                if status.is_regression() && judged {
                    Seen::Caught(checks)
                } else {
                    Seen::Passed
                }
            }
            Reply::Report(r) if r.outcome == crate::judge::protocol::RunVerdict::Skip => {
                Seen::Skipped(r.reason)
            }
            Reply::Report(r) => {
                if self.verbose {
                    println!("  {} {name}: {} {}", self.fault.name(), r.outcome, r.reason);
                }
                Seen::Passed
            }
            Reply::Crashed(how) => Seen::Caught(format!("crash ({how})")),
            Reply::TimedOut => Seen::Caught("timeout".into()),
            // umbra's own limit saw nothing of the fault: never a catch (a budget too small
            // for any run once made every fault "caught").
            Reply::OverBudget(why) => Seen::Skipped(format!("umbra's memory budget: {why}")),
        }
    }
}

/// Runs the points that exercise `fault` on a faulted `backend` worker and counts catches.
fn hunt(
    backend: &str,
    fault: Fault,
    points: &[(PathBuf, usize, umbra_case::CasePoint)],
    how: &How,
) -> Hunt {
    let mut h = Hunt::default();
    let mut faulted = match Faulted::start(backend, fault, how) {
        Ok(f) => f,
        Err((note, refused)) => {
            h.note = Some(note);
            h.refused = refused;
            return h;
        }
    };
    let es2 = Descriptor::of(backend).is_some_and(|b| b.gles2_technique());
    let candidates: Vec<&(PathBuf, usize, umbra_case::CasePoint)> = points
        .iter()
        .filter(|(_, _, p)| fault.exercises(&p.case, es2))
        .filter(|(_, _, p)| {
            how.tier
                .is_none_or(|t| t.contains(&format!("{backend}/{}", p.id())))
        })
        .collect();
    h.exercising = candidates.len();
    if candidates.is_empty() {
        h.note = Some("no case point exercises it".into());
        return h;
    }
    // A spread of up to SAMPLE of the points aimed at the fault, and a spread of SAMPLE
    // over the others; then the rest in order until enough catch.
    let order = sample_order(fault, &candidates);
    let sampled = order_sampled(fault, &candidates);
    for (k, &i) in order.iter().enumerate() {
        if k >= sampled && h.caught.len() >= MIN_POINTS && !how.every_point {
            break;
        }
        let point = &candidates[i].2;
        h.tried += 1;
        match faulted.run(point) {
            Seen::Caught(checks) => h.caught.push((point.id(), checks)),
            Seen::Passed => {}
            Seen::Skipped(reason) => {
                h.tried -= 1;
                h.skipped += 1;
                h.skip_reason.get_or_insert(reason);
            }
            Seen::Gone => {
                h.tried -= 1;
                h.note = Some("the worker could not be restarted after a crash".into());
                break;
            }
        }
    }
    h
}

/// The order `candidates` are tried in for `fault`: up to SAMPLE of the points aimed at it,
/// round-robin over their cases so each aimed case gets its turn, then a spread of SAMPLE
/// over the others, then the rest.
pub(crate) fn sample_order(
    fault: Fault,
    candidates: &[&(PathBuf, usize, umbra_case::CasePoint)],
) -> Vec<usize> {
    let (aimed, others): (Vec<usize>, Vec<usize>) =
        (0..candidates.len()).partition(|&i| fault.aimed_at(&candidates[i].2.case));
    let spread = |v: &[usize]| -> Vec<usize> {
        let step = (v.len() / SAMPLE).max(1);
        v.iter().copied().step_by(step).take(SAMPLE).collect()
    };
    let mut by_case: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for &i in &aimed {
        by_case
            .entry(candidates[i].2.case.name.as_str())
            .or_default()
            .push(i);
    }
    let rounds = by_case.values().map(Vec::len).max().unwrap_or(0);
    let aimed: Vec<usize> = (0..rounds)
        .flat_map(|k| by_case.values().filter_map(move |v| v.get(k).copied()))
        .collect();
    let mut order: Vec<usize> = aimed.iter().copied().take(SAMPLE).collect();
    order.extend(spread(&others));
    let rest: Vec<usize> = (0..candidates.len())
        .filter(|i| !order.contains(i))
        .collect();
    order.extend(rest);
    order
}

/// How many of [`sample_order`]'s points are the sample (always run).
fn order_sampled(fault: Fault, candidates: &[&(PathBuf, usize, umbra_case::CasePoint)]) -> usize {
    let aimed = candidates
        .iter()
        .filter(|c| fault.aimed_at(&c.2.case))
        .count();
    aimed.min(SAMPLE) + (candidates.len() - aimed).min(SAMPLE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_apply_where_they_mean_something() {
        assert!(
            applies(Fault::GlDepthRange, "wgpu-vk/lavapipe")
                && !applies(Fault::GlDepthRange, "gl33/zink")
        );
        assert!(
            applies(Fault::WrongTextureUnit, "gles2/softpipe")
                && !applies(Fault::WrongTextureUnit, "wgpu-gl/llvmpipe")
        );
        assert!(
            applies(Fault::NoClamp, "gles2/llvmpipe") && !applies(Fault::NoClamp, "gl33/llvmpipe")
        );
        assert!(!applies(Fault::ClampFloat, "gles2/zink"));
        assert!(!applies(Fault::BilinearCoarse, "wgpu-gl/llvmpipe"));
        assert!(
            !Fault::ALL.iter().any(|f| applies(*f, "ref")),
            "the reference is the yardstick, not a suspect"
        );
        // Every fault applies somewhere, on GL, GLES 2 or wgpu.
        for f in Fault::ALL {
            assert!(
                crate::harness::registry::known()
                    .iter()
                    .any(|b| applies(f, b)),
                "{} applies nowhere",
                f.name()
            );
        }
    }

    #[test]
    fn flags_the_command_line_would_ignore_are_refused() {
        let cases_and_seed = SelftestArgs {
            cases: Some("cases".into()),
            seed: Some(3),
            ..SelftestArgs::default()
        };
        assert!(conflicts(&cases_and_seed).is_err_and(|e| e.contains("give one")));
        let fault_in_cards = SelftestArgs {
            mode: SelftestMode::Cards,
            fault: vec!["no-guard".into()],
            ..SelftestArgs::default()
        };
        assert!(conflicts(&fault_in_cards).is_err_and(|e| e.contains("leave --fault out")));
        let fault_in_faults = SelftestArgs {
            fault: vec!["no-guard".into()],
            ..SelftestArgs::default()
        };
        assert_eq!(conflicts(&fault_in_faults), Ok(()));
    }

    #[test]
    fn faults_stay_off_outside_the_selftest() {
        // This test process has no UMBRA_SELFTEST, whatever UMBRA_FAULT might say.
        if std::env::var("UMBRA_SELFTEST").is_err() {
            assert_eq!(Fault::active(), None);
        }
        assert_eq!(Fault::parse("no-guard"), Some(Fault::NoGuard));
        assert!(
            Fault::ALL
                .iter()
                .all(|f| Fault::parse(&f.name()) == Some(*f))
        );
    }

    #[test]
    fn there_are_a_dozen_subtle_faults_on_each_api() {
        use umbra_case::fault::Subtlety;
        for backend in ["gl33/llvmpipe", "gles2/llvmpipe", "wgpu-vk/lavapipe"] {
            let subtle = Fault::ALL
                .iter()
                .filter(|f| f.subtlety() != Subtlety::Gross && applies(**f, backend))
                .count();
            assert!(subtle >= 12, "{backend}: only {subtle} subtle faults");
        }
    }

    #[test]
    fn aimed_cases_exist_and_exercise_their_fault() {
        // A renamed case must not silently drop a fault back to the catalogue-wide spread.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases");
        let points: Vec<umbra_case::CasePoint> = umbra_case::case_files(&root)
            .expect("cases/")
            .iter()
            .flat_map(|f| umbra_case::load_file(f).expect("a valid case"))
            .collect();
        for f in Fault::ALL {
            let aimed: Vec<_> = points.iter().filter(|p| f.aimed_at(&p.case)).collect();
            if aimed.is_empty() {
                continue;
            }
            assert!(
                aimed
                    .iter()
                    .any(|p| f.exercises(&p.case, false) || f.exercises(&p.case, true)),
                "{}: no aimed point exercises it",
                f.name()
            );
        }
        for f in [
            Fault::CompareStrict,
            Fault::QuarterTexel,
            Fault::OffsetUnitsLow,
            Fault::Vis4Bit,
            Fault::NoGuard,
            Fault::ClampIgnored,
            Fault::ClampForced,
            Fault::LayerShift,
            Fault::CascadeByDistance,
            Fault::BlendIgnored,
            Fault::BandOfRange,
            Fault::WorldOffsetsDropped,
            Fault::LightColourIgnored,
            Fault::ClearIgnored,
            Fault::LitCullFlipped,
            Fault::DepthFuncSwapped,
            Fault::SrgbIgnored,
            Fault::LightSwap,
            Fault::ArrayLayerZero,
        ] {
            assert!(
                points.iter().any(|p| f.aimed_at(&p.case)),
                "{}: its aimed cases are gone",
                f.name()
            );
        }
    }
}
