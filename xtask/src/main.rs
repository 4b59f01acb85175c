//! umbra's developer commands, rust-analyzer style: one module per command, no dependencies.
//!
//! - `cargo xtask conformance [ARGS]`: installs the Mesa packages when missing and allowed,
//!   then runs `umbra conformance ARGS` and passes its exit code through (0 as expected,
//!   1 regressions, 125 could not run), so `git bisect run cargo xtask conformance` works.
//! - `cargo xtask test`: the same set-up, then the whole test suite and a conformance run.
//! - `cargo xtask selftest`: every injected fault on every backend it applies to; a fault the
//!   judge does not catch fails it. Part of `cargo xtask test`.
//! - `cargo xtask sweep [--scene CASE] [--backend ID]...`: speed against error, a technique
//!   matrix measured per backend (`umbra sweep`): CSV, Pareto plot (PNG, SVG) and an HTML
//!   section under target/umbra/sweep/.
//! - `cargo xtask bless [ARGS]`: a conformance run that accepts every changed or new golden
//!   (insta's `INSTA_UPDATE=always`), then lists what changed under `golden/` for review in
//!   `git diff` before committing. Refused under `CI=true`: CI never writes a golden.
//! - `cargo xtask fetch-mesa [--dir DIR]`: a second Mesa (bookworm-backports, 25.0.7) unpacked
//!   into a directory without changing the system (`fetch_mesa`), for `--mesa DIR`.
//! - `cargo xtask drivers --baseline A --candidate B`, `cargo xtask bisect --mesa-src DIR
//!   --good REV --bad REV`, `cargo xtask reduce CASE --point ID --backend ID`: the same set-up,
//!   then `umbra drivers`, `umbra bisect`, `umbra reduce`.

mod fetch_mesa;
mod mesa;

use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let code = match args.first().map(String::as_str) {
        Some("conformance") => {
            mesa::ensure();
            umbra(&["conformance"], &args[1..])
        }
        Some("test") => test(&args[1..]),
        Some("bless") => bless(&args[1..]),
        Some("selftest") => {
            mesa::ensure();
            umbra(&["selftest"], &args[1..])
        }
        Some("sweep") => {
            mesa::ensure();
            umbra(&["sweep"], &args[1..])
        }
        Some(cmd @ ("drivers" | "bisect" | "reduce")) => {
            mesa::ensure();
            umbra(&[cmd], &args[1..])
        }
        Some("fetch-mesa") => fetch_mesa::main(&args[1..], &workspace_root()),
        _ => {
            eprintln!(
                "usage:\n  cargo xtask conformance [--filter GLOB] [--backend ID]... [--verbose]\n  \
                 cargo xtask test [-- CARGO TEST ARGS]\n  \
                 cargo xtask sweep [--scene CASE.json] [--point ID] [--backend ID|all]... [--repeat N]\n  \
                 cargo xtask bless [--filter GLOB] [--backend ID]...\n  \
                 cargo xtask fetch-mesa [--dir DIR] [--suite SUITE]\n  \
                 cargo xtask drivers --baseline PREFIX|system --candidate PREFIX|system [--filter GLOB] [--backend ID]...\n  \
                 cargo xtask bisect --mesa-src DIR --good REV --bad REV [--filter GLOB] [--backend ID]...\n  \
                 cargo xtask reduce CASE.json --point ID --backend ID [-o OUT.json]"
            );
            2
        }
    };
    ExitCode::from(code.clamp(0, 255) as u8)
}

fn test(extra: &[String]) -> i32 {
    mesa::ensure();
    let mut cmd = cargo();
    cmd.args(["test", "--workspace"]);
    cmd.args(extra);
    let code = status(cmd);
    if code != 0 {
        return code;
    }
    // The main job on every case, as CI will run it, then the harness's own sensitivity.
    let conformance = umbra(&["conformance"], &[]);
    let selftest = umbra(&["selftest"], &[]);
    if conformance != 0 {
        conformance
    } else {
        selftest
    }
}

fn bless(args: &[String]) -> i32 {
    if std::env::var("CI").is_ok_and(|v| v == "true" || v == "1") {
        eprintln!("error: CI=true: goldens change only through review, never in CI");
        return 2;
    }
    mesa::ensure();
    let mut cmd = umbra_command(&["conformance"], args);
    cmd.env("INSTA_UPDATE", "always");
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

fn cargo() -> Command {
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.current_dir(workspace_root());
    cmd
}

fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default()
}

fn status(mut cmd: Command) -> i32 {
    match cmd.status() {
        Ok(s) => s.code().unwrap_or(125),
        Err(e) => {
            eprintln!("error: cannot run {cmd:?}: {e}");
            125
        }
    }
}
