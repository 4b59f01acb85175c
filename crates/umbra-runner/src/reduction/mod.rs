//! The reducer, as a library: shrinks a failing case point to a minimal case file for a bug
//! report. `umbra reduce CASE.json --point ID --backend ID` calls [`reduce`] with the
//! terminal as its log; `umbra repro` calls it with `reduce.log`, and reads what it kept
//! from the typed [`Reduced`] (or the error) rather than from the log.
//!
//! The point must fail on the backend (its frame, not only a twin or a golden). The reducer
//! then tries smaller cases one change at a time, greedily, and keeps a change when the
//! smaller case still **fails the same way** on the backend and still **passes on the
//! reference** (judged against its own model, with the case's own claims): so the reduced
//! case is one the harness stands behind, not one that fails for a new reason. "The same
//! way" means: the smaller case fails some of the checks the point failed and no other (a
//! fault that breaks the shadow map and, through it, 40 pixels' visibility may be left
//! breaking the map alone; it may not start failing the colour check), plus every check named
//! with `--check` (to keep, say, the visibility failure a bug report shows); a crash or hang
//! must stay a crash or hang. The changes, in order of what they save:
//!
//! 1. no sweep (the point's values are baked in) and no twins;
//! 2. lights removed one at a time (the last two become a one-light case), objects removed
//!    (halves first, then one at a time), sphere tessellation halved, inline mesh triangles
//!    removed;
//! 3. the camera's image and the shadow map halved (down to 16 pixels a side);
//! 4. technique, shading and light fields back to their defaults, one at a time (filter,
//!    bias terms, compare, attachments, cull, outside, ...);
//! 5. fields equal to their defaults dropped from the text (no render needed).
//!
//! It writes each change it kept to its log, and writes the reduced case (`name-reduced`, with an
//! `about` saying where it came from and how it fails) to `-o` (default
//! `target/umbra/reduce/NAME-reduced.json`). The environment passes to the workers, so a
//! self-test fault (`UMBRA_SELFTEST=1 UMBRA_FAULT=...`) or a `--mesa` build reduces like a
//! driver bug.

mod case_json;

use case_json::{
    case_text, describe_objects, differs, size_line, strip_defaults, tidy, without_lights,
};

use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde_json::Value;

use crate::case_size::Size;
use umbra_report::check::Check;

use crate::cli::ReduceArgs;
use crate::exit::{Error, Exit};
use crate::harness::pool::Reply;
use crate::harness::scheduler::{NotReady, Session};
use crate::judge::protocol::{JudgeRequest, Request, RunVerdict};

/// How a run ended, in the terms "fails the same way" compares.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Passed.
    Pass,
    /// Failed these checks (twins and goldens aside).
    Fail(BTreeSet<Check>),
    /// The worker died or hung.
    Crash(String),
    /// Skipped, or the case did not load.
    Other(String),
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Verdict::Pass => f.write_str("pass"),
            Verdict::Fail(c) => write!(
                f,
                "fails {}",
                c.iter().map(Check::name).collect::<Vec<_>>().join("+")
            ),
            Verdict::Crash(how) => write!(f, "crash ({how})"),
            Verdict::Other(why) => f.write_str(why),
        }
    }
}

/// Runs candidates on the backend and on the reference.
struct Judge {
    backend: String,
    worker: Option<Session>,
    reference: Option<Session>,
    timeout: Duration,
    dir: PathBuf,
    tried: usize,
    /// Why the last candidate was not kept.
    last: String,
    /// Checks every candidate must still fail (`--check`).
    required: BTreeSet<Check>,
}

