//! The one scheduler every command runs its requests through: requests in, results out.
//!
//! - [`Session`]: one backend's worker across many requests. It starts the worker (timing
//!   the start-up), keeps the first worker's hello (what the driver is, or why it cannot
//!   run), and restarts a worker that died or timed out before the next request, so a crash
//!   or a hang costs one run. [`Session::attempt`] turns a reply into an [`Attempt`] (a
//!   report's status, a crash with the worker's last stderr line, a timeout), and
//!   [`Session::attempt_or_rerun`] adds the rerun policy: a run that fails is run once more,
//!   alone on a fresh worker; a pass then makes a crash or a hang a flake, and a judged
//!   failure that followed another run [`Status::OrderDependent`] (a regression), with the
//!   failed attempt's evidence kept. Commands
//!   that read replies their own way (a sweep's timings, the self-test's catches, a
//!   reduction's verdicts) ask [`Session::reply`], which restarts the same way.
//! - [`run_pool`]: independent tasks (the self-test's fault × backend pairs) on `jobs`
//!   threads, each task opening its own sessions.
//! - [`run_queues`]: a plan's requests grouped by backend, `jobs` threads each working on
//!   one backend at a time in a session of its own, a thread that runs out joining the
//!   backend with the most runs left, no new run after an interrupt.
//!
//! The conformance run, deqp, the self-test, the sweep and reduce all use it; what a command
//! does with a result (expectations, catches, timings) stays the command's.

use std::collections::{BTreeMap, VecDeque};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use umbra_report::{Metrics, Status};

use crate::harness::pool::{Reply, Worker};
use crate::harness::worker::Hello;
use crate::judge::protocol::{Request, RunReport, RunVerdict};

/// Worker start-up (spawn to hello), summed over every session of this process, in µs.
static WORKER_START_US: AtomicU64 = AtomicU64::new(0);
/// Within it, context or device creation (the hello's `create_ms`), in µs.
static CONTEXT_US: AtomicU64 = AtomicU64::new(0);

/// The time every session's workers spent starting, and within it creating their contexts
/// or devices: part of the harness overhead a conformance run reports.
pub fn start_up_time() -> (Duration, Duration) {
    (
        Duration::from_micros(WORKER_START_US.load(Ordering::Relaxed)),
        Duration::from_micros(CONTEXT_US.load(Ordering::Relaxed)),
    )
}

/// One attempt at a run, as the worker's reply (or its death) left it.
#[derive(Debug)]
pub struct Attempt {
    /// Pass, Fail, Skip (with the reason), Crash or Timeout; Flake after a rerun.
    pub status: Status,
    /// Why, in one line; a failure ends with its signature (`[failed: value=12]`).
    pub reason: String,
    /// The run's figures, where it was judged.
    pub metrics: Option<Metrics>,
    /// The judge's details (`--verbose`).
    pub details: String,
    /// The checks it failed.
    pub failed: Vec<umbra_report::FailedCheck>,
    /// What happened to its golden.
    pub golden: Option<String>,
    /// Which pixels and texels failed, for the consensus across drivers.
    pub fingerprint: Option<umbra_compare::consensus::Fingerprint>,
    /// The checks still failed when judged under the deviation its expectation names.
    pub under_deviation: Option<Vec<umbra_report::FailedCheck>>,
    /// Pictures that could not be written.
    pub storage: Option<String>,
    /// What the worker wrote on stderr during the attempt ([`Worker::stderr`]).
    pub stderr: String,
}

impl Attempt {
    /// An attempt that never reached a worker, or whose worker died: a status and a reason.
    pub fn bare(status: Status, reason: String) -> Attempt {
        Attempt {
            status,
            reason,
            metrics: None,
            details: String::new(),
            failed: Vec::new(),
            golden: None,
            fingerprint: None,
            under_deviation: None,
            storage: None,
            stderr: String::new(),
        }
    }

