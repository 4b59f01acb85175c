//! `umbra bisect --mesa-src DIR --good REV --bad REV`: finds the Mesa commit that broke a
//! case, with `git bisect run` over a Mesa source tree.
//!
//! - **Configure once.** The build directory (default `target/umbra/bisect/build`) is set up
//!   with meson the first time, for the drivers umbra runs: llvmpipe and softpipe (swrast),
//!   zink, lavapipe, surfaceless EGL through glvnd, no GLX or window systems
//!   ([`MESON_OPTIONS`]; add your own with `--meson-option`). Later commits rebuild
//!   incrementally in the same directory (ninja rebuilds what changed; meson reconfigures
//!   itself when a build file changed).
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
//! `--build-script PATH` replaces meson: it is run as `PATH SRC PREFIX` in the source tree
//! and must install a Mesa (or, in umbra's own tests, a fake build) into PREFIX.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::cli::{BisectArgs, BisectStepArgs, Selection};
use crate::exit::{Error, Exit, Outcome};

/// The one-time configuration: the smallest Mesa that holds every driver umbra runs.
pub const MESON_OPTIONS: &[&str] = &[
    "--prefix=/usr",
    "--libdir=lib/x86_64-linux-gnu",
    "--buildtype=release",
    "-Db_ndebug=true",
    "-Dplatforms=",
    "-Dglx=disabled",
    "-Degl=enabled",
    "-Dgbm=disabled",
    "-Dglvnd=true",
    "-Dgles1=disabled",
    "-Dgles2=enabled",
    "-Dopengl=true",
    "-Dshared-glapi=enabled",
    "-Dgallium-drivers=swrast,zink",
    "-Dvulkan-drivers=swrast",
    "-Dllvm=enabled",
    "-Dshared-llvm=enabled",
    "-Ddri3=disabled",
    "-Dgallium-va=disabled",
    "-Dgallium-vdpau=disabled",
    "-Dgallium-xa=disabled",
    "-Dgallium-nine=false",
    "-Dgallium-opencl=disabled",
    "-Dosmesa=false",
    "-Dvalgrind=disabled",
    "-Dlibunwind=disabled",
    "-Dbuild-tests=false",
    "-Dvideo-codecs=",
    "-Dvulkan-layers=",
    "-Dtools=",
];

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
    let work = absolute(&args.work);
    // The work directory is umbra's (its steps, prefixes and logs are replaced and removed):
    // a directory that holds anything else is refused, never emptied.
    umbra_owned::claim(&work, "umbra bisect").map_err(|e| Error::new(format!("--work: {e}")))?;
    let _ = std::fs::remove_file(work.join("steps.csv"));
    let script = args.build_script.as_deref().map(absolute);
    configure(args, &src, &work, script.as_deref())?;
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

/// The build: `--build-script`, which must exist, or meson, configured once in `WORK/build`.
fn configure(
    args: &BisectArgs,
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
        return Ok(());
    }
    let build = work.join("build");
    if build.join("build.ninja").is_file() {
        return Ok(());
    }
    let t = Instant::now();
    let mut cmd = Command::new("meson");
    cmd.arg("setup").arg(&build).arg(src).args(MESON_OPTIONS);
    cmd.args(&args.meson_option);
    println!("bisect: configuring once: {cmd:?}");
    match cmd.status() {
        Ok(s) if s.success() => {
            println!(
                "bisect: configured in {:.0} s; the first build compiles all of Mesa's swrast, zink and lavapipe (about 40 min on 2 cores), later ones only what a commit touched",
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        Ok(s) => Err(Error::new(format!(
            "meson setup failed ({s}); fix: install Mesa's build dependencies (README, \"Bisecting a Mesa tree\") and check that `python3` has mako"
        ))),
        Err(e) => Err(Error::new(format!(
            "cannot run meson: {e}; fix: apt-get install meson ninja-build"
        ))),
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
        match args.build_script.as_deref() {
            Some(script) => run(Command::new(script).arg(&src).arg(&prefix)),
            None => {
                let build = work.join("build");
                run(Command::new("ninja").arg("-C").arg(&build))
                    && run(Command::new("meson")
                        .args(["install", "--no-rebuild", "--quiet", "-C"])
                        .arg(&build)
                        .arg("--destdir")
                        .arg(&prefix))
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
