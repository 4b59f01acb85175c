//! `umbra drivers --baseline A --candidate B`: two Mesa builds side by side.
//!
//! Each side is a conformance run of the catalogue (`--mesa A`, then `--mesa B`; `system` is
//! the system's Mesa), in a process of its own, without goldens (a golden guards one driver
//! against itself; here the builds are compared with each other). The two `report.json` are
//! then joined run by run, and every case point whose verdict, error against the truth,
//! agreement with the reference or picture changed is listed:
//!
//! - `regression`: passed on the baseline, fails (or crashes, or hangs) on the candidate;
//! - `fix`: the reverse;
//! - `changed failure`: fails on both, with another signature (other checks or counts);
//! - `support`: runs on one side and is a skip on the other;
//! - `picture`: same verdict, another frame (colour or visibility hashes differ);
//! - `numbers`: same frame bytes aside, the error or the judge's counts changed (this
//!   cannot happen without a picture change unless the judge itself changed).
//!
//! First, before any run, both sides' behaviour cards ([`crate::judge::card`]) are measured
//! and every entry that changed is named (`gl33/zink: polygon-offset unit r, D16: 4 codes → 2
//! codes`), in the terminal, `card-changes.txt`, each side's `cards.json` and at the top of
//! report.html: a change of what a driver chose inside the specs, which no verdict shows.
//!
//! The verdicts are *raw* (before expectations): an expected failure on one version is still
//! a failure, so a driver fix of a known bug shows as a fix. Outputs in `--out` (default
//! `target/umbra/drivers/`): `report.html` (baseline | candidate | reference | difference for
//! each changed point, up to `--pictures N`), `changes.csv`, deqp-runner-style
//! `regressions.csv` and `fixes.csv` (`test,status`), and each side's full conformance
//! reports. Exit 1 when there is a regression, 0 otherwise, 125 when a side could not run.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use umbra_report::{Metrics, Report, ReportRun};

use crate::cli::DriversArgs;
use crate::exit::{Error, Exit, Outcome};
use umbra_report::escape::{base64, esc};

/// One run's raw verdict.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// `pass`, `fail`, `skip`, `crash`, `timeout`.
    pub kind: String,
    /// For a failure, its signature (`value=12+map=3`).
    pub signature: String,
}

impl Verdict {
    /// From a report.json run: expectations undone (ExpectedFail is a failure, UnexpectedPass
    /// and Flake a pass); `absent` where the side has no such run.
    pub fn of(run: Option<&ReportRun>) -> Verdict {
        let Some(run) = run else {
            return Verdict {
                kind: "absent".into(),
                signature: String::new(),
            };
        };
        let kind = match run.status.as_str() {
            "Pass" | "UnexpectedPass" | "Flake" => "pass",
            "Skip" => "skip",
            "Crash" => "crash",
            "Timeout" => "timeout",
            _ => "fail",
        };
        let signature = run
            .failed
            .iter()
            .map(|c| format!("{}={}", c.check, c.count))
            .collect::<Vec<_>>()
            .join("+");
        Verdict {
            kind: kind.into(),
            signature,
        }
    }

    fn failing(&self) -> bool {
        matches!(self.kind.as_str(), "fail" | "crash" | "timeout")
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.kind == "fail" && !self.signature.is_empty() {
            write!(f, "fail ({})", self.signature)
        } else {
            f.write_str(&self.kind)
        }
    }
}

/// One changed case point.
#[derive(Clone, Debug)]
pub struct Change {
    /// Run name (`backend/case@sweep`).
    pub name: String,
    /// `regression`, `fix`, `changed failure`, `support`, `picture`, `numbers`.
    pub kind: &'static str,
    /// Baseline verdict.
    pub baseline: Verdict,
    /// Candidate verdict.
    pub candidate: Verdict,
    /// What else changed, in words.
    pub detail: String,
    /// The case file, point id and backend, for pictures.
    pub file: String,
    /// See `file`.
    pub point: String,
    /// See `file`.
    pub backend: String,
    /// The pictures' measured difference, once rendered.
    pub measured: Option<PictureDiff>,
}