    fn of_report(r: RunReport) -> Attempt {
        let status = match r.outcome {
            RunVerdict::Pass => Status::Pass,
            RunVerdict::Skip => Status::Skip(r.reason.clone()),
            RunVerdict::Fail => Status::Fail,
        };
        let mut reason = r.reason;
        if status == Status::Fail && !r.failed.is_empty() {
            let _ = write!(
                reason,
                " [failed: {}]",
                crate::judge::expectations::signature(&r.failed)
            );
        }
        Attempt {
            status,
            reason,
            metrics: r.metrics,
            details: r.details,
            failed: r.failed,
            golden: r.golden,
            fingerprint: r.fingerprint,
            under_deviation: r.under_deviation,
            storage: r.storage,
            stderr: String::new(),
        }
    }
}

/// The last stderr line of a worker that died, for its run's one-line reason (the whole tail
/// is the run's `stderr`).
fn last_words(stderr: &str) -> String {
    match stderr.lines().rev().find(|l| !l.trim().is_empty()) {
        Some(l) => format!("; its last stderr line: {}", l.trim()),
        None => String::new(),
    }
}

/// Why a session's backend cannot take requests ([`Session::ready`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NotReady {
    /// No worker process could be started (the harness's failure).
    NoWorker(String),
    /// The backend cannot run here (a missing driver or device): its runs are skips.
    Unavailable(String),
    /// Its worker refused the Mesa build asked for (`--mesa`).
    Refused(String),
}

/// One backend's worker across requests, restarted after a crash or a timeout.
pub struct Session {
    backend: String,
    env: Vec<(String, String)>,
    /// The per-request time limit (and the limit on a worker's start-up).
    limit: Duration,
    /// The `umbra` executable, where it is not this process's (benchmarks).
    exe: Option<PathBuf>,
    worker: Result<Worker, String>,
    /// The first worker's hello (Unavailable with the reason when it could not start).
    hello: Hello,
    /// Why the first worker could not be started at all.
    start_error: Option<String>,
    /// The request the current worker answered last, with its run's name: what state it
    /// holds may have come from ([`Session::attempt_or_rerun`]). None on a fresh worker.
    previous: Option<(Request, String)>,
}

impl Session {
    /// Starts `backend`'s worker with `env`; `limit` bounds its start-up and each request.
    pub fn start(backend: &str, env: &[(String, String)], limit: Duration) -> Session {
        Session::start_with(None, backend, env, limit)
    }

    /// [`Session::start`] with the `umbra` executable given (benchmarks, whose own
    /// executable is not `umbra`).
    pub fn start_exe(
        exe: &std::path::Path,
        backend: &str,
        env: &[(String, String)],
        limit: Duration,
    ) -> Session {
        Session::start_with(Some(exe.to_path_buf()), backend, env, limit)
    }

    fn start_with(
        exe: Option<PathBuf>,
        backend: &str,
        env: &[(String, String)],
        limit: Duration,
    ) -> Session {
        let mut s = Session {
            backend: backend.to_string(),
            env: env.to_vec(),
            limit,
            exe,
            worker: Err("not started".into()),
            hello: Hello::Unavailable("it has not said hello yet".into()),
            start_error: None,
            previous: None,
        };
        s.worker = s.spawn();
        match &s.worker {
            Ok(w) => s.hello = w.hello.clone(),
            Err(e) => {
                s.hello = Hello::Unavailable(e.clone());
                s.start_error = Some(e.clone());
            }
        }
        s
    }

    /// A fresh worker, its start-up timed.
    fn spawn(&self) -> Result<Worker, String> {
        let t = Instant::now();
        let w = match &self.exe {
            Some(exe) => Worker::start_exe(exe, &self.backend, &self.env, self.limit),
            None => Worker::start(&self.backend, &self.env, self.limit),
        };
        WORKER_START_US.fetch_add(t.elapsed().as_micros() as u64, Ordering::Relaxed);
        if let Some(ms) = w
            .as_ref()
            .ok()
            .and_then(|w| w.hello.ready().map(|r| r.create_ms))
        {
            CONTEXT_US.fetch_add((ms * 1e3) as u64, Ordering::Relaxed);
        }
        w
    }

