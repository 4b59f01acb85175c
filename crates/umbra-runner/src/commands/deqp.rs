//! `umbra deqp`: umbra as a dEQP test binary, so that Mesa's deqp-runner drives it from a
//! suite TOML (`[[deqp]]`) beside its dEQP entries, with its caselists, `--fraction`,
//! baselines (`DRIVER-fails.txt`), skips and flakes.
//!
//! Why dEQP's protocol rather than gtest's: deqp-runner hands a dEQP binary a caselist file
//! of any size (`--deqp-caselist-file=F`, the tests of one group) and reads one status per
//! test from its stdout (`Test case 'NAME'..` then `  Pass (detail)`, `  Fail (…)`,
//! `  NotSupported (…)`, `  Crash (…)`, `  Timeout (…)`); a binary that dies leaves its
//! remaining tests Missing and deqp-runner reruns them. umbra keeps its own isolation under
//! that: every test runs in a worker process of its backend ([`crate::harness::pool`]), a
//! driver crash or hang costs that test (reported `Crash` or `Timeout`) and a fresh worker
//! takes the next, so one bad test never hides a group. The judge is umbra's, the spec's
//! intervals and the exact truth, with no golden check (a deqp-runner run is a partial run:
//! baselines are deqp-runner's). Failing tests leave umbra's pictures (expected, actual,
//! error) under `--umbra-pictures=DIR`, one directory per test.
//!
//! Test names are `umbra.API.DRIVER.CASE.K`: the backend id with `/` as `.`, the case's name
//! and the point's index in its case file (K counts the file's sweep points from 0). Run
//! names (`gl33/llvmpipe/beyond-far@shadow.compare=hardware,…`) hold commas, `=`, `{` and
//! `"`, which deqp-runner's CSV files and regex skip lists cannot carry; `--list` prints both
//! names side by side.
//!
//! - `umbra deqp --deqp-caselist-file=F [--cases=DIR] [--umbra-pictures=DIR]
//!   [--umbra-judge-cache=DIR] [--umbra-mesa=DIR] [--deqp-…]`: runs the listed tests (on the
//!   Mesa in `--umbra-mesa`, a CI job's freshly built install, checked as `--mesa` checks it) (deqp-runner starts the
//!   binary in its own directory, so the suite gives absolute paths) (other `--deqp-*` flags are accepted and ignored, as deqp-runner
//!   adds its log, shader-cache and flush flags).
//! - `umbra deqp --list [--backend=ID]… [--cases=DIR] [--expectations=DIR]`: one line per
//!   test, `NAME<TAB>RUN NAME<TAB>EXPECTED`, EXPECTED being what umbra's expectations say for
//!   the backend's driver (`Pass`, `Fail`, `Crash`, `Timeout`, `Skip`, or `Cause` for an
//!   expectation by cause, which fails only where its cause shows and which umbra itself
//!   reports as `QualityWarning` when the cause explains the failure), which
//!   `cargo xtask mesa-ci` turns into the driver's fails and skips files.
//!
//! What deqp-runner's files cannot say, umbra's own check keeps: an expected failure's
//! signature (which checks, on how many pixels) and an expectation by cause. In deqp-runner a
//! baselined test that fails differently still reads `Fail`; `umbra conformance` on the same
//! driver tells "fails differently" (a regression) from the expected failure.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use umbra_report::Status;

use crate::exit::{Error, Exit, Outcome};
use crate::harness::scheduler;
use crate::judge::expectations::{Expectations, Expected};
use crate::judge::protocol::{JudgeRequest, Request};

/// A test's name for deqp-runner.
pub fn test_name(backend: &str, case: &str, index: usize) -> String {
    format!("umbra.{}.{case}.{index}", backend.replace('/', "."))
}

/// The backend, case name and point index a test name stands for.
pub fn parse_test_name(name: &str) -> Option<(String, String, usize)> {
    let rest = name.strip_prefix("umbra.")?;
    let (rest, index) = rest.rsplit_once('.')?;
    let (backend, case) = rest.rsplit_once('.')?;
    let (api, driver) = backend.split_once('.')?;
    Some((
        format!("{api}/{driver}"),
        case.to_string(),
        index.parse().ok()?,
    ))
}

/// The value of `--NAME=V` among `argv`, every one of them.
fn values<'a>(argv: &'a [String], name: &str) -> Vec<&'a str> {
    let prefix = format!("--{name}=");
    argv.iter()
        .filter_map(|a| a.strip_prefix(prefix.as_str()))
        .collect()
}

