//! `umbra repro RUN -o DIR`: a failing run (`backend/case@point`, as conformance names it)
//! becomes a bundle a driver developer can use without umbra (see [`crate::repro`]):
//!
//! 1. the point is found under `--cases` (or `--case FILE`) and reduced by the reducer
//!    ([`crate::reduction`]: same failed checks, still passing on the reference; its log in
//!    `reduce.log`) into `case.json`; a case of several lights becomes a one-light case when
//!    the failure needs only one, and is refused, naming the reduced case, when it needs
//!    several;
//! 2. in the driver's process, the reduced run is rendered judged and recorded, and
//!    `repro.c`, the probes, the pictures and `facts.json` are written ([`crate::repro::emit`]);
//! 3. `repro.c` is compiled with `cc` and run on the driver and on a conforming control
//!    (`--control`, by default the same API on llvmpipe): the bundle is done only when it
//!    exits 1 on the driver and 0 on the control;
//! 4. for GL runs with apitrace installed, the program's calls are captured
//!    (`capture.trace`) and replayed on both drivers with `eglretrace --headless --snapshot`
//!    at the lit pass's draw;
//! 5. `issue.md` (Mesa's bug template) and `README.md` are written.
//!
//! Exit: 0 a bundle that reproduces, 1 nothing to reproduce (the run passes) or a program
//! that does not reproduce, 125 could not run.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use crate::cli::ReproArgs;
use crate::exit::{Error, Exit, Outcome};
use crate::harness::registry;
use crate::repro::issue::{Measured, ProgramRun, Replay};

/// The longest a compiled repro may run.
const PROGRAM_TIMEOUT: Duration = Duration::from_secs(120);

/// The usage line of `umbra repro`'s own errors.
const USAGE: &str = "umbra repro BACKEND/CASE@POINT -o DIR";

/// What the bundle is of, and where it goes.
struct Target {
    run: String,
    backend: String,
    out: PathBuf,
    case_file: PathBuf,
    point: String,
}

/// Runs `umbra repro`: the steps in order; an `Err` is the step that ended the command.
pub fn main(args: &ReproArgs) -> Outcome {
    crate::harness::mesa_build::select(args.mesa.as_ref()).map_err(Error::new)?;
    if args.emit {
        return emit(args);
    }
    if args.bisect_log.is_some() && args.first_bad.is_none() {
        return Err(usage(
            "--bisect-log goes with --first-bad COMMIT (the commit the log found): give both",
        ));
    }
    // Read before the reduction, not after it: a damaged directory is said, not dropped from
    // issue.md.
    let expectations =
        crate::judge::expectations::Expectations::load(&args.expectations).map_err(Error::new)?;
    let t = target(args)?;
    println!(
        "repro: {} ({} point {})",
        t.run,
        t.case_file.display(),
        t.point
    );
    let (reduced, summary) = reduce_step(args, &t)?;
    one_light(&reduced)?;
    let facts = emit_step(args, &t, &reduced)?;
    let mut m = Measured::new(
        t.run.clone(),
        t.case_file.display().to_string(),
        t.point.clone(),
    );
    m.reduced = summary;
    m.command = format!(
        "umbra {}",
        std::env::args().skip(1).collect::<Vec<_>>().join(" ")
    );
    let control = args.control.clone().or_else(|| default_control(&t.backend));
    let binary = t.out.join("repro");
    run_programs(&t, &facts, &binary, control.as_deref(), &mut m)?;
    (m.capture, m.replays) = if registry::Descriptor::of(&t.backend).is_some_and(|d| d.vulkan()) {
        gfxr_capture(&t.out, &t.backend, &reduced)
    } else {
        capture(&t.out, &binary, &t.backend, control.as_deref(), &m)
    };
    m.diagnosis = diagnosis(&expectations, &t.run, &reduced);
    m.mesa_build = crate::harness::mesa_build::selected().map(|b| b.describe());
    if let Some(commit) = args.first_bad.as_deref() {
        let log = match args.bisect_log.as_deref() {
            Some(l) => {
                let text = std::fs::read_to_string(l)
                    .map_err(|e| Error::new(format!("--bisect-log {}: {e}", l.display())))?;
                save(&t.out.join("bisect.log"), &text)?;
                Some(text)
            }
            None => None,
        };
        m.bisect = Some((commit.to_string(), log));
    }
    finish(&t.out, &facts, &mut m)
}

