//! `umbra sweep`: speed against error. A matrix of shadow techniques on one scene, each
//! measured on each chosen backend (frame time: median of N renders after a warm-up; error
//! against the exact truth: false shadow, false light, edge displacement), written as a CSV, a
//! Pareto plot of time against error per backend (PNG and SVG) and an HTML section.
//!
//! The matrix is two crossed families around the scene's own technique rather than the full
//! product (which would be 600 points a backend): map size 256…4096 × filter (NEAREST,
//! LINEAR, PCF 3, PCF 5), and format (D16, D24, D32F) × bias strategy (none, constant,
//! polygon offset, slope-scaled, normal offset); each in both light frusta (fitted to the
//! scene, and a fixed hand-set box) where the light is directional. The generated case file
//! is kept beside the results, so every point can be re-run with `umbra render`.
//!
//! Each backend runs in its own worker process (the Mesa driver's environment), one backend
//! after the other so that their timings do not compete, and in one run, so that ratios
//! between them are measured side by side.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::cli::SweepArgs;
use crate::exit::{Error, Exit, Outcome};
use crate::harness::measure::Measured;
use crate::harness::pool::Reply;
use crate::harness::scheduler::{NotReady, Session};
use crate::harness::worker::{Request, RunVerdict};
use umbra_report::escape::esc;

/// Backends swept when none is named: the reference and one of each GPU API family.
pub const DEFAULT_BACKENDS: [&str; 3] = ["ref", "gl33/llvmpipe", "wgpu-vk/lavapipe"];

/// The scene swept when none is named: the packed cubes with the light behind them, so that
/// their shadow falls towards the camera (at azimuth 0 it hides behind the block).
pub const DEFAULT_SCENE: (&str, &str) = (
    "cases/packed-cubes/packed-cubes.json",
    "packed-cubes@light.directional.azimuth_deg=135",
);

/// The fixed frustum a program without fitting would pick for a directional light: a
/// generous hand-set box.
const FIXED_ORTHO: [f64; 6] = [-50.0, 50.0, -50.0, 50.0, 1.0, 150.0];

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
    let light = serde_json::to_value(&case.light).unwrap_or(Value::Null);
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

/// Writes the generated case (the scene with a sweep over `shadow` and `light`) and returns
/// its points in file order, each with its technique.
fn write_case(
    point: &umbra_case::CasePoint,
    techniques: &[Technique],
    out: &Path,
) -> Result<(PathBuf, Vec<Option<Technique>>), String> {
    let mut doc = serde_json::to_value(&point.case).map_err(|e| e.to_string())?;
    let name = format!("{}-sweep", point.case.name);
    doc["name"] = json!(name);
    doc["about"] = json!(format!(
        "generated by umbra sweep from {}: the technique matrix",
        point.id()
    ));
    if let Some(map) = doc.as_object_mut() {
        map.remove("expect");
    }
    let mut shadows: Vec<Value> = Vec::new();
    let mut lights: Vec<Value> = Vec::new();
    for t in techniques {
        if !shadows.contains(&t.shadow) {
            shadows.push(t.shadow.clone());
        }
        if !lights.contains(&t.light) {
            lights.push(t.light.clone());
        }
    }
    doc["sweep"] = json!({ "shadow": { "values": shadows }, "light": { "values": lights } });
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    let file = out.join(format!("{name}.json"));
    std::fs::write(
        &file,
        serde_json::to_string_pretty(&doc).map_err(|e| e.to_string())?,
    )
    .map_err(|e| format!("cannot write {}: {e}", file.display()))?;
    let points = umbra_case::load_file(&file).map_err(|e| e.to_string())?;
    // Match each expanded point back to its technique by value (the expansion's order is the
    // loader's business); the cartesian product may hold points no technique asked for,
    // which are not run (None).
    let plan = points
        .iter()
        .map(|p| {
            let get = |k: &str| p.values.iter().find(|(path, _)| path == k).map(|v| &v.1);
            techniques
                .iter()
                .find(|t| get("shadow") == Some(&t.shadow) && get("light") == Some(&t.light))
                .cloned()
        })
        .collect();
    Ok((file, plan))
}

