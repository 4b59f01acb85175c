//! The texture v flip and the [0,1] depth range are right on both wgpu backends: the
//! asymmetric shadow of an L-shaped occluder matches the reference's exactly away from edges
//! (every disagreement legal by a spec rule), and has zero error against the truth there.
//!
//! Negative control: the same frame against the reference of the *mirrored* L (what a
//! forgotten v flip would show) disagrees on hundreds of pixels away from any edge, so the
//! test can tell a flip from a match.

use umbra_case::{Backend, ClipDepth, Prepared};
use umbra_wgpu::{Target, WgpuBackend};

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
    let truth = umbra_ref::truth::ground_truth(&run.lights[0]);
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
    for target in Target::software() {
        let kind = &target;
        let mut backend = WgpuBackend::new(target.clone()).unwrap_or_else(|e| {
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
        let e = umbra_compare::truth_error(frame.light(0).expect("a light"), &truth);
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

#[test]
fn adapters_are_chosen_by_the_name_their_driver_gives_and_lavapipe_is_found() {
    let named = umbra_wgpu::device::named_adapters(umbra_wgpu::Kind::Vulkan);
    assert!(
        named.iter().any(|(n, _)| n == "lavapipe"),
        "lavapipe among {:?}",
        named.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    let target = Target::parse("wgpu-vk/lavapipe").expect("an id");
    let backend = WgpuBackend::new(target).unwrap_or_else(|e| panic!("{}", e.0));
    let info = backend.info();
    assert!(info.renderer.starts_with("llvmpipe"), "{info:?}");
    assert!(info.version.contains("Mesa"), "{info:?}");
    let missing = WgpuBackend::new(Target::parse("wgpu-vk/nonesuch").expect("an id"));
    let why = missing.err().map(|e| e.0).unwrap_or_default();
    assert!(
        why.contains("no adapter named \"nonesuch\"") && why.contains("wgpu-vk/lavapipe"),
        "{why}"
    );
}

#[test]
fn adapter_names_come_from_what_the_driver_reports() {
    use umbra_wgpu::Kind;
    use umbra_wgpu::device::adapter_slug;
    assert_eq!(
        adapter_slug(Kind::Vulkan, "llvmpipe", "llvmpipe (LLVM 15)", true),
        "lavapipe"
    );
    assert_eq!(
        adapter_slug(
            Kind::Vulkan,
            "radv",
            "AMD Radeon RX 6800 (RADV NAVI21)",
            false
        ),
        "radv"
    );
    assert_eq!(
        adapter_slug(
            Kind::Vulkan,
            "Intel open-source Mesa driver",
            "Intel(R) UHD",
            false
        ),
        "anv"
    );
    assert_eq!(
        adapter_slug(Kind::Vulkan, "NVIDIA", "NVIDIA H100 PCIe", false),
        "nvidia"
    );
    assert_eq!(
        adapter_slug(Kind::Gl, "", "llvmpipe (LLVM 15.0.6, 256 bits)", true),
        "llvmpipe"
    );
    assert_eq!(
        adapter_slug(Kind::Gl, "", "NVIDIA H100 PCIe/PCIe/SSE2", false),
        "nvidia"
    );
    assert_eq!(adapter_slug(Kind::Vulkan, "", "", false), "unknown");
    assert_eq!(
        Target::parse("wgpu-vk/radv.2").map(|t| t.id()),
        Some("wgpu-vk/radv.2".into())
    );
    assert_eq!(Target::parse("wgpu-vk/Bad Name"), None);
}
