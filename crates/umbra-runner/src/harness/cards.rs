//! A backend's behaviour card measured in a worker process of its own ([`of_session`],
//! [`measured_alone`], once per run for every thread that asks: [`LiveCards`]), or on another
//! Mesa build in a child `umbra card --json` ([`measure_in_child`]: one Mesa per process, so
//! the child is the point; the cards come back as JSON of [`Card`]).

use std::sync::Arc;
use std::time::Duration;

use crate::harness::scheduler::Session;
use crate::judge::card::Card;
use crate::judge::protocol::Request;

/// The card of `session`'s backend, measured by its worker; `Err`: why there is none (the
/// backend is unavailable here, or its worker died or timed out).
pub fn of_session(session: &mut Session) -> Result<Card, String> {
    if let Err(why) = session.ready() {
        return Err(format!("{why:?}"));
    }
    match session.reply(&Request::Card)? {
        (crate::harness::pool::Reply::Report(r), _) => r
            .card
            .ok_or_else(|| format!("the worker answered without a card: {}", r.reason)),
        (crate::harness::pool::Reply::Crashed(how), stderr) => Err(format!(
            "the worker died measuring it: {how}; stderr: {}",
            stderr.lines().last().unwrap_or("")
        )),
        (crate::harness::pool::Reply::TimedOut, _) => {
            Err("the probes did not finish within the time limit".into())
        }
        (crate::harness::pool::Reply::OverBudget(why), _) => {
            Err(format!("stopped by umbra's memory budget: {why}"))
        }
    }
}

/// Each backend's live card in one run, measured once: by whichever of the backend's worker
/// threads asks first, the others waiting for it (a `OnceLock` per backend).
#[derive(Default)]
pub struct LiveCards(std::sync::Mutex<std::collections::HashMap<String, Arc<Measured>>>);

/// One backend's card, measured once ([`LiveCards`]).
type Measured = std::sync::OnceLock<Result<Card, String>>;

impl LiveCards {
    /// `backend`'s card ([`measured_alone`]) unless another thread has measured it.
    pub fn measured(
        &self,
        backend: &str,
        env: &[(String, String)],
        limit: Duration,
    ) -> Result<Card, String> {
        let cell = match self.0.lock() {
            Ok(mut cells) => Arc::clone(cells.entry(backend.to_string()).or_default()),
            Err(_) => return measured_alone(backend, env, limit),
        };
        cell.get_or_init(|| measured_alone(backend, env, limit))
            .clone()
    }
}

/// `backend`'s card, measured in a worker of its own (environment `env`, probes within
/// `limit`): the probes' renders leave nothing in the workers that run the cases (a driver's
/// caches, a fake backend's call count), and a backend that crashes or hangs on a probe
/// costs its card, not a run.
pub fn measured_alone(
    backend: &str,
    env: &[(String, String)],
    limit: Duration,
) -> Result<Card, String> {
    of_session(&mut Session::start(backend, env, limit))
}

/// Measures the cards of `backends` (none: this build's ids) on Mesa `mesa` (`system`, a
/// prefix or build) in a child `umbra card --json`, as `drivers` and `bisect` do for each
/// side or commit; `Err`: why there are none (the child failed, or measured nothing).
pub fn measure_in_child(
    exe: &std::path::Path,
    mesa: &std::ffi::OsStr,
    backends: &[impl AsRef<str>],
) -> Result<Vec<Card>, String> {
    let mut cmd = std::process::Command::new(exe);
    cmd.args(["card", "--json", "--mesa"]).arg(mesa);
    for b in backends {
        cmd.args(["--backend", b.as_ref()]);
    }
    let out = cmd
        .env_remove(crate::harness::mesa_build::ENV)
        .stderr(std::process::Stdio::piped())
        .output()
        .map_err(|e| format!("cannot run umbra card: {e}"))?;
    let said = || String::from_utf8_lossy(&out.stderr).trim().to_string();
    if !out.status.success() {
        return Err(format!("umbra card failed ({}): {}", out.status, said()));
    }
    let cards: Vec<Card> = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("umbra card gave no cards ({e}); it said: {}", said()))?;
    if cards.is_empty() {
        return Err(format!(
            "umbra card measured no backend; it said: {}",
            said()
        ));
    }
    Ok(cards)
}
