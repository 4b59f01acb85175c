//! Each backend's frame (shadow pass + lit pass, on the clock shown; wall ms adds set-up and
//! readback) for the standard scene (the packed cubes with the light behind them,
//! as written: 1024² D24 map, NEAREST, polygon offset 2/4, 384² view), median of 9 renders
//! after a warm-up, every backend in its own worker process and one after the other in this
//! one run, so the ratios between them are measured side by side. The clock column says
//! whether a time comes from GPU timer queries or CPU wall.
//!
//! Then the catalogue's largest frames, the reference beside gl33/llvmpipe in the same way:
//! the point with the most view pixels and the point with the most shadow-map texels (all
//! faces), each passes' times and their ratio.
//!
//! Then the reference's own passes on 1 thread and on every core (Mpixels/s of the map and of
//! the view), and the per-stage share of the latest conformance run in this target directory
//! (target/umbra/latest/report.json), when there is one: `cargo xtask conformance` measures
//! it on every run (frames, twins, judging, PNG encoding, worker start).
//!
//! `cargo bench -p umbra-runner --bench frames`

use std::path::Path;
use std::time::Duration;

use umbra_runner::commands::sweep::{DEFAULT_SCENE, measure_backends};

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let exe = Path::new(env!("CARGO_BIN_EXE_umbra"));
    let file = root.join(DEFAULT_SCENE.0);
    let points = umbra_case::load_file(&file).unwrap_or_else(|e| panic!("{e}"));
    let index = points
        .iter()
        .position(|p| p.id() == DEFAULT_SCENE.1)
        .expect("the standard point");
    every_backend(exe, &points[index]);
    largest_frames(exe, &root);
    reference_per_thread_count(exe, &points[index]);
    latest_conformance_stages(&root);
}

/// The standard point on every backend, side by side, with each one's ratio to the reference
/// and to gl33/llvmpipe.
fn every_backend(exe: &Path, point: &umbra_case::CasePoint) {
    // Every backend, each in a worker with its driver's environment (a backend whose driver is
    // missing says so in its row).
    let backends: Vec<String> = umbra_runner::harness::registry::known();
    println!(
        "{} on every backend, median of 9 after a warm-up:",
        DEFAULT_SCENE.1
    );
    let results = measure_backends(exe, point, &backends, 9, Duration::from_secs(600), &[]);
    let total = |b: &str| {
        results
            .iter()
            .find(|(id, _)| id == b)
            .and_then(|(_, r)| r.as_ref().ok())
            .map(|m| m.frame_ms)
    };
    let (reference, llvmpipe) = (total("ref"), total("gl33/llvmpipe"));
    println!(
        "{:<18} {:>10} {:>10} {:>10} {:>9} {:>10} {:>11} {:>15}",
        "backend",
        "shadow ms",
        "lit ms",
        "frame ms",
        "clock",
        "wall ms",
        "vs ref",
        "vs gl33/llvmpipe"
    );
    for (b, r) in &results {
        match r {
            Ok(m) => println!(
                "{b:<18} {:>10.2} {:>10.2} {:>10.2} {:>9} {:>10.2} {:>10.2}x {:>14.2}x",
                m.shadow_ms,
                m.lit_ms,
                m.frame_ms,
                m.clock,
                m.total_ms,
                reference.map_or(f64::NAN, |x| m.frame_ms / x),
                llvmpipe.map_or(f64::NAN, |x| m.frame_ms / x),
            ),
            Err(e) => println!("{b:<18} not measured: {e}"),
        }
    }
    if let (Some(r), Some(l)) = (reference, llvmpipe) {
        println!(
            "reference / gl33/llvmpipe frame time, same frame, same run: {:.2}",
            r / l
        );
    }
}

/// The catalogue's points as (the point, view pixels, map texels over every face, id).
fn catalogue_sizes(root: &Path) -> Vec<(umbra_case::CasePoint, u64, u64, String)> {
    let mut catalogue: Vec<(umbra_case::CasePoint, u64, u64, String)> = Vec::new();
    let files = umbra_case::case_files(&root.join("cases")).unwrap_or_default();
    for f in &files {
        for p in umbra_case::load_file(f).unwrap_or_default() {
            let [w, h] = p.case.camera.size;
            let [mw, mh] = p.case.shadow.size;
            // Every light's map: a cube's six faces, else one.
            let faces: u64 = p
                .case
                .lights
                .iter()
                .map(|l| {
                    if matches!(l, umbra_case::format::Light::Point(_)) {
                        6
                    } else {
                        1
                    }
                })
                .sum();
            let id = p.id();
            catalogue.push((
                p,
                u64::from(w) * u64::from(h),
                u64::from(mw) * u64::from(mh) * faces,
                id,
            ));
        }
    }
    catalogue
}

