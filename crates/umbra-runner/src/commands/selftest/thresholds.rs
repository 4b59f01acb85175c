//! `umbra selftest thresholds` (or `--thresholds`): the smallest error of each continuous
//! parameter that the catalogue catches, per backend family.
//!
//! The self-test's parameter faults are large (units × 0.1, slope × 0.8): catching them says
//! nothing about a driver that is off by 5 %. Here each parameter a driver (or a program) can
//! get slightly wrong ([`Param`]: the polygon offset's units, factor and clamp, the shader's
//! constant, slope and N·L biases, the normal offset, the lookup coordinate and the shadow
//! pass's image in u and v, a manual bilinear filter's weights) is put off by a decreasing
//! ladder of errors ([`LADDER`]: relative, or texels for the shifts), in each direction, on one
//! backend of each family, and the catalogue's points that exercise it are judged exactly as
//! the self-test judges them (expectations applied). A step counts as caught when one point
//! fails; the sweep goes down the ladder until a step is not caught, trying first the point
//! that caught the step before, then every point built for the parameter, then a spread of
//! [`TRIES`] of the rest. The threshold is the smallest step caught (it can
//! only be read as "at most this": a point outside the tries might catch a smaller one).
//!
//! Families: GL 3.3 and GLES 3 share their shaders and state (gl33/llvmpipe stands for both),
//! GLES 2 packs depth and offsets in the shader (gles2/llvmpipe), wgpu has its own shaders and
//! an integer depth-bias constant (wgpu-vk/lavapipe). `--backend` picks others.

use std::path::PathBuf;

use umbra_case::CasePoint;
use umbra_case::fault::{Fault, Param};

use crate::exit::{Exit, Outcome};

use super::{Faulted, How, Seen, applies, sample_order};

/// The errors tried, largest first: relative for a parameter, texels for a shift. The steps
/// between 50 % and 90 % read a parameter whose spec leaves a factor-of-two freedom (the
/// polygon-offset unit r ∈ [2⁻ⁿ, 2·2⁻ⁿ]): a driver at one edge is legal down to −50 %, and 55 %
/// then means 10 % beyond the other edge.
pub const LADDER: [f64; 11] = [
    0.9, 0.75, 0.6, 0.55, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.005,
];

/// Points tried at most per step, besides every point built for the parameter, before it
/// counts as not caught.
pub const TRIES: usize = 12;

/// The backend standing for each family, by default.
pub const FAMILIES: [(&str, &str); 3] = [
    ("GL 3.3/GLES 3", "gl33/llvmpipe"),
    ("GLES 2", "gles2/llvmpipe"),
    ("wgpu", "wgpu-vk/lavapipe"),
];

/// The outcome of one parameter, direction and backend.
#[derive(Clone, Debug, Default)]
pub struct Threshold {
    /// Points that exercise the parameter on the backend.
    pub exercising: usize,
    /// The smallest step caught, the point that caught it and how.
    pub caught: Option<(f64, String, String)>,
    /// Why nothing was run, when so.
    pub note: Option<String>,
}

type Point = (PathBuf, usize, CasePoint);

/// Walks the ladder for `param` in direction `sign` on `backend`.
fn sweep(backend: &str, param: Param, sign: f64, points: &[Point], how: &How) -> Threshold {
    let mut t = Threshold::default();
    let probe = Fault::scaled(param, sign * LADDER[0]);
    let es2 =
        crate::harness::registry::Descriptor::of(backend).is_some_and(|b| b.gles2_technique());
    let candidates: Vec<&Point> = points
        .iter()
        .filter(|(_, _, p)| probe.exercises(&p.case, es2))
        .collect();
    t.exercising = candidates.len();
    if candidates.is_empty() {
        t.note = Some("no point exercises it".into());
        return t;
    }
    // Every point built for the parameter, then a spread of the others.
    let aimed = candidates
        .iter()
        .filter(|c| probe.aimed_at(&c.2.case))
        .count();
    let base = sample_order(probe, &candidates);
    let mut base: Vec<usize> = base
        .iter()
        .copied()
        .filter(|&i| probe.aimed_at(&candidates[i].2.case))
        .chain(
            base.iter()
                .copied()
                .filter(|&i| !probe.aimed_at(&candidates[i].2.case)),
        )
        .collect();
    base.truncate(aimed + TRIES);
    let mut first: Option<usize> = None;
    for e in LADDER {
        let fault = Fault::scaled(param, sign * e);
        let mut faulted = match Faulted::start(backend, fault, how) {
            Ok(f) => f,
            Err((why, _)) => {
                t.note = Some(why);
                return t;
            }
        };
        let order: Vec<usize> = first
            .into_iter()
            .chain(base.iter().copied().filter(|i| Some(*i) != first))
            .collect();
        let mut hit = None;
        for i in order {
            let point = &candidates[i].2;
            if !applied_as_asked(backend, fault, &point.case) {
                continue;
            }
            match faulted.run(point) {
                Seen::Caught(checks) => {
                    hit = Some((i, point.id(), checks));
                    break;
                }
                Seen::Passed | Seen::Skipped(_) => {}
                // No worker: this magnitude was not measured, nor can a smaller one be.
                Seen::Gone => break,
            }
        }
        match hit {
            Some((i, id, checks)) => {
                first = Some(i);
                t.caught = Some((e, id, checks));
            }
            None => break,
        }
    }
    t
}

