//! `report.html`: one self-contained page (images inlined as data URIs) for a person at a
//! desk or a CI artifact viewer: the summary, the drivers, every failure with its reference |
//! backend | truth | heat-map pictures side by side and the command that reproduces it, the
//! gallery of every run ([`crate::gallery`]), and a table of every run with its error,
//! agreement, SSIM and time. Script errors are recorded on the root element
//! (`data-script-errors`) as well as in the console, so a headless browser test can read them.

use std::fmt::Write as _;
use std::path::Path;

use crate::escape::{base64, esc};
use crate::model::{Metrics, RunResult, Status, TimeBudget};

fn img(dir: &Path, file: &str, caption: &str) -> String {
    match std::fs::read(dir.join(file)) {
        Ok(bytes) => format!(
            "<figure><img src=\"data:image/png;base64,{}\" alt=\"{caption}\"><figcaption>{caption}</figcaption></figure>",
            base64(&bytes)
        ),
        Err(_) => format!(
            "<figure class=\"missing\"><figcaption>{caption}: not written</figcaption></figure>"
        ),
    }
}

/// The page.
pub fn report(
    results: &[RunResult],
    drivers: &str,
    failures_dir: &Path,
    pictures: &Path,
    command: &str,
    budget: &TimeBudget,
) -> String {
    let mut s = head(results, command, budget);
    s.push_str(&crate::gallery::section(results, pictures));
    s.push_str(&drivers_section(drivers));
    s.push_str(&failures_section(results, failures_dir));
    s.push_str(&changed_pictures_section(results));
    s.push_str(&strength_section(results));
    s.push_str(&twins_section(results));
    s.push_str(&crate::error_curves::section(results));
    // The latest `umbra sweep` (speed against error), when one has run in this target dir.
    if let Ok(sweep) =
        std::fs::read_to_string(std::path::Path::new("target/umbra/sweep/section.html"))
    {
        s.push_str("<p><i>From the latest <code>cargo xtask sweep</code> (target/umbra/sweep/), not from this conformance run:</i></p>");
        s.push_str(&sweep);
    }
    s.push_str(&all_runs_section(results));
    s.push_str("</body></html>\n");
    s
}

