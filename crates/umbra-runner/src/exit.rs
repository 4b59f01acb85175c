//! How a command ends: an [`Exit`] code, or an [`Error`] that carries its own.
//!
//! umbra's exit codes follow `git bisect run`'s: 0 as expected, 1 regressions (a fault
//! unseen, a first bad commit not found, a bisection step that fails), 125 could not run (a
//! bad command line or case, a missing driver, an unwritable directory), which `git bisect
//! run cargo xtask conformance …` reads as "skip this commit" rather than "bad"; 130 an
//! interrupt, as a shell reports one. Every command
//! returns an [`Outcome`]; `main` prints an error's message once, as `error: …`, and exits with
//! its code.

use std::fmt;

/// A command's exit status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// 0: every run as expected (a bisection step: good).
    Pass,
    /// 1: a regression, a fault the judge did not see (a bisection step: bad).
    Fail,
    /// 125: the command could not run (a bisection step: skip).
    CouldNotRun,
    /// 130: stopped by an interrupt (SIGINT or SIGTERM), the shell's 128 + 2; what was
    /// finished is written as a partial run.
    Interrupted,
}

impl Exit {
    /// The process exit code.
    pub const fn code(self) -> u8 {
        match self {
            Exit::Pass => 0,
            Exit::Fail => 1,
            Exit::CouldNotRun => 125,
            Exit::Interrupted => 130,
        }
    }

    /// [`Exit::Pass`] when `ok`, else [`Exit::Fail`].
    pub const fn pass_if(ok: bool) -> Exit {
        if ok { Exit::Pass } else { Exit::Fail }
    }

    /// The status of a child umbra that exited with `code` (an interrupt stays one;
    /// anything else but 0 and 1 could not run).
    pub const fn of_code(code: i32) -> Exit {
        match code {
            0 => Exit::Pass,
            1 => Exit::Fail,
            130 => Exit::Interrupted,
            _ => Exit::CouldNotRun,
        }
    }
}

/// Why a command stopped: what to print and the exit it carries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    exit: Exit,
    /// What to print after `error: ` (empty: already said on stderr, as a command that
    /// reported its own failures line by line).
    message: String,
}

impl Error {
    /// A set-up error: the command could not run (exit 125).
    pub fn new(message: impl Into<String>) -> Error {
        Error {
            exit: Exit::CouldNotRun,
            message: message.into(),
        }
    }

    /// An error with its own exit (a reduction whose point does not fail: [`Exit::Fail`]).
    pub fn with(exit: Exit, message: impl Into<String>) -> Error {
        Error {
            exit,
            message: message.into(),
        }
    }

    /// An error whose details the command has already written to stderr.
    pub fn said(exit: Exit) -> Error {
        Error {
            exit,
            message: String::new(),
        }
    }

    /// The exit it carries.
    pub fn exit(&self) -> Exit {
        self.exit
    }

    /// Prints `error: MESSAGE` on stderr (nothing when already said) and returns the exit.
    pub fn report(&self) -> Exit {
        if !self.message.is_empty() {
            eprintln!("error: {}", self.message);
        }
        self.exit
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

impl From<String> for Error {
    fn from(message: String) -> Error {
        Error::new(message)
    }
}

/// What every command returns.
pub type Outcome = Result<Exit, Error>;

/// The process exit code of an outcome, its error printed.
pub fn code(outcome: Outcome) -> u8 {
    match outcome {
        Ok(e) => e.code(),
        Err(e) => e.report().code(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_git_bisect_runs() {
        assert_eq!(
            [Exit::Pass, Exit::Fail, Exit::CouldNotRun].map(Exit::code),
            [0, 1, 125]
        );
        assert_eq!(Exit::of_code(3), Exit::CouldNotRun);
        assert_eq!(Exit::of_code(130), Exit::Interrupted);
        assert_eq!(Exit::of_code(101), Exit::CouldNotRun);
        assert_eq!(Error::new("x").exit(), Exit::CouldNotRun);
        assert_eq!(code(Err(Error::said(Exit::Fail))), 1);
    }
}
