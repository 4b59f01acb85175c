//! `cargo bench -p umbra-ref`: the reference rasterizer's throughput on the packed cubes with a
//! 1024x1024 shadow map and a 1024x1024 camera view, per pass, in Mpixels/s (pixels of the
//! pass's target per second of wall time, median of 9 runs after one warm-up), on 1 thread and
//! on every thread of the machine, side by side in one run.

use std::time::Duration;

use umbra_case::{ClipDepth, Prepared};

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/packed-cubes/packed-cubes.json");
    let mut point = umbra_case::load_file(&path)
        .expect("packed-cubes case")
        .swap_remove(2);
    point.case.shadow.size = [1024, 1024];
    point.case.camera.size = [1024, 1024];
    let run = Prepared::new(point);
    let pixels = 1024.0 * 1024.0;
    let all = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    println!(
        "reference rasterizer, {} ({} triangles), map 1024x1024, view 1024x1024",
        run.point.id(),
        run.geometry.triangles.len()
    );
    for threads in [1, all] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let (shadow, lit) = pool.install(|| {
            umbra_ref::render(&run, ClipDepth::MinusOneToOne);
            let frames: Vec<_> = (0..9)
                .map(|_| umbra_ref::render(&run, ClipDepth::MinusOneToOne).timings)
                .collect();
            (
                median(frames.iter().map(|t| t.shadow_pass).collect()),
                median(frames.iter().map(|t| t.lit_pass).collect()),
            )
        });
        let mps = |d: Duration| pixels / d.as_secs_f64() / 1e6;
        println!(
            "  {threads} thread(s): shadow pass {:.2} ms = {:.1} Mpixels/s; lit pass {:.2} ms = {:.1} Mpixels/s",
            shadow.as_secs_f64() * 1e3,
            mps(shadow),
            lit.as_secs_f64() * 1e3,
            mps(lit)
        );
    }
}
