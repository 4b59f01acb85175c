//! `umbra reduce CASE.json --point ID --backend ID`: shrinks a failing case point to a
//! minimal case file for a bug report ([`crate::reduction`] says how), its progress on the
//! terminal. Exit 0 reduced, 1 the point does not fail as required, 125 could not run.

use crate::cli::ReduceArgs;
use crate::exit::{Exit, Outcome};

/// Runs the command; returns its outcome.
pub fn main(args: &ReduceArgs) -> Outcome {
    crate::reduction::reduce(args, &mut std::io::stdout()).map(|_| Exit::Pass)
}
