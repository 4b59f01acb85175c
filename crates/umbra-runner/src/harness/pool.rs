//! The parent's side of the workers: one worker process per backend (with the driver's
//! environment), fed one run at a time; a per-run timeout; a dead or hung worker costs its
//! run (Crash or Timeout) and a fresh worker takes the rest; so does one whose resident
//! memory goes over the budget ([`crate::harness::memory_limit`]), whose run is umbra's limit
//! ([`Reply::OverBudget`]), not the driver's crash.

use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use crate::harness::stderr_log::StderrLog;
use crate::harness::worker::Hello;
use crate::judge::protocol::{Request, RunReport};

/// What a worker answered for one run.
pub enum Reply {
    /// A report.
    Report(Box<RunReport>),
    /// The worker died (the reason names the exit status).
    Crashed(String),
    /// No answer within the limit.
    TimedOut,
    /// Stopped by umbra's own memory budget ([`crate::harness::memory_limit::over`]: the
    /// figures): umbra's limit, not a finding about the driver, so never a crash.
    OverBudget(String),
}

/// A live worker.
pub struct Worker {
    child: Child,
    stdin: ChildStdin,
    lines: Receiver<String>,
    /// What the worker said when it started: its driver, or why it cannot run.
    pub hello: Hello,
    /// How it was started, to start a fresh one when it retires.
    start: (std::path::PathBuf, String, Vec<(String, String)>, Duration),
    /// Its stderr, kept per run ([`Worker::stderr`]).
    log: StderrLog,
    /// The marks its stderr had when the current run began.
    marks: u64,
    /// Why it cannot take another run (a fresh worker after a retirement did not come up).
    dead: Option<String>,
}

impl Worker {
    /// Starts `umbra worker --backend id` with `env`; waits up to `limit` for its hello.
    pub fn start(id: &str, env: &[(String, String)], limit: Duration) -> Result<Worker, String> {
        let exe = crate::harness::own_libc::self_exe()
            .map_err(|e| format!("cannot find this executable: {e}"))?;
        Worker::start_exe(&exe, id, env, limit)
    }

    /// Like [`Worker::start`], with the `umbra` executable given (benchmarks and tests, whose
    /// own executable is not `umbra`).
    pub fn start_exe(
        exe: &std::path::Path,
        id: &str,
        env: &[(String, String)],
        limit: Duration,
    ) -> Result<Worker, String> {
        let mut cmd = Command::new(exe);
        cmd.args(["worker", "--backend", id])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            // glibc's fatal messages ("malloc(): invalid next size") to stderr, not the tty.
            .env("LIBC_FATAL_STDERR_", "1");
        without_inherited_insta(&mut cmd);
        cmd.env(crate::harness::orphan::ENV, std::process::id().to_string());
        for v in crate::harness::registry::env_removed(id) {
            cmd.env_remove(v);
        }
        for (k, v) in env {
            cmd.env(k, v);
        }
        let mut child = cmd
            .spawn()
            .map_err(|e| format!("cannot start a worker: {e}"))?;
        let stdin = child.stdin.take().ok_or("worker has no stdin")?;
        let stdout = child.stdout.take().ok_or("worker has no stdout")?;
        let stderr_pipe = child.stderr.take().ok_or("worker has no stderr")?;
        let log = StderrLog::spawn(stderr_pipe, id.to_string());
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                // Only protocol lines are JSON objects; anything a library prints goes to stderr.
                if !line.starts_with('{') {
                    eprintln!("{line}");
                    continue;
                }
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let mut w = Worker {
            child,
            stdin,
            lines: rx,
            hello: Hello::Unavailable("it has not said hello yet".into()),
            start: (exe.to_path_buf(), id.to_string(), env.to_vec(), limit),
            log,
            marks: 0,
            dead: None,
        };
        match w.lines.recv_timeout(limit) {
            Ok(line) => {
                w.hello = serde_json::from_str(&line)
                    .map_err(|e| format!("worker said {line:?}: {e}"))?;
                Ok(w)
            }
            Err(_) => {
                let status = w.stop();
                Err(format!("the worker for {id} did not start ({status})"))
            }
        }
    }

    /// What the worker wrote on stderr during the last run ([`Worker::run`]); after a crash,
    /// everything up to its end.
    pub fn stderr(&mut self) -> String {
        if self.child.try_wait().is_ok_and(|s| s.is_some()) {
            // Dead: its stderr closes, and the reader reaches the end (bounded: a grandchild
            // holding the pipe open must not hang the run; its bytes are in the pipe already,
            // so the bound is only met by such a grandchild or by a reader thread stalled on a
            // loaded machine).
            self.log.wait_closed(Duration::from_secs(2));
        }
        self.log.text()
    }

