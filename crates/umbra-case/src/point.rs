//! A case point and the JSON paths into a case: what the loader produces and what twins,
//! sweeps and conditions address. Below the loader, the twins and validation, so that none of
//! them imports another's caller (the loader and the twins once imported each other).

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::CaseError;
use crate::format::{Case, LightsError};

/// One runnable point of a case: the case with its sweep values applied. It travels to a
/// worker as it is (serde), so a point is loaded, validated and expanded once, by the parent.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CasePoint {
    /// The file it came from.
    pub file: PathBuf,
    /// The case with this point's values (its `sweep` is empty).
    pub case: Case,
    /// `(path, value)` for each swept axis, in axis order.
    pub values: Vec<(String, Value)>,
}

impl CasePoint {
    /// A stable identifier: `name` or `name@path=value,path=value`.
    pub fn id(&self) -> String {
        if self.values.is_empty() {
            return self.case.name.clone();
        }
        let parts: Vec<String> = self
            .values
            .iter()
            .map(|(p, v)| format!("{p}={}", compact(v)))
            .collect();
        format!("{}@{}", self.case.name, parts.join(","))
    }
}

pub(crate) fn compact(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Deserialises a case from JSON, naming the path of the first type error. One light is
/// written `light`, several `lights` ([`crate::format::CaseFile`]); one that gives both (as a
/// case written back does) must give the same first light.
pub(crate) fn parse_value(value: &Value, file: &Path, context: &str) -> Result<Case, CaseError> {
    serde_path_to_error::deserialize::<_, Case>(value).map_err(|e| {
        let path = e.path().to_string();
        let path = if path == "." { String::new() } else { path };
        let inner = e.into_inner().to_string();
        // The lights' own rules (`Case`'s conversion from its file), each at its field.
        let lights = [
            (
                LightsError::Differ,
                "light",
                "give `light` for one light or `lights` for several, not both",
            ),
            (
                LightsError::One,
                "lights",
                "write one light as `light`, or remove lights (each is one lit pass and one map)",
            ),
        ];
        if let Some((_, field, fix)) = lights.iter().find(|(l, ..)| inner == l.to_string()) {
            return CaseError::new(file, *field, format!("{context}{inner}"), *fix);
        }
        let fix = if inner.starts_with("unknown field") {
            "remove the field or correct its spelling (cases/README.md lists every field)"
        } else if inner.starts_with("missing field") {
            "add the field (cases/README.md says which fields are required)"
        } else if inner.starts_with("unknown variant") {
            "use one of the listed names"
        } else if inner.contains("untagged enum Extent") {
            "give one number for a square or [half_u, half_v]"
        } else if inner.contains("untagged enum Scale") {
            "give one number or [sx, sy, sz]"
        } else {
            "give the field the type cases/README.md shows for it"
        };
        CaseError::new(file, path, format!("{context}{inner}"), fix)
    })
}

/// The slot at a dotted path (`a.b[2].c`), creating objects along the way.
pub(crate) fn set_path<'v>(doc: &'v mut Value, path: &str) -> Result<&'v mut Value, String> {
    let mut cur = doc;
    if path.is_empty() {
        return Err("the path is empty".into());
    }
    for seg in path.split('.') {
        let (key, index) = match seg.find('[') {
            Some(open) if seg.ends_with(']') => {
                let idx: usize = seg[open + 1..seg.len() - 1]
                    .parse()
                    .map_err(|_| format!("bad index in segment {seg:?}"))?;
                (&seg[..open], Some(idx))
            }
            _ => (seg, None),
        };
        if key.is_empty() {
            return Err(format!("empty segment in path {path:?}"));
        }
        if cur.is_null() {
            *cur = Value::Object(Default::default());
        }
        let Value::Object(map) = cur else {
            return Err(format!(
                "{key:?} is reached through a value that is not an object"
            ));
        };
        cur = map.entry(key.to_string()).or_insert(Value::Null);
        if let Some(i) = index {
            let Value::Array(items) = cur else {
                return Err(format!("{key:?} is not an array, so [{i}] cannot index it"));
            };
            let len = items.len();
            cur = items
                .get_mut(i)
                .ok_or_else(|| format!("index {i} is past the end of {key:?} ({len} items)"))?;
        }
    }
    Ok(cur)
}

/// The value at a dotted path (`a.b[2].c`) of `doc`, if there is one: the reading twin of
/// the sweeps' paths (expectations' `@when` conditions use it).
pub fn get_path<'v>(doc: &'v Value, path: &str) -> Option<&'v Value> {
    let mut cur = doc;
    for seg in path.split('.') {
        let (key, mut rest) = seg.split_at(seg.find('[').unwrap_or(seg.len()));
        cur = cur.as_object()?.get(key)?;
        // Indices, one or more (`positions[3][1]`).
        while let Some(inner) = rest.strip_prefix('[') {
            let close = inner.find(']')?;
            cur = cur.as_array()?.get(inner[..close].parse::<usize>().ok()?)?;
            rest = &inner[close + 1..];
        }
        if !rest.is_empty() {
            return None;
        }
    }
    Some(cur)
}
