//! Malformed and impossible cases: each must be refused with an error that names the file, the
//! JSON path and a fix. One test per mistake, so a failure names the mistake.

use std::path::Path;

use serde_json::{Value, json};
use umbra_case::{CaseErrors, load_str};

const FILE: &str = "cases/test/bad.json";

fn base() -> Value {
    json!({
        "name": "base",
        "about": "a valid case that each test breaks in one place",
        "scene": { "objects": [
            { "plane": { "point": [0, 0, 0], "half_extent": 10 } },
            { "box": { "center": [0, 1, 0], "size": [1, 1, 1] } },
            { "sphere": { "center": [2, 1, 0], "radius": 0.5 } },
            { "mesh": { "positions": [[0, 2, 0], [1, 2, 0], [0, 3, 0]], "triangles": [[0, 1, 2]] } }
        ] },
        "camera": { "eye": [0, 5, 10], "target": [0, 0, 0] },
        "light": { "spot": { "position": [3, 10, 3], "target": [0, 0, 0], "fov_y_deg": 60 } },
        "shadow": { "size": [256, 256] }
    })
}

/// Sets the value at a JSON pointer, creating objects on the way.
fn set(mut doc: Value, pointer: &str, v: Value) -> Value {
    let (parent, key) = pointer.rsplit_once('/').expect("pointer");
    let slot = if parent.is_empty() {
        &mut doc
    } else {
        doc.pointer_mut(parent).expect("parent exists")
    };
    match slot {
        Value::Object(m) => {
            m.insert(key.to_string(), v);
        }
        Value::Array(a) => a[key.parse::<usize>().expect("index")] = v,
        _ => panic!("not a container"),
    }
    doc
}

fn remove(mut doc: Value, pointer: &str) -> Value {
    let (parent, key) = pointer.rsplit_once('/').expect("pointer");
    doc.pointer_mut(parent)
        .and_then(Value::as_object_mut)
        .expect("object")
        .remove(key);
    doc
}

fn errors(doc: &Value) -> CaseErrors {
    match load_str(&doc.to_string(), Path::new(FILE)) {
        Ok(_) => panic!("accepted a malformed case: {doc}"),
        Err(e) => e,
    }
}

/// Asserts an error at `path` whose message contains `needle`, and that every error names the
/// file and carries a fix.
fn assert_error(doc: Value, path: &str, needle: &str) {
    let e = errors(&doc);
    assert!(
        e.has(path, needle),
        "expected an error at {path:?} containing {needle:?}, got:\n{e}"
    );
    for one in &e.0 {
        assert_eq!(one.file, Path::new(FILE));
        assert!(!one.fix.is_empty(), "no fix in {one}");
        let shown = one.to_string();
        assert!(
            shown.starts_with(FILE) && shown.contains("fix: "),
            "{shown}"
        );
    }
}

#[test]
fn the_base_case_is_valid() {
    let points = load_str(&base().to_string(), Path::new(FILE)).expect("valid");
    assert_eq!(points.len(), 1);
    assert_eq!(points[0].id(), "base");
}

#[test]
fn syntax_error_names_line_and_column() {
    let e = load_str("{\n  \"name\": \"x\",,\n}", Path::new(FILE)).expect_err("bad json");
    assert!(e.first().message.contains("line 2 column"), "{e}");
}

#[test]
fn unknown_field_is_an_error() {
    assert_error(
        set(base(), "/camera/fovy", json!(40)),
        "camera.fovy",
        "unknown field `fovy`",
    );
}

#[test]
fn unknown_field_deep_in_an_object() {
    assert_error(
        set(base(), "/scene/objects/1/box/centre", json!([0, 0, 0])),
        "scene.objects[1].box.centre",
        "unknown field `centre`",
    );
}

#[test]
fn missing_required_field() {
    assert_error(
        remove(base(), "/camera/eye"),
        "camera",
        "missing field `eye`",
    );
}

#[test]
fn wrong_type() {
    assert_error(
        set(base(), "/shadow/size", json!("large")),
        "shadow.size",
        "invalid type",
    );
}

#[test]
fn unknown_format_name() {
    assert_error(
        set(base(), "/shadow/format", json!("depth8")),
        "shadow.format",
        "unknown variant `depth8`",
    );
}

