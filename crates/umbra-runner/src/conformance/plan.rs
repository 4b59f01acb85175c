//! A conformance run's first step: the command line's options checked ([`Options`]: every
//! bad value a usage error naming the flag), the case points loaded and crossed with the
//! backends in a fixed order, sharded and filtered ([`plan_runs`]), the expectations
//! validated against the plan, and the goldens settled (which backends have none).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::{Planned, PointPlan};
use crate::cli::ConformanceArgs;
use crate::exit::Error;
use crate::judge::expectations::Expectations;
use crate::judge::falls_along::FallsAlong;
use umbra_report::escape::term;
use umbra_report::{RunResult, Status};

/// What the command line asks for, checked: every bad value is a usage error (exit 125)
/// that names the flag and the fix.
pub(crate) struct Options {
    pub(crate) build: Option<&'static crate::harness::mesa_build::MesaBuild>,
    pub(crate) out: PathBuf,
    pub(crate) filter: String,
    pub(crate) backends: Vec<String>,
    pub(crate) shard: (usize, usize),
    /// How the plan is split over the shards (`--durations`).
    pub(crate) by: crate::shards::balance::By,
    /// Digests of the cases, expectations and goldens, for the run's record.
    pub(crate) inputs: crate::shards::record::Inputs,
    pub(crate) jobs: usize,
    pub(crate) timeout: Duration,
    pub(crate) golden: Option<PathBuf>,
    pub(crate) expectations: Expectations,
    pub(crate) files: Vec<PathBuf>,
    pub(crate) bless: bool,
    /// Whether expectation lines that match no loaded point are warned about.
    pub(crate) stale_check: bool,
    /// `--tier` or `--budget`: the only runs to make ([`crate::tier`]).
    pub(crate) tier: Option<crate::tier::Tier>,
}

impl Options {
    pub(crate) fn read(args: &ConformanceArgs) -> Result<Options, Error> {
        let fail = Error::new;
        let (selection, execution) = (&args.selection, &args.execution);
        let build = crate::harness::mesa_build::select(execution.mesa.as_ref()).map_err(fail)?;
        let shard = args.shard.unwrap_or(crate::cli::Shard::WHOLE);
        let shard = (shard.index, shard.count);
        let limits = execution.resolve("conformance")?;
        let (jobs, timeout) = (limits.jobs, limits.timeout);
        let golden = golden_dir(&args.golden)?;
        if let Some(warning) = golden
            .as_deref()
            .and_then(crate::judge::golden::check_manifest)
        {
            eprintln!("{}", term(&warning));
        }
        if let Some(dir) = golden.as_deref() {
            crate::judge::golden::check_confirmed(dir).map_err(fail)?;
        }
        let by = match args.durations.as_deref() {
            None => crate::shards::balance::By::Stride,
            Some(_) if shard.1 == 1 => {
                return Err(crate::cli::usage_error(
                    "conformance",
                    "--durations balances shards: give it with --shard I/N (N > 1)",
                ));
            }
            Some(f) => crate::shards::balance::By::Durations(
                crate::shards::balance::Durations::read(f)
                    .map_err(|e| crate::cli::usage_error("conformance", e))?,
            ),
        };
        let out = args
            .output
            .out
            .clone()
            .unwrap_or_else(|| PathBuf::from(OUT));
        outside_cases(&out, &selection.cases).map_err(|e| {
            crate::cli::usage_error("conformance", format!("--out {}: {e}", out.display()))
        })?;
        let selected = selection.resolve(crate::harness::registry::known())?;
        let tier = tier_of(args, jobs)?;
        let (cases_dir, expectations_dir) = (&selected.cases, &selected.expectations_dir);
        let digest = |d: &Path| {
            crate::shards::record::Digest::of(d)
                .map_err(|e| fail(format!("cannot read what the run's record names: {e}")))
        };
        let inputs = crate::shards::record::Inputs {
            cases: digest(cases_dir)?,
            expectations: if expectations_dir.is_dir() {
                digest(expectations_dir)?
            } else {
                crate::shards::record::Digest {
                    dir: expectations_dir.display().to_string(),
                    files: 0,
                    digest: String::new(),
                }
            },
            golden: golden
                .as_deref()
                .map(|g| {
                    crate::shards::record::Digest::of_goldens(g)
                        .map_err(|e| fail(format!("cannot read what the run's record names: {e}")))
                })
                .transpose()?,
        };
        Ok(Options {
            build,
            out,
            filter: selected.filter,
            backends: selected.backends,
            shard,
            by,
            inputs,
            jobs,
            timeout,
            golden,
            expectations: selected.expectations,
            files: selected.files,
            bless: args.bless,
            stale_check: true,
            tier,
        })
    }
}

