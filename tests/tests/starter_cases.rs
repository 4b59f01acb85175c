//! Every checked-in case parses, validates and has a unique id; the seed set-ups of
//! docs/catalogue.md §14 carry the write-ups' parameters.

use std::collections::BTreeSet;

use umbra_case::format::{Filter, Light};
use umbra_tests::{cases_dir, points};

#[test]
fn every_case_file_loads_and_ids_are_unique() {
    let files = umbra_case::case_files(&cases_dir()).expect("cases/ readable");
    assert!(
        files.len() >= 5,
        "expected the starter cases, found {files:?}"
    );
    let mut ids = BTreeSet::new();
    for f in files {
        let pts = umbra_case::load_file(&f).unwrap_or_else(|e| panic!("{e}"));
        for p in pts {
            assert!(ids.insert(p.id()), "duplicate run id {}", p.id());
        }
    }
}

#[test]
fn seed_setups_use_the_write_ups_parameters() {
    let d = points("lights/directional-ortho-10.json").remove(0).case;
    let Light::Directional(l) = &d.lights[0] else {
        panic!("directional")
    };
    let o = l.ortho.expect("explicit bounds");
    assert_eq!(
        (
            l.position,
            [o.left, o.right, o.bottom, o.top, o.near, o.far]
        ),
        (
            Some([-3.0, 20.0, 20.0]),
            [-10.0, 10.0, -10.0, 10.0, 0.1, 100.0]
        )
    );
    assert_eq!(
        (d.shadow.size, d.shadow.filter),
        ([512, 512], Filter::Linear)
    );

    let d = points("lights/directional-ortho-20.json").remove(0).case;
    let Light::Directional(l) = &d.lights[0] else {
        panic!("directional")
    };
    let o = l.ortho.expect("explicit bounds");
    assert_eq!(
        (l.position, [o.left, o.right, o.near, o.far]),
        (Some([-4.0, 2.6, -0.25]), [-20.0, 20.0, 0.2, 15.0])
    );

    let s = points("lights/spot-20deg.json").remove(0).case;
    let Light::Spot(l) = &s.lights[0] else {
        panic!("spot")
    };
    assert_eq!((l.fov_y_deg, l.near, l.far), (20.0, 1.0, 50.0));

    let cubes = points("packed-cubes/packed-cubes.json");
    assert_eq!(cubes.len(), 16, "a full turn in 16 steps");
}
