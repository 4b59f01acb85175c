//! `umbra render CASE [--backend ID] [-o DIR] [--point GLOB]`: one case on one backend, for a
//! person at a desk. Writes colour, visibility, truth, error heat map and shadow map PNGs and
//! prints the error figures and timings of each sweep point.

use std::path::{Path, PathBuf};

use crate::args::Args;
use crate::judge::run::{Outcome, describe, run_point};

/// Runs the command; returns the process exit code.
pub fn main(args: &Args) -> i32 {
    let budget = match crate::harness::memory_limit::select(args.value("max-memory"), 1) {
        Ok(b) => b,
        Err(e) => return usage_error(&e),
    };
    let build = match crate::harness::mesa_build::select(args.value("mesa")) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            return 125;
        }
    };
    let [case] = args.positional.as_slice() else {
        return usage_error("give exactly one case file");
    };
    let backend_id = args.value("backend").unwrap_or("ref");
    let out = PathBuf::from(args.value("out").unwrap_or("target/umbra/render"));
    if !crate::harness::registry::hostable_here(backend_id) {
        let env = crate::harness::registry::worker_env(backend_id);
        // The same command line, in a process with the backend's environment.
        let again: Vec<String> = std::env::args().skip(1).collect();
        return crate::harness::child::rerun(&again, &env);
    }
    let on_build = build.filter(|_| crate::harness::mesa_build::is_mesa_backed(backend_id));
    if let Some(why) = on_build.and_then(|b| b.lacks(backend_id)) {
        println!("skip {backend_id}: {why}");
        return 0;
    }
    let mut backend = match crate::harness::registry::create(backend_id) {
        Ok(b) => b,
        Err(crate::harness::registry::CreateError::Unknown(e)) => return usage_error(&e),
        Err(e) if on_build.is_some() => {
            eprintln!("error: {backend_id}: the driver of the Mesa build did not load: {e}");
            return 125;
        }
        Err(e) => {
            println!("skip {backend_id}: {e}");
            return 0;
        }
    };
    if let Some(b) = on_build.filter(|b| b.layout != "fake (tests)") {
        if let Err(e) = crate::harness::mesa_build::check_loaded(
            &b.root,
            &crate::harness::mesa_build::loaded_libs(),
        ) {
            eprintln!("error: {backend_id}: {e}");
            return 125;
        }
        println!("{backend_id} on the Mesa build {}", b.describe());
    }
    let points = match umbra_case::load_file(Path::new(case)) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    let selected: Vec<_> = points
        .into_iter()
        .filter(|p| {
            args.value("point")
                .is_none_or(|g| crate::glob::matches(g, &p.id()))
        })
        .collect();
    if selected.is_empty() {
        eprintln!(
            "error: --point {:?} matches no sweep point of {case}",
            args.value("point").unwrap_or("")
        );
        return 1;
    }
    // Refuse what cannot fit before anything renders, then watch what does.
    let mut estimated = 0;
    for p in &selected {
        let triangles = umbra_case::tessellate(&p.case.scene).triangles.len();
        let e = umbra_case::memory::estimate(&p.case, triangles);
        if let Some(why) = e.refuse(budget) {
            eprintln!("error: {case} point {}: {why}", p.id());
            return 125;
        }
        estimated = estimated.max(e.total());
    }
    crate::harness::memory_limit::watch_self(budget);
    let many = selected.len() > 1;
    let mut code = 0;
    for point in selected {
        let id = point.id();
        println!("{id} on {backend_id}");
        match run_point(backend.as_mut(), point, true) {
            Outcome::Skip(why) => println!("  skip: {why}"),
            Outcome::Error(e) => {
                println!("  error: {e}");
                code = 1;
            }
            Outcome::Done(j) => {
                println!("{}", describe(&j));
                for p in &j.problems {
                    println!("  problem: {p}");
                    code = 1;
                }
                let dir = if many {
                    out.join(umbra_report::names::file_name(&id))
                } else {
                    out.clone()
                };
                match crate::judge::pictures::write_images(&dir, &j) {
                    Ok(()) => println!(
                        "  wrote {}/{{color,visibility,truth,error,shadow_map}}.png",
                        dir.display()
                    ),
                    Err(e) => {
                        eprintln!("error: cannot write images to {}: {e}", dir.display());
                        return 1;
                    }
                }
            }
        }
    }
    if let Some(peak) = crate::harness::memory_limit::peak_self() {
        println!(
            "memory: peak resident {} (estimate {}, budget {})",
            umbra_case::memory::gib(peak),
            umbra_case::memory::gib(estimated),
            umbra_case::memory::gib(budget)
        );
    }
    code
}

fn usage_error(msg: &str) -> i32 {
    eprintln!("error: {msg}\nusage: {}", crate::cli::usage("render"));
    2
}
