//! Every starter case on both wgpu backends agrees with the GL backend (gl33/llvmpipe), in
//! this process: where the two differ (surface or lit/shadowed answer), the reference's judged
//! renders for both backends' profiles must leave the answer free there. Both are also held
//! to the reference by the conformance run; this checks them against each other directly.

use std::path::Path;

use umbra_case::{ClipDepth, Prepared};

#[test]
fn wgpu_agrees_with_gl_on_every_starter_case() {
    let cases = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases");
    let mut gl = umbra_runner::harness::registry::create("gl33/llvmpipe")
        .unwrap_or_else(|e| panic!("{e} (`cargo xtask test` installs the Mesa packages)"));
    let mut backends: Vec<_> = ["wgpu-vk/lavapipe", "wgpu-gl/llvmpipe"]
        .iter()
        .map(|id| {
            umbra_runner::harness::registry::create(id).unwrap_or_else(|e| panic!("{id}: {e}"))
        })
        .collect();
    let mut compared = 0;
    for dir in ["basics", "lights", "packed-cubes"] {
        for file in umbra_case::case_files(&cases.join(dir)).expect("cases") {
            let point = umbra_case::load_file(&file)
                .unwrap_or_else(|e| panic!("{e}"))
                .remove(0);
            let run = Prepared::new(point);
            let judged_gl = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, gl.profile());
            let gl_frame = gl.render(&run).unwrap_or_else(|e| panic!("gl: {e}"));
            for b in &mut backends {
                let frame = b.render(&run).unwrap_or_else(|e| panic!("{}: {e}", b.id()));
                let judged = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, b.profile());
                let pair =
                    umbra_compare::reference::judge_pair(&frame, &judged, &gl_frame, &judged_gl);
                println!(
                    "{} vs gl33/llvmpipe on {}: {pair:?}",
                    b.id(),
                    run.point.id()
                );
                assert_eq!(
                    pair.illegal,
                    0,
                    "{} and gl33/llvmpipe disagree on {} where no freedom explains it",
                    b.id(),
                    run.point.id()
                );
                compared += pair.compared;
            }
        }
    }
    // 7 starter cases × 2 backends at 60k–110k px each: guard against comparing nothing.
    assert!(compared > 700_000, "only {compared} px compared");
}
