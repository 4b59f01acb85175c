//! `umbra sweep` on a cascaded directional light: cascade count (1 to 4) × split scheme
//! (uniform, logarithmic, practical λ = 0.5) in place of the technique matrix, the rest of
//! the scene's technique as written (its shadow distance kept, no blend band). Each point reports, beside its frame time and its error
//! against the exact truth, its perspective aliasing (screen pixels per shadow-map texel,
//! `umbra_ref::truth::aliasing`), and the section sets the worst pixel's against what Lloyd
//! et al.'s analysis of z-partitioning predicts for the same splits.
//!
//! The prediction: a slice's map is about as wide as the slice's far end, so at view depth d
//! in slice k a texel spans m ∝ s_{k+1} / d pixels, worst at the nearest receiver of the
//! slice, max(s_k, d_min) (d_min, d_max: the frame's nearest and farthest judged depths).
//! Over the slices the frame sees, P = max_k s_{k+1} / max(s_k, d_min): logarithmic splits
//! give (f/n)^(1/N) where d_min = n, the least possible; uniform ones leave the first slice
//! 1 + (f − n)/(N·n). The section prints P and the measured worst m beside it, and their
//! ratio, which is the scene's constant (the slice boxes' width against their far ends, the
//! map and image sizes) where the model holds.

use std::fmt::Write as _;

use serde_json::{Value, json};

use super::matrix::{Row, Technique};
use umbra_case::format::{Cascades, Light, SplitScheme};
use umbra_report::escape::esc;

/// Cascade counts swept.
pub const COUNTS: [u32; 4] = [1, 2, 3, 4];

/// Split schemes swept, with the practical scheme's λ.
const SCHEMES: [(SplitScheme, Option<f32>); 3] = [
    (SplitScheme::Uniform, None),
    (SplitScheme::Logarithmic, None),
    (SplitScheme::Practical, Some(0.5)),
];

fn scheme_name(s: SplitScheme) -> &'static str {
    match s {
        SplitScheme::Uniform => "uniform",
        SplitScheme::Logarithmic => "logarithmic",
        SplitScheme::Practical => "practical",
        SplitScheme::Fractions => "fractions",
    }
}

/// The cascade matrix of `case`, or `None` where its light has no cascades.
pub fn matrix(case: &umbra_case::Case) -> Option<Vec<Technique>> {
    // Cascades are a case's one light's (validation).
    let [Light::Directional(d)] = case.lights.as_slice() else {
        return None;
    };
    let distance = d.cascades.as_ref()?.distance;
    let shadow = serde_json::to_value(&case.shadow).ok()?;
    let format = shadow["format"].as_str().unwrap_or("depth24").to_string();
    let filter = match &shadow["filter"] {
        Value::String(f) => f.clone(),
        other => other.to_string().replace(['{', '}', '"', ':'], ""),
    };
    let mut out = Vec::new();
    for count in COUNTS {
        for (split, lambda) in SCHEMES {
            let mut dir = d.clone();
            dir.cascades = Some(Cascades {
                count,
                split,
                lambda,
                at: None,
                distance,
                blend: 0.0,
                blend_of: Default::default(),
                fit: Default::default(),
            });
            out.push(Technique {
                size: case.shadow.size[0],
                format: format.clone(),
                filter: filter.clone(),
                bias: "as-written".into(),
                frustum: format!("{count} {}", scheme_name(split)),
                shadow: shadow.clone(),
                light: json!({ "directional": dir }),
            });
        }
    }
    Some(out)
}

/// P for the technique's splits over view depths `(d_min, d_max)` (see the module note).
fn predicted(case: &umbra_case::Case, t: &Technique, (lo, hi): (f64, f64)) -> Option<f64> {
    let c: Cascades = serde_json::from_value(t.light["directional"]["cascades"].clone()).ok()?;
    let s = umbra_case::light::cascade_splits(&c, case.camera.near, case.camera.far);
    s.windows(2)
        .map(|w| (f64::from(w[0]), f64::from(w[1])))
        .filter(|(a, b)| *b >= lo && *a <= hi)
        .map(|(a, b)| b / a.max(lo))
        .reduce(f64::max)
}