/// `--tier FILE`, or `--budget DURATION` chosen from the recorded catches and durations
/// ([`crate::tier::make`]); said on the terminal.
fn tier_of(args: &ConformanceArgs, jobs: usize) -> Result<Option<crate::tier::Tier>, Error> {
    let usage = |e: String| crate::cli::usage_error("conformance", e);
    let tier = match (&args.tier, &args.budget) {
        (Some(file), _) => crate::tier::Tier::read(file).map_err(usage)?,
        (None, Some(budget)) => {
            let seconds =
                crate::tier::parse_budget(budget).map_err(|e| usage(format!("--budget {e}")))?;
            crate::tier::make(
                seconds,
                Path::new(crate::tier::CATCHES),
                Path::new(crate::tier::DURATIONS),
                jobs,
                None,
            )
            .map_err(|e| usage(format!("--budget: {e}")))?
        }
        (None, None) => return Ok(None),
    };
    print!("{}", tier.describe());
    Ok(Some(tier))
}

/// `--out`'s default for a conformance run.
pub(crate) const OUT: &str = "target/umbra";

/// `--golden`: the golden directory, or none (`--golden none`).
pub(crate) fn golden_dir(flag: &Path) -> Result<Option<PathBuf>, Error> {
    if flag == Path::new("none") {
        return Ok(None);
    }
    if !flag.is_dir() {
        return Err(crate::cli::usage_error(
            "conformance",
            format!(
                "--golden {}: no such directory; give the golden directory (golden/), or --golden none to run without golden checks",
                flag.display()
            ),
        ));
    }
    Ok(Some(flag.to_path_buf()))
}

/// The runs to make: the case files that did not load (each a failed result already), the
/// `expect.error_falls_along` series, and this shard's runs.
pub(crate) struct Plan {
    pub(crate) results: Vec<RunResult>,
    pub(crate) falls_along: Vec<FallsAlong>,
    pub(crate) plan: Vec<Planned>,
    /// Every selected run's name before sharding, in plan order (the run's record).
    pub(crate) names: Vec<String>,
}

