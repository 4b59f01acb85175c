//! Judging glue: one point rendered and judged ([`run`]) against the shared judging basis
//! ([`judge_cache`], keyed by [`basis_key`]), its golden ([`golden`], the store's records in
//! [`blessings`]), its pictures ([`pictures`]), what a raw outcome becomes under the
//! checked-in expectations ([`expectations`]), and how a failing run compares with the other
//! drivers' runs of its point ([`consensus`]), and the check across one backend's runs of a
//! sweep ([`falls_along`]); the worker protocol's messages ([`protocol`]) and what a worker
//! answers each request with ([`answer`]: a point judged, measured for a sweep
//! ([`measure`]), or the card measured); and the backend's behaviour card ([`card`],
//! measured by [`card_probes`], read as a narrowing of the judge by [`calibration`], and as
//! conformance's card row by [`card_row`]). Depends on nothing else in the runner but the
//! glob matcher and the files written whole.

pub mod answer;
pub mod basis_key;
pub mod blessings;
pub mod calibration;
pub mod card;
pub mod card_probes;
pub mod card_row;
pub mod card_sampler_probes;
pub mod consensus;
pub mod expectations;
pub mod falls_along;
pub mod golden;
pub mod judge_cache;
pub mod measure;
pub mod pictures;
pub mod protocol;
pub mod run;
pub mod stages;
