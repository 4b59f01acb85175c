//! The GL backend reached through an EGL device (EGL_EXT_platform_device, what EGL libraries
//! without Mesa's surfaceless platform offer) renders what the surfaceless path renders: on
//! llvmpipe, every picture of these cases on GL 3.3, GLES 3 and GLES 2 is byte-identical
//! either way (colour, visibility, the judge's pictures and the read-back shadow map). A
//! device that does not exist is a skip that says so, not a failure or a fallback.
//!
//! A device umbra has never seen: Mesa's software EGL device under the id its driver gives
//! (`gl33/swrast`: llvmpipe, renamed), with no goldens and no expectation naming it, is judged
//! by the specs and the reference alone and passes; the same runs with a self-test fault on
//! (polygon-offset units a step low) fail.

mod common;

use common::{scratch, text};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn umbra(args: &[&str], platform: Option<&str>) -> Output {
    umbra_with(args, platform, &[])
}

fn umbra_with(args: &[&str], platform: Option<&str>, env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_umbra"));
    c.args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env_remove("UMBRA_MESA")
        .env_remove("UMBRA_SELFTEST")
        .env_remove("UMBRA_FAULT")
        .env_remove("UMBRA_EGL_PLATFORM");
    if let Some(p) = platform {
        c.env("UMBRA_EGL_PLATFORM", p);
    }
    c.envs(env.iter().copied());
    c.output().expect("run umbra")
}

/// Every PNG under `dir`, relative, sorted.
fn pictures(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "png") {
                out.push(p.strip_prefix(dir).unwrap_or(&p).to_path_buf());
            }
        }
    }
    out.sort();
    out
}

#[test]
fn the_egl_device_path_renders_what_the_surfaceless_path_renders() {
    let cases = [
        "cases/lights/point-cube.json",
        "cases/mipmaps/averaged.json",
        "cases/formats/formats.json",
        "cases/lookup/outside.json",
    ];
    let root = scratch("egl-device");
    let mut compared = 0;
    for backend in ["gl33/llvmpipe", "gles3/llvmpipe", "gles2/llvmpipe"] {
        for case in cases {
            let name = format!(
                "{}-{}",
                backend.replace('/', "-"),
                Path::new(case)
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or("case")
            );
            let (a, b) = (
                root.join(&name).join("surfaceless"),
                root.join(&name).join("device"),
            );
            let oa = umbra(
                &[
                    "render",
                    case,
                    "--backend",
                    backend,
                    "-o",
                    a.to_str().unwrap_or_default(),
                ],
                None,
            );
            let ob = umbra(
                &[
                    "render",
                    case,
                    "--backend",
                    backend,
                    "-o",
                    b.to_str().unwrap_or_default(),
                ],
                Some("device"),
            );
            // Both ran, or both had nothing but skips (exit 125, "nothing ran": a case GLES 2
            // cannot render at all).
            let only_skips = |o: &std::process::Output| {
                o.status.code() == Some(125) && text(o).contains("error: nothing ran: every point")
            };
            assert!(
                (oa.status.success() && ob.status.success())
                    || (only_skips(&oa) && only_skips(&ob)),
                "{}\n{}",
                text(&oa),
                text(&ob)
            );
            // The backend itself opens on the device; a case's own skips match.
            assert!(
                !text(&ob).contains(&format!("skip {backend}:")),
                "{}",
                text(&ob)
            );
            assert_eq!(
                text(&oa).matches("  skip: ").count(),
                text(&ob).matches("  skip: ").count()
            );
            let (pa, pb) = (pictures(&a), pictures(&b));
            assert_eq!(pa, pb, "{name}: the same pictures");
            for p in &pa {
                let (x, y) = (std::fs::read(a.join(p)), std::fs::read(b.join(p)));
                assert!(
                    x.is_ok() && x.ok() == y.ok(),
                    "{name}: {} differs",
                    p.display()
                );
                compared += 1;
            }
        }
    }
    assert!(compared > 100, "only {compared} pictures compared");
}

#[test]
fn a_device_that_does_not_exist_is_a_skip_with_its_reason() {
    let dir = scratch("egl-device-missing");
    let o = umbra(
        &[
            "render",
            "cases/basics/square-occluder.json",
            "--backend",
            "gl33/llvmpipe",
            "-o",
            dir.to_str().unwrap_or_default(),
        ],
        Some("device:99"),
    );
    let t = text(&o);
    assert!(
        t.contains("skip gl33/llvmpipe: UMBRA_EGL_PLATFORM: there is no EGL device 99"),
        "{t}"
    );
    assert!(!dir.join("color.png").exists(), "{t}");
}

