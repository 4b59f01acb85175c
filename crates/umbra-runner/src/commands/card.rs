//! `umbra card --backend ID [--json]`: each backend's behaviour card ([`crate::judge::card`]),
//! measured in its own worker process as a run would be; `--diff OLD NEW` names what changed
//! between two stored cards (two releases of one backend, or two backends).

use crate::cli::CardArgs;
use crate::exit::{Error, Exit, Outcome};
use crate::harness::cards::of_session;
use crate::harness::scheduler::Session;
use crate::judge::card::Card;

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
    crate::harness::mesa_build::select(args.mesa.as_ref()).map_err(Error::new)?;
    let named = crate::cli::values::names(&args.backend);
    let ids = crate::harness::registry::selected(&named, crate::harness::registry::known())
        .map_err(|e| crate::cli::usage_error("card", &e))?;
    let limit = args.timeout.duration();
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

/// `--diff OLD NEW`.
fn diff(old: &std::path::Path, new: &std::path::Path, json: bool) -> Outcome {
    let read = |f: &std::path::Path| Card::read(f).map_err(Error::new);
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