impl Judge {
    fn run_on(&mut self, reference: bool, case: &Value) -> Verdict {
        self.tried += 1;
        let file = self.dir.join(format!("candidate-{}.json", self.tried));
        let text = serde_json::to_string_pretty(case).unwrap_or_default();
        if std::fs::write(&file, &text).is_err() {
            return Verdict::Other(format!("cannot write {}", file.display()));
        }
        let id = if reference {
            "ref".to_string()
        } else {
            self.backend.clone()
        };
        let slot = if reference {
            &mut self.reference
        } else {
            &mut self.worker
        };
        if slot.is_none() {
            let env = crate::harness::registry::worker_env(&id);
            let session = Session::start(&id, &env, self.timeout);
            match session.ready() {
                Ok(()) => *slot = Some(session),
                Err(NotReady::NoWorker(e)) => {
                    return Verdict::Other(format!("no worker for {id}: {e}"));
                }
                Err(NotReady::Unavailable(u) | NotReady::Refused(u)) => {
                    return Verdict::Other(format!("{id} cannot run: {u}"));
                }
            }
        }
        let Some(w) = slot.as_mut() else {
            return Verdict::Other("no worker".into());
        };
        // The candidate is loaded here from the text just written (kept in the file for a
        // person), as conformance loads a case, and sent whole; a
        // candidate that does not load is an error, as the worker once reported it.
        let point = match umbra_case::load_str(&text, &file).map(Vec::into_iter) {
            Ok(mut points) => match points.next() {
                Some(p) => p,
                None => return Verdict::Other(format!("error: {} has no point", file.display())),
            },
            Err(e) => return Verdict::Other(format!("error: {e}")),
        };
        let req = Request::Judge(JudgeRequest::bare(point, true));
        // A worker that crashed or timed out is started again by the session, for the next
        // candidate.
        let v = match w.reply(&req).map(|(reply, _)| reply) {
            Ok(Reply::Report(r)) => match r.outcome {
                RunVerdict::Pass => Verdict::Pass,
                RunVerdict::Fail if r.failed.is_empty() => {
                    Verdict::Other(format!("error: {}", r.reason))
                }
                RunVerdict::Fail => Verdict::Fail(
                    r.failed
                        .iter()
                        .map(|c| c.check.clone())
                        .filter(|c| !matches!(c, Check::Twin(_) | Check::Golden))
                        .collect(),
                ),
                RunVerdict::Skip => Verdict::Other(format!("{}: {}", r.outcome, r.reason)),
            },
            Ok(Reply::Crashed(how)) => Verdict::Crash(how),
            Ok(Reply::TimedOut) => Verdict::Crash("timeout".into()),
            Ok(Reply::OverBudget(why)) => Verdict::Other(format!("umbra's memory budget: {why}")),
            Err(e) => Verdict::Other(format!("no worker for {id}: {e}")),
        };
        let _ = std::fs::remove_file(&file);
        v
    }

    /// Whether `case` fails on the backend as `want` does and passes on the reference.
    fn keeps(&mut self, case: &Value, want: &Verdict) -> bool {
        if Size::of(case).is_none() {
            self.last = "does not load".into();
            return false;
        }
        let got = self.run_on(false, case);
        let same = match (&got, want) {
            (Verdict::Fail(a), Verdict::Fail(b)) => {
                !a.is_empty() && a.is_subset(b) && self.required.is_subset(a)
            }
            (Verdict::Crash(_), Verdict::Crash(_)) => true,
            _ => false,
        };
        if !same {
            self.last = format!("{} {got}", self.backend);
            return false;
        }
        let r = self.run_on(true, case);
        self.last = format!("ref {r}");
        r == Verdict::Pass
    }
}

/// A finished reduction.
#[derive(Clone, Debug)]
pub struct Reduced {
    /// The reduced case file.
    pub file: PathBuf,
    /// The reducer's before → after line (`reduce: 3 objects … → 1 object …; it fails …`).
    pub summary: String,
}

/// Reduces `args`' point, writing its progress to `log`. An error that carries
/// [`Exit::Fail`] says the point does not fail as required (nothing to reduce); any other, that
/// the reduction could not run (bad input, no worker).
pub fn reduce(args: &ReduceArgs, log: &mut dyn Write) -> Result<Reduced, Error> {
    let (point, backend) = target(args)?;
    let mut r = Reducer::start(args, &point, &backend, log)?;
    r.lights();
    r.objects();
    r.tessellation();
    r.sizes();
    r.defaults();
    r.finish(args, &point)
}

/// The point to reduce and its backend, checked: a usage error names what is wrong.
fn target(args: &ReduceArgs) -> Result<(umbra_case::CasePoint, String), Error> {
    let (file, point_id) = (args.positional.display(), args.point.as_str());
    let backend = match args.backend.as_slice() {
        [one] => one.as_str(),
        many => {
            return Err(crate::cli::usage_error(
                "reduce",
                format!(
                    "--backend {}: a reduction keeps one backend's failure; give --backend once (run umbra reduce once per backend)",
                    crate::cli::values::names(many).join(" --backend ")
                ),
            ));
        }
    };
    crate::harness::mesa_build::select(args.mesa.as_ref()).map_err(Error::new)?;
    if !crate::harness::registry::is_known(backend) || backend == "ref" {
        return Err(Error::new(format!(
            "--backend {backend:?}: give a backend other than ref; this build has: {}",
            crate::harness::registry::known().join(", ")
        )));
    }
    let points = umbra_case::load_file(&args.positional).map_err(|e| Error::new(e.to_string()))?;
    // An id, or a glob over the ids (as --help offers) that selects exactly one.
    let exact: Vec<&umbra_case::CasePoint> = points.iter().filter(|p| p.id() == point_id).collect();
    let matching = if exact.is_empty() {
        points
            .iter()
            .filter(|p| crate::glob::matches(point_id, &p.id()))
            .collect()
    } else {
        exact
    };
    match matching.as_slice() {
        [p] => Ok(((*p).clone(), backend.to_string())),
        [] => Err(Error::new(format!(
            "{file} has no point {point_id:?}; its points: {}",
            points.iter().map(|p| p.id()).collect::<Vec<_>>().join(", ")
        ))),
        many => Err(Error::new(format!(
            "--point {point_id:?} matches {} points of {file} ({}); a reduction takes one: give its id, or a glob that selects only it",
            many.len(),
            many.iter().map(|p| p.id()).collect::<Vec<_>>().join(", ")
        ))),
    }
}