/// The run named on the command line, its case file and an empty bundle directory.
fn target(args: &ReproArgs) -> Result<Target, Error> {
    let run = &args.positional;
    let Some((backend, case_point)) = split_run(run) else {
        return Err(usage(format!(
            "{run:?} is not a run name: give backend/case@point as conformance prints it (e.g. gl33/softpipe/beyond-far@shadow.format=depth24)"
        )));
    };
    if !registry::is_known(&backend) || backend == "ref" {
        return Err(usage(format!(
            "{backend:?} is not a driver backend; this build has: {}",
            registry::known().join(", ")
        )));
    }
    let out = PathBuf::from(&args.out);
    if std::fs::read_dir(&out).is_ok_and(|mut d| d.next().is_some()) {
        return Err(Error::new(format!(
            "{} is not empty: give a new directory for the bundle (a bundle's files must all come from one run)",
            out.display()
        )));
    }
    // The point first: a run that names no case point leaves no directory behind.
    let (case_file, point) = find_point(args, &case_point).map_err(Error::new)?;
    std::fs::create_dir_all(&out)
        .map_err(|e| Error::new(format!("cannot create {}: {e}", out.display())))?;
    Ok(Target {
        run: run.clone(),
        backend,
        out,
        case_file,
        point,
    })
}

/// The reducer ([`crate::reduction`]) into `case.json`, its log into `reduce.log`: the
/// reduced file and the reducer's before → after line. A point that passes fails the
/// command, "nothing to reproduce".
fn reduce_step(args: &ReproArgs, t: &Target) -> Result<(PathBuf, String), Error> {
    let reduced = t.out.join("case.json");
    let reduce = crate::cli::ReduceArgs {
        positional: t.case_file.clone(),
        point: t.point.clone(),
        backend: vec![crate::cli::BackendName(t.backend.clone())],
        check: args.check.clone(),
        output: crate::cli::Output {
            out: Some(reduced.clone()),
            ..Default::default()
        },
        timeout: args.timeout,
        mesa: args.mesa.clone(),
    };
    let log_path = t.out.join("reduce.log");
    let mut log = std::fs::File::create(&log_path)
        .map_err(|e| Error::new(format!("cannot write {}: {e}", log_path.display())))?;
    let done = crate::reduction::reduce(&reduce, &mut log);
    match done {
        Ok(r) => {
            println!("  reduced: {}", r.file.display());
            Ok((r.file, r.summary))
        }
        Err(e) => {
            // The log ends as the command's would, with the error.
            let _ = writeln!(log, "error: {e}");
            if e.exit() == Exit::Fail {
                eprintln!(
                    "error: nothing to reproduce: {e}\n(umbra repro takes a run whose frame or shadow map fails the judge, as `umbra conformance` lists them; the reducer's log is in {})",
                    log_path.display()
                );
                return Err(Error::said(Exit::Fail));
            }
            Err(Error::new(format!("the reducer could not run: {e}")))
        }
    }
}

/// Refuses a reduced case that still has several lights: the standalone program's probes
/// hold one visibility readback to one light's intervals, and the reducer keeps every light
/// the failure needs (it drops them one at a time while the rest still fails).
fn one_light(reduced: &Path) -> Result<(), Error> {
    let lights = umbra_case::load_file(reduced)
        .map(|points| {
            points
                .iter()
                .map(|p| p.case.lights.len())
                .max()
                .unwrap_or(0)
        })
        .map_err(|e| Error::new(format!("the reduced case does not load: {e}")))?;
    if lights > 1 {
        return Err(Error::new(format!(
            "the failure needs {lights} lights: without any one of them the reduced case no longer \
             fails the same way (reduce.log), and a standalone program of several lights is not \
             built yet (its probes hold one light's visibility). The reduced case is {}; \
             `umbra render` on it shows each light's failures",
            reduced.display()
        )));
    }
    Ok(())
}

