//! `umbra render CASE [--backend ID] [-o DIR] [--point GLOB]`: one case on one backend, for a
//! person at a desk. Writes colour, visibility, truth, error heat map and shadow map PNGs and
//! prints the error figures and timings of each sweep point. A run that breaks what the specs
//! allow lists its first illegal pixels with their intervals, and `--explain X,Y` prints the
//! reference's judged lookup at one pixel step by step: the evidence for a bug report, or
//! for a fix of umbra's model.

use std::path::{Path, PathBuf};

use crate::cli::RenderArgs;
use crate::exit::{Error, Exit};
use crate::judge::run::{Outcome, describe, run_point};

/// Runs the command; returns its outcome.
pub fn main(args: &RenderArgs) -> crate::exit::Outcome {
    let budget = crate::harness::memory_limit::select(args.max_memory.as_deref(), 1)
        .map_err(|e| crate::cli::usage_error("render", e))?;
    let build = crate::harness::mesa_build::select(args.mesa.as_deref()).map_err(Error::new)?;
    let case = &args.positional;
    let backend_id = args.backend.as_deref().unwrap_or("ref");
    let out = PathBuf::from(args.out.as_deref().unwrap_or("target/umbra/render"));
    if !crate::harness::registry::is_known(backend_id) {
        return Err(crate::cli::usage_error(
            "render",
            format!(
                "unknown backend {backend_id:?}; this build has: {} (`umbra backends` lists this machine's devices too)",
                crate::harness::registry::known().join(", ")
            ),
        ));
    }
    if !crate::harness::registry::hostable_here(backend_id) {
        let env = crate::harness::registry::worker_env(backend_id);
        // The same command line, in a process with the backend's environment.
        let again: Vec<String> = std::env::args().skip(1).collect();
        return crate::harness::child::rerun_for(backend_id, &again, &env);
    }
    let on_build = build.filter(|_| crate::harness::mesa_build::is_mesa_backed(backend_id));
    // Nothing that could not run exits 0: a skip of every point is 125, as conformance's
    // "nothing ran" is.
    if let Some(why) = on_build.and_then(|b| b.lacks(backend_id)) {
        println!("skip {backend_id}: {why}");
        return Err(Error::new(format!(
            "nothing ran: {backend_id} is a skip on this Mesa build"
        )));
    }
    if let Some(Err(e)) = on_build.map(crate::harness::mesa_build::MesaBuild::enter) {
        return Err(Error::new(format!("{backend_id}: {e}")));
    }
    let mut backend = match crate::harness::registry::create(backend_id) {
        Ok(b) => b,
        Err(crate::harness::registry::CreateError::Unknown(e)) => {
            return Err(crate::cli::usage_error("render", e));
        }
        Err(e) if on_build.is_some() => {
            return Err(Error::new(format!(
                "{backend_id}: the driver of the Mesa build did not load: {e}"
            )));
        }
        Err(e) => {
            println!("skip {backend_id}: {e}");
            return Err(Error::new(format!(
                "nothing ran: {backend_id} is not available here"
            )));
        }
    };
    if let Some(b) = on_build.filter(|b| b.layout != "fake (tests)") {
        crate::harness::mesa_build::check_loaded(
            &b.root,
            &crate::harness::mesa_build::loaded_libs(),
        )
        .map_err(|e| Error::new(format!("{backend_id}: {e}")))?;
        println!("{backend_id} on the Mesa build {}", b.describe());
    }
    // A case that cannot be read or is invalid: nothing could run, not a failure.
    let points = umbra_case::load_file(Path::new(case)).map_err(|e| Error::new(e.to_string()))?;
    let selected: Vec<_> = points
        .into_iter()
        .filter(|p| {
            args.point
                .as_deref()
                .is_none_or(|g| crate::glob::matches(g, &p.id()))
        })
        .collect();
    if selected.is_empty() {
        return Err(Error::new(format!(
            "--point {:?} matches no sweep point of {case}",
            args.point.as_deref().unwrap_or("")
        )));
    }
    // Refuse what cannot fit before anything renders, then watch what does.
    let mut estimated = 0;
    for p in &selected {
        let triangles = umbra_case::tessellate(&p.case.scene).triangles.len();
        let e = umbra_case::memory::estimate(&p.case, triangles);
        if let Some(why) = e.refuse(budget) {
            return Err(Error::new(format!("{case} point {}: {why}", p.id())));
        }
        estimated = estimated.max(e.total());
    }
    let explain = args
        .explain
        .as_deref()
        .map(parse_pixel)
        .transpose()
        .map_err(|e| crate::cli::usage_error("render", e))?;
    crate::harness::memory_limit::watch_self(budget);
    let many = selected.len() > 1;
    let mut failed = false;
    let mut ran = 0;
    for point in selected {
        let id = point.id();
        println!("{id} on {backend_id}");
        let outcome = run_point(backend.as_mut(), point, true);
        ran += usize::from(!matches!(outcome, Outcome::Skip(_)));
        match outcome {
            Outcome::Skip(why) => println!("  skip: {why}"),
            Outcome::Error(e) => {
                println!("  error: {e}");
                failed = true;
            }
            Outcome::Done(j) => {
                println!("{}", describe(&j));
                for p in &j.problems {
                    println!("  problem: {p}");
                    failed = true;
                }
                if explain.is_some() || !j.fingerprint.is_empty() {
                    print!("{}", explain_pixels(&j, backend.profile(), explain));
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
                        // A point that ran but whose pictures are lost fails.
                        eprintln!("error: cannot write images to {}: {e}", dir.display());
                        return Err(Error::said(Exit::Fail));
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
    if ran == 0 {
        return Err(Error::new(format!(
            "nothing ran: every point of {case} is a skip on {backend_id}"
        )));
    }
    Ok(Exit::pass_if(!failed))
}

fn value_ok_light(v: f32, l: &umbra_ref::PixelLegal, quantum: f32, eps: f32) -> bool {
    umbra_compare::reference::value_ok(v, l.lo, l.hi, quantum, eps)
}

/// How many illegal pixels `render` lists.
const LISTED: usize = 12;

/// The first illegal pixels of a judged run, each with its value and what the specs allow
/// there, and with `pixel` the reference's step-by-step trace of that pixel's judged lookup
/// (why its interval is what it is).
fn explain_pixels(
    j: &crate::judge::run::Judged,
    profile: umbra_case::Profile,
    pixel: Option<(u32, u32)>,
) -> String {
    use std::fmt::Write as _;
    let profile = profile.effective_for(j.prepared.case());
    let (basis, trace) = umbra_ref::explain(
        &j.prepared,
        umbra_case::ClipDepth::MinusOneToOne,
        profile,
        pixel,
    );
    let w = j.frame.width as usize;
    let mut s = String::new();
    let failed = &j.fingerprint.frame;
    if failed.total > 0 {
        let _ = writeln!(
            s,
            "  illegal pixels ({} in all; x, y top-left, the backend's value, the interval a conformant {} implementation may return, why it is that wide):",
            failed.total,
            profile.name()
        );
    }
    for e in failed.entries.iter().take(LISTED) {
        let i = (*e >> 1) as usize;
        let l = basis.legal[i];
        let v = j.frame.visibility[i];
        let eps = j.frame.visibility_storage.tolerance();
        let lights: Vec<(f32, umbra_ref::PixelLegal)> = (0..basis.light_count())
            .filter(|&k| k < j.frame.light_count())
            .map(|k| {
                let b = basis.for_light(k);
                (j.frame.for_light(k).visibility[i], b.legal[i])
            })
            .collect();
        let all_legal = (0..lights.len()).all(|k| {
            let (v, l) = lights[k];
            value_ok_light(v, &l, basis.for_light(k).quantum, eps)
        });
        if lights.len() > 1 && all_legal {
            // Every light's value legal, and a colour that is not the sum of their shadings.
            let rgb = &j.frame.color[i * 4..i * 4 + 3];
            let sum = |c: usize| {
                lights
                    .iter()
                    .map(|(v, l)| l.c0[c] + (l.c1[c] - l.c0[c]) * v)
                    .sum::<f32>()
            };
            let visibilities: Vec<f32> = lights.iter().map(|(v, _)| *v).collect();
            let _ = writeln!(
                s,
                "    ({}, {}): the lights' visibilities {visibilities:?} are legal, but the colour {rgb:?} is not the sum of their shadings {:?} (×255: {:?}; each light's tolerance, and each pass after the first its stored code)",
                i % w,
                i / w,
                [sum(0), sum(1), sum(2)],
                [sum(0) * 255.0, sum(1) * 255.0, sum(2) * 255.0],
            );
            continue;
        }
        if umbra_compare::reference::value_ok(v, l.lo, l.hi, basis.quantum, eps)
            && lights.len() == 1
        {
            // A legal value with a colour that is not its shading (or another surface).
            let rgb = &j.frame.color[i * 4..i * 4 + 3];
            let shade = |c: usize| l.c0[c] + (l.c1[c] - l.c0[c]) * v;
            let _ = writeln!(
                s,
                "    ({}, {}): visibility {v} is legal, but the colour {rgb:?} is not its shading {:?} ± {} per channel (×255: {:?})",
                i % w,
                i / w,
                [shade(0), shade(1), shade(2)],
                l.ctol,
                [shade(0) * 255.0, shade(1) * 255.0, shade(2) * 255.0],
            );
            continue;
        }
        let _ = writeln!(
            s,
            "    ({}, {}): {v} not in [{}, {}] ({}); the reference gives {}",
            i % w,
            i / w,
            l.lo,
            l.hi,
            flag_names(l.flags),
            basis.frame.visibility[i],
        );
    }
    if let (Some(map), Some(failed)) = (&j.frame.shadow_map, &j.fingerprint.map) {
        if failed.total > 0 {
            let _ = writeln!(
                s,
                "  illegal shadow-map texels ({} in all; layer, x, y top-left, the stored value, the range a conformant implementation may store):",
                failed.total
            );
        }
        let per_layer = (map.width * map.height) as usize;
        for e in failed.entries.iter().take(LISTED) {
            let k = (*e >> 1) as usize;
            let (layer, t) = (k / per_layer, k % per_layer);
            let (lo, hi) = basis.map.get(k).copied().unwrap_or((f32::NAN, f32::NAN));
            let _ = writeln!(
                s,
                "    layer {layer} ({}, {}): {} not in [{lo}, {hi}]; the reference stores {}",
                t % map.width as usize,
                t / map.width as usize,
                map.values[k],
                basis
                    .frame
                    .shadow_map
                    .as_ref()
                    .and_then(|m| m.values.get(k))
                    .copied()
                    .unwrap_or(f32::NAN),
            );
        }
    }
    if let Some((x, y)) = pixel {
        let i = y as usize * w + x as usize;
        match (j.frame.visibility.get(i), basis.legal.get(i)) {
            (Some(v), Some(l)) => {
                let _ = writeln!(
                    s,
                    "  pixel ({x}, {y}): the backend gives {v}, legal [{}, {}] ({}); the reference's judged lookup:",
                    l.lo,
                    l.hi,
                    flag_names(l.flags)
                );
                for line in trace.lines() {
                    let _ = writeln!(s, "    {line}");
                }
            }
            _ => {
                let _ = writeln!(
                    s,
                    "  pixel ({x}, {y}) is outside the {}x{} frame",
                    j.frame.width, j.frame.height
                );
            }
        }
    }
    s
}

/// The names of a pixel's ambiguity flags, or `exact`.
fn flag_names(flags: u8) -> String {
    use umbra_ref::lookup::ambiguity as a;
    let names: Vec<&str> = [
        (a::DEPTH_TIE, "depth tie"),
        (a::TEXEL_BOUNDARY, "texel"),
        (a::FILTER, "filter"),
        (a::POSITION, "position"),
        (a::COVERAGE, "coverage"),
        (a::SEAM, "seam"),
        (a::SURFACE, "other surface"),
        (a::LOD, "mip level"),
    ]
    .into_iter()
    .filter(|(f, _)| flags & f != 0)
    .map(|(_, n)| n)
    .collect();
    if names.is_empty() {
        "exact".into()
    } else {
        names.join(", ")
    }
}

/// `X,Y` → (x, y).
fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("--explain takes a pixel as X,Y (top-left origin), got {s:?}");
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    Ok((
        x.trim().parse().map_err(|_| bad())?,
        y.trim().parse().map_err(|_| bad())?,
    ))
}
