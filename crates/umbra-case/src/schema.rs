//! The case format as a schema that a condition over a case point can be checked against.
//!
//! `@when shadow.bias.constant>0` in an expectation file reads a case point's JSON; a
//! mistyped path (`shadow.bais.constant`) or a value its field can never hold (`>>0`,
//! `shadow.filter=pcf`) would otherwise make the lines under it silently never apply, or, with
//! `!=`, always apply. [`check_term`] refuses both, against the format's own serde types:
//!
//! - A path must resolve in one of the [`EXEMPLARS`]: case documents that together use every
//!   field and every variant of [`crate::format`] (a test holds every catalogue case point to
//!   them, so a field added to the format and used fails that test until it is added here).
//!   Arrays of numbers are fixed-size vectors (`[x, y, z]`), so their index is bounded;
//!   arrays of objects are lists (`scene.objects[7]`), any index.
//! - A value is put at that path in the exemplar and the document deserialized as a
//!   [`crate::format::Case`]: what serde refuses (a string in a number field, an unknown enum
//!   word, 1.5 for a map size) the field can never hold. `null` is allowed only where the
//!   field can be absent (an `Option`, another variant's key).
//! - `<`, `>`, `<=`, `>=` need a number field and a number.
//!
//! Numbers in a case are `f32`; [`compare_numbers`] compares at that precision, so
//! `constant=0.0005` holds for a case that wrote 0.0005 (its f32 widened to f64 is
//! 0.000500000023748725, which no decimal in a condition equals).

use serde_json::Value;