    /// Runs one request.
    pub fn run(&mut self, req: &Request, limit: Duration) -> Reply {
        if let Some(why) = &self.dead {
            return Reply::Crashed(why.clone());
        }
        self.marks = self.log.begin();
        let line = serde_json::to_string(req).unwrap_or_default();
        if writeln!(self.stdin, "{line}")
            .and_then(|_| self.stdin.flush())
            .is_err()
        {
            return Reply::Crashed(self.stop());
        }
        // Wait in short ticks, watching the worker's resident memory against the budget.
        let deadline = Instant::now() + limit;
        let budget = crate::harness::memory_limit::budget();
        loop {
            let tick = crate::harness::memory_limit::POLL
                .min(deadline.saturating_duration_since(Instant::now()));
            match self.lines.recv_timeout(tick) {
                Ok(line) => {
                    return match serde_json::from_str::<RunReport>(&line) {
                        Ok(mut r) => {
                            // The run's last stderr lines are in before its answer is used.
                            // The worker wrote the mark before this answer: the wait ends as
                            // soon as the reader thread runs; the bound is for a stalled one.
                            self.log.wait_mark(self.marks, Duration::from_secs(10));
                            if let Some(why) = r.retired.clone() {
                                // The run's stderr is the retiring worker's: kept past the swap.
                                let said = self.log.text();
                                r.reason.push_str(&self.replace(&why));
                                self.log.set(&said);
                            }
                            Reply::Report(Box::new(r))
                        }
                        Err(e) => Reply::Crashed(format!("unreadable answer {line:?}: {e}")),
                    };
                }
                Err(RecvTimeoutError::Timeout) if Instant::now() >= deadline => {
                    self.stop();
                    return Reply::TimedOut;
                }
                Err(RecvTimeoutError::Timeout) => {
                    // Asked to stop (SIGINT, SIGTERM): the run in flight ends now, unpublished.
                    if crate::harness::interrupt::requested().is_some() {
                        let _ = self.child.kill();
                        let _ = self.child.wait();
                        return Reply::Crashed("interrupted".into());
                    }
                    if let Some(why) = crate::harness::memory_limit::over(self.child.id(), budget) {
                        let _ = self.child.kill();
                        let _ = self.child.wait();
                        return Reply::OverBudget(why);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => return Reply::Crashed(self.stop()),
            }
        }
    }

    /// Starts a fresh worker in place of one that retired (its backend could not be restored
    /// after a failed run); what to add to that run's details.
    fn replace(&mut self, why: &str) -> String {
        let (exe, id, env, limit) = self.start.clone();
        self.stop();
        match Worker::start_exe(&exe, &id, &env, limit) {
            Ok(fresh) if fresh.hello.ready().is_none() => {
                let said = format!(
                    "a fresh worker for {id} did not come up after a retirement: {:?}",
                    fresh.hello
                );
                self.dead = Some(said.clone());
                format!(
                    "; the worker could not restore its context after this run ({why}), and {said}"
                )
            }
            Ok(fresh) => {
                *self = fresh;
                format!(
                    "; the worker could not restore its context after this run ({why}): a fresh worker takes the next run"
                )
            }
            // The next run finds the old worker gone and reports it: a crash, with this reason.
            Err(e) => format!(
                "; the worker could not restore its context after this run ({why}), and a fresh one did not start: {e}"
            ),
        }
    }

    /// Kills the worker (if alive) and says how it ended.
    pub fn stop(&mut self) -> String {
        if let Ok(Some(status)) = self.child.try_wait() {
            return status.to_string();
        }
        // Give a dying worker a moment to be reaped, then kill it.
        std::thread::sleep(Duration::from_millis(50));
        if let Ok(Some(status)) = self.child.try_wait() {
            return status.to_string();
        }
        let _ = self.child.kill();
        self.child
            .wait()
            .map(|s| s.to_string())
            .unwrap_or_else(|e| e.to_string())
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Removes every inherited insta variable that steers it from `cmd`'s environment: goldens are written
/// only as umbra decides ([`crate::judge::golden::insta_env`]), whatever the shell or the CI
/// file set.
pub fn without_inherited_insta(cmd: &mut Command) {
    for (k, _) in std::env::vars_os() {
        if crate::judge::golden::controls_insta(&k.to_string_lossy()) {
            cmd.env_remove(k);
        }
    }
}