/// The driver-side half ([`crate::repro::emit`]) in the backend's own process; its facts.
fn emit_step(args: &ReproArgs, t: &Target, reduced: &Path) -> Result<crate::repro::Facts, Error> {
    let mut emit_args: Vec<String> = vec![
        "repro".into(),
        "--emit".into(),
        format!("--backend={}", t.backend),
        format!("--out={}", t.out.display()),
    ];
    if let Some(m) = &args.mesa {
        emit_args.push(format!("--mesa={m}"));
    }
    emit_args.extend(["--".into(), reduced.display().to_string()]);
    // The driver process says its own errors; its exit is the command's.
    let emitted = crate::harness::child::rerun_for(
        &t.backend,
        &emit_args,
        &registry::worker_env(&t.backend),
    )?;
    if emitted != Exit::Pass {
        return Err(Error::said(emitted));
    }
    let facts = crate::repro::Facts::read(&t.out).map_err(|e| {
        Error::new(format!(
            "the driver process wrote no readable facts.json: {e}"
        ))
    })?;
    if !facts.deterministic {
        println!(
            "  warning: the recorded render differs from the judged one: the driver is not deterministic on this case, so the probes test a frame umbra judged once"
        );
    }
    Ok(facts)
}

/// Compiles `repro.c` and runs it on the driver, then on the control (outputs kept as
/// `repro-BACKEND.txt`).
fn run_programs(
    t: &Target,
    facts: &crate::repro::Facts,
    binary: &Path,
    control: Option<&str>,
    m: &mut Measured,
) -> Result<(), Error> {
    if !facts.repro_c {
        m.no_program = Some(format!(
            "{} records no GL calls (repro.c is written for the GL backends)",
            t.backend
        ));
        return Ok(());
    }
    compile(&t.out.join("repro.c"), binary).map_err(Error::new)?;
    for b in std::iter::once(t.backend.as_str()).chain(control) {
        let r = run_program(binary, b, &t.out);
        save(
            &t.out.join(format!("repro-{}.txt", b.replace('/', "-"))),
            &r.output,
        )?;
        println!(
            "  repro on {}: exit {}",
            r.backend,
            r.code.map_or("none".into(), |c| c.to_string())
        );
        m.runs.push(r);
    }
    Ok(())
}

/// Writes issue.md and README.md; the outcome: it passes only when the program fails on the
/// driver and passes on the control (or none was run), fails otherwise (could not run: a file
/// not written).
fn finish(out: &Path, facts: &crate::repro::Facts, m: &mut Measured) -> Outcome {
    let reproduces = match (m.runs.first(), m.runs.get(1)) {
        (Some(d), c) => Some(d.code == Some(1) && c.is_none_or(|c| c.code == Some(0))),
        (None, _) => None,
    };
    m.verdict = match reproduces {
        Some(true) => {
            "Reproduces: the program exits 1 on the driver and 0 on the conforming control.".into()
        }
        Some(false) => {
            "**Does not reproduce as it must** (see the exit codes in issue.md): do not file it."
                .into()
        }
        None => "No program was run.".into(),
    };
    save(
        &out.join("issue.md"),
        &crate::repro::issue::issue_md(facts, m),
    )?;
    let files = list_files(out);
    save(
        &out.join("README.md"),
        &crate::repro::issue::readme(facts, m, &files),
    )?;
    println!("  wrote {} (its README.md lists the files)", out.display());
    match reproduces {
        Some(true) => Ok(Exit::Pass),
        Some(false) => {
            let codes: Vec<String> = m
                .runs
                .iter()
                .map(|r| {
                    format!(
                        "exit {} on {}",
                        r.code.map_or("none".into(), |c| c.to_string()),
                        r.backend
                    )
                })
                .collect();
            eprintln!(
                "error: the program does not reproduce as it must: {} (want 1 on the driver, 0 on the control); see {}",
                codes.join(", "),
                out.display()
            );
            Err(Error::said(Exit::Fail))
        }
        None => {
            eprintln!(
                "note: no program was run ({}); the bundle has the case, pictures and issue.md",
                m.no_program.as_deref().unwrap_or("?")
            );
            Ok(Exit::Pass)
        }
    }
}

/// The driver-side step (in the backend's process).
fn emit(args: &ReproArgs) -> Outcome {
    let Some(backend) = args.backend.as_ref().map(crate::cli::BackendName::as_str) else {
        return Err(usage("--emit takes the reduced case, --backend and --out"));
    };
    if !registry::hostable_here(backend) {
        return Err(Error::new(format!(
            "--emit must run in {backend}'s process (umbra repro starts it)"
        )));
    }
    crate::repro::emit(Path::new(&args.positional), backend, Path::new(&args.out))
}