#[test]
fn zero_map_size() {
    assert_error(
        set(base(), "/shadow/size", json!([0, 256])),
        "shadow.size[0]",
        "from 1 to 16384",
    );
}

#[test]
fn huge_map_size() {
    assert_error(
        set(base(), "/shadow/size", json!([256, 100000])),
        "shadow.size[1]",
        "got 100000",
    );
}

#[test]
fn non_finite_number() {
    // JSON has no NaN; 1e39 overflows f32 to infinity, the same hazard.
    assert_error(
        set(base(), "/camera/eye", json!([1e39, 0, 0])),
        "camera.eye[0]",
        "not a finite f32",
    );
}

#[test]
fn near_not_below_far() {
    let doc = set(
        set(base(), "/camera/near", json!(10)),
        "/camera/far",
        json!(10),
    );
    assert_error(doc, "camera.far", "must be greater than near");
}

#[test]
fn perspective_near_must_be_positive() {
    assert_error(
        set(base(), "/light/spot/near", json!(0)),
        "light.spot.near",
        "must be > 0",
    );
}

#[test]
fn fov_out_of_range() {
    assert_error(
        set(base(), "/light/spot/fov_y_deg", json!(180)),
        "light.spot.fov_y_deg",
        "strictly between 0 and 180",
    );
}

#[test]
fn light_at_its_own_target() {
    assert_error(
        set(base(), "/light/spot/target", json!([3, 10, 3])),
        "light.spot.target",
        "same point",
    );
}

#[test]
fn camera_up_parallel_to_view() {
    let doc = set(
        set(base(), "/camera/eye", json!([0, 10, 0])),
        "/camera/target",
        json!([0, 0, 0]),
    );
    assert_error(doc, "camera.up", "parallel to the view direction");
}

#[test]
fn empty_scene() {
    assert_error(
        set(base(), "/scene/objects", json!([])),
        "scene.objects",
        "the scene is empty",
    );
}

#[test]
fn sphere_radius_not_positive() {
    assert_error(
        set(base(), "/scene/objects/2/sphere/radius", json!(-1)),
        "scene.objects[2].sphere.radius",
        "must be > 0",
    );
}

#[test]
fn sphere_too_few_segments() {
    assert_error(
        set(base(), "/scene/objects/2/sphere/segments", json!(3)),
        "scene.objects[2].sphere.segments",
        "from 4 to 512",
    );
}

#[test]
fn box_with_a_flat_side() {
    assert_error(
        set(base(), "/scene/objects/1/box/size", json!([1, 0, 1])),
        "scene.objects[1].box.size[1]",
        "must be > 0",
    );
}

#[test]
fn plane_normal_zero() {
    assert_error(
        set(base(), "/scene/objects/0/plane/normal", json!([0, 0, 0])),
        "scene.objects[0].plane.normal",
        "zero vector",
    );
}

#[test]
fn rotation_axis_zero() {
    let doc = set(
        base(),
        "/scene/objects/1/box/transform",
        json!({ "rotate_deg": { "axis": [0, 0, 0], "angle": 30 } }),
    );
    assert_error(
        doc,
        "scene.objects[1].box.transform.rotate_deg.axis",
        "zero vector",
    );
}

#[test]
fn zero_scale() {
    let doc = set(
        base(),
        "/scene/objects/1/box/transform",
        json!({ "scale": [1, 0, 1] }),
    );
    assert_error(doc, "scene.objects[1].box.transform.scale[1]", "zero scale");
}

#[test]
fn mesh_index_out_of_range() {
    assert_error(
        set(
            base(),
            "/scene/objects/3/mesh/triangles",
            json!([[0, 1, 3]]),
        ),
        "scene.objects[3].mesh.triangles[0]",
        "out of range",
    );
}

#[test]
fn mesh_degenerate_triangle() {
    assert_error(
        set(
            base(),
            "/scene/objects/3/mesh/triangles",
            json!([[0, 1, 1]]),
        ),
        "scene.objects[3].mesh.triangles[0]",
        "zero area",
    );
}

#[test]
fn pcf_kernel_too_wide() {
    assert_error(
        set(base(), "/shadow/filter", json!({ "pcf": 31 })),
        "shadow.filter.pcf",
        "from 2 to 15",
    );
}

