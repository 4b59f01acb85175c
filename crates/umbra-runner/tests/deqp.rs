//! umbra as a dEQP binary (`umbra deqp`), held to the protocol deqp-runner parses
//! (deqp-runner 0.24's parse_deqp.rs: `Test case 'NAME'..`, then `  STATUS (detail)` with
//! STATUS one of dEQP's result names): the statuses of a passing test, a failure a modelled
//! deviation explains (QualityWarning), a faulted test (Fail, with its pictures), an unknown
//! name and deqp-runner's info probe; and `--list`'s names, which carry no comma, quote or
//! brace into deqp-runner's CSV and regex files.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::{scratch, text};

fn umbra(args: &[String], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env_remove("UMBRA_SELFTEST")
        .env_remove("UMBRA_FAULT")
        .envs(env.iter().copied())
        .output()
        .expect("run umbra")
}

/// (name, status) pairs as deqp-runner reads them from stdout.
fn parsed(stdout: &str) -> Vec<(String, String)> {
    const STATUSES: &[&str] = &[
        "Pass",
        "Fail",
        "QualityWarning",
        "CompatibilityWarning",
        "NotSupported",
        "InternalError",
        "Crash",
        "Timeout",
    ];
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in stdout.lines() {
        if let Some(name) = line
            .strip_prefix("Test case '")
            .and_then(|r| r.strip_suffix("'.."))
        {
            current = Some(name.to_string());
        } else if let (Some(rest), Some(name)) = (line.strip_prefix("  "), current.take()) {
            let (status, detail) = rest.split_once(' ').expect("status and detail");
            assert!(STATUSES.contains(&status), "{line}");
            assert!(detail.starts_with('(') && detail.ends_with(')'), "{line}");
            out.push((name, status.to_string()));
        }
    }
    out
}

fn run_tests(dir: &Path, names: &[&str], env: &[(&str, &str)]) -> (Vec<(String, String)>, String) {
    let caselist = dir.join("caselist.txt");
    std::fs::write(&caselist, names.join("\n") + "\n").expect("caselist");
    let args = vec![
        "deqp".to_string(),
        format!("--deqp-caselist-file={}", caselist.display()),
        format!("--deqp-log-filename={}", dir.join("log.qpa").display()),
        "--deqp-log-flush=disable".to_string(),
        format!(
            "--deqp-shadercache-filename={}",
            dir.join("cache").display()
        ),
        "--deqp-shadercache-truncate=disable".to_string(),
        format!("--umbra-pictures={}", dir.join("pictures").display()),
    ];
    let o = umbra(&args, env);
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(stdout.trim_end().ends_with("DONE!"), "{stdout}");
    (parsed(&stdout), stdout)
}

#[test]
fn umbra_speaks_deqp_s_protocol() {
    let dir = scratch("deqp");
    let names = [
        "umbra.gl33.llvmpipe.formats.1",
        // zink's polygon-offset unit ×4, a modelled deviation (expectations/mesa-22.3.txt).
        "umbra.gl33.zink.offset-magnified.0",
        "umbra.gl33.llvmpipe.no-such-case.0",
        "umbra.info.renderer",
    ];
    let (got, stdout) = run_tests(&dir, &names, &[]);
    let status = |n: &str| {
        got.iter()
            .find(|(name, _)| name == n)
            .map(|(_, s)| s.as_str())
            .unwrap_or_else(|| panic!("{n} has no status: {stdout}"))
    };
    assert_eq!(got.len(), names.len(), "{stdout}");
    assert_eq!(status(names[0]), "Pass", "{stdout}");
    assert_eq!(status(names[1]), "QualityWarning", "{stdout}");
    assert!(stdout.contains("expected by cause"), "{stdout}");
    assert_eq!(status(names[2]), "InternalError", "{stdout}");
    assert_eq!(status(names[3]), "NotSupported", "{stdout}");
    assert!(dir.join("log.qpa").is_file());

    // A self-test fault (polygon-offset units a step low): the test fails and leaves its
    // pictures under --umbra-pictures.
    let faulted = scratch("deqp-fault");
    let (got, stdout) = run_tests(
        &faulted,
        &[names[0]],
        &[("UMBRA_SELFTEST", "1"), ("UMBRA_FAULT", "offset-units-low")],
    );
    assert_eq!(
        got,
        [(names[0].to_string(), "Fail".to_string())],
        "{stdout}"
    );
    assert!(
        std::fs::read_dir(faulted.join("pictures").join(names[0]))
            .is_ok_and(|mut d| d.next().is_some()),
        "pictures of the failing test"
    );
}

