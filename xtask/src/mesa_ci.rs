//! `cargo xtask mesa-ci --driver DRIVER --out DIR [--fraction N] [--run]`: what a Mesa
//! driver's `ci/` directory would hold to run umbra under deqp-runner, beside its dEQP suites
//! (umbra speaks dEQP's protocol: `umbra deqp`, crates/umbra-runner/src/commands/deqp.rs):
//!
//! - `umbra-DRIVER.toml`: the suite entry (`[[deqp]]`: the umbra binary, its caselist, the
//!   arguments that make it umbra's dEQP mode, the baseline, skips and flakes);
//! - `umbra-DRIVER-caselist.txt`: every test of the driver's backends (GL 3.3, GLES 3,
//!   GLES 2; `wgpu-vk/lavapipe` for lavapipe), named `umbra.API.DRIVER.CASE.K`;
//! - `umbra-DRIVER-fails.txt`, `-flakes.txt`, `-skips.txt` in deqp-runner's formats,
//!   generated from umbra's expectations for the driver this machine has (its Mesa version
//!   selects the `@applies` lines): a name-pinned expected failure, crash or timeout is a
//!   baseline line; an expected skip is a skip (anchored regex). Each line's comment names
//!   the run. An expectation by cause (`@when`, a modelled deviation) fails only where its
//!   cause shows, which no list can say: `umbra deqp` judges such a test again under the
//!   cause and reports a failure it explains as QualityWarning (deqp-runner's Warn), any
//!   other as Fail. What deqp-runner cannot express (which checks fail, on how many pixels,
//!   for a name-pinned expectation) stays in umbra's own check, `umbra conformance`.
//!
//! With `--run` it also installs deqp-runner 0.24.0 with cargo when none is on PATH (or in
//! `DEQP_RUNNER`), runs the suite (`deqp-runner suite`, `--fraction N`), and writes JUnit
//! from its failures.csv: `DIR/results` then holds results.csv, failures.csv, junit.xml and
//! `umbra-pictures/TEST/` (expected, actual and error pictures of each failing test).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The options, as the command line gave them.
pub struct Options {
    pub driver: String,
    pub out: PathBuf,
    pub fraction: Option<u32>,
    pub run: bool,
}

/// Runs the command.
pub fn main(o: &Options, root: &Path) -> i32 {
    if let Err(e) = std::fs::create_dir_all(&o.out) {
        eprintln!("error: --out {}: {e}", o.out.display());
        return 125;
    }
    let out = std::fs::canonicalize(&o.out).unwrap_or(o.out.clone());
    let build = crate::status(crate::cargo_args(&[
        "build",
        "--quiet",
        "--package",
        "umbra-runner",
        "--bin",
        "umbra",
    ]));
    if build != 0 {
        return build;
    }
    let umbra = target_dir(root).join("debug/umbra");
    let backends = backends(&o.driver);
    let listed = match list(&umbra, root, &backends) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: {e}");
            return 125;
        }
    };
    if let Err(e) = write_files(&o.driver, &out, root, &umbra, &listed) {
        eprintln!("error: cannot write under {}: {e}", out.display());
        return 125;
    }
    let count = |what: &str| listed.iter().filter(|t| t.expected == what).count();
    println!(
        "mesa-ci: {} tests of {} in {}: {} expected failures, {} expected by cause (reported QualityWarning when the cause explains them), {} skips (umbra's expectations for this machine's {})",
        listed.len(),
        backends.join(", "),
        out.display(),
        count("Fail") + count("Crash") + count("Timeout"),
        count("Cause"),
        count("Skip"),
        o.driver
    );
    if !o.run {
        return 0;
    }
    run_suite(o, &out)
}

/// The backends a driver's umbra suite runs.
fn backends(driver: &str) -> Vec<String> {
    match driver {
        "lavapipe" => vec!["wgpu-vk/lavapipe".into()],
        d => ["gl33", "gles3", "gles2"]
            .iter()
            .map(|api| format!("{api}/{d}"))
            .collect(),
    }
}

fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from)
}

/// One test as `umbra deqp --list` gives it.
struct Listed {
    name: String,
    run: String,
    expected: String,
}

fn list(umbra: &Path, root: &Path, backends: &[String]) -> Result<Vec<Listed>, String> {
    let mut cmd = Command::new(umbra);
    cmd.current_dir(root).args(["deqp", "--list"]);
    for b in backends {
        cmd.arg(format!("--backend={b}"));
    }
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {}: {e}", umbra.display()))?;
    if !out.status.success() {
        return Err(format!(
            "`umbra deqp --list` failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let mut f = l.split('\t');
            Some(Listed {
                name: f.next()?.to_string(),
                run: f.next()?.to_string(),
                expected: f.next()?.to_string(),
            })
        })
        .collect())
}

/// An anchored regex matching exactly `name` (deqp-runner's skips and flakes are regexes).
fn exact(name: &str) -> String {
    format!("^{}$", name.replace('.', "\\."))
}

