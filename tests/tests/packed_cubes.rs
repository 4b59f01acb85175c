//! Must-show: four touching cubes leak no light through their shared faces, in the truth or in
//! the reference, for every light direction of the sweep.
//!
//! The block is x ∈ [−2, 6], y ∈ [2, 10], z ∈ [−18, −14] on a floor at y = 2. Its shadow on
//! the floor is the convex hull of its 8 corners projected along the light direction; every
//! floor point inside that hull is in shadow. Light that leaked between the cubes would show
//! up as lit floor points inside it.

use glam::{DVec2, DVec3};
use umbra_case::{LightKind, Prepared};
use umbra_ref::truth::{Class, ground_truth};
use umbra_tests::points;

fn hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut h: Vec<DVec2> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

/// Signed distance inside a counter-clockwise convex polygon (positive inside).
fn inside_by(poly: &[DVec2], p: DVec2) -> f64 {
    (0..poly.len())
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            (b - a).perp_dot(p - a) / (b - a).length()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn no_light_leaks_between_the_cubes_in_truth_or_reference() {
    let mut judged_inside = 0u64;
    for point in points("packed-cubes/packed-cubes.json") {
        let id = point.id();
        let run = Prepared::new(point);
        let LightKind::Directional { towards, .. } = run.lights[0].light.kind else {
            panic!("directional")
        };
        let t = towards.as_dvec3();
        let mut corners = Vec::new();
        for x in [-2.0, 6.0] {
            for y in [2.0, 10.0] {
                for z in [-18.0, -14.0] {
                    let c = DVec3::new(x, y, z) - t * ((y - 2.0) / t.y);
                    corners.push(DVec2::new(c.x, c.z));
                }
            }
        }
        let shadow = hull(corners);
        let frame = umbra_ref::render(&run, umbra_case::ClipDepth::MinusOneToOne);
        let truth = ground_truth(&run.lights[0]);
        // One shadow texel in world units (ortho width / map size), twice, for the reference.
        let b = match run.lights[0].light.views[0].projection {
            umbra_case::light::Projection::Ortho { bounds } => bounds,
            _ => unreachable!(),
        };
        let texel = f64::from((b[1] - b[0]).max(b[3] - b[2])) / 1024.0;
        for i in 0..truth.class.len() {
            if truth.face[i] != 1 || !matches!(truth.class[i], Class::Lit | Class::Shadowed) {
                continue; // floor pixels only (object 0, face 0)
            }
            let p = truth.point[i];
            let depth_inside = inside_by(&shadow, DVec2::new(p.x, p.z));
            if depth_inside > 1e-6 {
                judged_inside += 1;
                assert_eq!(
                    truth.class[i],
                    Class::Shadowed,
                    "{id}: truth leaks light at ({:.4}, {:.4})",
                    p.x,
                    p.z
                );
            }
            if depth_inside > 2.0 * texel {
                assert!(
                    umbra_compare::is_shadowed(frame.lights[0].visibility[i]),
                    "{id}: the reference leaks light at ({:.4}, {:.4})",
                    p.x,
                    p.z
                );
            }
        }
        let e = umbra_compare::truth_error(frame.light(0).expect("a light"), &truth);
        assert_eq!(
            e.away_from_edges.false_light, 0,
            "{id}: false light away from edges"
        );
    }
    assert!(
        judged_inside > 20000,
        "the shadow must be in view for the test to mean anything ({judged_inside} px)"
    );
}

#[test]
fn rays_along_the_shared_planes_hit_the_block() {
    // Rays that run exactly in the shared planes x = 2 and y = 6, and through the line where
    // all four cubes meet, from every side.
    let run = Prepared::new(points("packed-cubes/packed-cubes.json").remove(0));
    let bvh = umbra_ref::truth::bvh::Bvh::new(&run.geometry);
    let targets = [
        DVec3::new(2.0, 6.0, -16.0),
        DVec3::new(2.0, 3.0, -16.0),
        DVec3::new(-1.0, 6.0, -15.0),
        DVec3::new(2.0, 9.999, -17.5),
    ];
    let mut rays = 0;
    for target in targets {
        for dir in [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Z,
            DVec3::NEG_Z,
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(0.0, 1.0, 1.0),
            DVec3::new(1.0, 1.0, -1.0),
        ] {
            let origin = target - dir * 50.0;
            let ray = umbra_ref::truth::ray::Ray::new(origin, dir);
            assert!(
                bvh.closest(&ray, 0.0, 100.0).is_some(),
                "ray to {target} along {dir} leaks through"
            );
            rays += 1;
        }
    }
    assert_eq!(rays, 28);
}
