//! `umbra card --backend ID [--json]`: each backend's behaviour card ([`crate::judge::card`]),
//! measured in its own worker process as a run would be; `--diff OLD NEW` names what changed
//! between two stored cards (two releases of one backend, or two backends).

use std::sync::Arc;
use std::time::Duration;

use crate::cli::CardArgs;
use crate::exit::{Error, Exit, Outcome};
use crate::harness::scheduler::Session;
use crate::harness::worker::Request;
use crate::judge::card::Card;

/// The default time limit of one backend's probes (they take 0.1 to 2 s on this machine's
/// software drivers; a slow hardware driver's shader compiles may take far longer).
const DEFAULT_TIMEOUT_S: u64 = 300;

/// Runs `umbra card`; returns its outcome.
pub fn main(args: &CardArgs) -> Outcome {
    if let [old, new] = &args.diff[..] {
        return diff(old, new, args.json);
    }
    if args.keep.is_some() && crate::judge::golden::under_ci() {
        return Err(crate::cli::usage_error(
            "card",
            "--keep writes baselines, which CI never does (CI=true): keep cards locally and commit them after review",
        ));
    }
    crate::harness::mesa_build::select(args.mesa.as_deref()).map_err(Error::new)?;
    let named: Vec<&str> = args.backend.iter().map(String::as_str).collect();
    let ids = crate::harness::registry::selected(&named, crate::harness::registry::known())
        .map_err(|e| crate::cli::usage_error("card", &e))?;
    let limit = crate::cli::timeout_secs(
        "card",
        args.timeout.map(|t| t.to_string()).as_deref(),
        DEFAULT_TIMEOUT_S,
    )?;
    let mut cards = Vec::new();
    let mut could_not = Vec::new();
    for id in &ids {
        let env = crate::harness::registry::worker_env(id);
        let mut session = Session::start(id, &env, limit);
        match of_session(&mut session) {
            Ok(c) => {
                if !args.json {
                    print!("{}", c.table());
                }
                if let Some(dir) = &args.keep {
                    let f = crate::judge::card::file(std::path::Path::new(dir), id, &c.release);
                    std::fs::create_dir_all(f.parent().unwrap_or(std::path::Path::new(dir)))
                        .and_then(|()| crate::atomic_file::write(&f, c.stored().as_bytes()))
                        .map_err(|e| Error::new(format!("cannot keep {}: {e}", f.display())))?;
                    eprintln!("kept {}", f.display());
                }
                cards.push(c);
            }
            Err(e) => {
                eprintln!("{id}: no card: {e}");
                could_not.push(id.clone());
            }
        }
    }
    if cards.is_empty() && !could_not.is_empty() {
        return Err(Error::new(format!(
            "no backend could be measured ({})",
            could_not.join(", ")
        )));
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&cards).unwrap_or_default()
        );
    }
    Ok(Exit::Pass)
}

