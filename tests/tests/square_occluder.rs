//! Must-show: a 2 m square 5 m above a floor, lit from straight above, casts exactly its own
//! 4 m² shadow. The camera looks straight down from x = 5 (so it sees the shadow, not the
//! occluder), which makes every floor pixel the same size: h = 2·10·tan(35°)/256 m.

use umbra_ref::truth::Class;
use umbra_tests::prepared;

#[test]
fn reference_and_truth_shadow_the_analytic_square() {
    let run = prepared("basics/square-occluder.json");
    let frame = umbra_ref::render(&run, umbra_case::ClipDepth::MinusOneToOne);
    let truth = umbra_ref::truth::ground_truth(&run.lights[0]);
    let px = 2.0 * 10.0 * 35f64.to_radians().tan() / 256.0;
    let texel = 12.0 / 512.0;
    let half = px / 2.0;
    let (mut inside, mut outside, mut band) = (0u64, 0u64, 0u64);
    let (mut ref_area, mut truth_area) = (0u64, 0u64);
    for i in 0..truth.class.len() {
        if !matches!(truth.class[i], Class::Lit | Class::Shadowed) {
            continue;
        }
        let p = truth.point[i];
        assert!(p.y.abs() < 1e-9, "the camera sees only the floor here");
        let (ax, az) = (p.x.abs(), p.z.abs());
        let ref_shadowed = umbra_compare::is_shadowed(frame.lights[0].visibility[i]);
        let truth_shadowed = truth.class[i] == Class::Shadowed;
        ref_area += u64::from(ref_shadowed);
        truth_area += u64::from(truth_shadowed);
        // Pixel square [x ± h] × [z ± h]: wholly inside, wholly outside, or on the boundary;
        // the reference may also move the boundary by one shadow texel.
        let m = half + texel;
        if ax + m < 1.0 && az + m < 1.0 {
            inside += 1;
            assert!(
                truth_shadowed && ref_shadowed,
                "pixel {i} at ({:.3}, {:.3}) is inside the shadow",
                p.x,
                p.z
            );
        } else if ax - m > 1.0 || az - m > 1.0 {
            outside += 1;
            assert!(
                !truth_shadowed && !ref_shadowed,
                "pixel {i} at ({:.3}, {:.3}) is outside the shadow",
                p.x,
                p.z
            );
        } else {
            band += 1;
        }
    }
    let analytic = 4.0 / (px * px);
    for (who, area) in [("reference", ref_area), ("truth", truth_area)] {
        let diff = (area as f64 - analytic).abs();
        println!("{who}: {area} px shadowed, analytic {analytic:.1} px, boundary band {band} px");
        assert!(
            diff <= band as f64,
            "{who}: shadow area {area} px differs from the analytic {analytic:.1} px by more than the {band} boundary pixels"
        );
    }
    assert!(
        inside > 1000 && outside > 10000,
        "the test must judge real areas ({inside} inside, {outside} outside)"
    );
    let e = umbra_compare::truth_error(frame.light(0).expect("a light"), &truth);
    assert_eq!(
        (
            e.away_from_edges.false_shadow,
            e.away_from_edges.false_light
        ),
        (0, 0),
        "{e:?}"
    );
    assert!(e.away_from_edges.judged > 30000);
}
