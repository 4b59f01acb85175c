//! Pre-merge tiers: a subset of the catalogue's runs chosen for a time budget by what it
//! catches.
//!
//! Mesa's CI gives a job minutes and runs a fraction of a suite before merging
//! (deqp-runner's `--fraction N`: every Nth test of a shuffled list). A fraction drawn at
//! random throws away what umbra's self-test has measured: which case points catch which
//! wrong driver. A tier keeps it. Its inputs are recorded, so the choice is reproducible:
//!
//! - **The catch matrix** ([`Catches`], `umbra selftest --catches FILE`): for each fault ×
//!   backend pair, the case points that caught it.
//! - **Durations**: a full run's `results.csv` (deqp-runner's `test,status,duration`).
//!
//! [`select::choose`] then picks runs per backend so that every pair the catalogue catches is
//! caught by at least one chosen run, then by two, then three, cheapest catch first, until
//! the budget is spent ([`Tier`]: the runs, their expected time, the pairs covered and how
//! deep). `umbra tier` writes one; `umbra conformance --tier FILE` (or `--budget`) runs it
//! and keeps the file in its run directory; `umbra selftest --tier FILE` measures what it
//! catches. `--random SEED` draws a random tier of the same expected time, the fraction to
//! compare against.

pub mod select;

use std::collections::BTreeSet;
use std::path::Path;

use serde::{Deserialize, Serialize};

/// What the self-test saw of one fault on one backend.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Pair {
    /// The fault's name (`umbra selftest --fault` takes it).
    pub fault: String,
    /// The backend id.
    pub backend: String,
    /// How many case points exercise the fault on the backend.
    pub exercising: usize,
    /// How many the hunt ran (it stops after enough catch).
    pub tried: usize,
    /// The points that caught it (`Case@point` ids, as run names end).
    pub caught: Vec<String>,
}

/// The self-test's catch matrix, with what it was measured on.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Catches {
    /// The command and the Mesa it ran on, in words.
    pub measured: String,
    /// Every fault × backend pair hunted.
    pub pairs: Vec<Pair>,
}

impl Catches {
    /// Reads a catch matrix; the error names the file and the fix.
    pub fn read(path: &Path) -> Result<Catches, String> {
        read_json(
            path,
            "a catch matrix (`umbra selftest --catches FILE` writes one; tiers/catches.json is the recorded one)",
            "write it again with `umbra selftest --catches FILE`",
        )
    }
}

/// Refuses to replace `path` unless it is absent or already a file of this kind (`read`
/// takes it): umbra writes over only what it wrote (`--out tiers/catches.json` by mistake
/// must not destroy the matrix).
pub fn replaceable<T>(
    path: &Path,
    read: impl Fn(&Path) -> Result<T, String>,
    what: &str,
) -> Result<(), String> {
    if path.exists() && read(path).is_err() {
        return Err(format!(
            "{} exists and is not {what}: umbra replaces only a file it wrote; give another path",
            path.display()
        ));
    }
    Ok(())
}

/// A JSON file read into `T`; an error names the file, the field, and `what`/`fix`.
fn read_json<T: serde::de::DeserializeOwned>(
    path: &Path,
    what: &str,
    fix: &str,
) -> Result<T, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: {e}; give {what}", path.display()))?;
    let de = &mut serde_json::Deserializer::from_str(&text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        format!(
            "{}: field {}: {}; fix: {fix}",
            path.display(),
            e.path(),
            e.inner()
        )
    })
}

/// A chosen tier: the runs, what they are expected to cost and catch, and where the choice
/// came from (enough to make it again).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Tier {
    /// How it was chosen: `by catches` or `random, seed S`.
    pub chosen: String,
    /// The budget, in seconds of wall time.
    pub budget_s: f64,
    /// The worker processes the wall time assumes.
    pub jobs: usize,
    /// The catch matrix (path and FNV-1a digest of its bytes).
    pub catches: String,
    /// The durations (path and digest).
    pub durations: String,
    /// Expected worker time of the runs, seconds (their recorded durations).
    pub expected_worker_s: f64,
    /// Expected wall time: worker time over the jobs, plus the start ([`select::START_S`]).
    pub expected_wall_s: f64,
    /// The fault × backend pairs the catalogue catches.
    pub pairs: usize,
    /// How many of them a chosen run caught in the self-test, by at least 1, 2 and 3 runs.
    pub covered: [usize; 3],
    /// The pairs no chosen run caught (`fault on backend`).
    pub uncovered: Vec<String>,
    /// The smallest expected wall time that covers every pair (the greedy cover's).
    pub full_cover_wall_s: f64,
    /// The runs, `backend/Case@point`, sorted.
    pub runs: Vec<String>,
}

