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
            let truth = umbra_ref::truth::ground_truth(&run.lights[0]);
            let g = umbra_compare::agreement(
                gl.light(0).expect("a light"),
                zo.light(0).expect("a light"),
                0,
            );
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

/// The reference rendered in the zero-to-one convention is a conformant implementation
/// (another clip range, another projection matrix, other f32 roundings: what a Vulkan or
/// wgpu driver computes), so on generated scenes (far from the origin, reversed depth, every
/// format and filter) its frame and its shadow map must lie inside the intervals the judge
/// computes in the GL convention. Before the stored depth's freedom counted the projection's
/// cancellation (`umbra_ref::shadow_pass::depth_error`), reversed-depth D32F maps and scenes
/// 4·10⁴ m from the origin failed here as they failed on wgpu-vk/lavapipe in the soak.
#[test]
fn zero_to_one_references_are_legal_under_the_gl_judge() {
    let mut texels = 0u64;
    let mut pixels = 0u64;
    for seed in [5u64, 8] {
        for case in umbra_case::generate::cases(seed, 25) {
            let text = umbra_case::generate::to_json(&case);
            let points = umbra_case::load_str(&text, std::path::Path::new("generated.json"))
                .expect("a generated case is valid");
            for point in points {
                let id = point.id();
                let run = Prepared::new(point);
                let profile = umbra_case::Profile::GL.effective_for(run.case());
                let judged = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, profile);
                let zo = umbra_ref::render(&run, ClipDepth::ZeroToOne);
                let (a, _) = umbra_compare::reference::judge(&judged, &zo);
                assert_eq!(
                    (a.illegal, a.illegal_map),
                    (0, 0),
                    "{id}: the zero-to-one reference breaks the GL judge ({}; {} map texels)",
                    a.illegal_summary(),
                    a.illegal_map
                );
                texels += a.map_checked;
                pixels += a.compared;
            }
        }
    }
    println!("{pixels} pixels and {texels} map texels held");
    assert!(texels > 1_000_000 && pixels > 500_000, "{pixels} {texels}");
}
