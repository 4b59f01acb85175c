//! Behaviour cards end to end, on the reference (the backend every machine has): `umbra
//! card` measures and prints one, `--diff` names what changed between two kept cards, and
//! conformance's `card` check passes on the kept card, fails on a changed one naming the
//! entry with both values, and skips (saying so) where no card is kept for the release.

mod common;

use common::{scratch, seed_goldens, text};

use std::path::Path;
use std::process::{Command, Output};

fn repo() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn umbra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(args)
        .current_dir(repo())
        .env("CI", "true")
        .output()
        .expect("run umbra")
}

#[test]
fn the_reference_card_is_measured_and_printed() {
    let o = umbra(&["card", "--backend", "ref", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let cards: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let card = &cards[0];
    assert_eq!(card["backend"], "ref");
    assert_eq!(card["release"], "umbra");
    let entry = |k: &str| {
        card["entries"]
            .as_array()
            .and_then(|e| e.iter().find(|e| e["key"] == k))
            .cloned()
            .unwrap_or_else(|| panic!("no entry {k}: {card}"))
    };
    assert_eq!(entry("offset-unit.depth16.z0.375")["value"], "1 code");
    assert_eq!(entry("reference-clamp.depth32f")["value"], "not clamped");
    // Every entry carries its spec, its probe and how sure it is.
    for e in card["entries"].as_array().into_iter().flatten() {
        for field in ["what", "value", "spec", "probe", "sure"] {
            assert!(!e[field].is_null(), "{field} missing in {e}");
        }
    }
    let t = umbra(&["card", "--backend", "ref"]);
    assert!(
        text(&t).contains("polygon-offset unit r, D16, z ≈ 0.375"),
        "{}",
        text(&t)
    );
    assert!(
        text(&t).contains("1 code (inside the spec)"),
        "{}",
        text(&t)
    );
}

/// The repository's kept card of `ref` with one entry's value replaced.
fn changed_card(key: &str, value: &str) -> String {
    let kept = repo().join("golden/ref/card-umbra.json");
    let mut card: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(kept).expect("ref's kept card"))
            .expect("JSON");
    for e in card["entries"].as_array_mut().into_iter().flatten() {
        if e["key"] == key {
            e["value"] = value.into();
        }
    }
    serde_json::to_string_pretty(&card).expect("JSON")
}

#[test]
fn diff_names_each_changed_entry_with_both_values() {
    let dir = scratch("diff");
    let new = dir.join("new.json");
    std::fs::write(
        &new,
        changed_card("depth-rounding.depth16", "truncated (towards 0)"),
    )
    .expect("write");
    let old = repo().join("golden/ref/card-umbra.json");
    let o = umbra(&[
        "card",
        "--diff",
        old.to_str().unwrap_or_default(),
        new.to_str().unwrap_or_default(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("1 changed"), "{t}");
    assert!(
        t.contains("depth rounding, D16: to nearest → truncated (towards 0)"),
        "{t}"
    );
}

fn conformance(cases: &Path, golden: &Path, out: &Path) -> Output {
    umbra(&[
        "conformance",
        "--backend",
        "ref",
        "--cases",
        cases.to_str().unwrap_or_default(),
        "--golden",
        golden.to_str().unwrap_or_default(),
        "--out",
        out.to_str().unwrap_or_default(),
    ])
}

#[test]
fn conformance_holds_a_backend_to_its_kept_card() {
    let dir = scratch("conformance");
    let (cases, golden) = (dir.join("cases"), dir.join("golden"));
    std::fs::create_dir_all(&cases).expect("cases");
    std::fs::copy(
        repo().join("cases/bias/acne-cull-front.json"),
        cases.join("acne-cull-front.json"),
    )
    .expect("a case");
    seed_goldens(&golden);
    let kept = golden.join("ref").join("card-umbra.json");

    // The kept card: the row passes.
    std::fs::copy(repo().join("golden/ref/card-umbra.json"), &kept).expect("card");
    let o = conformance(&cases, &golden, &dir.join("same"));
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("Pass ref/card"), "{}", text(&o));

    // A changed entry: check `card` fails, naming the entry and both values.
    std::fs::write(
        &kept,
        changed_card("slope-term.diagonal", "√(∂z/∂x² + ∂z/∂y²), exact"),
    )
    .expect("card");
    let o = conformance(&cases, &golden, &dir.join("changed"));
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("Fail ref/card"), "{t}");
    assert!(
        t.contains("√(∂z/∂x² + ∂z/∂y²), exact → max(|∂z/∂x|, |∂z/∂y|)"),
        "{t}"
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("changed/latest/report.json")).unwrap_or_default(),
    )
    .expect("report.json");
    let row = report["runs"]
        .as_array()
        .and_then(|r| r.iter().find(|r| r["name"] == "ref/card"))
        .cloned()
        .unwrap_or_default();
    assert_eq!(
        row["failed"],
        serde_json::json!([{"check": "card", "count": 1}]),
        "{row}"
    );
    // Nothing was written under CI.
    assert!(
        std::fs::read_to_string(&kept).is_ok_and(|t| t.contains("exact")),
        "the kept card was rewritten"
    );

    // No card kept for the release: a skip that says so, not a pass.
    std::fs::remove_file(&kept).expect("rm");
    let o = conformance(&cases, &golden, &dir.join("none"));
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("Skip ref/card") && t.contains("no card kept for ref on umbra"),
        "{t}"
    );
}

