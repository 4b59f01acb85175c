//! Which shard takes which run (`--shard I/N`): by stride, every N-th planned run from I (as
//! deqp-runner's fractions split a caselist), or, with `--durations results.csv`, by the
//! durations a previous run measured: longest run first, each to the shard with the least
//! predicted time so far (ties to the lower index), which keeps the slowest shard within one
//! run of the average. The assignment depends only on the plan and the file, so N jobs given
//! the same two compute the same split, each keeping its own share; a run the file does not
//! time counts at the median of those it does.

use std::collections::HashMap;
use std::path::Path;

/// How the runs are split.
pub enum By {
    /// Every N-th run.
    Stride,
    /// By a previous run's durations.
    Durations(Durations),
}

impl By {
    /// How the split is recorded in each shard's record (`umbra merge` refuses shards split
    /// differently): `stride`, or `durations DIGEST` (the file's contents, wherever each job
    /// keeps it).
    pub fn describe(&self) -> String {
        match self {
            By::Stride => "stride".into(),
            By::Durations(d) => format!("durations {}", d.digest),
        }
    }
}

/// A previous run's durations: run name → seconds (results.csv's third column).
pub struct Durations {
    /// The file, as given.
    pub source: String,
    /// 64-bit FNV-1a of its bytes: every shard must read the same file.
    pub digest: String,
    times: HashMap<String, f64>,
}

impl Durations {
    /// Each run's recorded duration in seconds, by run name.
    pub fn times(&self) -> &HashMap<String, f64> {
        &self.times
    }

    /// Reads a results.csv (deqp-runner's `test,status,duration`, umbra's or deqp-runner's
    /// own). An error names the file and the line, and says what the file should be.
    pub fn read(path: &Path) -> Result<Durations, String> {
        let bytes = std::fs::read(path).map_err(|e| {
            format!(
                "--durations {}: {e}; give the results.csv of a previous run (OUT/latest/results.csv)",
                path.display()
            )
        })?;
        let text = String::from_utf8_lossy(&bytes);
        let rows = umbra_report::csv::parse_results(&text).map_err(|e| {
            format!(
                "--durations {}: {e}; it should be a results.csv (test,status,duration seconds per line)",
                path.display()
            )
        })?;
        Ok(Durations {
            source: path.display().to_string(),
            digest: format!(
                "{:016x}",
                crate::judge::basis_key::fnv(crate::judge::basis_key::FNV_START, &bytes)
            ),
            times: rows.into_iter().map(|(n, _, t)| (n, t)).collect(),
        })
    }

    /// Each run's predicted time, and how many the file timed: the median of the timed runs
    /// stands in for the others.
    fn predict(&self, names: &[String]) -> (Vec<f64>, usize) {
        let mut known: Vec<f64> = names
            .iter()
            .filter_map(|n| self.times.get(n).copied())
            .collect();
        let timed = known.len();
        known.sort_by(f64::total_cmp);
        let median = known.get(known.len() / 2).copied().unwrap_or(1.0);
        (
            names
                .iter()
                .map(|n| self.times.get(n).copied().unwrap_or(median))
                .collect(),
            timed,
        )
    }
}

/// The shard (0..count) of each of `names`, the whole plan in order.
pub fn assign(names: &[String], count: usize, by: &By) -> Vec<usize> {
    match by {
        By::Stride => (0..names.len()).map(|i| i % count).collect(),
        By::Durations(d) => {
            let (times, _) = d.predict(names);
            longest_first(&times, count)
        }
    }
}

/// Longest-processing-time-first: each run, longest first (ties in plan order), to the shard
/// with the least time so far (ties to the lower index).
fn longest_first(times: &[f64], count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[b].total_cmp(&times[a]).then(a.cmp(&b)));
    let mut load = vec![0.0f64; count];
    let mut shard = vec![0; times.len()];
    for i in order {
        let (k, _) = load
            .iter()
            .enumerate()
            .min_by(|(ka, a), (kb, b)| a.total_cmp(b).then(ka.cmp(kb)))
            .unwrap_or((0, &0.0));
        shard[i] = k;
        load[k] += times[i];
    }
    shard
}

/// Predicted time per shard of an assignment.
fn loads(times: &[f64], shards: &[usize], count: usize) -> Vec<f64> {
    let mut load = vec![0.0; count];
    for (t, &s) in times.iter().zip(shards) {
        load[s] += t;
    }
    load
}

/// Slowest over fastest (1.0 is perfect balance; infinite when a shard has nothing).
pub fn imbalance(loads: &[f64]) -> f64 {
    let max = loads.iter().copied().fold(0.0, f64::max);
    let min = loads.iter().copied().fold(f64::INFINITY, f64::min);
    if min > 0.0 { max / min } else { f64::INFINITY }
}

/// The line a shard split by durations prints: the prediction for every shard, its
/// imbalance, and the stride split's for comparison.
pub fn report(names: &[String], count: usize, durations: &Durations) -> String {
    let (times, timed) = durations.predict(names);
    let by_time = loads(&times, &longest_first(&times, count), count);
    let stride: Vec<usize> = (0..names.len()).map(|i| i % count).collect();
    let by_stride = loads(&times, &stride, count);
    let list = |l: &[f64]| {
        l.iter()
            .map(|x| format!("{x:.1}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "balance: by the durations in {} ({timed} of {} planned runs timed there, the rest at their median): predicted run time per shard {} s, slowest/fastest {:.3}; split by stride it would be {} s, {:.3}",
        durations.source,
        names.len(),
        list(&by_time),
        imbalance(&by_time),
        list(&by_stride),
        imbalance(&by_stride)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn longest_first_evens_out_what_a_stride_leaves_uneven() {
        // Every third run is slow: a stride of 3 puts them all in shard 0.
        let times: Vec<f64> = (0..30)
            .map(|i| if i % 3 == 0 { 10.0 } else { 1.0 })
            .collect();
        let stride: Vec<usize> = (0..30).map(|i| i % 3).collect();
        assert_eq!(loads(&times, &stride, 3), vec![100.0, 10.0, 10.0]);
        let split = longest_first(&times, 3);
        let l = loads(&times, &split, 3);
        assert!(imbalance(&l) < 1.1, "{l:?}");
        // Every run is in exactly one shard, and the split is the same every time.
        assert_eq!(split.len(), 30);
        assert_eq!(split, longest_first(&times, 3));
    }

    #[test]
    fn an_empty_shard_is_an_infinite_imbalance() {
        assert!(imbalance(&[1.0, 0.0]).is_infinite());
        assert_eq!(imbalance(&[2.0, 1.0]), 2.0);
    }
}
