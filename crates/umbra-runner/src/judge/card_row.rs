//! What a backend's live behaviour card means for a run: the calibration it gives the
//! judge ([`calibration_of`]) and conformance's `BACKEND/card` row, the live card against the
//! kept one ([`conformance_row`]).

use crate::judge::card::Card;

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
