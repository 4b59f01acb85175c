//! A worker's stderr, kept per run as its evidence (a driver's warnings; before a crash,
//! glibc's or the driver's last words) and shown on the terminal under the backend's name,
//! escaped for it.
//!
//! Lines are read as bytes (a driver may write anything: a line that is not UTF-8 is kept
//! lossily, and the pipe is drained to its end whatever comes, so a chatty worker never blocks
//! on a full pipe). The worker writes [`MARK`] on stderr before each answer on stdout, and the
//! parent waits (briefly) for it before it takes the run's lines: the last lines of a run are
//! its own, never the next run's.

use std::collections::VecDeque;
use std::io::BufRead as _;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// The most lines a run keeps (the last ones: a crash's messages come last).
pub const LINES: usize = 200;

/// What a worker writes on stderr after a run, before its answer.
pub const MARK: &str = "\u{1e}umbra: end of run\u{1e}";

#[derive(Default)]
struct State {
    lines: VecDeque<String>,
    marks: u64,
    closed: bool,
}

/// The stderr of one worker process.
pub struct StderrLog {
    state: Arc<(Mutex<State>, Condvar)>,
}

impl StderrLog {
    /// Reads `pipe` on a thread of its own until the worker closes it.
    pub fn spawn(pipe: std::process::ChildStderr, label: String) -> StderrLog {
        let state: Arc<(Mutex<State>, Condvar)> = Arc::default();
        let shared = Arc::clone(&state);
        std::thread::spawn(move || {
            let mut reader = std::io::BufReader::new(pipe);
            let mut buf = Vec::new();
            loop {
                buf.clear();
                match reader.read_until(b'\n', &mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {}
                }
                let line = String::from_utf8_lossy(&buf)
                    .trim_end_matches(['\n', '\r'])
                    .to_string();
                let (lock, seen) = &*shared;
                let Ok(mut s) = lock.lock() else { break };
                if line == MARK {
                    s.marks += 1;
                    seen.notify_all();
                    continue;
                }
                eprintln!(
                    "{}",
                    umbra_report::escape::term(&format!("{label}: {line}"))
                );
                if s.lines.len() == LINES {
                    s.lines.pop_front();
                }
                s.lines.push_back(line);
            }
            let (lock, seen) = &*shared;
            if let Ok(mut s) = lock.lock() {
                s.closed = true;
            }
            seen.notify_all();
        });
        StderrLog { state }
    }

    /// Starts a run: forgets the lines before it; returns the marks seen so far.
    pub fn begin(&self) -> u64 {
        let Ok(mut s) = self.state.0.lock() else {
            return 0;
        };
        s.lines.clear();
        s.marks
    }

    /// Waits, at most `limit`, until the worker's end-of-run mark after `marks` has been read
    /// (or its stderr closed).
    pub fn wait_mark(&self, marks: u64, limit: Duration) {
        self.wait(limit, |s| s.marks > marks || s.closed);
    }

    /// Waits, at most `limit`, until the worker's stderr is closed (it died).
    pub fn wait_closed(&self, limit: Duration) {
        self.wait(limit, |s| s.closed);
    }

    fn wait(&self, limit: Duration, done: impl Fn(&State) -> bool) {
        let until = Instant::now() + limit;
        let (lock, seen) = &*self.state;
        let Ok(mut s) = lock.lock() else { return };
        while !done(&s) {
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return;
            }
            match seen.wait_timeout(s, left) {
                Ok((next, _)) => s = next,
                Err(_) => return,
            }
        }
    }

    /// The run's lines so far, joined.
    pub fn text(&self) -> String {
        self.state
            .0
            .lock()
            .map(|s| s.lines.iter().cloned().collect::<Vec<_>>().join("\n"))
            .unwrap_or_default()
    }

    /// Puts `text`'s lines in place of what this log holds (a retired worker's run, carried
    /// over to its successor's log).
    pub fn set(&self, text: &str) {
        if let Ok(mut s) = self.state.0.lock() {
            s.lines = text.lines().map(str::to_string).collect();
        }
    }
}
