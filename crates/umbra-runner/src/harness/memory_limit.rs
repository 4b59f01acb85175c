//! The memory budget of one run, and its enforcement, so that no case can take the machine
//! down (a runaway costs one run, reported as such).
//!
//! - **Budget**: `--max-memory SIZE` (or `UMBRA_MAX_MEMORY`), else half of the memory the
//!   kernel reports available (`MemAvailable`) shared by the workers that run at once.
//! - **Before rendering**: each run's need is estimated from its case
//!   ([`umbra_case::memory`]); a run that would not fit is refused with the fields to shrink
//!   (a failure of check `memory` in a conformance run, exit 125 from `umbra render`).
//! - **While rendering**: the parent polls each worker's resident memory (`VmRSS`) every
//!   100 ms and kills a worker that exceeds the budget: that run is a `Crash` whose reason
//!   gives the figures, and a fresh worker takes the rest. `umbra render`, which renders in
//!   its own process, watches itself the same way and exits 125.

use std::sync::OnceLock;
use std::time::Duration;

/// The environment variable that carries the budget to workers (and lets a user set it).
pub const ENV: &str = "UMBRA_MAX_MEMORY";

/// How often resident memory is polled.
pub const POLL: Duration = Duration::from_millis(100);

static BUDGET: OnceLock<u64> = OnceLock::new();

/// Sets this process's budget from `--max-memory` (bytes, as clap read it; else the
/// environment, else the default for `workers` at once). Returns it, or an error naming the
/// variable.
pub fn select(arg: Option<u64>, workers: usize) -> Result<u64, String> {
    let explicit = match arg {
        Some(a) => Some(a),
        None => match std::env::var(ENV) {
            Ok(v) => Some(umbra_case::memory::parse_size(&v).map_err(|e| format!("{ENV}: {e}"))?),
            Err(_) => None,
        },
    };
    let b = explicit.unwrap_or_else(|| default_budget(workers));
    Ok(*BUDGET.get_or_init(|| b))
}

/// Whether `jobs` workers at once fit this machine: each needs at least one run's base
/// ([`umbra_case::memory::BASE_BYTES`]: a process with its driver, before any case) of the
/// memory the kernel reports available. An error naming `--jobs` and the most that fit.
pub fn check_jobs(jobs: usize) -> Result<(), String> {
    let Some(avail) = available() else {
        return Ok(());
    };
    let base = umbra_case::memory::BASE_BYTES;
    let most = (avail / base).max(1);
    if jobs as u64 > most {
        return Err(format!(
            "--jobs {jobs}: {jobs} workers need at least {} ({} each before any case), and this machine has {} available; give --jobs {most} or fewer (default: the core count)",
            umbra_case::memory::gib(base.saturating_mul(jobs as u64)),
            umbra_case::memory::gib(base),
            umbra_case::memory::gib(avail)
        ));
    }
    Ok(())
}

/// This process's budget ([`select`]ed, else from the environment, else the default for one
/// worker).
pub fn budget() -> u64 {
    *BUDGET.get_or_init(|| {
        std::env::var(ENV)
            .ok()
            .and_then(|v| umbra_case::memory::parse_size(&v).ok())
            .unwrap_or_else(|| default_budget(1))
    })
}

/// `UMBRA_MAX_MEMORY` as every command reads it, checked once before any command runs: a
/// value that is not a size is refused (exit 125) rather than taken as the default by the
/// commands that read the budget without `--max-memory` (reduce, repro, card, deqp, workers).
pub fn check_env() -> Result<(), String> {
    match std::env::var(ENV) {
        Ok(v) => umbra_case::memory::parse_size(&v)
            .map(drop)
            .map_err(|e| format!("{ENV}: {e}; or unset it for the default")),
        Err(std::env::VarError::NotPresent) => Ok(()),
        Err(e) => Err(format!("{ENV}: {e}")),
    }
}

/// Half of the available memory, shared by `workers`; 4 GiB a worker where the kernel does
/// not say.
pub fn default_budget(workers: usize) -> u64 {
    available().map_or(4 << 30, |a| a / 2 / workers.max(1) as u64)
}

/// This process's peak resident memory so far (`VmHWM`), in bytes.
pub fn peak_self() -> Option<u64> {
    kib_field(
        &std::fs::read_to_string("/proc/self/status").ok()?,
        "VmHWM:",
    )
}

/// `MemAvailable` from /proc/meminfo, in bytes.
pub fn available() -> Option<u64> {
    kib_field(
        &std::fs::read_to_string("/proc/meminfo").ok()?,
        "MemAvailable:",
    )
}

/// The resident memory of process `pid`, in bytes.
pub fn resident(pid: u32) -> Option<u64> {
    kib_field(
        &std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?,
        "VmRSS:",
    )
}

fn kib_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// Why `pid` must be stopped, if its resident memory is over `budget`.
pub fn over(pid: u32, budget: u64) -> Option<String> {
    let rss = resident(pid)?;
    (rss > budget).then(|| {
        format!(
            "killed: its resident memory reached {}, over the memory budget of {} (--max-memory; the run's case estimate fitted, so the driver or umbra used more than the case predicts)",
            umbra_case::memory::gib(rss),
            umbra_case::memory::gib(budget)
        )
    })
}

/// Watches this process from a thread: ends it with exit 125 (could not run: umbra's own
/// limit, not a finding), the figures on stderr, if its resident memory goes over `budget`
/// (for commands that render in their own process). It once aborted, and the shell saw
/// 134, a code outside umbra's four.
pub fn watch_self(budget: u64) {
    let pid = std::process::id();
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(POLL);
            if let Some(why) = over(pid, budget) {
                eprintln!("error: stopped by umbra's memory budget: {why}");
                std::process::exit(i32::from(crate::exit::Exit::CouldNotRun.code()));
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_has_a_resident_size_and_the_machine_an_available_one() {
        let rss = resident(std::process::id()).expect("VmRSS");
        assert!(rss > 1 << 20, "{rss}");
        assert!(available().is_some_and(|a| a > 0));
        assert!(over(std::process::id(), u64::MAX).is_none());
        assert!(over(std::process::id(), 1).is_some_and(|w| w.contains("over the memory budget")));
    }
}
