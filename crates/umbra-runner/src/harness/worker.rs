//! `umbra worker --backend ID`: one backend in one process, fed runs on stdin.
//!
//! Protocol, one JSON object per line:
//! - worker → parent, once: a [`Hello`] (`{"ready": {...}}`, `{"unavailable": "reason"}` or
//!   `{"refused": "reason"}`);
//! - parent → worker: a [`Request`] (`{"judge": {"point": {"file": …, "case": {…},
//!   "values": […]}, …}}`, `{"measure": …}` or `"card"`): the case point whole, as the
//!   parent loaded it, so a worker reads no case file;
//! - worker → parent: a [`RunReport`].
//!
//! This file is the loop: hello, read, answer ([`crate::judge::answer`], where judging
//! lives), restore or retire. The context or device is created once and reused. The parent owns timeouts and crashes: a
//! worker that stops answering is killed, one that dies is noticed at end of input, and a
//! fresh worker takes the remaining runs.

use std::io::{BufRead, Write};
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::exit::Exit;
use crate::judge::protocol::{Request, RunReport, RunVerdict};

/// What a worker says once, when it has started: its driver, or why it cannot run. On the
/// wire, `{"ready": {...}}`, `{"unavailable": "why"}` or `{"refused": "why"}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hello {
    /// The backend came up on this driver.
    Ready(Ready),
    /// The backend cannot run here (a missing driver or device): its runs are skips.
    Unavailable(String),
    /// The `--mesa` build asked for lacks the driver, or it loaded from elsewhere: never a
    /// silent run on the system's Mesa.
    Refused(String),
}

/// The driver a ready worker runs on.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Ready {
    /// GL_VENDOR, or the adapter's vendor.
    pub vendor: String,
    /// GL_RENDERER, or the adapter's name.
    pub renderer: String,
    /// GL_VERSION, or the adapter's driver version.
    pub version: String,
    /// What the backend reports beside them (extensions, wgpu's driver notes).
    pub extensions: Vec<String>,
    /// The device and how it is reached.
    pub device: String,
    /// How long creating the context or device took, ms.
    pub create_ms: f64,
    /// The `--mesa` build it runs on, described.
    pub build: Option<String>,
    /// The Mesa libraries the process loaded.
    pub mesa_libs: Vec<PathBuf>,
}

impl Hello {
    /// The driver, when the worker is ready.
    pub fn ready(&self) -> Option<&Ready> {
        match self {
            Hello::Ready(r) => Some(r),
            _ => None,
        }
    }

    /// Why the backend cannot run here, when it cannot.
    pub fn unavailable(&self) -> Option<&str> {
        match self {
            Hello::Unavailable(why) => Some(why),
            _ => None,
        }
    }

    /// The driver's facts that select expectations (none where it did not come up).
    pub fn facts(&self) -> crate::judge::expectations::DriverFacts {
        self.ready().map_or_else(Default::default, |r| {
            crate::judge::expectations::DriverFacts::from_driver(
                &r.version,
                &r.renderer,
                &r.extensions,
            )
        })
    }

    /// Why the Mesa build was refused, when it was.
    pub fn refused(&self) -> Option<&str> {
        match self {
            Hello::Refused(why) => Some(why),
            _ => None,
        }
    }
}

