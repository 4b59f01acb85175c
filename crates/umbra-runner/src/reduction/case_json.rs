//! The case text the reducer works on and writes: JSON values tidied as a person would write
//! them, defaults stripped, lights and objects described for the log, sizes in one line.

use std::path::Path;

use serde_json::Value;

use crate::case_size::Size;

/// The case as a person would write it: f32 values at their shortest (0.4, not
/// 0.4000000059604645), no nulls.
pub(super) fn tidy(v: Value) -> Value {
    match v {
        Value::Number(n) if n.is_f64() => {
            let f = n.as_f64().unwrap_or_default();
            // Values that came from f32 fields print as that f32's shortest decimal.
            let short: f64 = format!("{}", f as f32).parse().unwrap_or(f);
            let keep = if (short as f32) == (f as f32) {
                short
            } else {
                f
            };
            if keep.fract() == 0.0 && keep.abs() < 1e15 {
                Value::from(keep as i64)
            } else {
                serde_json::Number::from_f64(keep).map_or(Value::Null, Value::Number)
            }
        }
        Value::Array(a) => Value::Array(a.into_iter().map(tidy).collect()),
        Value::Object(o) => Value::Object(
            o.into_iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k, tidy(v)))
                .collect(),
        ),
        other => other,
    }
}

/// JSON in the catalogue's layout: name and about first, then scene, camera, light, shadow,
/// shading, expect; arrays of numbers and small objects on one line.
pub(super) fn case_text(v: &Value, depth: usize) -> String {
    const ORDER: [&str; 8] = [
        "name", "about", "scene", "camera", "light", "shadow", "shading", "expect",
    ];
    let one_line = v.to_string();
    if one_line.len() <= 90 || !matches!(v, Value::Object(_) | Value::Array(_)) {
        return one_line;
    }
    let pad = "  ".repeat(depth + 1);
    let end = "  ".repeat(depth);
    match v {
        Value::Object(o) => {
            let mut keys: Vec<&String> = o.keys().collect();
            keys.sort_by_key(|k| ORDER.iter().position(|o| o == k).unwrap_or(ORDER.len()));
            let items: Vec<String> = keys
                .iter()
                .map(|k| {
                    format!(
                        "{pad}{}: {}",
                        Value::from(k.as_str()),
                        case_text(&o[*k], depth + 1)
                    )
                })
                .collect();
            format!("{{\n{}\n{end}}}", items.join(",\n"))
        }
        Value::Array(a) => {
            let items: Vec<String> = a
                .iter()
                .map(|x| format!("{pad}{}", case_text(x, depth + 1)))
                .collect();
            format!("[\n{}\n{end}]", items.join(",\n"))
        }
        _ => one_line,
    }
}

pub(super) fn size_line(s: &Size) -> String {
    format!(
        "{} triangles, {} pixels, {} map texels",
        s.triangles, s.pixels, s.texels
    )
}

/// `case` lit by `rest` only: `lights` for two or more (a case written back holds `light`
/// too, equal to the first), `light` alone for one.
pub(super) fn without_lights(case: &Value, rest: Vec<Value>) -> Value {
    let mut cand = case.clone();
    let Some(first) = rest.first().cloned() else {
        return cand;
    };
    if let Some(obj) = cand.as_object_mut() {
        obj.insert("light".into(), first);
        if rest.len() == 1 {
            obj.remove("lights");
            if let Some(shadow) = obj.get_mut("shadow").and_then(Value::as_object_mut) {
                shadow.remove("placement");
            }
        } else {
            obj.insert("lights".into(), Value::Array(rest));
        }
    }
    cand
}

pub(super) fn describe_objects(objs: &[Value]) -> String {
    objs.iter()
        .map(|o| {
            o.as_object()
                .and_then(|m| m.keys().next().cloned())
                .unwrap_or_else(|| "?".into())
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether two case texts parse to different cases (a removal that changes nothing is not
/// worth a render).
pub(super) fn differs(a: &Value, b: &Value) -> bool {
    let parse = |v: &Value| {
        umbra_case::load_str(&v.to_string(), Path::new("reduce.json"))
            .ok()
            .and_then(|p| p.into_iter().next())
            .map(|p| p.case)
    };
    match (parse(a), parse(b)) {
        (Some(x), Some(y)) => x != y,
        _ => false,
    }
}

/// Removes every field whose removal leaves the same case (a default written out).
pub(super) fn strip_defaults(mut case: Value) -> Value {
    fn paths(v: &Value, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
        if let Some(o) = v.as_object() {
            for (k, child) in o {
                prefix.push(k.clone());
                paths(child, prefix, out);
                out.push(prefix.clone());
                prefix.pop();
            }
        }
    }
    let mut all = Vec::new();
    paths(&case, &mut Vec::new(), &mut all);
    for p in all {
        if p.len() == 1 && (p[0] == "name" || p[0] == "about") {
            continue;
        }
        let mut cand = case.clone();
        let mut node = &mut cand;
        for k in &p[..p.len() - 1] {
            node = &mut node[k.as_str()];
        }
        if let Some(o) = node.as_object_mut() {
            o.remove(&p[p.len() - 1]);
        } else {
            continue;
        }
        if Size::of(&cand).is_some() && !differs(&case, &cand) {
            case = cand;
        }
    }
    case
}