/// `gl33/softpipe/case@point` → (`gl33/softpipe`, `case@point`).
pub fn split_run(run: &str) -> Option<(String, String)> {
    let mut parts = run.splitn(3, '/');
    let (api, driver, rest) = (parts.next()?, parts.next()?, parts.next()?);
    (!api.is_empty() && !driver.is_empty() && !rest.is_empty())
        .then(|| (format!("{api}/{driver}"), rest.to_string()))
}

/// The case file and point id of `case@point`.
fn find_point(args: &ReproArgs, case_point: &str) -> Result<(PathBuf, String), String> {
    let files = match &args.case {
        Some(f) => vec![f.clone()],
        None => umbra_case::load::case_files(&args.cases)
            .map_err(|e| format!("cannot list case files under {}: {e}", args.cases.display()))?,
    };
    for f in &files {
        // A file that does not load is said (it once became "no case point").
        let points = umbra_case::load_file(f).map_err(|e| e.to_string())?;
        // A case without a sweep has one point, named by the case alone.
        if let Some(p) = points.iter().find(|p| p.id() == case_point) {
            return Ok((f.clone(), p.id()));
        }
    }
    Err(format!(
        "no case point {case_point:?} in {} ({} files): give it as conformance names it, or --case FILE",
        args.case.as_ref().unwrap_or(&args.cases).display(),
        files.len()
    ))
}

/// The same API on llvmpipe (none when the run is on llvmpipe already).
fn default_control(backend: &str) -> Option<String> {
    let (api, driver) = backend.split_once('/')?;
    let gl = registry::Descriptor::of(backend).is_some_and(|d| d.umbra_makes_the_gl_calls());
    (gl && driver != "llvmpipe").then(|| format!("{api}/llvmpipe"))
}

/// `cc repro.c -o repro -lEGL -lm`, as the README says.
fn compile(source: &Path, binary: &Path) -> Result<(), String> {
    let o = Command::new("cc")
        .arg(source)
        .arg("-o")
        .arg(binary)
        .args(["-lEGL", "-lm"])
        .output()
        .map_err(|e| {
            format!("no C compiler: `cc` did not start ({e}); install gcc and libegl-dev")
        })?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!(
            "`cc repro.c -o repro -lEGL -lm` failed: {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .take(12)
                .collect::<Vec<_>>()
                .join("\n")
        ))
    }
}

/// The environment that selects `backend`'s driver (and the `--mesa` build's loaders), and
/// the driver variables the run inherited ([`registry::inherited_driver_env`]).
fn program_env(backend: &str) -> Vec<(String, String)> {
    let mut env: Vec<(String, String)> = registry::driver_env(backend)
        .unwrap_or_default()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    if let Some(build) = crate::harness::mesa_build::selected()
        .filter(|_| crate::harness::mesa_build::is_mesa_backed(backend))
    {
        env.extend(build.env(backend));
    }
    env.extend(registry::inherited_driver_env(backend));
    env
}

