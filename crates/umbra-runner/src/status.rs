//! Run statuses and expectations, after Mesa's deqp-runner.
//!
//! [`Status`] is one exhaustive enum. A raw outcome (Pass, Fail, Crash, Timeout, Skip) meets
//! the checked-in expectations (`expectations/*.txt`) and becomes the final status: an
//! expected failure is `ExpectedFail`, an expected failure that passed is `UnexpectedPass`
//! (which fails the run until the baseline is updated, as in deqp-runner), and a failure that
//! passes on its rerun is `Flake`.
//!
//! Expectation files hold one line per pattern: `GLOB,STATUS,REASON`, where GLOB matches the
//! full run name (`backend/case@sweep`), STATUS is `Fail`, `Crash`, `Timeout` or `Skip`, and
//! REASON is required (a baseline without a reason is an error). `#` starts a comment.

use std::fmt;
use std::path::Path;

use serde::Serialize;

/// The status of one run.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "status", content = "reason")]
pub enum Status {
    /// Rendered and judged as expected.
    Pass,
    /// Rendered and judged wrong, or the backend reported an error.
    Fail,
    /// The worker died during the run.
    Crash,
    /// The run did not finish within the per-run time limit.
    Timeout,
    /// The backend cannot run it; the reason says why.
    Skip(String),
    /// Failed as an expectation says it will.
    ExpectedFail,
    /// Passed although an expectation says it fails: update the baseline.
    UnexpectedPass,
    /// Failed, then passed on its rerun.
    Flake,
}

impl Status {
    /// The name deqp-runner's CSV uses.
    pub fn name(&self) -> &'static str {
        match self {
            Status::Pass => "Pass",
            Status::Fail => "Fail",
            Status::Crash => "Crash",
            Status::Timeout => "Timeout",
            Status::Skip(_) => "Skip",
            Status::ExpectedFail => "ExpectedFail",
            Status::UnexpectedPass => "UnexpectedPass",
            Status::Flake => "Flake",
        }
    }

    /// Whether the status makes the run a regression (exit code 1).
    pub fn is_regression(&self) -> bool {
        matches!(
            self,
            Status::Fail | Status::Crash | Status::Timeout | Status::UnexpectedPass
        )
    }

    /// Whether the raw outcome is a failure of some kind (worth a rerun).
    pub fn is_failure(&self) -> bool {
        matches!(self, Status::Fail | Status::Crash | Status::Timeout)
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One expectation line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expectation {
    /// Glob over the run name.
    pub pattern: String,
    /// Expected raw status: Fail, Crash, Timeout or Skip.
    pub status: String,
    /// Why.
    pub reason: String,
    /// `file:line`, for messages.
    pub source: String,
}

/// Every expectation of a directory, in file and line order.
#[derive(Clone, Debug, Default)]
pub struct Expectations(pub Vec<Expectation>);

impl Expectations {
    /// Reads `dir/*.txt` (a missing directory means no expectations).
    pub fn load(dir: &Path) -> Result<Expectations, String> {
        let mut files: Vec<_> = match std::fs::read_dir(dir) {
            Ok(rd) => rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "txt"))
                .collect(),
            Err(_) => return Ok(Expectations::default()),
        };
        files.sort();
        let mut out = Vec::new();
        for f in files {
            let text = std::fs::read_to_string(&f).map_err(|e| format!("{}: {e}", f.display()))?;
            for (n, line) in text.lines().enumerate() {
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                let source = format!("{}:{}", f.display(), n + 1);
                let mut parts = line.splitn(3, ',');
                let (pattern, status, reason) = (
                    parts.next().unwrap_or("").trim(),
                    parts.next().unwrap_or("").trim(),
                    parts.next().unwrap_or("").trim(),
                );
                if !matches!(status, "Fail" | "Crash" | "Timeout" | "Skip") {
                    return Err(format!(
                        "{source}: status {status:?} is not one of Fail, Crash, Timeout, Skip; write GLOB,STATUS,REASON"
                    ));
                }
                if reason.is_empty() || pattern.is_empty() {
                    return Err(format!(
                        "{source}: every expectation needs a pattern and a reason; write GLOB,STATUS,REASON"
                    ));
                }
                out.push(Expectation {
                    pattern: pattern.into(),
                    status: status.into(),
                    reason: reason.into(),
                    source,
                });
            }
        }
        Ok(Expectations(out))
    }

    /// The first expectation whose pattern matches `name`.
    pub fn find(&self, name: &str) -> Option<&Expectation> {
        self.0
            .iter()
            .find(|e| crate::glob::matches(&e.pattern, name))
    }

    /// The final status of a raw outcome for `name`.
    pub fn apply(&self, name: &str, raw: Status) -> (Status, Option<String>) {
        let Some(e) = self.find(name) else {
            return (raw, None);
        };
        let why = Some(format!("{} ({})", e.reason, e.source));
        match (&raw, e.status.as_str()) {
            (Status::Pass | Status::Flake, _) => (Status::UnexpectedPass, why),
            (Status::Fail, "Fail") | (Status::Crash, "Crash") | (Status::Timeout, "Timeout") => {
                (Status::ExpectedFail, why)
            }
            (Status::Skip(_), "Skip") => (raw, why),
            _ => (raw, why),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expectations_turn_failures_into_expected_ones_and_passes_into_unexpected() {
        let e = Expectations(vec![Expectation {
            pattern: "gles2/*/spot*".into(),
            status: "Fail".into(),
            reason: "driver bug 123".into(),
            source: "x.txt:1".into(),
        }]);
        assert_eq!(
            e.apply("gles2/zink/spot-20deg", Status::Fail).0,
            Status::ExpectedFail
        );
        assert_eq!(
            e.apply("gles2/zink/spot-20deg", Status::Pass).0,
            Status::UnexpectedPass
        );
        assert_eq!(
            e.apply("gles2/zink/spot-20deg", Status::Crash).0,
            Status::Crash
        );
        assert_eq!(
            e.apply("gl33/zink/spot-20deg", Status::Fail).0,
            Status::Fail
        );
        assert!(Status::UnexpectedPass.is_regression() && !Status::ExpectedFail.is_regression());
    }

    #[test]
    fn a_baseline_line_without_a_reason_is_refused() {
        let dir = std::env::temp_dir().join(format!("umbra-exp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("bad.txt"), "gl33/*,Fail,\n").expect("write");
        let err = Expectations::load(&dir).expect_err("no reason");
        assert!(
            err.contains("bad.txt:1") && err.contains("needs a pattern and a reason"),
            "{err}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
