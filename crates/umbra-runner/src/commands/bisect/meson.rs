//! The meson a Mesa tree asks for, and where to get it.
//!
//! Each Mesa release names its minimum meson in `project(..., meson_version : '>= X')`:
//! 0.53 for 22.3, 0.60 for 24.0, 1.1.0 from 24.1, 1.4.0 for 25.2 and 26.2
//! (`tests/fixtures/meson-options/SOURCES.md`). Debian 12's meson is 1.0.1, so a current
//! tree stops in `meson setup` with "Meson version is 1.0.1 but project requires >= 1.4.0".
//! umbra reads the requirement first ([`required`]), says it, and where the machine's meson
//! is older, brings a newer one into the work directory with pip ([`bring`]: a venv that
//! sees the system's site packages, so Mesa's mako and PyYAML from Debian still import)
//! rather than failing mid-bisection (ninja with it, where the machine has none). The
//! brought meson is kept, and found again ([`find`]) by the next step and the next
//! bisection in the same work directory.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A meson version, compared numerically part by part (`1.4.0` > `1.10` is false).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Version(pub Vec<u64>);

impl Version {
    /// The leading dotted numbers of `text` (`1.0.1`, `0.53`, `1.4.0rc2` → 1.4.0).
    pub fn parse(text: &str) -> Option<Version> {
        let parts: Vec<u64> = text
            .trim()
            .split('.')
            .map_while(|p| {
                let digits: String = p.chars().take_while(char::is_ascii_digit).collect();
                digits.parse().ok()
            })
            .collect();
        (!parts.is_empty()).then_some(Version(parts))
    }

    fn padded(&self) -> [u64; 4] {
        let mut out = [0; 4];
        for (o, p) in out.iter_mut().zip(&self.0) {
            *o = *p;
        }
        out
    }

    /// Whether this version is at least `min` (missing parts count as 0).
    pub fn at_least(&self, min: &Version) -> bool {
        self.padded() >= min.padded()
    }
}

impl std::fmt::Display for Version {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self.0.iter().map(u64::to_string).collect();
        f.write_str(&parts.join("."))
    }
}

/// The minimum meson a tree's top-level `meson.build` asks for (`meson_version : '>= 1.4.0'`).
pub fn required(meson_build: &str) -> Option<Version> {
    let at = meson_build.find("meson_version")?;
    let rest = &meson_build[at..];
    let open = rest.find('\'')?;
    let close = rest[open + 1..].find('\'')?;
    let spec = &rest[open + 1..open + 1 + close];
    Version::parse(spec.trim_start_matches(['>', '=', ' ']))
}

/// The version a meson executable says it is.
pub fn version_of(meson: &Path) -> Option<Version> {
    let out = Command::new(meson).arg("--version").output().ok()?;
    out.status
        .success()
        .then(|| Version::parse(&String::from_utf8_lossy(&out.stdout)))
        .flatten()
}

/// Where [`bring`] puts its meson: a venv in the work directory.
pub fn brought_dir(work: &Path) -> PathBuf {
    work.join("meson")
}

/// A meson at least `min`: the brought one in `work` if it is new enough, else the
/// system's if it is; `Err` says what the machine has (none, or too old).
pub fn find(work: &Path, min: Option<&Version>) -> Result<PathBuf, String> {
    let enough = |v: &Option<Version>| match (v, min) {
        (Some(v), Some(m)) => v.at_least(m),
        (Some(_), None) => true,
        (None, _) => false,
    };
    let brought = brought_dir(work).join("bin/meson");
    if brought.is_file() && enough(&version_of(&brought)) {
        return Ok(brought);
    }
    let system = PathBuf::from("meson");
    let have = version_of(&system);
    if enough(&have) {
        return Ok(system);
    }
    Err(match (have, min) {
        (None, _) => "this machine has no meson".to_string(),
        (Some(v), Some(m)) => format!("this machine's meson is {v}, the tree asks for >= {m}"),
        (Some(v), None) => format!("this machine's meson is {v}"),
    })
}

/// Brings a meson at least `min` into `work` (a venv with the system's site packages, and
/// `pip install meson>=MIN` in it); returns its path. `Err` says what failed and the fix.
pub fn bring(work: &Path, min: &Version) -> Result<PathBuf, String> {
    let dir = brought_dir(work);
    let run = |cmd: &mut Command, what: &str| -> Result<(), String> {
        let out = cmd
            .output()
            .map_err(|e| format!("cannot run {what}: {e}"))?;
        if out.status.success() {
            Ok(())
        } else {
            Err(format!(
                "{what} failed: {}",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            ))
        }
    };
    let fix = "fix: install a meson >= the tree's (pip install --user 'meson>=VERSION', or your distribution's backports) and put it first on PATH";
    run(
        Command::new("python3")
            .args(["-m", "venv", "--system-site-packages"])
            .arg(&dir),
        "python3 -m venv",
    )
    .map_err(|e| format!("{e}; {fix}"))?;
    // meson's backend too, where the machine has none.
    let ninja = Command::new("ninja")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let mut pip = Command::new(dir.join("bin/pip"));
    pip.args(["install", "--quiet", "--disable-pip-version-check"])
        .arg(format!("meson>={min}"));
    if !ninja {
        pip.arg("ninja");
    }
    run(&mut pip, "pip install meson").map_err(|e| format!("{e}; {fix}"))?;
    let meson = dir.join("bin/meson");
    match version_of(&meson) {
        Some(v) if v.at_least(min) => Ok(meson),
        v => Err(format!(
            "pip brought meson {} into {}, not >= {min}; {fix}",
            v.map_or("(none)".into(), |v| v.to_string()),
            dir.display()
        )),
    }
}

/// A command of `program` (meson, ninja) that finds a brought meson's own tools first: its
/// venv's `bin` leads `PATH` when `meson` is the brought one.
pub fn command(program: &str, meson: &Path) -> Command {
    let bin = meson.parent().filter(|d| d.join("python3").exists());
    let mut cmd = match bin {
        Some(b) if b.join(program).is_file() => Command::new(b.join(program)),
        _ => Command::new(program),
    };
    if let Some(b) = bin {
        let path = std::env::var_os("PATH").unwrap_or_default();
        let mut dirs = vec![b.to_path_buf()];
        dirs.extend(std::env::split_paths(&path));
        if let Ok(joined) = std::env::join_paths(dirs) {
            cmd.env("PATH", joined);
        }
    }
    cmd
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_compare_by_number_and_requirements_are_read_from_project() {
        let v = |s| Version::parse(s).expect("version");
        assert!(v("1.0.1").at_least(&v("0.53")));
        assert!(!v("1.0.1").at_least(&v("1.1.0")));
        assert!(v("1.10.0").at_least(&v("1.4")));
        assert!(v("1.4.0rc2").at_least(&v("1.4.0")));
        assert_eq!(v("1.4").to_string(), "1.4");
        let build = "project(\n  'mesa',\n  ['c', 'cpp'],\n  version : files('VERSION'),\n  license : 'MIT',\n  meson_version : '>= 1.4.0',\n  default_options : [...]\n)\n";
        assert_eq!(required(build), Some(v("1.4.0")));
        assert_eq!(required("project('x')"), None);
    }
}