/// Runs the worker loop; returns its outcome (it passes when the backend could not come up
/// too: the hello says so, and the parent reads it).
/// `id`: the backend it hosts (`umbra worker --backend ID`).
pub fn main(id: &str) -> crate::exit::Outcome {
    crate::harness::orphan::watch();
    // A fault in the driver (or here) names its address's mapping and the faulting library
    // on stderr before the signal ends the worker: the crash's reason says whose it is.
    crate::harness::crash_report::install();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    // A backend that cannot come up has said why in its hello; the worker is done.
    let Some(mut backend) = come_up(id, &mut out) else {
        return Ok(Exit::Pass);
    };
    for line in std::io::stdin().lock().lines() {
        let Ok(line) = line else { break };
        let mut report = match serde_json::from_str::<Request>(&line) {
            Ok(req) => crate::judge::answer::answer(
                backend.as_mut(),
                &req,
                crate::harness::memory_limit::budget(),
            ),
            Err(e) => RunReport {
                outcome: RunVerdict::Fail,
                reason: format!("bad request: {e}"),
                ..Default::default()
            },
        };
        // A failed run's errors stay in that run: the backend restores its state (GL errors
        // drained, queries ended, defaults bound), or this worker retires.
        if report.outcome == RunVerdict::Fail {
            report.retired = backend.restore().err();
        }
        // The end of this run's stderr, before its answer (the parent waits for it).
        eprintln!("{}", crate::harness::stderr_log::MARK);
        let _ = writeln!(
            out,
            "{}",
            serde_json::to_string(&report).unwrap_or_default()
        );
        let _ = out.flush();
        if report.retired.is_some() {
            break;
        }
    }
    Ok(Exit::Pass)
}

/// The worker's hello: the Mesa build checked (a backend its build lacks is unavailable, one
/// whose driver does not load, or loads from elsewhere, is refused: never a silent run on
/// the system's Mesa), the backend created and its driver's strings said. `None` once a
/// hello other than ready has been said.
fn come_up(id: &str, out: &mut std::io::StdoutLock<'_>) -> Option<Box<dyn umbra_case::Backend>> {
    let created = std::time::Instant::now();
    // On a Mesa build (`--mesa`), a backend whose driver the build lacks is a skip, and one
    // whose driver does not load, or loads from elsewhere, is refused: never a silent run
    // on the system's Mesa.
    let build = std::env::var(crate::harness::mesa_build::ENV)
        .ok()
        .filter(|_| crate::harness::mesa_build::is_mesa_backed(id))
        .map(|root| crate::harness::mesa_build::MesaBuild::open(std::path::Path::new(&root)));
    let say = |out: &mut std::io::StdoutLock, hello: Hello| {
        let _ = writeln!(out, "{}", serde_json::to_string(&hello).unwrap_or_default());
        let _ = out.flush();
    };
    let build = match build {
        Some(Err(e)) => {
            say(out, Hello::Refused(format!("--mesa: {e}")));
            return None;
        }
        Some(Ok(b)) => {
            if let Some(why) = b.lacks(id) {
                say(out, Hello::Unavailable(why.to_string()));
                return None;
            }
            // A build with its own C library: this process continues on it (re-executed).
            if let Err(e) = b.enter() {
                say(out, Hello::Refused(format!("{id}: {e}")));
                return None;
            }
            Some(b)
        }
        None => None,
    };
    let backend = match crate::harness::registry::create(id) {
        Ok(b) => {
            let i = b.info();
            let create_ms = created.elapsed().as_secs_f64() * 1e3;
            let libs = crate::harness::mesa_build::loaded_libs();
            if let Some(build) = &build {
                if build.layout != "fake (tests)" {
                    if let Err(e) = crate::harness::mesa_build::check_loaded(&build.root, &libs) {
                        say(out, Hello::Refused(format!("{id}: {e}")));
                        return None;
                    }
                }
            }
            let hello = Hello::Ready(Ready {
                vendor: i.vendor,
                renderer: i.renderer,
                version: i.version,
                extensions: i.extensions,
                device: i.device,
                create_ms,
                build: build.as_ref().map(|b| b.describe()),
                mesa_libs: libs,
            });
            say(out, hello);
            b
        }
        Err(e) => {
            let v = match &build {
                // The build has the driver (lacks() said so), yet it did not come up.
                Some(b) => Hello::Refused(format!(
                    "{id}: the driver of the Mesa build in {} did not load: {e}",
                    b.root.display()
                )),
                None => Hello::Unavailable(e.to_string()),
            };
            say(out, v);
            return None;
        }
    };
    Some(backend)
}