#[test]
fn listed_names_are_safe_for_deqp_runner_s_files_and_name_their_runs() {
    let o = umbra(
        &[
            "deqp".into(),
            "--list".into(),
            "--backend=gl33/softpipe".into(),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let rows: Vec<Vec<&str>> = stdout.lines().map(|l| l.split('\t').collect()).collect();
    assert!(rows.len() > 200, "{stdout}");
    for r in &rows {
        assert_eq!(r.len(), 3, "{r:?}");
        assert!(r[0].starts_with("umbra.gl33.softpipe."), "{r:?}");
        assert!(!r[0].contains([',', '"', '{', '=', ' ', '/']), "{r:?}");
        assert!(r[1].starts_with("gl33/softpipe/"), "{r:?}");
        assert!(
            ["Pass", "Fail", "Crash", "Timeout", "Skip", "Cause"].contains(&r[2]),
            "{r:?}"
        );
    }
    // softpipe's name-pinned expected failure and its expectations by cause.
    assert!(
        rows.iter()
            .any(|r| r[1].starts_with("gl33/softpipe/beyond-far@") && r[2] == "Fail")
    );
    assert!(rows.iter().any(|r| r[2] == "Cause"));
}

/// Configuration mistakes are said as such, never as a driver's failure (issue 36): a backend
/// this umbra does not have is an InternalError naming it, one the machine lacks is
/// NotSupported with the worker's reason (not a Crash of a worker that exited as it should);
/// a mistyped flag, two case files of one name and pictures inside the cases are refused.
#[test]
fn configuration_mistakes_are_not_driver_failures() {
    let dir = scratch("deqp-config");
    let names = [
        "umbra.gl34.llvmpipe.formats.1",
        "umbra.gl33.radeonsi.7.formats.1",
    ];
    let (got, stdout) = run_tests(&dir, &names, &[]);
    assert_eq!(got[0].1, "InternalError", "{stdout}");
    assert!(stdout.contains("does not have"), "{stdout}");
    assert_eq!(got[1].1, "NotSupported", "{stdout}");
    assert!(stdout.contains("unavailable"), "{stdout}");
    assert!(!stdout.contains("Crash"), "{stdout}");

    let refused = |args: &[String], says: &[&str]| {
        let o = umbra(args, &[]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(125), "{args:?}: {t}");
        for s in says {
            assert!(t.contains(s), "{args:?} must say {s}: {t}");
        }
    };
    let caselist = dir.join("caselist.txt");
    let list = format!("--deqp-caselist-file={}", caselist.display());
    refused(
        &["deqp".into(), list.clone(), "--umbra-picture=x".into()],
        &["--umbra-picture=x", "--umbra-pictures"],
    );
    let cases = dir.join("cases");
    std::fs::create_dir_all(&cases).expect("cases");
    let square = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/basics/square-occluder.json"),
    )
    .expect("case");
    std::fs::write(cases.join("a.json"), &square).expect("a");
    std::fs::write(cases.join("b.json"), &square).expect("b");
    refused(
        &[
            "deqp".into(),
            list.clone(),
            format!("--cases={}", cases.display()),
        ],
        &["a.json", "b.json", "\"name\""],
    );
    std::fs::remove_file(cases.join("b.json")).expect("rm");
    refused(
        &[
            "deqp".into(),
            list,
            format!("--cases={}", cases.display()),
            format!("--umbra-pictures={}", cases.join("pictures").display()),
        ],
        &["inside the case directory"],
    );
}