#[test]
fn directional_with_both_bounds() {
    let doc = set(
        base(),
        "/light",
        json!({ "directional": { "position": [0, 10, 1], "fit": "scene",
                                 "ortho": { "left": -1, "right": 1, "bottom": -1, "top": 1, "near": 0, "far": 20 } } }),
    );
    assert_error(doc, "light.directional.fit", "both explicit bounds");
}

#[test]
fn directional_without_bounds() {
    let doc = set(
        base(),
        "/light",
        json!({ "directional": { "position": [0, 10, 1] } }),
    );
    assert_error(doc, "light.directional.ortho", "needs bounds");
}

#[test]
fn directional_half_placed_by_angles() {
    let doc = set(
        base(),
        "/light",
        json!({ "directional": { "azimuth_deg": 30, "fit": "scene" } }),
    );
    assert_error(doc, "light.directional.elevation_deg", "missing");
}

#[test]
fn ortho_bounds_inverted() {
    let doc = set(
        base(),
        "/light",
        json!({ "directional": { "position": [0, 10, 1],
                                 "ortho": { "left": 1, "right": -1, "bottom": -1, "top": 1, "near": 0, "far": 20 } } }),
    );
    assert_error(doc, "light.directional.ortho.right", "must exceed left");
}

#[test]
fn point_light_needs_square_faces() {
    let doc = set(
        base(),
        "/light",
        json!({ "point": { "position": [0, 5, 0] } }),
    );
    assert_error(
        set(doc, "/shadow/size", json!([256, 128])),
        "shadow.size",
        "square faces",
    );
}

#[test]
fn ambient_out_of_range() {
    assert_error(
        set(base(), "/shading", json!({ "ambient": 1.5 })),
        "shading.ambient",
        "must be in [0, 1]",
    );
}

#[test]
fn invalid_name() {
    assert_error(
        set(base(), "/name", json!("Packed Cubes")),
        "name",
        "not a valid case name",
    );
}

#[test]
fn empty_about() {
    assert_error(set(base(), "/about", json!(" ")), "about", "is empty");
}

#[test]
fn sweep_of_an_unknown_field() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "light.spot.fov": { "values": [10, 20] } }),
    );
    let e = errors(&doc);
    let first = e.first();
    assert!(
        first.message.contains("at sweep point light.spot.fov=10")
            && first.message.contains("unknown field `fov`"),
        "{e}"
    );
    assert!(first.fix.contains("sweep.light.spot.fov"), "{e}");
}

#[test]
fn sweep_to_an_impossible_value() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "light.spot.fov_y_deg": { "from": 90, "to": 270, "steps": 3 } }),
    );
    let e = errors(&doc);
    assert!(
        e.has(
            "light.spot.fov_y_deg",
            "at sweep point light.spot.fov_y_deg=180"
        ),
        "{e}"
    );
}

#[test]
fn sweep_without_steps() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "light.spot.fov_y_deg": { "from": 10, "to": 20 } }),
    );
    assert_error(
        doc,
        "sweep.light.spot.fov_y_deg.from",
        "needs from, to and steps",
    );
}

#[test]
fn log_sweep_through_zero() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "light.spot.near": { "from": 0, "to": 1, "steps": 3, "scale": "log" } }),
    );
    assert_error(doc, "sweep.light.spot.near.scale", "log spacing");
}

#[test]
fn every_problem_is_reported_at_once() {
    let doc = set(
        set(base(), "/shadow/size", json!([0, 0])),
        "/camera/fov_y_deg",
        json!(0),
    );
    let e = errors(&doc);
    assert!(e.0.len() >= 3, "{e}");
}

#[test]
fn sweeps_expand_to_the_cartesian_product_in_order() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "light.spot.fov_y_deg": { "from": 20, "to": 60, "steps": 3 },
                "shadow.format": { "values": ["depth16", "depth32f"] } }),
    );
    let points = load_str(&doc.to_string(), Path::new(FILE)).expect("valid sweep");
    let ids: Vec<String> = points.iter().map(|p| p.id()).collect();
    assert_eq!(ids.len(), 6);
    assert_eq!(ids[0], "base@light.spot.fov_y_deg=20,shadow.format=depth16");
    assert_eq!(
        ids[1],
        "base@light.spot.fov_y_deg=20,shadow.format=depth32f"
    );
    assert_eq!(
        ids[5],
        "base@light.spot.fov_y_deg=60,shadow.format=depth32f"
    );
    assert!(points.iter().all(|p| p.case.sweep.is_empty()));
    let umbra_case::format::Light::Spot(s) = &points[2].case.lights[0] else {
        panic!("spot")
    };
    assert_eq!(s.fov_y_deg, 40.0);
}

