//! umbra's developer commands, rust-analyzer style: one module per command; clap parses the
//! command line (the only dependency), and the commands that run `umbra` pass their arguments
//! through untouched, so `cargo xtask conformance --help` is `umbra conformance --help`.
//!
//! - `cargo xtask conformance [ARGS]`: installs the Mesa packages when missing and allowed,
//!   then runs `umbra conformance ARGS` and passes its exit code through (0 as expected,
//!   1 regressions, 125 could not run), so `git bisect run cargo xtask conformance` works.
//! - `cargo xtask test`: the same set-up, then the whole test suite, a conformance run, the
//!   self-test, a fixed-seed soak of generated cases, and the catalogue again on the newest
//!   Mesa Debian ships (sid, fetched with `fetch-mesa`).
//! - `cargo xtask soak --seed S --count N`: generated cases on every backend, judged alone,
//!   failures by class (`umbra soak`).
//! - `cargo xtask selftest`: every injected fault on every backend it applies to; a fault the
//!   judge does not catch fails it. Part of `cargo xtask test`.
//! - `cargo xtask sweep [--scene CASE] [--backend ID]...`: speed against error, a technique
//!   matrix measured per backend (`umbra sweep`): CSV, Pareto plot (PNG, SVG) and an HTML
//!   section under target/umbra/sweep/.
//! - `cargo xtask bless [ARGS]`: a conformance run that accepts every changed or new golden
//!   (`umbra conformance --bless`, which alone gives its workers `INSTA_UPDATE=always`), then lists what changed under `golden/` for review in
//!   `git diff` before committing. Refused under `CI=true`: CI never writes a golden.
//! - `cargo xtask fetch-mesa [--suite SUITE] [--dir DIR]`: any Debian suite's Mesa (default
//!   bookworm-backports, 25.0.7; sid is 26.2.6), with its own C library where the suite's is
//!   newer than the machine's, unpacked without changing the system (`fetch_mesa`), for
//!   `--mesa DIR`.
//! - `cargo xtask gpu-bundle [--out DIR]`: a self-contained folder (stripped release umbra,
//!   cases, expectations, run.sh) that runs the catalogue on every hardware backend of a GPU
//!   machine, judged by the specs (`gpu_bundle`).
//! - `cargo xtask mesa-ci --driver DRIVER --out DIR [--fraction N] [--run]`: what a Mesa
//!   driver's `ci/` directory would hold to run umbra under deqp-runner (`mesa_ci`), and with
//!   `--run` the suite run by deqp-runner 0.24.
//! - `cargo xtask drivers --baseline A --candidate B`, `cargo xtask bisect --mesa-src DIR
//!   --good REV --bad REV`, `cargo xtask reduce CASE --point ID --backend ID`: the same set-up,
//!   then `umbra drivers`, `umbra bisect`, `umbra reduce`.

mod bless_patch;
mod disk;
mod fetch_mesa;
mod gpu_bundle;
mod mesa;
mod mesa_ci;
mod test_pool;

use std::path::PathBuf;
use std::process::{Command, ExitCode};

use clap::Arg;

/// The `umbra` commands xtask runs after the set-up (Mesa packages), with their help.
const PASS_THROUGH: &[(&str, &str)] = &[
    (
        "conformance",
        "Install the Mesa packages when missing and allowed, then `umbra conformance ARGS` (exit code passed through: 0 as expected, 1 regressions, 125 could not run)",
    ),
    (
        "selftest",
        "The same set-up, then `umbra selftest ARGS`: every injected fault on every backend it applies to",
    ),
    (
        "soak",
        "The same set-up, then `umbra soak ARGS`: generated cases (--seed S --count N) on every backend, judged alone, failures by class",
    ),
    (
        "sweep",
        "The same set-up, then `umbra sweep ARGS`: speed against error (CSV, Pareto plot, HTML)",
    ),
    (
        "drivers",
        "The same set-up, then `umbra drivers ARGS`: the catalogue on two Mesa builds, every change",
    ),
    (
        "bisect",
        "The same set-up, then `umbra bisect ARGS`: the first Mesa commit that breaks the chosen points",
    ),
    (
        "reduce",
        "The same set-up, then `umbra reduce ARGS`: a failing point shrunk to a minimal case",
    ),
];

