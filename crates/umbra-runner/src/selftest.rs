//! `umbra selftest`: proves the harness can tell right from wrong. For every named fault
//! ([`umbra_case::fault::Fault`]) and every backend it applies to, a worker runs with the fault
//! turned on (`UMBRA_SELFTEST=1`, `UMBRA_FAULT=name`) and is fed case points, in the catalogue's
//! order, until the judge fails one (or the worker crashes or hangs): the fault is caught. A
//! fault that every case point lets through is missed, and a missed fault fails the self-test.
//! Goldens are not consulted, so a catch is the judge's (truth and reference), not a picture
//! diff.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use umbra_case::fault::Fault;

use crate::args::Args;
use crate::pool::{Reply, Worker};
use crate::worker::Request;

/// Usage line.
pub const USAGE: &str =
    "umbra selftest [--backend ID]... [--cases DIR] [--timeout SECS] [--jobs N]";

/// Whether `fault` means anything on backend `id`.
pub fn applies(fault: Fault, id: &str) -> bool {
    let gl = umbra_gl::parse_id(id).is_some();
    let wgpu = umbra_wgpu::Kind::parse(id).is_some();
    match fault {
        Fault::GlDepthRange => wgpu,
        Fault::WrongComponent | Fault::WrongTextureUnit => gl,
        _ => gl || wgpu,
    }
}

/// Whether case `c` exercises `fault` at all (points that do are tried first; the rest stay
/// eligible, so this orders the hunt without deciding it).
pub fn exercises(fault: Fault, c: &umbra_case::Case) -> bool {
    use umbra_case::format::{Compare, Light, Outside};
    match fault {
        Fault::WrongComponent => c.shadow.compare == Compare::Manual,
        Fault::Repeat => c.shadow.outside != Outside::Lit,
        Fault::NoGuard | Fault::NoDivide => !matches!(c.light, Light::Directional(_)),
        Fault::ShadowViewport => c.shadow.size != c.camera.size,
        _ => true,
    }
}

/// Runs the command; returns the exit code.
pub fn main(argv: &[String]) -> i32 {
    let args = match Args::parse(argv, &["backend", "cases", "timeout", "jobs"], &[]) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}\nusage: {USAGE}");
            return 125;
        }
    };
    let cases = PathBuf::from(args.value("cases").unwrap_or("cases"));
    let timeout = Duration::from_secs(
        args.value("timeout")
            .and_then(|t| t.parse().ok())
            .unwrap_or(120),
    );
    let jobs = args
        .value("jobs")
        .and_then(|j| j.parse().ok())
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    let mut backends: Vec<String> = args
        .values("backend")
        .iter()
        .map(|s| s.to_string())
        .collect();
    if backends.is_empty() {
        backends = crate::registry::known()
            .into_iter()
            .filter(|b| b != "ref")
            .collect();
    }
    let mut points = Vec::new();
    for f in umbra_case::case_files(&cases).unwrap_or_default() {
        match umbra_case::load_file(&f) {
            Ok(p) => points.extend(p.into_iter().enumerate().map(|(i, p)| (f.clone(), i, p))),
            Err(e) => {
                eprintln!("error: {e}");
                return 125;
            }
        }
    }
    if points.is_empty() {
        eprintln!("error: no case under {}", cases.display());
        return 125;
    }
    let pairs: Vec<(String, Fault)> = backends
        .iter()
        .flat_map(|b| {
            Fault::ALL
                .into_iter()
                .filter(|f| applies(*f, b))
                .map(move |f| (b.clone(), f))
        })
        .collect();
    let queue = Mutex::new(pairs.clone());
    let results = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                let next = || queue.lock().ok().and_then(|mut q| q.pop());
                while let Some((backend, fault)) = next() {
                    let verdict = hunt(&backend, fault, &points, timeout);
                    println!(
                        "{:<18} {:<20} {}",
                        fault.name(),
                        backend,
                        verdict
                            .as_ref()
                            .map_or_else(|e| format!("MISSED: {e}"), |c| format!("caught by {c}"))
                    );
                    if let Ok(mut r) = results.lock() {
                        r.push((backend, fault, verdict));
                    }
                }
            });
        }
    });
    let results = results.into_inner().unwrap_or_default();
    let caught = results.iter().filter(|r| r.2.is_ok()).count();
    let missed: Vec<_> = results.iter().filter(|r| r.2.is_err()).collect();
    for (b, f, v) in &missed {
        if let Err(e) = v {
            println!("  missed: {} on {b}: {e}", f.name());
        }
    }
    println!(
        "selftest: {caught} of {} fault × backend pairs caught",
        results.len()
    );
    println!("selftest: {caught} passed, {} failed", missed.len());
    if results.is_empty() {
        125
    } else if missed.is_empty() {
        0
    } else {
        1
    }
}