    /// What the first worker said: its driver, or why the backend cannot run here.
    pub fn hello(&self) -> &Hello {
        &self.hello
    }

    /// Whether the backend can take requests, and if not, why: no worker could be started,
    /// the backend is unavailable here, or its worker refused the Mesa build. The one place
    /// these three are told apart, in this order.
    pub fn ready(&self) -> Result<(), NotReady> {
        if let Some(e) = &self.start_error {
            return Err(NotReady::NoWorker(e.clone()));
        }
        if let Some(why) = self.hello.unavailable() {
            return Err(NotReady::Unavailable(why.to_string()));
        }
        match self.hello.refused() {
            Some(why) => Err(NotReady::Refused(why.to_string())),
            None => Ok(()),
        }
    }

    /// Starts a fresh worker now if the last one died; `Err` when it does not come up. Where
    /// the first worker never started, the first that does gives the session its hello.
    pub fn restart(&mut self) -> Result<(), String> {
        if self.worker.is_err() {
            self.previous = None;
            self.worker = self.spawn();
            if let (Ok(w), Some(_)) = (&self.worker, &self.start_error) {
                self.hello = w.hello.clone();
                self.start_error = None;
            }
        }
        self.worker.as_ref().map(|_| ()).map_err(String::clone)
    }

    /// Sends `req` (restarting a dead worker first) and returns the reply; a worker that
    /// crashed or timed out is restarted before the next request. `Err`: no worker could be
    /// started for it.
    pub fn reply(&mut self, req: &Request) -> Result<(Reply, String), String> {
        self.restart()?;
        let w = self.worker.as_mut().map_err(|e| e.clone())?;
        let reply = w.run(req, self.limit);
        let stderr = w.stderr();
        match &reply {
            Reply::Crashed(how) => self.worker = Err(how.clone()),
            Reply::TimedOut => self.worker = Err("timed out".into()),
            Reply::OverBudget(why) => self.worker = Err(why.clone()),
            // A worker that retired after this run is a fresh one: nothing went before.
            Reply::Report(r) if r.retired.is_some() => self.previous = None,
            Reply::Report(_) => {}
        }
        Ok((reply, stderr))
    }

    /// Ends the current worker, so the next request starts a fresh one that has run nothing.
    fn retire(&mut self) {
        if self.worker.is_ok() {
            self.worker = Err("retired for a run alone on a fresh worker".into());
        }
        self.previous = None;
    }

    /// One attempt at `req`: the report, or a crash (with the worker's last stderr line) or a
    /// timeout, each costing this run only.
    pub fn attempt(&mut self, req: &Request) -> Attempt {
        let (reply, stderr) = match self.reply(req) {
            Ok(r) => r,
            Err(e) => return Attempt::bare(Status::Crash, format!("no worker: {e}")),
        };
        let mut a = match reply {
            Reply::Report(r) => Attempt::of_report(*r),
            Reply::Crashed(how) => Attempt::bare(
                Status::Crash,
                format!("the worker died: {how}{}", last_words(&stderr)),
            ),
            Reply::TimedOut => Attempt::bare(
                Status::Timeout,
                format!(
                    "no answer within {} s; the worker was killed{}",
                    self.limit.as_secs(),
                    last_words(&stderr)
                ),
            ),
            // umbra's limit, with its figures: a skip that says whose it is, never the
            // driver's crash or a flake.
            Reply::OverBudget(why) => {
                let why = format!(
                    "umbra's memory budget stopped the run, not the driver: {why}; run it alone with a larger --max-memory to judge it"
                );
                Attempt::bare(Status::Skip(why.clone()), why)
            }
        };
        a.stderr = stderr;
        a
    }