/// `umbra selftest cards` on one GL 3.3 and one GLES 2 backend (every card fault applies to
/// one of them): each fault moves its own entry, and the card names it.
#[test]
fn every_card_fault_is_named_by_its_entry() {
    let o = umbra(&[
        "selftest",
        "cards",
        "--backend",
        "gl33/llvmpipe",
        "--backend",
        "gles2/llvmpipe",
    ]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(!t.contains("MISSED"), "{t}");
    for fault in [
        "offset-units@-0.5",
        "offset-factor@0.41421356",
        "bilinear-coarse",
        "clamp-float",
        "no-clamp",
        "mip-level-coarse",
        "clamp-ignored",
        "clamp-forced",
    ] {
        assert!(
            t.contains(&format!("caught gl33/llvmpipe {fault}"))
                || t.contains(&format!("caught gles2/llvmpipe {fault}")),
            "{fault}: {t}"
        );
    }
    assert!(
        t.contains("12 of 12 fault × backend pairs named by their entry"),
        "{t}"
    );
}

/// Calibrated judging sees what the spec cannot: `slope-short` (a slope-scaled bias a little
/// short) on the curved receiver's slope-scaled point stays inside the spec's freedom (the
/// polygon-offset unit and slope form may be anything the specs allow), and outside the
/// driver's own card, measured without the fault.
#[test]
fn a_run_inside_the_spec_but_outside_its_card_fails_card() {
    let dir = scratch("curved");
    let mut case: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(repo().join("cases/magnified/bias-forms-curved.json"))
            .expect("the curved case"),
    )
    .expect("JSON");
    case["sweep"]["shadow.bias"]["values"] =
        serde_json::json!([{"slope": {"scale": 0.0001, "max": 0.005}}]);
    std::fs::write(dir.join("curved.json"), case.to_string()).expect("write the case");
    let cases = dir.to_string_lossy().into_owned();
    let selftest = |extra: &[&str]| {
        let mut args = vec![
            "selftest",
            "--cases",
            &cases,
            "--backend",
            "gl33/llvmpipe",
            "--fault",
            "slope-short",
        ];
        args.extend_from_slice(extra);
        text(&umbra(&args))
    };
    let calibrated = selftest(&[]);
    assert!(
        calibrated.contains("caught by 1 of 1 points (card×1)"),
        "{calibrated}"
    );
    let spec = selftest(&["--spec-only"]);
    assert!(
        spec.contains("slope-short") && spec.contains("MISSED"),
        "{spec}"
    );
}