/// How two renders of one point differ, pixel by pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PictureDiff {
    /// Pixels compared.
    pub pixels: u64,
    /// Pixels whose colour differs in any channel.
    pub colour_px: u64,
    /// The largest difference of one 8-bit channel.
    pub colour_max: u8,
    /// Pixels whose stored visibility differs.
    pub visibility_px: u64,
}

impl std::fmt::Display for PictureDiff {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "colour differs on {} of {} px, by at most {}/255 a channel; visibility differs on {} px",
            self.colour_px, self.pixels, self.colour_max, self.visibility_px
        )
    }
}

/// Joins two report.json run lists and lists what changed.
pub fn compare(baseline: &Report, candidate: &Report) -> Vec<Change> {
    let (a, b) = (by_name(baseline), by_name(candidate));
    let mut names: Vec<&str> = a.keys().chain(b.keys()).copied().collect();
    names.sort();
    names.dedup();
    let mut out = Vec::new();
    for name in names {
        let (ra, rb) = (a.get(name).copied(), b.get(name).copied());
        let (va, vb) = (Verdict::of(ra), Verdict::of(rb));
        let mut detail = Vec::new();
        let (ma, mb) = (
            ra.and_then(|r| r.metrics.as_ref()),
            rb.and_then(|r| r.metrics.as_ref()),
        );
        type Count = fn(&Metrics) -> Option<u64>;
        let counts: [(&str, Count); 4] = [
            ("false shadow", |m| Some(m.false_shadow)),
            ("false light", |m| Some(m.false_light)),
            ("illegal", |m| m.reference.as_ref().map(|r| r.illegal)),
            ("differ from the reference", |m| {
                m.reference.as_ref().map(|r| r.differ)
            }),
        ];
        for (what, count) in counts {
            let (x, y) = (ma.and_then(count), mb.and_then(count));
            if x != y {
                detail.push(format!("{what} {} → {} px", opt(x), opt(y)));
            }
        }
        let picture = ma.map(|m| (&m.color_hash, &m.visibility_hash))
            != mb.map(|m| (&m.color_hash, &m.visibility_hash));
        let both = ra.is_some() && rb.is_some();
        if picture && both && va.kind != "skip" && vb.kind != "skip" {
            detail.push("picture changed".into());
        }
        let kind = if va.kind == "pass" && vb.failing() {
            "regression"
        } else if va.failing() && vb.kind == "pass" {
            "fix"
        } else if va.failing() && vb.failing() && va != vb {
            "changed failure"
        } else if va.kind != vb.kind {
            "support"
        } else if picture && va.kind != "skip" {
            "picture"
        } else if !detail.is_empty() {
            "numbers"
        } else {
            continue;
        };
        let Some(pick) = rb.or(ra) else {
            continue;
        };
        out.push(Change {
            name: name.to_string(),
            kind,
            baseline: va,
            candidate: vb,
            detail: detail.join("; "),
            file: pick.file.clone(),
            point: pick.case.clone(),
            backend: pick.backend.clone(),
            measured: None,
        });
    }
    let rank = |k: &str| match k {
        "regression" => 0,
        "fix" => 1,
        "changed failure" => 2,
        "support" => 3,
        "picture" => 4,
        _ => 5,
    };
    out.sort_by(|x, y| (rank(x.kind), &x.name).cmp(&(rank(y.kind), &y.name)));
    out
}

/// A report's runs by name.
fn by_name(r: &Report) -> BTreeMap<&str, &ReportRun> {
    r.runs.iter().map(|x| (x.name.as_str(), x)).collect()
}

fn opt(v: Option<u64>) -> String {
    v.map_or("-".into(), |v| v.to_string())
}