/// Case documents that together use every field and variant of the case format.
pub const EXEMPLARS: &[&str] = &[
    // Only what is required: every Option absent or null, untagged enums in their scalar form.
    r#"{"name":"a","about":"a","scene":{"objects":[{"plane":{"point":[0,0,0],"half_extent":1}}]},
        "camera":{"eye":[0,1,1],"target":[0,0,0]},"light":{"directional":{"azimuth_deg":0,"elevation_deg":45}}}"#,
    // Every field written, directional light by position with an explicit box.
    r#"{"name":"b","about":"b",
        "scene":{"objects":[
            {"plane":{"point":[0,0,0],"normal":[0,1,0],"half_extent":[1,2],"color":[1,1,1],
                      "transform":{"translate":[0,0,0],"rotate_deg":{"axis":[0,1,0],"angle":10},"scale":1}}},
            {"box":{"center":[0,0,0],"size":[1,1,1],"color":[1,1,1],
                    "transform":{"translate":[0,0,0],"rotate_deg":{"axis":[0,1,0],"angle":10},"scale":[1,1,1]}}},
            {"sphere":{"center":[0,0,0],"radius":1,"segments":16,"color":[1,1,1],"transform":{"translate":[0,0,0],"rotate_deg":{"axis":[0,1,0],"angle":10}}}},
            {"cylinder":{"center":[0,0,0],"radius":1,"height":2,"segments":12,"color":[1,1,1],"transform":{"translate":[0,0,0],"rotate_deg":{"axis":[1,0,0],"angle":90}}}},
            {"mesh":{"positions":[[0,0,0],[1,0,0],[0,1,0]],"triangles":[[0,1,2]],"color":[1,1,1],"transform":{"translate":[0,0,0],"rotate_deg":{"axis":[0,1,0],"angle":10}}}}],
            "offset":[1,0,0]},
        "camera":{"eye":[0,1,1],"target":[0,0,0],"up":[0,1,0],"fov_y_deg":45,"near":0.1,"far":10,"size":[64,64],
                  "clear":[0.1,0.2,0.3],"cull":"back","color_format":"srgb8_alpha8"},
        "light":{"directional":{"position":[0,1,0],"azimuth_deg":0,"elevation_deg":45,"distance":10,"target":[0,0,0],
                 "up":[0,1,0],"ortho":{"left":-1,"right":1,"bottom":-1,"top":1,"near":0.1,"far":10},"fit":"scene",
                 "color":[1,0.5,0.5],"intensity":2}},
        "shadow":{"size":[256,256],"format":"depth24","filter":{"pcf":3},"compare":"manual",
                  "bias":{"constant":0.001,"polygon_offset":[1,1],"polygon_offset_clamp":0,"slope":{"scale":1,"max":1},
                          "n_dot_l":{"scale":1,"min":0,"light":"position"},"normal_offset":0,
                          "normal_offset_texels":1.8,"light_offset":0.02},
                  "cull":"back","bias_matrix":"after_divide","attachments":"with_color","outside":"border",
                  "beyond_far":"lit","depth_clamp":true,"guard_behind_light":true,"depth_order":"reversed",
                  "depth_func":"greater_equal","mipmaps":{"levels":2,"filter":"linear","source":"averaged"}},
        "shading":{"model":"classic","ambient":0.1,"dimming":0.5,"specular":0.2,"shininess":16,"shadowed_factor":0.2},
        "sweep":{"shadow.bias.constant":{"from":0,"to":1,"steps":2,"scale":"linear","values":[0]}},
        "expect":{"backends_agree":true,"interior_error":"zero","twins":[{"name":"t","set":{},"agree":"legal"}],
                  "error_falls_along":"shadow.bias.constant"}}"#,
    r#"{"name":"c","about":"c","scene":{"objects":[{"plane":{"point":[0,0,0],"half_extent":1}}]},
        "camera":{"eye":[0,1,1],"target":[0,0,0]},
        "light":{"spot":{"position":[0,1,0],"target":[0,0,0],"up":[0,0,1],"fov_y_deg":60,"near":0.1,"far":10,
                 "color":[0.5,1,0.5],"intensity":0.5}}}"#,
    r#"{"name":"d","about":"d","scene":{"objects":[{"plane":{"point":[0,0,0],"half_extent":1}}]},
        "camera":{"eye":[0,1,1],"target":[0,0,0]},
        "light":{"point":{"position":[0,1,0],"near":0.1,"far":10,"color":[1,1,0.5],"intensity":3}}}"#,
    r#"{"name":"e","about":"e","scene":{"objects":[{"plane":{"point":[0,0,0],"half_extent":1}}]},
        "camera":{"eye":[0,1,1],"target":[0,0,0]},
        "light":{"directional":{"azimuth_deg":0,"elevation_deg":45,
                 "cascades":{"count":3,"split":"practical","lambda":0.5,"at":[0.2,0.5,0.8],"distance":5,"blend":0.1,
                 "blend_of":"far","fit":"stable"}}}}"#,
    // Several lights, one of each kind, every field written; `light` is the first of them.
    r#"{"name":"f","about":"f","scene":{"objects":[{"plane":{"point":[0,0,0],"half_extent":1}}]},
        "camera":{"eye":[0,1,1],"target":[0,0,0]},
        "light":{"spot":{"position":[0,1,0],"target":[0,0,0],"up":[0,0,1],"fov_y_deg":60,"near":0.1,"far":10,
                 "color":[0.5,1,0.5],"intensity":0.5}},
        "lights":[
          {"spot":{"position":[0,1,0],"target":[0,0,0],"up":[0,0,1],"fov_y_deg":60,"near":0.1,"far":10,
                   "color":[0.5,1,0.5],"intensity":0.5}},
          {"directional":{"position":[0,1,0],"azimuth_deg":0,"elevation_deg":45,"distance":10,"target":[0,0,0],
                 "up":[0,1,0],"ortho":{"left":-1,"right":1,"bottom":-1,"top":1,"near":0.1,"far":10},"fit":"scene",
                 "color":[1,0.5,0.5],"intensity":2}},
          {"point":{"position":[0,1,0],"near":0.1,"far":10,"color":[1,1,0.5],"intensity":3}}],
        "shadow":{"placement":"array"}}"#,
];

/// The exemplars as JSON with every default filled in, as a case point's JSON is.
fn exemplars() -> Vec<Value> {
    EXEMPLARS
        .iter()
        .map(|text| {
            let case: crate::format::Case =
                serde_json::from_str(text).expect("a schema exemplar is a valid case");
            serde_json::to_value(case).expect("a case serializes")
        })
        .collect()
}

