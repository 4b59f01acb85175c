//! The `umbra` subcommands, one module each: each takes its parsed options (the command line is
//! parsed in `cli`) and calls into the harness, the judge and `umbra_report`.

pub mod backends;
pub mod bisect;
pub mod card;
pub mod conformance;
pub mod deqp;
pub mod drivers;
pub mod merge;
pub mod reduce;
pub mod render;
pub mod repro;
pub mod selftest;
pub mod soak;
pub mod sweep;
pub mod tier;
pub mod timing;
