//! umbra's numbers must not depend on the C library a process runs on: a worker on a Debian
//! suite's own glibc (`cargo xtask fetch-mesa --suite sid`) computed another camera
//! projection and another truth than one on the machine's, because `f32::tan` and friends
//! call the C library's libm (umbra_case::math says more). Every transcendental function of
//! the crates that build cases, matrices, references, truths and verdicts goes through
//! `umbra_case::math` (pure-Rust musl); this test holds their sources to it. (umbra-report's
//! plots may use std's: their axes are pictures, not results.)

use std::path::{Path, PathBuf};

/// Method calls that reach the C library's libm.
const LIBM_METHODS: &[&str] = &[
    ".sin()",
    ".cos()",
    ".tan()",
    ".sin_cos()",
    ".asin()",
    ".acos()",
    ".atan()",
    ".atan2(",
    ".sinh()",
    ".cosh()",
    ".tanh()",
    ".exp()",
    ".exp2()",
    ".exp_m1()",
    ".ln()",
    ".ln_1p()",
    ".log(",
    ".log2()",
    ".log10()",
    ".powf(",
    ".cbrt()",
    ".hypot(",
];

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir)
        .expect("read a source directory")
        .flatten()
    {
        let p = e.path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn results_use_no_libm_of_the_c_library() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    for c in [
        "umbra-case",
        "umbra-ref",
        "umbra-compare",
        "umbra-gl",
        "umbra-wgpu",
        "umbra-runner",
    ] {
        sources(&root.join("crates").join(c).join("src"), &mut files);
    }
    let math = root.join("crates/umbra-case/src/math.rs");
    let mut found = Vec::new();
    for f in files.iter().filter(|f| **f != math) {
        let text = std::fs::read_to_string(f).expect("read a source");
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for m in LIBM_METHODS {
                if code.contains(m) {
                    found.push(format!("{}:{}: {m}", f.display(), n + 1));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "these call the C library's libm; use umbra_case::math instead:\n{}",
        found.join("\n")
    );
    assert!(files.len() > 50, "the sources were found ({})", files.len());
}
