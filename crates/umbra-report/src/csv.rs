//! The CSV files of a conformance run, in deqp-runner's spirit: `results.csv` (`test,status,
//! time`, deqp-runner's own status names), `failures.csv` (the regressions only), `errors.csv` (every judged figure of a run)
//! `twins.csv` (one row per metamorphic twin) and `goldens.csv` (every picture that differs
//! from its golden: how much, between which driver versions, and whether every changed
//! pixel is legal). One row per run, one header line naming every column; fields quoted per
//! RFC 4180 where they need it.

use std::fmt::Write as _;

use crate::model::RunResult;

/// The four tables, as file contents.
pub struct Tables {
    /// `results.csv`.
    pub results: String,
    /// `failures.csv`.
    pub failures: String,
    /// `errors.csv`.
    pub errors: String,
    /// `twins.csv`.
    pub twins: String,
    /// `goldens.csv`.
    pub goldens: String,
}

/// Writes the tables of `results`.
pub fn tables(results: &[RunResult]) -> Tables {
    let mut csv = String::new();
    let mut failures = String::new();
    let mut errors = String::from(
        "test,status,judged,false_shadow,false_light,interior_judged,interior_false_shadow,interior_false_light,edge_px,silhouette,faces_away,outside,agreement,illegal,compared,blind,blind_pct,value_checked,value_margin,illegal_value,illegal_nan,illegal_coverage,illegal_colour,profile,shadow_ms,lit_ms,total_ms,clock,blind_card_pct,judged_as_card\n",
    );
    let mut twins = String::from(
        "test,twin,agree,skipped,differ,legal_tie,legal_coverage,legal_texel,legal_filter,legal_position,legal_surface,blind,illegal,illegal_value,illegal_coverage,illegal_colour,interior_error,twin_interior_error,render_ms,ok,by_construction,shared_shadow_pass\n",
    );
    for r in results {
        for t in r.metrics.iter().flat_map(|m| &m.twins) {
            let _ = writeln!(
                twins,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{},{},{}",
                csv_field(&r.name),
                t.name,
                t.agree,
                t.skipped.is_some(),
                t.pair.differ,
                t.pair.legal_tie,
                t.pair.legal_coverage,
                t.pair.legal_texel,
                t.pair.legal_filter,
                t.pair.legal_position,
                t.pair.legal_surface,
                t.pair.blind,
                t.pair.illegal,
                t.pair.illegal_value,
                t.pair.illegal_coverage,
                t.pair.illegal_colour,
                t.interior_error,
                t.twin_interior_error
                    .map(|e| e.to_string())
                    .unwrap_or_default(),
                t.render_ms,
                t.ok,
                t.by_construction,
                t.shared_shadow_pass
            );
        }
    }
    let mut goldens =
        String::from("test,status,golden,blessed_on,driver,pixels,max_step,new,legal_change\n");
    for r in results {
        let Some(c) = r.metrics.as_ref().and_then(|m| m.golden_change.as_ref()) else {
            continue;
        };
        let _ = writeln!(
            goldens,
            "{},{},{},{},{},{},{},{},{}",
            csv_field(&r.name),
            r.status,
            r.golden.as_deref().unwrap_or(""),
            csv_field(c.blessed_on.as_deref().unwrap_or("")),
            csv_field(c.driver.as_deref().unwrap_or("")),
            c.pixels,
            c.max_step,
            c.new,
            c.legal
        );
    }
    for r in results {
        // deqp-runner's status names, which Mesa's tools parse ([`crate::Status::deqp_name`]).
        let status = r.status.deqp_name();
        let _ = writeln!(csv, "{},{status},{:.3}", csv_field(&r.name), r.time_s);
        if r.status.is_regression() {
            let _ = writeln!(failures, "{},{status}", csv_field(&r.name));
        }
        if let Some(m) = &r.metrics {
            let _ = writeln!(
                errors,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{},{},{}",
                csv_field(&r.name),
                r.status,
                m.judged,
                m.false_shadow,
                m.false_light,
                m.interior_judged,
                m.interior_false_shadow,
                m.interior_false_light,
                m.edge_px,
                m.silhouette,
                m.faces_away,
                m.outside,
                m.agreement.map(|a| format!("{a:.6}")).unwrap_or_default(),
                m.illegal.map(|a| a.to_string()).unwrap_or_default(),
                opt(m.reference.as_ref().map(|a| a.compared)),
                opt(m.reference.as_ref().map(|a| a.blind)),
                m.reference
                    .as_ref()
                    .map(|a| format!("{:.4}", 100.0 * a.blind_share()))
                    .unwrap_or_default(),
                opt(m.reference.as_ref().map(|a| a.value_checked)),
                m.reference
                    .as_ref()
                    .and_then(|a| a.value_margin)
                    .map(|v| format!("{v:.5}"))
                    .unwrap_or_default(),
                opt(m.reference.as_ref().map(|a| a.illegal_value)),
                opt(m.reference.as_ref().map(|a| a.illegal_nan)),
                opt(m.reference.as_ref().map(|a| a.illegal_coverage)),
                opt(m.reference.as_ref().map(|a| a.illegal_colour)),
                m.profile,
                m.shadow_ms,
                m.lit_ms,
                m.total_ms,
                m.clock,
                m.reference_card
                    .as_ref()
                    .map(|a| format!("{:.4}", 100.0 * a.blind_share()))
                    .unwrap_or_default(),
                csv_field(&m.judged_as_card)
            );
        }
    }
    Tables {
        results: csv,
        failures,
        errors,
        twins,
        goldens,
    }
}