/// The steps of the dotted `path`: each an object key, then its array indices
/// (`positions[3][1]`); `Err` names a bad segment.
fn steps(path: &str) -> Result<Vec<(&str, Vec<usize>)>, String> {
    path.split('.')
        .map(|seg| {
            let (key, mut rest) = seg.split_at(seg.find('[').unwrap_or(seg.len()));
            if key.is_empty() {
                return Err(format!("{seg:?} is not KEY or KEY[INDEX]"));
            }
            let mut indices = Vec::new();
            while let Some(inner) = rest.strip_prefix('[') {
                let close = inner
                    .find(']')
                    .ok_or(format!("{seg:?} has an unclosed ["))?;
                let i = inner[..close]
                    .parse::<usize>()
                    .map_err(|_| format!("{seg:?} has an index that is not a number"))?;
                indices.push(i);
                rest = &inner[close + 1..];
            }
            if rest.is_empty() {
                Ok((key, indices))
            } else {
                Err(format!("{seg:?} is not KEY or KEY[INDEX]"))
            }
        })
        .collect()
}

/// Where `path` resolves in `doc`: the concrete JSON pointer and the value; `Err(true)` where
/// it stops at a key its parent may lack (so null is a value it can have), `Err(false)` where
/// it does not name a field at all.
fn resolve<'v>(doc: &'v Value, path: &str) -> Result<(String, &'v Value), bool> {
    let Ok(steps) = steps(path) else {
        return Err(false);
    };
    walk(doc, &steps, String::new())
}

fn walk<'v>(
    cur: &'v Value,
    steps: &[(&str, Vec<usize>)],
    pointer: String,
) -> Result<(String, &'v Value), bool> {
    let Some(((key, indices), rest)) = steps.split_first() else {
        return Ok((pointer, cur));
    };
    let Some(obj) = cur.as_object() else {
        return Err(false);
    };
    let Some(next) = obj.get(*key) else {
        // A key an exemplar lacks at the last step may be another variant's or an absent
        // option's: the caller tries the other exemplars too.
        return Err(rest.is_empty() && indices.is_empty());
    };
    index(next, indices, rest, format!("{pointer}/{key}"))
}

/// The indices of one step, then the rest of the path.
fn index<'v>(
    cur: &'v Value,
    indices: &[usize],
    rest: &[(&str, Vec<usize>)],
    pointer: String,
) -> Result<(String, &'v Value), bool> {
    let Some((i, more)) = indices.split_first() else {
        return walk(cur, rest, pointer);
    };
    let Some(items) = cur.as_array() else {
        return Err(false);
    };
    if items.iter().all(Value::is_number) {
        // A vector of numbers (`[x, y, z]`) is fixed-size: only its own indices.
        return match items.get(*i) {
            Some(v) => index(v, more, rest, format!("{pointer}/{i}")),
            None => Err(false),
        };
    }
    // A list (objects, vertices) takes any index: the rest of the path in any of its items.
    let mut absent = false;
    for (at, item) in items.iter().enumerate() {
        match index(item, more, rest, format!("{pointer}/{at}")) {
            Ok(found) => return Ok(found),
            Err(a) => absent |= a,
        }
    }
    Err(absent)
}

/// Checks one condition term against the case format: `path` names a field (or an element of
/// one), and `value` is a value that field can hold (compared with `op`). The error says what
/// is wrong and what would be right.
pub fn check_term(path: &str, op: &str, value: &Value) -> Result<(), String> {
    steps(path).map_err(|e| format!("path {path:?}: {e}"))?;
    let docs = exemplars();
    let mut may_be_absent = false;
    let mut found = Vec::new();
    for doc in &docs {
        match resolve(doc, path) {
            Ok((pointer, at)) => {
                may_be_absent |= at.is_null();
                found.push((doc, pointer, at));
            }
            Err(absent) => may_be_absent |= absent,
        }
    }
    if found.is_empty() {
        return Err(format!(
            "path {path:?} names no field of the case format (cases/README.md lists them; \
             e.g. shadow.bias.constant, shadow.filter, light.point.near, scene.objects[0].box.size[1])"
        ));
    }
    if value.is_null() {
        return if may_be_absent && matches!(op, "=" | "!=") {
            Ok(())
        } else {
            Err(format!(
                "{path}{op}null can never hold: {path} is always present in a case point"
            ))
        };
    }
    let ordered = matches!(op, "<" | ">" | "<=" | ">=");
    let mut refusal = String::new();
    for (doc, pointer, at) in found {
        if ordered && !(value.is_number() && at.is_number()) {
            refusal = format!("{op} compares numbers, and {path} or {value} is not one");
            continue;
        }
        let mut doc = doc.clone();
        // A case of several lights writes its first twice (`light` is `lights[0]`, which
        // the format holds it to): a value put in one is put in the other.
        let twin = pointer
            .strip_prefix("/light/")
            .map(|rest| format!("/lights/0/{rest}"))
            .or_else(|| {
                pointer
                    .strip_prefix("/lights/0/")
                    .map(|rest| format!("/light/{rest}"))
            });
        for at in std::iter::once(&pointer).chain(twin.as_ref()) {
            if let Some(slot) = doc.pointer_mut(at) {
                *slot = value.clone();
            }
        }
        match serde_json::from_value::<crate::format::Case>(doc) {
            Ok(_) => return Ok(()),
            Err(e) => refusal = format!("{path} can never be {value}: {e}"),
        }
    }
    Err(refusal)
}

