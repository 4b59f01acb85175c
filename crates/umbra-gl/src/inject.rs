//! A real GL error, on purpose, for the runner's own tests of error containment: with
//! `UMBRA_FAKE_BACKENDS=1` (the switch of the fake backends, never set by a user's run) and
//! `UMBRA_INJECT_GL_ERROR=CASE`, the run of case CASE makes an invalid GL call while its shadow
//! pass's timer query is open, so the shadow pass fails with GL_INVALID_ENUM exactly as a
//! driver's own error would, through the same checks. The test then holds the runs after it on
//! the same worker to passing (issue 36: one error once became 143 failures).

use crate::record::Gl;

/// The variable naming the case whose shadow pass gets the error.
pub const VAR: &str = "UMBRA_INJECT_GL_ERROR";

/// Makes the invalid call if this run's case is the one named.
pub fn gl_error(gl: &Gl, case: &umbra_case::format::Case) {
    let armed = std::env::var("UMBRA_FAKE_BACKENDS").is_ok_and(|v| v == "1")
        && std::env::var(VAR).is_ok_and(|c| c == case.name);
    if armed {
        // SAFETY: an enum no GL accepts: GL_INVALID_ENUM, and no state change.
        unsafe { gl.enable(0xFFFF) };
    }
}
