//! The texture v flip and the [0,1] depth range are right on both wgpu backends: the
//! asymmetric shadow of an L-shaped occluder matches the reference's exactly away from edges
//! (every disagreement legal by a spec rule), and has zero error against the truth there.
//!
//! Negative control: the same frame against the reference of the *mirrored* L (what a
//! forgotten v flip would show) disagrees on hundreds of pixels away from any edge, so the
//! test can tell a flip from a match.

use umbra_case::{Backend, ClipDepth, Prepared};
use umbra_wgpu::{Kind, WgpuBackend};

fn l_case() -> umbra_case::CasePoint {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/basics/l-occluder.json");
    umbra_case::load_file(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(0)
}

#[test]
fn the_l_shaped_shadow_lands_where_the_reference_puts_it() {
    let run = Prepared::new(l_case());
    let truth = umbra_ref::truth::ground_truth(&run);
    let mut mirrored = l_case();
    if let umbra_case::format::Object::Mesh(m) = &mut mirrored.case.scene.objects[1] {
        for p in &mut m.positions {
            p[2] = -p[2];
        }
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
    }
    let mirrored_run = Prepared::new(mirrored);
    for kind in Kind::ALL {
        let mut backend = WgpuBackend::new(kind).unwrap_or_else(|e| {
            panic!(
                "{}: {} (`cargo xtask test` installs the Mesa packages)",
                kind.id(),
                e.0
            )
        });
        let frame = backend
            .render(&run)
            .unwrap_or_else(|e| panic!("{}: {e}", kind.id()));
        let judged = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, backend.profile());
        let a = umbra_compare::reference::judge(&judged, &frame).0;
        println!("{}: {a:?}", kind.id());
        assert_eq!(
            a.illegal,
            0,
            "{}: the shadow is displaced: {a:?}",
            kind.id()
        );
        let e = umbra_compare::truth_error(&frame, &truth);
        assert_eq!(
            (
                e.away_from_edges.false_shadow,
                e.away_from_edges.false_light
            ),
            (0, 0),
            "{}: {:?}",
            kind.id(),
            e.away_from_edges
        );
        assert!(
            e.truth_shadowed > 1000,
            "{}: the shadow must be in view",
            kind.id()
        );
        let mirrored_ref =
            umbra_ref::render_judged(&mirrored_run, ClipDepth::MinusOneToOne, backend.profile());
        let control = umbra_compare::reference::judge(&mirrored_ref, &frame).0;
        assert!(
            control.illegal > 300,
            "{}: a mirrored shadow would not be caught: {control:?}",
            kind.id()
        );
    }
}
