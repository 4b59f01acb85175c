//! `cargo bench -p umbra-ref`: the reference rasterizer's throughput on the packed cubes, per
//! pass, in Mpixels/s (pixels of the pass's target per second of wall time, median of 9 runs
//! after one warm-up), on 1 thread and on every thread of the machine, side by side in one
//! run: on the standard frame (the point the frames bench compares with llvmpipe: a 1024²
//! map, a 384² view) and with both grown to 1024²; and what the judged render (ambiguity
//! flags, legal intervals) of the standard frame costs beside the plain one (median of 5).
//!
//! `UMBRA_BENCH_THREADS=N` measures N threads only and reports the fastest of the 9 runs
//! rather than the median (for A/B comparisons of two builds on a noisy, shared machine).

use std::time::Duration;

use umbra_case::{ClipDepth, Prepared};

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/packed-cubes/packed-cubes.json");
    let standard = umbra_case::load_file(&path)
        .expect("packed-cubes case")
        .swap_remove(2);
    let mut large = standard.clone();
    large.case.shadow.size = [1024, 1024];
    large.case.camera.size = [1024, 1024];
    let all = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    type Pick = fn(Vec<Duration>) -> Duration;
    let (threads, pick): (Vec<usize>, Pick) = match std::env::var("UMBRA_BENCH_THREADS") {
        Ok(n) => (
            vec![n.parse().expect("UMBRA_BENCH_THREADS: a number")],
            |v| v.into_iter().min().unwrap_or_default(),
        ),
        Err(_) => (vec![1, all], median),
    };
    for (label, point) in [("standard frame", standard), ("1024² view", large)] {
        let run = Prepared::new(point);
        let [mw, mh] = run.case().shadow.size;
        let [cw, ch] = run.camera.size;
        println!(
            "reference rasterizer, {label}: {} ({} triangles), map {mw}x{mh}, view {cw}x{ch}",
            run.point.id(),
            run.geometry.triangles.len()
        );
        for &n in &threads {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("pool");
            let (shadow, lit) = pool.install(|| {
                umbra_ref::render(&run, ClipDepth::MinusOneToOne);
                let frames: Vec<_> = (0..9)
                    .map(|_| umbra_ref::render(&run, ClipDepth::MinusOneToOne).timings)
                    .collect();
                (
                    pick(frames.iter().map(|t| t.shadow_pass).collect()),
                    pick(frames.iter().map(|t| t.lit_pass).collect()),
                )
            });
            let mps = |d: Duration, px: u32| f64::from(px) / d.as_secs_f64() / 1e6;
            println!(
                "  {n} thread(s): shadow pass {:.2} ms = {:.1} Mpixels/s; lit pass {:.2} ms = {:.1} Mpixels/s",
                shadow.as_secs_f64() * 1e3,
                mps(shadow, mw * mh),
                lit.as_secs_f64() * 1e3,
                mps(lit, cw * ch)
            );
            // The judged variant (what every pixel and texel allows, for the judge): what it
            // costs beside the plain frame, on the standard frame only (it is the judge's
            // cold-run cost, computed once per point and profile and then cached).
            if label == "standard frame" {
                let (plain, judged) = pool.install(|| {
                    let time = |f: &dyn Fn()| {
                        let t = std::time::Instant::now();
                        f();
                        t.elapsed()
                    };
                    let plain =
                        |_| time(&|| drop(umbra_ref::render(&run, ClipDepth::MinusOneToOne)));
                    let judged = |_| {
                        time(&|| {
                            drop(umbra_ref::render_judged(
                                &run,
                                ClipDepth::MinusOneToOne,
                                umbra_case::Profile::GL,
                            ))
                        })
                    };
                    (
                        pick((0..5).map(plain).collect()),
                        pick((0..5).map(judged).collect()),
                    )
                });
                println!(
                    "  {n} thread(s): judged render (GL profile) {:.1} ms against {:.1} ms for the plain one ({:.1}x)",
                    judged.as_secs_f64() * 1e3,
                    plain.as_secs_f64() * 1e3,
                    judged.as_secs_f64() / plain.as_secs_f64()
                );
            }
        }
    }
}