/// The catalogue's largest frames (most view pixels, most map texels), the reference beside
/// gl33/llvmpipe.
fn largest_frames(exe: &Path, root: &Path) {
    // The catalogue's largest frames: most view pixels, most map texels (every face).
    let catalogue = catalogue_sizes(root);
    let largest_view = catalogue.iter().max_by_key(|p| (p.1, p.2));
    let largest_map = catalogue.iter().max_by_key(|p| (p.2, p.1));
    for (what, p) in [
        ("most view pixels", largest_view),
        ("most map texels", largest_map),
    ] {
        let Some((point, view, texels, id)) = p else {
            continue;
        };
        let r = measure_backends(
            exe,
            point,
            &["ref".to_string(), "gl33/llvmpipe".to_string()],
            9,
            Duration::from_secs(600),
            &[],
        );
        let get = |b: &str| {
            r.iter()
                .find(|(id, _)| id == b)
                .and_then(|(_, m)| m.as_ref().ok())
        };
        match (get("ref"), get("gl33/llvmpipe")) {
            (Some(a), Some(b)) => println!(
                "largest frame ({what}: {id}, {view} px, {texels} texels): reference shadow {:.2} + lit {:.2} = {:.2} ms, gl33/llvmpipe {:.2} + {:.2} = {:.2} ms ({}); ratio {:.2} (shadow {:.2}, lit {:.2})",
                a.shadow_ms,
                a.lit_ms,
                a.frame_ms,
                b.shadow_ms,
                b.lit_ms,
                b.frame_ms,
                b.clock,
                a.frame_ms / b.frame_ms,
                a.shadow_ms / b.shadow_ms,
                a.lit_ms / b.lit_ms
            ),
            _ => println!(
                "largest frame ({what}: {id}): not measured: {r:?}",
                r = r
                    .iter()
                    .map(|(b, m)| (b, m.as_ref().err()))
                    .collect::<Vec<_>>()
            ),
        }
    }
}

/// The reference's passes on 1 thread and on every core, in Mpixels/s of the map and the view.
fn reference_per_thread_count(exe: &Path, point: &umbra_case::CasePoint) {
    // The reference's passes per thread count, in the same run: its worker inherits
    // RAYON_NUM_THREADS (the judged variant is not timed here: see judging in the time budget).
    let view = {
        let [w, h] = point.case.camera.size;
        f64::from(w * h)
    };
    let map = {
        let [w, h] = point.case.shadow.size;
        f64::from(w * h)
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for threads in [1, cores] {
        let env = [("RAYON_NUM_THREADS".to_string(), threads.to_string())];
        let r = measure_backends(
            exe,
            point,
            &["ref".to_string()],
            9,
            Duration::from_secs(600),
            &env,
        );
        match r.first().map(|(_, r)| r) {
            Some(Ok(m)) => println!(
                "reference on {threads} thread(s): shadow pass {:.2} ms = {:.0} Mpixels/s, lit pass {:.2} ms = {:.1} Mpixels/s, frame {:.2} ms",
                m.shadow_ms,
                map / m.shadow_ms / 1e3,
                m.lit_ms,
                view / m.lit_ms / 1e3,
                m.frame_ms
            ),
            Some(Err(e)) => println!("reference on {threads} thread(s): not measured: {e}"),
            None => {}
        }
    }
}

/// The per-stage share of the latest conformance run in this target directory, when there is
/// one.
fn latest_conformance_stages(root: &Path) {
    match std::fs::read_to_string(root.join("target/umbra/latest/report.json")) {
        Ok(text) => {
            let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
            match v.get("harness_overhead_share").and_then(|x| x.as_f64()) {
                Some(share) => {
                    let b = &v["time_budget"];
                    let f = |k: &str| b[k].as_f64().unwrap_or(0.0);
                    let total = (f("runs_s") + f("worker_start_s")).max(1e-9);
                    println!(
                        "latest conformance run ({}): {} runs, {:.1} s wall, {:.1} s of worker time",
                        v["command"].as_str().unwrap_or(""),
                        v["runs"].as_array().map_or(0, Vec::len),
                        f("wall_s"),
                        total
                    );
                    println!(
                        "  per stage: frames {:.0}%, twins {:.0}%, judging {:.0}%, goldens/PNG {:.0}%, worker start {:.0}%, other {:.0}%; harness overhead (start, context, judging, PNG) {:.1}%",
                        100.0 * f("render_s") / total,
                        100.0 * f("twins_s") / total,
                        100.0 * f("judge_s") / total,
                        100.0 * f("golden_s") / total,
                        100.0 * f("worker_start_s") / total,
                        100.0 * f("other_s") / total,
                        100.0 * share
                    );
                }
                None => println!("the latest conformance report predates the time budget"),
            }
        }
        Err(_) => {
            println!("no conformance report yet: run `cargo xtask conformance` for the overhead")
        }
    }
}
