use super::*;

/// The judged interval of a lookup holds the value at *every* point of the region its
/// moves span, not only at the centre and the corners: a LINEAR or PCF value is a product
/// of weights and tap decisions that change across the region, and its extreme can lie
/// inside (hulling the corners missed it and failed correct drivers on generated scenes).
/// On surface points of generated cases, with moves like the camera's snapping, the
/// reference's own value at interior points lies in the interval judged at the centre.
#[test]
fn the_interval_holds_inside_the_region_of_moves() {
    let mut rand = crate::test_rng::uniform(0x5EED_1234);
    let mut checked = 0;
    for case in umbra_case::generate::cases(11, 30) {
        let text = umbra_case::generate::to_json(&case);
        let point = umbra_case::load_str(&text, std::path::Path::new("g.json"))
            .expect("a generated case is valid")
            .swap_remove(0);
        checked += every_light(point, &mut rand, 120);
    }
    assert!(checked > 50_000, "{checked}");
}

/// The same on the cascade cases, whose receivers cross splits, blend bands and the
/// shadow distance: the value at every point of a region (the reference's f32 view
/// depth, cascade and blend weight there) lies in the interval judged for it.
#[test]
fn the_interval_holds_across_cascade_splits_and_bands() {
    let mut rand = crate::test_rng::uniform(0x5EED_4321);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/cascades");
    let mut checked = 0;
    for name in ["blend.json", "on-split.json"] {
        for point in umbra_case::load_file(&dir.join(name)).expect("a cascade case loads") {
            checked += every_light(point, &mut rand, 400);
        }
    }
    assert!(checked > 50_000, "{checked}");
}

/// The same with Castano's filter on the generated cases that can have it (2D maps):
/// nine LINEAR taps whose places and weights move with the coordinate, and whose base
/// texel jumps at half-texels.
#[test]
fn the_interval_holds_for_castanos_taps() {
    let mut rand = crate::test_rng::uniform(0x5EED_0C13);
    let mut checked = 0;
    for point in two_d_cases(13, 24, Filter::Castano13) {
        checked += every_light(point, &mut rand, 120);
    }
    assert!(checked > 20_000, "{checked}");
}

/// The generated cases of `seed` (the first `count`) that can have a 2D map's filter (no
/// point light, no mip levels), each with `filter`, as case points.
fn two_d_cases(seed: u64, count: usize, filter: Filter) -> Vec<umbra_case::CasePoint> {
    umbra_case::generate::cases(seed, count)
        .into_iter()
        .filter(|case| {
            !case
                .lights
                .iter()
                .any(|l| matches!(l, umbra_case::format::Light::Point(_)))
                && case.shadow.mipmaps.is_none()
        })
        .map(|mut case| {
            case.shadow.filter = filter;
            let text = umbra_case::generate::to_json(&case);
            umbra_case::load_str(&text, std::path::Path::new("g.json"))
                .unwrap_or_else(|e| panic!("a 2D generated case takes {filter:?}: {e}"))
                .swap_remove(0)
        })
        .collect()
}

/// The same for three.js's Vogel disk at pixels all over a frame: each pixel's rotation
/// (its arcs, where the noise's arithmetic allows two) and each tap's move within it.
#[test]
fn the_interval_holds_for_the_vogel_disk() {
    let mut rand = crate::test_rng::uniform(0x5EED_7003);
    let mut checked = 0;
    for point in two_d_cases(17, 16, Filter::Vogel5) {
        for _ in 0..4 {
            let window = [
                (rand() * 400.0).floor() + 0.5,
                (rand() * 300.0).floor() + 0.5,
            ];
            checked += at_window(window, || every_light(point.clone(), &mut rand, 40));
        }
    }
    assert!(checked > 20_000, "{checked}");
}

