//! The `umbra` binary as a user meets it: driver processes, exit codes, reports, errors.

mod common;

use common::{scratch, text};

use std::path::Path;
use std::process::{Command, Output};

fn umbra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env_remove("GALLIUM_DRIVER")
        .env_remove("LIBGL_ALWAYS_SOFTWARE")
        .output()
        .expect("run umbra")
}

#[test]
fn a_driver_other_than_this_process_runs_in_its_own_process_and_reports_back() {
    let out = scratch("softpipe");
    let o = umbra(&[
        "conformance",
        "--backend",
        "gles3/softpipe",
        "--backend",
        "ref",
        "--filter",
        "spot*",
        "--out",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let results = std::fs::read_to_string(out.join("latest/results.csv")).expect("results.csv");
    assert!(
        results.contains("gles3/softpipe/spot-20deg,Pass,"),
        "{results}"
    );
    assert!(results.contains("ref/spot-20deg,Pass,"), "{results}");
    assert!(
        text(&o).contains("conformance: 2 passed, 0 failed, 0 skipped"),
        "{}",
        text(&o)
    );
}

#[test]
fn render_on_zink_writes_the_pictures() {
    let out = scratch("zink");
    let o = umbra(&[
        "render",
        "cases/basics/square-occluder.json",
        "--backend",
        "gl33/zink",
        "-o",
        out.to_str().unwrap_or_default(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(
        text(&o).contains("square-occluder on gl33/zink"),
        "{}",
        text(&o)
    );
    assert!(text(&o).contains("vs reference: 0 of"), "{}", text(&o));
    for f in [
        "color.png",
        "visibility.png",
        "truth.png",
        "error.png",
        "shadow_map.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
}

#[test]
fn an_unknown_backend_cannot_run() {
    let o = umbra(&["conformance", "--backend", "vulkan/nvidia"]);
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
    assert!(
        text(&o).contains("invalid value 'vulkan/nvidia' for '--backend <ID>': unknown backend")
            && text(&o).contains("gles2/zink"),
        "{}",
        text(&o)
    );
}

#[test]
fn a_malformed_case_fails_the_run_with_its_file_path_and_fix() {
    let dir = scratch("cases");
    std::fs::write(dir.join("bad.json"), r#"{ "name": "bad", "about": "x", "scene": { "objects": [] },
        "camera": { "eye": [0, 1, 2], "target": [0, 0, 0] },
        "light": { "spot": { "position": [0, 5, 0], "target": [0, 0, 0], "fov_y_deg": 30, "up": [0, 0, 1] } } }"#)
        .expect("write");
    let o = umbra(&[
        "conformance",
        "--backend",
        "ref",
        "--cases",
        dir.to_str().unwrap_or_default(),
        "--out",
        scratch("cases-out").to_str().unwrap_or_default(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("bad.json: scene.objects: the scene is empty; fix: add at least one object"),
        "{t}"
    );
}

#[test]
fn no_cases_cannot_run() {
    let dir = scratch("empty");
    let o = umbra(&["conformance", "--cases", dir.to_str().unwrap_or_default()]);
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
}

#[test]
fn without_a_loadable_libegl_gl_runs_are_skips_that_name_the_package() {
    // A libEGL that cannot be loaded stands in for a machine without Mesa.
    let lib = scratch("noegl");
    for name in ["libEGL.so.1", "libEGL.so"] {
        std::fs::write(lib.join(name), b"not a shared object").expect("fake lib");
    }
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args([
            "conformance",
            "--backend",
            "gles3/llvmpipe",
            "--filter",
            "square*",
            "--out",
            lib.join("out").to_str().unwrap_or_default(),
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env("LD_LIBRARY_PATH", &lib)
        .env_remove("GALLIUM_DRIVER")
        .output()
        .expect("run umbra");
    let t = text(&o);
    assert_eq!(
        o.status.code(),
        Some(125),
        "nothing could run here, so 125 (git bisect skips): {t}"
    );
    assert!(
        t.contains("Skip gles3/llvmpipe/square-occluder (") && t.contains("cannot load libEGL"),
        "{t}"
    );
    assert!(t.contains("libegl1 and libegl-mesa0"), "{t}");
    assert!(
        t.contains("conformance: 0 passed, 0 failed, 1 skipped"),
        "{t}"
    );
}

#[test]
fn without_a_vulkan_driver_wgpu_vk_runs_are_skips_that_name_the_package() {
    // No ICD for the Vulkan loader stands in for a machine without mesa-vulkan-drivers.
    let out = scratch("novk");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args([
            "conformance",
            "--backend",
            "wgpu-vk/lavapipe",
            "--filter",
            "square*",
            "--out",
            out.to_str().unwrap_or_default(),
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .output()
        .expect("run umbra");
    let t = text(&o);
    assert_eq!(
        o.status.code(),
        Some(125),
        "nothing could run here, so 125 (git bisect skips): {t}"
    );
    assert!(
        t.contains("Skip wgpu-vk/lavapipe/square-occluder (")
            && t.contains("no adapter on Backends(VULKAN)"),
        "{t}"
    );
    assert!(t.contains("mesa-vulkan-drivers"), "{t}");
}

/// `umbra render` says "could not run" (125, as its help says) for a missing case, an invalid
/// one, an unknown backend and a --point that matches nothing; never 1 (a failing point) or 2
/// (issue 36).
#[test]
fn render_that_cannot_run_exits_125() {
    let dir = scratch("render-125");
    let invalid = dir.join("invalid.json");
    std::fs::write(&invalid, "{\"name\": \"x\"}").expect("case");
    let invalid = invalid.to_string_lossy().into_owned();
    for (args, says) in [
        (vec!["render", "cases/nosuch.json"], "cannot read the file"),
        (vec!["render", invalid.as_str()], "invalid.json"),
        (
            vec![
                "render",
                "cases/basics/square-occluder.json",
                "--backend",
                "gl99/x",
            ],
            "unknown backend",
        ),
        (
            vec![
                "render",
                "cases/basics/square-occluder.json",
                "--point",
                "nothing*",
            ],
            "matches no sweep point",
        ),
    ] {
        let o = umbra(&args);
        assert_eq!(o.status.code(), Some(125), "{args:?}: {}", text(&o));
        assert!(text(&o).contains(says), "{args:?}: {}", text(&o));
    }
}
