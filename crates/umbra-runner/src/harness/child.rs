//! Re-running this binary with a driver's environment. Mesa picks its driver when EGL loads,
//! so `umbra render --backend gles3/softpipe` and every per-driver group of a conformance run
//! execute in a child process with `GALLIUM_DRIVER` (and friends) set. A driver that crashes
//! or hangs takes its child down, not the run.

use std::process::Command;

/// Runs this executable with `args` and the environment `env`; returns its exit code (125 if
/// it could not start or died from a signal).
pub fn rerun(args: &[String], env: &[(String, String)]) -> i32 {
    rerun_without(args, env, &[])
}

/// [`rerun`] for backend `id`: without the variables its processes must not inherit
/// ([`crate::harness::registry::env_removed`]).
pub fn rerun_for(id: &str, args: &[String], env: &[(String, String)]) -> i32 {
    rerun_without(args, env, crate::harness::registry::env_removed(id))
}

fn rerun_without(args: &[String], env: &[(String, String)], removed: &[&str]) -> i32 {
    let exe = match crate::harness::own_libc::self_exe() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: cannot find this executable to start a driver process: {e}");
            return 125;
        }
    };
    let mut cmd = Command::new(exe);
    cmd.args(args);
    crate::harness::pool::without_inherited_insta(&mut cmd);
    for v in removed {
        cmd.env_remove(v);
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    match cmd.status() {
        Ok(s) => s.code().unwrap_or_else(|| {
            eprintln!("error: the driver process died: {s}");
            125
        }),
        Err(e) => {
            eprintln!("error: cannot start a driver process: {e}");
            125
        }
    }
}
