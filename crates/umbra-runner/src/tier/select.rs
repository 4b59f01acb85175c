//! Choosing a tier: a greedy cover of the catch matrix, cheapest catch first, within a
//! budget; and the random draw of equal time it is measured against.
//!
//! The problem is weighted set cover (each run covers the fault × backend pairs its point
//! caught, at the cost of its recorded duration), NP-hard in general; the greedy choice
//! (most newly covered pairs per second, ties to the cheaper run, then by name) is within a
//! logarithmic factor of the best cover and is deterministic, so the same inputs give the
//! same tier. Rounds: every pair caught once, then twice, then three times (the self-test's
//! own floor, `selftest::MIN_POINTS`), and on while known catches remain, each round only
//! while the budget lasts; a run that would overrun the budget is passed over for cheaper
//! ones.

use std::collections::{BTreeMap, BTreeSet};

use super::{Catches, Tier};

/// The fixed part of a run's wall time: starting the workers and creating their contexts,
/// loading and planning the catalogue (seconds, measured on the 2-core CI machine kind).
pub const START_S: f64 = 5.0;

/// Where the inputs came from, for the tier's record.
pub struct Inputs<'a> {
    /// The self-test's catch matrix.
    pub catches: &'a Catches,
    /// Each run's recorded duration, seconds, by run name (`backend/Case@point`).
    pub durations: &'a BTreeMap<String, f64>,
    /// The catch matrix's `path (digest)`.
    pub catches_source: String,
    /// The durations' `path (digest)`.
    pub durations_source: String,
}

/// The pairs the catalogue catches (`fault on backend`), each with the runs that caught it
/// and exist in the durations (a run not timed is not in the catalogue being chosen from).
fn pairs(inputs: &Inputs) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for p in &inputs.catches.pairs {
        let runs: Vec<String> = p
            .caught
            .iter()
            .map(|point| format!("{}/{point}", p.backend))
            .filter(|r| inputs.durations.contains_key(r))
            .collect();
        if !runs.is_empty() {
            out.insert(format!("{} on {}", p.fault, p.backend), runs);
        }
    }
    out
}

fn wall(worker_s: f64, jobs: usize) -> f64 {
    worker_s / jobs.max(1) as f64 + START_S
}

/// The greedy rounds within `budget_s` of wall time: the chosen runs.
fn greedy(
    pairs: &BTreeMap<String, Vec<String>>,
    durations: &BTreeMap<String, f64>,
    budget_s: f64,
    jobs: usize,
    depth: usize,
) -> BTreeSet<String> {
    // Which pairs each run catches.
    let mut covers: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (pair, runs) in pairs {
        for r in runs {
            covers.entry(r.as_str()).or_default().push(pair.as_str());
        }
    }
    let mut chosen: BTreeSet<String> = BTreeSet::new();
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    let mut worker = 0.0;
    for round in 1..=depth {
        loop {
            // The run that raises the most pairs to this round's depth per second.
            let best = covers
                .iter()
                .filter(|(r, _)| !chosen.contains(**r))
                .filter_map(|(r, ps)| {
                    let gain = ps
                        .iter()
                        .filter(|p| count.get(**p).copied().unwrap_or(0) < round)
                        .count();
                    let cost = durations.get(*r).copied().unwrap_or(0.0).max(1e-3);
                    (gain > 0 && wall(worker + cost, jobs) <= budget_s).then_some((
                        *r,
                        gain as f64 / cost,
                        cost,
                    ))
                })
                .max_by(|a, b| {
                    a.1.total_cmp(&b.1)
                        .then(b.2.total_cmp(&a.2))
                        .then(b.0.cmp(a.0))
                });
            let Some((run, _, cost)) = best else { break };
            chosen.insert(run.to_string());
            worker += cost;
            for p in &covers[run] {
                *count.entry(p).or_insert(0) += 1;
            }
        }
    }
    chosen
}

/// The tier for `budget_s` of wall time on `jobs` workers, chosen by catches.
pub fn choose(inputs: &Inputs, budget_s: f64, jobs: usize) -> Tier {
    let pairs = pairs(inputs);
    let deepest = pairs.values().map(Vec::len).max().unwrap_or(0);
    let runs = greedy(&pairs, inputs.durations, budget_s, jobs, deepest);
    tier_of(inputs, &pairs, runs, budget_s, jobs, "by catches".into())
}

/// The expected wall time of the greedy cover of every pair, without a budget.
fn full_cover_wall(
    pairs: &BTreeMap<String, Vec<String>>,
    durations: &BTreeMap<String, f64>,
    jobs: usize,
) -> f64 {
    let worker: f64 = greedy(pairs, durations, f64::INFINITY, jobs, 1)
        .iter()
        .filter_map(|r| durations.get(r))
        .sum();
    wall(worker, jobs)
}