/// Runs the command; returns its outcome.
pub fn main(args: &DriversArgs) -> Outcome {
    for (flag, v) in [
        ("--baseline", &args.baseline),
        ("--candidate", &args.candidate),
    ] {
        if let crate::cli::MesaChoice::Dir(dir) = v {
            if let Err(e) = crate::harness::mesa_build::MesaBuild::open(dir) {
                return Err(Error::new(format!("{flag} {v}: {e}")));
            }
        }
    }
    // Each side's --mesa as its child conformance run is given it.
    let (base, cand) = (args.baseline.to_string(), args.candidate.to_string());
    let (base, cand) = (base.as_str(), cand.as_str());
    let pictures = args.pictures;
    let out = args.out.clone();
    // The last comparison is replaced; a directory umbra did not make is refused.
    umbra_owned::fresh(&out, "umbra drivers").map_err(|e| Error::new(format!("--out: {e}")))?;
    let Ok(exe) = crate::harness::own_libc::self_exe() else {
        return Err(Error::new("cannot find this executable"));
    };
    // The cards first: what each driver chose inside the specs, side by side, so that a
    // change of behaviour is named before any picture.
    let card_changes = side_cards(args, &exe, &out, base, cand);
    let mut reports = Vec::new();
    for (side, mesa) in [("baseline", base), ("candidate", cand)] {
        reports.push(run_side(args, &exe, &out, side, mesa)?);
    }
    let mut changes = compare(&reports[0], &reports[1]);
    let label = |r: &Report, mesa: &str| {
        let mut v: Vec<&str> = r.drivers.iter().filter_map(|d| d.mesa.as_deref()).collect();
        v.sort();
        v.dedup();
        format!(
            "{mesa} (Mesa {})",
            if v.is_empty() {
                "?".into()
            } else {
                v.join(", ")
            }
        )
    };
    let (la, lb) = (label(&reports[0], base), label(&reports[1], cand));
    // Pictures for the first N changes.
    for c in changes.iter_mut().take(pictures) {
        c.measured = render_pictures(&exe, &out, c, base, cand);
        if let Some(m) = c.measured {
            c.detail = if c.detail.is_empty() || c.detail == "picture changed" {
                m.to_string()
            } else {
                format!("{}; {m}", c.detail)
            };
        }
    }
    if let Err(e) = write_outputs(&out, &changes, (&la, &lb), &card_changes, &reports, cand) {
        return Err(Error::new(format!(
            "cannot write under {}: {e}",
            out.display()
        )));
    }
    let compared = reports[1].runs.len();
    let count = |k: &str| changes.iter().filter(|c| c.kind == k).count();
    println!("\ndrivers: baseline {la} vs candidate {lb}");
    match &card_changes {
        Ok(lines) => {
            println!(
                "drivers: behaviour cards: {} entries changed (card-changes.txt)",
                lines.len()
            );
            for l in lines {
                println!("  card             {l}");
            }
        }
        Err(e) => println!("drivers: behaviour cards not compared: {e}"),
    }
    println!(
        "drivers: {compared} runs compared: {} regressions, {} fixes, {} changed failures, {} support changes, {} changed pictures, {} changed numbers",
        count("regression"),
        count("fix"),
        count("changed failure"),
        count("support"),
        count("picture"),
        count("numbers")
    );
    for c in changes
        .iter()
        .filter(|c| c.kind != "picture" && c.kind != "numbers")
    {
        println!(
            "  {:<16} {}: {} → {}{}",
            c.kind,
            c.name,
            c.baseline,
            c.candidate,
            if c.detail.is_empty() {
                String::new()
            } else {
                format!(" ({})", c.detail)
            }
        );
    }
    // Changed pictures, per backend, with the measured size of the change.
    let mut by_backend: BTreeMap<&str, (usize, usize, PictureDiff)> = BTreeMap::new();
    for c in changes.iter().filter(|c| c.kind == "picture") {
        let e = by_backend.entry(c.backend.as_str()).or_default();
        e.0 += 1;
        if let Some(m) = c.measured {
            e.1 += 1;
            e.2.colour_px = e.2.colour_px.max(m.colour_px);
            e.2.colour_max = e.2.colour_max.max(m.colour_max);
            e.2.visibility_px = e.2.visibility_px.max(m.visibility_px);
        }
    }
    for (b, (n, measured, m)) in &by_backend {
        println!(
            "  picture          {b}: {n} points; of the {measured} rendered, at most {} px differ in colour, by at most {}/255, and at most {} px in visibility",
            m.colour_px, m.colour_max, m.visibility_px
        );
    }
    println!("drivers: report in {}", out.join("report.html").display());
    Ok(Exit::pass_if(count("regression") == 0))
}