#[test]
fn log_sweeps_are_evenly_spaced_in_decades() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "light.spot.near": { "from": 0.001, "to": 1, "steps": 4, "scale": "log" } }),
    );
    let points = load_str(&doc.to_string(), Path::new(FILE)).expect("valid");
    let nears: Vec<f32> = points
        .iter()
        .map(|p| match &p.case.lights[0] {
            umbra_case::format::Light::Spot(s) => s.near,
            _ => unreachable!(),
        })
        .collect();
    assert_eq!(nears, vec![0.001, 0.01, 0.1, 1.0]);
}

#[test]
fn twin_with_a_bad_value_names_the_twin() {
    let doc = set(
        base(),
        "/expect",
        json!({ "twins": [ { "name": "t", "set": { "shadow.format": "depth48" } } ] }),
    );
    let e = errors(&doc);
    assert!(
        e.0.iter()
            .any(|x| x.message.contains("expect.twins[0]") && x.message.contains("depth48")),
        "{e}"
    );
}

#[test]
fn twin_that_sets_nothing_is_an_error() {
    assert_error(
        set(
            base(),
            "/expect",
            json!({ "twins": [ { "name": "t", "set": {} } ] }),
        ),
        "expect.twins[0].set",
        "sets nothing",
    );
}

#[test]
fn twin_may_not_take_the_built_in_name() {
    assert_error(
        set(
            base(),
            "/expect",
            json!({ "twins": [ { "name": "bias-order", "set": { "shadow.cull": "front" } } ] }),
        ),
        "expect.twins[0].name",
        "is taken",
    );
}

#[test]
fn error_falls_along_must_name_a_swept_path() {
    let doc = set(
        set(
            base(),
            "/sweep",
            json!({ "shadow.size": { "values": [[128, 128], [256, 256]] } }),
        ),
        "/expect",
        json!({ "error_falls_along": "shadow.format" }),
    );
    assert_error(doc, "expect.error_falls_along", "not a swept path");
}

#[test]
fn scene_offset_must_be_finite() {
    assert_error(
        set(base(), "/scene/offset", json!([1e39, 0, 0])),
        "scene.offset[0]",
        "not a finite f32",
    );
}

/// The base case with a mipmapped map of `levels` levels.
fn mipmapped(levels: u32) -> Value {
    set(base(), "/shadow/mipmaps", json!({ "levels": levels }))
}

#[test]
fn mipmaps_validate_and_name_the_field_that_breaks_them() {
    let ok = umbra_case::load_str(&mipmapped(9).to_string(), std::path::Path::new("m.json"));
    assert!(ok.is_ok(), "{ok:?}");
    assert_error(mipmapped(1), "shadow.mipmaps.levels", "from 2 to 9");
    assert_error(mipmapped(10), "shadow.mipmaps.levels", "from 2 to 9");
    assert_error(
        set(mipmapped(3), "/shadow/size", json!([300, 256])),
        "shadow.size",
        "power-of-two",
    );
    assert_error(
        set(mipmapped(3), "/shadow/compare", json!("manual")),
        "shadow.compare",
        "needs `hardware`",
    );
    assert_error(
        set(mipmapped(3), "/shadow/filter", json!({ "pcf": 3 })),
        "shadow.filter",
        "`nearest` or `linear`",
    );
    assert_error(
        set(
            mipmapped(3),
            "/light",
            json!({ "point": { "position": [0, 5, 0] } }),
        ),
        "shadow.mipmaps",
        "2D maps only",
    );
    assert_error(
        set(
            mipmapped(3),
            "/shadow/mipmaps",
            json!({ "levels": 3, "source": "generated" }),
        ),
        "shadow.mipmaps.source",
        "expected `rendered` or `averaged`",
    );
}