fn command() -> clap::Command {
    let rest = || {
        Arg::new("args")
            .value_name("ARGS")
            .num_args(0..)
            .trailing_var_arg(true)
            .allow_hyphen_values(true)
    };
    let mut c = clap::Command::new("cargo xtask")
        .bin_name("cargo xtask")
        .about("umbra's developer commands")
        .subcommand_required(true)
        .arg_required_else_help(true);
    for (name, about) in PASS_THROUGH {
        c = c.subcommand(
            clap::Command::new(*name)
                .about(*about)
                .after_help(format!(
                    "ARGS are umbra's: see `cargo xtask {name} --help`."
                ))
                .disable_help_flag(true)
                .arg(rest().help("arguments for `umbra`, including --help")),
        );
    }
    c.subcommand(
        clap::Command::new("test")
            .about("The set-up, the whole test suite (cargo test --workspace ARGS), then conformance, selftest, a 60-case soak and conformance on Debian sid's Mesa, as CI runs them")
            .arg(rest().help("extra arguments for cargo test")),
    )
    .subcommand(
        clap::Command::new("bless")
            .about("A conformance run that accepts every changed or new golden, then lists what changed under golden/ for review (refused under CI=true)")
            .disable_help_flag(true)
            .arg(rest().help("arguments for `umbra conformance` (e.g. --filter, --backend)")),
    )
    .subcommand(
        clap::Command::new("mesa-ci")
            .about("Write what a Mesa driver's ci/ directory would hold to run umbra under deqp-runner (suite TOML, caselist, fails/flakes/skips from umbra's expectations); with --run, run it with deqp-runner 0.24")
            .arg(Arg::new("driver").long("driver").value_name("DRIVER").required(true).help("the driver: llvmpipe, softpipe, zink, lavapipe, or a device's name (radeonsi …)"))
            .arg(Arg::new("out").long("out").value_name("DIR").required(true).help("where to write the files (and results/ with --run)"))
            .arg(Arg::new("fraction").long("fraction").value_name("N").value_parser(clap::value_parser!(u32).range(1..)).help("with --run: run 1 test of every N (deqp-runner --fraction)"))
            .arg(Arg::new("run").long("run").action(clap::ArgAction::SetTrue).help("run the suite with deqp-runner (installed with cargo when missing)"))
            .arg(Arg::new("budget").long("budget").value_name("DURATION").help("only the tests of a pre-merge tier for this wall time (umbra tier --budget: 90s, 5m, premerge, smoke), chosen by what they catch"))
            .arg(Arg::new("bundle").long("bundle").action(clap::ArgAction::SetTrue).help("make DIR self-contained for a CI job: umbra, its cases, expectations and tiers beside the suite, its paths filled in by DIR/run.sh where the job runs it (Mesa's pipeline: docs/ci/mesa/)")),
    )
    .subcommand(
        clap::Command::new("gpu-bundle")
            .about("Write a self-contained folder (a stripped release umbra, the cases, the expectations, run.sh) that runs the catalogue judged by the specs on every hardware backend of a GPU machine, at most 48 MiB")
            .arg(Arg::new("out").long("out").value_name("DIR").help("where to write the bundle [default: target/umbra/gpu-bundle]"))
            .arg(
                Arg::new("profile")
                    .long("profile")
                    .value_name("PROFILE")
                    .default_value("bundle")
                    .value_parser(["bundle", "dev"])
                    .help("bundle: the stripped release build; dev: the debug build (tests; over the size limit)"),
            ),
    )
    .subcommand(
        clap::Command::new("fetch-mesa")
            .about("Download any Debian suite's Mesa (sid, trixie, trixie-backports, bookworm-backports …) with what it links against, and unpack it without touching the system, for --mesa DIR")
            .arg(Arg::new("dir").long("dir").value_name("DIR").help("where to unpack [default: target/mesa/SUITE]"))
            .arg(
                Arg::new("suite")
                    .long("suite")
                    .value_name("SUITE")
                    .default_value("bookworm-backports")
                    .help("Debian suite to take Mesa from"),
            ),
    )
}

