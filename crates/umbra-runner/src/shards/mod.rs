//! Splitting a conformance run over CI jobs or machines and putting it back together: which
//! runs a shard takes ([`balance`]: by stride or by a previous run's durations), and what
//! each run leaves for `umbra merge` ([`record`]).

pub mod balance;
pub mod record;
