//! umbra's runner: the backend registry, running and judging one case point, and the commands
//! of the `umbra` binary.
//!
//! For now the registry holds the CPU reference only; the GL and wgpu backends join it in
//! their own crates, and process isolation, expectations, goldens and the full report set come
//! with the conformance runner.

pub mod args;
pub mod conformance;
pub mod glob;
pub mod registry;
pub mod render_cmd;
pub mod run;