    /// [`Session::attempt`] of run `name`, and once more if it failed, alone on a fresh
    /// worker (the failed attempt's evidence is kept either way):
    ///
    /// - a second failure keeps the first attempt;
    /// - a pass after a crash or a timeout (the worker's own nondeterminism) is a flake;
    /// - a pass after a judged failure on a worker where another run went before is
    ///   [`Status::OrderDependent`], naming that run: state it left changed the answer (a
    ///   rerun on the same worker right after once passed such a run as a flake). The two
    ///   are then run again in their order on another fresh worker, and the reason says
    ///   whether that reproduced the failure;
    /// - a pass after a judged failure on a worker that had run nothing before stays a
    ///   failure: the same request answered two ways with nothing before it.
    pub fn attempt_or_rerun(&mut self, req: &Request, name: &str) -> Attempt {
        let before = self.previous.take();
        let first = self.attempt(req);
        self.previous = Some((req.clone(), name.to_string()));
        if !first.status.is_failure() {
            return first;
        }
        self.retire();
        let second = self.attempt(req);
        self.previous = Some((req.clone(), name.to_string()));
        if second.status != Status::Pass {
            return first;
        }
        let how = format!("{}: {}", first.status, first.reason);
        let (status, reason) = match (&first.status, before) {
            (Status::Crash | Status::Timeout, _) => (
                Status::Flake,
                format!("failed first ({how}), passed on its rerun on a fresh worker"),
            ),
            (_, Some((prev, prev_name))) => {
                let replay = self.replay(&prev, req);
                (
                    Status::OrderDependent,
                    format!(
                        "failed after {prev_name} on the same worker ({how}) and passed alone on a fresh worker: state left by an earlier run changed its answer; {replay}"
                    ),
                )
            }
            (_, None) => (
                Status::Fail,
                format!(
                    "failed on a fresh worker ({how}), then passed on another: the same run answered two ways with nothing before it"
                ),
            ),
        };
        Attempt {
            status,
            reason,
            stderr: first.stderr,
            ..second
        }
    }

    /// `prev` then `req` on a fresh worker: whether the order alone reproduces `req`'s
    /// failure, in words for the reason.
    fn replay(&mut self, prev: &Request, req: &Request) -> String {
        self.retire();
        let _ = self.attempt(prev);
        let again = self.attempt(req);
        self.previous = Some((req.clone(), String::new()));
        if again.status.is_failure() {
            format!(
                "reproduced: run after it on a fresh worker, it failed again ({})",
                again.status
            )
        } else {
            "not reproduced by that run alone before it: an earlier run on the worker may have left the state".into()
        }
    }
}

/// The runs not started yet, per backend, and how many threads work on each backend.
///
/// A thread that runs out picks the backend with the most runs left that nobody works on;
/// when every backend with runs left is taken, it joins the one with the most (a second
/// worker of the same driver). So a slow driver's runs (softpipe's GLES 2 path is half the
/// catalogue's worker time) are shared at the end instead of keeping one core busy long
/// after the others are idle: the wall time comes within about one run of the worker time
/// over the job count.
struct Queues<T> {
    remaining: BTreeMap<String, VecDeque<T>>,
    busy: BTreeMap<String, usize>,
}

impl<T> Queues<T> {
    /// A backend to work on, and whether this is its first thread.
    fn pick(&mut self) -> Option<(String, bool)> {
        // Interrupted: no new run starts; those in flight finish.
        if crate::harness::interrupt::requested().is_some() {
            return None;
        }
        let left = |b: &String| self.remaining.get(b).map_or(0, VecDeque::len);
        let busy = |b: &String| self.busy.get(b).copied().unwrap_or(0);
        let free = self
            .remaining
            .keys()
            .filter(|b| left(b) > 0 && busy(b) == 0)
            .max_by_key(|b| left(b));
        // Joining a backend is worth a worker only if it has more runs left than workers on it.
        let backend = match free {
            Some(b) => b.clone(),
            None => self
                .remaining
                .keys()
                .filter(|b| left(b) > busy(b))
                .max_by_key(|b| left(b))?
                .clone(),
        };
        let first = !self.busy.contains_key(&backend);
        *self.busy.entry(backend.clone()).or_default() += 1;
        Some((backend, first))
    }

