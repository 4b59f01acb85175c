//! `cargo xtask gpu-bundle [--out DIR] [--profile bundle|dev]`: a self-contained folder that
//! runs umbra's catalogue on a machine with a GPU and nothing of umbra's: no Rust, no
//! checkout, no Mesa. It holds
//!
//! - `umbra`: a release build without debug information or symbols (cargo profile `bundle`);
//! - `cases/` and `expectations/`, as in the checkout;
//! - `run.sh` ([`SCRIPT`]): unpacks GL/Vulkan loader packages put beside it when the machine
//!   has none, points the loaders at NVIDIA's files where a container keeps them apart, lists
//!   the machine's backends and runs `umbra conformance --backend hw --golden none` (every
//!   hardware EGL device and wgpu adapter, judged by the specs: a GPU umbra has never seen has
//!   no goldens), then copies report.json, results.csv and drivers.txt (with failures.csv,
//!   junit.xml and the backends found) into one folder;
//! - `README.md`, the three commands a person needs.
//!
//! It must fit in [`LIMIT`] (what a device machine's call carries beside other work); the
//! build is refused when it does not. `--profile dev` bundles the debug build instead (for
//! the test of the script, which needs no release build; larger than the limit, and said so).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The largest bundle, bytes (48 MiB).
pub const LIMIT: u64 = 48 << 20;

/// The script the bundle runs (`run.sh`).
pub const SCRIPT: &str = include_str!("gpu_bundle.sh");

const README: &str = "# umbra GPU bundle

umbra's shadow-mapping catalogue, judged by the GL and Vulkan specs alone, on every hardware
backend of the machine it runs on (`./umbra backends` lists them).

```sh
./run.sh                           # every hardware backend; results in results/
./run.sh --backend gl33/nvidia     # one backend (repeatable)
./run.sh --loaders DIR             # unpack the GL/Vulkan loaders' .deb files first (no root)
```

`results/` then holds report.json, results.csv (deqp-runner's `test,status,time`),
drivers.txt, failures.csv, junit.xml, backends.txt, cards.txt and cards.json (each backend's
behaviour card: what its driver chose inside the specs' freedom) and run.log;
`results/run/latest/` the
report.html with every picture. Exit status 0 when every run is as expected, 1 on a failure,
125 when nothing could run. Made by `cargo xtask gpu-bundle` in umbra's repository.
";

/// Runs the command; returns the exit code.
pub fn main(out: Option<PathBuf>, profile: &str, root: &Path) -> i32 {
    match bundle(out, profile, root) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: gpu-bundle: {e}");
            125
        }
    }
}

fn bundle(out: Option<PathBuf>, profile: &str, root: &Path) -> Result<(), String> {
    if !matches!(profile, "bundle" | "dev") {
        return Err(format!(
            "--profile {profile:?}: give bundle (the stripped release build) or dev (the debug build, for tests)"
        ));
    }
    let out = out.unwrap_or_else(|| root.join("target").join("umbra").join("gpu-bundle"));
    // Refused before the build: a directory umbra did not make is never replaced.
    umbra_owned::fresh(&out, WHAT).map_err(|e| e.to_string())?;
    let started = std::time::Instant::now();
    println!("gpu-bundle: building umbra (cargo build --profile {profile})");
    let built = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(root)
        .args([
            "build",
            "--quiet",
            "--profile",
            profile,
            "--package",
            "umbra-runner",
            "--bin",
            "umbra",
        ])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !built.success() {
        return Err("cargo build failed".into());
    }
    let dir = if profile == "dev" { "debug" } else { profile };
    assemble(&crate::target_dir(root).join(dir).join("umbra"), &out, root)?;
    let size = size_of(&out);
    println!(
        "gpu-bundle: {} ({:.1} MiB: umbra {:.1} MiB, cases and expectations {:.2} MiB) in {:.0} s\ngpu-bundle: run it with {}/run.sh (see its README.md)",
        out.display(),
        size as f64 / f64::from(1 << 20),
        std::fs::metadata(out.join("umbra")).map_or(0, |m| m.len()) as f64 / f64::from(1 << 20),
        (size_of(&out.join("cases")) + size_of(&out.join("expectations"))) as f64
            / f64::from(1 << 20),
        started.elapsed().as_secs_f64(),
        out.display()
    );
    if size > LIMIT {
        if profile == "dev" {
            println!(
                "gpu-bundle: note: the dev profile's bundle is over the {} MiB a bundle may take; it is for tests",
                LIMIT >> 20
            );
        } else {
            return Err(format!(
                "the bundle is {:.1} MiB, over its {} MiB limit",
                size as f64 / f64::from(1 << 20),
                LIMIT >> 20
            ));
        }
    }
    Ok(())
}