/// Both sides' behaviour cards (`OUT/SIDE/cards.json`) and what changed between them
/// (`OUT/card-changes.txt`, one `backend: entry: old → new` line each).
fn side_cards(
    args: &DriversArgs,
    exe: &Path,
    out: &Path,
    base: &str,
    cand: &str,
) -> Result<Vec<String>, String> {
    let mut sides = Vec::new();
    for (side, mesa) in [("baseline", base), ("candidate", cand)] {
        println!("drivers: measuring the {side}'s behaviour cards ({mesa})");
        let cards = crate::harness::cards::measure_in_child(
            exe,
            std::ffi::OsStr::new(mesa),
            &args.selection.backend,
        )
        .map_err(|e| format!("the {side}'s: {e}"))?;
        let dir = out.join(side);
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(
            dir.join("cards.json"),
            serde_json::to_string_pretty(&cards).unwrap_or_default(),
        );
        sides.push(cards);
    }
    let lines = crate::judge::card::changes_between(&sides[0], &sides[1]);
    let _ = std::fs::write(out.join("card-changes.txt"), lines.join("\n") + "\n");
    Ok(lines)
}

/// One side's conformance run (`umbra conformance --mesa MESA`, goldens off) in a process of
/// its own, its output in `OUT/SIDE/conformance.log`; returns its report.json.
fn run_side(
    args: &DriversArgs,
    exe: &Path,
    out: &Path,
    side: &str,
    mesa: &str,
) -> Result<Report, Error> {
    let dir = out.join(side);
    let _ = std::fs::create_dir_all(&dir);
    let mut cmd = Command::new(exe);
    cmd.args(["conformance", "--mesa", mesa, "--golden", "none", "--out"])
        .arg(&dir)
        .args(args.selection.argv());
    if let Some(j) = args.jobs {
        cmd.arg("--jobs").arg(j.to_string());
    }
    if let Some(t) = args.timeout {
        cmd.arg("--timeout").arg(t.to_string());
    }
    let log = dir.join("conformance.log");
    let Ok(file) = std::fs::File::create(&log) else {
        return Err(Error::new(format!("cannot write {}", log.display())));
    };
    cmd.env_remove(crate::harness::mesa_build::ENV)
        .stdout(Stdio::from(file));
    println!(
        "drivers: running the {side} ({mesa}); log in {}",
        log.display()
    );
    let started = std::time::Instant::now();
    // A child that did not start, or did not exit (a signal), counts as could not run (125).
    let could_not_run = i32::from(Exit::CouldNotRun.code());
    let code = cmd
        .status()
        .ok()
        .and_then(|s| s.code())
        .unwrap_or(could_not_run);
    // The closing line is the child's report's, not read back from its terminal output.
    let report = dir.join("latest").join("report.json");
    let read = report.exists().then(|| Report::read(&report));
    let closing = match &read {
        Some(Ok(r)) => umbra_report::summary::closing_line_of("conformance", r),
        _ => "no report".to_string(),
    };
    println!(
        "drivers: {side} done in {:.0} s (exit {code}): {closing}",
        started.elapsed().as_secs_f64()
    );
    if code == could_not_run {
        return Err(Error::new(format!(
            "the {side} run could not run ({mesa}); see {}",
            log.display()
        )));
    }
    let Some(read) = read else {
        return Err(Error::new(format!(
            "the {side} run wrote no report.json under {}",
            dir.display()
        )));
    };
    read.map_err(|e| Error::new(format!("the {side} run's report: {e}")))
}