/// The environment as shell text for the bundle's readers. A `--mesa` build's loader files
/// that umbra wrote into a temporary directory (the glvnd vendor file, lavapipe's ICD) are
/// copied into the bundle's `mesa/` and named relative to it, so the commands work from the
/// bundle after this process is gone.
fn env_text(env: &[(String, String)], out: &Path) -> String {
    let tmp = std::env::temp_dir();
    env.iter()
        .filter(|(k, _)| !k.starts_with("UMBRA"))
        .map(|(k, v)| {
            let p = Path::new(v);
            let v = match p.file_name() {
                Some(name) if p.starts_with(&tmp) && p.is_file() => {
                    let _ = std::fs::create_dir_all(out.join("mesa"));
                    let _ = std::fs::copy(p, out.join("mesa").join(name));
                    format!("mesa/{}", name.to_string_lossy())
                }
                _ => v.clone(),
            };
            format!("{k}={}", umbra_report::escape::shell_word(&v))
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Runs the compiled program on `backend`'s driver, killed after [`PROGRAM_TIMEOUT`].
fn run_program(binary: &Path, backend: &str, out: &Path) -> ProgramRun {
    let env = program_env(backend);
    // A build with its own C library runs the program through its loader.
    let build = crate::harness::mesa_build::selected()
        .filter(|_| crate::harness::mesa_build::is_mesa_backed(backend));
    let own = build.and_then(crate::harness::mesa_build::MesaBuild::own_libc);
    let mut cmd = crate::harness::own_libc::command(own.as_ref(), binary);
    for v in registry::env_removed(backend) {
        cmd.env_remove(v);
    }
    let (code, output) = run_with_timeout(cmd.envs(env.clone()), PROGRAM_TIMEOUT);
    // What a reader types: the environment, then the build's loader where it has one.
    let through = own.as_ref().map_or(String::new(), |o| {
        format!(
            " {} --library-path {}",
            o.loader.display(),
            crate::harness::own_libc::search_path(o.dirs)
        )
    });
    ProgramRun {
        backend: backend.to_string(),
        env: env_text(&env, out) + &through,
        code,
        output,
    }
}

/// Runs `cmd`, its output captured, killed after `limit`.
fn run_with_timeout(cmd: &mut Command, limit: Duration) -> (Option<i32>, String) {
    let child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => return (None, format!("did not start: {e}\n")),
    };
    let start = std::time::Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return (None, format!("killed after {} s\n", limit.as_secs()));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return (None, format!("wait failed: {e}\n")),
        }
    }
    match child.wait_with_output() {
        Ok(o) => {
            let mut t = String::from_utf8_lossy(&o.stdout).into_owned();
            t.push_str(&String::from_utf8_lossy(&o.stderr));
            (o.status.code(), t)
        }
        Err(e) => (None, format!("no output: {e}\n")),
    }
}

/// An apitrace capture of the program on the driver, replayed on the driver and the control
/// with a snapshot at the lit pass's draw (the last glDrawArrays).
fn capture(
    out: &Path,
    binary: &Path,
    backend: &str,
    control: Option<&str>,
    m: &Measured,
) -> (Result<String, String>, Vec<Replay>) {
    if !registry::Descriptor::of(backend).is_some_and(|d| d.umbra_makes_the_gl_calls()) {
        return (
            Err(format!(
                "{backend} runs through wgpu's GL backend, whose calls umbra does not record; `apitrace trace --api egl umbra render case.json --backend {backend}` captures them"
            )),
            Vec::new(),
        );
    }
    if m.runs.is_empty() {
        return (Err("no program was built to capture".into()), Vec::new());
    }
    if let Some(b) = crate::harness::mesa_build::selected()
        .filter(|b| b.loader.is_some() && crate::harness::mesa_build::is_mesa_backed(backend))
    {
        return (
            Err(format!(
                "the Mesa build in {} carries its own C library and runs through its own loader, which apitrace's capture (LD_PRELOAD of the machine's libraries) cannot follow; run repro.c there as the bundle's commands say",
                b.root.display()
            )),
            Vec::new(),
        );
    }
    let trace = out.join("capture.trace");
    let env = program_env(backend);
    let (code, text) = run_with_timeout(
        Command::new("apitrace")
            .args(["trace", "--api", "egl", "-o"])
            .arg(&trace)
            .arg(binary)
            .envs(env.clone()),
        PROGRAM_TIMEOUT,
    );
    if code.is_none() || !trace.exists() {
        return (
            Err(format!(
                "apitrace is not installed or did not record (`apt install apitrace`): {}",
                text.lines().last().unwrap_or("")
            )),
            Vec::new(),
        );
    }
    let (_, dump) = run_with_timeout(
        Command::new("apitrace").arg("dump").arg(&trace),
        PROGRAM_TIMEOUT,
    );
    let Some(call) = dump
        .lines()
        .filter(|l| l.contains(" glDrawArrays("))
        .filter_map(|l| l.split_whitespace().next()?.parse::<u64>().ok())
        .next_back()
    else {
        return (
            Err("the capture holds no glDrawArrays call".into()),
            Vec::new(),
        );
    };
    let how = format!(
        "`capture.trace` (apitrace {}, `{} apitrace trace --api egl ./repro`) records the program's GL calls on {backend}. Replay it headless with a snapshot of the lit pass's colour target after its draw, call {call}:",
        version("apitrace"),
        env_text(&env, out)
    );
    let runs: Vec<(Replay, Option<PathBuf>, Option<serde_json::Value>)> = std::iter::once(backend)
        .chain(control)
        .map(|b| replay_on(out, b, call))
        .collect();
    let mut replays: Vec<Replay> = runs.iter().map(|r| r.0.clone()).collect();
    if let ([(_, pa, sa), (_, pb, sb)], Some(last)) = (runs.as_slice(), replays.last_mut()) {
        last.outcome
            .push_str(&compare_replays(backend, pa, pb, sa, sb));
    }
    (Ok(how), replays)
}

