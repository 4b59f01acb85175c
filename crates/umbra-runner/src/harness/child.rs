//! Re-running this binary with a driver's environment. Mesa picks its driver when EGL loads,
//! so `umbra render --backend gles3/softpipe` and every per-driver group of a conformance run
//! execute in a child process with `GALLIUM_DRIVER` (and friends) set. A driver that crashes
//! or hangs takes its child down, not the run.

use std::process::Command;

use crate::exit::{Error, Exit, Outcome};

/// Runs this executable with `args` and the environment `env`; returns the child's exit
/// ([`Exit::of_code`]: its own errors are on stderr already), or an error when it could not
/// start or died from a signal.
pub fn rerun(args: &[String], env: &[(String, String)]) -> Outcome {
    rerun_without(args, env, &[])
}

/// [`rerun`] for backend `id`: without the variables its processes must not inherit
/// ([`crate::harness::registry::env_removed`]).
pub fn rerun_for(id: &str, args: &[String], env: &[(String, String)]) -> Outcome {
    rerun_without(args, env, crate::harness::registry::env_removed(id))
}

fn rerun_without(args: &[String], env: &[(String, String)], removed: &[&str]) -> Outcome {
    let exe = crate::harness::own_libc::self_exe().map_err(|e| {
        Error::new(format!(
            "cannot find this executable to start a driver process: {e}"
        ))
    })?;
    let mut cmd = Command::new(exe);
    cmd.args(args);
    crate::harness::pool::without_inherited_insta(&mut cmd);
    for v in removed {
        cmd.env_remove(v);
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    let status = cmd
        .status()
        .map_err(|e| Error::new(format!("cannot start a driver process: {e}")))?;
    match status.code() {
        Some(code) => Ok(Exit::of_code(code)),
        None => Err(Error::new(format!("the driver process died: {status}"))),
    }
}