/// What made a bundle's directory, in its [`umbra_owned::MARKER`].
const WHAT: &str = "cargo xtask gpu-bundle";

/// Writes the bundle of `binary` into `out` (replacing it when umbra made it, refusing a
/// directory that holds anything else): the binary, the checkout's cases and expectations,
/// the script and the README.
fn assemble(binary: &Path, out: &Path, root: &Path) -> Result<(), String> {
    umbra_owned::fresh(out, WHAT).map_err(|e| e.to_string())?;
    let copy = |from: &Path, to: &Path| {
        std::fs::copy(from, to)
            .map(|_| ())
            .map_err(|e| format!("cannot copy {} to {}: {e}", from.display(), to.display()))
    };
    copy(binary, &out.join("umbra"))?;
    for d in ["cases", "expectations"] {
        copy_tree(&root.join(d), &out.join(d))?;
    }
    let script = out.join("run.sh");
    std::fs::write(&script, SCRIPT)
        .and_then(|()| std::fs::write(out.join("README.md"), README))
        .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    executable(&script)
}

pub(crate) fn copy_tree(from: &Path, to: &Path) -> Result<(), String> {
    std::fs::create_dir_all(to).map_err(|e| format!("cannot create {}: {e}", to.display()))?;
    let entries =
        std::fs::read_dir(from).map_err(|e| format!("cannot read {}: {e}", from.display()))?;
    for e in entries.filter_map(Result::ok) {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_tree(&src, &dst)?;
        } else {
            std::fs::copy(&src, &dst)
                .map_err(|err| format!("cannot copy {}: {err}", src.display()))?;
        }
    }
    Ok(())
}

fn size_of(p: &Path) -> u64 {
    match std::fs::symlink_metadata(p) {
        Ok(m) if m.is_dir() => std::fs::read_dir(p)
            .into_iter()
            .flatten()
            .filter_map(Result::ok)
            .map(|e| size_of(&e.path()))
            .sum(),
        Ok(m) => m.len(),
        Err(_) => 0,
    }
}

pub(crate) fn executable(p: &Path) -> Result<(), String> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755))
        .map_err(|e| format!("cannot make {} executable: {e}", p.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bundle of the debug binary (which `cargo test --workspace` has just built) runs its
    /// script end to end on Mesa's software EGL device (the device platform, as an NVIDIA GPU
    /// is reached) and leaves the reports in one folder.
    #[test]
    fn a_bundle_runs_its_script_and_leaves_the_reports() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .expect("workspace")
            .to_path_buf();
        let binary = crate::target_dir(&root).join("debug/umbra");
        assert!(
            binary.is_file(),
            "{} is not built: run cargo test --workspace",
            binary.display()
        );
        let out = std::env::temp_dir().join(format!("umbra-gpu-bundle-{}", std::process::id()));
        assemble(&binary, &out, &root).expect("the bundle is written");
        for f in [
            "umbra",
            "run.sh",
            "README.md",
            "cases/README.md",
            "expectations",
        ] {
            assert!(out.join(f).exists(), "{f} is missing from the bundle");
        }
        let results = out.join("results");
        let status = Command::new(out.join("run.sh"))
            .args(["--backend", "gl33/swrast", "--", "--filter", "l-occluder*"])
            .status()
            .expect("run.sh runs");
        assert_eq!(status.code(), Some(0), "run.sh's exit status");
        for f in ["report.json", "results.csv", "drivers.txt", "backends.txt"] {
            assert!(results.join(f).is_file(), "{f} is missing from results/");
        }
        let csv = std::fs::read_to_string(results.join("results.csv")).expect("results.csv");
        assert!(
            csv.lines()
                .any(|l| l.starts_with("gl33/swrast/l-occluder,Pass")),
            "{csv}"
        );
        let drivers = std::fs::read_to_string(results.join("drivers.txt")).expect("drivers");
        assert!(drivers.contains("gl33/swrast"), "{drivers}");
        let cards = std::fs::read_to_string(results.join("cards.json")).expect("cards.json");
        let cards: serde_json::Value = serde_json::from_str(&cards).expect("cards.json parses");
        assert!(cards.to_string().contains("gl33/swrast"), "{cards}");
        let _ = std::fs::remove_dir_all(&out);
    }
}
