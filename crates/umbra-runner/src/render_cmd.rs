//! `umbra render CASE [--backend ID] [-o DIR] [--point GLOB]`: one case on one backend, for a
//! person at a desk. Writes colour, visibility, truth, error heat map and shadow map PNGs and
//! prints the error figures and timings of each sweep point.

use std::path::{Path, PathBuf};

use umbra_compare::heatmap;

use crate::args::Args;
use crate::run::{Outcome, describe, run_point};

/// Usage line.
pub const USAGE: &str = "umbra render CASE.json [--backend ref|gl33/llvmpipe|gles2/zink|...] [-o DIR] [--point GLOB] [--mesa PREFIX|BUILD_DIR|system] [--max-memory SIZE]";

/// Runs the command; returns the process exit code.
pub fn main(argv: &[String]) -> i32 {
    let args = match Args::parse(
        argv,
        &["backend", "o", "out", "point", "mesa", "max-memory"],
        &[],
    ) {
        Ok(a) => a,
        Err(e) => return usage_error(&e),
    };
    let budget = match crate::memory_limit::select(args.value("max-memory"), 1) {
        Ok(b) => b,
        Err(e) => return usage_error(&e),
    };
    let build = match crate::mesa_build::select(args.value("mesa")) {
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
    let out = PathBuf::from(
        args.value("o")
            .or(args.value("out"))
            .unwrap_or("target/umbra/render"),
    );
    if !crate::registry::hostable_here(backend_id) {
        let env = crate::registry::worker_env(backend_id);
        let mut again = vec!["render".to_string()];
        again.extend(argv.iter().cloned());
        return crate::child::rerun(&again, &env);
    }
    let on_build = build.filter(|_| crate::mesa_build::is_mesa_backed(backend_id));
    if let Some(why) = on_build.and_then(|b| b.lacks(backend_id)) {
        println!("skip {backend_id}: {why}");
        return 0;
    }
    let mut backend = match crate::registry::create(backend_id) {
        Ok(b) => b,
        Err(crate::registry::CreateError::Unknown(e)) => return usage_error(&e),
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
        if let Err(e) = crate::mesa_build::check_loaded(&b.root, &crate::mesa_build::loaded_libs())
        {
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
    crate::memory_limit::watch_self(budget);
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
                    out.join(file_name(&id))
                } else {
                    out.clone()
                };
                match write_images(&dir, &j) {
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
    if let Some(peak) = crate::memory_limit::peak_self() {
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
    eprintln!("error: {msg}\nusage: {USAGE}");
    2
}

/// A run id as a file name (`/` and other awkward characters replaced).
pub fn file_name(id: &str) -> String {
    let plain: String = id
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.=@,".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    // File systems stop at 255 bytes; long sweep ids (JSON values) keep a prefix and a hash.
    if plain.len() <= 120 {
        plain
    } else {
        format!("{}-{:08x}", &plain[..100], crate::golden::fnv1a(id))
    }
}

/// Writes the images of a judged run into `dir`.
pub fn write_images(dir: &Path, j: &crate::run::Judged) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let f = &j.frame;
    image::save_buffer(
        dir.join("color.png"),
        &f.color,
        f.width,
        f.height,
        image::ColorType::Rgba8,
    )?;
    heatmap::visibility_map(&f.visibility, f.width, f.height)
        .save_png(&dir.join("visibility.png"))?;
    heatmap::truth_map(&j.truth).save_png(&dir.join("truth.png"))?;
    heatmap::truth_error_map(&j.error, &j.truth).save_png(&dir.join("error.png"))?;
    if let Some(r) = &j.reference {
        image::save_buffer(
            dir.join("reference.png"),
            &r.color,
            r.width,
            r.height,
            image::ColorType::Rgba8,
        )?;
    }
    if let Some(m) = &f.shadow_map {
        // Layers stacked top to bottom (cube faces +x, −x, +y, −y, +z, −z).
        heatmap::depth_map(&m.values, m.width, m.height * m.layers)
            .save_png(&dir.join("shadow_map.png"))?;
    }
    Ok(())
}
