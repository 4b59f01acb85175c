//! Goldens through insta, end to end, in a scratch golden directory that holds one other
//! golden of the backend (an empty directory, tested last, must fail the same way):
//! missing golden under CI → fail, nothing written; bless (`--bless`, what `cargo xtask
//! bless` runs) → written;
//! unchanged → pass without rewriting; a deliberately changed golden → fail under CI with
//! nothing written, and outside CI a pending `.snap.new` for `cargo insta review`.

mod common;

use common::{seed_goldens, text};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn umbra(golden: &Path, out: &Path, env: &[(&str, &str)]) -> Output {
    umbra_with(golden, out, env, &[])
}

fn umbra_with(golden: &Path, out: &Path, env: &[(&str, &str)], extra: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_umbra"));
    cmd.args([
        "conformance",
        "--backend",
        "ref",
        "--filter",
        "square*",
        "--golden",
        golden.to_str().unwrap_or_default(),
        "--out",
        out.to_str().unwrap_or_default(),
    ])
    .args(extra)
    .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
    .env_remove("CI")
    .env_remove("INSTA_UPDATE");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run umbra")
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn goldens_fail_on_change_and_are_only_written_by_blessing() {
    let root: PathBuf = std::env::temp_dir().join(format!("umbra-golden-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("dir");
    let seeded = seed_goldens(&golden);
    // The backend's goldens are in its own folder of the golden directory, and nothing else
    // is there beside it.
    let folder = umbra_runner::judge::golden::folder("ref");
    let ref_goldens = golden.join(&folder);
    let before_ci = files(&ref_goldens);
    assert_eq!(files(&golden), [folder.as_str()]);

    let o = umbra(&golden, &out, &[("CI", "true")]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("has no golden yet; CI=true: nothing written"),
        "{}",
        text(&o)
    );
    assert_eq!(
        files(&ref_goldens),
        before_ci,
        "CI wrote {:?}",
        files(&ref_goldens)
    );
    assert_eq!(
        files(&golden),
        [folder.as_str()],
        "CI wrote {:?}",
        files(&golden)
    );

    let o = umbra_with(&golden, &out, &[], &["--bless"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let written: Vec<String> = files(&ref_goldens)
        .into_iter()
        .filter(|f| !f.starts_with(seeded))
        .collect();
    // The golden (snapshot + picture); the reference has no driver version, so no manifest
    // of blessed drivers is written.
    assert_eq!(written.len(), 2, "{written:?}");
    assert_eq!(files(&golden), [folder.as_str()], "{:?}", files(&golden));
    let png = ref_goldens.join(
        written
            .iter()
            .find(|f| f.ends_with(".snap.png"))
            .expect("png"),
    );
    let before = std::fs::read(&png).expect("golden png");

    let o = umbra(&golden, &out, &[("CI", "true")]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "unchanged must pass: {}",
        text(&o)
    );
    assert_eq!(
        std::fs::read(&png).expect("png"),
        before,
        "an unchanged golden is not rewritten"
    );

    // Deliberately change the golden: paint a 12x12 block red.
    let mut img = image::load_from_memory(&before).expect("decode").to_rgba8();
    for y in 100..112 {
        for x in 100..112 {
            img.put_pixel(x, y, image::Rgba([255, 0, 0, 255]));
        }
    }
    img.save(&png).expect("save");
    let o = umbra(&golden, &out, &[("CI", "true")]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("differs from its golden"), "{}", text(&o));
    assert_eq!(
        files(&ref_goldens).len(),
        4,
        "CI must not write a pending snapshot"
    );
    assert_eq!(
        files(&golden),
        [folder.as_str()],
        "CI must not write a pending snapshot"
    );

    let o = umbra(&golden, &out, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        files(&ref_goldens).iter().any(|f| f.ends_with(".snap.new")),
        "pending snapshot for review: {:?}",
        files(&ref_goldens)
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_golden_mismatch_is_one_line_even_with_backtraces_on() {
    let root: PathBuf =
        std::env::temp_dir().join(format!("umbra-golden-bt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("dir");
    seed_goldens(&golden);
    let o = umbra(&golden, &out, &[("CI", "true"), ("RUST_BACKTRACE", "1")]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    for noise in ["stack backtrace", "panicked", "Snapshot Summary"] {
        assert!(!t.contains(noise), "{noise:?} in:\n{t}");
    }
    // One line on the terminal per mismatch (the run's line), the command to review it in it.
    let lines: Vec<&str> = t
        .lines()
        .filter(|l| l.contains("has no golden yet"))
        .collect();
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("[1/1] Fail ref/square-occluder")
                && l.contains("cargo xtask bless")),
        "{t}"
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn an_empty_golden_directory_never_switches_this_build_s_golden_checks_off() {
    // Only a device's id may have no goldens (egl_device.rs); for this build's ids an empty
    // golden directory (a wrong working directory, an unchecked-out golden/) is a missing
    // golden per run, a failure under CI.
    let root: PathBuf =
        std::env::temp_dir().join(format!("umbra-golden-none-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (golden, out) = (root.join("golden"), root.join("out"));
    std::fs::create_dir_all(&golden).expect("dir");
    let o = umbra(&golden, &out, &[("CI", "true")]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("has no golden yet"), "{t}");
    assert!(!t.contains("no goldens for this backend"), "{t}");
    assert!(files(&golden).is_empty(), "CI wrote {:?}", files(&golden));
    let _ = std::fs::remove_dir_all(&root);
}