/// The directory of one change's pictures.
fn picture_dir(out: &Path, c: &Change) -> PathBuf {
    out.join("pictures")
        .join(crate::judge::golden::stem(&c.name))
}

/// Renders a changed point on both builds and on the reference, and the difference.
fn render_pictures(
    exe: &Path,
    out: &Path,
    c: &Change,
    base: &str,
    cand: &str,
) -> Option<PictureDiff> {
    let dir = picture_dir(out, c);
    for (side, backend, mesa) in [
        ("baseline", c.backend.as_str(), base),
        ("candidate", c.backend.as_str(), cand),
        ("reference", "ref", "system"),
    ] {
        let _ = Command::new(exe)
            .args([
                "render".to_string(),
                format!("--point={}", c.point),
                format!("--backend={backend}"),
                format!("--mesa={mesa}"),
                format!("--out={}", dir.join(side).display()),
                "--".to_string(),
                c.file.clone(),
            ])
            .env_remove(crate::harness::mesa_build::ENV)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status();
    }
    let load = |side: &str, file: &str| {
        image::open(dir.join(side).join(file))
            .ok()
            .map(|i| i.to_rgba8())
    };
    let (a, b) = (
        load("baseline", "color.png")?,
        load("candidate", "color.png")?,
    );
    if a.dimensions() != b.dimensions() {
        return None;
    }
    let mut m = PictureDiff {
        pixels: u64::from(a.width()) * u64::from(a.height()),
        ..PictureDiff::default()
    };
    let mut d = image::RgbaImage::new(a.width(), a.height());
    for ((pa, pb), pd) in a.pixels().zip(b.pixels()).zip(d.pixels_mut()) {
        let diff =
            pa.0.iter()
                .zip(pb.0.iter())
                .take(3)
                .map(|(x, y)| x.abs_diff(*y))
                .max()
                .unwrap_or(0);
        m.colour_max = m.colour_max.max(diff);
        *pd = if diff == 0 {
            let g = (u16::from(pa.0[0]) + u16::from(pa.0[1]) + u16::from(pa.0[2])) / 12;
            image::Rgba([g as u8, g as u8, g as u8, 255])
        } else {
            m.colour_px += 1;
            image::Rgba([255, 64u8.saturating_add(diff.saturating_mul(4)), 255, 255])
        };
    }
    let _ = d.save(dir.join("difference.png"));
    if let (Some(va), Some(vb)) = (
        load("baseline", "visibility.png"),
        load("candidate", "visibility.png"),
    ) {
        m.visibility_px = va.pixels().zip(vb.pixels()).filter(|(x, y)| x != y).count() as u64;
    }
    Some(m)
}

fn img(path: &Path, caption: &str) -> String {
    match std::fs::read(path) {
        Ok(bytes) => format!(
            "<figure><img src=\"data:image/png;base64,{}\" alt=\"{caption}\"><figcaption>{caption}</figcaption></figure>",
            base64(&bytes)
        ),
        Err(_) => format!(
            "<figure><div class=\"none\">no picture</div><figcaption>{caption}</figcaption></figure>"
        ),
    }
}

/// changes.csv, regressions.csv and fixes.csv.
fn write_tables(out: &Path, changes: &[Change]) -> std::io::Result<()> {
    std::fs::create_dir_all(out)?;
    let q = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut csv = String::from("test,change,baseline,candidate,detail\n");
    let mut regressions = String::new();
    let mut fixes = String::new();
    for c in changes {
        let _ = writeln!(
            csv,
            "{},{},{},{},{}",
            q(&c.name),
            c.kind,
            q(&c.baseline.to_string()),
            q(&c.candidate.to_string()),
            q(&c.detail)
        );
        let status = |v: &Verdict| match v.kind.as_str() {
            "pass" => "Pass",
            "skip" => "Skip",
            "crash" => "Crash",
            "timeout" => "Timeout",
            _ => "Fail",
        };
        match c.kind {
            "regression" => {
                let _ = writeln!(regressions, "{},{}", q(&c.name), status(&c.candidate));
            }
            "fix" => {
                let _ = writeln!(fixes, "{},{}", q(&c.name), status(&c.candidate));
            }
            _ => {}
        }
    }
    std::fs::write(out.join("changes.csv"), csv)?;
    std::fs::write(out.join("regressions.csv"), regressions)?;
    std::fs::write(out.join("fixes.csv"), fixes)
}

