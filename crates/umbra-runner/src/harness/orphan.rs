//! A worker dies with its parent. A worker blocked in a driver (a shader compiler's loop, a
//! GPU hang, `fake/hang`) never reads its input again, so it cannot learn from a closed pipe
//! that the run which started it was killed (SIGKILL, an OOM kill, a CI job cancelled): it
//! would keep a core or a GPU busy, reparented to PID 1, until someone noticed (issue 36:
//! four such workers after every CI run).
//!
//! A watchdog thread compares the worker's parent with the one that started it
//! (`UMBRA_PARENT_PID`, set by [`crate::harness::pool`], read before the first look so a
//! parent that died during the start is caught too) every [`POLL`], and ends the process
//! with `_exit` when they differ: no atexit handler runs, since a hung driver may hold the
//! locks one would wait on. Why not `PR_SET_PDEATHSIG`: it fires when the *thread* that
//! spawned the worker exits, and the parent's threads come and go while its workers live on.

#![allow(unsafe_code)] // _exit(2) through libc: the one block says why it holds.

use std::time::Duration;

/// The variable holding the parent's PID.
pub const ENV: &str = "UMBRA_PARENT_PID";

/// How often the watchdog looks.
pub const POLL: Duration = Duration::from_millis(100);

/// Starts the watchdog (a worker calls it first).
pub fn watch() {
    let parent = std::env::var(ENV)
        .ok()
        .and_then(|p| p.parse::<u32>().ok())
        .unwrap_or_else(std::os::unix::process::parent_id);
    let watchdog = move || {
        loop {
            if std::os::unix::process::parent_id() != parent {
                // SAFETY: ends this process at once; nothing of it is needed any more.
                unsafe { libc::_exit(137) };
            }
            std::thread::sleep(POLL);
        }
    };
    let _ = std::thread::Builder::new()
        .name("orphan-watchdog".into())
        .spawn(watchdog);
}