impl Tier {
    /// Reads a tier file; the error names the file and the fix.
    pub fn read(path: &Path) -> Result<Tier, String> {
        read_json(
            path,
            "a tier file (`umbra tier --budget DURATION` writes one)",
            "write it again with `umbra tier`",
        )
        .map_err(|e| format!("--tier {e}"))
    }

    /// Writes it as pretty JSON.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
        }
        let text = serde_json::to_string_pretty(self).unwrap_or_default();
        crate::atomic_file::write(path, text.as_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The runs as a set, for membership.
    pub fn run_set(&self) -> BTreeSet<&str> {
        self.runs.iter().map(String::as_str).collect()
    }

    /// The summary lines a command prints.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "tier ({}): {} runs, expected {:.0} s of wall time on {} jobs ({:.0} s of worker time) for a budget of {:.0} s\n\
             tier: fault × backend pairs caught by a chosen run in the self-test: {} of {} (by 2 runs: {}, by 3: {}); covering every pair needs {:.0} s\n",
            self.chosen,
            self.runs.len(),
            self.expected_wall_s,
            self.jobs,
            self.expected_worker_s,
            self.budget_s,
            self.covered[0],
            self.pairs,
            self.covered[1],
            self.covered[2],
            self.full_cover_wall_s,
        );
        if !self.uncovered.is_empty() {
            let shown: Vec<&str> = self.uncovered.iter().take(8).map(String::as_str).collect();
            s.push_str(&format!(
                "tier: not covered ({}): {}{}\n",
                self.uncovered.len(),
                shown.join(", "),
                if self.uncovered.len() > shown.len() {
                    ", …"
                } else {
                    ""
                }
            ));
        }
        s
    }
}

/// The recorded inputs (`tiers/` in the repository), the defaults of `--catches` and
/// `--durations`.
pub const CATCHES: &str = "tiers/catches.json";
/// See [`CATCHES`].
pub const DURATIONS: &str = "tiers/durations.csv";

/// A tier for `budget_s` from the catch matrix and durations in these files: chosen by
/// catches, or with `random` a random draw of the same expected worker time.
pub fn make(
    budget_s: f64,
    catches: &Path,
    durations: &Path,
    jobs: usize,
    random: Option<u64>,
) -> Result<Tier, String> {
    let c = Catches::read(catches)?;
    let d = crate::shards::balance::Durations::read(durations)?;
    let times: std::collections::BTreeMap<String, f64> =
        d.times().iter().map(|(n, t)| (n.clone(), *t)).collect();
    let catches_digest = format!(
        "{:016x}",
        crate::judge::basis_key::fnv(
            crate::judge::basis_key::FNV_START,
            &std::fs::read(catches).unwrap_or_default()
        )
    );
    let inputs = select::Inputs {
        catches: &c,
        durations: &times,
        catches_source: format!("{} ({catches_digest})", catches.display()),
        durations_source: format!("{} ({})", d.source, d.digest),
    };
    let by_catches = select::choose(&inputs, budget_s, jobs);
    Ok(match random {
        None => by_catches,
        Some(seed) => select::random(&inputs, seed, by_catches.expected_worker_s, budget_s, jobs),
    })
}

/// A budget: seconds (`300`), or with a unit (`90s`, `5m`, `1h`), or a named tier
/// (`premerge`: 5 minutes, the order of Mesa's pre-merge software-renderer jobs).
pub fn parse_budget(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let named = [("premerge", 300.0), ("smoke", 60.0)];
    if let Some((_, s)) = named.iter().find(|(n, _)| *n == t) {
        return Ok(*s);
    }
    let (num, unit) = match t.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&t[..i], &t[i..]),
        None => (t, "s"),
    };
    let scale = match unit {
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => {
            return Err(format!(
                "{text:?}: a budget is seconds, 90s, 5m, 1h, or premerge (5m) or smoke (1m)"
            ));
        }
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v * scale),
        _ => Err(format!(
            "{text:?}: a budget is a positive duration: 90s, 5m, 1h, premerge or smoke"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::parse_budget;

    #[test]
    fn budgets_take_units_and_names_and_refuse_the_rest() {
        assert_eq!(parse_budget("300"), Ok(300.0));
        assert_eq!(parse_budget("90s"), Ok(90.0));
        assert_eq!(parse_budget("5m"), Ok(300.0));
        assert_eq!(parse_budget("1h"), Ok(3600.0));
        assert_eq!(parse_budget("premerge"), Ok(300.0));
        assert_eq!(parse_budget("smoke"), Ok(60.0));
        for bad in ["", "0", "-5m", "5d", "fast", "nan"] {
            assert!(parse_budget(bad).is_err(), "{bad}");
        }
    }
}
