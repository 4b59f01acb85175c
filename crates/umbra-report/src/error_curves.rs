//! Error against a swept parameter, per backend: the report's answer to "where does each
//! backend break?". For every case with a numeric sweep axis (a number, or an array whose
//! first element is one, such as `shadow.size`), one table and one SVG plot per combination
//! of the other axes (e.g. one per depth format): x is the axis value (log scale when it
//! spans two decades or more), y is the error against the truth (false shadow + false light,
//! % of judged pixels), one line per backend.
//!
//! The SVG is written by hand: a polyline plot needs no plotting library.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde_json::Value;

use crate::escape::esc;
use crate::model::RunResult;

/// One run on a curve: (x, error %, frame ms, point id, false shadow %, false light %).
type Point = (f64, f64, f64, String, f64, f64);

/// One curve family: a case, its numeric axis, and the other axes' values.
#[derive(Default)]
struct Family {
    /// Per backend: (x, error %, frame ms, point id, false shadow %, false light %).
    series: BTreeMap<String, Vec<Point>>,
}

fn numeric(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => n.as_f64(),
        Value::Array(a) => a.first().and_then(Value::as_f64),
        _ => None,
    }
}

/// The report section (empty when no case has a numeric axis).
pub fn section(results: &[RunResult]) -> String {
    // (case name, axis, other axes) → family
    let mut families: BTreeMap<(String, String, String), Family> = BTreeMap::new();
    for r in results {
        let Some(m) = &r.metrics else { continue };
        let Some((axis, x)) = r
            .values
            .iter()
            .find_map(|(p, v)| numeric(v).map(|x| (p.clone(), x)))
        else {
            continue;
        };
        let others: Vec<String> = r
            .values
            .iter()
            .filter(|(p, _)| *p != axis)
            .map(|(p, v)| match v {
                Value::String(s) => format!("{p}={s}"),
                other => format!("{p}={other}"),
            })
            .collect();
        let case = r.case.split('@').next().unwrap_or(&r.case).to_string();
        let pct = |n: u64| {
            if m.judged == 0 {
                0.0
            } else {
                100.0 * n as f64 / m.judged as f64
            }
        };
        let err = pct(m.false_shadow + m.false_light);
        families
            .entry((case, axis, others.join(", ")))
            .or_default()
            .series
            .entry(r.backend.clone())
            .or_default()
            .push((
                x,
                err,
                m.total_ms,
                r.case.clone(),
                pct(m.false_shadow),
                pct(m.false_light),
            ));
    }
    if families.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "<h2>Error against swept parameters</h2><p>Error against the exact truth (false shadow + \
         false light, % of judged pixels) along each case's numeric sweep axis, per backend; \
         one plot per value of the other axes. Cells: false shadow % (acne) / false light % \
         (leaks, peter-panning) · frame time (ms).</p>",
    );
    for ((case, axis, others), fam) in &families {
        let mut xs: Vec<f64> = fam.series.values().flatten().map(|p| p.0).collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        let _ = write!(
            s,
            "<h3>{} along {}{}</h3>",
            esc(case),
            esc(axis),
            if others.is_empty() {
                String::new()
            } else {
                format!(" ({})", esc(others))
            }
        );
        s.push_str(&plot(fam, &xs, axis));
        s.push_str("<table><tr><th>backend</th>");
        for x in &xs {
            let _ = write!(s, "<th>{x}</th>");
        }
        s.push_str("</tr>");
        for (backend, pts) in &fam.series {
            let _ = write!(s, "<tr><td>{}</td>", esc(backend));
            for x in &xs {
                match pts.iter().find(|p| p.0 == *x) {
                    Some(p) => {
                        let _ = write!(
                            s,
                            "<td title=\"{}\">{:.3}% / {:.3}% · {:.1}</td>",
                            esc(&p.3),
                            p.4,
                            p.5,
                            p.2
                        );
                    }
                    None => s.push_str("<td>–</td>"),
                }
            }
            s.push_str("</tr>");
        }
        s.push_str("</table>");
    }
    s
}

const PALETTE: [&str; 12] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf", "#000000", "#aec7e8",
];

/// A polyline plot of the family, one line per backend.
fn plot(fam: &Family, xs: &[f64], axis: &str) -> String {
    let (w, h, left, right, top, bottom) = (560.0, 260.0, 56.0, 170.0, 12.0, 36.0);
    let (lo, hi) = (xs[0], xs[xs.len() - 1]);
    let log = lo > 0.0 && hi / lo >= 100.0;
    let tx = |x: f64| -> f64 {
        let t = if hi == lo {
            0.5
        } else if log {
            (x.log10() - lo.log10()) / (hi.log10() - lo.log10())
        } else {
            (x - lo) / (hi - lo)
        };
        left + t * (w - left - right)
    };
    let ymax = fam
        .series
        .values()
        .flatten()
        .map(|p| p.1)
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 1.1;
    let ty = |y: f64| top + (1.0 - y / ymax) * (h - top - bottom);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-size=\"10\" style=\"border:1px solid #ddd;display:block;margin:6px 0\">"
    );
    // Axes, ticks at the swept values, and the y range.
    let _ = write!(
        s,
        "<line x1=\"{left}\" y1=\"{0}\" x2=\"{1}\" y2=\"{0}\" stroke=\"#444\"/><line x1=\"{left}\" y1=\"{top}\" x2=\"{left}\" y2=\"{0}\" stroke=\"#444\"/>",
        h - bottom,
        w - right
    );
    for x in xs {
        let _ = write!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{x}</text>",
            tx(*x),
            h - bottom + 12.0
        );
    }
    let _ = write!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}{}</text>",
        left + (w - left - right) / 2.0,
        h - 6.0,
        esc(axis),
        if log { " (log)" } else { "" }
    );
    for (y, label) in [(0.0, "0%".to_string()), (ymax, format!("{ymax:.2}%"))] {
        let _ = write!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{label}</text>",
            left - 4.0,
            ty(y) + 3.0
        );
    }
    for (i, (backend, pts)) in fam.series.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let mut pts = pts.clone();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let line: Vec<String> = pts
            .iter()
            .map(|p| format!("{:.1},{:.1}", tx(p.0), ty(p.1)))
            .collect();
        let _ = write!(
            s,
            "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\" points=\"{}\"/>",
            line.join(" ")
        );
        for p in &pts {
            let _ = write!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"{colour}\"><title>{}: {:.3}%</title></circle>",
                tx(p.0),
                ty(p.1),
                esc(backend),
                p.1
            );
        }
        let ly = top + 12.0 * i as f64 + 6.0;
        let _ = write!(
            s,
            "<line x1=\"{0:.1}\" y1=\"{ly:.1}\" x2=\"{1:.1}\" y2=\"{ly:.1}\" stroke=\"{colour}\" stroke-width=\"2\"/><text x=\"{2:.1}\" y=\"{3:.1}\">{4}</text>",
            w - right + 8.0,
            w - right + 24.0,
            w - right + 28.0,
            ly + 3.0,
            esc(backend)
        );
    }
    s.push_str("</svg>");
    s
}