fn main() -> ExitCode {
    let m = match command().try_get_matches() {
        Ok(m) => m,
        Err(e) => {
            let _ = e.print();
            // A usage error could not run: 125, as umbra's own (clap's default is 2).
            return ExitCode::from(if e.use_stderr() {
                COULD_NOT_RUN as u8
            } else {
                0
            });
        }
    };
    let (name, sub) = m.subcommand().unwrap_or(("", &m));
    let args: Vec<String> = sub
        .try_get_many::<String>("args")
        .ok()
        .flatten()
        .into_iter()
        .flatten()
        .cloned()
        .collect();
    let code = match name {
        "test" => test(&args),
        "bless" => bless(&args),
        "gpu-bundle" => gpu_bundle::main(
            sub.get_one::<String>("out").map(PathBuf::from),
            sub.get_one::<String>("profile")
                .map_or("bundle", String::as_str),
            &workspace_root(),
        ),
        "fetch-mesa" => fetch_mesa::main(
            sub.get_one::<String>("suite")
                .map_or("bookworm-backports", String::as_str),
            sub.get_one::<String>("dir").map(PathBuf::from),
            &workspace_root(),
        ),
        "mesa-ci" => {
            mesa::ensure();
            mesa_ci::main(
                &mesa_ci::Options {
                    driver: sub.get_one::<String>("driver").cloned().unwrap_or_default(),
                    out: sub
                        .get_one::<String>("out")
                        .map(PathBuf::from)
                        .unwrap_or_default(),
                    fraction: sub.get_one::<u32>("fraction").copied(),
                    run: sub.get_flag("run"),
                    budget: sub.get_one::<String>("budget").cloned(),
                    bundle: sub.get_flag("bundle"),
                },
                &workspace_root(),
            )
        }
        "conformance" => {
            mesa::ensure();
            conformance_ci(&args)
        }
        cmd => {
            mesa::ensure();
            umbra(&[cmd], &args)
        }
    };
    // Every path above returns one of the four; anything else would be a bug here.
    ExitCode::from(match code {
        0 | 1 | 125 | 130 => code as u8,
        _ => COULD_NOT_RUN as u8,
    })
}

/// Whether this process runs under CI: `CI` set to anything but empty, `0`, `false`, `no` or
/// `off` (any case), as `umbra_runner::judge::golden::under_ci` reads it; `CI=True`
/// (AppVeyor) once read as "not CI" and let goldens be blessed there.
fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        !matches!(
            v.to_ascii_lowercase().as_str(),
            "" | "0" | "false" | "no" | "off"
        )
    })
}

/// umbra's four exit codes (docs/ci.md#exit-codes): 0 as expected, 1 a regression, 125 could
/// not run, 130 interrupted. xtask says nothing else, whatever its children said.
const COULD_NOT_RUN: i32 = 125;

/// What a child's exit status means in umbra's four codes. `cargo` (`test`) exits 101 when a
/// test fails, which is a regression (1); for `cargo run` (every other command) 101 is a build
/// that failed or a panic, which could not run. A child killed by SIGINT or SIGTERM was
/// interrupted (130); any other signal or code could not run, and is said.
fn four(status: std::process::ExitStatus, what: &str, failed_tests_are_101: bool) -> i32 {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c @ (0 | 1 | 125 | 130)), _) => c,
        (Some(101), _) if failed_tests_are_101 => 1,
        (None, Some(2 | 15)) => 130,
        (code, signal) => {
            eprintln!(
                "error: {what} ended with {}: could not run (exit 125)",
                code.map_or_else(
                    || format!("signal {}", signal.unwrap_or(0)),
                    |c| format!("exit code {c}")
                )
            );
            COULD_NOT_RUN
        }
    }
}

