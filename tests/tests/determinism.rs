//! The reference is bit-identical whatever the thread count (tiny-skia's habit: CI reruns
//! under other settings to prove the output does not change), and the truth too.

use umbra_tests::prepared;

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool")
        .install(f)
}

#[test]
fn frames_and_truth_are_identical_on_1_and_3_threads() {
    for case in [
        "packed-cubes/packed-cubes.json",
        "lights/spot-20deg.json",
        "lights/directional-ortho-10.json",
    ] {
        let run = prepared(case);
        let one = in_pool(1, || {
            umbra_ref::render(&run, umbra_case::ClipDepth::MinusOneToOne)
        });
        let three = in_pool(3, || {
            umbra_ref::render(&run, umbra_case::ClipDepth::MinusOneToOne)
        });
        assert_eq!(one.color, three.color, "{case}: colour");
        // Bitwise, NaN background included.
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&one.lights[0].visibility),
            bits(&three.lights[0].visibility),
            "{case}: visibility"
        );
        assert_eq!(
            one.lights[0].surface, three.lights[0].surface,
            "{case}: surface ids"
        );
        assert_eq!(
            one.lights[0].shadow_map, three.lights[0].shadow_map,
            "{case}: shadow map"
        );
        let t1 = in_pool(1, || umbra_ref::truth::ground_truth(&run.lights[0]));
        let t3 = in_pool(3, || umbra_ref::truth::ground_truth(&run.lights[0]));
        assert_eq!((t1.class, t1.edge), (t3.class, t3.edge), "{case}: truth");
    }
}

/// The plain render shades a run of pixels at a time ([`umbra_ref::surface`], the batched
/// lookup and shading); the judged render looks every pixel up on its own, through the
/// per-point functions the judge's moved points use. Both must give the same frame, bit for
/// bit, on the first point of every case file (every filter, outside policy, bias form, light
/// kind, depth order and bias-matrix order the catalogue has), in both conventions.
#[test]
fn the_batched_frame_is_the_per_pixel_frame() {
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let files = umbra_case::case_files(&umbra_tests::cases_dir()).expect("cases");
    assert!(files.len() > 30, "{} case files", files.len());
    for file in files {
        let Some(point) = umbra_case::load_file(&file)
            .ok()
            .and_then(|mut p| (!p.is_empty()).then(|| p.swap_remove(0)))
        else {
            continue;
        };
        let id = point.id();
        let run = umbra_case::Prepared::new(point);
        for (clip, profile) in [
            (
                umbra_case::ClipDepth::MinusOneToOne,
                umbra_case::Profile::GL,
            ),
            (
                umbra_case::ClipDepth::ZeroToOne,
                umbra_case::Profile::VULKAN,
            ),
        ] {
            let plain = umbra_ref::render(&run, clip);
            let judged = umbra_ref::render_judged(&run, clip, profile).frame;
            assert_eq!(plain.color, judged.color, "{id} {clip:?}: colour");
            assert_eq!(
                bits(&plain.lights[0].visibility),
                bits(&judged.lights[0].visibility),
                "{id} {clip:?}: visibility"
            );
        }
    }
}