/// Replays the capture on `backend`'s driver: a colour snapshot after the lit pass's draw
/// (`call`) and the GL state there (`eglretrace -D`, kept as `state-BACKEND.json`).
fn replay_on(
    out: &Path,
    backend: &str,
    call: u64,
) -> (Replay, Option<PathBuf>, Option<serde_json::Value>) {
    let prefix = format!("replay-{}-", backend.replace('/', "-"));
    let mut env = program_env(backend);
    env.push(("WAFFLE_PLATFORM".into(), "surfaceless_egl".into()));
    let command = format!(
        "{} eglretrace --headless --snapshot={call} --snapshot-prefix={prefix} capture.trace",
        env_text(&env, out)
    );
    let (code, text) = run_with_timeout(
        Command::new("eglretrace")
            .current_dir(out)
            .args([
                "--headless".to_string(),
                format!("--snapshot={call}"),
                format!("--snapshot-prefix={prefix}"),
                "capture.trace".into(),
            ])
            .envs(env.clone()),
        PROGRAM_TIMEOUT,
    );
    let png = out.join(format!("{prefix}{call:010}.png"));
    let state = crate::repro::state::dump(out, "capture.trace", call, &env);
    if let Some(s) = &state {
        let _ = std::fs::write(
            out.join(format!("state-{}.json", backend.replace('/', "-"))),
            serde_json::to_string(s).unwrap_or_default(),
        );
    }
    let outcome = if png.exists() {
        format!(
            "wrote `{}`",
            png.file_name().unwrap_or_default().to_string_lossy()
        )
    } else {
        format!(
            "no snapshot (exit {}): {}",
            code.map_or("none".into(), |c| c.to_string()),
            text.lines().last().unwrap_or("")
        )
    };
    let replay = Replay {
        backend: backend.to_string(),
        command,
        outcome,
    };
    (replay, png.exists().then_some(png), state)
}

/// How the control's replay differs from the driver's: the colour snapshots, then every
/// texture and attachment of the state at the draw (the shadow map and the visibility target
/// show what the colour may not).
fn compare_replays(
    driver: &str,
    pa: &Option<PathBuf>,
    pb: &Option<PathBuf>,
    sa: &Option<serde_json::Value>,
    sb: &Option<serde_json::Value>,
) -> String {
    let mut text = String::new();
    if let (Some(pa), Some(pb)) = (pa, pb) {
        if let (Ok(ia), Ok(ib)) = (image::open(pa), image::open(pb)) {
            let (ia, ib) = (ia.to_rgba8(), ib.to_rgba8());
            let differ = ia.pixels().zip(ib.pixels()).filter(|(x, y)| x != y).count();
            text.push_str(&format!(
                "; its snapshot differs from {driver}'s on {differ} of {} pixels",
                ia.width() * ia.height()
            ));
        }
    }
    if let (Some(sa), Some(sb)) = (sa, sb) {
        let diffs: Vec<String> = crate::repro::state::differences(sa, sb)
            .into_iter()
            .map(|(name, d)| match d {
                Some((n, of)) => format!("{name}: {n} of {of} differ"),
                None => format!("{name}: not comparable"),
            })
            .collect();
        if !diffs.is_empty() {
            text.push_str(&format!(
                "; the state at that call (`eglretrace --headless -D CALL capture.trace`, kept as state-*.json): {}",
                diffs.join(", ")
            ));
        }
    }
    text
}