#[test]
fn umbra_backends_lists_the_backends_the_egl_devices_and_the_adapters() {
    let o = umbra(&["backends", "--json"], None);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value =
        serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&o)));
    let backend = |id: &str| {
        v["backends"]
            .as_array()
            .and_then(|a| a.iter().find(|b| b["id"] == id))
            .cloned()
            .unwrap_or_else(|| panic!("{id} not listed: {v}"))
    };
    let llvm = backend("gl33/llvmpipe");
    assert_eq!(llvm["available"], true, "{llvm}");
    assert!(
        llvm["renderer"]
            .as_str()
            .is_some_and(|r| r.starts_with("llvmpipe")),
        "{llvm}"
    );
    assert!(
        llvm["version"].as_str().is_some_and(|r| r.contains("Mesa")),
        "{llvm}"
    );
    assert_eq!(backend("gl33/softpipe")["renderer"], "softpipe");
    // The software EGL device under its driver's name, reached through the device platform,
    // run only when named; wgpu's lavapipe found by its name.
    let swrast = backend("gl33/swrast");
    assert_eq!(swrast["available"], true, "{swrast}");
    assert_eq!(swrast["kind"], "software device", "{swrast}");
    assert!(
        swrast["device"]
            .as_str()
            .is_some_and(|d| d.starts_with("EGL device")),
        "{swrast}"
    );
    let lavapipe = backend("wgpu-vk/lavapipe");
    assert_eq!(lavapipe["available"], true, "{lavapipe}");
    assert!(
        lavapipe["renderer"]
            .as_str()
            .is_some_and(|r| r.starts_with("llvmpipe")),
        "{lavapipe}"
    );
    // Mesa's software device, with a context of each API.
    let devices = v["egl_devices"].as_array().expect("EGL devices listed");
    let software = devices
        .iter()
        .find(|d| d["software"] == true)
        .unwrap_or_else(|| panic!("no software device: {v}"));
    let contexts = software["contexts"].as_array().expect("contexts");
    assert_eq!(contexts.len(), 3, "{software}");
    assert!(
        contexts.iter().all(|c| c["renderer"].is_string()),
        "{software}"
    );
    // lavapipe among wgpu's Vulkan adapters.
    assert!(
        v["wgpu_adapters"].as_array().is_some_and(|a| a
            .iter()
            .any(|x| x["backend"] == "Vulkan" && x["device_type"] == "Cpu")),
        "{v}"
    );
}

