//! Errors a user can act on: each names the file, the JSON path and the fix.

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem with one case file.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseError {
    /// The case file (or `<inline>` for text that did not come from a file).
    pub file: PathBuf,
    /// Where in the JSON, as `shadow.size[0]`; empty for the whole document.
    pub path: String,
    /// What is wrong, lower-case, no final period.
    pub message: String,
    /// What to do about it.
    pub fix: String,
}

impl CaseError {
    /// A new error for `file` at JSON `path`.
    pub fn new(
        file: &Path,
        path: impl Into<String>,
        message: impl Into<String>,
        fix: impl Into<String>,
    ) -> Self {
        CaseError {
            file: file.to_path_buf(),
            path: path.into(),
            message: message.into(),
            fix: fix.into(),
        }
    }
}

impl fmt::Display for CaseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let path = if self.path.is_empty() {
            "(document)"
        } else {
            &self.path
        };
        write!(
            f,
            "{}: {}: {}; fix: {}",
            self.file.display(),
            path,
            self.message,
            self.fix
        )
    }
}

impl std::error::Error for CaseError {}

/// Every problem found in one case file; validation does not stop at the first.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseErrors(pub Vec<CaseError>);

impl CaseErrors {
    /// The same errors with `context` (such as "at sweep point x=1: ") before each message.
    pub fn in_context(self, context: &str) -> CaseErrors {
        CaseErrors(
            self.0
                .into_iter()
                .map(|mut e| {
                    e.message = format!("{context}{}", e.message);
                    e
                })
                .collect(),
        )
    }

    /// The first error (there is always one).
    pub fn first(&self) -> &CaseError {
        &self.0[0]
    }

    /// Whether any error sits at `path` and mentions `needle`.
    pub fn has(&self, path: &str, needle: &str) -> bool {
        self.0
            .iter()
            .any(|e| e.path == path && e.message.contains(needle))
    }
}

impl fmt::Display for CaseErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for CaseErrors {}

impl From<CaseError> for CaseErrors {
    fn from(e: CaseError) -> Self {
        CaseErrors(vec![e])
    }
}
