//! `umbra selftest`'s three modes over one setup ([`super::selftest::setup`]): the hunt of
//! every fault on every backend (the default, `faults`), `thresholds` (the smallest error of
//! each parameter each backend's judge catches: [`super::thresholds`]) and `orientations`
//! (the face/orientation table: [`super::orientations`]). The modes live here, above the
//! three, so that none of them imports another's caller: the self-test and its thresholds
//! once imported each other.

use crate::cli::{SelftestArgs, SelftestMode};
use crate::exit::Outcome;

/// Runs `umbra selftest` in the mode asked for ([`SelftestArgs::mode`]); returns its outcome.
pub fn main(args: &SelftestArgs) -> Outcome {
    let setup = super::selftest::setup(args)?;
    match args.mode() {
        SelftestMode::Orientations => {
            let points: Vec<umbra_case::CasePoint> =
                setup.points.iter().map(|p| p.2.clone()).collect();
            super::orientations::main(&points)
        }
        SelftestMode::Thresholds => {
            let chosen = setup.chosen.then_some(&setup.backends[..]);
            super::thresholds::main(&setup.points, chosen, &setup.how(), setup.jobs)
        }
        SelftestMode::Faults => super::selftest::hunt_all(&setup),
        SelftestMode::Cards => super::card_selftest::main(&setup.backends, setup.how().timeout),
    }
}
