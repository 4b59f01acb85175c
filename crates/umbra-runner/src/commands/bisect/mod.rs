//! `umbra bisect --mesa-src DIR --good REV --bad REV`: finds the Mesa commit that broke a
//! case, with `git bisect run` over a Mesa source tree.
//!
//! - **Options from the tree.** Each commit's meson options are derived from that commit's
//!   own `meson.options` (`meson_options.txt` before 25.0) ([`meson_options`]): the drivers
//!   umbra runs (llvmpipe and softpipe, `swrast` before 24.3; zink; lavapipe), surfaceless
//!   EGL through glvnd, no GLX or window systems, each in the form that tree declares, an
//!   option it lacks or has deprecated left out. So one bisection crosses a renamed or
//!   removed option. `--meson-option`s come after and are checked against the tree too.
//! - **The meson it asks for.** A tree's `meson_version` newer than the machine's meson
//!   brings one into `WORK/meson` with pip before anything builds ([`meson`]).
//! - **Configure once per option set.** Each distinct option list has its build directory
//!   (`WORK/build-HASH`), set up the first time a commit needs it; later commits rebuild
//!   incrementally there (ninja rebuilds what changed; meson reconfigures itself when a
//!   build file changed). `--configure-only` derives and checks both ends' options,
//!   configures, and stops: the check to run first on a tree.
//! - **Each commit into its own prefix**: `meson install --destdir PREFIXES/<commit>`, which
//!   `--mesa` then loads (and checks it loaded). A commit that does not build is 125
//!   (`git bisect skip`).
//! - **Test**: `umbra conformance --mesa PREFIX` on the chosen cases and backends (`--filter`,
//!   `--backend`), goldens off: 0 good, 1 bad, 125 when nothing could be judged. With
//!   `--card KEY=VALUE` the test is a behaviour instead: good when every selected backend's
//!   card entry KEY has VALUE ([`crate::judge::card`]), so a bisection can target what a
//!   driver chose (its polygon-offset unit, its depth rounding), not a picture.
//! - **Cards at every step**: each commit's behaviour cards are kept
//!   (`WORK/reports/<commit>/cards.json`), and the end names the card entries that changed at
//!   the first bad commit before its failing runs.
//! - **Ends first**: the good and the bad commit are built and tested before git bisects
//!   (`--no-check-ends` skips it): cases that already fail on the good commit, or pass on the
//!   bad one, would make git name a meaningless commit, so that is an error (125).
//! - At the end it prints the first bad commit, the case's failure on it, and every step with
//!   its build and test time (also in `WORK/steps.csv`, with the full transcript in
//!   `WORK/bisect.log`).
//!
//! `--build-script PATH` replaces meson: it is run as `PATH SRC PREFIX OPTION...` in the
//! source tree (the commit's derived options) and must install a Mesa (or, in umbra's own
//! tests, a fake build) into PREFIX.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::cli::{BisectArgs, BisectStepArgs, Selection};
use crate::exit::{Error, Exit, Outcome};

mod meson;
pub mod meson_options;

use meson::Version;

