//! `umbra selftest`'s three modes over one setup ([`super::selftest::setup`]): the hunt of
//! every fault on every backend (the default), `--thresholds` (the smallest error of each
//! parameter each backend's judge catches: [`super::thresholds`]) and `--orientations` (the
//! face/orientation table: [`super::orientations`]). The modes live here, above the three, so
//! that none of them imports another's caller: the self-test and its thresholds once imported
//! each other.

use crate::args::Args;

/// Runs `umbra selftest` in the mode its flags ask for; returns the exit code.
pub fn main(args: &Args) -> i32 {
    let setup = match super::selftest::setup(args) {
        Ok(s) => s,
        Err(code) => return code,
    };
    if args.has("orientations") {
        let points: Vec<umbra_case::CasePoint> = setup.points.iter().map(|p| p.2.clone()).collect();
        return super::orientations::main(&points);
    }
    if args.has("thresholds") {
        let chosen = setup.chosen.then_some(&setup.backends[..]);
        return super::thresholds::main(&setup.points, chosen, &setup.how(), setup.jobs);
    }
    super::selftest::hunt_all(&setup)
}