/// The tables ([`write_tables`]) and report.html: the card changes first, then the drivers,
/// the changed runs and their pictures.
fn write_outputs(
    out: &Path,
    changes: &[Change],
    (la, lb): (&str, &str),
    cards: &Result<Vec<String>, String>,
    reports: &[Report],
    candidate: &str,
) -> std::io::Result<()> {
    write_tables(out, changes)?;
    let mut h = String::new();
    let _ = write!(
        h,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>umbra drivers: {}</title><style>\
         body{{font-family:sans-serif;margin:1.5em}} table{{border-collapse:collapse}} td,th{{border:1px solid #ccc;padding:2px 6px;font-size:13px}}\
         figure{{display:inline-block;margin:4px}} figure img{{max-width:300px;image-rendering:pixelated}} .none{{width:200px;height:150px;background:#eee}}\
         .regression{{color:#b00}} .fix{{color:#070}}</style></head><body>",
        esc(lb)
    );
    let _ = write!(
        h,
        "<h1>Driver builds compared</h1><p>baseline: <b>{}</b><br>candidate: <b>{}</b></p>",
        esc(la),
        esc(lb)
    );
    match cards {
        Ok(lines) => {
            let _ = write!(h, "<h2>{} behaviour-card changes</h2><ul>", lines.len());
            for l in lines {
                let _ = write!(h, "<li>{}</li>", esc(l));
            }
            h.push_str("</ul>");
        }
        Err(e) => {
            let _ = write!(h, "<h2>Behaviour cards not compared</h2><p>{}</p>", esc(e));
        }
    }
    for (side, r) in ["baseline", "candidate"].iter().zip(reports) {
        let _ = write!(
            h,
            "<h3>{side}: drivers</h3><table><tr><th>backend</th><th>version</th><th>build</th><th>expectations applied</th></tr>"
        );
        for d in &r.drivers {
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&d.backend),
                esc(d
                    .version
                    .as_deref()
                    .or(d.unavailable.as_deref())
                    .unwrap_or("")),
                esc(d.build.as_deref().unwrap_or("system")),
                esc(&d.expectations.join(", "))
            );
        }
        h.push_str("</table>");
    }
    let _ = write!(
        h,
        "<h2>{} changed runs</h2><table><tr><th>change</th><th>run</th><th>baseline</th><th>candidate</th><th>detail</th></tr>",
        changes.len()
    );
    for c in changes {
        let cls = c.kind.replace(' ', "-");
        // A regression whose candidate frame fails gets the command for its bug report, on
        // the candidate's Mesa.
        let repro = if c.kind == "regression" && c.candidate.kind == "fail" {
            format!(
                "<br>bug report: <code>{}</code>",
                esc(&umbra_report::names::repro_command(
                    &c.name,
                    (candidate != "system").then_some(candidate)
                ))
            )
        } else {
            String::new()
        };
        let _ = write!(
            h,
            "<tr><td class=\"{cls}\">{}</td><td><a href=\"#{}\">{}</a></td><td>{}</td><td>{}</td><td>{}{repro}</td></tr>",
            c.kind,
            esc(&crate::judge::golden::stem(&c.name)),
            esc(&c.name),
            esc(&c.baseline.to_string()),
            esc(&c.candidate.to_string()),
            esc(&c.detail)
        );
    }
    h.push_str("</table><h2>Pictures</h2>");
    for c in changes {
        let dir = picture_dir(out, c);
        if !dir.exists() {
            continue;
        }
        let _ = write!(
            h,
            "<h3 id=\"{}\">{} <small>({}: {} → {})</small></h3>",
            esc(&crate::judge::golden::stem(&c.name)),
            esc(&c.name),
            c.kind,
            esc(&c.baseline.to_string()),
            esc(&c.candidate.to_string())
        );
        h.push_str(&img(&dir.join("baseline").join("color.png"), "baseline"));
        h.push_str(&img(&dir.join("candidate").join("color.png"), "candidate"));
        h.push_str(&img(&dir.join("reference").join("color.png"), "reference"));
        h.push_str(&img(
            &dir.join("difference.png"),
            "difference (magenta: changed)",
        ));
    }
    h.push_str("</body></html>");
    std::fs::write(out.join("report.html"), h)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(name: &str, status: &str, failed: &[(&str, u64)], hash: &str, fs: u64) -> ReportRun {
        let failed: Vec<umbra_report::FailedCheck> = failed
            .iter()
            .map(|(c, n)| umbra_report::FailedCheck {
                check: umbra_report::check::Check::parse(c).expect("a check"),
                count: *n,
            })
            .collect();
        let reference = umbra_compare::reference::RefAgreement {
            illegal: failed.first().map_or(0, |f| f.count),
            ..Default::default()
        };
        ReportRun {
            name: name.into(),
            case: "c".into(),
            file: "cases/c.json".into(),
            backend: "b".into(),
            golden: None,
            status: status.into(),
            reason: String::new(),
            false_shadow: None,
            false_light: None,
            agreement: None,
            ssim: None,
            ssim_golden: None,
            time_ms: 1.0,
            metrics: Some(Metrics {
                false_shadow: fs,
                color_hash: hash.into(),
                visibility_hash: hash.into(),
                reference: Some(reference),
                ..Metrics::default()
            }),
            failed,
            diagnosis: None,
            reproduce: String::new(),
            stderr: None,
        }
    }

    fn report(runs: Vec<ReportRun>) -> Report {
        Report {
            schema: umbra_report::json::SCHEMA,
            wall_s: 0.0,
            time_budget: umbra_report::TimeBudget::default(),
            harness_overhead_share: 0.0,
            command: String::new(),
            mesa_build: serde_json::Value::Null,
            drivers: Vec::new(),
            runs,
            shards: None,
        }
    }

    #[test]
    fn changes_are_classified_on_raw_verdicts() {
        let a = report(vec![
            run("b/same", "Pass", &[], "1", 0),
            run("b/regressed", "Pass", &[], "1", 0),
            run("b/fixed", "ExpectedFail", &[("value", 9)], "1", 0),
            run("b/other-failure", "ExpectedFail", &[("value", 9)], "1", 0),
            run("b/picture", "Pass", &[], "1", 3),
            run("b/now-supported", "Skip", &[], "", 0),
        ]);
        let b = report(vec![
            run("b/same", "Pass", &[], "1", 0),
            run("b/regressed", "Fail", &[("value", 4)], "2", 0),
            run("b/fixed", "UnexpectedPass", &[], "2", 0),
            run("b/other-failure", "Fail", &[("map", 2)], "1", 0),
            run("b/picture", "Pass", &[], "2", 5),
            run("b/now-supported", "Pass", &[], "1", 0),
        ]);
        let c = compare(&a, &b);
        let kinds: Vec<(&str, &str)> = c.iter().map(|c| (c.name.as_str(), c.kind)).collect();
        assert_eq!(
            kinds,
            [
                ("b/regressed", "regression"),
                ("b/fixed", "fix"),
                ("b/other-failure", "changed failure"),
                ("b/now-supported", "support"),
                ("b/picture", "picture"),
            ]
        );
        assert_eq!(c[0].candidate.to_string(), "fail (value=4)");
        assert!(
            c[4].detail.contains("false shadow 3 → 5 px"),
            "{}",
            c[4].detail
        );
    }
}
