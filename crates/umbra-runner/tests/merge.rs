//! `umbra conformance --shard I/N` and `umbra merge`: three shards merged give the statuses,
//! diagnoses and failure list of one unsharded run, whether split by stride or by a previous
//! run's durations; the merge refuses what would make its report wrong (a missing shard, one
//! given twice, overlapping runs, another build of umbra, another case set) and names it.
//!
//! The runs are the CPU reference, llvmpipe and `fake/wrong` (inverts every shadow) on the
//! basic cases and a sweep with `expect.error_falls_along`: the fake's failures get a
//! consensus diagnosis from llvmpipe's runs, which a stride of three puts in other shards, and
//! the sweep's check reads neighbouring points, which it puts in other shards too.

mod common;

use common::{scratch, text};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use umbra_runner::shards::record::{seal, unseal};

/// A shard record's JSON (inside its checksum seal).
fn read_record(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).expect("record");
    serde_json::from_str(unseal(&text).expect("sealed")).expect("record JSON")
}

/// `v` written as a record another run of umbra would have written (sealed).
fn write_record(path: &Path, v: &serde_json::Value) {
    std::fs::write(path, seal(v.to_string().as_bytes())).expect("write record");
}

/// The test's cases: the two basic scenes and the resolution sweep (error_falls_along),
/// copied into a directory of their own under `root`.
fn cases(root: &Path) -> PathBuf {
    let dir = root.join("cases");
    std::fs::create_dir_all(&dir).expect("cases dir");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases");
    for f in [
        "basics/square-occluder.json",
        "basics/l-occluder.json",
        "lookup/resolution.json",
    ] {
        let name = Path::new(f).file_name().expect("file name");
        std::fs::copy(repo.join(f), dir.join(name)).expect("copy a case");
    }
    dir
}

fn umbra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env("UMBRA_FAKE_BACKENDS", "1")
        .output()
        .expect("run umbra")
}

/// A conformance run of the test's plan (the cases in `cases`) into `out`, with `extra` flags.
fn conformance(cases: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "conformance",
        "--cases",
        cases.to_str().unwrap_or_default(),
        "--backend",
        "ref",
        "--backend",
        "gl33/llvmpipe",
        "--backend",
        "fake/wrong",
        "--golden",
        "none",
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap_or_default(),
    ];
    args.extend_from_slice(extra);
    umbra(&args)
}

fn merge(dirs: &[&Path], out: &Path) -> Output {
    let mut args: Vec<String> = vec!["merge".into()];
    args.extend(dirs.iter().map(|d| d.display().to_string()));
    args.extend(["-o".into(), out.display().to_string()]);
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(&args)
        .output()
        .expect("run umbra merge")
}

/// `name,status` of every row of a results.csv.
fn statuses(out: &Path) -> Vec<String> {
    let t = std::fs::read_to_string(out.join("latest/results.csv")).expect("results.csv");
    t.lines()
        .map(|l| l.rsplit_once(',').map_or("", |x| x.0).to_string())
        .collect()
}