fn opt(v: Option<u64>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// A CSV field, quoted (RFC 4180) when it holds a comma, a quote or a line break: point ids
/// of multi-axis sweeps hold commas.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The fields of one CSV line (RFC 4180 quoting; a line holds one record).
pub fn split_line(line: &str) -> Result<Vec<String>, String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    let mut at_start = true;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (false, '"') if at_start => quoted = true,
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => {
                quoted = false;
                if chars.peek().is_some_and(|c| *c != ',') {
                    return Err("a quoted field goes on after its closing quote".into());
                }
            }
            (false, ',') => {
                fields.push(std::mem::take(&mut field));
                at_start = true;
                continue;
            }
            (_, c) => field.push(c),
        }
        at_start = false;
    }
    if quoted {
        return Err("a quoted field is not closed".into());
    }
    fields.push(field);
    Ok(fields)
}

/// The rows of a results.csv (`test,status,duration`, no header): name, status, seconds.
/// An error names the line.
pub fn parse_results(text: &str) -> Result<Vec<(String, String, f64)>, String> {
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let bad = |why: &str| format!("line {}: {why}: {line:?}", i + 1);
        let fields = split_line(line).map_err(|e| bad(&e))?;
        let [name, status, time] = fields.as_slice() else {
            return Err(bad("not three fields (test,status,duration)"));
        };
        let time: f64 = time
            .trim()
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite() && *t >= 0.0)
            .ok_or_else(|| bad("the duration is not a number of seconds (finite, not negative)"))?;
        rows.push((name.clone(), status.clone(), time));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_read_back_what_tables_write() {
        let name = r#"gl33/llvmpipe/acne@shadow.bias={"constant":0.0005}"#;
        let line = format!("{},Pass,0.019", csv_field(name));
        assert_eq!(
            parse_results(&line),
            Ok(vec![(name.to_string(), "Pass".to_string(), 0.019)])
        );
        assert!(
            parse_results("a,Pass")
                .expect_err("two fields")
                .contains("line 1")
        );
        assert!(parse_results("\"a,Pass,1").is_err());
        assert!(parse_results("a,Pass,fast").is_err());
        assert!(parse_results("a,Pass,NaN").is_err());
        assert!(parse_results("a,Pass,-1").is_err());
        assert!(parse_results("a,Pass,inf").is_err());
    }
}
