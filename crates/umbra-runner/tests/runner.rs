//! The conformance runner against backends that misbehave on purpose (crash, hang, flake,
//! render wrong; `UMBRA_FAKE_BACKENDS=1` enables them): each gets the right status, the run
//! completes and reports, expectations turn known failures into ExpectedFail and a pass of a
//! known failure into UnexpectedPass, and shards split a run exactly.

mod common;

use common::{scratch, text};

use std::path::Path;
use std::process::{Command, Output};

fn umbra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env("UMBRA_FAKE_BACKENDS", "1")
        // fake/flaky's one death per run, claimed in a file no earlier run left.
        .env("UMBRA_FAKE_FLAKY_FILE", {
            static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
            let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            scratch(&format!("flaky-claim-{n}")).join("claimed")
        })
        // Fakes have no goldens: these tests are about statuses, not pictures.
        .args(["--golden", "none"])
        .output()
        .expect("run umbra")
}

#[test]
fn crash_hang_flake_and_wrong_each_get_their_status_and_the_run_completes() {
    let out = scratch("fakes");
    let no_expectations = scratch("fakes-exp");
    let o = umbra(&[
        "conformance",
        "--backend",
        "fake/crash",
        "--backend",
        "fake/hang",
        "--backend",
        "fake/flaky",
        "--backend",
        "fake/wrong",
        "--backend",
        "ref",
        "--filter",
        "square*",
        // Every backend's limit, not only fake/hang's: it covers each worker's start and the
        // basis computed into an empty cache (0.3 s here when idle), so it leaves room for a
        // loaded machine; fake/hang costs it once.
        "--timeout",
        "6",
        "--out",
        out.to_str().unwrap_or_default(),
        "--expectations",
        no_expectations.to_str().unwrap_or_default(),
    ]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let results = std::fs::read_to_string(out.join("latest/results.csv")).expect("results.csv");
    for (name, status) in [
        ("fake/crash/square-occluder", "Crash"),
        ("fake/hang/square-occluder", "Timeout"),
        ("fake/flaky/square-occluder", "Flake"),
        ("fake/wrong/square-occluder", "Fail"),
        ("ref/square-occluder", "Pass"),
    ] {
        assert!(
            results.contains(&format!("{name},{status},")),
            "{name} should be {status}:\n{results}"
        );
    }
    let failures = std::fs::read_to_string(out.join("latest/failures.csv")).expect("failures.csv");
    assert_eq!(
        failures.lines().count(),
        3,
        "crash, timeout and fail are regressions; a flake (a crash, then a pass on a fresh worker) is not:\n{failures}"
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json")).expect("report.json"),
    )
    .expect("json");
    let runs = report["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 5);
    let wrong = runs
        .iter()
        .find(|r| r["name"] == "fake/wrong/square-occluder")
        .expect("wrong run");
    assert!(
        wrong["metrics"]["illegal"].as_u64().unwrap_or(0) > 10_000,
        "{wrong}"
    );
    assert!(
        wrong["reproduce"]
            .as_str()
            .unwrap_or("")
            .contains("--backend=fake/wrong"),
        "{wrong}"
    );
    let junit = std::fs::read_to_string(out.join("latest/junit.xml")).expect("junit.xml");
    assert!(junit.contains("tests=\"5\" failures=\"3\""), "{junit}");
    assert!(
        out.join("latest/failures/fake_wrong_square-occluder/error.png")
            .is_file(),
        "failure pictures"
    );
    assert!(
        t.contains("conformance: 2 passed, 3 failed, 0 skipped"),
        "{t}"
    );
}

#[test]
fn expectations_make_known_failures_expected_and_their_passes_unexpected() {
    let exp = scratch("exp");
    // The inverted shadows fail the value check (and the colour, which no longer matches the
    // visibility written) on every pixel, the case's zero interior error, and the built-in
    // twin likewise.
    let broad = "Fail:value<=1000000+colour<=1000000+interior<=1000000+twin:bias-order<=1000000";
    std::fs::write(
        exp.join("fake.txt"),
        format!("# known bad\nfake/wrong/*,{broad},inverts every shadow on purpose\n"),
    )
    .expect("write");
    let out = scratch("exp-out");
    let run = |backend: &str| {
        umbra(&[
            "conformance",
            "--backend",
            backend,
            "--filter",
            "square*",
            "--expectations",
            exp.to_str().unwrap_or_default(),
            "--out",
            out.to_str().unwrap_or_default(),
        ])
    };
    let o = run("fake/wrong");
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(
        text(&o).contains("ExpectedFail fake/wrong/square-occluder"),
        "{}",
        text(&o)
    );

    // The same run against an expectation of another failure (a few map texels) fails
    // differently: a regression, whose reason names what was not expected.
    std::fs::write(
        exp.join("fake.txt"),
        "fake/wrong/*,Fail:map<=10,expects only a few map texels\n",
    )
    .expect("write");
    let o = run("fake/wrong");
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("fails differently than expected") && text(&o).contains("+value="),
        "{}",
        text(&o)
    );

    // An expected failure without its signature is refused, with the fix.
    std::fs::write(exp.join("fake.txt"), "fake/wrong/*,Fail,no signature\n").expect("write");
    let o = run("fake/wrong");
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
    assert!(text(&o).contains("Fail:CHECK<=N"), "{}", text(&o));

    std::fs::write(
        exp.join("fake.txt"),
        "ref/square*,Fail:value<=1,pretend the reference is broken\n",
    )
    .expect("write");
    let o = umbra(&[
        "conformance",
        "--backend",
        "ref",
        "--filter",
        "square*",
        "--expectations",
        exp.to_str().unwrap_or_default(),
        "--out",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "an unexpected pass fails until the baseline is updated: {}",
        text(&o)
    );
    assert!(
        text(&o).contains("UnexpectedPass ref/square-occluder"),
        "{}",
        text(&o)
    );
}

#[test]
fn shards_split_a_run_exactly() {
    let mut all = Vec::new();
    for shard in ["0/3", "1/3", "2/3"] {
        let out = scratch(&format!("shard{}", &shard[..1]));
        let o = umbra(&[
            "conformance",
            "--backend",
            "ref",
            "--filter",
            "packed*",
            "--shard",
            shard,
            "--out",
            out.to_str().unwrap_or_default(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", text(&o));
        let results = std::fs::read_to_string(out.join("latest/results.csv")).expect("results.csv");
        all.extend(
            results
                .lines()
                .map(|l| l.split(',').next().unwrap_or("").to_string()),
        );
    }
    let n = all.len();
    all.sort();
    all.dedup();
    assert_eq!(
        (n, all.len()),
        (16, 16),
        "three shards cover the 16 points once each"
    );
    let o = umbra(&["conformance", "--shard", "3/3"]);
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
}

/// Integrity round three: a backend that keeps state from one point to the next failed the
/// second point by thousands of pixels, passed its rerun on the same worker right after, and
/// was a Flake (exit 0). The rerun is alone on a fresh worker now: the run is
/// OrderDependent (a regression), naming the point that went before it, and the order alone
/// reproduces it.
#[test]
fn state_left_by_an_earlier_point_is_an_order_dependent_failure_not_a_flake() {
    let out = scratch("stale");
    let no_expectations = scratch("stale-exp");
    let o = umbra(&[
        "conformance",
        "--backend",
        "fake/stale",
        "--filter",
        "*-occluder",
        "--jobs",
        "1",
        "--out",
        out.to_str().unwrap_or_default(),
        "--expectations",
        no_expectations.to_str().unwrap_or_default(),
    ]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let results = std::fs::read_to_string(out.join("latest/results.csv")).expect("results.csv");
    let rows: Vec<&str> = results
        .lines()
        .filter(|l| l.starts_with("fake/stale/"))
        .collect();
    assert_eq!(rows.len(), 2, "{results}");
    // Whichever ran first on the worker passed; the other is order-dependent, naming it:
    // a Fail in results.csv, deqp-runner having no word for it, OrderDependent in the report.
    let passed = rows.iter().filter(|l| l.contains(",Pass,")).count();
    let ordered = rows.iter().filter(|l| l.contains(",Fail,")).count();
    assert_eq!((passed, ordered), (1, 1), "{results}");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json")).expect("report.json"),
    )
    .expect("json");
    let run = report["runs"]
        .as_array()
        .and_then(|r| r.iter().find(|r| r["status"] == "OrderDependent"))
        .expect("the order-dependent run");
    let reason = run["reason"].as_str().unwrap_or("");
    assert!(
        reason.contains("failed after fake/stale/")
            && reason.contains("passed alone on a fresh worker")
            && reason.contains("reproduced: run after it on a fresh worker, it failed again"),
        "{reason}"
    );
    assert!(!results.contains(",Flake,"), "{results}");
    assert!(t.contains("order-dependent 1"), "{t}");
}
