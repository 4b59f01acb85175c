//! The consensus diagnosis of a conformance run ([`umbra_compare::consensus`]): each failing
//! run's fingerprint held against every other driver's run of the same case point judged
//! against the same intervals (the same effective profile). The reference is not a driver and
//! takes no part.
//!
//! - Every other driver fails the same way there: "suspected model error: N of N drivers
//!   agree", umbra's tolerance model is the first suspect.
//! - None does: "suspected driver deviation", the failing driver is.
//! - Some do: both are named.
//!
//! The diagnosis changes no status; it is shown under each regression in the terminal, in
//! report.json (`diagnosis`) and in report.html, and `umbra soak` counts the suspected model
//! errors apart.

use umbra_compare::consensus::{Answer, agree};
use umbra_report::{Diagnosis, RunResult, Status};

/// Sets `diagnosis` on every failing run that left a fingerprint and has a driver to compare
/// with.
pub fn diagnose(results: &mut [RunResult]) {
    let diagnoses: Vec<Option<Diagnosis>> = results
        .iter()
        .map(|a| {
            let fp = a.fingerprint.as_ref()?;
            let failing = a.status.is_regression() || a.status == Status::ExpectedFail;
            if !failing || a.backend == "ref" {
                return None;
            }
            let mut same = Vec::new();
            let mut legal = Vec::new();
            for b in results.iter().filter(|b| {
                b.case == a.case
                    && b.backend != a.backend
                    && b.backend != "ref"
                    && b.metrics
                        .as_ref()
                        .is_some_and(|m| m.judged_as == fp.profile)
            }) {
                let Some(m) = b.metrics.as_ref() else {
                    continue;
                };
                let map_checked = m.reference.as_ref().is_some_and(|r| r.map_checked > 0);
                let twins: Vec<&str> = m
                    .twins
                    .iter()
                    .filter(|t| t.skipped.is_none())
                    .map(|t| t.name.as_str())
                    .collect();
                match agree(fp, b.fingerprint.as_ref(), map_checked, &twins) {
                    Answer::Same => same.push(b.backend.clone()),
                    Answer::Legal => legal.push(b.backend.clone()),
                    Answer::NotComparable => {}
                }
            }
            let drivers = 1 + same.len() + legal.len();
            if drivers == 1 {
                return None;
            }
            let agree = 1 + same.len();
            let message = if legal.is_empty() {
                format!(
                    "suspected model error: {agree} of {drivers} drivers agree (every driver judged against these intervals fails the same way at these pixels: suspect umbra's tolerance model before the drivers)"
                )
            } else if same.is_empty() {
                format!(
                    "suspected driver deviation: 1 of {drivers} drivers fails this way; {} answer legally at these pixels",
                    legal.join(", ")
                )
            } else {
                format!(
                    "{agree} of {drivers} drivers fail this way ({}); {} answer legally at these pixels",
                    same.join(", "),
                    legal.join(", ")
                )
            };
            Some(Diagnosis {
                drivers,
                agree,
                disagree: legal,
                message,
            })
        })
        .collect();
    for (r, d) in results.iter_mut().zip(diagnoses) {
        r.diagnosis = d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use umbra_compare::consensus::{Failed, Fingerprint};
    use umbra_report::{Metrics, RunResult};

    fn run(backend: &str, status: Status, judged_as: &str, failed_at: &[usize]) -> RunResult {
        let fingerprint = (!failed_at.is_empty()).then(|| {
            let mut frame = Failed::default();
            for &i in failed_at {
                frame.push(i, true);
            }
            Fingerprint {
                profile: judged_as.into(),
                frame,
                ..Default::default()
            }
        });
        RunResult {
            name: format!("{backend}/c"),
            backend: backend.into(),
            case: "c".into(),
            file: "c.json".into(),
            values: Vec::new(),
            status,
            reason: String::new(),
            metrics: Some(Metrics {
                judged_as: judged_as.into(),
                ..Default::default()
            }),
            failed: Vec::new(),
            golden: None,
            time_s: 0.0,
            reproduce: String::new(),
            diagnosis: None,
            stderr: String::new(),
            fingerprint,
            details: String::new(),
        }
    }

    /// Every driver of the profile failing alike points at the model; one alone at itself;
    /// a driver of another profile (other intervals) and the reference take no part.
    #[test]
    fn consensus_names_who_fails_alike() {
        let mut all = vec![
            run("gl33/a", Status::Fail, "gl", &[4, 9]),
            run("gl33/b", Status::Fail, "gl", &[4, 9, 11]),
            run("ref", Status::Pass, "gl", &[]),
            run("gles2/a", Status::Pass, "gles2-packed", &[]),
        ];
        diagnose(&mut all);
        let d = all[0].diagnosis.clone().expect("diagnosed");
        assert!(d.suspect_model(), "{d:?}");
        assert_eq!((d.agree, d.drivers), (2, 2));
        assert!(
            d.message
                .starts_with("suspected model error: 2 of 2 drivers agree")
        );
        assert!(all[2].diagnosis.is_none() && all[3].diagnosis.is_none());

        let mut one = vec![
            run("gl33/a", Status::Fail, "gl", &[4, 9]),
            run("gl33/b", Status::Pass, "gl", &[]),
            run("gles3/b", Status::Pass, "gl", &[]),
        ];
        diagnose(&mut one);
        let d = one[0].diagnosis.clone().expect("diagnosed");
        assert!(!d.suspect_model());
        assert_eq!(d.disagree, ["gl33/b", "gles3/b"]);
        assert!(d.message.starts_with("suspected driver deviation: 1 of 3"));

        // Alone in its profile: nothing to compare with.
        let mut alone = vec![run("gl33/a", Status::Fail, "gl", &[4])];
        diagnose(&mut alone);
        assert!(alone[0].diagnosis.is_none());
    }
}