/// The flags `umbra deqp` takes (`--NAME=V`, or bare); any `--deqp-*` flag is deqp-runner's
/// and accepted.
const FLAGS: &[&str] = &[
    "cases",
    "backend",
    "expectations",
    "umbra-expectations",
    "umbra-pictures",
    "umbra-judge-cache",
    "umbra-mesa",
];

/// Refuses a flag umbra deqp does not take (a mistyped `--umbra-picture=` would otherwise
/// leave no pictures and say nothing), naming it and the ones it takes.
fn known_flags(argv: &[String]) -> Result<(), String> {
    for a in argv {
        if a.starts_with("--deqp-") || a == "--list" {
            continue;
        }
        let name = a
            .strip_prefix("--")
            .map(|n| n.split('=').next().unwrap_or(n));
        match name {
            Some(n) if FLAGS.contains(&n) && a.contains('=') => {}
            Some(n) if FLAGS.contains(&n) => {
                return Err(format!("--{n} takes a value: --{n}=VALUE"));
            }
            _ => {
                return Err(format!(
                    "unknown argument {a:?}; it takes --list, --{}=VALUE and deqp-runner's --deqp-* flags",
                    FLAGS.join("=VALUE, --")
                ));
            }
        }
    }
    let list = argv.iter().any(|a| a == "--list");
    for name in FLAGS.iter().chain(READ_ONCE) {
        let n = values(argv, name).len();
        if *name == "backend" && n > 0 && !list {
            return Err(
                "--backend selects what --list lists; a test's name says its backend".into(),
            );
        }
        if n > 1 && !(*name == "backend" && list) {
            return Err(format!("--{name} is given {n} times: give it once"));
        }
    }
    if !values(argv, "expectations").is_empty() && !values(argv, "umbra-expectations").is_empty() {
        return Err("--expectations and --umbra-expectations name the same thing: give one".into());
    }
    Ok(())
}

/// The deqp-runner flags umbra deqp reads (one value each): a repeated one is refused rather
/// than its first taken.
const READ_ONCE: &[&str] = &["deqp-caselist-file", "deqp-case", "deqp-log-filename"];

/// `umbra deqp --help`.
const HELP: &str = "umbra deqp: umbra as a dEQP test binary, for Mesa's deqp-runner (cargo xtask mesa-ci writes the suite)

Usage:
  umbra deqp --deqp-caselist-file=FILE [--deqp-case=NAME[,NAME]] [--cases=DIR]
             [--umbra-expectations=DIR] [--umbra-pictures=DIR] [--umbra-judge-cache=DIR]
             [--umbra-mesa=DIR] [--deqp-...]
  umbra deqp --list [--backend=ID]... [--cases=DIR] [--expectations=DIR]