/// Loads every case file, plans every backend × point the filter selects, checks the
/// expectations against the plan, and keeps this shard's share.
pub(crate) fn plan_runs(opts: &Options) -> Result<Plan, Error> {
    let mut results: Vec<RunResult> = Vec::new();
    let mut points: Vec<(PathBuf, Vec<PointPlan>)> = Vec::new();
    let mut falls_along: Vec<FallsAlong> = Vec::new();
    for f in &opts.files {
        match umbra_case::load_file(f) {
            Ok(p) => {
                falls_along.extend(FallsAlong::of(&p));
                points.push((
                    f.clone(),
                    p.into_iter()
                        .map(|p| {
                            let case = umbra_case::schema::condition_json(&p.case);
                            (p.id(), std::sync::Arc::new(p), std::sync::Arc::new(case))
                        })
                        .collect(),
                ));
            }
            Err(e) => results.push(unloadable(f, &e.to_string())),
        }
    }
    if let Some(e) = duplicate_names(&points) {
        return Err(crate::cli::usage_error("conformance", e));
    }
    let tier = opts.tier.as_ref().map(crate::tier::Tier::run_set);
    let mut plan = Vec::new();
    for b in &opts.backends {
        for (_, ids) in &points {
            for (id, point, case) in ids {
                let p = Planned {
                    backend: b.clone(),
                    id: id.clone(),
                    point: point.clone(),
                    case: case.clone(),
                };
                let in_tier = tier.as_ref().is_none_or(|t| t.contains(p.name().as_str()));
                if in_tier
                    && (crate::glob::matches(&opts.filter, id)
                        || crate::glob::matches(&opts.filter, &p.name()))
                {
                    plan.push(p);
                }
            }
        }
    }
    validate_expectations(opts, &plan)?;
    if opts.stale_check {
        warn_stale_expectations(opts, &points);
    }
    let selected = plan.len();
    if selected == 0 && results.is_empty() {
        return Err(Error::new(format!(
            "--filter {:?} selects no run",
            opts.filter
        )));
    }
    let names: Vec<String> = plan.iter().map(Planned::name).collect();
    let (index, count) = opts.shard;
    let shard_of = crate::shards::balance::assign(&names, count, &opts.by);
    let plan: Vec<Planned> = plan
        .into_iter()
        .zip(&shard_of)
        .filter(|(_, s)| **s == index)
        .map(|(p, _)| p)
        .collect();
    if count > 1 {
        println!(
            "shard {index}/{count}: {} of the {selected} selected runs",
            plan.len()
        );
        if let crate::shards::balance::By::Durations(d) = &opts.by {
            println!("{}", crate::shards::balance::report(&names, count, d));
        }
    }
    if plan.is_empty() && results.is_empty() {
        // More shards than runs (a CI matrix sized for a larger plan): an empty shard is a
        // successful one, and leaves its (empty) reports and record for the merge.
        println!(
            "note: shard {index}/{count} holds none of the {selected} selected runs (there are more shards than runs); nothing to do"
        );
    }
    Ok(Plan {
        results,
        falls_along,
        plan,
        names,
    })
}

/// A case file that did not load, as a failed result naming the error.
pub(crate) fn unloadable(f: &Path, why: &str) -> RunResult {
    RunResult {
        name: format!("cases/{}", f.display()),
        backend: String::new(),
        case: f.display().to_string(),
        file: f.display().to_string(),
        values: Vec::new(),
        status: Status::Fail,
        reason: why.to_string(),
        metrics: None,
        failed: Vec::new(),
        golden: None,
        time_s: 0.0,
        reproduce: format!("cargo run --bin umbra -- render {}", f.display()),
        diagnosis: None,
        stderr: String::new(),
        fingerprint: None,
        details: String::new(),
    }
}

/// The expectations checked against the planned runs ([`Expectations::validate`]).
pub(crate) fn validate_expectations(opts: &Options, plan: &[Planned]) -> Result<(), Error> {
    let known = crate::harness::registry::known();
    let mut ids: Vec<&str> = known.iter().map(String::as_str).collect();
    ids.extend(opts.backends.iter().map(String::as_str));
    if crate::harness::fake::enabled() {
        ids.extend(crate::harness::fake::IDS);
    }
    let runs: Vec<(String, &serde_json::Value)> =
        plan.iter().map(|p| (p.name(), &*p.case)).collect();
    opts.expectations.validate(&ids, &runs).map_err(Error::new)
}

/// Says each expectation line that matches no run of every case point loaded on any of this
/// build's backends (whatever --filter, --backend and --shard select): stale or mistyped.
pub(crate) fn warn_stale_expectations(opts: &Options, points: &[(PathBuf, Vec<PointPlan>)]) {
    let known = crate::harness::registry::known();
    let ids: Vec<&str> = known.iter().map(String::as_str).collect();
    let all: Vec<(String, &serde_json::Value)> = points
        .iter()
        .flat_map(|(_, ids)| ids.iter().map(|(id, _, case)| (id.clone(), &**case)))
        .collect();
    // A line for a device this build does not list (gl33/radeonsi/*) is not stale here.
    let on_device = |e: &&crate::judge::expectations::Expectation| {
        let mut parts = e.pattern.splitn(3, '/');
        let backend = format!(
            "{}/{}",
            parts.next().unwrap_or(""),
            parts.next().unwrap_or("")
        );
        !backend.contains(['*', '?']) && crate::harness::registry::is_device_id(&backend)
    };
    for e in opts
        .expectations
        .stale(&ids, &all)
        .iter()
        .filter(|e| !on_device(e))
    {
        eprintln!(
            "warning: expectation {} ({}) matches no run of the {} case points loaded on any of this build's backends: stale (its case renamed or removed) or mistyped; it expects nothing",
            e.source,
            e.pattern,
            all.len()
        );
    }
}

