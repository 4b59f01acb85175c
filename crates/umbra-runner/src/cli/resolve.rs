//! The shared flag groups resolved into what a run needs, one way for every command (the
//! shape of deqp-runner's `TestConfiguration::from_cli`): clap has already refused a value
//! that is not a number, a duration, a size or a backend name ([`super::values`]); here the
//! defaults that depend on the machine are filled in (the core count, a share of the memory
//! available) and what only the machine can refuse is refused: a device it lacks, a case
//! directory without cases, expectations that do not read ([`Selection::resolve`]), a
//! memory budget below one run ([`Execution::resolve`]).

use std::path::PathBuf;
use std::time::Duration;

use super::{Execution, Selection, usage_error};
use crate::exit::Error;
use crate::judge::expectations::Expectations;

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

/// What a run covers: the selection group resolved.
pub struct Selected {
    /// The backend ids, aliases expanded and every device id present on this machine.
    pub backends: Vec<String>,
    /// The case directory (`--cases`).
    pub cases: PathBuf,
    /// Its case files, sorted; never empty.
    pub files: Vec<PathBuf>,
    /// The glob over point ids and run names (`*` when none is given).
    pub filter: String,
    /// The expectations directory (`--expectations`) and what it holds.
    pub expectations_dir: PathBuf,
    /// The expectations, loaded and checked.
    pub expectations: Expectations,
}

impl Selection {
    /// The selection resolved on this machine, as every command that runs the catalogue reads
    /// it: the backends (`default` when none is named) with aliases expanded and devices
    /// checked ([`crate::harness::registry::selected`]), the case files, the filter, and the
    /// expectations loaded. Each error names the flag or the file and the fix.
    pub fn resolve(&self, default: Vec<String>) -> Result<Selected, Error> {
        let backends =
            crate::harness::registry::selected(&super::values::names(&self.backend), default)
                .map_err(Error::new)?;
        let expectations = Expectations::load(&self.expectations).map_err(Error::new)?;
        let files = match umbra_case::case_files(&self.cases) {
            Ok(f) if !f.is_empty() => f,
            Ok(_) => {
                return Err(Error::new(format!(
                    "no *.json case under {}",
                    self.cases.display()
                )));
            }
            Err(e) => {
                return Err(Error::new(format!(
                    "cannot read {}: {e}",
                    self.cases.display()
                )));
            }
        };
        Ok(Selected {
            backends,
            cases: self.cases.clone(),
            files,
            filter: self.filter.clone().unwrap_or_else(|| "*".into()),
            expectations_dir: self.expectations.clone(),
            expectations,
        })
    }
}