    /// The next run of `backend`, if any is left (none after an interrupt).
    fn next_run(&mut self, backend: &str) -> Option<T> {
        if crate::harness::interrupt::requested().is_some() {
            return None;
        }
        self.remaining.get_mut(backend)?.pop_front()
    }

    fn release(&mut self, backend: &str) {
        if let Some(n) = self.busy.get_mut(backend) {
            *n = n.saturating_sub(1);
        }
    }
}

/// Runs `groups` (each backend's runs, in order) on `jobs` threads: each thread takes a
/// backend ([`Queues`]) and calls `work(backend, first, next)`, where `first` says it is the
/// backend's first thread and `next` hands out the backend's runs one by one until none is
/// left (or an interrupt was asked for). `work` opens its own [`Session`].
pub fn run_queues<T: Send>(
    groups: BTreeMap<String, VecDeque<T>>,
    jobs: usize,
    work: impl Fn(&str, bool, &dyn Fn() -> Option<T>) + Sync,
) {
    let queues = Mutex::new(Queues {
        remaining: groups,
        busy: BTreeMap::new(),
    });
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                // Pick a backend in a function of its own, so the lock is released before its
                // runs start (a `while let` on the lock would hold it throughout).
                let pick = || queues.lock().ok().and_then(|mut q| q.pick());
                while let Some((backend, first)) = pick() {
                    let next = || queues.lock().ok().and_then(|mut q| q.next_run(&backend));
                    work(&backend, first, &next);
                    if let Ok(mut q) = queues.lock() {
                        q.release(&backend);
                    }
                }
            });
        }
    });
}

/// Runs `work` on each of `items` on `jobs` threads, taking them from the end (the
/// self-test's fault × backend pairs, its thresholds' sweeps: each opens its own sessions);
/// the results in the order they finished.
pub fn run_pool<T: Send, R: Send>(
    items: Vec<T>,
    jobs: usize,
    work: impl Fn(T) -> R + Sync,
) -> Vec<R> {
    let queue = Mutex::new(items);
    let results = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                let next = || queue.lock().ok().and_then(|mut q| q.pop());
                while let Some(item) = next() {
                    let r = work(item);
                    if let Ok(mut rs) = results.lock() {
                        rs.push(r);
                    }
                }
            });
        }
    });
    results.into_inner().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thread_that_runs_out_joins_the_backend_with_the_most_left() {
        let mut groups = BTreeMap::new();
        groups.insert("a".to_string(), VecDeque::from([1, 2, 3, 4]));
        groups.insert("b".to_string(), VecDeque::from([5]));
        let mut q = Queues {
            remaining: groups,
            busy: BTreeMap::new(),
        };
        assert_eq!(q.pick(), Some(("a".into(), true)));
        assert_eq!(q.pick(), Some(("b".into(), true)));
        assert_eq!(q.next_run("b"), Some(5));
        q.release("b");
        // b is empty: the third thread joins a, which has more runs left than threads.
        assert_eq!(q.pick(), Some(("a".into(), false)));
        assert_eq!(q.next_run("a"), Some(1));
    }

    #[test]
    fn every_run_is_handed_out_once() {
        let mut groups = BTreeMap::new();
        for b in ["x", "y", "z"] {
            groups.insert(b.to_string(), (0..50).map(|i| (b, i)).collect());
        }
        let seen = Mutex::new(Vec::new());
        run_queues(groups, 4, |backend, _, next| {
            while let Some((b, i)) = next() {
                assert_eq!(b, backend);
                seen.lock().expect("lock").push((b, i));
            }
        });
        let mut seen = seen.into_inner().expect("lock");
        seen.sort();
        assert_eq!(seen.len(), 150);
        seen.dedup();
        assert_eq!(seen.len(), 150);
    }

    #[test]
    fn a_pool_runs_every_item_once() {
        let mut out = run_pool((0..40).collect(), 3, |i: u32| i * 2);
        out.sort();
        assert_eq!(out, (0..40).map(|i| i * 2).collect::<Vec<_>>());
    }
}
