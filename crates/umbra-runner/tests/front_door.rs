//! The command line at the front door: a closed pipe is not a crash.

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