fn write_files(
    driver: &str,
    out: &Path,
    root: &Path,
    umbra: &Path,
    listed: &[Listed],
) -> std::io::Result<()> {
    let file = |suffix: &str| out.join(format!("umbra-{driver}{suffix}"));
    let header = |what: &str| {
        format!(
            "# umbra's {what} for {driver}, in deqp-runner's format, generated by `cargo xtask mesa-ci --driver {driver}`\n\
             # from umbra's expectations (expectations/*.txt) for this machine's {driver}. Each test's\n\
             # run name follows it as a comment; `umbra conformance` on the driver checks the full\n\
             # expectation (which checks fail, on how many pixels), which this file cannot say.\n"
        )
    };
    let names: String = listed.iter().map(|t| format!("{}\n", t.name)).collect();
    std::fs::write(file("-caselist.txt"), names)?;
    let mut fails = header("expected failures");
    let causes = listed.iter().filter(|t| t.expected == "Cause").count();
    let mut flakes = header("flakes");
    flakes.push_str("# umbra reruns nothing on its own: a test whose answer changes between runs is a\n# driver's flake to list here by hand.\n");
    let mut skips = header("skips");
    for t in listed {
        match t.expected.as_str() {
            "Fail" | "Crash" | "Timeout" => {
                fails.push_str(&format!("# {}\n{},{}\n", t.run, t.name, t.expected))
            }
            "Skip" => skips.push_str(&format!("# {}\n{}\n", t.run, exact(&t.name))),
            _ => {}
        }
    }
    fails.push_str(&format!(
        "# {causes} tests carry an expectation by cause (an `@when` line or a modelled driver\n\
         # deviation, expectations/*.txt): `umbra deqp` judges them again under it and reports a\n\
         # failure the cause explains as QualityWarning (deqp-runner's Warn, a success), any\n\
         # other failure as Fail. They need no line here.\n"
    ));
    std::fs::write(file("-fails.txt"), fails)?;
    std::fs::write(file("-flakes.txt"), flakes)?;
    std::fs::write(file("-skips.txt"), skips)?;
    let q = |p: &Path| format!("{:?}", p.display().to_string());
    let toml = format!(
        "# umbra's shadow-mapping conformance as a deqp-runner suite entry for {driver}\n\
         # (generated by `cargo xtask mesa-ci --driver {driver}`). umbra speaks dEQP's protocol\n\
         # as `umbra deqp`; every test runs in a worker process of its own backend.\n\
         [[deqp]]\n\
         deqp = {umbra}\n\
         caselists = [{caselist}]\n\
         baseline = {fails}\n\
         skips = [{skips}]\n\
         flakes = [{flakes}]\n\
         timeout = 300.0\n\
         deqp_args = [\"deqp\", \"--cases={cases}\", \"--umbra-expectations={expectations}\", \"--umbra-pictures={pictures}\", \"--umbra-judge-cache={cache}\"]\n",
        umbra = q(umbra),
        caselist = q(&file("-caselist.txt")),
        fails = q(&file("-fails.txt")),
        skips = q(&file("-skips.txt")),
        flakes = q(&file("-flakes.txt")),
        cases = root.join("cases").display(),
        expectations = root.join("expectations").display(),
        pictures = out.join("results/umbra-pictures").display(),
        cache = target_dir(root).join("umbra/cache/judge").display(),
    );
    std::fs::write(file(".toml"), toml)
}

/// deqp-runner: `DEQP_RUNNER`, else on PATH, else in cargo's bin directory, else installed
/// there with `cargo install deqp-runner --version 0.24.0`.
fn deqp_runner() -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("DEQP_RUNNER") {
        return Ok(PathBuf::from(p));
    }
    let works = |p: &Path| {
        Command::new(p)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let cargo_bin = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")))
        .unwrap_or_default()
        .join("bin/deqp-runner");
    for p in [PathBuf::from("deqp-runner"), cargo_bin.clone()] {
        if works(&p) {
            return Ok(p);
        }
    }
    println!("mesa-ci: installing deqp-runner 0.24.0 (cargo install deqp-runner --version 0.24.0)");
    let code = crate::status(crate::cargo_args(&[
        "install",
        "deqp-runner",
        "--version",
        "0.24.0",
        "--locked",
    ]));
    if code == 0 && works(&cargo_bin) {
        Ok(cargo_bin)
    } else {
        Err("cannot install deqp-runner 0.24.0 with cargo (exit {code}); install it and set DEQP_RUNNER=PATH".replace("{code}", &code.to_string()))
    }
}

/// Runs the suite under deqp-runner and writes JUnit from its failures.
fn run_suite(o: &Options, out: &Path) -> i32 {
    let runner = match deqp_runner() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 125;
        }
    };
    let results = out.join("results");
    // deqp-runner's results replace the last run's, and only those umbra made.
    if let Err(e) = umbra_owned::fresh(&results, "cargo xtask mesa-ci --run") {
        eprintln!("error: {e}");
        return 125;
    }
    let mut cmd = Command::new(&runner);
    cmd.arg("suite")
        .arg("--suite")
        .arg(out.join(format!("umbra-{}.toml", o.driver)))
        .arg("--output")
        .arg(&results);
    if let Some(n) = o.fraction {
        cmd.args(["--fraction", &n.to_string()]);
    }
    println!("mesa-ci: {cmd:?}");
    let code = crate::status(cmd);
    let junit = crate::status({
        let mut j = Command::new(&runner);
        j.arg("junit")
            .args(["--testsuite", "umbra"])
            .arg("--results")
            .arg(results.join("failures.csv"))
            .arg("--output")
            .arg(results.join("junit.xml"));
        j
    });
    let lines = std::fs::read_to_string(results.join("results.csv"))
        .map(|t| t.lines().count())
        .unwrap_or(0);
    println!(
        "mesa-ci: deqp-runner exit {code}; {} holds results.csv ({lines} lines), failures.csv, junit.xml (exit {junit}) and umbra-pictures/ (each failing test's pictures)",
        results.display()
    );
    code
}