/// The cascade table and plot: per backend and technique, frame time, error, measured and
/// predicted worst aliasing, mean aliasing.
pub fn section(rows: &[Row], case: &umbra_case::Case) -> String {
    let mut s = String::from(
        "<h3>Cascades: perspective aliasing against Lloyd et al.'s prediction</h3>\
         <p>m: screen pixels per shadow-map texel at a judged pixel (the texel's width over the \
         pixel's, across the view; surface orientation left out). P: the prediction \
         max<sub>k</sub> s<sub>k+1</sub> / max(s<sub>k</sub>, d<sub>min</sub>) over the slices \
         the frame sees, d<sub>min</sub> the nearest judged view depth. Where the model holds, \
         worst m / P is the same on every row: the slices' box widths against their far ends, \
         the map's and the image's sizes.</p>\
         <table><tr><th>backend</th><th>cascades</th><th>frame ms</th><th>error %</th>\
         <th>worst m</th><th>P</th><th>worst m / P</th><th>mean m</th></tr>",
    );
    let mut plot: Vec<(String, u32, f64, f64)> = Vec::new();
    for r in rows {
        let Ok(m) = &r.result else { continue };
        let (Some(worst), Some(mean), Some(depths)) =
            (m.aliasing_max, m.aliasing_mean, m.view_depths)
        else {
            continue;
        };
        let p = predicted(case, &r.technique, depths);
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td>{:.3}</td><td>{worst:.2}</td><td>{}</td><td>{}</td><td>{mean:.2}</td></tr>",
            esc(&r.backend),
            esc(&r.technique.frustum),
            m.frame_ms,
            r.error_pct().unwrap_or_default(),
            p.map_or("–".into(), |p| format!("{p:.2}")),
            p.map_or("–".into(), |p| format!("{:.3}", worst / p)),
        );
        if r.backend == rows[0].backend {
            if let (Some((n, scheme)), Some(p)) = (r.technique.frustum.split_once(' '), p) {
                let n = n.parse().unwrap_or(0);
                plot.push((scheme.to_string(), n, worst, p));
            }
        }
    }
    s.push_str("</table>");
    s.push_str(&plot_svg(&plot));
    s
}

/// Worst m (solid) and P scaled to the measured 1-cascade value (dashed) against the count,
/// per scheme, on a log axis.
fn plot_svg(points: &[(String, u32, f64, f64)]) -> String {
    if points.is_empty() {
        return String::new();
    }
    let (w, h, pad) = (480.0, 300.0, 44.0);
    let log = |v: f64| umbra_case::math::log10(v.max(1e-6));
    let ys: Vec<f64> = points.iter().map(|p| log(p.2)).collect();
    let (lo, hi) = ys
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(*y), b.max(*y))
        });
    let (lo, hi) = (lo - 0.05, hi + 0.05);
    let x = |n: u32| pad + (f64::from(n) - 1.0) / 3.0 * (w - 2.0 * pad);
    let y = |v: f64| h - pad - (log(v) - lo) / (hi - lo) * (h - 2.0 * pad);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-size=\"11\">\
         <text x=\"{pad}\" y=\"16\">worst m (solid) and P scaled at 1 cascade (dashed), log scale</text>"
    );
    for tick in [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0] {
        if (lo..=hi).contains(&log(tick)) {
            let _ = write!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{tick}</text>\
                 <line x1=\"{pad}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>",
                pad - 4.0,
                y(tick) + 4.0,
                w - pad,
                y = y(tick)
            );
        }
    }
    for n in COUNTS {
        let _ = write!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{n}</text>",
            x(n),
            h - pad + 16.0
        );
    }
    let colours = [
        ("uniform", "#c0392b"),
        ("logarithmic", "#2471a3"),
        ("practical", "#229954"),
    ];
    for (k, (scheme, colour)) in colours.iter().enumerate() {
        let mut line: Vec<(u32, f64, f64)> = points
            .iter()
            .filter(|p| p.0 == *scheme)
            .map(|p| (p.1, p.2, p.3))
            .collect();
        line.sort_by_key(|p| p.0);
        let Some(first) = line.first().copied() else {
            continue;
        };
        let scale = first.1 / first.2;
        let path = |f: &dyn Fn(&(u32, f64, f64)) -> f64| {
            line.iter()
                .map(|p| format!("{:.1},{:.1}", x(p.0), y(f(p))))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let _ = write!(
            s,
            "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"2\" points=\"{}\"/>\
             <polyline fill=\"none\" stroke=\"{colour}\" stroke-dasharray=\"4 3\" points=\"{}\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" fill=\"{colour}\">{scheme}</text>",
            path(&|p| p.1),
            path(&|p| p.2 * scale),
            w - pad - 70.0,
            30.0 + 14.0 * k as f64
        );
    }
    s.push_str("</svg>");
    s
}
