//! The technique matrix `umbra sweep` measures, and its rows: two crossed families around
//! the scene's own technique rather than the full product (which would be 600 points a
//! backend): map size 256…4096 × filter (NEAREST, LINEAR, PCF 3, PCF 5), and format (D16,
//! D24, D32F) × bias strategy (none, constant, polygon offset, slope-scaled, normal offset);
//! each in both light frusta (fitted to the scene, and a fixed hand-set box) where the light
//! is directional. A cascaded light sweeps its cascades instead (`sweep_cascades`).

use serde_json::{Value, json};

use crate::judge::measure::Measured;

/// The fixed frustum a program without fitting would pick for a directional light: a
/// generous hand-set box.
pub const FIXED_ORTHO: [f64; 6] = [-50.0, 50.0, -50.0, 50.0, 1.0, 150.0];

/// One technique of the matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Technique {
    /// Map side (first component of `shadow.size`).
    pub size: u32,
    /// Depth format label.
    pub format: String,
    /// Filter label: nearest, linear, pcf3, pcf5.
    pub filter: String,
    /// Bias strategy label.
    pub bias: String,
    /// fitted, fixed or as-written.
    pub frustum: String,
    /// The `shadow` object.
    pub shadow: Value,
    /// The `light` object.
    pub light: Value,
}

impl Technique {
    /// Short label, e.g. `1024 depth24 pcf3 polygon-offset fitted`.
    pub fn label(&self) -> String {
        format!(
            "{} {} {} {} {}",
            self.size, self.format, self.filter, self.bias, self.frustum
        )
    }
}

/// One measured (or skipped) point.
#[derive(Clone, Debug)]
pub struct Row {
    /// Backend id.
    pub backend: String,
    /// The technique.
    pub technique: Technique,
    /// The measurement, or why there is none.
    pub result: Result<Measured, String>,
    /// Whether the backend said it cannot run the technique (a skip, not an error).
    pub skipped: bool,
}

impl Row {
    /// Error against the truth, % of judged pixels (false shadow + false light).
    pub fn error_pct(&self) -> Option<f64> {
        self.result.as_ref().ok().map(|m| {
            if m.judged == 0 {
                0.0
            } else {
                100.0 * (m.false_shadow + m.false_light) as f64 / m.judged as f64
            }
        })
    }
}

fn filter_value(label: &str) -> Value {
    match label {
        "pcf3" => json!({ "pcf": 3 }),
        "pcf5" => json!({ "pcf": 5 }),
        other => json!(other),
    }
}

fn bias_value(label: &str) -> Value {
    match label {
        "constant" => json!({ "constant": 0.0005 }),
        "polygon-offset" => json!({ "polygon_offset": [2.0, 4.0] }),
        "slope" => json!({ "slope": { "scale": 0.0005, "max": 0.002 } }),
        "normal-offset" => json!({ "normal_offset": 0.05 }),
        _ => json!({}),
    }
}

/// The light objects to sweep: the scene's own, and for a directional light the other
/// frustum (fitted ↔ fixed box).
fn lights(light: &Value) -> Vec<(String, Value)> {
    let Some(d) = light.get("directional").and_then(Value::as_object) else {
        return vec![("as-written".into(), light.clone())];
    };
    let mut fitted = d.clone();
    fitted.remove("ortho");
    fitted.insert("fit".into(), json!("scene"));
    let mut fixed = d.clone();
    fixed.remove("fit");
    let [l, r, b, t, n, f] = FIXED_ORTHO;
    fixed.insert(
        "ortho".into(),
        json!({ "left": l, "right": r, "bottom": b, "top": t, "near": n, "far": f }),
    );
    vec![
        ("fitted".into(), json!({ "directional": fitted })),
        ("fixed".into(), json!({ "directional": fixed })),
    ]
}

/// The technique matrix around the scene's own technique (see the module note).
pub fn matrix(case: &umbra_case::Case) -> Vec<Technique> {
    let shadow = serde_json::to_value(&case.shadow).unwrap_or(Value::Null);
    // The sweep's axis is the file's `light` (the first light of several).
    let light = serde_json::to_value(&case.lights[0]).unwrap_or(Value::Null);
    let base_size = case.shadow.size[0];
    let base_format = serde_json::to_value(case.shadow.format)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_default();
    let aspect = f64::from(case.shadow.size[1]) / f64::from(case.shadow.size[0]);
    let mut combos: Vec<(u32, String, String, String)> = Vec::new();
    for size in [256u32, 512, 1024, 2048, 4096] {
        for filter in ["nearest", "linear", "pcf3", "pcf5"] {
            combos.push((
                size,
                base_format.clone(),
                filter.into(),
                "polygon-offset".into(),
            ));
        }
    }
    for format in ["depth16", "depth24", "depth32f"] {
        for bias in [
            "none",
            "constant",
            "polygon-offset",
            "slope",
            "normal-offset",
        ] {
            combos.push((base_size, format.into(), "nearest".into(), bias.into()));
        }
    }
    let mut out: Vec<Technique> = Vec::new();
    for (size, format, filter, bias) in combos {
        let mut s = shadow.clone();
        s["size"] = json!([size, ((f64::from(size) * aspect).round() as u32).max(1)]);
        s["format"] = json!(format);
        s["filter"] = filter_value(&filter);
        s["bias"] = bias_value(&bias);
        for (frustum, l) in lights(&light) {
            let t = Technique {
                size,
                format: format.clone(),
                filter: filter.clone(),
                bias: bias.clone(),
                frustum,
                shadow: s.clone(),
                light: l,
            };
            if !out.contains(&t) {
                out.push(t);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_matrix_crosses_both_families_in_both_frusta() {
        let p = &umbra_case::load_file(
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../cases/packed-cubes/packed-cubes.json"),
        )
        .expect("packed cubes")[0];
        let m = matrix(&p.case);
        // (5 sizes × 4 filters + 3 formats × 5 biases − the one shared) × 2 frusta.
        assert_eq!(m.len(), (20 + 15 - 1) * 2);
        assert!(m.iter().any(|t| t.size == 4096 && t.filter == "pcf5"));
        assert!(
            m.iter()
                .any(|t| t.frustum == "fixed" && t.bias == "normal-offset")
        );
    }
}