fn cascaded(cascades: Value) -> Value {
    set(
        base(),
        "/light",
        json!({ "directional": { "azimuth_deg": 30, "elevation_deg": 50, "cascades": cascades } }),
    )
}

#[test]
fn cascades_validate_and_name_the_field_that_breaks_them() {
    for ok in [
        json!({ "count": 1 }),
        json!({ "count": 6, "split": "logarithmic" }),
        json!({ "count": 3, "split": "practical", "lambda": 1 }),
    ] {
        let r = load_str(&cascaded(ok.clone()).to_string(), Path::new("c.json"));
        assert!(r.is_ok(), "{ok}: {r:?}");
    }
    assert_error(
        cascaded(json!({ "count": 0 })),
        "light.directional.cascades.count",
        "from 1 to 6",
    );
    assert_error(
        cascaded(json!({ "count": 7 })),
        "light.directional.cascades.count",
        "from 1 to 6",
    );
    assert_error(
        cascaded(json!({ "count": 2, "lambda": 1.5 })),
        "light.directional.cascades.lambda",
        "got 1.5",
    );
    assert_error(
        cascaded(json!({ "count": 2, "split": "uniform", "lambda": 0.5 })),
        "light.directional.cascades.lambda",
        "practical scheme only",
    );
    assert_error(
        set(
            cascaded(json!({ "count": 2 })),
            "/light/directional/fit",
            json!("scene"),
        ),
        "light.directional.fit",
        "fit each cascade's bounds",
    );
    assert_error(
        set(
            cascaded(json!({ "count": 2 })),
            "/shadow/mipmaps",
            json!({ "levels": 2 }),
        ),
        "shadow.mipmaps",
        "cascade array",
    );
    let ok = cascaded(
        json!({ "count": 3, "split": "fractions", "at": [0.2, 0.5], "distance": 8, "blend": 0.5 }),
    );
    let r = load_str(&ok.to_string(), Path::new("c.json"));
    assert!(r.is_ok(), "{r:?}");
    assert_error(
        cascaded(json!({ "count": 3, "split": "fractions" })),
        "light.directional.cascades.at",
        "needs its split fractions",
    );
    for at in [json!([0.5]), json!([0.5, 0.2]), json!([0.2, 1.0])] {
        assert_error(
            cascaded(json!({ "count": 3, "split": "fractions", "at": at })),
            "light.directional.cascades.at",
            "increasing fractions",
        );
    }
    assert_error(
        cascaded(json!({ "count": 3, "at": [0.2, 0.5] })),
        "light.directional.cascades.at",
        "fractions scheme only",
    );
    // The base camera sees from its default near plane (0.1) to its far plane (100).
    for distance in [0.05, 101.0] {
        assert_error(
            cascaded(json!({ "count": 2, "distance": distance })),
            "light.directional.cascades.distance",
            "beyond the camera's near plane",
        );
    }
    assert_error(
        cascaded(json!({ "count": 2, "blend": 0.6 })),
        "light.directional.cascades.blend",
        "at most half",
    );
}

/// Two sweep points with one name (a value repeated or written two ways) would be two runs,
/// two report rows and one golden under one name (issue 36); two values that round to one
/// f32 would be the same run twice.
#[test]
fn sweep_points_with_one_name_or_one_case() {
    let doc = set(
        base(),
        "/sweep",
        json!({ "shadow.bias.constant": { "values": [0.0005, 0.0005, 5e-4] } }),
    );
    assert_error(
        doc,
        "sweep.shadow.bias.constant",
        "sweep points 1 and 2 of 3 are both",
    );
    let doc = set(
        base(),
        "/sweep",
        json!({ "shadow.bias.constant": { "values": [0.0005, 0.00050000001] } }),
    );
    assert_error(doc, "sweep.shadow.bias.constant", "are the same case");
}

