//! `umbra conformance`: every case point on every selected backend, judged, with results in
//! `OUT/latest/` (and a copy per run under `OUT/runs/<unix time>/`):
//! - `results.csv`: `test,status,duration` as Mesa's deqp-runner writes it;
//! - `errors.csv`: per run, the error figures against the truth and the pass timings.
//!
//! Exit codes: 0 all as expected, 1 a failure, 125 nothing could run (no case, no backend),
//! so `git bisect run` can drive it. This is the reference-only first cut; isolation,
//! expectations, goldens and the HTML report arrive with the conformance runner issue.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::args::Args;
use crate::run::{Outcome, describe, run_point};

/// Usage line.
pub const USAGE: &str =
    "umbra conformance [--cases DIR] [--filter GLOB] [--backend ID]... [--out DIR] [--verbose]";

/// Runs the command; returns the process exit code.
pub fn main(argv: &[String]) -> i32 {
    let args = match Args::parse(
        argv,
        &["cases", "filter", "backend", "out"],
        &["verbose", "child"],
    ) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}\nusage: {USAGE}");
            return 2;
        }
    };
    let cases_dir = PathBuf::from(args.value("cases").unwrap_or("cases"));
    let out = PathBuf::from(args.value("out").unwrap_or("target/umbra"));
    let filter = args.value("filter").unwrap_or("*");
    let mut ids: Vec<String> = args
        .values("backend")
        .iter()
        .map(|s| s.to_string())
        .collect();
    if ids.is_empty() {
        ids = crate::registry::known();
    }
    let files = match umbra_case::case_files(&cases_dir) {
        Ok(f) if !f.is_empty() => f,
        Ok(_) => {
            eprintln!("error: no *.json case under {}", cases_dir.display());
            return 125;
        }
        Err(e) => {
            eprintln!("error: cannot read {}: {e}", cases_dir.display());
            return 125;
        }
    };
    let mut rows: Vec<(String, &'static str, f64)> = Vec::new();
    let mut errors_csv = String::from(
        "test,status,judged,false_shadow,false_light,interior_judged,interior_false_shadow,interior_false_light,edge_px,silhouette,faces_away,outside,shadow_ms,lit_ms,total_ms,clock\n",
    );
    let mut failures = Vec::new();
    let started = Instant::now();
    let mut drivers = String::new();
    for backend_id in &ids {
        if !crate::registry::hostable_here(backend_id) {
            // Another Mesa driver: run this backend in a child process with its environment.
            let part = out
                .join("parts")
                .join(crate::render_cmd::file_name(backend_id));
            let mut child_args = vec![
                "conformance".to_string(),
                "--child".into(),
                "--backend".into(),
                backend_id.clone(),
            ];
            child_args.extend([
                "--cases".into(),
                cases_dir.display().to_string(),
                "--filter".into(),
                filter.to_string(),
                "--out".into(),
                part.display().to_string(),
            ]);
            if args.has("verbose") {
                child_args.push("--verbose".into());
            }
            let env = crate::registry::driver_env(backend_id).unwrap_or_default();
            let code = crate::child::rerun(&child_args, &env);
            match merge_part(
                &part.join("latest"),
                &mut rows,
                &mut errors_csv,
                &mut drivers,
            ) {
                Ok(()) if code == 0 || code == 1 => {}
                Ok(()) | Err(_) => {
                    let why = format!(
                        "{backend_id}: its driver process ended with code {code} before reporting every run"
                    );
                    println!("Crash {why}");
                    failures.push(why);
                    rows.push((format!("{backend_id}/*"), "Crash", 0.0));
                }
            }
            failures.extend(
                rows.iter()
                    .filter(|r| r.0.starts_with(&format!("{backend_id}/")) && r.1 == "Fail")
                    .map(|r| r.0.clone()),
            );
            continue;
        }
        // An unavailable backend (no libEGL, no driver) turns every run into a skip with the reason.
        let (mut backend, unavailable_reason) = match crate::registry::create(backend_id) {
            Ok(b) => (Some(b), None),
            Err(crate::registry::CreateError::Unknown(e)) => {
                eprintln!("error: {e}");
                return 125;
            }
            Err(crate::registry::CreateError::Unavailable(why)) => (None, Some(why)),
        };
        let line = match (&backend, &unavailable_reason) {
            (Some(b), _) => {
                let i = b.info();
                format!(
                    "{backend_id}: {} | {} | {} | {}",
                    i.vendor,
                    i.renderer,
                    i.version,
                    i.extensions.join(" ")
                )
            }
            (None, why) => format!(
                "{backend_id}: unavailable: {}",
                why.clone().unwrap_or_default()
            ),
        };
        println!("{line}");
        drivers.push_str(&line);
        drivers.push('\n');
        for file in &files {
            let points = match umbra_case::load_file(file) {
                Ok(p) => p,
                Err(e) => {
                    let name = format!("{}/{}", backend_id, file.display());
                    println!("Fail {name}: {e}");
                    failures.push(format!("{name}: {e}"));
                    rows.push((name, "Fail", 0.0));
                    continue;
                }
            };
            for point in points {
                let test = format!("{backend_id}/{}", point.id());
                if !crate::glob::matches(filter, &point.id())
                    && !crate::glob::matches(filter, &test)
                {
                    continue;
                }
                let t0 = Instant::now();
                let outcome = match (&mut backend, &unavailable_reason) {
                    (Some(b), _) => run_point(b.as_mut(), point),
                    (None, why) => Outcome::Skip(why.clone().unwrap_or_default()),
                };
                let secs = t0.elapsed().as_secs_f64();
                let status = match &outcome {
                    Outcome::Skip(why) => {
                        println!("Skip {test}: {why}");
                        "Skip"
                    }
                    Outcome::Error(e) => {
                        println!("Fail {test}: {e}");
                        failures.push(format!("{test}: {e}"));
                        "Fail"
                    }
                    Outcome::Done(j) => {
                        let status = if j.problems.is_empty() {
                            "Pass"
                        } else {
                            "Fail"
                        };
                        println!("{status} {test} ({:.0} ms)", secs * 1e3);
                        if args.has("verbose") || status == "Fail" {
                            println!("{}", describe(j));
                        }
                        for p in &j.problems {
                            println!("  problem: {p}");
                            failures.push(format!("{test}: {p}"));
                        }
                        if status == "Fail" {
                            let dir = out
                                .join("latest")
                                .join("failures")
                                .join(crate::render_cmd::file_name(&test));
                            if let Err(e) = crate::render_cmd::write_images(&dir, j) {
                                eprintln!(
                                    "warning: cannot write failure images to {}: {e}",
                                    dir.display()
                                );
                            }
                        }
                        let e = &j.error;
                        let t = &j.frame.timings;
                        let _ = writeln!(
                            errors_csv,
                            "{test},{status},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{}",
                            e.all.judged,
                            e.all.false_shadow,
                            e.all.false_light,
                            e.away_from_edges.judged,
                            e.away_from_edges.false_shadow,
                            e.away_from_edges.false_light,
                            e.edge_pixels,
                            e.silhouette,
                            e.faces_away,
                            e.outside,
                            t.shadow_pass.as_secs_f64() * 1e3,
                            t.lit_pass.as_secs_f64() * 1e3,
                            t.total.as_secs_f64() * 1e3,
                            if t.clock == Some(umbra_case::Clock::Gpu) {
                                "gpu"
                            } else {
                                "cpu-wall"
                            },
                        );
                        status
                    }
                };
                rows.push((test, status, secs));
            }
        }
    }
    if rows.is_empty() {
        eprintln!("error: --filter {filter:?} selects no run");
        return 125;
    }
    let mut results = String::new();
    for (test, status, secs) in &rows {
        let _ = writeln!(results, "{test},{status},{secs:.3}");
    }
    if let Err(e) = write_reports(&out, &results, &errors_csv, &drivers) {
        eprintln!("error: cannot write reports under {}: {e}", out.display());
        return 125;
    }
    let count = |s: &str| rows.iter().filter(|r| r.1 == s).count();
    println!(
        "\n{} runs in {:.1} s; reports in {}",
        rows.len(),
        started.elapsed().as_secs_f64(),
        out.join("latest").display()
    );
    if args.has("child") {
        // The parent prints the run's closing line; a driver process only reports its part.
        println!(
            "driver process done: {} pass, {} fail, {} skip",
            count("Pass"),
            count("Fail"),
            count("Skip")
        );
    } else {
        println!(
            "conformance: {} passed, {} failed, {} skipped",
            count("Pass"),
            count("Fail"),
            count("Skip")
        );
    }
    if failures.is_empty() { 0 } else { 1 }
}

