//! The shared flag groups resolved into what a run needs, one way for every command (the
//! shape of deqp-runner's `TestConfiguration::from_cli`): clap has already refused a value
//! that is not a number, a duration or a size ([`super::values`]); here the defaults that
//! depend on the machine are filled in (the core count, a share of the memory available) and
//! what only the machine can refuse is refused, as a usage error of the command.

use std::time::Duration;

use super::{Execution, usage_error};
use crate::exit::Error;

/// How a command's runs execute: workers at once, each run's time limit, each worker's
/// memory budget.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Worker processes at once (`--jobs`, default: the core count).
    pub jobs: usize,
    /// Each run's time limit (`--timeout`, its default the command's declaration).
    pub timeout: Duration,
    /// Each worker's memory budget in bytes (`--max-memory`, `UMBRA_MAX_MEMORY`, default a
    /// share of the memory available).
    pub budget: u64,
}

impl Execution {
    /// `--jobs`, `--timeout` and `--max-memory` of `command` resolved, the budget selected for
    /// every worker this process starts: one reading for every command that runs workers
    /// (selftest once ran `--timeout 10s` silently with its default, and a budget below one
    /// run's base counted every fault as caught).
    pub fn resolve(&self, command: &str) -> Result<Limits, Error> {
        let jobs = self.jobs.map_or_else(
            || std::thread::available_parallelism().map_or(1, |n| n.get()),
            super::Jobs::get,
        );
        crate::harness::memory_limit::check_jobs(jobs).map_err(|e| usage_error(command, e))?;
        let budget = crate::harness::memory_limit::select(self.max_memory.map(|b| b.0), jobs)
            .map_err(|e| usage_error(command, e))?;
        if budget < umbra_case::memory::BASE_BYTES {
            return Err(usage_error(
                command,
                format!(
                    "the memory budget per worker, {}, is below one run's base ({}: a worker with its driver, before any case; umbra_case::memory::BASE_BYTES); give --max-memory 1GiB or more, or fewer --jobs",
                    umbra_case::memory::gib(budget),
                    umbra_case::memory::gib(umbra_case::memory::BASE_BYTES)
                ),
            ));
        }
        Ok(Limits {
            jobs,
            timeout: self.timeout.duration(),
            budget,
        })
    }
}
