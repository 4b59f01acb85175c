//! `junit.xml`: one `<testcase>` per run (class = backend, name = case point), regressions as
//! `<failure>` with the reproduce command, skips as `<skipped>` with their reason: what CI
//! viewers (GitLab, Jenkins, GitHub test reporters) show.

use std::fmt::Write as _;

use crate::escape::xml;
use crate::model::{RunResult, Status};

/// The document.
pub fn junit(results: &[RunResult]) -> String {
    let failures = results.iter().filter(|r| r.status.is_regression()).count();
    let skipped = results
        .iter()
        .filter(|r| matches!(r.status, Status::Skip(_)))
        .count();
    let time: f64 = results.iter().map(|r| r.time_s).sum();
    let mut s = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n<testsuite name=\"umbra conformance\" tests=\"{}\" failures=\"{failures}\" skipped=\"{skipped}\" time=\"{time:.3}\">\n",
        results.len()
    );
    for r in results {
        let _ = write!(
            s,
            "  <testcase classname=\"{}\" name=\"{}\" time=\"{:.3}\">",
            xml(&r.backend),
            xml(&r.case),
            r.time_s
        );
        match &r.status {
            st if st.is_regression() => {
                let _ = write!(
                    s,
                    "<failure type=\"{}\" message=\"{}\">{}</failure>",
                    xml(&st.to_string()),
                    xml(first_line(&r.reason)),
                    xml(&r.reproduce)
                );
            }
            Status::Skip(why) => {
                let _ = write!(s, "<skipped message=\"{}\"/>", xml(why));
            }
            _ => {}
        }
        // The worker's stderr of a run that did not pass: its evidence (a crash's last words).
        if !r.stderr.is_empty() {
            let _ = write!(s, "<system-err>{}</system-err>", xml(&r.stderr));
        }
        s.push_str("</testcase>\n");
    }
    s.push_str("</testsuite>\n</testsuites>\n");
    s
}

fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or("")
}