/// Appends a child's `results.csv` and `errors.csv` rows to this run's.
fn merge_part(
    dir: &Path,
    rows: &mut Vec<(String, &'static str, f64)>,
    errors_csv: &mut String,
    drivers: &mut String,
) -> std::io::Result<()> {
    let results = std::fs::read_to_string(dir.join("results.csv"))?;
    for line in results.lines() {
        let mut f = line.rsplitn(3, ',');
        let (secs, status, test) = (
            f.next().unwrap_or("0"),
            f.next().unwrap_or(""),
            f.next().unwrap_or(""),
        );
        let status: &'static str = match status {
            "Pass" => "Pass",
            "Skip" => "Skip",
            "Crash" => "Crash",
            _ => "Fail",
        };
        rows.push((test.to_string(), status, secs.parse().unwrap_or(0.0)));
    }
    if let Ok(d) = std::fs::read_to_string(dir.join("drivers.txt")) {
        drivers.push_str(&d);
    }
    let errors = std::fs::read_to_string(dir.join("errors.csv"))?;
    for line in errors.lines().skip(1) {
        errors_csv.push_str(line);
        errors_csv.push('\n');
    }
    Ok(())
}

fn write_reports(out: &Path, results: &str, errors: &str, drivers: &str) -> std::io::Result<()> {
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    for dir in [out.join("latest"), out.join("runs").join(stamp.to_string())] {
        std::fs::create_dir_all(&dir)?;
        std::fs::write(dir.join("results.csv"), results)?;
        std::fs::write(dir.join("errors.csv"), errors)?;
        std::fs::write(dir.join("drivers.txt"), drivers)?;
    }
    Ok(())
}