/// A reduction under way: the case as reduced so far, how it must keep failing (`want`), the
/// judge of candidates and the changes kept.
struct Reducer<'l> {
    case: Value,
    judge: Judge,
    want: Verdict,
    removed: Vec<String>,
    verbose: bool,
    before: Size,
    /// Where candidates are written; removed when the reduction ends.
    dir: PathBuf,
    file: String,
    point_id: String,
    /// Where progress goes (the terminal, or `umbra repro`'s `reduce.log`).
    log: &'l mut dyn Write,
}

impl<'l> Reducer<'l> {
    /// Step 1: the point without its sweep and twins, which must still fail the asked checks
    /// (or crash) on the backend and pass on the reference.
    fn start(
        args: &ReduceArgs,
        point: &umbra_case::CasePoint,
        backend: &str,
        log: &'l mut dyn Write,
    ) -> Result<Reducer<'l>, Error> {
        let file = args.positional.display().to_string();
        let point_id = point.id();
        let timeout = args.timeout.duration();
        let required = args
            .check
            .iter()
            .map(String::as_str)
            .map(Check::parse)
            .collect::<Result<BTreeSet<Check>, String>>()
            .map_err(|e| Error::new(format!("--check: {e}")))?;
        let dir = std::env::temp_dir().join(format!("umbra-reduce-{}", std::process::id()));
        umbra_owned::fresh(&dir, "umbra reduce").map_err(|e| Error::new(e.to_string()))?;
        let mut judge = Judge {
            backend: backend.to_string(),
            worker: None,
            reference: None,
            timeout,
            dir: dir.clone(),
            tried: 0,
            last: String::new(),
            required,
        };
        let Ok(mut case) = serde_json::to_value(&point.case) else {
            return Err(Error::new("cannot write the point as JSON"));
        };
        if let Some(o) = case.as_object_mut() {
            o.remove("sweep");
        }
        if let Some(e) = case.get_mut("expect").and_then(Value::as_object_mut) {
            e.remove("twins");
            e.remove("error_falls_along");
        }
        let gone = |e: Error| {
            let _ = umbra_owned::remove(&dir);
            e
        };
        let want = judge.run_on(false, &case);
        match &want {
            Verdict::Fail(c) if !c.is_empty() && judge.required.is_subset(c) => {}
            Verdict::Fail(c) if !c.is_empty() => {
                return Err(gone(Error::new(format!(
                    "--check {}: {point_id} on {backend} fails {} only; name checks it fails",
                    judge
                        .required
                        .iter()
                        .map(Check::name)
                        .collect::<Vec<_>>()
                        .join(" --check "),
                    c.iter().map(Check::name).collect::<Vec<_>>().join("+")
                ))));
            }
            Verdict::Crash(_) => {}
            other => {
                return Err(gone(Error::with(
                    Exit::Fail,
                    format!(
                        "{point_id} on {backend} {other} once its twins and golden are set aside; reduce needs a point whose own frame fails (or that crashes)"
                    ),
                )));
            }
        }
        let reference = judge.run_on(true, &case);
        if reference != Verdict::Pass {
            return Err(gone(Error::with(
                Exit::Fail,
                format!(
                    "{point_id} does not pass on the reference ({reference}): nothing to reduce against"
                ),
            )));
        }
        let before = Size::of(&case).unwrap_or_default();
        // The log is the terminal or a file; a line it cannot take is not the reduction's
        // failure.
        let _ = writeln!(
            log,
            "reduce: {point_id} on {backend} {want}; passes on ref; {}",
            size_line(&before)
        );
        Ok(Reducer {
            case,
            judge,
            want,
            removed: Vec::new(),
            verbose: args.output.verbose,
            before,
            dir,
            file,
            point_id,
            log,
        })
    }

    /// Keeps `cand` if it still fails as wanted; says so.
    fn keep(&mut self, cand: Value, what: String) -> bool {
        if self.judge.keeps(&cand, &self.want) {
            let s = Size::of(&cand).unwrap_or_default();
            let _ = writeln!(self.log, "  kept: {what} ({})", size_line(&s));
            self.removed.push(what);
            self.case = cand;
            true
        } else {
            if self.verbose {
                let _ = writeln!(self.log, "  not kept: {what} ({})", self.judge.last);
            }
            false
        }
    }

    /// Step 2: lights, one at a time, while the rest still fails the same way. Two become
    /// one as a one-light case (`light` alone, no `lights`, no `shadow.placement`, which says
    /// where several lights' maps live), the case `umbra repro`'s program can carry; the
    /// first light's ambient term stays with whichever light is left. Each light is a lit
    /// pass and a map, so this saves the most of any step on a case of several.
    fn lights(&mut self) {
        loop {
            let lights = self.case["lights"].as_array().cloned().unwrap_or_default();
            if lights.len() < 2 {
                return;
            }
            let n = lights.len();
            let kept = (0..n).any(|k| {
                let mut rest = lights.clone();
                let gone = rest.remove(k);
                let what = format!("removed light {k} of {n} ({})", describe_objects(&[gone]));
                self.keep(without_lights(&self.case, rest), what)
            });
            if !kept {
                return;
            }
        }
    }

    /// Step 2, continued: objects, halves first, then one at a time, until nothing more goes.
    fn objects(&mut self) {
        let count = |case: &Value| case["scene"]["objects"].as_array().map_or(0, Vec::len);
        loop {
            let mut progress = false;
            let mut chunk = count(&self.case) / 2;
            while chunk >= 1 && !progress {
                let mut start = 0;
                while start < count(&self.case) {
                    let objs = self.case["scene"]["objects"]
                        .as_array()
                        .cloned()
                        .unwrap_or_default();
                    if objs.len() <= 1 {
                        break;
                    }
                    let end = (start + chunk).min(objs.len());
                    let mut cand = self.case.clone();
                    let rest: Vec<Value> = objs
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| *i < start || *i >= end)
                        .map(|(_, o)| o.clone())
                        .collect();
                    cand["scene"]["objects"] = Value::Array(rest);
                    let what = format!(
                        "removed object{} {}",
                        if end - start > 1 { "s" } else { "" },
                        describe_objects(&objs[start..end])
                    );
                    if self.keep(cand, what) {
                        progress = true;
                    } else {
                        start = end;
                    }
                }
                chunk /= 2;
            }
            if !progress {
                break;
            }
        }
    }

    /// Step 2, continued: spheres' segments halved, meshes' triangles one at a time.
    fn tessellation(&mut self) {
        let n = self.case["scene"]["objects"].as_array().map_or(0, Vec::len);
        for i in 0..n {
            while let Some(seg) = self.case["scene"]["objects"][i]["sphere"]["segments"]
                .as_u64()
                .filter(|s| *s > 4)
            {
                let mut cand = self.case.clone();
                cand["scene"]["objects"][i]["sphere"]["segments"] = Value::from((seg / 2).max(4));
                let what = format!("sphere {i}: segments {seg} → {}", (seg / 2).max(4));
                if !self.keep(cand, what) {
                    break;
                }
            }
            let Some(mut current) = self.case["scene"]["objects"][i]["mesh"]["triangles"]
                .as_array()
                .cloned()
            else {
                continue;
            };
            let mut t = 0;
            while t < current.len() && current.len() > 1 {
                let mut cand = self.case.clone();
                let mut fewer = current.clone();
                fewer.remove(t);
                cand["scene"]["objects"][i]["mesh"]["triangles"] = Value::Array(fewer.clone());
                if self.keep(cand, format!("mesh {i}: triangle {t}")) {
                    current = fewer;
                } else {
                    t += 1;
                }
            }
        }
    }

    /// Step 3: the camera image and the shadow map halved while they stay 16 or more.
    fn sizes(&mut self) {
        for (path, what) in [
            (["camera", "size"], "camera image"),
            (["shadow", "size"], "shadow map"),
        ] {
            loop {
                let s = &self.case[path[0]][path[1]];
                let (Some(w), Some(h)) = (s[0].as_u64(), s[1].as_u64()) else {
                    break;
                };
                if w < 32 || h < 32 {
                    break;
                }
                let mut cand = self.case.clone();
                cand[path[0]][path[1]] = serde_json::json!([w / 2, h / 2]);
                if !self.keep(cand, format!("{what} {w}x{h} → {}x{}", w / 2, h / 2)) {
                    break;
                }
            }
        }
    }

    /// Step 4: fields of `shadow`, `shading` and `expect` back to their defaults, one at a
    /// time (sub-fields first).
    fn defaults(&mut self) {
        for section in ["shadow", "shading", "expect"] {
            let keys: Vec<String> = self.case[section]
                .as_object()
                .map(|o| o.keys().cloned().collect())
                .unwrap_or_default();
            for k in keys {
                if section == "shadow" && k == "size" {
                    continue;
                }
                if let Some(sub) = self.case[section][&k].as_object().cloned() {
                    for sk in sub.keys() {
                        let mut cand = self.case.clone();
                        if let Some(o) = cand[section][&k].as_object_mut() {
                            o.remove(sk);
                        }
                        if differs(&self.case, &cand) {
                            self.keep(cand, format!("{section}.{k}.{sk} → default"));
                        }
                    }
                }
                let mut cand = self.case.clone();
                if let Some(o) = cand[section].as_object_mut() {
                    o.remove(&k);
                }
                if differs(&self.case, &cand) {
                    self.keep(cand, format!("{section}.{k} → default"));
                }
            }
        }
    }

    /// Step 5: what equals its default dropped from the text, the case named and described
    /// (how it fails now, what was kept), checked to load, and written.
    fn finish(
        mut self,
        args: &ReduceArgs,
        point: &umbra_case::CasePoint,
    ) -> Result<Reduced, Error> {
        let (file, point_id, backend) = (
            self.file.clone(),
            self.point_id.clone(),
            self.judge.backend.clone(),
        );
        let mut case = strip_defaults(std::mem::take(&mut self.case));
        let after = Size::of(&case).unwrap_or_default();
        // How the reduced case fails, as written (a subset of the point's failed checks).
        let now = self.judge.run_on(false, &case);
        let name = format!("{}-reduced", point.case.name);
        case["name"] = Value::from(name.clone());
        case["about"] = Value::from(format!(
            "{REDUCED_BY}{file} point {point_id} on {backend}, where it {}; reduced, it {now} there and passes on the reference; {} changes kept ({} candidates tried): {}",
            self.want,
            self.removed.len(),
            self.judge.tried,
            if self.removed.is_empty() {
                "none".into()
            } else {
                self.removed.join("; ")
            }
        ));
        if let Some(o) = case.as_object_mut() {
            o.retain(|_, v| !v.is_null());
        }
        let out = args
            .output
            .out
            .as_deref()
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("target/umbra/reduce").join(format!("{name}.json")));
        if let Some(parent) = out.parent() {
            let _ = std::fs::create_dir_all(parent);
        }
        let _ = umbra_owned::remove(&self.dir);
        if let Some(why) = foreign_output(&out) {
            return Err(Error::new(why));
        }
        // The reduced case must load as written.
        let text = case_text(&tidy(case), 0) + "\n";
        if let Err(e) = umbra_case::load_str(&text, &out) {
            return Err(Error::new(format!(
                "the reduced case does not load ({e}); this is a bug in the reducer"
            )));
        }
        std::fs::write(&out, text)
            .map_err(|e| Error::new(format!("cannot write {}: {e}", out.display())))?;
        let summary = format!(
            "reduce: {} → {}; it {now}; {} changes kept of {} candidates tried",
            size_line(&self.before),
            size_line(&after),
            self.removed.len(),
            self.judge.tried
        );
        let _ = writeln!(self.log, "{summary}");
        let _ = writeln!(
            self.log,
            "reduce: wrote {} (cargo run --bin umbra -- render {} --backend {backend})",
            out.display(),
            out.display()
        );
        Ok(Reduced { file: out, summary })
    }
}

/// Why `out` must not be overwritten: it exists and is not a case `umbra reduce` wrote (its
/// `about` begins with [`REDUCED_BY`]). `None` when it is not there or was reduced before.
fn foreign_output(out: &Path) -> Option<String> {
    let meta = std::fs::symlink_metadata(out).ok()?;
    let reduced_before = meta.is_file()
        && std::fs::read_to_string(out)
            .ok()
            .and_then(|t| serde_json::from_str::<Value>(&t).ok())
            .is_some_and(|v| {
                v["about"]
                    .as_str()
                    .is_some_and(|a| a.starts_with(REDUCED_BY))
            });
    (!reduced_before).then(|| {
        format!(
            "--out {}: the file exists and is not a case umbra reduce wrote; give a new path (or remove it yourself if it is not yours to keep)",
            out.display()
        )
    })
}

/// How a reduced case's `about` begins: what marks the file as one umbra may overwrite.
const REDUCED_BY: &str = "reduced by umbra reduce from ";
