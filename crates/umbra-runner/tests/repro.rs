//! `umbra repro` on a real driver deviation (softpipe's per-vertex clamp of the polygon offset,
//! expectations/mesa-22.3.txt): the bundle's `repro.c`, compiled here with `cc` and run without
//! umbra, exits 1 on softpipe and 0 on llvmpipe; its capture replays on both. And the ways a
//! repro could be wrong are refused: a run that passes, and a mistake in umbra's own GL calls
//! (a self-test fault), which the conforming control reproduces too.

mod common;

use common::{scratch, text};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// beyond-far on softpipe: receivers just before the far plane, whose far-clipped triangles
/// lose their polygon offset on softpipe (draw_pipe_offset.c).
const OFFSET_CLAMP: &str = "gl33/softpipe/beyond-far@shadow.compare=hardware,shadow.format=depth24";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn umbra(args: &[&str], fault: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_umbra"));
    c.args(args)
        .current_dir(repo())
        .env_remove("UMBRA_MESA")
        .env_remove("UMBRA_SELFTEST")
        .env_remove("UMBRA_FAULT");
    if let Some(f) = fault {
        c.env("UMBRA_SELFTEST", "1").env("UMBRA_FAULT", f);
    }
    c.output().expect("run umbra")
}

/// Runs the compiled program on a Mesa driver, as the bundle's README says.
fn run_repro(binary: &Path, driver: &str) -> Output {
    Command::new(binary)
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .env("GALLIUM_DRIVER", driver)
        .env_remove("UMBRA_MESA")
        .output()
        .expect("run repro")
}