fn git(src: &Path, args: &[&str]) -> Result<String, String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(src)
        .args(args)
        .output()
        .map_err(|e| format!("cannot run git: {e}"))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
    } else {
        Err(format!(
            "git {} failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

fn absolute(p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().map_or_else(|_| p.to_path_buf(), |d| d.join(p))
    }
}

/// Runs the command; returns its outcome (a pass: a first bad commit was found; a failure:
/// not found or ambiguous; could not run: bad input or set-up). The steps: check the tree
/// and the ends' revisions, configure once, check the ends, bisect, and say what was found.
pub fn main(args: &BisectArgs) -> Outcome {
    let (good, bad) = (args.good.as_str(), args.bad.as_str());
    if args.card.as_deref().is_some_and(|c| !c.contains('=')) {
        return Err(crate::cli::usage_error(
            "bisect",
            "--card takes KEY=VALUE, an entry of `umbra card` and the value a good commit has (e.g. 'offset-unit.depth16.z0.375=4 codes')",
        ));
    }
    if args.card.is_some() && args.selection.backend.is_empty() {
        return Err(crate::cli::usage_error(
            "bisect",
            "--card needs --backend: the backends whose card entry is bisected (the reference's card never changes with Mesa)",
        ));
    }
    let src = absolute(&args.mesa_src);
    check_tree(&src, good, bad)?;
    // The ends as commits, before any checkout moves HEAD (`--bad HEAD` names the commit
    // the tree is on now, not wherever a step left it).
    let resolve = |rev: &str| {
        git(
            &src,
            &["rev-parse", "--verify", &format!("{rev}^{{commit}}")],
        )
    };
    let (good_sha, bad_sha) = (
        resolve(good).map_err(Error::new)?,
        resolve(bad).map_err(Error::new)?,
    );
    let (good, bad) = (good_sha.as_str(), bad_sha.as_str());
    let work = absolute(&args.work);
    // The work directory is umbra's (its steps, prefixes and logs are replaced and removed):
    // a directory that holds anything else is refused, never emptied.
    umbra_owned::claim(&work, "umbra bisect").map_err(|e| Error::new(format!("--work: {e}")))?;
    let _ = std::fs::remove_file(work.join("steps.csv"));
    let script = args.build_script.as_deref().map(absolute);
    prepare(args, [good, bad], &src, &work, script.as_deref())?;
    if args.configure_only {
        println!(
            "bisect: --configure-only: both ends configure{}; run without it to bisect",
            if script.is_some() {
                " (their options check against their trees; --build-script builds, so meson was not run)"
            } else {
                ""
            }
        );
        return Ok(Exit::Pass);
    }
    let exe = crate::harness::own_libc::self_exe()
        .map_err(|e| Error::new(format!("cannot find this executable: {e}")))?;
    let step = step_argv(args, &src, &work, script.as_deref());
    let started = Instant::now();
    let _ = git(&src, &["bisect", "reset"]);
    // Each bisection starts its own list of steps.
    let _ = std::fs::remove_file(work.join("steps.csv"));
    if !args.no_check_ends {
        check_ends(&src, &exe, &step, good, bad).map_err(Error::new)?;
    }
    git(&src, &["bisect", "start", bad, good]).map_err(Error::new)?;
    println!(
        "bisect: {} between good {good} and bad {bad}",
        src.display()
    );
    let log_path = work.join("bisect.log");
    let transcript = bisect_run(&src, &exe, &step, &log_path);
    // The steps, as the step processes recorded them.
    let steps = std::fs::read_to_string(work.join("steps.csv")).unwrap_or_default();
    println!("\nbisect: steps (commit, build s, test s, verdict, subject):");
    for l in steps.lines() {
        println!("  {l}");
    }
    let first_bad = transcript
        .lines()
        .find_map(|l| l.strip_suffix(" is the first bad commit"))
        .map(str::to_string);
    println!(
        "bisect: {:.0} s in all; transcript in {}",
        started.elapsed().as_secs_f64(),
        log_path.display()
    );
    match first_bad {
        Some(sha) => say_first_bad(args, &src, &work, &sha, &log_path),
        None => {
            let tail: Vec<&str> = transcript.lines().rev().take(8).collect();
            eprintln!(
                "bisect: no single first bad commit; git said:\n{}",
                tail.into_iter().rev().collect::<Vec<_>>().join("\n")
            );
            Ok(Exit::Fail)
        }
    }
}

/// `--mesa-src` is a clean git work tree holding `--good` and `--bad`.
fn check_tree(src: &Path, good: &str, bad: &str) -> Result<(), Error> {
    if let Err(e) = git(src, &["rev-parse", "--git-dir"]) {
        return Err(Error::new(format!(
            "--mesa-src {}: not a git work tree ({e}); fix: clone Mesa, or `git init` an unpacked source and commit it",
            src.display()
        )));
    }
    match git(src, &["status", "--porcelain", "--untracked-files=no"]) {
        Ok(s) if s.is_empty() => {}
        Ok(s) => {
            return Err(Error::new(format!(
                "--mesa-src {} has uncommitted changes, which bisect's checkouts would clobber:\n{s}\nfix: commit or stash them",
                src.display()
            )));
        }
        Err(e) => return Err(Error::new(e)),
    }
    for (flag, rev) in [("--good", good), ("--bad", bad)] {
        if let Err(e) = git(
            src,
            &["rev-parse", "--verify", &format!("{rev}^{{commit}}")],
        ) {
            return Err(Error::new(format!(
                "{flag} {rev}: not a commit of {} ({e})",
                src.display()
            )));
        }
    }
    Ok(())
}

/// One commit's build configuration: its option file, the derived options (the user's
/// `--meson-option`s after them) with the notes, and the meson it asks for.
struct Configuration {
    file: String,
    args: Vec<String>,
    notes: Vec<String>,
    meson_min: Option<Version>,
}

impl Configuration {
    /// `rev`'s configuration, read with git; `Err` names the revision, the file and what
    /// meson would refuse in it.
    fn at(src: &Path, rev: &str, extra: &[String]) -> Result<Configuration, String> {
        let (text, file) = meson_options::at_revision(src, rev)?;
        let tree = meson_options::parse(&text).map_err(|e| format!("{rev}:{file}: {e}"))?;
        let derived = meson_options::derive(&tree).map_err(|e| format!("{rev}:{file}: {e}"))?;
        let mut args = derived.args;
        args.extend(extra.iter().cloned());
        let problems = meson_options::check(&args, &tree);
        if !problems.is_empty() {
            return Err(format!(
                "{rev}:{file}: meson would refuse these options:\n  {}\nfix: change or drop the --meson-option named (the others are derived from the tree)",
                problems.join("\n  ")
            ));
        }
        let meson_min = git(src, &["show", &format!("{rev}:meson.build")])
            .ok()
            .and_then(|t| meson::required(&t));
        Ok(Configuration {
            file,
            args,
            notes: derived.notes,
            meson_min,
        })
    }

    /// The build directory of this option list: one per distinct list, so each side of a
    /// renamed option keeps its own incremental build.
    fn build_dir(&self, work: &Path) -> PathBuf {
        work.join(format!(
            "build-{:08x}",
            umbra_report::names::fnv1a(&self.args.join("\n"))
        ))
    }
}

/// Both ends' configurations, said; the meson they need found or brought (with meson, not
/// `--build-script`), and with `--configure-only` each distinct option list set up.
fn prepare(
    args: &BisectArgs,
    [good, bad]: [&str; 2],
    src: &Path,
    work: &Path,
    script: Option<&Path>,
) -> Result<(), Error> {
    if let Some(s) = script {
        if !s.is_file() {
            return Err(Error::new(format!(
                "--build-script {}: no such file",
                s.display()
            )));
        }
    }
    let mut ends = Vec::new();
    for (flag, rev) in [("--good", good), ("--bad", bad)] {
        let c = Configuration::at(src, rev, &args.meson_option)
            .map_err(|e| Error::new(format!("{flag} {e}")))?;
        println!(
            "bisect: {flag} {rev}: {}{}; options: {}",
            c.file,
            c.meson_min
                .as_ref()
                .map_or(String::new(), |v| format!(", meson >= {v}")),
            c.args.join(" ")
        );
        for n in &c.notes {
            println!("bisect:   {n}");
        }
        ends.push(c);
    }
    if script.is_some() {
        return Ok(());
    }
    let min = ends.iter().filter_map(|c| c.meson_min.clone()).max();
    let meson = meson_for(work, min.as_ref())?;
    if args.configure_only {
        // meson reads the work tree: each end is set up at its own checkout, and the tree
        // is left where it was.
        let here = match git(src, &["symbolic-ref", "-q", "--short", "HEAD"]) {
            Ok(branch) if !branch.is_empty() => branch,
            _ => git(src, &["rev-parse", "HEAD"]).map_err(Error::new)?,
        };
        let mut outcome = Ok(());
        for (c, rev) in ends.iter().zip([good, bad]) {
            outcome = git(src, &["checkout", "-q", "--detach", rev])
                .and_then(|_| setup(&meson, src, &c.build_dir(work), &c.args, None));
            if outcome.is_err() {
                break;
            }
        }
        git(src, &["checkout", "-q", &here]).map_err(Error::new)?;
        outcome.map_err(Error::new)?;
    }
    Ok(())
}

/// A meson of at least `min`: found, or brought into the work directory with pip.
fn meson_for(work: &Path, min: Option<&Version>) -> Result<PathBuf, Error> {
    match meson::find(work, min) {
        Ok(m) => Ok(m),
        Err(why) => {
            let Some(min) = min else {
                return Err(Error::new(format!(
                    "{why}; fix: apt-get install meson ninja-build"
                )));
            };
            println!(
                "bisect: {why}: bringing meson >= {min} into {} with pip",
                meson::brought_dir(work).display()
            );
            let m = meson::bring(work, min).map_err(Error::new)?;
            println!(
                "bisect: meson {} in {}",
                meson::version_of(&m).map_or("?".into(), |v| v.to_string()),
                m.display()
            );
            Ok(m)
        }
    }
}

/// `meson setup` of `build` (unless it is set up already), its output to `log` or the
/// terminal.
fn setup(
    meson: &Path,
    src: &Path,
    build: &Path,
    options: &[String],
    log: Option<&Path>,
) -> Result<(), String> {
    if build.join("build.ninja").is_file() {
        return Ok(());
    }
    let t = Instant::now();
    let mut cmd = meson::command("meson", meson);
    cmd.arg("setup").arg(build).arg(src).args(options);
    if let Some(f) = log.and_then(|l| {
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(l)
            .ok()
    }) {
        if let Ok(f2) = f.try_clone() {
            cmd.stderr(Stdio::from(f2));
        }
        cmd.stdout(Stdio::from(f));
    } else {
        println!(
            "bisect: configuring {}: {} setup {} {} {}",
            build.display(),
            meson.display(),
            build.display(),
            src.display(),
            options.join(" ")
        );
    }
    match cmd.status() {
        Ok(s) if s.success() => {
            println!(
                "bisect: configured {} in {:.0} s; its first build compiles all of Mesa's llvmpipe, softpipe, zink and lavapipe (about 40 min on 2 cores), later ones only what a commit touched",
                build.display(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        Ok(s) => Err(format!(
            "meson setup {} failed ({s}); fix: install Mesa's build dependencies (docs/bisection.md, \"Bisecting a Mesa tree\") and check that `python3` has mako",
            build.display()
        )),
        Err(e) => Err(format!(
            "cannot run {}: {e}; fix: apt-get install meson ninja-build",
            meson.display()
        )),
    }
}

/// The step's arguments (`umbra bisect-step …`), every path absolute (git bisect run works
/// in the source tree), in the order git's `running …` lines have always shown them.
fn step_argv(args: &BisectArgs, src: &Path, work: &Path, script: Option<&Path>) -> Vec<String> {
    let selection = Selection {
        cases: absolute(&args.selection.cases),
        expectations: absolute(&args.selection.expectations),
        filter: None,
        backend: args.selection.backend.clone(),
    };
    let mut step: Vec<String> = vec![
        "bisect-step".into(),
        "--src".into(),
        src.display().to_string(),
        "--work".into(),
        work.display().to_string(),
    ];
    if let Some(f) = &args.selection.filter {
        step.extend(["--filter".into(), f.clone()]);
    }
    if let Some(s) = script {
        step.extend(["--build-script".into(), s.display().to_string()]);
    }
    for o in &args.meson_option {
        step.extend(["--meson-option".into(), o.clone()]);
    }
    step.extend(selection.argv());
    if let Some(c) = &args.card {
        step.extend(["--card".into(), c.clone()]);
    }
    step
}

/// `git bisect run` of the step, its output streamed (each step's line among it) and kept;
/// the transcript and git's bisect log go to `log_path`, and the tree is reset. Returns the
/// transcript.
fn bisect_run(src: &Path, exe: &Path, step: &[String], log_path: &Path) -> String {
    let mut transcript = String::new();
    match Command::new("git")
        .arg("-C")
        .arg(src)
        .args(["bisect", "run"])
        .arg(exe)
        .args(step)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
    {
        Ok(mut child) => {
            if let Some(out) = child.stdout.take() {
                use std::io::BufRead as _;
                for line in std::io::BufReader::new(out).lines().map_while(Result::ok) {
                    println!("{line}");
                    transcript.push_str(&line);
                    transcript.push('\n');
                }
            }
            let _ = child.wait();
        }
        Err(e) => transcript = format!("cannot run git bisect run: {e}"),
    }
    let bisect_log = git(src, &["bisect", "log"]).unwrap_or_default();
    let _ = git(src, &["bisect", "reset"]);
    if let Ok(mut f) = std::fs::File::create(log_path) {
        let command: Vec<String> = std::env::args().skip(1).collect();
        let _ = write!(
            f,
            "# umbra {}\n{transcript}\n# git bisect log\n{bisect_log}\n",
            command.join(" ")
        );
    }
    transcript
}

/// Says the first bad commit and the case's failure on it (from its step's report), and,
/// with `--repro`, writes the bundle of its first failed run.
fn say_first_bad(
    args: &BisectArgs,
    src: &Path,
    work: &Path,
    sha: &str,
    log_path: &Path,
) -> Outcome {
    let subject = git(src, &["log", "-1", "--format=%h %s", sha]).unwrap_or_default();
    println!("bisect: first bad commit: {sha}\nbisect:   {subject}");
    let short = git(src, &["rev-parse", "--short=12", sha]).unwrap_or(sha.to_string());
    say_card_changes(src, work, &short, &args.good);
    let report = work
        .join("reports")
        .join(&short)
        .join("latest")
        .join("report.json");
    let Some(r) = report
        .exists()
        .then(|| umbra_report::Report::read(&report))
        .transpose()
        .map_err(|e| Error::new(format!("bisect: the first bad commit's report: {e}")))?
    else {
        if args.repro.is_some() {
            return Err(Error::new(format!(
                "--repro: no report of the first bad commit at {}",
                report.display()
            )));
        }
        return Ok(Exit::Pass);
    };
    println!("bisect: the case's failure on it ({}):", report.display());
    for run in &r.runs {
        let status = run.status.as_str();
        if matches!(
            status,
            "Fail" | "Crash" | "Timeout" | "UnexpectedPass" | "OrderDependent"
        ) {
            println!(
                "  {status} {}: {}",
                run.name,
                run.reason.lines().next().unwrap_or("")
            );
        }
    }
    match &args.repro {
        Some(dir) => repro_first_bad(
            args,
            &r,
            sha,
            &work.join("prefixes").join(&short),
            log_path,
            dir,
        ),
        None => Ok(Exit::Pass),
    }
}

/// The behaviour-card entries that changed at the first bad commit `short`, first: against
/// its parent's cards where that commit was tested, else the good end's.
fn say_card_changes(src: &Path, work: &Path, short: &str, good: &str) {
    let cards_of = |rev: &str| -> Option<(String, Vec<crate::judge::card::Card>)> {
        let s = git(src, &["rev-parse", "--short=12", rev]).ok()?;
        let text =
            std::fs::read_to_string(work.join("reports").join(&s).join("cards.json")).ok()?;
        Some((s, serde_json::from_str(&text).ok()?))
    };
    let Some((_, bad)) = cards_of(short) else {
        println!("bisect: no behaviour cards of the first bad commit to compare");
        return;
    };
    let parent = format!("{short}^");
    let Some((before, old)) = cards_of(&parent).or_else(|| cards_of(good)) else {
        println!("bisect: no behaviour cards of a good commit to compare with");
        return;
    };
    let lines = crate::judge::card::changes_between(&old, &bad);
    println!(
        "bisect: behaviour-card changes from {before} to {short}: {}",
        if lines.is_empty() { "none" } else { "" }
    );
    for l in lines {
        println!("  {l}");
    }
}

/// `--repro DIR`: the bundle of the first bad commit's first failed run (`umbra repro` on
/// its prefix), its issue.md naming the commit and carrying the bisection log.
fn repro_first_bad(
    args: &BisectArgs,
    report: &umbra_report::Report,
    sha: &str,
    prefix: &Path,
    log: &Path,
    dir: &Path,
) -> Outcome {
    let Some(run) = report
        .runs
        .iter()
        .find(|r| r.status == "Fail")
        .map(|r| r.name.as_str())
    else {
        return Err(Error::new(
            "--repro: the first bad commit's report has no failed run to reproduce (a crash or timeout has no frame to probe)",
        ));
    };
    println!(
        "bisect: the repro bundle of {run} on {sha}: {}",
        dir.display()
    );
    let Ok(exe) = crate::harness::own_libc::self_exe() else {
        // Not said, as before: this executable was found moments ago.
        return Err(Error::said(Exit::CouldNotRun));
    };
    let mut cmd = Command::new(exe);
    cmd.args(["repro", run, "--out"])
        .arg(dir)
        .args(["--first-bad", sha])
        .arg("--mesa")
        .arg(prefix)
        .arg("--bisect-log")
        .arg(log);
    // Not Selection::argv(): repro takes no --filter, and its paths are made absolute.
    let selection = &args.selection;
    for (flag, v) in [
        ("--cases", &selection.cases),
        ("--expectations", &selection.expectations),
    ] {
        cmd.arg(flag).arg(absolute(v));
    }
    match cmd.status() {
        // umbra repro's own exit, passed on (a signal: could not run).
        Ok(s) => Ok(s.code().map_or(Exit::CouldNotRun, Exit::of_code)),
        Err(e) => Err(Error::new(format!("cannot start umbra repro: {e}"))),
    }
}

/// Builds and tests the two ends first: a bisection whose "good" commit already fails, or
/// whose "bad" one passes, would name a meaningless commit. The tree is left where it was.
fn check_ends(
    src: &Path,
    exe: &Path,
    step: &[String],
    good: &str,
    bad: &str,
) -> Result<(), String> {
    let here = match git(src, &["symbolic-ref", "-q", "--short", "HEAD"]) {
        Ok(branch) if !branch.is_empty() => branch,
        _ => git(src, &["rev-parse", "HEAD"])?,
    };
    let mut outcome = Ok(());
    for (rev, want, what) in [(good, Exit::Pass, "good"), (bad, Exit::Fail, "bad")] {
        println!("bisect: checking the {what} end, {rev}");
        if let Err(e) = git(src, &["checkout", "-q", "--detach", rev]) {
            outcome = Err(e);
            break;
        }
        let code = Command::new(exe)
            .args(step)
            .current_dir(src)
            .status()
            .ok()
            .and_then(|s| s.code());
        if code == Some(i32::from(want.code())) {
            continue;
        }
        outcome = Err(match (what, code) {
            (_, Some(SKIP)) => format!(
                "the {what} commit {rev} could not be built or tested (see its logs under the work directory); pick another {what} commit"
            ),
            ("good", _) => format!(
                "the chosen cases already fail on the good commit {rev}: pick an older --good, or a --filter/--backend that passes there (its report is under the work directory's reports/)"
            ),
            _ => format!(
                "the chosen cases pass on the bad commit {rev}: nothing to bisect; check --filter and --backend (umbra conformance --mesa on that build shows what fails)"
            ),
        });
        break;
    }
    git(src, &["checkout", "-q", &here])?;
    outcome
}

/// A step's exit code that `git bisect run` reads as "skip this commit" (125).
const SKIP: i32 = Exit::CouldNotRun.code() as i32;

/// `umbra bisect-step`: one commit (HEAD of the source tree): build, install into its own
/// prefix, test. Its outcome: a pass (good), a failure (bad), could not run (125, skip: did
/// not build, or could not be tested).
pub fn step(args: &BisectStepArgs) -> Outcome {
    let (src, work) = (PathBuf::from(&args.src), PathBuf::from(&args.work));
    let sha = git(&src, &["rev-parse", "--short=12", "HEAD"]).unwrap_or_else(|_| "unknown".into());
    let subject = git(&src, &["log", "-1", "--format=%s"]).unwrap_or_default();
    if !umbra_owned::owned(&work) {
        return Err(Error::new(format!(
            "--work {}: not a work directory umbra bisect made (no {} in it); start with umbra bisect, which makes it",
            work.display(),
            umbra_owned::MARKER
        )));
    }
    let prefix = work.join("prefixes").join(&sha);
    let log = work.join("logs");
    let _ = std::fs::create_dir_all(&log);
    let build_log = log.join(format!("{sha}-build.log"));
    let t = Instant::now();
    let built = if prefix.is_dir() {
        true
    } else {
        let run = |cmd: &mut Command| -> bool {
            let Ok(f) = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&build_log)
            else {
                return false;
            };
            let f2 = f.try_clone().ok();
            cmd.current_dir(&src).stdout(Stdio::from(f));
            if let Some(f2) = f2 {
                cmd.stderr(Stdio::from(f2));
            }
            cmd.status().is_ok_and(|s| s.success())
        };
        // This commit's options, from its own option file.
        match Configuration::at(&src, "HEAD", &args.meson_option) {
            Err(e) => {
                let _ = std::fs::write(&build_log, format!("{e}\n"));
                false
            }
            Ok(c) => {
                let _ = std::fs::write(&build_log, format!("# {}: {}\n", c.file, c.args.join(" ")));
                match args.build_script.as_deref() {
                    Some(script) => run(Command::new(script).arg(&src).arg(&prefix).args(&c.args)),
                    None => {
                        let build = c.build_dir(&work);
                        match meson::find(&work, c.meson_min.as_ref()).and_then(|m| {
                            setup(&m, &src, &build, &c.args, Some(&build_log)).map(|()| m)
                        }) {
                            Err(e) => {
                                let _ = std::fs::write(&build_log, format!("{e}\n"));
                                false
                            }
                            Ok(meson) => {
                                run(meson::command("ninja", &meson).arg("-C").arg(&build))
                                    && run(meson::command("meson", &meson)
                                        .args(["install", "--no-rebuild", "--quiet", "-C"])
                                        .arg(&build)
                                        .arg("--destdir")
                                        .arg(&prefix))
                            }
                        }
                    }
                }
            }
        }
    };
    let build_s = t.elapsed().as_secs_f64();
    let record = |test_s: f64, verdict: &str| {
        if let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(work.join("steps.csv"))
        {
            let _ = writeln!(
                f,
                "{sha},{build_s:.1},{test_s:.1},{verdict},{}",
                subject.replace(',', ";")
            );
        }
        println!(
            "bisect-step: {sha} {subject}: built in {build_s:.1} s, tested in {test_s:.1} s: {verdict}"
        );
    };
    if !built {
        let _ = std::fs::remove_dir_all(&prefix);
        record(0.0, "skip (does not build; see the log)");
        return Ok(Exit::CouldNotRun);
    }
    let t = Instant::now();
    let Ok(exe) = crate::harness::own_libc::self_exe() else {
        // Not said, as before: a skip.
        return Err(Error::said(Exit::CouldNotRun));
    };
    let report = work.join("reports").join(&sha);
    // Every step's cards, so the end can name what changed at the first bad commit.
    let cards =
        crate::harness::cards::measure_in_child(&exe, prefix.as_os_str(), &args.selection.backend);
    if let Ok(c) = &cards {
        let _ = std::fs::create_dir_all(&report);
        let _ = std::fs::write(
            report.join("cards.json"),
            serde_json::to_string_pretty(c).unwrap_or_default(),
        );
    }
    let code = match &args.card {
        Some(target) => card_verdict(target, cards, &log.join(format!("{sha}-test.log"))),
        None => test_cases(&exe, &prefix, &report, &work, &log, &sha, &args.selection),
    };
    let test_s = t.elapsed().as_secs_f64();
    let (verdict, exit) = match code.map(Exit::of_code) {
        Some(Exit::Pass) => ("good", Exit::Pass),
        Some(Exit::Fail) => ("bad", Exit::Fail),
        _ => (
            "skip (could not be tested; see the test log)",
            Exit::CouldNotRun,
        ),
    };
    record(test_s, verdict);
    Ok(exit)
}

/// A step's test of the chosen cases: `umbra conformance --mesa PREFIX`, goldens off; its
/// exit code.
fn test_cases(
    exe: &Path,
    prefix: &Path,
    report: &Path,
    work: &Path,
    log: &Path,
    sha: &str,
    selection: &Selection,
) -> Option<i32> {
    let mut cmd = Command::new(exe);
    cmd.arg("conformance")
        .arg("--mesa")
        .arg(prefix)
        .args(["--golden", "none", "--out"])
        .arg(report)
        // One judging cache for every step: umbra stays fixed while Mesa changes, so the
        // truth and reference of each point are computed at the first step only.
        .arg("--judge-cache")
        .arg(work.join("cache").join("judge"))
        .args(selection.argv());
    let test_log = log.join(format!("{sha}-test.log"));
    if let Ok(f) = std::fs::File::create(&test_log) {
        cmd.stdout(Stdio::from(f));
    }
    cmd.env_remove(crate::harness::mesa_build::ENV)
        .status()
        .ok()
        .and_then(|s| s.code())
}

/// `--card KEY=VALUE`: good (0) when every measured backend's entry KEY has VALUE, bad (1)
/// when one's differs, could not run (125) without cards or without the entry; the verdict
/// per backend goes to `test_log`.
fn card_verdict(
    target: &str,
    cards: Result<Vec<crate::judge::card::Card>, String>,
    test_log: &Path,
) -> Option<i32> {
    let (key, want) = target.split_once('=')?;
    let mut lines = Vec::new();
    let skip = i32::from(Exit::CouldNotRun.code());
    let mut code = i32::from(Exit::Pass.code());
    match cards {
        Err(e) => {
            lines.push(format!("no cards: {e}"));
            code = skip;
        }
        Ok(cards) if cards.is_empty() => {
            lines.push("no cards: no backend was measured".into());
            code = skip;
        }
        Ok(cards) => {
            for c in &cards {
                match c.entries.iter().find(|e| e.key == key) {
                    // A probe that could not measure says nothing of good or bad.
                    Some(e) if e.value.starts_with("not measured") => {
                        lines.push(format!("{}: {key} {}", c.backend, e.value));
                        code = skip;
                    }
                    Some(e) if e.value == want => {
                        lines.push(format!("{}: {key} = {}", c.backend, e.value))
                    }
                    Some(e) => {
                        lines.push(format!("{}: {key} = {} (not {want})", c.backend, e.value));
                        if code != skip {
                            code = i32::from(Exit::Fail.code());
                        }
                    }
                    None => {
                        lines.push(format!("{}: no entry {key}", c.backend));
                        code = skip;
                    }
                }
            }
        }
    }
    let _ = std::fs::write(test_log, lines.join("\n") + "\n");
    Some(code)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::judge::card::{Card, Entry, Sure};

    fn card(backend: &str, value: &str) -> Card {
        Card {
            backend: backend.into(),
            driver: "d".into(),
            release: "mesa-26.2.6".into(),
            entries: vec![Entry::new(
                "offset-unit.depth16.z0.375",
                "r",
                value.into(),
                None,
                "s",
                Some(true),
                "p",
                Sure::Exact,
            )],
            renders: 0,
            seconds: 0.0,
        }
    }

    /// `--card KEY=VALUE`: good where every backend's entry has the value, bad where one's
    /// differs, a skip where there are no cards or no such entry.
    #[test]
    fn a_card_step_is_good_bad_or_skipped_by_the_entry() {
        let log = std::env::temp_dir().join(format!("umbra-card-step-{}.log", std::process::id()));
        let target = "offset-unit.depth16.z0.375=4 codes";
        let v = |cards| card_verdict(target, cards, &log);
        assert_eq!(v(Ok(vec![card("gl33/zink", "4 codes")])), Some(0));
        assert_eq!(
            v(Ok(vec![
                card("gl33/zink", "4 codes"),
                card("gles3/zink", "2 codes")
            ])),
            Some(1)
        );
        assert!(std::fs::read_to_string(&log).is_ok_and(|t| t.contains("2 codes (not 4 codes)")));
        assert_eq!(v(Err("no driver".into())), Some(125));
        assert_eq!(v(Ok(Vec::new())), Some(125));
        assert_eq!(
            v(Ok(vec![card("gl33/zink", "not measured: no crossing")])),
            Some(125)
        );
        assert_eq!(
            card_verdict(
                "no-such-entry=x",
                Ok(vec![card("gl33/zink", "4 codes")]),
                &log
            ),
            Some(125)
        );
        let _ = std::fs::remove_file(&log);
    }
}
