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
            bits(&one.visibility),
            bits(&three.visibility),
            "{case}: visibility"
        );
        assert_eq!(one.surface, three.surface, "{case}: surface ids");
        assert_eq!(one.shadow_map, three.shadow_map, "{case}: shadow map");
        let t1 = in_pool(1, || umbra_ref::truth::ground_truth(&run));
        let t3 = in_pool(3, || umbra_ref::truth::ground_truth(&run));
        assert_eq!((t1.class, t1.edge), (t3.class, t3.edge), "{case}: truth");
    }
}