fn test(extra: &[String]) -> i32 {
    let mut phases = Phases::default();
    phases.time("set-up (disk, apt)", || {
        disk::warn_if_short(
            &workspace_root(),
            disk::test_peak_gib(),
            "`cargo xtask test`",
        );
        mesa::ensure();
        mesa::ensure_test_tools();
        0
    });
    // Built first on its own (`--no-run`), so the phase table separates the build from the
    // tests (on a clean clone the build is half of the time). A test build that fails could
    // not run (125, like any build of umbra under xtask); a failing test is 1. The binaries
    // then run two at a time (test_pool says why); what follows `--` goes to each of them.
    let (cargo_extra, test_extra) = match extra.iter().position(|a| a == "--") {
        Some(i) => (&extra[..i], &extra[i + 1..]),
        None => (extra, &[][..]),
    };
    let mut binaries = Vec::new();
    let build = phases.time("cargo test: build (--no-run)", || {
        match test_pool::build(cargo_extra) {
            Ok(b) => {
                binaries = b;
                0
            }
            Err(code) => code,
        }
    });
    if build != 0 {
        phases.print();
        return build;
    }
    let code = phases.time("cargo test: run (two binaries at a time)", || {
        test_pool::run(binaries, cargo_extra, test_extra)
    });
    if code != 0 {
        phases.print();
        return code;
    }
    // The main job on every case, as CI will run it, then the harness's own sensitivity, then
    // the judge on scenes it was not developed against (a fixed seed: the same 60 generated
    // cases in every CI run, about a minute on 2 cores), then the catalogue again on the
    // newest Mesa Debian ships, so umbra stays green on what its users run today.
    let conformance = phases.time("conformance (this machine's Mesa)", || conformance_ci(&[]));
    let selftest = phases.time("selftest", || umbra(&["selftest"], &[]));
    let soak = phases.time("soak", || umbra(&["soak"], &CI_SOAK.map(String::from)));
    let current = phases.time("conformance (sid's Mesa, fetch included)", current_mesa);
    phases.print();
    [conformance, selftest, soak, current]
        .into_iter()
        .find(|c| *c != 0)
        .unwrap_or(0)
}

/// Where `cargo xtask test`'s wall time went, phase by phase, printed at its end: CI's total
/// is read against these (a CI log that only says "2,093 s" cannot say what grew).
#[derive(Default)]
struct Phases {
    rows: Vec<(&'static str, std::time::Duration, i32)>,
}

impl Phases {
    /// Runs `f` as phase `name`, timing it: its exit code.
    fn time(&mut self, name: &'static str, f: impl FnOnce() -> i32) -> i32 {
        let t0 = std::time::Instant::now();
        let code = f();
        self.rows.push((name, t0.elapsed(), code));
        code
    }