#[test]
fn light_colour_intensity_and_clear_colour_validate_and_name_the_field() {
    let ok = set(
        set(base(), "/light/spot/color", json!([1, 0.5, 0.25])),
        "/light/spot/intensity",
        json!(2.5),
    );
    let ok = set(ok, "/camera/clear", json!([0.1, 0.2, 0.3]));
    let points = load_str(&ok.to_string(), Path::new(FILE)).expect("valid");
    // Written back only where given, so no existing point's id moves.
    let text = serde_json::to_string(&points[0].case).expect("json");
    assert!(text.contains("\"intensity\":2.5") && text.contains("\"clear\":[0.1,0.2,0.3]"));
    let plain = load_str(&base().to_string(), Path::new(FILE)).expect("valid");
    let light = serde_json::to_string(&plain[0].case.lights[0]).expect("json");
    let camera = serde_json::to_string(&plain[0].case.camera).expect("json");
    assert!(!light.contains("intensity") && !light.contains("color") && !camera.contains("clear"));
    assert_error(
        set(base(), "/light/spot/color", json!([1, 1.5, 0])),
        "light.spot.color[1]",
        "must be in [0, 1]",
    );
    assert_error(
        set(base(), "/light/spot/intensity", json!(-1)),
        "light.spot.intensity",
        "must be ≥ 0",
    );
    assert_error(
        set(base(), "/camera/clear", json!([0, 0, 2])),
        "camera.clear[2]",
        "must be in [0, 1]",
    );
    let point = set(
        remove(base(), "/light/spot"),
        "/light/point",
        json!({ "position": [0, 5, 0], "color": [0, -0.5, 0] }),
    );
    assert_error(point, "light.point.color[1]", "must be in [0, 1]");
}

#[test]
fn a_depth_function_that_keeps_the_farther_surface_is_refused_with_the_fix() {
    for (order, func) in [
        ("forward", "less_equal"),
        ("forward", "less"),
        ("reversed", "greater_equal"),
        ("reversed", "greater"),
    ] {
        let doc = set(base(), "/shadow/depth_order", json!(order));
        let doc = set(doc, "/shadow/depth_func", json!(func));
        let points = load_str(&doc.to_string(), Path::new(FILE)).expect("valid");
        assert_eq!(points[0].case.shadow.depth_test().name(), func);
    }
    // Left out of a point's JSON where not given, so no existing point's id moves.
    let plain = load_str(&base().to_string(), Path::new(FILE)).expect("valid");
    let shadow = serde_json::to_string(&plain[0].case.shadow).expect("json");
    assert!(!shadow.contains("depth_func"));
    assert_eq!(plain[0].case.shadow.depth_test().name(), "less");
    let wrong = set(base(), "/shadow/depth_func", json!("greater_equal"));
    assert_error(wrong, "shadow.depth_func", "keeps the farther surface");
    let wrong = set(base(), "/shadow/depth_order", json!("reversed"));
    let wrong = set(wrong, "/shadow/depth_func", json!("less"));
    assert_error(
        wrong,
        "shadow.depth_func",
        "farther surface in reversed depth order",
    );
    let unknown = set(base(), "/shadow/depth_func", json!("lequal"));
    assert_error(unknown, "shadow.depth_func", "unknown variant");
}

/// `base()` lit by `lights` instead of its one `light`.
fn with_lights(lights: Value) -> Value {
    let mut doc = base();
    doc.as_object_mut().expect("object").remove("light");
    set(doc, "/lights", lights)
}