Tests are named umbra.API.DRIVER.CASE.K; each runs in a worker of its backend and prints
`Test case 'NAME'..` and `  STATUS (detail)` (Pass, Fail, QualityWarning for a failure an
expectation by cause explains, NotSupported, Crash, Timeout, InternalError). Other --deqp-*
flags are accepted and ignored. --list prints NAME, run name and expected status, tab-separated.
--umbra-mesa=DIR runs the tests on the Mesa in DIR (an install prefix: a CI job's install/),
checking that each worker loaded it, as umbra conformance --mesa does.
";

/// Runs `umbra deqp ARGS` (`argv`: the arguments after `deqp`); returns its outcome.
pub fn main(argv: &[String]) -> Outcome {
    if argv.iter().any(|a| a == "--help" || a == "-h") {
        print!("{HELP}");
        return Ok(Exit::Pass);
    }
    known_flags(argv).map_err(|e| Error::new(format!("umbra deqp: {e}\n{HELP}")))?;
    let cases = PathBuf::from(values(argv, "cases").first().copied().unwrap_or("cases"));
    if let Some(pictures) = values(argv, "umbra-pictures").first() {
        if let Err(e) = crate::conformance::plan::outside_cases(Path::new(pictures), &cases) {
            return Err(Error::new(format!(
                "umbra deqp: --umbra-pictures={pictures}: {e}"
            )));
        }
    }
    // `--umbra-mesa=DIR` (or UMBRA_MESA): the tree's freshly built install, as `--mesa`.
    let mesa = values(argv, "umbra-mesa")
        .first()
        .map(|v| v.parse::<crate::harness::mesa_build::MesaChoice>())
        .transpose()
        .map_err(|e| Error::new(format!("umbra deqp: --umbra-mesa: {e}")))?;
    crate::harness::mesa_build::select(mesa.as_ref())
        .map_err(|e| Error::new(format!("umbra deqp: {e}")))?;
    let index = CaseIndex::load(&cases).map_err(Error::new)?;
    if argv.iter().any(|a| a == "--list") {
        return list(argv, &index);
    }
    // The tests: a caselist file, or `--deqp-case=A,B` (deqp-runner's probe of
    // `umbra.info.renderer,…` before a run: umbra has no info tests, so they are NotSupported
    // and the log holds no TestCaseResult, which deqp-runner takes as "no check").
    let names: Vec<String> = match (
        values(argv, "deqp-caselist-file").first().copied(),
        values(argv, "deqp-case").first().copied(),
    ) {
        (Some(caselist), _) => match std::fs::read_to_string(caselist) {
            Ok(t) => t
                .lines()
                .map(str::trim)
                .filter(|l| !l.is_empty())
                .map(str::to_string)
                .collect(),
            Err(e) => return Err(Error::new(format!("cannot read {caselist}: {e}"))),
        },
        (None, Some(cases)) => cases.split(',').map(str::to_string).collect(),
        (None, None) => {
            return Err(Error::new(
                "umbra deqp: give --deqp-caselist-file=FILE (the tests to run, one name a line), --deqp-case=NAME[,NAME] or --list",
            ));
        }
    };
    let expectations = load_expectations(argv)?;
    let opts = RunOptions {
        pictures: values(argv, "umbra-pictures").first().map(PathBuf::from),
        log: values(argv, "deqp-log-filename").first().map(PathBuf::from),
        cache: PathBuf::from(
            values(argv, "umbra-judge-cache")
                .first()
                .copied()
                .unwrap_or(crate::judge::judge_cache::DEFAULT_ROOT),
        ),
        expectations,
    };
    run(&names, &index, &opts)
}

/// umbra's expectations from `--umbra-expectations=DIR` (the suite's spelling) or
/// `--expectations=DIR`, `expectations` by default; expectations that do not load are an
/// error (exit 125).
fn load_expectations(argv: &[String]) -> Result<Expectations, Error> {
    let dir = values(argv, "umbra-expectations")
        .into_iter()
        .chain(values(argv, "expectations"))
        .next()
        .unwrap_or("expectations");
    Expectations::load(Path::new(dir)).map_err(Error::new)
}

/// Every case file's points by case name: the file, and each point's id and case as JSON
/// (what expectations' `@when` conditions read).
struct CaseIndex(BTreeMap<String, (PathBuf, Vec<Indexed>)>);

/// One case point of the index: its id, the point as loaded (sent whole to the worker) and
/// its case as JSON (what expectations read).
struct Indexed {
    id: String,
    point: umbra_case::CasePoint,
    json: serde_json::Value,
}

impl CaseIndex {
    fn load(dir: &Path) -> Result<CaseIndex, String> {
        let files = umbra_case::case_files(dir)
            .map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
        let mut map = BTreeMap::new();
        for f in files {
            let points = umbra_case::load_file(&f).map_err(|e| e.to_string())?;
            if let Some(first) = points.first() {
                let abs = std::fs::canonicalize(&f).unwrap_or(f.clone());
                if let Some((other, _)) = map.get(&first.case.name) {
                    return Err(format!(
                        "{} and {} both have \"name\": {:?}; their tests would be one; rename one (the field `name`)",
                        Path::new(other).display(),
                        abs.display(),
                        first.case.name
                    ));
                }
                let name = first.case.name.clone();
                map.insert(
                    name,
                    (
                        abs.clone(),
                        points
                            .into_iter()
                            .map(|point| Indexed {
                                id: point.id(),
                                json: umbra_case::schema::condition_json(&point.case),
                                point: umbra_case::CasePoint {
                                    file: abs.clone(),
                                    ..point
                                },
                            })
                            .collect(),
                    ),
                );
            }
        }
        Ok(CaseIndex(map))
    }
}

/// Runs each test in a worker of its backend and prints its status as dEQP does (a pass:
/// each test's status is deqp-runner's to read).
fn run(names: &[String], index: &CaseIndex, opts: &RunOptions) -> Outcome {
    let mut session = Runs {
        cache: crate::judge::judge_cache::prepare(&opts.cache),
        timeout: Duration::from_secs(300),
        workers: BTreeMap::new(),
        facts: BTreeMap::new(),
    };
    let mut logged = String::new();
    let stdout = std::io::stdout();
    for name in names {
        let mut out = stdout.lock();
        let _ = writeln!(out, "Test case '{name}'..");
        let _ = out.flush();
        drop(out);
        let (status, detail) = match parse_test_name(name).and_then(|(backend, case, k)| {
            let (_, points) = index.0.get(&case)?;
            Some((backend, points.get(k)?))
        }) {
            None if name.starts_with("umbra.info.") => (
                "NotSupported",
                "umbra has no info tests; `umbra backends` lists the drivers".to_string(),
            ),
            None => (
                "InternalError",
                format!(
                    "{name} names no umbra test (umbra.API.DRIVER.CASE.K, `umbra deqp --list`)"
                ),
            ),
            Some((backend, point)) => session.test(name, &backend, point, opts),
        };
        let detail = detail.lines().next().unwrap_or("").replace(['(', ')'], "");
        let detail = if detail.is_empty() {
            "umbra".to_string()
        } else {
            detail
        };
        let mut out = stdout.lock();
        let _ = writeln!(out, "  {status} ({detail})\n");
        let _ = out.flush();
        logged.push_str(&format!("{name}\t{status}\t{detail}\n"));
    }
    println!("DONE!");
    if let Some(log) = &opts.log {
        let _ = std::fs::write(log, logged);
    }
    Ok(Exit::Pass)
}

/// What a run of tests is told: where failing tests' pictures go, the log deqp-runner names,
/// the judging cache, umbra's expectations.
struct RunOptions {
    pictures: Option<PathBuf>,
    log: Option<PathBuf>,
    cache: PathBuf,
    expectations: Expectations,
}

/// The sessions of a run (one per backend, its worker started again after a crash) and each
/// backend's driver facts (which select the expectations that apply).
struct Runs {
    cache: PathBuf,
    timeout: Duration,
    workers: BTreeMap<String, scheduler::Session>,
    facts: BTreeMap<String, crate::judge::expectations::DriverFacts>,
}

impl Runs {
    /// Runs one test in its backend's worker and says its dEQP status and detail. A failure
    /// that an expectation by cause explains (`@when`, a modelled deviation, judged again
    /// under it) is `QualityWarning`, which deqp-runner counts as a success (Warn) and keeps
    /// visible; any other failure is `Fail`, for the baseline to expect or not.
    #[allow(clippy::too_many_arguments)]
    fn test(
        &mut self,
        name: &str,
        backend: &str,
        indexed: &Indexed,
        opts: &RunOptions,
    ) -> (&'static str, String) {
        let (id, json) = (&indexed.id, &indexed.json);
        let mut env = crate::harness::registry::worker_env(backend);
        env.push((
            crate::judge::judge_cache::ENV.into(),
            self.cache.to_string_lossy().into_owned(),
        ));
        if !crate::harness::registry::is_known(backend) {
            return (
                "InternalError",
                format!(
                    "{name} names backend {backend}, which this umbra does not have (`umbra backends` lists them)"
                ),
            );
        }
        let timeout = self.timeout;
        let session = self
            .workers
            .entry(backend.to_string())
            .or_insert_with(|| scheduler::Session::start(backend, &env, timeout));
        // A backend that cannot run here says why in its hello: not supported (a missing
        // driver, a device the machine lacks) or refused (a Mesa build without its driver),
        // never a crash of a worker that exited as it should. A worker that could not be
        // started at all is tried again by the run (its failure is a crash).
        match session.ready() {
            Err(scheduler::NotReady::Unavailable(why)) => {
                return ("NotSupported", format!("{backend} is unavailable: {why}"));
            }
            Err(scheduler::NotReady::Refused(why)) => return ("InternalError", why),
            Err(scheduler::NotReady::NoWorker(_)) => {}
            Ok(()) => {
                let hello = session.hello();
                self.facts
                    .entry(backend.to_string())
                    .or_insert_with(|| hello.facts());
            }
        }
        let expectations = self
            .facts
            .get(backend)
            .map(|f| opts.expectations.for_driver(f))
            .unwrap_or_default();
        let run = format!("{backend}/{id}");
        let req = Request::Judge(JudgeRequest {
            failures: opts.pictures.as_ref().map(|p| p.join(name)),
            deviation: Some(expectations.deviations(&run, json).names()).filter(|n| !n.is_empty()),
            ..JudgeRequest::bare(indexed.point.clone(), false)
        });
        let a = session.attempt(&req);
        let raw = deqp_status(&a.status);
        let (status, why) = expectations.apply(
            &run,
            json,
            a.status.clone(),
            &a.failed,
            a.under_deviation.as_deref(),
            &[umbra_report::check::Check::Golden],
        );
        let by_cause = expectations
            .find(&run, json)
            .is_some_and(|e| !e.when.is_empty() || matches!(e.expected, Expected::Deviation(_)));
        match (status, why) {
            (Status::ExpectedFail, Some(why)) if by_cause => (
                "QualityWarning",
                format!("expected by cause: {why}; {}", a.reason),
            ),
            (_, Some(why)) if raw != "Pass" => (raw, format!("{} (umbra: {why})", a.reason)),
            _ => (raw, a.reason),
        }
    }
}

/// dEQP's name for a status (`qpTestLog.c`'s result names, as deqp-runner parses them).
fn deqp_status(s: &Status) -> &'static str {
    match s {
        Status::Pass | Status::Flake => "Pass",
        Status::Skip(_) => "NotSupported",
        Status::Crash => "Crash",
        Status::Timeout => "Timeout",
        _ => "Fail",
    }
}