/// Blessing's preconditions, and the backends judged without goldens: a device umbra has
/// never seen, without goldens, is judged by the specs and the reference; blessing starts
/// its goldens. This build's own ids always have goldens: a missing one (an empty or missing
/// golden directory included) is a change to review, never a check switched off.
pub(crate) fn settle_goldens(opts: &Options) -> Result<std::collections::BTreeSet<String>, Error> {
    if opts.bless && crate::judge::golden::under_ci() {
        return Err(crate::cli::usage_error(
            "conformance",
            "--bless: CI=true: goldens change only through review (`cargo xtask bless` or `cargo insta review` on a desk), never in CI",
        ));
    }
    if opts.bless && opts.golden.is_none() {
        return Err(crate::cli::usage_error(
            "conformance",
            "--bless with --golden none: there are no goldens to bless",
        ));
    }
    let no_goldens: std::collections::BTreeSet<String> = match (&opts.golden, opts.bless) {
        (Some(dir), false) => opts
            .backends
            .iter()
            .filter(|b| {
                crate::harness::registry::is_device_id(b)
                    && !crate::judge::golden::has_goldens(dir, b)
            })
            .cloned()
            .collect(),
        _ => Default::default(),
    };
    for b in &no_goldens {
        println!(
            "{b}: {} (`cargo xtask bless --backend {b}` starts them)",
            crate::judge::golden::NONE_FOR_BACKEND
        );
    }
    let inherited = crate::judge::golden::inherited_insta();
    if !inherited.is_empty() {
        eprintln!(
            "note: ignored {} from the environment: umbra sets insta's environment itself; goldens change only through `cargo xtask bless` or `cargo insta review`",
            term(&inherited.join(" "))
        );
    }
    Ok(no_goldens)
}

/// Refuses an output directory inside the case directory: its reports (report.json,
/// shard.json) would be read as cases by the next run.
pub fn outside_cases(out: &Path, cases: &Path) -> Result<(), String> {
    // The deepest existing ancestor, resolved (the output may not exist yet).
    let resolve = |p: &Path| {
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut head = abs.clone();
        let mut tail = Vec::new();
        while !head.exists() {
            match (head.file_name().map(|n| n.to_os_string()), head.parent()) {
                (Some(n), Some(parent)) => {
                    tail.push(n);
                    head = parent.to_path_buf();
                }
                _ => return abs,
            }
        }
        let mut real = std::fs::canonicalize(&head).unwrap_or(head);
        real.extend(tail.iter().rev());
        real
    };
    let (out, cases) = (resolve(out), resolve(cases));
    if out.starts_with(&cases) {
        return Err(format!(
            "is inside the case directory {}: the next run would read its reports as cases; write them elsewhere (the default is target/umbra)",
            cases.display()
        ));
    }
    Ok(())
}

/// Two case files that give one case name (their runs would share a name, a row and a
/// golden): the error naming both.
pub(crate) fn duplicate_names(points: &[(PathBuf, Vec<PointPlan>)]) -> Option<String> {
    let mut seen: BTreeMap<String, &Path> = BTreeMap::new();
    for (file, ids) in points {
        let Some(name) = ids
            .first()
            .and_then(|(_, _, case)| case["name"].as_str().map(str::to_string))
        else {
            continue;
        };
        if let Some(first) = seen.insert(name.clone(), file) {
            return Some(format!(
                "{} and {} both have \"name\": {name:?}; their runs, rows and goldens would be one; rename one (the field `name`)",
                first.display(),
                file.display()
            ));
        }
    }
    None
}
