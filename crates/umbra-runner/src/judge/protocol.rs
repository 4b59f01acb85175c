//! The worker protocol's messages, one JSON object a line: the parent's [`Request`] (judge a
//! point, measure it for a sweep, or measure the backend's card) and the worker's
//! [`RunReport`]. A request carries its case point whole: the parent loads, validates and
//! expands each case file once, and the worker never reads one. The worker's hello is [`crate::harness::worker::Hello`]; what a request is
//! answered with is [`crate::judge::answer`].

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use umbra_case::CasePoint;
use umbra_report::Metrics;

/// What the parent asks a worker, one request a line. On the wire, `{"judge": {...}}`,
/// `{"measure": {...}}` or `"card"`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Request {
    /// Render one case point and judge it, as a conformance run does.
    Judge(JudgeRequest),
    /// Render one case point 1 + N times for `umbra sweep`: timings and error only (no
    /// reference, twins or goldens).
    Measure(MeasureRequest),
    /// Measure the backend's behaviour card: the probes of [`crate::judge::card_probes`],
    /// answered in [`RunReport::card`].
    Card,
}

/// A run to judge, and what to do with its judgement.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct JudgeRequest {
    /// The case point, as the parent loaded it (the worker reads no case file).
    pub point: CasePoint,
    /// Where to write the pictures of a failing run (none: do not write).
    pub failures: Option<PathBuf>,
    /// The golden directory (none: no golden check).
    pub golden: Option<PathBuf>,
    /// Skip the metamorphic twins (the self-test and the reducer judge the frame alone).
    #[serde(default)]
    pub no_twins: bool,
    /// Where to write every judged run's gallery pictures (thumbnail, colour, heat map,
    /// reference, truth, golden; none: do not write).
    #[serde(default)]
    pub gallery: Option<PathBuf>,
    /// Modelled driver deviations ([`umbra_case::Deviation`] names joined by `+`): a failing
    /// run is judged again with them allowed, and the checks that still fail are reported
    /// ([`RunReport::under_deviation`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deviation: Option<String>,
    /// The backend's card read as a narrowing ([`umbra_case::Calibration::encode`]): the run
    /// is judged a second time against it (calibrated judging); none: by the spec alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<String>,
}

impl JudgeRequest {
    /// A request to judge `point` and do nothing else with it: no pictures, no golden, no
    /// deviation or calibration (twins as `no_twins` says).
    pub fn bare(point: CasePoint, no_twins: bool) -> JudgeRequest {
        JudgeRequest {
            point,
            failures: None,
            golden: None,
            no_twins,
            gallery: None,
            deviation: None,
            calibration: None,
        }
    }
}

/// A sweep's measurement of one point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MeasureRequest {
    /// The case point, as the parent loaded it.
    pub point: CasePoint,
    /// Timed renders after one warm-up.
    pub repeat: u32,
}

/// A run's raw verdict, before expectations (the parent's business).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunVerdict {
    /// Every check held.
    Pass,
    /// A check failed, or the run could not be made (the reason says which).
    #[default]
    Fail,
    /// The backend cannot run this case (the reason says why).
    Skip,
}

impl std::fmt::Display for RunVerdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RunVerdict::Pass => "pass",
            RunVerdict::Fail => "fail",
            RunVerdict::Skip => "skip",
        })
    }
}

/// What one run produced (the raw outcome; expectations are the parent's business).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunReport {
    /// Pass, fail or skip (`"pass"`, `"fail"`, `"skip"` on the wire).
    pub outcome: RunVerdict,
    /// Why, for fail and skip.
    pub reason: String,
    /// The multi-line description of a judged run.
    pub details: String,
    /// Error figures and timings of a judged run.
    pub metrics: Option<Metrics>,
    /// `unchanged`, `written` or `changed` when a golden was checked.
    pub golden: Option<String>,
    /// A sweep measurement ([`Request::Measure`]).
    #[serde(default)]
    pub measured: Option<crate::judge::measure::Measured>,
    /// The checks a failing run failed, with their pixel counts (what expectations match).
    #[serde(default)]
    pub failed: Vec<umbra_report::FailedCheck>,
    /// Where a judged run broke the model, when it did anywhere (the consensus diagnosis
    /// compares it across drivers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fingerprint: Option<umbra_compare::consensus::Fingerprint>,
    /// For a failing run of a request with a deviation: the checks that still fail when it is
    /// judged with the deviation allowed (empty: the deviation explains the failure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub under_deviation: Option<Vec<umbra_report::FailedCheck>>,
    /// A picture of the run that could not be written (a full disk): the run's judgement
    /// stands, but its report would be incomplete, so the conformance run is not published.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub storage: Option<String>,
    /// Set when the run failed and the backend could not be returned to a fresh state
    /// ([`umbra_case::Backend::restore`]): why. The worker exits after this answer and the
    /// parent starts a fresh one for the next run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retired: Option<String>,
    /// The behaviour card ([`Request::Card`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub card: Option<crate::judge::card::Card>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point a worker is sent arrives as the parent loaded it: the catalogue's and a soak's
    /// generated points each cross the wire (a `Judge` request written and read back) equal to
    /// themselves, to the last bit of every float, so judging it in the worker is judging
    /// what was planned.
    #[test]
    fn a_point_crosses_the_wire_unchanged() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases");
        let mut points = Vec::new();
        for f in umbra_case::case_files(&root).expect("the catalogue") {
            points.extend(umbra_case::load_file(&f).expect("a catalogue case loads"));
        }
        let generated = umbra_case::generate::cases(21, 60);
        for (k, case) in generated.into_iter().enumerate() {
            let file = PathBuf::from(format!("soak-21-{k}.json"));
            let text = umbra_case::generate::to_json(&case);
            points.extend(umbra_case::load_str(&text, &file).expect("a generated case loads"));
        }
        assert!(points.len() > 300, "{} points", points.len());
        for point in points {
            let req = Request::Judge(JudgeRequest::bare(point.clone(), false));
            let line = serde_json::to_string(&req).expect("a request writes");
            let Request::Judge(back) = serde_json::from_str(&line).expect("a request reads") else {
                panic!("{line}: not a judge request");
            };
            assert_eq!(back.point, point, "{} changed on the wire", point.id());
        }
    }
}
