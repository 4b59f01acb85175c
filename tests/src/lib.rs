//! Shared helpers for umbra's cross-crate tests: where the starter cases are, and loading one
//! point of a case ready to render.

use std::path::{Path, PathBuf};

use umbra_case::{CasePoint, Prepared};

/// The repository's `cases/` directory.
pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("cases")
}

/// Every point of the case file `rel` (relative to `cases/`).
pub fn points(rel: &str) -> Vec<CasePoint> {
    let path = cases_dir().join(rel);
    umbra_case::load_file(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The first point of `rel`, prepared.
pub fn prepared(rel: &str) -> Prepared {
    Prepared::new(points(rel).remove(0))
}
