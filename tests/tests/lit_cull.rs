//! Lit-pass culling (`camera.cull`, issue 39): in `shading/lit-cull.json` the reference's lit
//! pass and the exact truth show the same surface at all but a sliver of pixels (edges), the
//! culled faces nowhere: back culling removes the wall seen from behind, front culling the
//! floor seen from above, and the camera rays pass through to what lies behind.

use umbra_case::Prepared;
use umbra_case::format::Cull;
use umbra_tests::points;

/// The objects of `lit-cull.json`, in its order.
const FLOOR: u32 = 0;
const WALL: u32 = 1;

/// Per pixel, the object the face id (`face + 1`, 0 background) belongs to.
fn objects_shown(run: &Prepared, faces: &[u32]) -> Vec<Option<u32>> {
    let geo = &run.geometry;
    let object_of = |face: u32| {
        geo.face
            .iter()
            .position(|f| *f == face)
            .map(|t| geo.object[t])
    };
    faces
        .iter()
        .map(|&f| f.checked_sub(1).and_then(object_of))
        .collect()
}

#[test]
fn culled_faces_show_nowhere_and_reference_and_truth_agree() {
    let mut seen = Vec::new();
    for point in points("shading/lit-cull.json") {
        let run = Prepared::new(point);
        let cull = run.case().camera.cull;
        let frame = umbra_ref::render(&run, umbra_case::ClipDepth::MinusOneToOne);
        let truth = umbra_ref::truth::ground_truth(&run.lights[0]);
        let by_ref = objects_shown(
            &run,
            frame.lights[0]
                .surface
                .as_deref()
                .expect("the reference's faces"),
        );
        let by_truth = objects_shown(&run, &truth.face);
        let n = by_ref.len();
        let differ = (0..n).filter(|&i| by_ref[i] != by_truth[i]).count();
        // Edges between surfaces: the pixel centre on one side for the ray, the other for
        // the rasteriser's snapped vertices, a few per cent of the pixels at most.
        assert!(
            differ * 50 < n,
            "{}: {differ} of {n} pixels show another object in the reference than in the truth",
            run.point.id()
        );
        let shows = |o: u32| by_truth.iter().filter(|s| **s == Some(o)).count();
        let (floor, wall) = (shows(FLOOR), shows(WALL));
        match cull {
            Cull::None => assert!(floor > n / 4 && wall > n / 50, "{}", run.point.id()),
            Cull::Back => assert!(floor > n / 4 && wall == 0, "{}", run.point.id()),
            Cull::Front => assert!(floor == 0 && wall > n / 50, "{}", run.point.id()),
        }
        let culled = match cull {
            Cull::None => None,
            Cull::Back => Some(WALL),
            Cull::Front => Some(FLOOR),
        };
        if let Some(i) = by_ref.iter().position(|o| o.is_some() && *o == culled) {
            panic!(
                "{}: the reference shows a culled face at pixel {i}",
                run.point.id()
            );
        }
        seen.push(cull);
    }
    for c in [Cull::None, Cull::Back, Cull::Front] {
        assert!(seen.contains(&c), "lit-cull.json has no {c:?} point");
    }
}
