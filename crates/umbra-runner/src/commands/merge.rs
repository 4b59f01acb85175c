//! `umbra merge DIR... -o OUT`: the shards of one conformance run (`--shard I/N` on N CI jobs,
//! or N machines each running its own backends) put back together into one run in
//! `OUT/runs/ID` (shown by `OUT/latest`, as a conformance run's): results.csv,
//! failures.csv, errors.csv, twins.csv, junit.xml, drivers.txt, report.json and report.html,
//! with every shard's pictures.
//!
//! - Each DIR is a shard's `--out` (its `latest` is read), its `runs/ID` directory, or a
//!   directory holding one complete run (a CI artifact of `OUT/runs/`); the shard's record
//!   ([`crate::shards::record`]) says what it ran.
//! - Refused (exit 125), each naming the directories: shards of different builds of umbra
//!   (the key of every crate's sources and the toolchain), of different cases, expectations,
//!   goldens or Mesa builds, shards of one plan split differently, a shard given twice, a run
//!   in two shards, one backend on two different drivers, and a plan with a shard missing
//!   (named, with how many runs it holds and the first of them).
//! - The checks that read several runs at once (`expect.error_falls_along`, the consensus
//!   diagnosis) are made again over every shard's runs, from the results as they stood before
//!   them, so the merged statuses are those of one unsharded run.
//! - The shards' balance is printed: each one's runs, wall and worker time, and the slowest
//!   over the fastest.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::cli::MergeArgs;
use crate::exit::{Error, Outcome};
use crate::run_dir::RunDir;
use crate::shards::record::{DriverRecord, FILE, Record};
use umbra_report::escape::term;
use umbra_report::{RunResult, TimeBudget};

/// One shard as given.
struct Shard {
    /// The directory given on the command line.
    given: PathBuf,
    /// Its run directory (where the record and pictures are).
    run: PathBuf,
    record: Record,
    /// The planned runs it holds ([`Record::own_runs`]).
    runs: Vec<String>,
}

impl Shard {
    fn label(&self) -> String {
        format!(
            "{}/{} ({})",
            self.record.shard.index,
            self.record.shard.count,
            self.given.display()
        )
    }
}

/// Runs the command; returns its outcome.
pub fn main(args: &MergeArgs) -> Outcome {
    let out = args.out.clone();
    let shards = read_all(&args.dirs).map_err(refuse)?;
    out_apart(&out, &shards)
        .and_then(|()| same_inputs(&shards))
        .and_then(|()| complete_plans(&shards))
        .and_then(|()| disjoint(&shards))
        .map_err(refuse)?;
    let drivers = drivers(&shards).map_err(refuse)?;
    print_balance(&shards);
    let results = merged_results(&shards);
    let budget = TimeBudget::merged(
        &shards
            .iter()
            .map(|s| s.record.budget.clone())
            .collect::<Vec<_>>(),
    );
    let run_dir = RunDir::create(&out).map_err(|e| {
        refuse(format!(
            "cannot create a run directory under {}: {e}; give -o a writable directory",
            out.join("runs").display()
        ))
    })?;
    if let Err(e) = write(&shards, &results, &drivers, &budget, &run_dir) {
        run_dir.abandon(&format!("cannot write the merged reports: {e}"));
        return Err(Error::new(format!(
            "cannot write the merged reports into {}: {e}",
            run_dir.dir.display()
        )));
    }
    // The run's wall time is the slowest shard's (shards run side by side).
    let regressions = crate::conformance::summary::print_summary(
        &results,
        &budget,
        &out,
        &run_dir,
        std::time::Duration::from_secs_f64(budget.wall_s),
    );
    println!(
        "{}",
        crate::conformance::summary::closing_line("merge", &results)
    );
    let refused: Vec<String> = shards
        .iter()
        .flat_map(|s| s.record.refused.iter().cloned())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    crate::conformance::summary::outcome(
        &refused,
        shards.iter().map(|s| s.record.unavailable_runs).sum(),
        results.len(),
        regressions,
    )
}

