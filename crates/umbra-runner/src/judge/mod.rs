//! Judging glue: one point rendered and judged ([`run`]) against the shared judging basis
//! ([`judge_cache`]), its golden ([`golden`]), its pictures ([`pictures`]), and what a raw outcome
//! becomes under the checked-in expectations ([`expectations`]). Depends on nothing else in the
//! runner but the glob matcher.

pub mod expectations;
pub mod golden;
pub mod judge_cache;
pub mod pictures;
pub mod run;
