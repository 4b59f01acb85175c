//! Helpers shared by the `umbra` binary's integration tests.
// Each test binary compiles this module and uses part of it.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Output;

/// A fresh, empty directory for one test: `target/tmp/umbra-test/BINARY/NAME`, per test
/// binary so that parallel test binaries never meet, and the same path on every run, so that
/// a run replaces what the last one left instead of adding to it (named by process id under
/// /tmp, the suite's conformance runs and judging caches left about 150 MB a run behind).
pub fn scratch(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap_or_default();
    let stem = exe.file_stem().and_then(|s| s.to_str()).unwrap_or("test");
    // Cargo names test binaries NAME-HASH; the hash changes with every build.
    let binary = stem.rsplit_once('-').map_or(stem, |(b, _)| b);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("umbra-test")
        .join(binary)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// stdout then stderr of a finished command, for assertions and failure messages.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The repository's golden of one `ref` run (`ref/acne-cull-front`), copied into `dir`'s
/// folder of `ref` (`DIR/ref/`, as [`umbra_runner::judge::golden::folder`] names it), so
/// that `ref` is a backend with goldens there and a run without its own golden is a missing
/// golden (a change to review), not a backend judged without goldens. The copied files' stem.
pub fn seed_goldens(dir: &std::path::Path) -> &'static str {
    const STEM: &str = "ref_acne-cull-front-52c5bb2b";
    let folder = umbra_runner::judge::golden::folder("ref");
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../golden")
        .join(&folder);
    let seeded = dir.join(&folder);
    std::fs::create_dir_all(&seeded).expect("the golden folder of ref");
    for ext in [".snap", ".snap.png"] {
        std::fs::copy(
            repo.join(format!("{STEM}{ext}")),
            seeded.join(format!("{STEM}{ext}")),
        )
        .expect("the repository's golden of ref/acne-cull-front");
    }
    STEM
}