/// Castano's taps as written are his filter: along each axis the weights sum to 12 (the
/// sum over 144 is a mean), and the filtered value of any map is continuous in the
/// coordinate, across the half-texels where the base texel jumps too (the judge's
/// reading of a coordinate within reach of one: either base, one filter).
#[test]
fn castanos_taps_are_one_continuous_filter() {
    let mut rand = crate::test_rng::uniform(0xCA57);
    let size = 16.0f32;
    let map: Vec<f32> = (0..256).map(|_| f32::from(rand() < 0.5)).collect();
    let at = |i: i64, j: i64| map[(j.rem_euclid(16) * 16 + i.rem_euclid(16)) as usize];
    let bilinear = |u: f32, v: f32| {
        let (x, y) = (u * size - 0.5, v * size - 0.5);
        let (i, j) = (x.floor(), y.floor());
        let (a, b) = (x - i, y - j);
        let (i, j) = (i as i64, j as i64);
        (1.0 - a) * (1.0 - b) * at(i, j)
            + a * (1.0 - b) * at(i + 1, j)
            + (1.0 - a) * b * at(i, j + 1)
            + a * b * at(i + 1, j + 1)
    };
    let value = |u: f32, v: f32| {
        let taps = castano_taps([u, v], [size, size]);
        let w: f32 = taps.iter().map(|((a, b), _)| a * b).sum();
        assert!((w - 144.0).abs() < 1e-4, "weights sum to {w}");
        taps.iter()
            .map(|((a, b), (x, y))| a * b * bilinear(*x, *y))
            .sum::<f32>()
            / 144.0
    };
    for k in 2..14 {
        let v = (5.3 + rand()) / size;
        // Either side of the half-texel where the base texel changes.
        let u = (k as f32 - 0.5) / size;
        let (below, above) = (value(u - 1e-4 / size, v), value(u + 1e-4 / size, v));
        assert!(
            (below - above).abs() < 1e-3,
            "at texel {k}: {below} below and {above} above the jump"
        );
    }
}

/// [`region_checks`] on every light's run of `point`.
fn every_light(
    point: umbra_case::CasePoint,
    rand: &mut impl FnMut() -> f32,
    tries: usize,
) -> usize {
    let run = umbra_case::Prepared::new(point);
    run.lights
        .iter()
        .map(|l| region_checks(l, rand, tries))
        .sum()
}

/// Judges `tries` random surface points of `run` with snapping-like moves and checks the
/// reference's value at 24 points of each region against the region's interval; returns
/// how many values it checked.
fn region_checks(
    run: &umbra_case::LightRun,
    rand: &mut impl FnMut() -> f32,
    tries: usize,
) -> usize {
    let clip = umbra_case::ClipDepth::MinusOneToOne;
    let conv = crate::convention(run.case(), clip);
    let layers = crate::judged_layers(run, clip, Profile::GL);
    let lookup = Lookup::new(run, conv, &layers, Profile::GL);
    let geo = &run.geometry;
    let mut checked = 0;
    for _ in 0..tries {
        let t = (rand() * geo.triangles.len() as f32) as usize % geo.triangles.len();
        let [a, b, c] = geo.corners(t);
        let [na, nb, nc] = geo.triangles[t].map(|k| geo.normals[k as usize]);
        let (u, v) = (rand(), rand());
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let p = a + (b - a) * u + (c - a) * v;
        let n = (na * (1.0 - u - v) + nb * u + nc * v).normalize();
        // Moves of a few millimetres in the surface, as a pixel's snapping gives.
        let k = 0.002 + 0.02 * rand();
        let sx = (b - a).normalize_or_zero() * k;
        let sy = (c - a).normalize_or_zero() * k * rand();
        let (_, legal) = lookup.judged(p, n, [sx, sy], Turn::NONE);
        for _ in 0..24 {
            let q = p + sx * (2.0 * rand() - 1.0) + sy * (2.0 * rand() - 1.0);
            let vis = lookup.visibility(q, n);
            assert!(
                legal.lo - 1e-6 <= vis && vis <= legal.hi + 1e-6,
                "{}: the value {vis} at {q} (moved from {p}) is outside the interval [{}, {}] judged for the region",
                run.point.id(),
                legal.lo,
                legal.hi
            );
            checked += 1;
        }
    }
    checked
}
