//! Reading case files and expanding their sweeps into runnable points.
//!
//! A sweep overrides a JSON path of the case *before* it is deserialised, so any field can be
//! swept and every point goes through the same parsing and validation as a hand-written case:
//! a sweep cannot create a value that a file could not hold.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{CaseError, CaseErrors};
use crate::format::{Case, SweepAxis, SweepScale};
pub use crate::point::{CasePoint, get_path};
use crate::point::{compact, parse_value, set_path};
use crate::validate::validate;

/// Most points one case may expand to (a typo such as `"steps": 10000` should not queue hours).
pub const MAX_SWEEP_POINTS: usize = 4096;

/// Reads, parses, validates and expands one case file.
pub fn load_file(file: &Path) -> Result<Vec<CasePoint>, CaseErrors> {
    let text = std::fs::read_to_string(file).map_err(|e| {
        CaseError::new(
            file,
            "",
            format!("cannot read the file: {e}"),
            "check the path and its permissions",
        )
    })?;
    load_str(&text, file)
}

/// Parses, validates and expands case text; `file` is used in messages only.
pub fn load_str(text: &str, file: &Path) -> Result<Vec<CasePoint>, CaseErrors> {
    let value: Value = serde_json::from_str(text).map_err(|e| {
        CaseError::new(
            file,
            "",
            format!(
                "not valid JSON at line {} column {}: {e}",
                e.line(),
                e.column()
            ),
            "fix the JSON syntax (no comments or trailing commas)",
        )
    })?;
    let case = parse_value(&value, file, "")?;
    validate(&case, file)?;
    let points = if case.sweep.is_empty() {
        vec![CasePoint {
            file: file.to_path_buf(),
            case,
            values: Vec::new(),
        }]
    } else {
        expand(&value, &case, file)?
    };
    // A twin that cannot be built is a case error now, not a failed run later.
    for point in &points {
        for twin in crate::twin::twins_of(point) {
            twin.point?;
        }
    }
    Ok(points)
}

fn expand(base: &Value, case: &Case, file: &Path) -> Result<Vec<CasePoint>, CaseErrors> {
    let mut axes: Vec<(String, Vec<Value>)> = Vec::new();
    let mut errors = Vec::new();
    for (path, axis) in &case.sweep {
        match axis_values(axis) {
            Ok(vals) => axes.push((path.clone(), vals)),
            Err((field, msg, fix)) => errors.push(CaseError::new(
                file,
                format!("sweep.{path}.{field}"),
                msg,
                fix,
            )),
        }
    }
    if !errors.is_empty() {
        return Err(CaseErrors(errors));
    }
    let total: usize = axes.iter().map(|(_, v)| v.len()).product();
    if total > MAX_SWEEP_POINTS {
        return Err(CaseError::new(
            file,
            "sweep",
            format!("the sweep expands to {total} points, more than {MAX_SWEEP_POINTS}"),
            "use fewer steps or split the case",
        )
        .into());
    }
    let mut points = Vec::with_capacity(total);
    for index in 0..total {
        let mut rest = index;
        let mut doc = base.clone();
        if let Value::Object(map) = &mut doc {
            map.remove("sweep");
        }
        let mut values = Vec::with_capacity(axes.len());
        for (path, vals) in axes.iter().rev() {
            let v = vals[rest % vals.len()].clone();
            rest /= vals.len();
            if let Err(msg) = set_path(&mut doc, path).map(|slot| *slot = v.clone()) {
                return Err(CaseError::new(
                    file,
                    format!("sweep.{path}"),
                    msg,
                    "give a dotted path into the case, such as light.spot.fov_y_deg",
                )
                .into());
            }
            values.push((path.clone(), v));
        }
        values.reverse();
        let label = values
            .iter()
            .map(|(p, v)| format!("{p}={}", compact(v)))
            .collect::<Vec<_>>()
            .join(",");
        let context = format!("at sweep point {label}: ");
        let point = parse_value(&doc, file, &context).map_err(|mut e| {
            e.fix = format!(
                "{} (the value comes from sweep.{})",
                e.fix,
                values.first().map(|v| v.0.as_str()).unwrap_or("")
            );
            e
        })?;
        validate(&point, file).map_err(|e| e.in_context(&context))?;
        points.push(CasePoint {
            file: file.to_path_buf(),
            case: point,
            values,
        });
    }
    distinct(&points, file)?;
    Ok(points)
}

