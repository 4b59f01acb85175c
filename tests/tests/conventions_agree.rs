//! The reference rendered in the GL convention (clip z in [−1,1], bias matrix, rows from the
//! bottom, one flip at the end) and in the zero-to-one convention (wgpu/Vulkan) must give the
//! same shadows. In real arithmetic they are identical; in f32 the light-space depth and the
//! texel coordinate differ by an ulp or two (see umbra-case's `tests/conventions.rs`), so a
//! pixel may legally flip only where its lookup is that close to a decision: its reference
//! depth within a few ulps of the compared texel (a depth tie), or its texel coordinate
//! within a few ulps of a texel boundary. Such pixels are on shadow or acne boundaries by
//! construction; the test requires every disagreement to be a truth edge pixel, and counts.

use umbra_case::{ClipDepth, Prepared};
use umbra_tests::points;

#[test]
fn gl_and_zero_to_one_references_agree_away_from_edges() {
    let mut total = 0u64;
    let mut compared = 0u64;
    for case in [
        "basics/square-occluder.json",
        "lights/directional-ortho-10.json",
        "lights/directional-ortho-20.json",
        "lights/spot-20deg.json",
        "packed-cubes/packed-cubes.json",
    ] {
        for point in points(case).into_iter().step_by(3) {
            let id = point.id();
            let run = Prepared::new(point);
            let gl = umbra_ref::render(&run, ClipDepth::MinusOneToOne);
            let zo = umbra_ref::render(&run, ClipDepth::ZeroToOne);
            let truth = umbra_ref::truth::ground_truth(&run);
            let g = umbra_compare::agreement(&gl, &zo, 0);
            assert_eq!(g.coverage_differs, 0, "{id}: coverage differs");
            compared += g.compared;
            for (i, bad) in g.disagrees.iter().enumerate() {
                if *bad {
                    total += 1;
                    assert!(
                        truth.edge[i] || !truth.judged(i),
                        "{id}: pixel {i} differs between conventions away from any edge"
                    );
                }
            }
            println!("{id}: {} of {} px differ", g.unexplained(), g.compared);
        }
    }
    println!("total: {total} of {compared} px differ, all on edges");
    assert!(compared > 500_000);
}