/// Feeds points to a faulted worker until one fails; Ok(what caught it) or Err(why not).
fn hunt(
    backend: &str,
    fault: Fault,
    points: &[(PathBuf, usize, umbra_case::CasePoint)],
    timeout: Duration,
) -> Result<String, String> {
    let mut env = crate::registry::driver_env(backend).unwrap_or_default();
    env.extend([("UMBRA_SELFTEST", "1"), ("UMBRA_FAULT", fault.name())]);
    let mut worker = Worker::start(backend, &env, timeout)?;
    if let Some(u) = worker.hello.get("unavailable") {
        return Err(format!("backend unavailable: {u}"));
    }
    let mut order: Vec<&(PathBuf, usize, umbra_case::CasePoint)> = points.iter().collect();
    order.sort_by_key(|(_, _, p)| !exercises(fault, &p.case));
    for (file, index, point) in order {
        let id = point.id();
        let req = Request {
            file: file.clone(),
            index: *index,
            failures: None,
            golden: None,
            repeat: None,
        };
        match worker.run(&req, timeout) {
            Reply::Report(r) if r.outcome == "fail" => {
                return Ok(format!(
                    "{id} ({})",
                    r.reason
                        .lines()
                        .next()
                        .unwrap_or("")
                        .chars()
                        .take(90)
                        .collect::<String>()
                ));
            }
            Reply::Report(_) => {}
            Reply::Crashed(how) => return Ok(format!("{id} (the worker died: {how})")),
            Reply::TimedOut => return Ok(format!("{id} (timeout)")),
        }
    }
    Err(format!(
        "all {} case points passed with the fault on",
        points.len()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_apply_where_they_mean_something() {
        assert!(
            applies(Fault::GlDepthRange, "wgpu-vk/lavapipe")
                && !applies(Fault::GlDepthRange, "gl33/zink")
        );
        assert!(
            applies(Fault::WrongTextureUnit, "gles2/softpipe")
                && !applies(Fault::WrongTextureUnit, "wgpu-gl/llvmpipe")
        );
        assert!(
            !Fault::ALL.iter().any(|f| applies(*f, "ref")),
            "the reference is the yardstick, not a suspect"
        );
        let applicable: usize = crate::registry::known()
            .iter()
            .map(|b| Fault::ALL.iter().filter(|f| applies(**f, b)).count())
            .sum();
        assert_eq!(applicable, 9 * 10 + 2 * 9);
    }

    #[test]
    fn faults_stay_off_outside_the_selftest() {
        // This test process has no UMBRA_SELFTEST, whatever UMBRA_FAULT might say.
        if std::env::var("UMBRA_SELFTEST").is_err() {
            assert_eq!(Fault::active(), None);
        }
        assert_eq!(Fault::parse("no-guard"), Some(Fault::NoGuard));
        assert!(
            Fault::ALL
                .iter()
                .all(|f| Fault::parse(f.name()) == Some(*f))
        );
    }
}
