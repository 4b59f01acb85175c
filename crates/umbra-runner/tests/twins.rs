//! Metamorphic twins through `run_point`, on the reference backend.

use std::path::Path;

use umbra_runner::judge::run::{Outcome, run_point};

fn point(rel: &str, index: usize) -> umbra_case::CasePoint {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases")
        .join(rel);
    umbra_case::load_file(&file)
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(index)
}

fn judged(p: umbra_case::CasePoint) -> Box<umbra_runner::judge::run::Judged> {
    match run_point(&mut umbra_ref::RefBackend, p, true) {
        Outcome::Done(j) => j,
        Outcome::Skip(s) | Outcome::Error(s) => panic!("{s}"),
    }
}

#[test]
fn a_twin_that_resets_the_offset_really_renders_at_the_origin() {
    // 1e6 m out, f32 spacing is 6 cm: the frame must differ from the twin at the origin. A twin
    // built from the already-offset case (offset reset to zero, positions kept) would be the
    // same frame again and show no difference at all.
    let j = judged(point("numerics/far-from-origin-extreme.json", 1));
    let t = j
        .twins
        .iter()
        .find(|t| t.name == "at-origin")
        .expect("the at-origin twin");
    assert!(t.skipped.is_none(), "{t:?}");
    assert!(
        t.pair.differ > 100,
        "only {} px differ from the origin: {t:?}",
        t.pair.differ
    );
    assert!(
        t.twin_interior_error < Some(t.interior_error),
        "the origin should be more accurate: {t:?}"
    );
}

#[test]
fn every_case_gets_the_bias_order_twin_first() {
    let j = judged(point("basics/square-occluder.json", 0));
    assert_eq!(j.twins[0].name, "bias-order");
    assert!(
        j.twins[0].ok && j.twins[0].skipped.is_none(),
        "{:?}",
        j.twins[0]
    );
    assert!(j.twins[0].render_ms > 0.0);
}
