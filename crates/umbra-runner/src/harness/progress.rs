//! Progress of a conformance run. At a desk (stdout a terminal, `CI` unset, `TERM` not
//! `dumb`) one status line rewrites itself, with a bar, the running tally and an ETA, and
//! only runs that need a look (anything but a pass, an expected failure or a skip) stay on
//! screen. Elsewhere (CI logs, pipes, files) every run gets its own plain line, as before,
//! so logs stay greppable and diffable.

use std::io::{IsTerminal, Write};
use std::time::Instant;

/// The running state of a run's progress display.
#[derive(Debug)]
pub struct Progress {
    live: bool,
    started: Instant,
    total: usize,
    done: usize,
    pass: usize,
    fail: usize,
    skip: usize,
}

impl Default for Progress {
    fn default() -> Progress {
        Progress::new(0)
    }
}

/// Whether this process talks to a person: stdout is a terminal, not under CI, and the
/// terminal can move the cursor.
pub fn interactive() -> bool {
    std::io::stdout().is_terminal()
        && std::env::var_os("CI").is_none()
        && std::env::var("TERM").map_or(true, |t| t != "dumb")
}

impl Progress {
    /// Progress over `total` runs, live when [`interactive`].
    pub fn new(total: usize) -> Progress {
        Progress {
            live: interactive(),
            started: Instant::now(),
            total,
            done: 0,
            pass: 0,
            fail: 0,
            skip: 0,
        }
    }

    /// One run finished with `status` (its name: `Pass`, `Fail`, ...); `line` is its plain
    /// line (`[k/N] Status name (ms): reason`).
    pub fn finished(&mut self, status: &str, line: &str) {
        self.done += 1;
        // The line carries a case's name and a driver's or an error's text: no control
        // character of theirs reaches the terminal.
        let line = umbra_report::escape::term(line);
        let quiet = match status {
            "Pass" | "ExpectedFail" | "Flake" => {
                self.pass += 1;
                true
            }
            "Skip" => {
                self.skip += 1;
                true
            }
            _ => {
                self.fail += 1;
                false
            }
        };
        let mut out = std::io::stdout().lock();
        if !self.live {
            let _ = writeln!(out, "{line}");
            return;
        }
        // Clear the status line, keep what needs a look, redraw the status line.
        let _ = write!(out, "\r\x1b[2K");
        if !quiet {
            let _ = writeln!(out, "{line}");
        }
        let _ = write!(out, "{}", self.status_line());
        let _ = out.flush();
    }

    /// Clears the status line (live) before the summary is printed.
    pub fn close(&self) {
        if self.live {
            let mut out = std::io::stdout().lock();
            let _ = write!(out, "\r\x1b[2K");
            let _ = out.flush();
        }
    }

    /// `[k/N] ########------ pass P fail F skip S · 1m02s, ETA 0m41s`.
    pub fn status_line(&self) -> String {
        self.status_line_at(self.started.elapsed().as_secs_f64())
    }

    /// [`Progress::status_line`] `elapsed` seconds after the start.
    fn status_line_at(&self, elapsed: f64) -> String {
        const WIDTH: usize = 24;
        let filled = (self.done * WIDTH).checked_div(self.total).unwrap_or(0);
        let eta = if self.done == 0 {
            f64::NAN
        } else {
            elapsed / self.done as f64 * (self.total - self.done.min(self.total)) as f64
        };
        format!(
            "[{}/{}] {}{} pass {} fail {} skip {} · {}, ETA {}",
            self.done,
            self.total,
            "#".repeat(filled),
            "-".repeat(WIDTH - filled.min(WIDTH)),
            self.pass,
            self.fail,
            self.skip,
            clock(elapsed),
            clock(eta)
        )
    }
}

fn clock(s: f64) -> String {
    if !s.is_finite() {
        return "?".into();
    }
    let s = s.round() as u64;
    format!("{}m{:02}s", s / 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_status_line_has_the_tally_and_an_eta() {
        let mut p = Progress::new(4);
        p.live = false;
        for s in ["Pass", "Fail", "Skip"] {
            p.finished(s, "");
        }
        // At a fixed time (the wall clock's would make the text depend on the machine's
        // speed): 3 runs in 30 s leave one, 10 s.
        let l = p.status_line_at(30.0);
        assert_eq!(
            l, "[3/4] ##################------ pass 1 fail 1 skip 1 · 0m30s, ETA 0m10s",
            "{l}"
        );
        assert!(
            Progress::new(2)
                .status_line_at(0.0)
                .ends_with("0m00s, ETA ?")
        );
    }
}