/// A random tier of the catalogue's runs, drawn with `seed`, as large as fits
/// `worker_s` of worker time: deqp-runner's `--fraction` (a shuffled list, every Nth)
/// sized to the same time, for comparison.
pub fn random(inputs: &Inputs, seed: u64, worker_s: f64, budget_s: f64, jobs: usize) -> Tier {
    let pairs = pairs(inputs);
    // Only the backends the catch matrix hunted on: the same catalogue the choice saw.
    let backends: BTreeSet<&str> = inputs
        .catches
        .pairs
        .iter()
        .map(|p| p.backend.as_str())
        .collect();
    let mut all: Vec<(&String, f64)> = inputs
        .durations
        .iter()
        .filter(|(r, _)| {
            r.split_once('/')
                .is_some_and(|_| backends.iter().any(|b| r.starts_with(&format!("{b}/"))))
        })
        .map(|(r, d)| (r, *d))
        .collect();
    // A shuffle of its own (splitmix64), so the draw is the same on every machine.
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    for i in (1..all.len()).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        all.swap(i, j);
    }
    let mut runs = BTreeSet::new();
    let mut spent = 0.0;
    for (r, d) in all {
        if spent + d <= worker_s {
            spent += d;
            runs.insert(r.clone());
        }
    }
    tier_of(
        inputs,
        &pairs,
        runs,
        budget_s,
        jobs,
        format!("random, seed {seed}"),
    )
}

fn tier_of(
    inputs: &Inputs,
    pairs: &BTreeMap<String, Vec<String>>,
    runs: BTreeSet<String>,
    budget_s: f64,
    jobs: usize,
    chosen: String,
) -> Tier {
    let full_cover_wall_s = full_cover_wall(pairs, inputs.durations, jobs);
    let worker: f64 = runs.iter().filter_map(|r| inputs.durations.get(r)).sum();
    let mut covered = [0; 3];
    let mut uncovered = Vec::new();
    for (pair, catchers) in pairs {
        let n = catchers.iter().filter(|r| runs.contains(*r)).count();
        for (k, c) in covered.iter_mut().enumerate() {
            if n > k {
                *c += 1;
            }
        }
        if n == 0 {
            uncovered.push(pair.clone());
        }
    }
    Tier {
        chosen,
        budget_s,
        jobs,
        catches: inputs.catches_source.clone(),
        durations: inputs.durations_source.clone(),
        expected_worker_s: worker,
        expected_wall_s: wall(worker, jobs),
        pairs: pairs.len(),
        covered,
        uncovered,
        full_cover_wall_s,
        runs: runs.into_iter().collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tier::Pair;

    fn inputs_of<'a>(catches: &'a Catches, durations: &'a BTreeMap<String, f64>) -> Inputs<'a> {
        Inputs {
            catches,
            durations,
            catches_source: "c".into(),
            durations_source: "d".into(),
        }
    }

    fn pair(fault: &str, backend: &str, caught: &[&str]) -> Pair {
        Pair {
            fault: fault.into(),
            backend: backend.into(),
            exercising: 10,
            tried: 6,
            caught: caught.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// Three pairs on one backend: `cheap` catches two of them for 1 s, `slow` all three for
    /// 10 s, `mid` the third for 2 s. The cover is cheap + mid (3 s), not slow (10 s); a
    /// budget too small for both keeps the better ratio and names what it leaves.
    #[test]
    fn the_cover_takes_the_cheapest_catches_and_says_what_a_small_budget_leaves() {
        let catches = Catches {
            measured: "test".into(),
            pairs: vec![
                pair("f1", "b", &["cheap", "slow"]),
                pair("f2", "b", &["cheap", "slow"]),
                pair("f3", "b", &["slow", "mid"]),
                pair("f4", "b", &[]),
            ],
        };
        let durations: BTreeMap<String, f64> = [
            ("b/cheap", 1.0),
            ("b/slow", 10.0),
            ("b/mid", 2.0),
            ("b/idle", 4.0),
        ]
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect();
        let i = inputs_of(&catches, &durations);
        // Depth 1 only: budget for 3 s of work on one job.
        let t = choose(&i, START_S + 3.0, 1);
        assert_eq!(t.runs, ["b/cheap", "b/mid"]);
        assert_eq!((t.pairs, t.covered[0], t.uncovered.len()), (3, 3, 0));
        assert_eq!(t.full_cover_wall_s, START_S + 3.0);
        let small = choose(&i, START_S + 1.5, 1);
        assert_eq!(small.runs, ["b/cheap"]);
        assert_eq!(small.uncovered, ["f3 on b"]);
        // A larger budget deepens: slow catches every pair a second time.
        let deep = choose(&i, START_S + 20.0, 1);
        assert!(
            deep.runs.contains(&"b/slow".to_string()) && deep.covered[1] == 3,
            "{deep:?}"
        );
        // The same inputs, the same tier.
        assert_eq!(choose(&i, START_S + 3.0, 1), t);
        // A random tier of equal worker time is reproducible by its seed.
        let r = random(&i, 7, 3.0, START_S + 3.0, 1);
        assert!(r.expected_worker_s <= 3.0);
        assert_eq!(random(&i, 7, 3.0, START_S + 3.0, 1), r);
    }
}
