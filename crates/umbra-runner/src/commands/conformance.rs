//! `umbra conformance`: the command over [`crate::conformance`], which plans, runs, judges
//! and reports (its module doc says how).

use crate::cli::ConformanceArgs;
use crate::exit::Outcome;

/// Runs the command; returns its outcome.
pub fn main(args: &ConformanceArgs) -> Outcome {
    crate::conformance::run(args).outcome
}