/// Runs the command; returns its outcome.
pub fn main(args: &SweepArgs) -> Outcome {
    crate::harness::mesa_build::select(args.mesa.as_deref()).map_err(Error::new)?;
    crate::harness::memory_limit::select(args.max_memory.as_deref(), 1)
        .map_err(|e| crate::cli::usage_error("sweep", e))?;
    let scene = PathBuf::from(args.scene.as_deref().unwrap_or(DEFAULT_SCENE.0));
    let repeat = match args.repeat.as_deref().map(str::parse::<u32>).transpose() {
        Ok(r) => r.unwrap_or(5).max(1),
        Err(_) => {
            return Err(crate::cli::usage_error(
                "sweep",
                "--repeat takes a positive number",
            ));
        }
    };
    let timeout = match args.timeout.as_deref().map(str::parse::<u64>).transpose() {
        Ok(t) => Duration::from_secs(t.unwrap_or(600)),
        Err(_) => {
            return Err(crate::cli::usage_error(
                "sweep",
                "--timeout takes whole seconds",
            ));
        }
    };
    let out = PathBuf::from(args.out.as_deref().unwrap_or("target/umbra/sweep"));
    let default = DEFAULT_BACKENDS.iter().map(|s| s.to_string()).collect();
    let named: Vec<&str> = args.backend.iter().map(String::as_str).collect();
    let backends = crate::harness::registry::selected(&named, default).map_err(Error::new)?;
    let points = umbra_case::load_file(&scene).map_err(|e| Error::new(e.to_string()))?;
    let wanted = match (args.point.as_deref(), args.scene.as_deref()) {
        (Some(id), _) => Some(id),
        (None, None) => Some(DEFAULT_SCENE.1),
        (None, Some(_)) => None,
    };
    let point = match wanted {
        None => points[0].clone(),
        // An id, or a glob over the ids (the first point it matches).
        Some(id) => match points
            .iter()
            .find(|p| p.id() == id || crate::glob::matches(id, &p.id()))
        {
            Some(p) => p.clone(),
            None => {
                return Err(Error::new(format!(
                    "{} has no point {id:?}; its points: {}",
                    scene.display(),
                    points.iter().map(|p| p.id()).collect::<Vec<_>>().join(", ")
                )));
            }
        },
    };
    // A cascaded light sweeps its cascades instead (`sweep_cascades`).
    let techniques =
        super::sweep_cascades::matrix(&point.case).unwrap_or_else(|| matrix(&point.case));
    let (file, plan) = write_case(&point, &techniques, &out)
        .map_err(|e| Error::new(format!("cannot generate the sweep case: {e}")))?;
    let started = Instant::now();
    let total = plan.iter().flatten().count() * backends.len();
    let mut rows: Vec<Row> = Vec::new();
    let mut done = 0;
    // The truth of each technique point is cached per build of umbra, as conformance's is.
    let judge_cache = crate::judge::judge_cache::prepare(Path::new(
        args.judge_cache
            .as_deref()
            .unwrap_or(crate::judge::judge_cache::DEFAULT_ROOT),
    ));
    let sweep = Sweep {
        file: &file,
        plan: &plan,
        judge_cache: &judge_cache,
        repeat,
        timeout,
        total,
    };
    for backend in &backends {
        sweep.on(backend, &mut rows, &mut done)?;
    }
    let wall = started.elapsed();
    let command = format!(
        "umbra {}",
        std::env::args().skip(1).collect::<Vec<_>>().join(" ")
    );
    write_outputs(&out, &rows, &point, &command, wall).map_err(|e| {
        Error::new(format!(
            "cannot write the sweep's outputs under {}: {e}",
            out.display()
        ))
    })?;
    let errors = rows
        .iter()
        .filter(|r| r.result.is_err() && !r.skipped)
        .count();
    let skipped = rows.iter().filter(|r| r.skipped).count();
    println!(
        "\nsweep of {} on {} backends: {} points measured, {skipped} skipped, {errors} errors in {:.1} s; outputs in {}",
        point.id(),
        backends.len(),
        rows.len() - errors - skipped,
        wall.as_secs_f64(),
        out.display()
    );
    Ok(Exit::pass_if(errors == 0))
}

