//! Helpers shared by the `umbra` binary's integration tests.
// Each test binary compiles this module and uses part of it.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Output;

/// A fresh, empty directory for one test (per process, so parallel test binaries never meet).
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("umbra-test-{}-{name}", std::process::id()));
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

/// The repository's golden of one `ref` run (`ref/acne-cull-front`), copied into `dir`, so
/// that `ref` is a backend with goldens there and a run without its own golden is a missing
/// golden (a change to review), not a backend judged without goldens. The copied files' stem.
pub fn seed_goldens(dir: &std::path::Path) -> &'static str {
    const STEM: &str = "ref_acne-cull-front-52c5bb2b";
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../golden");
    for ext in [".snap", ".snap.png"] {
        std::fs::copy(
            repo.join(format!("{STEM}{ext}")),
            dir.join(format!("{STEM}{ext}")),
        )
        .expect("the repository's golden of ref/acne-cull-front");
    }
    STEM
}
