//! `umbra tier --budget DURATION`: chooses a pre-merge tier ([`crate::tier`]) from the
//! recorded catch matrix and durations, prints what it is expected to cost and catch, and
//! writes the tier file that `umbra conformance --tier` and `umbra selftest --tier` run.

use crate::cli::TierArgs;
use crate::exit::{Error, Exit, Outcome};

/// Runs `umbra tier`; returns its outcome.
pub fn main(args: &TierArgs) -> Outcome {
    let budget = crate::tier::parse_budget(&args.budget)
        .map_err(|e| crate::cli::usage_error("tier", format!("--budget {e}")))?;
    if args.jobs == 0 {
        return Err(crate::cli::usage_error("tier", "--jobs 0: give at least 1"));
    }
    crate::tier::replaceable(&args.out, crate::tier::Tier::read, "a tier file")
        .map_err(|e| crate::cli::usage_error("tier", format!("--out {e}")))?;
    let tier = crate::tier::make(
        budget,
        &args.catches,
        &args.durations,
        args.jobs,
        args.random,
    )
    .map_err(Error::new)?;
    print!("{}", tier.describe());
    tier.write(&args.out).map_err(Error::new)?;
    println!(
        "tier: written to {}; run it with `umbra conformance --tier {}`",
        args.out.display(),
        args.out.display()
    );
    Ok(Exit::Pass)
}