/// A GFXReconstruct capture of umbra rendering the reduced case on wgpu's Vulkan backend (no
/// program exists for it), replayed with gfxrecon-replay. The run is offscreen: it presents
/// no frame, so gfxreconstruct 0.9.18 replays every command but has no frame to screenshot;
/// the pictures are umbra's.
fn gfxr_capture(
    out: &Path,
    backend: &str,
    reduced: &Path,
) -> (Result<String, String>, Vec<Replay>) {
    let file = out.join("capture.gfxr");
    let Ok(exe) = crate::harness::own_libc::self_exe() else {
        return (Err("cannot find this executable".into()), Vec::new());
    };
    let layer = [
        ("VK_INSTANCE_LAYERS", "VK_LAYER_LUNARG_gfxreconstruct"),
        ("GFXRECON_CAPTURE_FILE_TIMESTAMP", "false"),
    ];
    let (code, text) = run_with_timeout(
        Command::new(exe)
            .arg("render")
            .arg(format!("--backend={backend}"))
            .arg(format!("--out={}", out.join("gfxr-render").display()))
            .arg("--")
            .arg(reduced)
            .envs(layer)
            .env("GFXRECON_CAPTURE_FILE", &file),
        PROGRAM_TIMEOUT,
    );
    let _ = std::fs::remove_dir_all(out.join("gfxr-render"));
    if code.is_none() || !file.exists() {
        return (
            Err(format!(
                "GFXReconstruct's capture layer is not installed or did not record (`apt install gfxreconstruct`): {}",
                text.lines().last().unwrap_or("")
            )),
            Vec::new(),
        );
    }
    let mut env = program_env(backend);
    env.push((
        "XDG_RUNTIME_DIR".into(),
        std::env::temp_dir().display().to_string(),
    ));
    let (code, text) = run_with_timeout(
        Command::new("gfxrecon-replay")
            .current_dir(out)
            .arg("capture.gfxr")
            .envs(env.clone()),
        PROGRAM_TIMEOUT,
    );
    let how = format!(
        "`capture.gfxr` (gfxreconstruct {}) records umbra's Vulkan calls for the reduced case on {backend} (`VK_INSTANCE_LAYERS=VK_LAYER_LUNARG_gfxreconstruct GFXRECON_CAPTURE_FILE=capture.gfxr umbra render case.json --backend {backend}`, the run and its twins). The run renders offscreen and presents nothing, so the replay executes every command but has no frame to screenshot (gfxreconstruct 0.9.18 snapshots presented frames only): the pictures above are umbra's readback. `gfxrecon-convert capture.gfxr` lists the calls as JSON.",
        version("gfxreconstruct")
    );
    let replays = vec![Replay {
        backend: backend.to_string(),
        command: format!("{} gfxrecon-replay capture.gfxr", env_text(&env, out)),
        outcome: format!(
            "exit {}: {}",
            code.map_or("none".into(), |c| c.to_string()),
            text.lines().last().unwrap_or("")
        ),
    }];
    (Ok(how), replays)
}

/// A Debian package's version (apitrace has no version command).
fn version(package: &str) -> String {
    Command::new("dpkg-query")
        .args(["-W", "-f", "${Version}", package])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "version unknown".into())
}

/// umbra's diagnosis of the run, when an expectation names it (its reason).
fn diagnosis(
    all: &crate::judge::expectations::Expectations,
    run: &str,
    reduced: &Path,
) -> Option<String> {
    let case: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(reduced).ok()?).ok()?;
    all.find(run, &case)
        .or_else(|| all.find(run, &serde_json::Value::Null))
        .map(|e| format!("{} ({})", e.reason, e.source))
}

/// Every file under `dir`, relative, with its size, sorted.
fn list_files(dir: &Path) -> Vec<(String, u64)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if let Ok(meta) = e.metadata() {
                let rel = p.strip_prefix(dir).unwrap_or(&p).display().to_string();
                out.push((rel, meta.len()));
            }
        }
    }
    out.retain(|(name, _)| name != "README.md");
    out.sort();
    out
}

/// Writes one bundle file, atomically; a file that cannot be written (a full disk) ends the
/// command (could not run) and says which, rather than leave a bundle that silently lacks it.
fn save(path: &Path, text: &str) -> Result<(), Error> {
    crate::atomic_file::write(path, text.as_bytes())
        .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))
}

/// A command-line mistake: the message, then [`USAGE`] (could not run).
fn usage(msg: impl std::fmt::Display) -> Error {
    Error::new(format!("{msg}\nusage: {USAGE}"))
}