/// What every backend of one sweep runs: the generated case file and its plan (a technique
/// per index of the file's expansion), and how.
struct Sweep<'a> {
    file: &'a Path,
    plan: &'a [Option<Technique>],
    judge_cache: &'a Path,
    repeat: u32,
    timeout: Duration,
    /// Planned points over every backend (for the progress count).
    total: usize,
}

impl Sweep<'_> {
    /// Every planned point on `backend`, in one worker (a fresh one after a crash or a
    /// timeout): a row each onto `rows`, counted in `done`. A worker that refuses the Mesa
    /// build ends the sweep (could not run).
    fn on(&self, backend: &str, rows: &mut Vec<Row>, done: &mut usize) -> Result<(), Error> {
        let (timeout, total) = (self.timeout, self.total);
        let mut env = crate::harness::registry::worker_env(backend);
        env.push((
            crate::judge::judge_cache::ENV.into(),
            self.judge_cache.to_string_lossy().into_owned(),
        ));
        // One session: a worker that crashed or timed out is started again for the next point.
        let mut session = Session::start(backend, &env, timeout);
        let not_ready = match session.ready() {
            Err(NotReady::Refused(why)) => return Err(Error::new(why)),
            r => r.err(),
        };
        for (index, t) in self.plan.iter().enumerate() {
            let Some(t) = t else { continue };
            *done += 1;
            if let Some(nr) = &not_ready {
                let (result, skipped) = match nr {
                    NotReady::Unavailable(why) => (Err(why.clone()), true),
                    NotReady::NoWorker(e) | NotReady::Refused(e) => {
                        (Err(format!("cannot start the worker: {e}")), false)
                    }
                };
                rows.push(Row {
                    backend: backend.to_string(),
                    technique: t.clone(),
                    result,
                    skipped,
                });
                continue;
            }
            let req = Request {
                file: self.file.to_path_buf(),
                index,
                failures: None,
                golden: None,
                repeat: Some(self.repeat),
                no_twins: false,
                gallery: None,
                deviation: None,
                card: false,
                calibration: None,
            };
            let (result, skipped) = match session.reply(&req) {
                Ok((Reply::Report(r), _)) => match (r.outcome, r.measured) {
                    (RunVerdict::Pass, Some(m)) => (Ok(m), false),
                    (RunVerdict::Skip, _) => (Err(r.reason), true),
                    _ => (Err(r.reason), false),
                },
                Ok((Reply::Crashed(why), _)) => (Err(format!("the worker crashed: {why}")), false),
                Ok((Reply::TimedOut, _)) => {
                    (Err(format!("no answer in {} s", timeout.as_secs())), false)
                }
                Err(e) => (Err(format!("cannot start the worker: {e}")), false),
            };
            let line = match &result {
                Ok(m) => format!(
                    "{:.2} ms ({}), error {:.3}%",
                    m.frame_ms,
                    m.clock,
                    100.0 * (m.false_shadow + m.false_light) as f64 / m.judged.max(1) as f64
                ),
                Err(e) if skipped => format!("skip: {e}"),
                Err(e) => format!("ERROR: {e}"),
            };
            println!("[{}/{total}] {backend} {}: {line}", *done, t.label());
            rows.push(Row {
                backend: backend.to_string(),
                technique: t.clone(),
                result,
                skipped,
            });
        }
        Ok(())
    }
}