#[test]
fn the_softpipe_offset_clamp_bundle_fails_on_softpipe_and_passes_on_llvmpipe_without_umbra() {
    let dir = scratch("repro-offset-clamp").join("bundle");
    let o = umbra(
        &[
            "repro",
            OFFSET_CLAMP,
            "-o",
            dir.to_str().unwrap_or_default(),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    for f in [
        "repro.c",
        "case.json",
        "issue.md",
        "README.md",
        "expected.png",
        "actual.png",
        "difference.png",
        "full/color.png",
        "capture.trace",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing: {t}");
    }
    // Compiled as issue.md says, by this test rather than by umbra.
    let binary = dir.join("repro-by-test");
    let cc = Command::new("cc")
        .arg(dir.join("repro.c"))
        .arg("-o")
        .arg(&binary)
        .args(["-Wall", "-lEGL", "-lm"])
        .output()
        .expect("cc (gcc) is installed by cargo xtask test");
    assert!(cc.status.success(), "{}", text(&cc));
    let soft = run_repro(&binary, "softpipe");
    let st = text(&soft);
    assert_eq!(soft.status.code(), Some(1), "softpipe: {st}");
    assert!(st.contains("GL_RENDERER: softpipe"), "{st}");
    assert!(st.contains("OUTSIDE"), "{st}");
    let llvm = run_repro(&binary, "llvmpipe");
    let lt = text(&llvm);
    assert_eq!(llvm.status.code(), Some(0), "llvmpipe: {lt}");
    assert!(lt.contains("GL_RENDERER: llvmpipe"), "{lt}");
    assert!(!lt.contains("OUTSIDE"), "{lt}");
    // Every probe printed on both, the same count: the same probes, two verdicts.
    let probes = |s: &str| {
        s.lines()
            .filter(|l| l.starts_with("pixel (") || l.starts_with("texel ("))
            .count()
    };
    let n = probes(&st);
    assert!(n > 0);
    assert_eq!(n, probes(&lt));
    // Every probe is a pixel or texel the judge failed on softpipe: the program must find
    // each one outside (an interval wider than the judge's would let some pass), and none on
    // llvmpipe, which the judge passes.
    assert!(st.contains(&format!("{n} of {n} probes outside")), "{st}");
    assert!(lt.contains(&format!("0 of {n} probes outside")), "{lt}");
    // issue.md: the violated rule in its title, the driver strings, both exit codes, the
    // capture's replays on both drivers.
    let issue = std::fs::read_to_string(dir.join("issue.md")).expect("issue.md");
    assert!(issue.starts_with("# softpipe: "), "{issue}");
    assert!(issue.contains("§14.6.5"), "{issue}");
    assert!(issue.contains("GL_RENDERER: `softpipe`"), "{issue}");
    assert!(
        issue.contains("./repro   # gl33/softpipe: exit 1"),
        "{issue}"
    );
    assert!(
        issue.contains("./repro   # gl33/llvmpipe: exit 0"),
        "{issue}"
    );
    assert!(
        issue.contains("draw_pipe_offset.c"),
        "the diagnosis: {issue}"
    );
    let replays = std::fs::read_dir(&dir)
        .expect("bundle")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("replay-"))
        .count();
    assert_eq!(replays, 2, "a snapshot replayed on each driver: {issue}");
    // The state at the draw, compared: the shadow map differs between the two replays.
    assert!(dir.join("state-gl33-softpipe.json").is_file(), "{issue}");
    let map_line = issue
        .lines()
        .find(|l| l.contains("GL_TEXTURE_2D, level = 0: "))
        .unwrap_or_else(|| panic!("no state comparison: {issue}"));
    assert!(!map_line.contains("level = 0: 0 of"), "{map_line}");
}

#[test]
fn a_run_that_passes_is_refused_with_a_reason() {
    let dir = scratch("repro-passing").join("bundle");
    let o = umbra(
        &[
            "repro",
            "gl33/llvmpipe/beyond-far@shadow.compare=hardware,shadow.format=depth24",
            "-o",
            dir.to_str().unwrap_or_default(),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("error: nothing to reproduce"), "{t}");
    assert!(t.contains("pass"), "{t}");
    assert!(!dir.join("repro.c").exists(), "{t}");
}

/// What repro was given is read strictly: a `--case` file that does not load says why (it
/// once became "no case point"), a damaged expectations directory is said before any work (it
/// was dropped from issue.md), and `--bisect-log` without `--first-bad` is refused (it was
/// ignored).
#[test]
fn what_repro_is_given_is_refused_when_it_cannot_be_read() {
    let dir = scratch("repro-strict");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{\"name\": \"bad\", \"shadow\": 3}").expect("case");
    let out = dir.join("bundle");
    let o = umbra(
        &[
            "repro",
            "gl33/llvmpipe/bad",
            &format!("--case={}", bad.display()),
            &format!("--out={}", out.display()),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("bad.json") && !t.contains("no case point"),
        "{t}"
    );
    let exp = dir.join("expectations");
    std::fs::create_dir_all(&exp).expect("dir");
    std::fs::write(exp.join("x.txt"), "not an expectation\n").expect("expectation");
    let o = umbra(
        &[
            "repro",
            "gl33/llvmpipe/l-occluder",
            &format!("--expectations={}", exp.display()),
            &format!("--out={}", out.display()),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("x.txt:1"), "{t}");
    let o = umbra(
        &[
            "repro",
            "gl33/llvmpipe/l-occluder",
            "--bisect-log=log.txt",
            &format!("--out={}", out.display()),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("--bisect-log goes with --first-bad"), "{t}");
    assert!(!out.exists(), "{t}");
}

#[test]
fn a_mistake_in_umbras_own_calls_is_not_blamed_on_the_driver() {
    // The shadow pass's viewport set to the camera's size: a bug in the program, which the
    // recorded C carries, so the conforming control fails it too.
    let dir = scratch("repro-fault").join("bundle");
    let o = umbra(
        &[
            "repro",
            "gl33/llvmpipe/square-occluder",
            "--control",
            "gl33/softpipe",
            "-o",
            dir.to_str().unwrap_or_default(),
        ],
        Some("shadow-viewport"),
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("does not reproduce as it must") && t.contains("exit 1 on gl33/softpipe"),
        "{t}"
    );
}

/// A failure that needs two lights (light-swap: one light's pass reads the other's map) keeps
/// both through the reducer, and the repro is refused naming the reduced case: its program's
/// probes hold one light's visibility.
#[test]
fn a_failure_that_needs_several_lights_is_refused_naming_its_reduced_case() {
    let dir = scratch("repro-lights").join("bundle");
    let o = umbra(
        &[
            "repro",
            "gl33/llvmpipe/three-lights@shadow.filter=nearest",
            "-o",
            dir.to_str().unwrap_or_default(),
        ],
        Some("light-swap"),
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("the failure needs 2 lights"), "{t}");
    let points = umbra_case::load_file(&dir.join("case.json")).expect("the reduced case");
    assert_eq!(points[0].case.lights.len(), 2, "{t}");
    assert!(!dir.join("repro.c").exists(), "{t}");
}

#[test]
fn a_bundle_is_never_written_over_another() {
    let dir = scratch("repro-twice");
    std::fs::write(dir.join("issue.md"), "an earlier bundle").expect("write");
    let o = umbra(
        &[
            "repro",
            OFFSET_CLAMP,
            "-o",
            dir.to_str().unwrap_or_default(),
        ],
        None,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("is not empty"), "{t}");
    assert_eq!(
        std::fs::read_to_string(dir.join("issue.md")).unwrap_or_default(),
        "an earlier bundle"
    );
}
