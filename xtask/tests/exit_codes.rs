//! `cargo xtask`'s exit codes are umbra's four (docs/ci.md#exit-codes): a usage error of any
//! subcommand could not run (125, never clap's 2), and what xtask refuses before it starts
//! anything is 125 too. The pass-through commands (conformance, selftest …) hand their
//! arguments to `umbra`, whose usage errors `umbra-runner`'s front-door test walks.

use std::process::Command;

fn xtask(args: &[&str], env: &[(&str, &str)]) -> (Option<i32>, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_xtask"));
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().expect("run xtask");
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    (o.status.code(), text)
}

#[test]
fn every_usage_error_exits_125() {
    for args in [
        &[][..],
        &["no-such-command"][..],
        &["fetch-mesa", "--suit", "sid"][..],
        &["gpu-bundle", "--profile", "release"][..],
        &["gpu-bundle", "--no-such-flag"][..],
        &["mesa-ci"][..],
        &[
            "mesa-ci",
            "--driver",
            "llvmpipe",
            "--out",
            "x",
            "--fraction",
            "0",
        ][..],
        &["fetch-mesa", "--suite", "../../../../x"][..],
        &["fetch-mesa", "--suite", "Sid"][..],
    ] {
        let (code, text) = xtask(args, &[]);
        assert_eq!(code, Some(125), "cargo xtask {args:?}: {text}");
    }
    let (code, text) = xtask(&["fetch-mesa", "--suite", "../../../../x"], &[]);
    assert!(text.contains("not a Debian suite name"), "{text}");
    assert_eq!(code, Some(125));
    let (code, text) = xtask(&["bless"], &[("CI", "true")]);
    assert_eq!(code, Some(125), "{text}");
    // Help is not an error.
    let (code, _) = xtask(&["--help"], &[]);
    assert_eq!(code, Some(0));
}

/// The reproducer: `cargo xtask gpu-bundle --out victim` removed `victim/precious.txt`
/// and exited 0. It is refused before anything is built, and the file stays.
#[test]
fn gpu_bundle_refuses_a_directory_it_did_not_make() {
    let victim = std::env::temp_dir().join(format!("umbra-xtask-victim-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&victim);
    std::fs::create_dir_all(&victim).expect("mkdir");
    std::fs::write(victim.join("precious.txt"), "precious\n").expect("write");
    let (code, text) = xtask(&["gpu-bundle", "--out", &victim.to_string_lossy()], &[]);
    assert_eq!(code, Some(125), "{text}");
    assert!(
        text.contains("holds files umbra did not write")
            && text.contains("give a new or empty directory"),
        "{text}"
    );
    assert_eq!(
        std::fs::read_to_string(victim.join("precious.txt")).expect("still there"),
        "precious\n"
    );
    let _ = std::fs::remove_dir_all(&victim);
}

/// With no mirror to reach, the fetch says so (it ended on apt-cache's "'sid' is invalid for
/// APT::Default-Release" before), and exits 125. The mirror is a closed port on loopback.
#[test]
fn an_unreachable_mirror_is_said_as_that() {
    let dir = std::env::temp_dir().join(format!("umbra-xtask-nomirror-{}", std::process::id()));
    let (code, text) = xtask(
        &[
            "fetch-mesa",
            "--suite",
            "sid",
            "--dir",
            &dir.join("sid").to_string_lossy(),
        ],
        &[("UMBRA_DEBIAN_MIRROR", "http://127.0.0.1:9/debian")],
    );
    assert_eq!(code, Some(125), "{text}");
    assert!(
        text.contains(
            "the mirror http://127.0.0.1:9/debian could not be reached for suite \"sid\""
        ),
        "{text}"
    );
    assert!(!text.contains("APT::Default-Release"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}