/// `--list`: every test of the backends asked for, its run name and what umbra's
/// expectations say for it on this machine's driver.
fn list(argv: &[String], index: &CaseIndex) -> Outcome {
    let named: Vec<&str> = values(argv, "backend");
    let backends = crate::harness::registry::selected(&named, crate::harness::registry::known())
        .map_err(Error::new)?;
    let expectations = load_expectations(argv)?;
    for backend in backends.iter().filter(|b| *b != "ref") {
        // The driver's facts (its Mesa version) select the expectations that apply.
        let session = scheduler::Session::start(
            backend,
            &crate::harness::registry::worker_env(backend),
            Duration::from_secs(60),
        );
        let facts = match session.ready() {
            Err(scheduler::NotReady::NoWorker(e)) => {
                return Err(Error::new(format!("{backend}: no worker ({e})")));
            }
            _ => session.hello().facts(),
        };
        let expectations = expectations.for_driver(&facts);
        for (case, (_, points)) in &index.0 {
            for (k, Indexed { id, json, .. }) in points.iter().enumerate() {
                let run = format!("{backend}/{id}");
                let expected = match expectations.find(&run, json) {
                    None => "Pass",
                    // By cause (`@when`, or a modelled deviation): it fails where the cause
                    // shows and passes elsewhere, which only a run tells; `umbra deqp`
                    // reports an explained failure as QualityWarning (deqp-runner's Warn).
                    Some(e)
                        if !e.when.is_empty() || matches!(e.expected, Expected::Deviation(_)) =>
                    {
                        "Cause"
                    }
                    Some(e) => match e.expected {
                        Expected::Fail(_) | Expected::Deviation(_) => "Fail",
                        Expected::Crash => "Crash",
                        Expected::Timeout => "Timeout",
                        Expected::Skip => "Skip",
                    },
                };
                println!("{}\t{run}\t{expected}", test_name(backend, case, k));
            }
        }
    }
    Ok(Exit::Pass)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test_names_carry_no_csv_or_regex_trouble_and_read_back() {
        let n = test_name("gl33/radeonsi.2", "beyond-far", 7);
        assert_eq!(n, "umbra.gl33.radeonsi.2.beyond-far.7");
        assert!(!n.contains([',', ' ', '"', '{', '=', '/']));
        assert_eq!(
            parse_test_name(&n),
            Some(("gl33/radeonsi.2".into(), "beyond-far".into(), 7))
        );
        assert_eq!(
            parse_test_name(&test_name("wgpu-vk/lavapipe", "l-occluder", 0)),
            Some(("wgpu-vk/lavapipe".into(), "l-occluder".into(), 0))
        );
        assert_eq!(parse_test_name("dEQP-GLES2.info.version"), None);
    }

    /// A flag umbra deqp reads once is refused when repeated (the first was taken without a
    /// word), and `--backend` outside `--list`, where it selected nothing.
    #[test]
    fn repeated_or_idle_flags_are_refused() {
        let argv = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(known_flags(&argv(&["--deqp-case=a", "--cases=c", "--deqp-foo=1"])).is_ok());
        assert!(known_flags(&argv(&["--list", "--backend=a", "--backend=b"])).is_ok());
        for (a, why) in [
            (
                &["--deqp-case=a", "--cases=c", "--cases=d"][..],
                "--cases is given 2 times",
            ),
            (
                &["--deqp-case=a", "--deqp-case=b"],
                "--deqp-case is given 2 times",
            ),
            (
                &["--deqp-case=a", "--backend=gl33/llvmpipe"],
                "--backend selects what --list",
            ),
            (
                &["--list", "--expectations=a", "--umbra-expectations=b"],
                "give one",
            ),
        ] {
            let e = known_flags(&argv(a)).expect_err(why);
            assert!(e.contains(why), "{a:?}: {e}");
        }
    }
}