/// The card of `session`'s backend, measured by its worker; `Err`: why there is none (the
/// backend is unavailable here, or its worker died or timed out).
pub fn of_session(session: &mut Session) -> Result<Card, String> {
    if let Err(why) = session.ready() {
        return Err(format!("{why:?}"));
    }
    match session.reply(&Request::card())? {
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

/// The calibration a live card gives a backend's runs (encoded for the worker's request);
/// none, said once (`first`) on stderr, where the card could not be measured or narrows
/// nothing: those runs are judged by the spec alone, as the report's `judged_as_card` shows.
pub fn calibration_of(
    backend: &str,
    live: Option<&Result<Card, String>>,
    first: bool,
) -> Option<String> {
    match live? {
        Ok(card) => {
            let c = crate::judge::calibration::of_card(card);
            if c.is_empty() && first {
                eprintln!(
                    "note: {backend}: its card narrows nothing; its runs are judged by the specs alone"
                );
            }
            (!c.is_empty()).then(|| c.encode())
        }
        Err(why) => {
            if first {
                eprintln!(
                    "note: {backend}: no behaviour card ({why}); its runs are judged by the specs alone"
                );
            }
            None
        }
    }
}

/// `--diff OLD NEW`.
fn diff(old: &str, new: &str, json: bool) -> Outcome {
    let read = |f: &str| Card::read(std::path::Path::new(f)).map_err(Error::new);
    let (o, n) = (read(old)?, read(new)?);
    let changes = n.changes_since(&o);
    if json {
        let rows: Vec<serde_json::Value> = changes
            .iter()
            .map(|c| {
                serde_json::json!({
                    "key": c.key, "what": c.what,
                    "old": c.old.as_ref().map(|e| &e.value),
                    "new": c.new.as_ref().map(|e| &e.value),
                    "old_inside_spec": c.old.as_ref().and_then(|e| e.inside),
                    "new_inside_spec": c.new.as_ref().and_then(|e| e.inside),
                    "line": c.line(),
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).unwrap_or_default()
        );
    } else {
        println!(
            "{} ({}) → {} ({}): {} changed",
            o.backend,
            o.release,
            n.backend,
            n.release,
            changes.len()
        );
        for c in &changes {
            println!("  {}", c.line());
        }
    }
    Ok(Exit::Pass)
}

/// Conformance's `card` row for `backend` (`BACKEND/card`): its live card against the one
/// kept in golden directory `dir` for its release ([`crate::judge::card::check`]). A change
/// fails check `card`, naming each entry; a release with no card kept yet is a skip that
/// names what differs from the nearest kept release's. `bless` keeps the live card (never
/// under `CI=true`: conformance refuses `--bless` there). A backend whose group cannot run
/// (`not_run`: its status and reason) is not measured; the row says why, as its runs do.
pub fn conformance_row(
    backend: &str,
    live: Option<Result<Card, String>>,
    dir: &std::path::Path,
    bless: bool,
    not_run: Option<(umbra_report::Status, String)>,
) -> umbra_report::RunResult {
    use umbra_report::Status;
    let t0 = std::time::Instant::now();
    let mut row = umbra_report::RunResult {
        name: format!("{backend}/card"),
        backend: backend.to_string(),
        case: "card".into(),
        file: String::new(),
        values: Vec::new(),
        status: Status::Pass,
        reason: String::new(),
        metrics: None,
        failed: Vec::new(),
        golden: None,
        time_s: 0.0,
        reproduce: format!("cargo run --bin umbra -- card --backend {backend}"),
        diagnosis: None,
        stderr: String::new(),
        fingerprint: None,
        details: String::new(),
    };
    if let Some((status, reason)) = not_run {
        (row.status, row.reason) = (status, reason);
        return row;
    }
    match live.unwrap_or_else(|| Err("not measured".into())) {
        Ok(live) => {
            row.details = live.table();
            let (status, reason, failed) = judged(backend, &live, dir, bless);
            (row.status, row.reason) = (status, reason);
            if failed > 0 {
                row.failed = vec![umbra_report::FailedCheck {
                    check: umbra_report::check::Check::Card,
                    count: failed,
                }];
            }
        }
        Err(e) => {
            row.status = Status::Crash;
            row.reason = format!("the behaviour card could not be measured: {e}");
        }
    }
    row.time_s = t0.elapsed().as_secs_f64();
    row
}

/// The card row's status, reason and how many entries fail check `card` (0: none).
fn judged(
    backend: &str,
    live: &Card,
    dir: &std::path::Path,
    bless: bool,
) -> (umbra_report::Status, String, u64) {
    use crate::judge::card::{Change, Verdict};
    use umbra_report::Status;
    let kept = crate::judge::card::file(dir, backend, &live.release);
    let keep = |why: &str| {
        let written = std::fs::create_dir_all(kept.parent().unwrap_or(dir))
            .and_then(|()| crate::atomic_file::write(&kept, live.stored().as_bytes()));
        match written {
            Ok(()) => (
                Status::Pass,
                format!("card kept: {} ({why})", kept.display()),
                0,
            ),
            Err(e) => (
                Status::Fail,
                format!("cannot keep the card in {}: {e}", kept.display()),
                1,
            ),
        }
    };
    let lines = |ch: &[Change]| ch.iter().map(Change::line).collect::<Vec<_>>().join("; ");
    let no_card = || Status::Skip(format!("no card kept for {backend} on {}", live.release));
    match crate::judge::card::check(dir, live) {
        Verdict::Unchanged => (Status::Pass, outside_the_spec(live), 0),
        Verdict::Changed(ch) if bless => keep(&format!("changed: {}", lines(&ch))),
        Verdict::Changed(ch) => (
            Status::Fail,
            format!(
                "card changed against {} ({}): {}; review and `cargo xtask bless` to keep it",
                kept.display(),
                live.release,
                lines(&ch)
            ),
            ch.len() as u64,
        ),
        Verdict::New(_) | Verdict::Unreadable(_) if bless => keep("new"),
        Verdict::New(None) => (
            no_card(),
            format!(
                "no card kept for {backend} on {}: `cargo xtask bless` keeps the live one",
                live.release
            ),
            0,
        ),
        Verdict::New(Some((other, ch))) => {
            let what = if ch.is_empty() {
                format!("the same as {other}'s")
            } else {
                format!("against {other}'s: {}", lines(&ch))
            };
            (
                no_card(),
                format!(
                    "no card kept for {} yet; {what} (`cargo xtask bless` keeps it)",
                    live.release
                ),
                0,
            )
        }
        Verdict::Unreadable(e) => (Status::Fail, e, 1),
    }
}

/// The entries of an unchanged card that lie outside the spec, for the passing row's reason
/// (empty when none): a known deviation stays in view though the card holds it.
fn outside_the_spec(card: &Card) -> String {
    let out: Vec<String> = card
        .entries
        .iter()
        .filter(|e| e.inside == Some(false))
        .map(|e| format!("{}: {}", e.what, e.value))
        .collect();
    if out.is_empty() {
        String::new()
    } else {
        format!(
            "the kept card, unchanged; outside the spec: {}",
            out.join("; ")
        )
    }
}

/// Measures the cards of `backends` (none: this build's ids) on Mesa `mesa` (`system`, a
/// prefix or build) in a child `umbra card --json`, as `drivers` and `bisect` do for each
/// side or commit; `Err`: why there are none (the child failed, or measured nothing).
pub fn measure_in_child(
    exe: &std::path::Path,
    mesa: &std::ffi::OsStr,
    backends: &[String],
) -> Result<Vec<Card>, String> {
    let mut cmd = std::process::Command::new(exe);
    cmd.args(["card", "--json", "--mesa"]).arg(mesa);
    for b in backends {
        cmd.args(["--backend", b]);
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

/// Every entry that changed from `old` to `new`, per backend both measured, as
/// `backend: change` lines in `new`'s order; then each backend measured on one side only.
pub fn changes_between(old: &[Card], new: &[Card]) -> Vec<String> {
    let find = |cards: &[Card], b: &str| cards.iter().position(|c| c.backend == b);
    let mut lines: Vec<String> = new
        .iter()
        .filter_map(|n| Some((n, &old[find(old, &n.backend)?])))
        .flat_map(|(n, o)| {
            n.changes_since(o)
                .into_iter()
                .map(move |c| format!("{}: {}", n.backend, c.line()))
        })
        .collect();
    for (cards, other, side) in [(new, old, "the new side"), (old, new, "the old side")] {
        for c in cards.iter().filter(|c| find(other, &c.backend).is_none()) {
            lines.push(format!("{}: measured on {side} only", c.backend));
        }
    }
    lines
}
