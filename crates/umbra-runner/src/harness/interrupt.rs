//! Interruption: `SIGINT` (Ctrl-C) or `SIGTERM` (a CI job cancelled) asks a run to stop.
//! The first signal only sets a flag: the scheduler hands out no new run, the runs in flight
//! finish (each is bounded by `--timeout`), and the run is left unpublished with its reason
//! (see [`crate::run_dir`]), its temporary files removed. A second signal ends the process
//! at once, with exit 130. Every other command ends at the first signal with 130
//! ([`exit_on_signal`]).
//!
//! `SIGXFSZ` is ignored from the start, so a file-size limit (`ulimit -f`) makes a write fail
//! with `EFBIG`, which umbra reports like a full disk, instead of killing the process mid-file.

#![allow(unsafe_code)] // signal(2) through libc: each block says why it holds.

use std::sync::atomic::{AtomicI32, Ordering};

static SIGNAL: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_signal(sig: libc::c_int) {
    if SIGNAL.swap(sig, Ordering::SeqCst) != 0 {
        // The second signal ends the process at once, as 130 (a death by the signal read
        // 143 for SIGTERM, outside umbra's four codes).
        on_signal_exit(sig);
    }
}

extern "C" fn on_signal_exit(_sig: libc::c_int) {
    // SAFETY: _exit(2) is async-signal-safe; nothing of this process is flushed or unwound.
    unsafe {
        libc::_exit(130);
    }
}

/// For a command that does not stop in order (everything but the runs of conformance and
/// soak, which [`install`] over this): SIGINT and SIGTERM end the process with exit 130,
/// umbra's interrupt, instead of a death by the signal (143 for SIGTERM).
pub fn exit_on_signal() {
    // SAFETY: `on_signal_exit` only calls `_exit`, which is async-signal-safe.
    unsafe {
        let handler = on_signal_exit as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
    }
}

/// Installs the handlers (once per process; commands that run many runs call it).
pub fn install() {
    // SAFETY: `on_signal` only stores to an atomic and calls `signal`, both
    // async-signal-safe; SIG_IGN for SIGXFSZ has no handler at all.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
        let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
    }
}

/// The signal that asked this process to stop, if one did.
pub fn requested() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// `SIGINT` or `SIGTERM`, by name.
pub fn name(sig: i32) -> &'static str {
    match sig {
        libc::SIGINT => "SIGINT",
        libc::SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}
