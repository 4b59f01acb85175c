//! umbra's runner: the backend registry, running and judging one case point, and the commands
//! of the `umbra` binary.
//!
//! The registry holds the CPU reference and the GL backends (one Mesa driver per process);
//! wgpu joins it with its own crate, and per-run isolation, expectations, goldens and the full
//! report set come with the conformance runner.

pub mod args;
pub mod bisect;
pub mod child;
pub mod conformance;
pub mod drivers;
pub mod error_curves;
pub mod fake;
pub mod glob;
pub mod golden;
pub mod html;
pub mod judge_cache;
pub mod measure;
pub mod memory_limit;
pub mod mesa_build;
pub mod pareto_plot;
pub mod pool;
pub mod progress;
pub mod reduce;
pub mod registry;
pub mod render_cmd;
pub mod run;
pub mod selftest;
pub mod status;
pub mod sweep;
pub mod worker;