#[test]
fn several_lights_are_a_list_and_are_refused_with_the_fix_where_not_modelled() {
    let spot = json!({ "spot": { "position": [3, 10, 3], "target": [0, 0, 0], "fov_y_deg": 60 } });
    let sun = json!({ "directional": { "azimuth_deg": 30, "elevation_deg": 50, "fit": "scene" } });
    let lamp = json!({ "point": { "position": [0, 3, 0], "near": 0.2, "far": 30 } });
    let doc = with_lights(json!([spot, sun]));
    let points = load_str(&doc.to_string(), Path::new(FILE)).expect("valid");
    let case = &points[0].case;
    assert_eq!(case.lights.len(), 2);
    // Light 1's run: that light alone, no ambient term (the first light's pass adds it).
    let one = case.for_light(1);
    assert_eq!(one.lights, [case.lights[1].clone()]);
    assert!(one.shading.ambient == 0.0);
    assert_eq!(case.for_light(0).shading.ambient, case.shading.ambient);
    // Written back, the case holds both, `light` the first of `lights` (paths and conditions
    // that name `light` read it), and reads back the same.
    let written = serde_json::to_value(case).expect("json");
    assert_eq!(written["light"], written["lights"][0], "{written}");
    let again = load_str(&written.to_string(), Path::new(FILE)).expect("reads back");
    assert_eq!(&again[0].case, case);
    // One light is written back as `light` alone, as its file gave it.
    let single = serde_json::to_value(
        &load_str(&base().to_string(), Path::new(FILE)).expect("valid")[0].case,
    )
    .expect("json");
    assert!(
        single.get("lights").is_none() && single.get("light").is_some(),
        "{single}"
    );
    // Both given and different: which one is meant?
    let both = set(doc.clone(), "/light", sun.clone());
    assert_error(both, "light", "`light` is not `lights[0]`");
    assert_error(with_lights(json!([spot])), "lights", "2 to 4");
    assert_error(
        with_lights(json!([spot, sun, spot, sun, spot])),
        "lights",
        "2 to 4",
    );
    // A light's own error is named under its index.
    let bad = with_lights(
        json!([spot, { "spot": { "position": [3, 10, 3], "target": [3, 10, 3], "fov_y_deg": 60 } }]),
    );
    assert!(
        errors(&bad)
            .0
            .iter()
            .any(|e| e.path.starts_with("lights[1].spot"))
    );
    let array = set(
        with_lights(json!([spot, lamp])),
        "/shadow/placement",
        json!("array"),
    );
    assert_error(array, "shadow.placement", "point light");
    // A cube-map array holds point lights' cubes only.
    let cubes = set(
        with_lights(json!([lamp, spot])),
        "/shadow/placement",
        json!("cube_array"),
    );
    assert_error(cubes, "shadow.placement", "no cube in a cube array");
    let cubes = set(
        with_lights(json!([lamp, lamp])),
        "/shadow/placement",
        json!("cube_array"),
    );
    load_str(&cubes.to_string(), Path::new(FILE)).expect("two point lights in a cube array");
    let classic = set(doc.clone(), "/shading", json!({ "model": "classic" }));
    assert_error(classic, "shading.model", "several shadows");
    let cascaded = json!({ "directional": { "azimuth_deg": 30, "elevation_deg": 50,
        "cascades": { "count": 2, "split": "uniform" } } });
    assert_error(
        with_lights(json!([spot, cascaded])),
        "lights[1].directional.cascades",
        "one of several",
    );
    let mip = set(doc, "/shadow/placement", json!("array"));
    let mip = set(mip, "/shadow/mipmaps", json!({ "levels": 2 }));
    assert_error(mip, "shadow.mipmaps", "no mip levels");
    assert_error(
        set(base(), "/shadow/placement", json!("layered")),
        "shadow.placement",
        "unknown variant",
    );
}

/// Bevy's forms: a band of the far bound must stay within half each cascade's range, and
/// the texel and world offsets belong to directional lights only.
#[test]
fn bevy_forms_validate_and_name_their_fields() {
    // Uniform splits of [0.1, 100]: cascade 0 is [0.1, 33.4], cascade 1 [33.4, 66.7]. A band
    // of 0.2 of each far bound (6.7, 13.3) is within half each range (16.7); one of 0.45 is
    // for cascade 0 (15.0) but not for cascade 1 (30.0).
    let ok = cascaded(
        json!({ "count": 3, "split": "uniform", "blend": 0.2, "blend_of": "far", "fit": "stable" }),
    );
    let r = load_str(&ok.to_string(), Path::new("c.json"));
    assert!(r.is_ok(), "{r:?}");
    assert_error(
        cascaded(json!({ "count": 3, "split": "uniform", "blend": 0.45, "blend_of": "far" })),
        "light.directional.cascades.blend",
        "more than half its range",
    );
    let with_offsets = |doc: Value| {
        set(
            doc,
            "/shadow/bias",
            json!({ "normal_offset_texels": 1.8, "light_offset": 0.02 }),
        )
    };
    let r = load_str(
        &with_offsets(cascaded(json!({ "count": 2 }))).to_string(),
        Path::new("c.json"),
    );
    assert!(r.is_ok(), "{r:?}");
    for field in ["normal_offset_texels", "light_offset"] {
        assert_error(
            with_offsets(base()),
            &format!("shadow.bias.{field}"),
            "only a directional light's map",
        );
    }
}
