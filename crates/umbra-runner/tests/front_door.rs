//! The command line at the front door: `--help` on every command, a mistyped flag named, shell
//! completions, a closed pipe that is not a crash, and a terminal that gets a
//! progress line (plain lines everywhere else: the other tests read those).

use std::path::Path;
use std::process::{Command, Stdio};

#[test]
fn a_closed_stdout_ends_umbra_quietly() {
    // The reader is gone before umbra writes its first line: every println hits EPIPE.
    let mut child = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args([
            "render",
            "cases/basics/square-occluder.json",
            "-o",
            &std::env::temp_dir()
                .join(format!("umbra-pipe-{}", std::process::id()))
                .to_string_lossy(),
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run umbra");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn at_a_terminal_progress_is_one_line_with_a_tally_and_an_eta() {
    // A pseudo-terminal through util-linux's `script` (bsdutils, essential on Debian).
    let out = std::env::temp_dir().join(format!("umbra-pty-{}", std::process::id()));
    let cmd = format!(
        "{} conformance --backend ref --filter 'square*' --golden none --out {}",
        env!("CARGO_BIN_EXE_umbra"),
        out.display()
    );
    let o = Command::new("script")
        .args(["-qec", &cmd, "/dev/null"])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env_remove("CI")
        .env("TERM", "xterm")
        .output()
        .expect("run script(1)");
    let t = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains("\r\x1b[2K[1/1] ") && t.contains("pass 1 fail 0 skip 0") && t.contains("ETA"),
        "{t}"
    );
    // A passing run does not stay on screen as a line of its own; the summary does.
    assert!(!t.contains("[1/1] Pass ref/square-occluder"), "{t}");
    assert!(
        t.contains("conformance: 1 passed, 0 failed, 0 skipped"),
        "{t}"
    );
}

fn umbra(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(args)
        .output()
        .expect("run umbra")
}

#[test]
fn every_command_answers_help_with_its_flags() {
    for (command, flag) in [
        ("render", "--backend"),
        ("conformance", "--shard"),
        ("selftest", "--fault"),
        ("sweep", "--repeat"),
        ("drivers", "--candidate"),
        ("bisect", "--mesa-src"),
        ("reduce", "--check"),
        ("completions", "<SHELL>"),
    ] {
        let o = umbra(&[command, "--help"]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert_eq!(o.status.code(), Some(0), "umbra {command} --help: {text}");
        assert!(
            text.contains(&format!("Usage: umbra {command}")) && text.contains(flag),
            "umbra {command} --help lacks {flag}: {text}"
        );
    }
}

#[test]
fn a_mistyped_flag_is_named_with_the_near_miss_and_cannot_run() {
    let o = umbra(&["conformance", "--filtre", "x"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(125), "{err}");
    assert!(
        err.contains("'--filtre'") && err.contains("'--filter'"),
        "{err}"
    );
}

#[test]
fn completions_cover_the_commands_and_their_flags() {
    let o = umbra(&["completions", "bash"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0));
    for word in ["conformance", "render", "--max-memory", "--mesa"] {
        assert!(text.contains(word), "bash completion lacks {word}");
    }
}

/// umbra's four exit codes (docs/ci.md#exit-codes) hold for every command's usage error: each
/// subcommand the parser knows, hidden ones included, walked from the parser itself (a new
/// command is walked too), given a flag it lacks, exits 125 and never clap's 2.
#[test]
fn every_commands_usage_error_exits_125() {
    let cli = umbra_runner::cli::command();
    let mut walked = 0;
    for sub in cli.get_subcommands() {
        let name = sub.get_name();
        if name == "help" {
            continue;
        }
        let o = umbra(&[name, "--no-such-flag-anywhere"]);
        assert_eq!(
            o.status.code(),
            Some(125),
            "umbra {name} --no-such-flag-anywhere: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        walked += 1;
    }
    assert!(walked >= 12, "only {walked} commands walked");
    for args in [
        &["no-such-command"][..],
        &[][..],
        &["deqp", "--deqp-no-such-flag=1"][..],
        &["render"][..],
        &["completions", "tcsh"][..],
    ] {
        let o = umbra(args);
        assert_eq!(
            o.status.code(),
            Some(125),
            "umbra {args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// `umbra drivers --out DIR` replaced DIR whole: a directory umbra did not make is refused
/// (125) and nothing in it is touched (integrity round three, "a user's files deleted").
#[test]
fn a_users_directory_is_never_replaced() {
    let root = std::env::temp_dir().join(format!("umbra-victim-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let victim = root.join("victim");
    std::fs::create_dir_all(&victim).expect("mkdir");
    std::fs::write(victim.join("precious.txt"), "precious\n").expect("write");
    let o = umbra(&[
        "drivers",
        "--baseline",
        "system",
        "--candidate",
        "system",
        "--out",
        &victim.to_string_lossy(),
    ]);
    let t = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("holds files umbra did not write"), "{t}");
    assert_eq!(
        std::fs::read_to_string(victim.join("precious.txt")).expect("still there"),
        "precious\n"
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// A case whose only point is a skip ran nothing: `umbra render` exits 125, as conformance
/// does for the same tree (it exited 0).
#[test]
fn render_of_nothing_but_skips_exits_125() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = std::env::temp_dir().join(format!("umbra-render-skip-{}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args([
            "render",
            "cases/lights/two-points.json",
            "--backend",
            "gles2/llvmpipe",
            "-o",
            &out.to_string_lossy(),
        ])
        .current_dir(&root)
        .output()
        .expect("run umbra");
    let t = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("skip") && t.contains("nothing ran"), "{t}");
    let _ = std::fs::remove_dir_all(&out);
}

/// render runs one backend: a second `--backend` is refused, not taken in place of the first.
#[test]
fn render_refuses_a_second_backend() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args([
            "render",
            "cases/basics/square-occluder.json",
            "--backend",
            "ref",
            "--backend",
            "gl33/llvmpipe",
        ])
        .current_dir(&root)
        .output()
        .expect("run umbra");
    let t = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("--backend") && t.contains("cannot be used multiple times"),
        "{t}"
    );
}

/// An interrupt is 130 for a command that does not stop in order too (it died by the signal:
/// the shell read 143 for SIGTERM, outside umbra's four codes).
#[test]
fn a_command_stopped_by_sigterm_exits_130() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args([
            "render",
            "cases/cascades/bevy-sun.json",
            "--backend",
            "ref",
            "-o",
            &std::env::temp_dir()
                .join(format!("umbra-sigterm-{}", std::process::id()))
                .to_string_lossy(),
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("run umbra");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let status = child.wait().expect("wait");
    assert_eq!(status.code(), Some(130), "{status:?}");
}
