//! `cargo xtask mesa-ci --driver DRIVER --out DIR [--fraction N] [--budget D] [--bundle] [--run]`: what a Mesa
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
//! `--budget DURATION` keeps only the tests of a pre-merge tier (`umbra tier`, chosen by what
//! they catch; the tier file is kept beside the suite). `--bundle` makes DIR self-contained
//! for a CI job: umbra, its cases, expectations and tiers beside the suite, whose paths
//! (`@BUNDLE@`, the Mesa install `@MESA@`, the results `@RESULTS@`) `DIR/run.sh` fills in
//! where the job runs it; run.sh then runs deqp-runner and writes JUnit (Mesa's pipeline:
//! docs/ci/mesa/).
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
    /// `--budget`: a tier's tests only.
    pub budget: Option<String>,
    /// `--bundle`: a self-contained directory for a CI job.
    pub bundle: bool,
}

/// Runs the command.
pub fn main(o: &Options, root: &Path) -> i32 {
    // A bundle replaces its cases, expectations and tiers: only in a directory umbra made
    // (or an empty one), never one that holds a user's files (`--out .` in a checkout).
    if o.bundle {
        if let Err(e) = umbra_owned::fresh(&o.out, "cargo xtask mesa-ci --bundle") {
            eprintln!("error: --out: {e}");
            return 125;
        }
    }
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
    let umbra = crate::target_dir(root).join("debug/umbra");
    let backends = backends(&o.driver);
    let listed = match list(&umbra, root, &backends) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: {e}");
            return 125;
        }
    };
    let listed = match &o.budget {
        None => listed,
        Some(b) => match tier_of(&umbra, root, &out, &o.driver, b, listed) {
            Ok(l) => l,
            Err(e) => {
                eprintln!("error: {e}");
                return 125;
            }
        },
    };
    let place = if o.bundle {
        match bundle(&umbra, root, &out) {
            Ok(()) => Place::Bundle,
            Err(e) => {
                eprintln!("error: --bundle: {e}");
                return 125;
            }
        }
    } else {
        Place::Here
    };
    if let Err(e) = write_files(&o.driver, &out, root, &umbra, &listed, place) {
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

/// The tests of the tier `umbra tier --budget BUDGET` chooses (its file kept in `out`).
fn tier_of(
    umbra: &Path,
    root: &Path,
    out: &Path,
    driver: &str,
    budget: &str,
    listed: Vec<Listed>,
) -> Result<Vec<Listed>, String> {
    let file = out.join(format!("umbra-{driver}-tier.json"));
    let status = Command::new(umbra)
        .current_dir(root)
        .args(["tier", "--budget", budget, "--out"])
        .arg(&file)
        .status()
        .map_err(|e| format!("cannot run umbra tier: {e}"))?;
    if !status.success() {
        return Err(format!("umbra tier --budget {budget} failed ({status})"));
    }
    let text = std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
    let tier: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    let runs: std::collections::BTreeSet<&str> = tier["runs"]
        .as_array()
        .map(|a| a.iter().filter_map(|r| r.as_str()).collect())
        .unwrap_or_default();
    let kept: Vec<Listed> = listed
        .into_iter()
        .filter(|t| runs.contains(t.run.as_str()))
        .collect();
    println!(
        "mesa-ci: the {budget} tier keeps {} of {driver}'s tests ({})",
        kept.len(),
        file.display()
    );
    Ok(kept)
}

/// Where the suite's paths point.
#[derive(Clone, Copy, PartialEq)]
enum Place {
    /// This checkout (absolute paths): for a run on this machine.
    Here,
    /// The bundle, wherever a job unpacks it: `@BUNDLE@`, which run.sh fills in.
    Bundle,
}

/// The script a CI job runs from the bundle: fills in its paths, runs the suite with
/// deqp-runner on the job's Mesa install, and writes JUnit.
const RUN_SH: &str = r#"#!/bin/sh
# umbra's suite under deqp-runner, in a CI job (made by `cargo xtask mesa-ci --bundle`).
# Usage: run.sh [RESULTS_DIR] ; environment: MESA_INSTALL (default: install, the job's
# freshly built Mesa), DEQP_RUNNER (default: deqp-runner on PATH), DEQP_FRACTION (default 1).
set -eu
B=$(cd "$(dirname "$0")" && pwd)
RESULTS=${1:-results}
MESA=$(cd "${MESA_INSTALL:-install}" && pwd)
RUNNER=${DEQP_RUNNER:-deqp-runner}
mkdir -p "$RESULTS"
for f in "$B"/*.toml.in; do
  sed -e "s|@BUNDLE@|$B|g" -e "s|@MESA@|$MESA|g" -e "s|@RESULTS@|$(cd "$RESULTS" && pwd)|g" "$f" > "${f%.in}"
done
status=0
"$RUNNER" suite --suite "$B"/umbra-*.toml --output "$RESULTS" --fraction "${DEQP_FRACTION:-1}" || status=$?
"$RUNNER" junit --testsuite umbra --results "$RESULTS/failures.csv" --output "$RESULTS/junit.xml" || true
exit $status
"#;

/// `--bundle`: umbra, the cases, expectations and tiers, and run.sh, into `out`.
fn bundle(umbra: &Path, root: &Path, out: &Path) -> Result<(), String> {
    std::fs::copy(umbra, out.join("umbra"))
        .map_err(|e| format!("cannot copy {}: {e}", umbra.display()))?;
    for d in ["cases", "expectations", "tiers"] {
        let _ = std::fs::remove_dir_all(out.join(d));
        crate::gpu_bundle::copy_tree(&root.join(d), &out.join(d))?;
    }
    let script = out.join("run.sh");
    std::fs::write(&script, RUN_SH).map_err(|e| format!("{}: {e}", script.display()))?;
    crate::gpu_bundle::executable(&script)
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
    place: Place,
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
    // In a bundle, every path is the bundle's, filled in by run.sh where the job runs it.
    let here = |p: &Path| match place {
        Place::Here => p.display().to_string(),
        Place::Bundle => p.strip_prefix(out).map_or_else(
            |_| p.display().to_string(),
            |rel| format!("@BUNDLE@/{}", rel.display()),
        ),
    };
    let q = |p: &Path| format!("{:?}", here(p));
    let (umbra_at, cases, expectations, pictures, cache, mesa) = match place {
        Place::Here => (
            umbra.to_path_buf(),
            root.join("cases").display().to_string(),
            root.join("expectations").display().to_string(),
            out.join("results/umbra-pictures").display().to_string(),
            crate::target_dir(root)
                .join("umbra/cache/judge")
                .display()
                .to_string(),
            String::new(),
        ),
        Place::Bundle => (
            out.join("umbra"),
            "@BUNDLE@/cases".into(),
            "@BUNDLE@/expectations".into(),
            "@RESULTS@/umbra-pictures".into(),
            "@BUNDLE@/judge-cache".into(),
            ", \"--umbra-mesa=@MESA@\"".into(),
        ),
    };
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
         deqp_args = [\"deqp\", \"--cases={cases}\", \"--umbra-expectations={expectations}\", \"--umbra-pictures={pictures}\", \"--umbra-judge-cache={cache}\"{mesa}]\n",
        umbra = q(&umbra_at),
        caselist = q(&file("-caselist.txt")),
        fails = q(&file("-fails.txt")),
        skips = q(&file("-skips.txt")),
        flakes = q(&file("-flakes.txt")),
    );
    match place {
        Place::Here => std::fs::write(file(".toml"), toml),
        Place::Bundle => std::fs::write(file(".toml.in"), toml),
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A bundle replaces its cases and expectations: never in a directory of the user's.
    #[test]
    fn a_bundle_is_never_written_into_a_users_directory() {
        let dir = std::env::temp_dir().join(format!("umbra-mesa-ci-own-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("cases")).expect("mkdir");
        std::fs::write(dir.join("cases/mine.json"), "{}").expect("write");
        let o = Options {
            driver: "llvmpipe".into(),
            out: dir.clone(),
            fraction: None,
            run: false,
            budget: None,
            bundle: true,
        };
        assert_eq!(main(&o, Path::new("/nowhere")), 125);
        assert!(dir.join("cases/mine.json").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The bundle's suite names no path of this machine: run.sh fills in the bundle's, the
    /// job's Mesa install and the results directory where the job runs it, then hands the
    /// suite to deqp-runner (here a stand-in that keeps what it was given) and writes JUnit.
    #[test]
    fn the_bundle_suite_has_its_paths_filled_in_where_it_runs() {
        let tmp = std::env::temp_dir().join(format!("umbra-mesa-ci-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        let out = tmp.join("bundle");
        std::fs::create_dir_all(&out).expect("mkdir");
        let listed = vec![Listed {
            name: "umbra.gl33.llvmpipe.l-occluder.0".into(),
            run: "gl33/llvmpipe/l-occluder".into(),
            expected: "Pass".into(),
        }];
        write_files(
            "llvmpipe",
            &out,
            Path::new("/nowhere"),
            &out.join("umbra"),
            &listed,
            Place::Bundle,
        )
        .expect("write");
        let template =
            std::fs::read_to_string(out.join("umbra-llvmpipe.toml.in")).expect("template");
        assert!(
            !template.contains("/nowhere") && template.contains("--umbra-mesa=@MESA@"),
            "{template}"
        );
        std::fs::write(out.join("run.sh"), RUN_SH).expect("run.sh");
        let runner = tmp.join("deqp-runner");
        std::fs::write(
            &runner,
            "#!/bin/sh\necho \"$@\" >> \"$(dirname \"$0\")/calls\"\nif [ \"$1\" = suite ]; then cp \"$3\" \"$(dirname \"$0\")/suite.toml\"; fi\n",
        )
        .expect("runner");
        crate::gpu_bundle::executable(&runner).expect("chmod");
        let job = tmp.join("job");
        std::fs::create_dir_all(job.join("install")).expect("mkdir");
        let status = Command::new("sh")
            .arg(out.join("run.sh"))
            .arg("results")
            .current_dir(&job)
            .env("DEQP_RUNNER", &runner)
            .env("MESA_INSTALL", "install")
            .status()
            .expect("run.sh");
        assert!(status.success());
        let suite =
            std::fs::read_to_string(tmp.join("suite.toml")).expect("the suite deqp-runner got");
        assert!(!suite.contains('@'), "{suite}");
        assert!(
            suite.contains(&format!("--umbra-mesa={}", job.join("install").display())),
            "{suite}"
        );
        assert!(
            suite.contains(&format!("deqp = \"{}\"", out.join("umbra").display())),
            "{suite}"
        );
        assert!(
            suite.contains(&format!("{}/umbra-pictures", job.join("results").display())),
            "{suite}"
        );
        let calls = std::fs::read_to_string(tmp.join("calls")).expect("calls");
        assert!(
            calls.contains("suite --suite") && calls.contains("--fraction 1"),
            "{calls}"
        );
        assert!(
            calls.contains("junit --testsuite umbra --results results/failures.csv"),
            "{calls}"
        );
        let _ = std::fs::remove_dir_all(&tmp);
    }
}