/// Whether `backend` applies `fault` to `case` as the error it is named for: wgpu's depth-bias
/// constant is an integer, so units off by e are rounded there, and a point whose rounded
/// units miss u·(1 + e) by more than a tenth of the error would measure another error.
fn applied_as_asked(backend: &str, fault: Fault, case: &umbra_case::Case) -> bool {
    let Some(e) = fault.error_of(Param::OffsetUnits) else {
        return true;
    };
    if !crate::harness::registry::Descriptor::of(backend).is_some_and(|d| d.integer_depth_bias()) {
        return true;
    }
    let u = f64::from(case.shadow.bias.polygon_offset[1]);
    let asked = u * (1.0 + f64::from(e));
    (asked.round() - asked).abs() <= 0.1 * (u * f64::from(e)).abs()
}

/// The command: the sweep on each family's backend (or `chosen`), the table; it passes (the
/// thresholds are measurements; the self-test proper holds the gross faults).
pub(crate) fn main(points: &[Point], chosen: Option<&[String]>, how: &How, jobs: usize) -> Outcome {
    let columns: Vec<(String, String)> = match chosen {
        Some(b) => b.iter().map(|b| (b.clone(), b.clone())).collect(),
        None => FAMILIES
            .iter()
            .map(|(f, b)| (f.to_string(), b.to_string()))
            .collect(),
    };
    let mut tasks = Vec::new();
    for (_, backend) in &columns {
        for param in Param::ALL {
            if !applies(Fault::scaled(param, 0.5), backend) {
                continue;
            }
            for sign in [-1.0, 1.0] {
                tasks.push((backend.clone(), param, sign));
            }
        }
    }
    let start = std::time::Instant::now();
    let results = crate::harness::scheduler::run_pool(tasks, jobs, |(backend, param, sign)| {
        let t = sweep(&backend, param, sign, points, how);
        println!("{}", line(&backend, param, sign, &t));
        (backend, param, sign, t)
    });
    print!("{}", table(&columns, &results));
    println!(
        "thresholds: {} sweeps in {:.0} s",
        results.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(Exit::Pass)
}

/// One step's text: "5 %" or "0.05 tx".
fn step(param: Param, e: f64) -> String {
    if param.in_texels() {
        format!("{e} tx")
    } else {
        format!("{} %", (e * 1e5).round() / 1e3)
    }
}

fn line(backend: &str, param: Param, sign: f64, t: &Threshold) -> String {
    let dir = if sign < 0.0 { "-" } else { "+" };
    match (&t.caught, &t.note) {
        (Some((e, id, checks)), _) => format!(
            "{:<16} {dir} {backend:<18} caught down to {} by {id} [{checks}] ({} points exercise it)",
            param.name(),
            step(param, *e),
            t.exercising
        ),
        (None, Some(n)) => format!("{:<16} {dir} {backend:<18} {n}", param.name()),
        (None, None) => format!(
            "{:<16} {dir} {backend:<18} not caught at {} ({} points exercise it)",
            param.name(),
            step(param, LADDER[0]),
            t.exercising
        ),
    }
}

/// The table: per parameter and column, the smaller and larger thresholds.
fn table(columns: &[(String, String)], results: &[(String, Param, f64, Threshold)]) -> String {
    let mut out = String::from(
        "\nthresholds: the smallest error the catalogue catches (too small / too large; relative, \
         or texels for the shifts; \"> 90 %\" = not caught at the ladder's top, \"-\" = no point \
         exercises it)\n",
    );
    out.push_str(&format!("{:<16}", "parameter"));
    for (name, _) in columns {
        out.push_str(&format!(" {name:>26}"));
    }
    out.push('\n');
    for param in Param::ALL {
        out.push_str(&format!("{:<16}", param.name()));
        for (_, backend) in columns {
            let cell = |sign: f64| -> String {
                let t = results
                    .iter()
                    .find(|r| r.0 == *backend && r.1 == param && r.2 == sign);
                match t {
                    None => "n/a".into(),
                    Some((_, _, _, t)) if t.exercising == 0 => "-".into(),
                    Some((_, _, _, t)) => match &t.caught {
                        Some((e, _, _)) => step(param, *e),
                        None => format!("> {}", step(param, LADDER[0])),
                    },
                }
            };
            out.push_str(&format!(
                " {:>26}",
                format!("{} / {}", cell(-1.0), cell(1.0))
            ));
        }
        out.push('\n');
    }
    out
}