/// Refuses two sweep points with one id (a value repeated, or written twice: `0.0005` and
/// `5e-4`), which would be two runs, two report rows and one golden under one name, and two
/// points that are one case (values that round to the same f32): the same run twice.
fn distinct(points: &[CasePoint], file: &Path) -> Result<(), CaseErrors> {
    let mut ids = std::collections::HashMap::new();
    let mut cases = std::collections::HashMap::new();
    for (i, p) in points.iter().enumerate() {
        let id = p.id();
        let axes: Vec<&str> = p.values.iter().map(|(a, _)| a.as_str()).collect();
        let field = format!("sweep.{}", axes.join("+"));
        if let Some(first) = ids.insert(id.clone(), i) {
            return Err(CaseError::new(
                file,
                field,
                format!(
                    "sweep points {} and {} of {} are both {id:?} (a value given twice, or written two ways): two runs, two report rows and one golden under one name",
                    first + 1,
                    i + 1,
                    points.len()
                ),
                "give each value once",
            )
            .into());
        }
        let key = serde_json::to_string(&p.case).unwrap_or_default();
        if let Some(first) = cases.insert(key, i) {
            return Err(CaseError::new(
                file,
                field,
                format!(
                    "sweep points {:?} and {id:?} are the same case (their values are the same f32): the same run twice",
                    points[first].id()
                ),
                "give values that differ at f32 precision, or one of them",
            )
            .into());
        }
    }
    Ok(())
}

type AxisError = (&'static str, String, &'static str);

fn axis_values(axis: &SweepAxis) -> Result<Vec<Value>, AxisError> {
    if let Some(vals) = &axis.values {
        if axis.from.is_some() || axis.to.is_some() || axis.steps.is_some() {
            return Err((
                "values",
                "both values and from/to/steps are given".into(),
                "keep one form",
            ));
        }
        if vals.is_empty() {
            return Err((
                "values",
                "the list is empty".into(),
                "give at least one value",
            ));
        }
        return Ok(vals.clone());
    }
    let (Some(from), Some(to), Some(steps)) = (axis.from, axis.to, axis.steps) else {
        return Err((
            "from",
            "an axis needs from, to and steps, or values".into(),
            "give all three, or a values list",
        ));
    };
    if steps == 0 {
        return Err((
            "steps",
            "must be at least 1".into(),
            "use 1 for a single value",
        ));
    }
    if !from.is_finite() || !to.is_finite() {
        return Err((
            "from",
            "from and to must be finite".into(),
            "use finite numbers",
        ));
    }
    if axis.scale == SweepScale::Log && (from <= 0.0 || to <= 0.0) {
        return Err((
            "scale",
            format!("log spacing needs from and to > 0, got {from} and {to}"),
            "use positive ends or linear spacing",
        ));
    }
    let n = steps as usize;
    Ok((0..n)
        .map(|i| {
            let t = if n == 1 {
                0.0
            } else {
                i as f64 / (n - 1) as f64
            };
            let x = match axis.scale {
                SweepScale::Linear => from + (to - from) * t,
                SweepScale::Log => crate::math::pow(
                    10.0,
                    crate::math::log10(from)
                        + (crate::math::log10(to) - crate::math::log10(from)) * t,
                ),
            };
            number(x)
        })
        .collect())
}

/// A JSON number, integral when the value is (so u32 fields accept it), otherwise rounded to 9
/// significant digits so that point names stay readable and stable.
fn number(x: f64) -> Value {
    if x.fract() == 0.0 && x.abs() < 9.0e15 {
        return Value::from(x as i64);
    }
    let rounded: f64 = format!("{x:.8e}").parse().unwrap_or(x);
    Value::from(rounded)
}

/// Every `*.json` under `dir`, recursively, sorted by path.
pub fn case_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d)? {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "json") {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}
