//! The `umbra` subcommands, one module each: each takes its parsed options (the command line is
//! parsed in `cli`) and calls into the harness, the judge and `umbra_report`.

pub mod backends;
pub mod bisect;
pub mod card;
pub mod card_selftest;
pub mod conformance;
pub mod deqp;
pub mod drivers;
pub mod merge;
pub mod orientations;
pub mod reduce;
pub mod render;
pub mod repro;
pub mod selftest;
pub mod selftest_modes;
pub mod soak;
pub mod sweep;
pub mod sweep_cascades;
pub mod sweep_matrix;
pub mod thresholds;
