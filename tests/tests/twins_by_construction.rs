//! A twin is skipped as "the same render by construction" only where the backend truly never
//! reads what the twin changes. The reference claims that for `shadow.attachments` (it has no
//! framebuffer objects): its frames for both attachment settings must be bit-identical, and
//! its claim must not reach any setting it does read.

use umbra_case::format::{Attachments, Filter};
use umbra_case::{Backend, ClipDepth, Prepared};
use umbra_ref::RefBackend;

#[test]
fn the_reference_ignores_exactly_the_attachments_it_claims_to() {
    let point = umbra_tests::points("packed-cubes/packed-cubes.json").remove(0);
    let mut with_color = point.clone();
    with_color.case.shadow.attachments = Attachments::WithColor;
    assert_ne!(point.case.shadow.attachments, Attachments::WithColor);

    let r = RefBackend;
    assert!(r.renders_identically(&point.case, &with_color.case));
    let a = umbra_ref::render(&Prepared::new(point.clone()), ClipDepth::MinusOneToOne);
    let b = umbra_ref::render(&Prepared::new(with_color.clone()), ClipDepth::MinusOneToOne);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(a.color, b.color);
    assert_eq!(bits(&a.lights[0].visibility), bits(&b.lights[0].visibility));
    assert_eq!(a.lights[0].shadow_map, b.lights[0].shadow_map);

    // Anything else it reads is not covered by the claim.
    let mut other = with_color.clone();
    other.case.shadow.filter = Filter::Pcf(3);
    assert!(!r.renders_identically(&point.case, &other.case));
    let mut moved = point.clone();
    moved.case.scene.offset = [1.0, 0.0, 0.0];
    assert!(!r.renders_identically(&point.case, &moved.case));
}