/// The page's head (style and the script-error recorder), its title and its summary: runs,
/// wall time, the breakdown by status, the command and the time budget.
fn head(results: &[RunResult], command: &str, budget: &TimeBudget) -> String {
    let (wall_s, timing) = (budget.wall_s, budget.line());
    let mut s = String::from(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>umbra conformance</title><style>\
         body{font:14px system-ui,sans-serif;margin:24px;color:#222}h1{margin:0 0 8px}code{background:#f3f3f3;padding:1px 4px}\
         table{border-collapse:collapse}td,th{border:1px solid #ddd;padding:3px 6px;text-align:right}td:first-child{text-align:left}\
         .Pass,.ExpectedFail{color:#176b1c}.Fail,.Crash,.Timeout,.UnexpectedPass{color:#b00020;font-weight:bold}.Skip{color:#777}.Flake{color:#b26a00}\
         figure{display:inline-block;margin:4px}figure img{image-rendering:pixelated;max-width:320px;border:1px solid #ccc}\
         .failure{border:1px solid #e0b4b4;background:#fff6f6;padding:8px;margin:12px 0}\
         .diagnosis{background:#eef4ff;padding:4px}.diagnosis.model{background:#fff3cd}",
    );
    s.push_str(crate::gallery::STYLE);
    s.push_str(
        "</style><script>window.addEventListener('error',function(e){var d=document.documentElement;\
         d.dataset.scriptErrors=(d.dataset.scriptErrors||'')+e.message+';';});</script></head><body>",
    );
    let _ = write!(
        s,
        "<h1>umbra conformance</h1><p>{} runs in {wall_s:.1} s: <b>{}</b></p><p>command: <code>{}</code></p><p>{}</p>",
        results.len(),
        crate::model::breakdown(results),
        esc(command),
        esc(&timing)
    );
    s
}

/// The drivers' table: each backend with its vendor, renderer, version and extensions.
fn drivers_section(drivers: &str) -> String {
    let mut s = String::new();
    s.push_str("<h2>Drivers</h2><table><tr><th>backend</th><th>vendor | renderer | version | extensions</th></tr>");
    for line in drivers.lines() {
        let (b, rest) = line.split_once(": ").unwrap_or((line, ""));
        let _ = write!(
            s,
            "<tr><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
            esc(b),
            esc(rest)
        );
    }
    s.push_str("</table>");
    s
}

/// Every failing or flaky run with its reason, diagnosis, checks, stderr, how to reproduce it
/// and its pictures (reference, backend, visibility, truth, heat map).
fn failures_section(results: &[RunResult], failures_dir: &Path) -> String {
    let mut s = String::from("<h2>Failures</h2>");
    let failing: Vec<&RunResult> = results
        .iter()
        .filter(|r| r.status.is_regression() || r.status == Status::Flake)
        .collect();
    if failing.is_empty() {
        s.push_str("<p>None.</p>");
    }
    for r in failing {
        let dir = failures_dir.join(crate::names::file_name(&r.name));
        let _ = write!(
            s,
            "<div class=\"failure\"><h3><span class=\"{}\">{}</span> {}</h3><p>{}</p>{}<p>reproduce: <code>{}</code></p>{}{}{}{}{}{}{}{}</div>",
            r.status.name(),
            r.status,
            esc(&r.name),
            esc(&r.reason),
            r.diagnosis.as_ref().map_or(String::new(), |d| format!(
                "<p class=\"diagnosis{}\"><b>consensus:</b> {}</p>",
                if d.suspect_model() { " model" } else { "" },
                esc(&d.message)
            )),
            esc(&r.reproduce),
            if r.status == Status::Fail && r.backend != "ref" {
                format!(
                    "<p class=\"repro\">bug report for the driver's developers (reduced case, standalone <code>repro.c</code>, API capture, issue.md): <code>{}</code></p>",
                    esc(&crate::names::repro_command(
                        &r.name,
                        crate::names::mesa_of(&r.reproduce).as_deref()
                    ))
                )
            } else {
                String::new()
            },
            checks_line(r),
            if r.stderr.is_empty() {
                String::new()
            } else {
                format!(
                    "<details class=\"stderr\"><summary>the worker's stderr during the run</summary><pre>{}</pre></details>",
                    esc(&r.stderr)
                )
            },
            img(&dir, "reference.png", "reference"),
            img(&dir, "color.png", "backend"),
            img(&dir, "visibility.png", "backend visibility"),
            img(
                &dir,
                "truth.png",
                "truth (white lit, grey shadowed, blue tint: edge)"
            ),
            img(
                &dir,
                "error.png",
                "heat map (red acne, blue leak, orange/light blue on edges)"
            ),
        );
    }
    s
}

/// The table of every run: its status, error, agreement, reference figures, SSIM and time.
fn all_runs_section(results: &[RunResult]) -> String {
    let mut s = String::from(
        "<h2>All runs</h2><table><tr><th>run</th><th>status</th><th>false shadow</th><th>false light</th>\
         <th>interior fs/fl</th><th>agreement</th><th>illegal</th><th>compared</th><th>blind</th><th>values held</th><th>margin</th><th>SSIM ref</th><th>SSIM golden</th><th>render ms</th><th>clock</th></tr>",
    );
    for r in results {
        let m = r.metrics.as_ref();
        let pct = |n: u64, d: u64| {
            if d == 0 {
                "0".to_string()
            } else {
                format!("{:.3}%", 100.0 * n as f64 / d as f64)
            }
        };
        let opt5 = |v: Option<f64>| v.map(|a| format!("{a:.5}")).unwrap_or_default();
        let cells = [
            m.map(|m| pct(m.false_shadow, m.judged)).unwrap_or_default(),
            m.map(|m| pct(m.false_light, m.judged)).unwrap_or_default(),
            m.map(|m| format!("{}/{}", m.interior_false_shadow, m.interior_false_light))
                .unwrap_or_default(),
            opt5(m.and_then(|m| m.agreement)),
            m.and_then(|m| m.illegal)
                .map(|a| a.to_string())
                .unwrap_or_default(),
            reference(m, |a| a.compared.to_string()),
            reference(m, |a| format!("{:.3}%", 100.0 * a.blind_share())),
            reference(m, |a| a.value_checked.to_string()),
            reference(m, |a| {
                a.value_margin.map_or("–".into(), |v| format!("{v:.4}"))
            }),
            opt5(m.and_then(|m| m.ssim)),
            opt5(m.and_then(|m| m.ssim_golden)),
            m.map(|m| format!("{:.1}", m.total_ms)).unwrap_or_default(),
            m.map(|m| m.clock.clone()).unwrap_or_default(),
        ];
        let _ = write!(
            s,
            "<tr><td>{}</td><td class=\"{}\">{}</td>",
            esc(&r.name),
            r.status.name(),
            r.status
        );
        for c in cells {
            let _ = write!(s, "<td>{}</td>", esc(&c));
        }
        s.push_str("</tr>");
    }
    s.push_str("</table>");
    s
}

/// Pictures that differ from their golden on another driver release where the judge holds
/// every changed pixel legal: not failures, but changes a person should see (each row opens
/// the run's golden beside its frame in the gallery).
fn changed_pictures_section(results: &[RunResult]) -> String {
    let changed: Vec<(&RunResult, &crate::model::GoldenChange)> = results
        .iter()
        .filter(|r| r.golden.as_deref() == Some("changed-legal"))
        .filter_map(|r| Some((r, r.metrics.as_ref()?.golden_change.as_ref()?)))
        .collect();
    if changed.is_empty() {
        return String::new();
    }
    let mut s = format!(
        "<h2 id=\"changed-pictures\">Changed pictures</h2><p>{} picture(s) differ from goldens blessed on another \
         driver release, and the judge holds every changed pixel legal on this driver: the driver's choice inside the \
         specs, reported and not failed. Click one for its golden beside this run's frame. After review, \
         <code>cargo xtask bless --mesa DIR</code> records this release's pictures beside the old goldens.</p>\
         <table><tr><th>run</th><th>status</th><th>golden blessed on</th><th>this driver</th><th>pixels changed</th>\
         <th>largest step</th></tr>",
        changed.len()
    );
    for (r, c) in changed {
        let _ = write!(
            s,
            "<tr><td><a href=\"#run={}\">{}</a></td><td class=\"{}\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}/255</td></tr>",
            esc(&crate::names::url_component(&r.name)),
            esc(&r.name),
            r.status.name(),
            r.status,
            esc(c
                .blessed_on
                .as_deref()
                .unwrap_or(if c.new { "none (new)" } else { "unknown" })),
            esc(c.driver.as_deref().unwrap_or("unknown")),
            c.pixels,
            c.max_step
        );
    }
    s.push_str("</table>");
    s
}

fn reference(
    m: Option<&Metrics>,
    f: impl Fn(&umbra_compare::reference::RefAgreement) -> String,
) -> String {
    m.and_then(|m| m.reference.as_ref())
        .map(f)
        .unwrap_or_default()
}

/// Blind area above this share of a run's compared pixels is flagged.
pub const BLIND_FLAG: f64 = 0.01;

/// Which judgement's blind area: the spec's, or the spec's narrowed by the backend's card
/// (calibrated judging).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Under {
    /// The specs' freedom.
    Spec,
    /// The freedom narrowed to the backend's card; a run judged by the spec alone counts
    /// with its spec figure (nothing narrowed it).
    Card,
}

/// The blind-area figures of a set of runs under one judgement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlindStats {
    /// Median share of compared pixels.
    pub median: f64,
    /// Largest share.
    pub max: f64,
    /// Runs above [`BLIND_FLAG`].
    pub above_flag: usize,
    /// Runs more than half blind.
    pub above_half: usize,
    /// Runs judged against the reference.
    pub runs: usize,
    /// Of those, runs judged against their card too.
    pub calibrated: usize,
}

impl BlindStats {
    /// One line: median, runs above 1 % and above 50 %, of how many.
    pub fn line(&self) -> String {
        format!(
            "median {:.3}%, max {:.2}%, {} of {} runs above {:.0}%, {} above 50%",
            100.0 * self.median,
            100.0 * self.max,
            self.above_flag,
            self.runs,
            100.0 * BLIND_FLAG,
            self.above_half
        )
    }
}

/// The comparison behind a run's blind area `under` a judgement.
pub fn judged_under(
    r: &RunResult,
    under: Under,
) -> Option<&umbra_compare::reference::RefAgreement> {
    let m = r.metrics.as_ref()?;
    match under {
        Under::Spec => m.reference.as_ref(),
        Under::Card => m.reference_card.as_ref().or(m.reference.as_ref()),
    }
}

/// The blind-area figures of a set of runs `under` a judgement.
pub fn blind_stats(results: &[RunResult], under: Under) -> Option<BlindStats> {
    let mut shares: Vec<f64> = results
        .iter()
        .filter_map(|r| judged_under(r, under))
        .filter(|a| a.compared > 0)
        .map(|a| a.blind_share())
        .collect();
    if shares.is_empty() {
        return None;
    }
    let calibrated = results
        .iter()
        .filter_map(|r| r.metrics.as_ref())
        .filter(|m| m.reference_card.as_ref().is_some_and(|a| a.compared > 0))
        .count();
    shares.sort_by(f64::total_cmp);
    Some(BlindStats {
        median: shares[shares.len() / 2],
        max: shares[shares.len() - 1],
        above_flag: shares.iter().filter(|s| **s > BLIND_FLAG).count(),
        above_half: shares.iter().filter(|s| **s > 0.5).count(),
        runs: shares.len(),
        calibrated,
    })
}

/// How strong the checks were: the blind area (pixels where any answer passes) per case and
/// backend, runs above 1 % flagged with the freedom that makes them blind.
fn strength_section(results: &[RunResult]) -> String {
    use std::collections::{BTreeMap, BTreeSet};
    let mut s = String::from(
        "<h2>Check strength</h2><p>Per run, the <i>blind area</i> is the share of compared pixels where any \
         visibility would pass (the legal interval holds both 0 and 1, or another surface may legally show): \
         what the judge cannot see. Everywhere else a value outside its interval, a colour that is not the shading \
         of its own visibility, or a coverage difference fails. The freedom behind the blind pixels is named after \
         the spec clause it comes from (README, Judging).</p>",
    );
    let (Some(spec), Some(card)) = (
        blind_stats(results, Under::Spec),
        blind_stats(results, Under::Card),
    ) else {
        s.push_str("<p>No run was judged against the reference.</p>");
        return s;
    };
    let _ = write!(
        s,
        "<table class=\"blind\"><tr><th>judged by</th><th>runs</th><th>median</th><th>max</th><th>above {:.0} %</th><th>above 50 %</th></tr>",
        100.0 * BLIND_FLAG
    );
    for (name, b) in [
        ("the specs", spec),
        ("the specs narrowed to each backend's card", card),
    ] {
        let _ = write!(
            s,
            "<tr><td style=\"text-align:left\">{name}</td><td>{}</td><td>{:.3} %</td><td>{:.2} %</td><td>{}</td><td>{}</td></tr>",
            b.runs,
            100.0 * b.median,
            100.0 * b.max,
            b.above_flag,
            b.above_half
        );
    }
    let _ = write!(
        s,
        "</table><p>{} of {} runs were judged against their backend's card too (calibrated judging: the spec's \
         freedom narrowed to what the card's probes read, docs/cards.md); the others count with their spec figure. \
         The table below is the spec's.</p>",
        card.calibrated, card.runs
    );
    let mut cells: BTreeMap<(String, String), (f64, String)> = BTreeMap::new();
    let mut backends = BTreeSet::new();
    let mut flagged = Vec::new();
    for r in results {
        let Some(a) = r.metrics.as_ref().and_then(|m| m.reference.as_ref()) else {
            continue;
        };
        let case = r.case.split('@').next().unwrap_or(&r.case).to_string();
        backends.insert(r.backend.clone());
        let share = a.blind_share();
        let cell = cells
            .entry((case, r.backend.clone()))
            .or_insert((0.0, String::new()));
        if share >= cell.0 {
            *cell = (share, r.case.clone());
        }
        if share > BLIND_FLAG {
            flagged.push((share, r, a.main_blind_reason()));
        }
    }
    let cases: BTreeSet<&String> = cells.keys().map(|(c, _)| c).collect();
    s.push_str("<table><tr><th>case (worst point)</th>");
    for b in &backends {
        let _ = write!(s, "<th>{}</th>", esc(b));
    }
    s.push_str("</tr>");
    for c in cases {
        let _ = write!(s, "<tr><td>{}</td>", esc(c));
        for b in &backends {
            match cells.get(&(c.clone(), b.clone())) {
                Some((share, point)) => {
                    let class = if *share > BLIND_FLAG {
                        " class=\"Fail\""
                    } else {
                        ""
                    };
                    let _ = write!(
                        s,
                        "<td{class} title=\"{}\">{:.2}%</td>",
                        esc(point),
                        100.0 * share
                    );
                }
                None => s.push_str("<td>–</td>"),
            }
        }
        s.push_str("</tr>");
    }
    s.push_str("</table>");
    flagged.sort_by(|a, b| b.0.total_cmp(&a.0));
    let _ = write!(
        s,
        "<h3>Runs above {:.0} % blind</h3><table><tr><th>run</th><th>blind</th><th>mostly</th></tr>",
        100.0 * BLIND_FLAG
    );
    for (share, r, why) in flagged {
        let why = why.map_or(String::new(), |(w, f)| format!("{w} ({:.0} %)", 100.0 * f));
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{:.2} %</td><td style=\"text-align:left\">{}</td></tr>",
            esc(&r.name),
            100.0 * share,
            esc(&why)
        );
    }
    s.push_str("</table>");
    s
}

/// Per twin and backend: how many runs compared, how many pixels differed and why.
fn twins_section(results: &[RunResult]) -> String {
    use std::collections::BTreeMap;
    #[derive(Default)]
    struct Row {
        runs: u64,
        skipped: u64,
        by_construction: u64,
        shared: u64,
        failed: u64,
        differ: u64,
        tie: u64,
        texel: u64,
        coverage: u64,
        surface: u64,
        illegal: u64,
        ms: f64,
        case_ms: f64,
        case_error: u64,
        twin_error: Option<u64>,
        worst: String,
    }
    let mut rows: BTreeMap<(String, String, String), Row> = BTreeMap::new();
    for r in results {
        let Some(m) = &r.metrics else { continue };
        for t in &m.twins {
            let row = rows
                .entry((t.name.clone(), t.agree.clone(), r.backend.clone()))
                .or_default();
            if t.skipped.is_some() && t.ok {
                row.skipped += 1;
                continue;
            }
            if t.by_construction {
                row.by_construction += 1;
                continue;
            }
            row.runs += 1;
            row.shared += u64::from(t.shared_shadow_pass);
            row.failed += u64::from(!t.ok);
            row.differ += t.pair.differ;
            row.tie += t.pair.legal_tie;
            row.texel += t.pair.legal_texel
                + t.pair.legal_filter
                + t.pair.legal_position
                + t.pair.legal_seam
                + t.pair.legal_lod;
            row.coverage += t.pair.legal_coverage;
            row.surface += t.pair.legal_surface;
            row.illegal += t.pair.illegal;
            row.ms += t.render_ms;
            row.case_ms += m.total_ms;
            row.case_error += t.interior_error;
            if let Some(e) = t.twin_interior_error {
                row.twin_error = Some(row.twin_error.unwrap_or(0) + e);
            }
            if !t.ok && row.worst.is_empty() {
                row.worst = r.name.clone();
            }
        }
    }
    let mut s = String::from(
        "<h2>Metamorphic twins</h2><p>Each run also renders its twins on the same backend and compares them with its own frame \
         (<code>bias-order</code>, the other bias-matrix order, is built into every case; the others are each case's \
         <code>expect.twins</code>). <i>identical</i>: bit-identical visibility; <i>legal</i>: the twin's frame passes the \
         same judge as a backend's frame against the case's reference; <i>no_worse</i>: the twin's interior error is not larger. Pixel counts are summed \
         over runs. <i>Shared shadow pass</i>: rendered over the case's own shadow map, where the twin changes only the lit pass and the \
         backend kept the map (the twin then tests the lit pass alone; its time is the lit pass's).</p><table><tr><th>twin</th><th>agree</th><th>backend</th><th>runs</th><th>not run</th><th>same render by construction</th><th>shared shadow pass</th><th>failed</th>\
         <th>px differ</th><th>ties</th><th>texel/filter/position/mip level</th><th>map coverage</th><th>other surface</th><th>illegal</th>\
         <th>interior error: case → twin</th><th>twin ms / case ms</th><th>first failing run</th></tr>",
    );
    for ((name, agree, backend), r) in &rows {
        let class = if r.failed > 0 { "Fail" } else { "Pass" };
        let ratio = if r.case_ms > 0.0 {
            r.ms / r.case_ms
        } else {
            0.0
        };
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"{class}\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} → {}</td><td>{ratio:.2}</td><td>{}</td></tr>",
            esc(name),
            esc(agree),
            esc(backend),
            r.runs,
            r.skipped,
            r.by_construction,
            r.shared,
            r.failed,
            r.differ,
            r.tie,
            r.texel,
            r.coverage,
            r.surface,
            r.illegal,
            r.case_error,
            r.twin_error.map(|e| e.to_string()).unwrap_or("–".into()),
            esc(&r.worst)
        );
    }
    s.push_str("</table>");
    s
}

/// A failing run's checks, each with what it holds the run to and the spec text behind it.
fn checks_line(r: &RunResult) -> String {
    if r.failed.is_empty() {
        return String::new();
    }
    let items: Vec<String> = r
        .failed
        .iter()
        .map(|f| {
            format!(
                "<li><b>{}</b> ({}): {}; <i>{}</i></li>",
                esc(&f.check.name()),
                f.count,
                esc(f.check.about()),
                esc(f.check.clause())
            )
        })
        .collect();
    format!("<ul class=\"checks\">{}</ul>", items.join(""))
}

#[cfg(test)]
mod tests {
    use super::*;
    use umbra_compare::reference::RefAgreement;

    fn run(spec: Option<(u64, u64)>, card: Option<(u64, u64)>) -> RunResult {
        let agreement = |(compared, blind): (u64, u64)| RefAgreement {
            compared,
            blind,
            ..Default::default()
        };
        RunResult {
            metrics: Some(crate::Metrics {
                reference: spec.map(agreement),
                reference_card: card.map(agreement),
                ..Default::default()
            }),
            ..RunResult::of_test("ref/case", Status::Pass)
        }
    }

    #[test]
    fn the_blind_area_is_counted_under_the_spec_and_under_the_card() {
        let runs = [
            run(Some((100, 60)), Some((100, 20))),
            run(Some((100, 2)), Some((100, 0))),
            // Judged by the spec alone: counts with its spec figure under the card too.
            run(Some((100, 55)), None),
            run(None, None),
        ];
        let spec = blind_stats(&runs, Under::Spec).expect("spec");
        let card = blind_stats(&runs, Under::Card).expect("card");
        assert_eq!((spec.runs, spec.above_flag, spec.above_half), (3, 3, 2));
        assert_eq!((card.runs, card.above_flag, card.above_half), (3, 2, 1));
        assert_eq!(card.calibrated, 2);
        assert_eq!(spec.median, 0.55);
        assert_eq!(card.median, 0.2);
        assert!(card.line().contains("2 of 3 runs above 1%, 1 above 50%"));
        let page = strength_section(&runs);
        assert!(page.contains("narrowed to each backend's card"), "{page}");
        assert!(page.contains("2 of 3 runs were judged against their backend's card"));
    }
}