/// A refusal: the error, escaped for the terminal (exit 125).
fn refuse(e: String) -> Error {
    Error::new(term(&e))
}

/// Every DIR's shard; an error names the directory and what it lacks.
fn read_all(dirs: &[PathBuf]) -> Result<Vec<Shard>, String> {
    let mut shards = Vec::new();
    for d in dirs {
        let given = d.clone();
        let run = locate(&given)?;
        let record = Record::read(&run.join(FILE))?;
        let runs = record.own_runs();
        shards.push(Shard {
            given,
            run,
            record,
            runs,
        });
    }
    Ok(shards)
}

/// The run directory of a shard given as its `--out` (its `latest`), or as the run directory
/// itself, or as a directory with a single complete run and no `latest` (an `--out` whose
/// link an artifact store dropped, or a copy of its `runs/`).
fn locate(dir: &Path) -> Result<PathBuf, String> {
    if dir.join(FILE).is_file() {
        return complete(dir).map(|()| dir.to_path_buf());
    }
    let latest = dir.join("latest");
    if latest.join(FILE).is_file() {
        let shown =
            std::fs::canonicalize(&latest).map_err(|e| format!("{}: {e}", latest.display()))?;
        complete(&shown)?;
        warn_if_newer_incomplete(dir, &shown);
        return Ok(shown);
    }
    if latest.exists() {
        return Err(format!(
            "{}: no {FILE} (a run of an umbra before `umbra merge`, or not a conformance run); run the shard again with this umbra",
            latest.display()
        ));
    }
    // Run directories under `runs/`, or directly under DIR (an artifact of `OUT/runs/`).
    let mut complete = Vec::new();
    let mut incomplete = Vec::new();
    for parent in [dir.join("runs"), dir.to_path_buf()] {
        let Ok(entries) = std::fs::read_dir(&parent) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if let Ok(why) = std::fs::read_to_string(p.join(crate::run_dir::INCOMPLETE)) {
                incomplete.push(format!("{}: {}", p.display(), why.trim()));
            } else if p.join(FILE).is_file() {
                complete.push(p);
            }
        }
    }
    complete.sort();
    match complete.as_slice() {
        [one] => Ok(one.clone()),
        [] if !incomplete.is_empty() => Err(format!(
            "{}: the shard did not complete ({}); run it again",
            dir.display(),
            incomplete.join("; ")
        )),
        [] => Err(format!(
            "{}: no shard's results there (no {FILE}, no latest/{FILE}); give the --out directory of an `umbra conformance --shard I/N` run, or its runs/ID directory",
            dir.display()
        )),
        many => Err(format!(
            "{}: {} complete runs and no latest to choose between them ({}); give the runs/ID directory of the shard meant",
            dir.display(),
            many.len(),
            many.iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// Refuses a run directory that carries the INCOMPLETE marker, record or not (a full disk
/// while publishing leaves both).
fn complete(run: &Path) -> Result<(), String> {
    let marker = run.join(crate::run_dir::INCOMPLETE);
    if !marker.exists() {
        return Ok(());
    }
    let why = std::fs::read_to_string(&marker)
        .unwrap_or_else(|e| format!("its marker cannot be read: {e}"));
    Err(format!(
        "{}: the shard did not complete ({}); run it again",
        run.display(),
        why.trim()
    ))
}

/// Refuses an `-o` that is one of the shards (or holds one): the merge would replace that
/// shard's `latest`, or publish beside it.
fn out_apart(out: &Path, shards: &[Shard]) -> Result<(), String> {
    let out = std::fs::canonicalize(out).unwrap_or_else(|_| out.to_path_buf());
    for s in shards {
        let given = std::fs::canonicalize(&s.given).unwrap_or_else(|_| s.given.clone());
        if given.starts_with(&out) || s.run.starts_with(&out) {
            return Err(format!(
                "-o {} is one of the shards ({}): the merge would replace its latest; give -o a directory of its own",
                out.display(),
                s.given.display()
            ));
        }
    }
    Ok(())
}

/// A run under `dir/runs` newer than the one `latest` shows that did not complete (a shard
/// run again and interrupted): the merge takes the older, complete one, and says so.
fn warn_if_newer_incomplete(dir: &Path, shown: &Path) {
    let Ok(entries) = std::fs::read_dir(dir.join("runs")) else {
        return;
    };
    let shown_name = shown.file_name().unwrap_or_default().to_os_string();
    for e in entries.flatten() {
        let p = e.path();
        if p.file_name().unwrap_or_default() > shown_name.as_os_str() {
            if let Ok(why) = std::fs::read_to_string(p.join(crate::run_dir::INCOMPLETE)) {
                eprintln!(
                    "warning: {}: a newer run did not complete ({}); merging the complete one latest shows, {}",
                    dir.display(),
                    why.trim(),
                    shown.display()
                );
            }
        }
    }
}

/// The same build of umbra, cases, expectations, goldens, settings and Mesa build in every
/// shard.
fn same_inputs(shards: &[Shard]) -> Result<(), String> {
    let first = &shards[0];
    if let Some(s) = shards.iter().find(|s| s.record.umbra.key.is_empty()) {
        return Err(format!(
            "{} was run by an umbra whose build has no key (built outside its workspace, so its build script could not hash the sources); run the shards with umbra built from its workspace",
            s.label()
        ));
    }
    let differ = |what: &str, a: String, b: String, s: &Shard| {
        format!(
            "the shards are of different {what}: {} has {a}, {} has {b}; merge only the shards of one run (one commit, one toolchain, the same inputs)",
            first.label(),
            s.label()
        )
    };
    for s in &shards[1..] {
        let (a, b) = (&first.record, &s.record);
        if a.umbra != b.umbra {
            return Err(differ(
                "builds of umbra",
                format!(
                    "umbra {} build {} ({})",
                    a.umbra.version, a.umbra.key, a.umbra.toolchain
                ),
                format!(
                    "umbra {} build {} ({})",
                    b.umbra.version, b.umbra.key, b.umbra.toolchain
                ),
                s,
            ));
        }
        let digest = |d: &crate::shards::record::Digest| {
            format!("{} ({} files, digest {})", d.dir, d.files, d.digest)
        };
        if !a.inputs.cases.same(&b.inputs.cases) {
            return Err(differ(
                "case sets",
                digest(&a.inputs.cases),
                digest(&b.inputs.cases),
                s,
            ));
        }
        if !a.inputs.expectations.same(&b.inputs.expectations) {
            return Err(differ(
                "expectations",
                digest(&a.inputs.expectations),
                digest(&b.inputs.expectations),
                s,
            ));
        }
        let golden = |g: &Option<crate::shards::record::Digest>| {
            g.as_ref().map_or("--golden none".to_string(), digest)
        };
        let same_golden = match (&a.inputs.golden, &b.inputs.golden) {
            (Some(x), Some(y)) => x.same(y),
            (None, None) => true,
            _ => false,
        };
        if !same_golden {
            return Err(differ(
                "goldens",
                golden(&a.inputs.golden),
                golden(&b.inputs.golden),
                s,
            ));
        }
        if a.settings != b.settings {
            return Err(differ(
                "settings",
                format!(
                    "--timeout {} bless {}",
                    a.settings.timeout_s, a.settings.bless
                ),
                format!(
                    "--timeout {} bless {}",
                    b.settings.timeout_s, b.settings.bless
                ),
                s,
            ));
        }
    }
    same_mesa_build(shards)
}

/// The Mesa build (`--mesa`), by what it is, not where it lies (each job's checkout has its
/// own path), and only between shards that ran one of its drivers: a machine that ran only
/// hardware device ids did not use it.
fn same_mesa_build(shards: &[Shard]) -> Result<(), String> {
    let mesa_backed = |s: &&Shard| {
        s.record
            .plan
            .backends
            .iter()
            .any(|b| crate::harness::mesa_build::is_mesa_backed(b))
    };
    let identity = |s: &Shard| {
        let m = &s.record.mesa_build;
        serde_json::json!([m["layout"], m["version"], m["dri_drivers"]])
    };
    let mut on_mesa = shards.iter().filter(mesa_backed);
    if let Some(a) = on_mesa.next() {
        if let Some(b) = on_mesa.find(|b| identity(a) != identity(b)) {
            return Err(format!(
                "the shards ran Mesa's drivers from different Mesa builds: {} has {}, {} has {}; merge only the shards of one run",
                a.label(),
                a.record.mesa_line,
                b.label(),
                b.record.mesa_line
            ));
        }
    }
    Ok(())
}

/// Every plan whole: its shards split alike, none given twice, none missing.
fn complete_plans(shards: &[Shard]) -> Result<(), String> {
    // Shards of one plan: the same filter, backends and runs.
    let mut plans: BTreeMap<String, Vec<&Shard>> = BTreeMap::new();
    for s in shards {
        let p = &s.record.plan;
        let key = serde_json::json!([p.filter, p.backends, p.runs]).to_string();
        plans.entry(key).or_default().push(s);
    }
    for group in plans.values() {
        let first = group[0];
        let (count, by) = (first.record.shard.count, &first.record.shard.by);
        if let Some(s) = group
            .iter()
            .find(|s| s.record.shard.count != count || &s.record.shard.by != by)
        {
            return Err(format!(
                "{} and {} split one plan differently ({} by {by}; {} by {}); run every shard with the same --shard N and --durations file",
                first.label(),
                s.label(),
                count,
                s.record.shard.count,
                s.record.shard.by
            ));
        }
        let mut seen: BTreeMap<usize, &Shard> = BTreeMap::new();
        for s in group {
            if let Some(other) = seen.insert(s.record.shard.index, s) {
                return Err(format!(
                    "shard {}/{count} is given twice: {} and {}; give each shard once",
                    s.record.shard.index,
                    other.given.display(),
                    s.given.display()
                ));
            }
        }
        let missing: Vec<usize> = (0..count).filter(|i| !seen.contains_key(i)).collect();
        if !missing.is_empty() {
            let present: BTreeSet<&str> = group
                .iter()
                .flat_map(|s| s.runs.iter().map(String::as_str))
                .collect();
            let absent: Vec<&str> = first
                .record
                .plan
                .runs
                .iter()
                .map(String::as_str)
                .filter(|n| !present.contains(n))
                .collect();
            return Err(format!(
                "{} of the {count} shards missing: {}; their {} runs ({}{}) are in no directory given; add their directories, or run `umbra conformance --shard I/{count}` for each (with the same --filter {:?}, --backend and --durations as the others)",
                missing.len(),
                missing
                    .iter()
                    .map(|i| format!("{i}/{count}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                absent.len(),
                absent
                    .iter()
                    .take(3)
                    .copied()
                    .collect::<Vec<_>>()
                    .join(", "),
                if absent.len() > 3 { ", …" } else { "" },
                first.record.plan.filter
            ));
        }
        let present: BTreeSet<&String> = group.iter().flat_map(|s| &s.runs).collect();
        if let Some(lost) = first.record.plan.runs.iter().find(|n| !present.contains(n)) {
            return Err(format!(
                "run {lost} of the plan is in none of its {count} shards: the shards did not split one plan alike; run them again with one umbra"
            ));
        }
    }
    Ok(())
}

/// No run in two shards (shards of different plans, say two machines each running its own
/// backends, may be merged when they share no run).
fn disjoint(shards: &[Shard]) -> Result<(), String> {
    let mut owner: BTreeMap<&str, &Shard> = BTreeMap::new();
    for s in shards {
        for n in &s.runs {
            if let Some(other) = owner.insert(n, s) {
                return Err(format!(
                    "run {n} is in two shards, {} and {}: overlapping runs would count twice; merge shards of one plan, or plans that share no run",
                    other.label(),
                    s.label()
                ));
            }
        }
    }
    Ok(())
}

/// Each backend's driver, once. Shards that ran one backend id on different drivers (another
/// vendor, driver version or Mesa version: two kinds of machine under one id) are refused.
/// The same driver on different hosts may report another renderer or device (llvmpipe's
/// vector width on AVX2 and AVX-512 runners, another GPU of one kind): kept, with each
/// variant and its shards added to the backend's drivers.txt lines and printed.
fn drivers(shards: &[Shard]) -> Result<Vec<DriverRecord>, String> {
    type Field = fn(&umbra_report::DriverRow) -> &Option<String>;
    const SAME: [(&str, Field); 3] = [
        ("vendor", |r| &r.vendor),
        ("version", |r| &r.version),
        ("mesa", |r| &r.mesa),
    ];
    const NOTED: [(&str, Field); 2] = [("renderer", |r| &r.renderer), ("device", |r| &r.device)];
    // As the file writes a value: a string quoted, none as null.
    let shown = |v: &Option<String>| serde_json::json!(v).to_string();
    let mut by_backend: BTreeMap<String, (DriverRecord, &Shard)> = BTreeMap::new();
    let mut notes: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for s in shards {
        for d in &s.record.drivers {
            let Some((first, owner)) = by_backend.get(&d.backend) else {
                by_backend.insert(d.backend.clone(), (d.clone(), s));
                continue;
            };
            if let Some((k, f)) = SAME.iter().find(|(_, f)| f(&first.row) != f(&d.row)) {
                return Err(format!(
                    "{} ran on different drivers: {} has {k} {}, {} has {}; give each kind of machine its own backend ids, or merge shards of one kind",
                    d.backend,
                    owner.label(),
                    shown(f(&first.row)),
                    s.label(),
                    shown(f(&d.row))
                ));
            }
            for (k, f) in NOTED {
                if f(&first.row) != f(&d.row) {
                    notes.entry(d.backend.clone()).or_default().push(format!(
                        "  also {k} {} (shard {}), beside {} (shard {})\n",
                        shown(f(&d.row)),
                        s.label(),
                        shown(f(&first.row)),
                        owner.label()
                    ));
                }
            }
        }
    }
    Ok(by_backend
        .into_values()
        .map(|(mut d, _)| {
            for n in notes.remove(&d.backend).unwrap_or_default() {
                print!("note: {}{n}", d.backend);
                d.text.push_str(&n);
            }
            d
        })
        .collect())
}

/// Slowest over fastest shard, by wall and by worker time; each shard's figures.
fn print_balance(shards: &[Shard]) {
    println!("shards:");
    for s in shards {
        let b = &s.record.budget;
        println!(
            "  {:<8} {:>5} runs  {:>7.1} s wall  {:>7.1} s worker time  split by {}  {}",
            format!("{}/{}", s.record.shard.index, s.record.shard.count),
            s.runs.len(),
            b.wall_s,
            b.runs_s + b.worker_start_s,
            s.record.shard.by.split(' ').next().unwrap_or(""),
            s.given.display()
        );
    }
    if shards.len() > 1 {
        let walls: Vec<f64> = shards.iter().map(|s| s.record.budget.wall_s).collect();
        let work: Vec<f64> = shards
            .iter()
            .map(|s| s.record.budget.runs_s + s.record.budget.worker_start_s)
            .collect();
        let span = |v: &[f64]| {
            (
                v.iter().copied().fold(0.0, f64::max),
                v.iter().copied().fold(f64::INFINITY, f64::min),
            )
        };
        let ((wmax, wmin), (kmax, kmin)) = (span(&walls), span(&work));
        println!(
            "imbalance: slowest/fastest shard {:.2} by wall time ({wmax:.1} s / {wmin:.1} s), {:.2} by worker time ({kmax:.1} s / {kmin:.1} s)",
            crate::shards::balance::imbalance(&walls),
            crate::shards::balance::imbalance(&work)
        );
    }
}

/// Every shard's runs, with their fingerprints, sorted by name, then judged across runs
/// (`expect.error_falls_along`, the consensus) as one unsharded run judges them. A case file
/// that did not load is reported by every shard; it is kept once.
fn merged_results(shards: &[Shard]) -> Vec<RunResult> {
    let mut results: BTreeMap<String, RunResult> = BTreeMap::new();
    for s in shards {
        for r in &s.record.runs {
            let mut r = r.clone();
            r.fingerprint = s.record.fingerprints.get(&r.name).cloned();
            results.entry(r.name.clone()).or_insert(r);
        }
    }
    let mut results: Vec<RunResult> = results.into_values().collect();
    for f in &shards[0].record.falls_along {
        f.judge(&mut results);
    }
    crate::judge::consensus::diagnose(&mut results);
    results
}

/// The merged reports, with every shard's pictures linked (or copied across file systems)
/// under the merged run's `failures/` and `pictures/`, then published.
fn write(
    shards: &[Shard],
    results: &[RunResult],
    drivers: &[DriverRecord],
    budget: &TimeBudget,
    run_dir: &RunDir,
) -> std::io::Result<()> {
    let failures = run_dir.dir.join("failures");
    let pictures = run_dir.dir.join("pictures");
    for s in shards {
        link_tree(&s.run.join("failures"), &failures)?;
        link_tree(&s.run.join("pictures"), &pictures)?;
    }
    let lines: Vec<(String, String)> = drivers
        .iter()
        .map(|d| (d.backend.clone(), d.text.clone()))
        .collect();
    let text = crate::conformance::summary::drivers_text(&shards[0].record.mesa_line, &lines);
    let header = umbra_report::Header {
        mesa_build: shards[0].record.mesa_build.clone(),
        drivers: drivers.iter().map(|d| d.row.clone()).collect(),
        shards: Some(
            shards
                .iter()
                .map(|s| umbra_report::json::ShardRow {
                    index: s.record.shard.index,
                    count: s.record.shard.count,
                    by: s.record.shard.by.clone(),
                    runs: s.runs.len(),
                    wall_s: s.record.budget.wall_s,
                    worker_s: s.record.budget.runs_s + s.record.budget.worker_start_s,
                    dir: s.given.display().to_string(),
                })
                .collect(),
        ),
    };
    umbra_report::write_conformance(
        &run_dir.dir,
        &failures,
        &pictures,
        results,
        &text,
        header,
        budget,
    )?;
    run_dir.publish()
}

/// Every file under `from` at the same place under `to`: a hard link where the two are on
/// one file system, a copy where not. A missing `from` (a shard with no failures) is
/// nothing to do.
fn link_tree(from: &Path, to: &Path) -> std::io::Result<()> {
    if !from.is_dir() {
        return Ok(());
    }
    for f in crate::judge::basis_key::files_under(from)? {
        let rel = f.strip_prefix(from).unwrap_or(&f);
        let dest = to.join(rel);
        if let Some(parent) = dest.parent() {
            std::fs::create_dir_all(parent)?;
        }
        // Shared pictures (`pictures/.shared/HASH.png`, named by their contents) come from
        // every shard that showed them: kept once. Any other clash would be two shards'
        // different pictures under one name, which disjoint runs cannot give.
        if dest.exists() {
            if std::fs::read(&f)? == std::fs::read(&dest)? {
                continue;
            }
            return Err(std::io::Error::other(format!(
                "{} differs from the picture another shard left at {}",
                f.display(),
                dest.display()
            )));
        }
        if std::fs::hard_link(&f, &dest).is_err() {
            std::fs::copy(&f, &dest)?;
        }
    }
    Ok(())
}