#[test]
fn a_device_umbra_has_never_seen_is_judged_by_the_specs_alone_and_a_fault_on_it_fails() {
    let ids = ["gl33/swrast", "gles3/swrast", "gles2/swrast"];
    let run = |out: &Path, env: &[(&str, &str)]| {
        let mut args = vec!["conformance", "--filter", "formats*", "--out"];
        args.push(out.to_str().unwrap_or_default());
        for id in ids {
            args.extend(["--backend", id]);
        }
        umbra_with(&args, None, &[&[("CI", "true")], env].concat())
    };
    let clean = scratch("never-seen");
    let o = run(&clean, &[]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    for id in ids {
        assert!(
            t.contains(&format!(
                "{id}: no goldens for this backend: judged by the specs and the reference"
            )),
            "{t}"
        );
    }
    let summary = t.lines().last().unwrap_or("");
    assert!(
        summary.starts_with("conformance: 22 passed, 0 failed"),
        "{t}"
    );
    let drivers = std::fs::read_to_string(clean.join("latest/drivers.txt")).unwrap_or_default();
    assert_eq!(
        drivers
            .matches("goldens: no goldens for this backend: judged by the specs and the reference")
            .count(),
        3,
        "{drivers}"
    );
    assert_eq!(
        drivers.matches("device: EGL device 0").count(),
        3,
        "{drivers}"
    );
    let html = std::fs::read_to_string(clean.join("latest/report.html")).unwrap_or_default();
    assert!(
        html.contains("no goldens for this backend"),
        "report.html says so"
    );
    // No golden was written for them.
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../golden");
    assert!(
        std::fs::read_dir(&golden)
            .into_iter()
            .flatten()
            .flatten()
            .all(|e| !e.file_name().to_string_lossy().contains("swrast")),
        "a golden for swrast appeared"
    );

    let faulted = scratch("never-seen-fault");
    let o = run(
        &faulted,
        &[("UMBRA_SELFTEST", "1"), ("UMBRA_FAULT", "offset-units-low")],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let failed: Vec<&str> = t.lines().filter(|l| l.contains("] Fail ")).collect();
    assert!(!failed.is_empty(), "{t}");
    assert!(failed.iter().all(|l| l.contains("/swrast/")), "{t}");
}

#[test]
fn device_ids_and_the_hw_alias_name_what_this_machine_has() {
    let dir = scratch("hw-alias");
    let out = dir.to_str().unwrap_or_default();
    let o = umbra(&["backends", "--ids"], None);
    let ids = text(&o);
    assert!(ids.contains(r#""id":"gles2/swrast""#), "{ids}");
    assert!(ids.contains(r#""id":"gl33/swrast","reached""#) || ids.contains("gl33/swrast"));
    // An expectation for a device this machine lacks is kept for the machines that have it,
    // not refused as a pattern that can never match.
    let exp = scratch("hw-alias-expectations");
    std::fs::write(
        exp.join("radeonsi.txt"),
        "gl33/radeonsi/formats@*,Fail:map<=1,an expectation for a machine with an AMD GPU\n",
    )
    .expect("expectations");
    let o = umbra(
        &[
            "conformance",
            "--backend",
            "gl33/swrast",
            "--filter",
            "formats@shadow.depth_order=forward,shadow.format=depth16",
            "--expectations",
            exp.to_str().unwrap_or_default(),
            "--out",
            out,
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // A device id's processes inherit none of Mesa's driver selection: with softpipe asked
    // for in the environment, the software device still answers with its default driver.
    let o = umbra_with(
        &[
            "conformance",
            "--backend",
            "gl33/swrast",
            "--filter",
            "formats@shadow.depth_order=forward,shadow.format=depth16",
            "--out",
            out,
        ],
        None,
        &[
            ("GALLIUM_DRIVER", "softpipe"),
            ("LIBGL_ALWAYS_SOFTWARE", "1"),
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let drivers = std::fs::read_to_string(dir.join("latest/drivers.txt")).unwrap_or_default();
    assert!(
        drivers.contains("gl33/swrast: Mesa/X.org | llvmpipe"),
        "{drivers}"
    );
    if ids.contains(r#""hardware":true"#) {
        println!("this machine has a hardware device; the no-GPU errors are not checked: {ids}");
        return;
    }
    // No GPU here: `hw` is an error that lists the devices there are, as is a device the
    // machine lacks; neither runs anything.
    for (id, says) in [
        ("hw", "--backend hw: this machine has no hardware device"),
        (
            "gl33/radeonsi",
            "--backend gl33/radeonsi: no such device on this machine",
        ),
    ] {
        let o = umbra(
            &[
                "conformance",
                "--backend",
                id,
                "--filter",
                "formats*",
                "--out",
                out,
            ],
            None,
        );
        let t = text(&o);
        assert_eq!(o.status.code(), Some(125), "{t}");
        assert!(t.contains(says) && t.contains("gl33/swrast"), "{t}");
    }
}

#[test]
fn a_context_on_a_pbuffer_renders_what_a_surfaceless_context_renders() {
    // The path a display without EGL_KHR_surfaceless_context takes (UMBRA_EGL_PBUFFER forces
    // it here).
    let root = scratch("egl-pbuffer");
    let o = umbra_with(&["backends", "--json"], None, &[("UMBRA_EGL_PBUFFER", "1")]);
    let listed = text(&o);
    assert!(
        listed.contains("\"egl\": \"Mesa Project 1.5, current on a 1x1 pbuffer\""),
        "the pbuffer path is taken: {listed}"
    );
    for backend in ["gl33/llvmpipe", "gles2/llvmpipe", "gl33/swrast"] {
        let dirs = [
            backend.replace('/', "-"),
            format!("{}-pbuffer", backend.replace('/', "-")),
        ]
        .map(|d| root.join(d));
        for (dir, env) in dirs
            .iter()
            .zip([&[][..], &[("UMBRA_EGL_PBUFFER", "1")][..]])
        {
            let o = umbra_with(
                &[
                    "render",
                    "cases/lights/point-cube.json",
                    "--backend",
                    backend,
                    "-o",
                    dir.to_str().unwrap_or_default(),
                ],
                None,
                env,
            );
            assert!(o.status.success(), "{}", text(&o));
        }
        let (pa, pb) = (pictures(&dirs[0]), pictures(&dirs[1]));
        assert!(!pa.is_empty() && pa == pb, "{backend}: {pa:?} {pb:?}");
        for p in &pa {
            assert_eq!(
                std::fs::read(dirs[0].join(p)).ok(),
                std::fs::read(dirs[1].join(p)).ok(),
                "{backend}: {} differs",
                p.display()
            );
        }
    }
}