/// Measures point `index` of case `file` on each backend, one backend after the other, each
/// in a worker started from `exe` (the `umbra` binary) with its driver's environment.
pub fn measure_backends(
    exe: &Path,
    file: &Path,
    index: usize,
    backends: &[String],
    repeat: u32,
    timeout: Duration,
    extra_env: &[(String, String)],
) -> Vec<(String, Result<Measured, String>)> {
    backends
        .iter()
        .map(|b| {
            let mut env = crate::harness::registry::worker_env(b);
            env.extend(extra_env.iter().cloned());
            let mut session = Session::start_exe(exe, b, &env, timeout);
            let result = (|| {
                match session.ready() {
                    Ok(()) => {}
                    Err(NotReady::NoWorker(e)) => return Err(e),
                    Err(NotReady::Unavailable(why)) => return Err(format!("unavailable: {why}")),
                    Err(NotReady::Refused(why)) => {
                        return Err(format!("refused the Mesa build: {why}"));
                    }
                }
                let req = Request {
                    file: file.to_path_buf(),
                    index,
                    failures: None,
                    golden: None,
                    repeat: Some(repeat),
                    no_twins: false,
                    gallery: None,
                    deviation: None,
                    card: false,
                    calibration: None,
                };
                match session.reply(&req)?.0 {
                    Reply::Report(r) => r.measured.ok_or(r.reason),
                    Reply::Crashed(why) => Err(format!("the worker crashed: {why}")),
                    Reply::TimedOut => Err("timed out".into()),
                }
            })();
            (b.clone(), result)
        })
        .collect()
}

/// Per backend, the indices of `rows` on the Pareto front of (time, error): no other point
/// of the backend is at least as fast and at least as accurate, and better in one.
pub fn pareto(rows: &[Row]) -> Vec<bool> {
    let key = |r: &Row| {
        r.result
            .as_ref()
            .ok()
            .map(|m| (m.frame_ms, r.error_pct().unwrap_or(f64::INFINITY)))
    };
    rows.iter()
        .map(|r| {
            let Some((t, e)) = key(r) else { return false };
            !rows.iter().any(|o| {
                o.backend == r.backend
                    && key(o).is_some_and(|(to, eo)| to <= t && eo <= e && (to < t || eo < e))
            })
        })
        .collect()
}

fn write_outputs(
    out: &Path,
    rows: &[Row],
    point: &umbra_case::CasePoint,
    command: &str,
    wall: Duration,
) -> std::io::Result<()> {
    let scene = &point.id();
    let front = pareto(rows);
    let mut csv = String::from(
        "backend,size,format,filter,bias,frustum,status,clock,samples,shadow_ms,lit_ms,frame_ms,wall_ms,judged,false_shadow,false_light,error_pct,edge_mean_px,edge_max_px,aliasing_max,aliasing_mean,pareto,reason\n",
    );
    for (r, on_front) in rows.iter().zip(&front) {
        let t = &r.technique;
        let opt = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_default();
        match &r.result {
            Ok(m) => {
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},ok,{},{},{:.3},{:.3},{:.3},{:.3},{},{},{},{:.4},{},{},{},{},{on_front},",
                    r.backend,
                    t.size,
                    t.format,
                    t.filter,
                    t.bias,
                    t.frustum,
                    m.clock,
                    m.samples,
                    m.shadow_ms,
                    m.lit_ms,
                    m.frame_ms,
                    m.total_ms,
                    m.judged,
                    m.false_shadow,
                    m.false_light,
                    r.error_pct().unwrap_or_default(),
                    opt(m.edge_mean_px),
                    opt(m.edge_max_px),
                    opt(m.aliasing_max),
                    opt(m.aliasing_mean)
                );
            }
            Err(e) => {
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},{},,,,,,,,,,,,,,,false,\"{}\"",
                    r.backend,
                    t.size,
                    t.format,
                    t.filter,
                    t.bias,
                    t.frustum,
                    if r.skipped { "skip" } else { "error" },
                    e.replace('"', "\"\"")
                );
            }
        }
    }
    std::fs::create_dir_all(out)?;
    std::fs::write(out.join("sweep.csv"), csv)?;
    let title = format!("{scene}: frame time vs error");
    let plotted: Vec<umbra_report::pareto::ParetoPoint> = rows
        .iter()
        .zip(&front)
        .map(|(r, on)| umbra_report::pareto::ParetoPoint {
            backend: r.backend.clone(),
            measured: r
                .result
                .as_ref()
                .ok()
                .zip(r.error_pct())
                .map(|(m, e)| (m.frame_ms, e)),
            front: *on,
        })
        .collect();
    std::fs::write(
        out.join("pareto.svg"),
        umbra_report::pareto::svg(&plotted, &title).map_err(std::io::Error::other)?,
    )?;
    std::fs::write(
        out.join("pareto.png"),
        umbra_report::pareto::png(&plotted, &title).map_err(std::io::Error::other)?,
    )?;
    let mut section = section(rows, &front, scene, command, wall, out);
    if super::sweep_cascades::matrix(&point.case).is_some() {
        section += &super::sweep_cascades::section(rows, &point.case);
    }
    std::fs::write(out.join("section.html"), &section)?;
    std::fs::write(
        out.join("report.html"),
        format!(
            "<!doctype html><html><head><meta charset=\"utf-8\"><title>umbra sweep</title><style>\
             body{{font:14px system-ui,sans-serif;margin:24px;color:#222}}table{{border-collapse:collapse}}\
             td,th{{border:1px solid #ddd;padding:3px 6px;text-align:right}}td:first-child{{text-align:left}}\
             .front{{font-weight:bold}}</style></head><body>{section}</body></html>\n"
        ),
    )?;
    Ok(())
}