    fn print(&self) {
        let total: std::time::Duration = self.rows.iter().map(|r| r.1).sum();
        eprintln!("cargo xtask test: wall time by phase");
        for (name, took, code) in &self.rows {
            eprintln!("  {:>7.1} s  {name} (exit {code})", took.as_secs_f64());
        }
        eprintln!("  {:>7.1} s  in all", total.as_secs_f64());
    }
}

/// The Debian suite with the newest Mesa (`cargo xtask test` runs the catalogue on it too).
const NEWEST_SUITE: &str = "sid";

/// The catalogue on the newest suite's Mesa (fetched into `target/mesa/sid`, its own C library
/// included): 0 when every run is as expected there. `UMBRA_SKIP_CURRENT_MESA=1` leaves it out
/// and says so (a machine without the network); it is never skipped silently.
fn current_mesa() -> i32 {
    // Read strictly: `=0` or an empty value from a CI matrix must not skip a gate.
    match std::env::var("UMBRA_SKIP_CURRENT_MESA").as_deref() {
        Err(_) | Ok("" | "0") => {}
        Ok("1") => {
            eprintln!(
                "note: UMBRA_SKIP_CURRENT_MESA=1: the catalogue on {NEWEST_SUITE}'s Mesa was NOT run"
            );
            return 0;
        }
        Ok(v) => {
            eprintln!(
                "error: UMBRA_SKIP_CURRENT_MESA={v:?}: give 1 to leave the current-Mesa run out, or unset it"
            );
            return COULD_NOT_RUN;
        }
    }
    let root = workspace_root();
    let code = fetch_mesa::main(NEWEST_SUITE, None, &root);
    if code != 0 {
        eprintln!(
            "error: cannot fetch {NEWEST_SUITE}'s Mesa for the current-release conformance run; on a machine without the network set UMBRA_SKIP_CURRENT_MESA=1 to leave it out"
        );
        return code;
    }
    let dir = root.join("target").join("mesa").join(NEWEST_SUITE);
    conformance_ci(&["--mesa".into(), dir.display().to_string()])
}

/// `umbra conformance ARGS`, and under CI, where it changed pictures, the patch that blesses
/// them for review ([`bless_patch`]): the exit code is the run's.
fn conformance_ci(args: &[String]) -> i32 {
    let code = umbra(&["conformance"], args);
    if under_ci() && code != COULD_NOT_RUN {
        bless_patch::after_phase(&workspace_root(), args);
    }
    code
}

/// The soak `cargo xtask test` runs (README, "Generated scenes").
const CI_SOAK: [&str; 4] = ["--seed", "21", "--count", "60"];

fn bless(args: &[String]) -> i32 {
    if under_ci() {
        eprintln!("error: CI=true: goldens change only through review, never in CI");
        return COULD_NOT_RUN;
    }
    mesa::ensure();
    let mut args = args.to_vec();
    args.push("--bless".into());
    let cmd = umbra_command(&["conformance"], &args);
    let code = status(cmd);
    let mut git = Command::new("git");
    git.current_dir(workspace_root())
        .args(["status", "--short", "--", "golden/"]);
    match git.output() {
        Ok(o) if o.stdout.is_empty() => println!("bless: no golden changed"),
        Ok(o) => println!(
            "bless: goldens changed (review with `git diff --stat golden/` before committing):\n{}",
            String::from_utf8_lossy(&o.stdout)
        ),
        Err(e) => eprintln!("note: cannot list changes with git: {e}"),
    }
    code
}

/// Runs the `umbra` binary through cargo, so it is built with the workspace's profile.
fn umbra(command: &[&str], args: &[String]) -> i32 {
    status(umbra_command(command, args))
}

/// The command that runs `umbra COMMAND ARGS` through cargo.
fn umbra_command(command: &[&str], args: &[String]) -> Command {
    let mut cmd = cargo();
    cmd.args([
        "run",
        "--quiet",
        "--package",
        "umbra-runner",
        "--bin",
        "umbra",
        "--",
    ]);
    cmd.args(command).args(args);
    cmd
}

/// `cargo ARGS` in the workspace.
fn cargo_args(args: &[&str]) -> Command {
    let mut cmd = cargo();
    cmd.args(args);
    cmd
}

fn cargo() -> Command {
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.current_dir(workspace_root());
    cmd
}

/// Cargo's target directory (`CARGO_TARGET_DIR`, relative to `root` when relative, else the
/// workspace's `target/`).
fn target_dir(root: &std::path::Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map(|d| if d.is_absolute() { d } else { root.join(d) })
        .unwrap_or_else(|| root.join("target"))
}

fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default()
}

/// `cmd`'s exit in umbra's four codes, its 101 a build that failed or a panic (125).
fn status(cmd: Command) -> i32 {
    status_of(cmd, false)
}

/// `cmd`'s exit in umbra's four codes; `tests` (the one `cargo test` that runs the tests):
/// its 101 is a failed test (1), not a failed build (125).
fn status_of(mut cmd: Command, tests: bool) -> i32 {
    let what = cmd.get_program().to_string_lossy().into_owned();
    match cmd.status() {
        Ok(s) => four(s, &what, tests),
        Err(e) => {
            eprintln!("error: cannot run {cmd:?}: {e}");
            COULD_NOT_RUN
        }
    }
}

#[cfg(test)]
mod tests {
    use std::os::unix::process::ExitStatusExt as _;
    use std::process::ExitStatus;

    /// A child's status in umbra's four codes: cargo test's 101 is a failed test (1), cargo
    /// run's 101 (a build that failed, a panic) and any stray code or signal could not run
    /// (125), SIGINT and SIGTERM an interrupt (130).
    #[test]
    fn a_childs_status_becomes_one_of_the_four() {
        let code = |c: i32| ExitStatus::from_raw(c << 8);
        let signal = ExitStatus::from_raw;
        for (status, tests, want) in [
            (code(0), false, 0),
            (code(1), false, 1),
            (code(125), false, 125),
            (code(130), false, 130),
            (code(101), true, 1),
            (code(101), false, 125),
            (code(2), false, 125),
            (code(134), false, 125),
            (signal(15), false, 130),
            (signal(2), false, 130),
            (signal(9), false, 125),
        ] {
            assert_eq!(super::four(status, "x", tests), want, "{status:?}");
        }
    }
}