/// Each run's name, status and diagnosis in report.json.
fn judged(out: &Path) -> Vec<(String, String, String)> {
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json")).expect("report.json"),
    )
    .expect("report.json is JSON");
    v["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .map(|r| {
            (
                r["name"].as_str().unwrap_or("").to_string(),
                r["status"].as_str().unwrap_or("").to_string(),
                r["diagnosis"]["message"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect()
}

/// Three shards of the plan, each into its own directory under `root`.
fn three_shards(cases: &Path, root: &Path, extra: &[&str]) -> Vec<PathBuf> {
    (0..3)
        .map(|i| {
            let dir = root.join(format!("shard{i}"));
            let shard = format!("{i}/3");
            let mut args = vec!["--shard", shard.as_str()];
            args.extend_from_slice(extra);
            let o = conformance(cases, &dir, &args);
            // The fake's failures make every shard that holds one exit 1.
            assert!(matches!(o.status.code(), Some(0 | 1)), "{}", text(&o));
            assert!(
                text(&o).contains(&format!("shard {i}/3: ")),
                "a shard says its share:\n{}",
                text(&o)
            );
            dir
        })
        .collect()
}

#[test]
fn three_shards_merged_are_one_unsharded_run() {
    let root = scratch("merge");
    let cases = cases(&root);
    let whole = root.join("whole");
    let o = conformance(&cases, &whole, &[]);
    assert_eq!(o.status.code(), Some(1), "fake/wrong fails:\n{}", text(&o));
    let expected = statuses(&whole);
    let expected_judged = judged(&whole);
    assert_eq!(expected.len(), 15, "{expected:?}");
    // The plan holds what the test is about: a failing fake whose diagnosis needs
    // llvmpipe's runs.
    assert!(
        expected_judged
            .iter()
            .any(|(n, s, d)| n.starts_with("fake/wrong/")
                && s == "Fail"
                && d.contains("gl33/llvmpipe")),
        "{expected_judged:?}"
    );
    let failures = std::fs::read_to_string(whole.join("latest/failures.csv")).expect("failures");

    for (label, extra) in [
        ("stride", vec![]),
        (
            "durations",
            vec![
                "--durations",
                whole
                    .join("latest/results.csv")
                    .to_str()
                    .unwrap_or_default(),
            ],
        ),
    ] {
        let dir = root.join(label);
        let shards = three_shards(&cases, &dir, &extra);
        // No shard alone holds the plan, and (by stride) some shard's fake runs lack the
        // diagnosis only the merge can give.
        let merged = dir.join("merged");
        let refs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
        let o = merge(&refs, &merged);
        let t = text(&o);
        assert_eq!(
            o.status.code(),
            Some(1),
            "the merge fails as the run does:\n{t}"
        );
        assert!(t.contains("imbalance: slowest/fastest shard"), "{t}");
        assert_eq!(statuses(&merged), expected, "{label}: statuses");
        assert_eq!(judged(&merged), expected_judged, "{label}: diagnoses");
        assert_eq!(
            std::fs::read_to_string(merged.join("latest/failures.csv")).expect("failures"),
            failures,
            "{label}: failures.csv"
        );
        let junit = std::fs::read_to_string(merged.join("latest/junit.xml")).expect("junit");
        assert_eq!(
            junit.matches("<testcase").count(),
            expected.len(),
            "{label}: junit"
        );
        let report = std::fs::read_to_string(merged.join("latest/report.json")).expect("json");
        assert!(
            report.contains("\"shards\""),
            "{label}: report.json lists the shards"
        );
        // Every failing run's pictures came along.
        for (name, status, _) in judged(&merged).iter().filter(|(_, s, _)| s == "Fail") {
            let file = umbra_report::names::file_name(name);
            assert!(
                merged.join("latest/failures").join(&file).is_dir(),
                "{label}: {name} ({status}) has its pictures"
            );
        }
        if label == "stride" {
            // Alone, the shards could not diagnose the fake's failures: llvmpipe's runs of
            // the same points are in other shards.
            let alone: Vec<_> = shards.iter().flat_map(|s| judged(s)).collect();
            assert!(
                alone
                    .iter()
                    .filter(|(n, _, _)| n.starts_with("fake/wrong/"))
                    .all(|(_, _, d)| d.is_empty()),
                "{alone:?}"
            );
            falls_along_is_judged_across_shards(&shards, &dir);
        }
        if label == "durations" {
            let o = conformance(
                &cases,
                &dir.join("again"),
                &["--shard", "0/3", "--durations", extra[1]],
            );
            assert!(
                text(&o).contains("balance: by the durations in")
                    && text(&o).contains("split by stride it would be"),
                "{}",
                text(&o)
            );
        }
    }
}

#[test]
fn a_merge_refuses_what_would_make_its_report_wrong_and_names_it() {
    let root = scratch("merge-refuse");
    let cases = cases(&root);
    let shards = three_shards(&cases, &root, &[]);
    let merged = root.join("merged");
    missing_repeated_or_overlapping_shards_are_refused(&root, &cases, &shards, &merged);
    records_of_another_build_case_set_setting_or_driver_are_refused(&root, &shards, &merged);
    another_renderer_on_another_host_is_kept_and_said(&root, &shards);
    damaged_forged_or_incomplete_records_are_refused(&root, &shards, &merged);
    an_output_among_the_inputs_or_no_shard_is_refused(&root, &shards, &merged);
    // The three whole shards merge, given as their --out or as a copy of their `runs/` (a
    // CI artifact, without the `latest` link).
    let refs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    assert_eq!(merge(&refs, &merged).status.code(), Some(1));
    let runs: Vec<PathBuf> = shards.iter().map(|s| s.join("runs")).collect();
    let refs: Vec<&Path> = runs.iter().map(PathBuf::as_path).collect();
    let o = merge(&refs, &root.join("merged-artifacts"));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

/// The merge of `dirs` into `merged` is refused (exit 125), saying `what`, and publishes
/// nothing.
fn assert_refused(merged: &Path, dirs: &[&Path], what: &str) {
    let o = merge(dirs, merged);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{what}:\n{t}");
    assert!(t.contains(what), "{what}:\n{t}");
    assert!(
        !merged.join("latest").exists(),
        "a refused merge publishes nothing"
    );
}

/// A shard missing (named, with its runs), one given twice, and runs in two shards (another
/// plan's run of the same points) are refused.
fn missing_repeated_or_overlapping_shards_are_refused(
    root: &Path,
    cases: &Path,
    shards: &[PathBuf],
    merged: &Path,
) {
    let refused = |dirs: &[&Path], what: &str| assert_refused(merged, dirs, what);
    // A shard missing: named, with its runs.
    refused(&[&shards[0], &shards[2]], "shards missing: 1/3");
    // A shard given twice.
    refused(
        &[&shards[0], &shards[0], &shards[1], &shards[2]],
        "given twice",
    );
    // Overlapping runs: another plan's run of the same points.
    let other = root.join("other");
    let o = umbra(&[
        "conformance",
        "--cases",
        cases.to_str().unwrap_or_default(),
        "--backend",
        "ref",
        "--filter",
        "square*",
        "--golden",
        "none",
        "--out",
        other.to_str().unwrap_or_default(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    refused(
        &[&shards[0], &shards[1], &shards[2], &other],
        "is in two shards",
    );
}

/// Shard 2/3's record (`shard`'s) as another job would have left it, edited by `change`, in a
/// directory `edited-LABEL` of its own under `root`.
fn edited_record(
    root: &Path,
    shard: &Path,
    label: &str,
    change: &dyn Fn(&mut serde_json::Value),
) -> PathBuf {
    let copy = root.join(format!("edited-{label}"));
    std::fs::create_dir_all(&copy).expect("copy dir");
    let mut v = read_record(&shard.join("latest/shard.json"));
    change(&mut v);
    write_record(&copy.join("shard.json"), &v);
    copy
}

/// Sets `key` of gl33/llvmpipe's row of drivers in record `v` to `value`.
fn set_llvmpipe_row(v: &mut serde_json::Value, key: &str, value: &str) {
    for d in v["drivers"].as_array_mut().expect("drivers") {
        if d["backend"] == "gl33/llvmpipe" {
            d["row"][key] = value.into();
        }
    }
}

/// Another build of umbra, case set, timeout or driver: the record says so, and the merge is
/// refused naming it.
fn records_of_another_build_case_set_setting_or_driver_are_refused(
    root: &Path,
    shards: &[PathBuf],
    merged: &Path,
) {
    // Another build of umbra, case set, timeout or driver: the record says so.
    for (label, what, change) in [
        (
            "key",
            "different builds of umbra",
            &(|v: &mut serde_json::Value| v["umbra"]["key"] = "0123456789abcdef".into())
                as &dyn Fn(&mut serde_json::Value),
        ),
        ("cases", "different case sets", &|v| {
            v["inputs"]["cases"]["digest"] = "fedcba9876543210".into()
        }),
        ("timeout", "different settings", &|v| {
            v["settings"]["timeout_s"] = 5.into()
        }),
        ("vendor", "gl33/llvmpipe ran on different drivers", &|v| {
            set_llvmpipe_row(v, "vendor", "Another Vendor")
        }),
    ] {
        let copy = edited_record(root, &shards[2], label, change);
        assert_refused(merged, &[&shards[0], &shards[1], &copy], what);
    }
}

/// The same driver reporting another renderer on another host is kept, and said.
fn another_renderer_on_another_host_is_kept_and_said(root: &Path, shards: &[PathBuf]) {
    let other_host = edited_record(root, &shards[2], "renderer", &|v| {
        set_llvmpipe_row(v, "renderer", "llvmpipe (LLVM 15.0.6, 512 bits)")
    });
    let o = merge(&[&shards[0], &shards[1], &other_host], &root.join("hosts"));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let drivers = std::fs::read_to_string(root.join("hosts/latest/drivers.txt")).expect("drivers");
    assert!(
        drivers.contains("also renderer") && drivers.contains("512 bits"),
        "{drivers}"
    );
}

/// A damaged record, one edited by hand (a failing run made a pass), and a run directory
/// carrying the INCOMPLETE marker are refused.
fn damaged_forged_or_incomplete_records_are_refused(
    root: &Path,
    shards: &[PathBuf],
    merged: &Path,
) {
    let refused = |dirs: &[&Path], what: &str| assert_refused(merged, dirs, what);
    // A damaged record.
    let damaged = root.join("damaged");
    std::fs::create_dir_all(&damaged).expect("dir");
    let bytes = std::fs::read(shards[1].join("latest/shard.json")).expect("record");
    std::fs::write(damaged.join("shard.json"), &bytes[..bytes.len() / 2]).expect("write");
    refused(&[&shards[0], &damaged, &shards[2]], "not a sealed record");
    // A record edited by hand, still valid JSON: a failing run made a pass (issue 36).
    let forged = root.join("forged");
    std::fs::create_dir_all(&forged).expect("dir");
    let record = std::fs::read_to_string(shards[1].join("latest/shard.json")).expect("record");
    assert!(
        record.contains("\"status\":\"Fail\""),
        "shard 2/3 holds a failing run"
    );
    std::fs::write(
        forged.join("shard.json"),
        record.replacen("\"status\":\"Fail\"", "\"status\":\"Pass\"", 1),
    )
    .expect("write");
    refused(
        &[&shards[0], &forged, &shards[2]],
        "does not match its contents",
    );
    // A run directory given directly that carries the INCOMPLETE marker (a full disk on the
    // `latest` switch leaves its record and the marker).
    let marked = root.join("marked");
    std::fs::create_dir_all(&marked).expect("dir");
    std::fs::copy(
        shards[1].join("latest/shard.json"),
        marked.join("shard.json"),
    )
    .expect("copy");
    std::fs::write(
        marked.join("INCOMPLETE"),
        "the disk filled while publishing\n",
    )
    .expect("marker");
    refused(&[&shards[0], &marked, &shards[2]], "did not complete");
}

/// `-o` naming one of the inputs, a directory that holds no shard, and an interrupted shard
/// (its run directory marked incomplete, no `latest`) are refused.
fn an_output_among_the_inputs_or_no_shard_is_refused(
    root: &Path,
    shards: &[PathBuf],
    merged: &Path,
) {
    let refused = |dirs: &[&Path], what: &str| assert_refused(merged, dirs, what);
    // -o naming one of the inputs would replace that shard's `latest`.
    let o = merge(&[&shards[0], &shards[1], &shards[2]], &shards[1]);
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
    assert!(text(&o).contains("is one of the shards"), "{}", text(&o));
    // Not a shard at all.
    refused(&[&root.join("nowhere")], "no shard's results there");
    // An interrupted shard: its run directory is marked incomplete and has no `latest`.
    let broken = root.join("broken");
    std::fs::create_dir_all(broken.join("runs/20261124T000000Z-1-0")).expect("dir");
    std::fs::write(
        broken.join("runs/20261124T000000Z-1-0/INCOMPLETE"),
        "interrupted by SIGTERM after 3 of 9 runs\n",
    )
    .expect("marker");
    refused(&[&shards[0], &shards[1], &broken], "did not complete");
}

/// The sweep's check across runs is the merge's to make: raise the error of llvmpipe's
/// largest map in its shard's record (its smaller neighbour is in another shard, where that
/// shard alone could not compare them) and the merged run fails it, naming the neighbour.
fn falls_along_is_judged_across_shards(shards: &[PathBuf], dir: &Path) {
    let last = "gl33/llvmpipe/resolution@shadow.size=[1280,960]";
    let before = "gl33/llvmpipe/resolution@shadow.size=[640,480]";
    let holder = |name: &str| {
        shards
            .iter()
            .position(|s| {
                std::fs::read_to_string(s.join("latest/shard.json"))
                    .expect("record")
                    .contains(&format!("\"{name}\""))
                    && std::fs::read_to_string(s.join("latest/results.csv"))
                        .expect("results")
                        .contains(name)
            })
            .expect("a shard holds the run")
    };
    let (k, k_before) = (holder(last), holder(before));
    assert_ne!(k, k_before, "a stride of three puts neighbours apart");
    let edited = dir.join("edited");
    std::fs::create_dir_all(&edited).expect("dir");
    let mut v = read_record(&shards[k].join("latest/shard.json"));
    for r in v["runs"].as_array_mut().expect("runs") {
        if r["name"] == last {
            r["metrics"]["false_shadow"] = 1_000_000.into();
        }
    }
    write_record(&edited.join("shard.json"), &v);
    let mut dirs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    dirs[k] = &edited;
    let out = dir.join("merged-edited");
    let o = merge(&dirs, &out);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let row = judged(&out)
        .into_iter()
        .find(|(n, _, _)| n == last)
        .expect("the run");
    assert_eq!(row.1, "Fail", "{row:?}");
    let report = std::fs::read_to_string(out.join("latest/report.json")).expect("json");
    assert!(
        report.contains("expect.error_falls_along shadow.size") && report.contains("[640,480]"),
        "the reason names the check and the neighbour"
    );
}
