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