/// A case point as conditions read it: its JSON with the defaults serde leaves out written
/// in (`scene.offset` `[0, 0, 0]`, `shadow.beyond_far` `compare`, `shadow.depth_clamp`
/// `false`, `shadow.bias.n_dot_l.light` `direction`, `camera.clear` `[0, 0, 0]`,
/// `camera.cull` `none`, `camera.color_format` `rgba8`, the light's `color` `[1, 1, 1]` and
/// `intensity` 1,
/// `shadow.depth_func` the order's strict function), so `@when shadow.beyond_far=compare` holds where the case did not write it.
pub fn condition_json(case: &crate::format::Case) -> Value {
    let mut v = serde_json::to_value(case).unwrap_or_default();
    let mut put = |pointer: &str, key: &str, value: Value| {
        if let Some(obj) = v.pointer_mut(pointer).and_then(Value::as_object_mut) {
            obj.entry(key).or_insert(value);
        }
    };
    put("/scene", "offset", serde_json::json!([0, 0, 0]));
    put("/shadow", "beyond_far", serde_json::json!("compare"));
    put("/shadow", "depth_clamp", serde_json::json!(false));
    put(
        "/shadow",
        "depth_func",
        serde_json::json!(case.shadow.depth_test().name()),
    );
    put("/camera", "clear", serde_json::json!([0, 0, 0]));
    put("/camera", "cull", serde_json::json!("none"));
    put("/camera", "color_format", serde_json::json!("rgba8"));
    for kind in ["directional", "spot", "point"] {
        put(
            &format!("/light/{kind}"),
            "color",
            serde_json::json!([1, 1, 1]),
        );
        put(&format!("/light/{kind}"), "intensity", serde_json::json!(1));
    }
    put(
        "/shadow/bias/n_dot_l",
        "light",
        serde_json::json!("direction"),
    );
    v
}

