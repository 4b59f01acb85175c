//! A case's `expect.error_falls_along`: runs of one backend that differ only in that axis,
//! in sweep order, whose error against the truth must not rise. The check reads several runs
//! at once, so it is made after the runs, over all of them: by `umbra conformance` over its
//! own runs, and by `umbra merge` again over every shard's (a shard alone may hold a point
//! without its predecessor).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use umbra_report::{Metrics, RunResult, Status};

/// One case's series, by the swept axis `path`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FallsAlong {
    /// The axis the error must not rise along.
    pub path: String,
    /// Per series (the other axes' values): the point ids in the axis's order.
    pub series: Vec<Vec<String>>,
}

impl FallsAlong {
    /// The series of one case file's points, when its case asks for the check.
    pub fn of(points: &[umbra_case::CasePoint]) -> Option<FallsAlong> {
        let path = points.first()?.case.expect.error_falls_along.clone()?;
        let mut series: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for p in points {
            let others: Vec<String> = p
                .values
                .iter()
                .filter(|(k, _)| *k != path)
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            series.entry(others.join(",")).or_default().push(p.id());
        }
        Some(FallsAlong {
            path,
            series: series.into_values().collect(),
        })
    }

    /// Fails every judged run whose error exceeds its predecessor's on the same backend.
    pub fn judge(&self, results: &mut [RunResult]) {
        let error = |m: &Metrics| m.false_shadow + m.false_light;
        let mut backends: Vec<String> = results.iter().map(|r| r.backend.clone()).collect();
        backends.sort();
        backends.dedup();
        for backend in &backends {
            for ids in &self.series {
                let mut previous: Option<(String, u64)> = None;
                for id in ids {
                    let Some(r) = results
                        .iter_mut()
                        .find(|r| &r.backend == backend && &r.case == id)
                    else {
                        continue;
                    };
                    let Some(e) = r.metrics.as_ref().map(error) else {
                        continue;
                    };
                    if let Some((prev_id, prev)) = &previous {
                        if e > *prev && !r.status.is_regression() {
                            r.status = Status::Fail;
                            r.failed.push(umbra_report::FailedCheck {
                                check: umbra_report::check::Check::FallsAlong,
                                count: 1,
                            });
                            r.reason = format!(
                                "expect.error_falls_along {}: the error against the truth rose to {e} px from {prev} px at {prev_id}",
                                self.path
                            );
                        }
                    }
                    previous = Some((id.clone(), e));
                }
            }
        }
    }
}
