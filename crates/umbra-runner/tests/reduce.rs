//! `umbra reduce` on a case point that fails under one of the self-test's faults (a driver
//! bug made to order): the reduced case has at most a quarter of the triangles and of the
//! pixels, still fails the same way on that backend, and still passes on the reference.

mod common;

use common::{scratch, text};

use std::path::Path;
use std::process::{Command, Output};

fn umbra(args: &[&str], fault: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_umbra"));
    c.args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env_remove("UMBRA_MESA")
        .env_remove("UMBRA_SELFTEST")
        .env_remove("UMBRA_FAULT");
    if let Some(f) = fault {
        c.env("UMBRA_SELFTEST", "1").env("UMBRA_FAULT", f);
    }
    c.output().expect("run umbra")
}

fn size(file: &Path) -> (usize, u64) {
    let points = umbra_case::load_file(file).expect("loads");
    let p = &points[0];
    let tris = umbra_case::tessellate(&p.case.scene).triangles.len();
    (
        tris,
        u64::from(p.case.camera.size[0]) * u64::from(p.case.camera.size[1]),
    )
}

#[test]
fn a_faulted_point_reduces_to_a_quarter_and_still_fails_the_same_way() {
    let fault = "shadow-half-texel";
    let backend = "gl33/llvmpipe";
    let case = "cases/bias/acne-cull-front.json";
    let out = scratch("reduce").join("reduced.json");
    let o = umbra(
        &[
            "reduce",
            case,
            "--point",
            "acne-cull-front",
            "--backend",
            backend,
            "-o",
            out.to_str().unwrap_or_default(),
        ],
        Some(fault),
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (tris0, px0) = size(&root.join(case));
    let (tris, px) = size(&out);
    assert!(tris * 4 <= tris0, "{tris} of {tris0} triangles\n{t}");
    assert!(px * 4 <= px0, "{px} of {px0} pixels\n{t}");
    let reduced = std::fs::read_to_string(&out).expect("reduced case");
    assert!(
        reduced.contains("reduced by umbra reduce from cases/bias/acne-cull-front.json"),
        "{reduced}"
    );
    // Still failing under the fault, by the same check the reducer kept.
    let file = out.to_str().unwrap_or_default();
    let o = umbra(
        &[
            "render",
            file,
            "--backend",
            backend,
            "-o",
            scratch("reduce-render").to_str().unwrap_or_default(),
        ],
        Some(fault),
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    // Still passing on the reference, and on the backend without the fault.
    for (b, f) in [("ref", None), (backend, None)] {
        let o = umbra(
            &[
                "render",
                file,
                "--backend",
                b,
                "-o",
                scratch("reduce-ok").to_str().unwrap_or_default(),
            ],
            f,
        );
        assert_eq!(o.status.code(), Some(0), "{b}: {}", text(&o));
    }
}

/// Lights go one at a time, and the last two become a one-light case (`light` alone, no
/// `lights`, no `shadow.placement`), which `umbra repro`'s program can carry: a fault that
/// breaks every light's map needs only one of three. (A fault that needs two lights keeps
/// two: `tests/repro.rs`, light-swap.)
#[test]
fn a_case_of_three_lights_reduces_to_the_one_light_its_failure_needs() {
    let out = scratch("reduce-lights").join("reduced.json");
    let o = umbra(
        &[
            "reduce",
            "cases/lights/three-lights.json",
            "--point",
            "three-lights@shadow.filter=nearest",
            "--backend",
            "gl33/llvmpipe",
            "-o",
            out.to_str().unwrap_or_default(),
        ],
        Some("shadow-half-texel"),
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("kept: removed light"), "{t}");
    let reduced = std::fs::read_to_string(&out).expect("reduced case");
    assert!(
        !reduced.contains("\"lights\"") && !reduced.contains("placement"),
        "{reduced}"
    );
    let points = umbra_case::load_file(&out).expect("the reduced case loads");
    assert_eq!(points[0].case.lights.len(), 1, "{reduced}");
    // Still failing under the fault, still passing without it.
    let file = out.to_str().unwrap_or_default();
    for (fault, code) in [(Some("shadow-half-texel"), 1), (None, 0)] {
        let dir = scratch("reduce-lights-render");
        let o = umbra(
            &[
                "render",
                file,
                "--backend",
                "gl33/llvmpipe",
                "-o",
                dir.to_str().unwrap_or_default(),
            ],
            fault,
        );
        assert_eq!(o.status.code(), Some(code), "{fault:?}: {}", text(&o));
    }
}

#[test]
fn a_point_that_passes_is_not_reduced() {
    let o = umbra(
        &[
            "reduce",
            "cases/basics/square-occluder.json",
            "--point",
            "square-occluder",
            "--backend",
            "gl33/llvmpipe",
            "-o",
            scratch("reduce-pass")
                .join("x.json")
                .to_str()
                .unwrap_or_default(),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("reduce needs a point whose own frame fails"),
        "{t}"
    );
}

/// `--point` takes the glob its help offers (one point must match; several are refused by
/// name), and a second `--backend` is refused rather than dropped (issue 36).
#[test]
fn point_globs_select_one_point_and_one_backend_is_asked() {
    let out = scratch("reduce-args").join("x.json");
    let out = out.to_str().unwrap_or_default();
    let glob = umbra(
        &[
            "reduce",
            "cases/basics/square-occluder.json",
            "--point",
            "square-*",
            "--backend",
            "gl33/llvmpipe",
            "-o",
            out,
        ],
        None,
    );
    let t = text(&glob);
    assert_eq!(glob.status.code(), Some(1), "{t}");
    assert!(
        t.contains("reduce needs a point whose own frame fails"),
        "the glob selected it: {t}"
    );
    let many = umbra(
        &[
            "reduce",
            "cases/bias/acne-remedies.json",
            "--point",
            "*",
            "--backend",
            "gl33/llvmpipe",
            "-o",
            out,
        ],
        None,
    );
    let t = text(&many);
    assert_eq!(many.status.code(), Some(125), "{t}");
    assert!(
        t.contains("matches") && t.contains("a reduction takes one"),
        "{t}"
    );
    let two = umbra(
        &[
            "reduce",
            "cases/basics/square-occluder.json",
            "--point",
            "square-occluder",
            "--backend",
            "gl33/llvmpipe",
            "--backend",
            "gl33/zink",
            "-o",
            out,
        ],
        None,
    );
    let t = text(&two);
    assert_eq!(two.status.code(), Some(125), "{t}");
    assert!(t.contains("give --backend once"), "{t}");
    // --check takes the judge's vocabulary, checked when read (issue 37: it was not).
    let typo = umbra(
        &[
            "reduce",
            "cases/basics/square-occluder.json",
            "--point",
            "square-occluder",
            "--backend",
            "gl33/llvmpipe",
            "--check",
            "color",
            "-o",
            out,
        ],
        None,
    );
    let t = text(&typo);
    assert_eq!(typo.status.code(), Some(125), "{t}");
    assert!(t.contains("did you mean colour?"), "{t}");
}