/// The HTML section: the plot, the front per backend, fitted vs fixed at equal cost, and the
/// ratio of each backend's frame time to the reference's on the same techniques.
fn section(
    rows: &[Row],
    front: &[bool],
    scene: &str,
    command: &str,
    wall: Duration,
    out: &Path,
) -> String {
    let svg = std::fs::read_to_string(out.join("pareto.svg")).unwrap_or_default();
    let mut s = format!(
        "<h2>Speed against error: {}</h2><p>command: <code>{}</code>, {:.1} s. Frame time: shadow \
         pass + lit pass, median of N renders after a warm-up, on the clock sweep.csv names per \
         point (<i>gpu</i>: timer queries; <i>cpu-wall</i>); <code>wall_ms</code> there adds set-up \
         and readback. Error: false shadow + false light against the exact truth, % of \
         judged pixels. The front (bold) holds the points no other point of the same backend \
         beats on both.</p>{svg}",
        esc(scene),
        esc(command),
        wall.as_secs_f64()
    );
    let mut by_backend: BTreeMap<&str, Vec<(usize, &Row)>> = BTreeMap::new();
    for (i, r) in rows.iter().enumerate() {
        by_backend.entry(&r.backend).or_default().push((i, r));
    }
    s.push_str("<h3>Pareto front per backend</h3><table><tr><th>backend</th><th>technique</th><th>frame ms</th><th>clock</th><th>error %</th><th>false shadow</th><th>false light</th><th>edge mean / max px</th></tr>");
    for (backend, list) in &by_backend {
        let mut on: Vec<&(usize, &Row)> = list.iter().filter(|(i, _)| front[*i]).collect();
        on.sort_by(|a, b| {
            let t = |r: &Row| r.result.as_ref().map(|m| m.frame_ms).unwrap_or(0.0);
            t(a.1).total_cmp(&t(b.1))
        });
        for (_, r) in on {
            if let Ok(m) = &r.result {
                let _ = write!(
                    s,
                    "<tr class=\"front\"><td>{}</td><td>{}</td><td>{:.2}</td><td>{}</td><td>{:.3}</td><td>{}</td><td>{}</td><td>{} / {}</td></tr>",
                    esc(backend),
                    esc(&r.technique.label()),
                    m.frame_ms,
                    m.clock,
                    r.error_pct().unwrap_or_default(),
                    m.false_shadow,
                    m.false_light,
                    m.edge_mean_px
                        .map(|x| format!("{x:.2}"))
                        .unwrap_or("–".into()),
                    m.edge_max_px
                        .map(|x| format!("{x:.1}"))
                        .unwrap_or("–".into()),
                );
            }
        }
    }
    s.push_str("</table>");
    // Fitted against fixed, same shadow technique (equal cost: same map).
    let mut pairs = String::new();
    for r in rows.iter().filter(|r| r.technique.frustum == "fitted") {
        let Some(f) = rows.iter().find(|o| {
            o.backend == r.backend
                && o.technique.frustum == "fixed"
                && o.technique.shadow == r.technique.shadow
        }) else {
            continue;
        };
        if let (Ok(a), Ok(b)) = (&r.result, &f.result) {
            let _ = write!(
                pairs,
                "<tr><td>{}</td><td>{} {} {} {}</td><td>{:.3}</td><td>{:.3}</td><td>{:.2}</td><td>{:.2}</td></tr>",
                esc(&r.backend),
                r.technique.size,
                esc(&r.technique.format),
                esc(&r.technique.filter),
                esc(&r.technique.bias),
                r.error_pct().unwrap_or_default(),
                f.error_pct().unwrap_or_default(),
                a.frame_ms,
                b.frame_ms
            );
        }
    }
    if !pairs.is_empty() {
        let _ = write!(
            s,
            "<h3>Fitted frustum against a fixed box at equal cost</h3><p>Fixed: ortho ±{} m, near {}, far {} (a generous hand-set box). Same map size, format, filter and bias.</p>\
             <table><tr><th>backend</th><th>technique</th><th>error % fitted</th><th>error % fixed</th><th>ms fitted</th><th>ms fixed</th></tr>{pairs}</table>",
            FIXED_ORTHO[1], FIXED_ORTHO[4], FIXED_ORTHO[5]
        );
    }
    // Frame time relative to the reference, same technique, same run.
    if rows.iter().any(|r| r.backend == "ref") {
        s.push_str("<h3>Frame time relative to the reference</h3><p>Median over the techniques both ran, of this backend's frame time (passes) over the reference's (same frame, same run).</p><table><tr><th>backend</th><th>techniques</th><th>median ratio backend / ref</th></tr>");
        for backend in by_backend.keys().filter(|b| **b != "ref") {
            let mut ratios: Vec<f64> = rows
                .iter()
                .filter(|r| r.backend == *backend)
                .filter_map(|r| {
                    let reference = rows
                        .iter()
                        .find(|o| o.backend == "ref" && o.technique == r.technique)?;
                    let (a, b) = (r.result.as_ref().ok()?, reference.result.as_ref().ok()?);
                    (b.frame_ms > 0.0).then(|| a.frame_ms / b.frame_ms)
                })
                .collect();
            ratios.sort_by(f64::total_cmp);
            if let Some(m) = ratios.get(ratios.len() / 2) {
                let _ = write!(
                    s,
                    "<tr><td>{}</td><td>{}</td><td>{m:.2}</td></tr>",
                    esc(backend),
                    ratios.len()
                );
            }
        }
        s.push_str("</table>");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(backend: &str, ms: f64, fs: u64) -> Row {
        Row {
            backend: backend.into(),
            technique: Technique {
                size: 1,
                format: String::new(),
                filter: String::new(),
                bias: String::new(),
                frustum: String::new(),
                shadow: Value::Null,
                light: Value::Null,
            },
            result: Ok(Measured {
                frame_ms: ms,
                judged: 100,
                false_shadow: fs,
                ..Default::default()
            }),
            skipped: false,
        }
    }

    #[test]
    fn pareto_keeps_the_undominated_points_per_backend() {
        let rows = [
            row("a", 1.0, 10),
            row("a", 2.0, 5),
            row("a", 3.0, 7), // dominated by (2, 5)
            row("a", 4.0, 1),
            row("b", 9.0, 9), // alone on its backend
        ];
        assert_eq!(pareto(&rows), [true, true, false, true, true]);
    }

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
