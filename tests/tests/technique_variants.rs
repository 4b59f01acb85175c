//! Technique knobs that must not change the answer: reversed depth (GEQUAL, 1→0) against
//! forward, the bias matrix after the divide against before, culling front faces on closed
//! casters; and a point light with a cube map, judged against the truth.
//!
//! A variant may legally flip a pixel only where the lookup sits on a decision boundary (a
//! depth tie within rounding, or a texel boundary within rounding): by construction those are
//! pixels on shadow or acne boundaries, which the truth marks as edge pixels. So every
//! disagreement must be an edge pixel (or one the truth does not judge).

use umbra_case::format::{BiasMatrix, Cull, DepthOrder};
use umbra_case::{CasePoint, ClipDepth, Prepared};
use umbra_tests::points;

fn assert_same_shadows(base: CasePoint, change: impl Fn(&mut umbra_case::Case), what: &str) -> u64 {
    let mut varied = base.clone();
    change(&mut varied.case);
    let (a, b) = (Prepared::new(base), Prepared::new(varied));
    let fa = umbra_ref::render(&a, ClipDepth::MinusOneToOne);
    let fb = umbra_ref::render(&b, ClipDepth::MinusOneToOne);
    let truth = umbra_ref::truth::ground_truth(&a.lights[0]);
    let g = umbra_compare::agreement(
        fa.light(0).expect("a light"),
        fb.light(0).expect("a light"),
        0,
    );
    for (i, bad) in g.disagrees.iter().enumerate() {
        assert!(
            !*bad || truth.edge[i] || !truth.judged(i),
            "{what} on {}: pixel {i} differs away from any edge",
            a.point.id()
        );
    }
    assert!(g.compared > 10_000);
    g.unexplained()
}

#[test]
fn reversed_depth_gives_the_same_shadows() {
    let mut flips = 0;
    for rel in [
        "basics/square-occluder.json",
        "lights/spot-20deg.json",
        "lights/directional-ortho-10.json",
    ] {
        for p in points(rel).into_iter().take(1) {
            flips += assert_same_shadows(
                p,
                |c| c.shadow.depth_order = DepthOrder::Reversed,
                "reversed depth",
            );
        }
    }
    println!("reversed vs forward: {flips} px differ, all on edges");
}

#[test]
fn bias_matrix_after_the_divide_gives_the_same_shadows() {
    let mut flips = 0;
    for rel in [
        "lights/spot-20deg.json",
        "packed-cubes/packed-cubes.json",
        "lights/directional-ortho-20.json",
    ] {
        for p in points(rel).into_iter().step_by(5) {
            flips += assert_same_shadows(
                p,
                |c| c.shadow.bias_matrix = BiasMatrix::AfterDivide,
                "after divide",
            );
        }
    }
    println!("after vs before divide: {flips} px differ, all on edges");
}

#[test]
fn a_point_light_shadows_in_every_direction() {
    let json = r#"{
      "name": "point-light-room", "about": "a point light between boxes: the cube map's six faces",
      "scene": { "objects": [
        { "plane": { "point": [0, 0, 0], "half_extent": 12 } },
        { "box": { "center": [3, 1, 0], "size": [1, 2, 1] } },
        { "box": { "center": [-3, 1, 0], "size": [1, 2, 1] } },
        { "box": { "center": [0, 1, 3], "size": [1, 2, 1] } },
        { "box": { "center": [0, 1, -3], "size": [1, 2, 1] } } ] },
      "camera": { "eye": [0, 16, 9], "target": [0, 0, 0], "size": [256, 256], "near": 1, "far": 60 },
      "light": { "point": { "position": [0, 3, 0], "near": 0.1, "far": 40 } },
      "shadow": { "size": [512, 512], "bias": { "polygon_offset": [2.0, 4.0], "normal_offset": 0.03 } }
    }"#;
    // Without the normal offset (about two texels at the boxes: 2·3.5 m / 512), the box tops,
    // which the light grazes at 68°, show acne within a texel of their convex edges, where a
    // texel straddling the edge holds the nearer side face. That is the technique's error, not
    // the reference's; the offset removes it, and then nothing may be wrong away from edges.
    let mut pts = umbra_case::load_str(json, std::path::Path::new("inline/point-light-room.json"))
        .expect("valid case");
    let run = Prepared::new(pts.remove(0));
    assert_eq!(run.lights[0].light.views.len(), 6);
    let frame = umbra_ref::render(&run, ClipDepth::MinusOneToOne);
    let map = frame.lights[0].shadow_map.as_ref().expect("depth map");
    assert_eq!(map.layers, 6);
    // Every face but +y sees the floor or a box, so it holds something nearer than the clear.
    let face = (map.width * map.height) as usize;
    for (k, layer) in map.values.chunks(face).enumerate() {
        let written = layer.iter().filter(|d| **d < 1.0).count();
        assert_eq!(
            written > 0,
            k != 2,
            "cube face {k}: {written} texels written"
        );
    }
    let truth = umbra_ref::truth::ground_truth(&run.lights[0]);
    let e = umbra_compare::truth_error(frame.light(0).expect("a light"), &truth);
    println!("all {:?}, away from edges {:?}", e.all, e.away_from_edges);
    assert!(e.truth_shadowed > 2000, "four long shadows must be in view");
    assert_eq!(e.away_from_edges.false_light, 0, "leaks away from edges");
    assert_eq!(e.away_from_edges.false_shadow, 0, "acne away from edges");
}

#[test]
fn front_face_culling_keeps_closed_casters_shadows() {
    let p = points("lights/spot-20deg.json").remove(0);
    let mut culled = p.clone();
    culled.case.shadow.cull = Cull::Front;
    let run = Prepared::new(culled);
    let frame = umbra_ref::render(&run, ClipDepth::MinusOneToOne);
    let e = umbra_compare::truth_error(
        frame.light(0).expect("a light"),
        &umbra_ref::truth::ground_truth(&run.lights[0]),
    );
    // The floor is single-sided and faces the light, so culling front faces removes it from
    // the map: the floor reads lit wherever no box is in front, which is the truth there.
    assert_eq!(e.away_from_edges.false_light, 0, "{:?}", e.away_from_edges);
    assert!(e.truth_shadowed > 200, "{} px in shadow", e.truth_shadowed);
}
