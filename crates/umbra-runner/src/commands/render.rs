//! `umbra render CASE [--backend ID] [-o DIR] [--point GLOB]`: one case on one backend, for a
//! person at a desk. Writes colour, visibility, truth, error heat map and shadow map PNGs and
//! prints the error figures and timings of each sweep point. A run that breaks what the specs
//! allow lists its first illegal pixels with their intervals, and `--explain X,Y` prints the
//! reference's judged lookup at one pixel step by step: the evidence for a bug report, or
//! for a fix of umbra's model.

use crate::cli::RenderArgs;
use crate::exit::{Error, Exit};
use crate::judge::run::{Outcome, describe, run_point};

/// Runs the command; returns its outcome.
pub fn main(args: &RenderArgs) -> crate::exit::Outcome {
    let budget = crate::harness::memory_limit::select(args.max_memory.map(|b| b.0), 1)
        .map_err(|e| crate::cli::usage_error("render", e))?;
    let build = crate::harness::mesa_build::select(args.mesa.as_ref()).map_err(Error::new)?;
    let case = &args.positional.display();
    let backend_id = args
        .backend
        .as_ref()
        .map_or("ref", crate::cli::BackendName::as_str);
    let out = args.out.clone();
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
    let (selected, estimated) = points_within(args, budget)?;
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

/// The case's points `--point` selects, each refused (before anything renders) if it cannot
/// fit in `budget` bytes, and the largest estimate. A case that cannot be read or is invalid,
/// or a `--point` that selects nothing: nothing could run, not a failure.
fn points_within(
    args: &RenderArgs,
    budget: u64,
) -> Result<(Vec<umbra_case::CasePoint>, u64), Error> {
    let case = args.positional.display();
    let points = umbra_case::load_file(&args.positional).map_err(|e| Error::new(e.to_string()))?;
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
    let mut estimated = 0;
    for p in &selected {
        let triangles = umbra_case::tessellate(&p.case.scene).triangles.len();
        let e = umbra_case::memory::estimate(&p.case, triangles);
        if let Some(why) = e.refuse(budget) {
            return Err(Error::new(format!("{case} point {}: {why}", p.id())));
        }
        estimated = estimated.max(e.total());
    }
    Ok((selected, estimated))
}

/// How many illegal pixels `render` lists.
const LISTED: usize = 12;

/// The first illegal pixels of a judged run, each with every light's value and what the specs
/// allow there, the first illegal map texels, and with `pixel` the reference's step-by-step
/// trace of that pixel's judged lookup in every light (why its interval is what it is).
fn explain_pixels(
    j: &crate::judge::run::Judged,
    profile: umbra_case::Profile,
    pixel: Option<(u32, u32)>,
) -> String {
    use std::fmt::Write as _;
    // Each light judged for its own effective profile, as the judge judges it.
    let mut each = Vec::new();
    let mut trace = String::new();
    for (k, light) in j.prepared.lights.iter().enumerate() {
        let (judged, t) = umbra_ref::explain_light(
            light,
            umbra_case::ClipDepth::MinusOneToOne,
            profile.effective_for(light.case()),
            pixel,
        );
        if !t.is_empty() {
            trace += &format!("light {k}:\n{t}");
        }
        each.push(judged);
    }
    let case = j.prepared.case();
    let profile = profile.effective_for(case);
    let basis = umbra_ref::Judged::of_lights(each, profile, case.camera.color_format);
    let mut s = String::new();
    let failed = &j.fingerprint.frame;
    if failed.total > 0 {
        let _ = writeln!(
            s,
            "  illegal pixels ({} in all; x, y top-left, each light's value, the interval a conformant {} implementation may return, why it is that wide):",
            failed.total,
            profile.name()
        );
    }
    for e in failed.entries.iter().take(LISTED) {
        s += &illegal_pixel(&j.frame, &basis, (*e >> 1) as usize);
    }
    s += &illegal_texels(&j.frame, &basis, j.fingerprint.map.as_ref());
    if let Some((x, y)) = pixel {
        let i = y as usize * j.frame.width as usize + x as usize;
        if i >= (j.frame.width * j.frame.height) as usize || x >= j.frame.width {
            let _ = writeln!(
                s,
                "  pixel ({x}, {y}) is outside the {}x{} frame",
                j.frame.width, j.frame.height
            );
            return s;
        }
        for (k, l) in basis.lights.iter().enumerate() {
            let v = j.frame.light(k).map_or(f32::NAN, |f| f.visibility[i]);
            let l = l.legal[i];
            let _ = writeln!(
                s,
                "  pixel ({x}, {y}), light {k}: the backend gives {v}, legal [{}, {}] ({})",
                l.lo,
                l.hi,
                flag_names(l.flags)
            );
        }
        let _ = writeln!(s, "  the reference's judged lookup:");
        for line in trace.lines() {
            let _ = writeln!(s, "    {line}");
        }
    }
    s
}

/// One illegal pixel's line: every light's value legal and a colour that is not the sum of
/// their shadings, or each light's value outside its interval.
fn illegal_pixel(frame: &umbra_case::Frame, basis: &umbra_ref::Judged, i: usize) -> String {
    use std::fmt::Write as _;
    let w = frame.width as usize;
    let eps = frame.visibility_storage.tolerance();
    let lights: Vec<(f32, &umbra_ref::JudgedLight)> = basis
        .lights
        .iter()
        .enumerate()
        .map(|(k, l)| (frame.light(k).map_or(f32::NAN, |f| f.visibility[i]), l))
        .collect();
    let legal = |(v, l): &(f32, &umbra_ref::JudgedLight)| {
        let p = l.legal[i];
        umbra_compare::reference::value_ok(*v, p.lo, p.hi, l.quantum, eps)
    };
    let mut s = String::new();
    if lights.iter().all(legal) {
        // Every light's value legal, and a colour that is not the sum of their shadings
        // (each light's tolerance, and each pass after the first its stored code).
        let rgb = &frame.color[i * 4..i * 4 + 3];
        let sum = |c: usize| {
            lights
                .iter()
                .map(|(v, l)| l.legal[i].c0[c] + (l.legal[i].c1[c] - l.legal[i].c0[c]) * v)
                .sum::<f32>()
        };
        let visibilities: Vec<f32> = lights.iter().map(|(v, _)| *v).collect();
        let tolerance: f32 = lights.iter().map(|(_, l)| l.legal[i].ctol).sum();
        let _ = writeln!(
            s,
            "    ({}, {}): the visibilities {visibilities:?} are legal, but the colour {rgb:?} is not their shading {:?} ± {tolerance} per channel (×255: {:?})",
            i % w,
            i / w,
            [sum(0), sum(1), sum(2)],
            [sum(0) * 255.0, sum(1) * 255.0, sum(2) * 255.0],
        );
        return s;
    }
    for (k, (v, l)) in lights.iter().enumerate().filter(|(_, x)| !legal(x)) {
        let p = l.legal[i];
        let _ = writeln!(
            s,
            "    ({}, {}), light {k}: {v} not in [{}, {}] ({}); the reference gives {}",
            i % w,
            i / w,
            p.lo,
            p.hi,
            flag_names(p.flags),
            basis.frame.light(k).map_or(f32::NAN, |f| f.visibility[i]),
        );
    }
    s
}

/// The first illegal map texels (`failed`, every light's texels numbered on from the previous
/// lights', [`umbra_compare::reference::map_failures`]), each with its light, layer and range.
fn illegal_texels(
    frame: &umbra_case::Frame,
    basis: &umbra_ref::Judged,
    failed: Option<&umbra_compare::consensus::Failed>,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let Some(failed) = failed.filter(|f| f.total > 0) else {
        return s;
    };
    let _ = writeln!(
        s,
        "  illegal shadow-map texels ({} in all; light, layer, x, y top-left, the stored value, the range a conformant implementation may store):",
        failed.total
    );
    for e in failed.entries.iter().take(LISTED) {
        // The light whose texels the index falls in.
        let mut k = (*e >> 1) as usize;
        let mut light = 0;
        while light < basis.lights.len() && k >= basis.lights[light].map.len() {
            k -= basis.lights[light].map.len();
            light += 1;
        }
        let (Some(map), Some(judged)) = (
            frame.light(light).and_then(|f| f.shadow_map),
            basis.lights.get(light),
        ) else {
            continue;
        };
        let per_layer = (map.width * map.height) as usize;
        let (layer, t) = (k / per_layer, k % per_layer);
        let (lo, hi) = judged.map.get(k).copied().unwrap_or((f32::NAN, f32::NAN));
        let _ = writeln!(
            s,
            "    light {light} layer {layer} ({}, {}): {} not in [{lo}, {hi}]; the reference stores {}",
            t % map.width as usize,
            t / map.width as usize,
            map.values.get(k).copied().unwrap_or(f32::NAN),
            basis
                .frame
                .light(light)
                .and_then(|f| f.shadow_map)
                .and_then(|m| m.values.get(k))
                .copied()
                .unwrap_or(f32::NAN),
        );
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
