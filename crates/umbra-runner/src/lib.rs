//! umbra's runner: the backend registry, running and judging one case point, and the commands
//! of the `umbra` binary.
//!
//! The registry holds the CPU reference and the GL backends (one Mesa driver per process);
//! wgpu joins it with its own crate, and per-run isolation, expectations, goldens and the full
//! report set come with the conformance runner.

pub mod atomic_file;
pub mod case_size;
pub mod cli;
pub mod commands;
pub mod conformance;
pub mod exit;
pub mod glob;
pub mod harness;
pub mod judge;
pub mod reduction;
pub mod repro;
pub mod run_dir;
pub mod shards;
pub mod tier;
pub mod version;