/// Orders a case's number against a condition's: at `f32`, the precision every number of the
/// case format has, so the decimal a user writes in a condition means what the same decimal
/// means in a case file.
pub fn compare_numbers(case: f64, condition: f64) -> Option<std::cmp::Ordering> {
    (case as f32).partial_cmp(&(condition as f32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn paths_and_values_are_checked_against_the_format() {
        let ok = |p: &str, op: &str, v: Value| check_term(p, op, &v);
        assert!(ok("shadow.bias.constant", ">", json!(0)).is_ok());
        assert!(ok("shadow.bias.polygon_offset[1]", "!=", json!(0)).is_ok());
        assert!(ok("shadow.bias.polygon_offset", "!=", json!([0, 0])).is_ok());
        assert!(ok("shadow.format", "=", json!("depth16")).is_ok());
        assert!(ok("light.point", "!=", Value::Null).is_ok());
        assert!(ok("shadow.filter", "=", json!("linear")).is_ok());
        assert!(ok("shadow.filter.pcf", ">=", json!(3)).is_ok());
        assert!(ok("scene.objects[5].box.size[2]", "<", json!(1)).is_ok());
        assert!(ok("shadow.mipmaps", "=", Value::Null).is_ok());
        assert!(ok("scene.objects[0].mesh.positions[9][1]", ">", json!(0)).is_ok());
        assert!(ok("scene.objects[0].mesh.positions[9][3]", ">", json!(0)).is_err());
        // The probes of issue 36: a mistyped path, a malformed value, words a field never holds.
        let err = ok("shadow.bais.constant", ">", json!(0)).expect_err("mistyped path");
        assert!(err.contains("names no field"), "{err}");
        let err = ok("shadow.bias.constant", ">", json!(">0")).expect_err("malformed value");
        assert!(err.contains("compares numbers"), "{err}");
        assert!(ok("shadow.bias.constant", "=", json!("x")).is_err());
        assert!(ok("shadow.format", "=", json!("depth17")).is_err());
        assert!(ok("shadow.filter", "=", json!("pcf")).is_err());
        assert!(ok("shadow.size[0]", "=", json!(1.5)).is_err());
        assert!(ok("shadow.bias.polygon_offset[2]", "=", json!(0)).is_err());
        assert!(ok("shadow.bias.constant", "=", Value::Null).is_err());
    }

    /// Fields serde skips at their default read as that default, not as absent.
    #[test]
    fn skipped_defaults_are_written_in_for_conditions() {
        let case: crate::format::Case = serde_json::from_str(EXEMPLARS[0]).expect("case");
        let v = condition_json(&case);
        assert_eq!(
            v.pointer("/scene/offset"),
            Some(&serde_json::json!([0, 0, 0]))
        );
        assert_eq!(
            v.pointer("/shadow/beyond_far"),
            Some(&serde_json::json!("compare"))
        );
        assert_eq!(
            v.pointer("/shadow/depth_clamp"),
            Some(&serde_json::json!(false))
        );
        assert_eq!(
            v.pointer("/shadow/depth_func"),
            Some(&serde_json::json!("less"))
        );
        let full: crate::format::Case = serde_json::from_str(EXEMPLARS[1]).expect("case");
        assert_eq!(
            condition_json(&full).pointer("/shadow/beyond_far"),
            Some(&serde_json::json!("lit"))
        );
    }

    #[test]
    fn numbers_compare_at_the_precision_of_a_case() {
        let widened = f64::from(0.0005f32);
        assert_ne!(widened, 0.0005);
        assert_eq!(
            compare_numbers(widened, 0.0005),
            Some(std::cmp::Ordering::Equal)
        );
        assert_eq!(
            compare_numbers(widened, 5e-4),
            Some(std::cmp::Ordering::Equal)
        );
        assert_eq!(
            compare_numbers(widened, 0.0004),
            Some(std::cmp::Ordering::Greater)
        );
    }

    /// Every field a catalogue case point has is one the exemplars have: a field added to the
    /// format and used in a case fails here until the exemplars cover it.
    #[test]
    fn the_exemplars_cover_every_field_the_catalogue_uses() {
        fn leaves(v: &Value, path: String, out: &mut Vec<String>) {
            match v {
                Value::Object(m) => {
                    for (k, x) in m {
                        let p = if path.is_empty() {
                            k.clone()
                        } else {
                            format!("{path}.{k}")
                        };
                        leaves(x, p, out);
                    }
                }
                Value::Array(a) => {
                    for (i, x) in a.iter().enumerate() {
                        leaves(x, format!("{path}[{i}]"), out);
                    }
                }
                _ => out.push(path),
            }
        }
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases");
        let (docs, mut checked) = (exemplars(), 0);
        for file in crate::load::case_files(&dir).expect("cases/") {
            for point in crate::load::load_file(&file).expect("a catalogue case loads") {
                let mut paths = Vec::new();
                leaves(
                    &serde_json::to_value(&point.case).expect("a case serializes"),
                    String::new(),
                    &mut paths,
                );
                for p in paths
                    .iter()
                    .filter(|p| !p.starts_with("sweep") && !p.contains(".set."))
                {
                    assert!(
                        docs.iter().any(|d| resolve(d, p).is_ok()),
                        "{}: {p} is not in schema::EXEMPLARS",
                        file.display()
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "only {checked} paths checked");
    }
}
