//! A bless to review, from CI (issue 59): when a conformance run under `CI=true` changed
//! pictures (its `goldens.csv`), the changed points are blessed again into a scratch copy of
//! the golden directory, and the difference is left as a patch,
//! `target/umbra/bless-patch/bless.patch`, that `git apply` takes at the repository's root and
//! `git diff` then shows. CI itself still never writes a golden: the repository's own
//! directory is only read (copied), the bless writes into the copy, and the run's exit code is
//! the conformance run's, a changed picture on its blessed release still failing it. It is
//! what a reviewer would otherwise make by running `cargo xtask bless` at a desk, made where
//! the pictures were seen (Filament's renderdiff accepts goldens through a commit tag; a patch
//! keeps the review).
//!
//! How: the scratch is a git repository of its own (`target/umbra/bless-patch/repo/`), the
//! golden directory copied in and committed; `umbra conformance --bless --golden SCRATCH`
//! runs without `CI` in its environment (the bless refuses under CI: here it writes only the
//! copy), with the phase's own arguments (its `--mesa` among them) and, when the phase chose
//! no runs of its own, only the changed cases; then `git diff --cached --binary` of the
//! copy is the patch, its paths `golden/…` as in the repository.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// More changed cases than this are blessed again by one run of everything the phase ran.
const CASES_ONE_BY_ONE: usize = 8;

/// Where the patch and its scratch copy are made, under the target directory.
pub fn dir(root: &Path) -> PathBuf {
    crate::target_dir(root).join("umbra").join("bless-patch")
}

/// The case ids whose pictures `goldens.csv` (a run's changed pictures: its `test` column,
/// `BACKEND/CASE@POINT`) lists, sorted.
pub fn changed_cases(goldens_csv: &str) -> BTreeSet<String> {
    goldens_csv
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next())
        .filter(|t| !t.is_empty())
        .map(|t| {
            let head = t.split_once('@').map_or(t, |(h, _)| h);
            head.rsplit('/').next().unwrap_or(head).to_string()
        })
        .collect()
}

/// The value of option `name` in `args` (`--name V` or `--name=V`), the last one given.
fn option(args: &[String], names: &[&str]) -> Option<String> {
    let mut found = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        for n in names {
            if a == n {
                found = it.clone().next().cloned();
            } else if let Some(v) = a.strip_prefix(&format!("{n}=")) {
                found = Some(v.to_string());
            }
        }
    }
    found
}

/// `args` without options `names` and their values.
fn without(args: &[String], names: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip = false;
    for a in args {
        if skip {
            skip = false;
            continue;
        }
        if names.contains(&a.as_str()) {
            skip = true;
        } else if !names.iter().any(|n| a.starts_with(&format!("{n}="))) {
            out.push(a.clone());
        }
    }
    out
}

/// The umbra argument lists that bless the changed points again into `golden`, writing their
/// runs under `out`: one per changed case with `--filter CASE*` (a point id is `CASE` or
/// `CASE@POINT`; a longer case name that the glob also takes is run too, and blesses nothing
/// that did not change), or the phase's own arguments once when it chose its runs itself
/// (`--filter`, `--tier`, `--budget`) or more than [`CASES_ONE_BY_ONE`] cases changed.
pub fn bless_runs(
    phase_args: &[String],
    cases: &BTreeSet<String>,
    golden: &Path,
    out: &Path,
) -> Vec<Vec<String>> {
    let mut base = without(phase_args, &["--golden", "--out", "-o", "--bless"]);
    base.extend([
        "--bless".to_string(),
        "--golden".to_string(),
        golden.display().to_string(),
        "--out".to_string(),
        out.display().to_string(),
    ]);
    let chose = ["--filter", "--tier", "--budget"]
        .iter()
        .any(|n| option(phase_args, &[n]).is_some());
    if chose || cases.len() > CASES_ONE_BY_ONE {
        return vec![base];
    }
    cases
        .iter()
        .map(|c| {
            let mut a = base.clone();
            a.extend(["--filter".to_string(), format!("{c}*")]);
            a
        })
        .collect()
}

/// After a conformance phase run as `umbra conformance PHASE_ARGS` under CI: when it changed
/// pictures, the patch that blesses them (its path), made as the module says; `None` when
/// nothing changed. Says what it did on standard error; a patch that cannot be made is said
/// and costs nothing else (the phase's own result stands).
pub fn after_phase(root: &Path, phase_args: &[String]) -> Option<PathBuf> {
    let out = option(phase_args, &["--out", "-o"])
        .map(|o| root.join(o))
        // umbra's own default, relative to the workspace it runs in.
        .unwrap_or_else(|| root.join("target").join("umbra"));
    let csv = std::fs::read_to_string(out.join("latest").join("goldens.csv")).ok()?;
    let cases = changed_cases(&csv);
    if cases.is_empty() {
        return None;
    }
    let golden = option(phase_args, &["--golden"])
        .map(|g| root.join(g))
        .unwrap_or_else(|| root.join("golden"));
    match make(root, phase_args, &cases, &golden) {
        Ok(Some(patch)) => {
            eprintln!(
                "bless patch: {} changed case(s) blessed into a copy of {}; to review them: `git apply {}` at the repository's root, then `git diff --stat golden/` (CI wrote no golden)",
                cases.len(),
                golden.display(),
                patch.display()
            );
            Some(patch)
        }
        Ok(None) => {
            eprintln!(
                "bless patch: blessing the {} changed case(s) again changed no picture (a flake, or a change the judge holds legal on a release whose golden is not strict): no patch",
                cases.len()
            );
            None
        }
        Err(e) => {
            eprintln!("bless patch: not made: {e}");
            None
        }
    }
}

/// The scratch copy, the bless into it, and the patch: `Ok(None)` when the bless changed
/// nothing.
fn make(
    root: &Path,
    phase_args: &[String],
    cases: &BTreeSet<String>,
    golden: &Path,
) -> Result<Option<PathBuf>, String> {
    let dir = dir(root);
    let repo = dir.join("repo");
    if repo.exists() {
        std::fs::remove_dir_all(&repo).map_err(|e| format!("{}: {e}", repo.display()))?;
    }
    std::fs::create_dir_all(&repo).map_err(|e| format!("{}: {e}", repo.display()))?;
    crate::gpu_bundle::copy_tree(golden, &repo.join("golden"))?;
    git(&repo, &["init", "--quiet"])?;
    git(&repo, &["add", "--all"])?;
    git(
        &repo,
        &[
            "-c",
            "user.name=umbra",
            "-c",
            "user.email=umbra@localhost",
            "commit",
            "--quiet",
            "--no-verify",
            "-m",
            "goldens as CI read them",
        ],
    )?;
    for args in bless_runs(phase_args, cases, &repo.join("golden"), &dir.join("runs")) {
        let mut cmd = crate::umbra_command(&["conformance"], &args);
        // The bless refuses under CI, rightly: here it writes only the scratch copy.
        cmd.env_remove("CI");
        let code = crate::status(cmd);
        // A bless run exits 1 where a run still fails its judged checks; the pictures it
        // could bless are written all the same.
        if code == crate::COULD_NOT_RUN || code == 130 {
            return Err(format!(
                "umbra conformance {} could not run",
                args.join(" ")
            ));
        }
    }
    git(&repo, &["add", "--all"])?;
    let diff = git(&repo, &["diff", "--cached", "--binary"])?;
    if diff.is_empty() {
        return Ok(None);
    }
    let patch = dir.join("bless.patch");
    std::fs::write(&patch, &diff).map_err(|e| format!("{}: {e}", patch.display()))?;
    Ok(Some(patch))
}

/// `git ARGS` in `dir`: its standard output, or what it said on failure.
fn git(dir: &Path, args: &[&str]) -> Result<Vec<u8>, String> {
    let out = Command::new("git")
        .current_dir(dir)
        .args(args)
        .output()
        .map_err(|e| format!("git {}: {e}", args.join(" ")))?;
    if out.status.success() {
        Ok(out.stdout)
    } else {
        Err(format!(
            "git {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn changed_cases_are_the_case_ids_of_goldens_csv() {
        let csv = "test,status,golden,blessed_on,driver,pixels,max_step,new,legal_change\n\
                   gl33/llvmpipe/bevy-sun,Fail,changed,22.3.6,22.3.6,927,10,false,false\n\
                   ref/bevy-sun,Fail,changed,22.3.6,22.3.6,931,10,false,false\n\
                   gles3/zink/beyond-far@shadow.format=depth16,Pass,changed-legal,22.3.6,26.2.6,3,1,false,true\n";
        let got: Vec<String> = changed_cases(csv).into_iter().collect();
        assert_eq!(got, ["bevy-sun", "beyond-far"]);
        assert!(changed_cases("test,status\n").is_empty());
    }

    #[test]
    fn the_bless_runs_keep_the_phase_arguments_and_write_only_the_copy() {
        let cases: BTreeSet<String> = ["a".to_string(), "b".to_string()].into();
        let g = Path::new("/s/golden");
        let o = Path::new("/s/runs");
        let runs = bless_runs(
            &s(&["--mesa", "/m", "--golden=golden", "-o", "x"]),
            &cases,
            g,
            o,
        );
        assert_eq!(runs.len(), 2, "one per changed case");
        assert_eq!(
            runs[0],
            s(&[
                "--mesa",
                "/m",
                "--bless",
                "--golden",
                "/s/golden",
                "--out",
                "/s/runs",
                "--filter",
                "a*"
            ])
        );
        // A phase that chose its runs is run as it was, once.
        let runs = bless_runs(&s(&["--filter", "*bevy*"]), &cases, g, o);
        assert_eq!(runs.len(), 1);
        assert!(runs[0].starts_with(&s(&["--filter", "*bevy*", "--bless"])));
        // Many cases: everything once.
        let many: BTreeSet<String> = (0..20).map(|k| format!("c{k}")).collect();
        assert_eq!(bless_runs(&[], &many, g, o).len(), 1);
    }

    /// The patch's paths are the repository's: made in a scratch repository holding
    /// `golden/`, it applies with `git apply` in another tree holding the same `golden/`, and
    /// binary pictures come through whole.
    #[test]
    fn a_scratch_diff_applies_at_the_repository_root() {
        let base = std::env::temp_dir().join(format!("umbra-bless-patch-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let (scratch, user) = (base.join("scratch"), base.join("user"));
        for d in [&scratch, &user] {
            std::fs::create_dir_all(d.join("golden/ref")).expect("dir");
            std::fs::write(d.join("golden/ref/a.snap.png"), [0u8, 1, 2, 255]).expect("write");
        }
        git(&scratch, &["init", "--quiet"]).expect("init");
        git(&scratch, &["add", "--all"]).expect("add");
        git(
            &scratch,
            &[
                "-c",
                "user.name=t",
                "-c",
                "user.email=t@t",
                "commit",
                "--quiet",
                "-m",
                "b",
            ],
        )
        .expect("commit");
        std::fs::write(scratch.join("golden/ref/a.snap.png"), [9u8, 0, 7]).expect("write");
        std::fs::write(scratch.join("golden/ref/new.snap.png"), [1u8, 2]).expect("write");
        git(&scratch, &["add", "--all"]).expect("add");
        let diff = git(&scratch, &["diff", "--cached", "--binary"]).expect("diff");
        let patch = base.join("p.patch");
        std::fs::write(&patch, &diff).expect("write");
        git(&user, &["init", "--quiet"]).expect("init");
        git(&user, &["apply", &patch.display().to_string()]).expect("git apply takes it");
        assert_eq!(
            std::fs::read(user.join("golden/ref/a.snap.png")).expect("read"),
            [9u8, 0, 7]
        );
        assert_eq!(
            std::fs::read(user.join("golden/ref/new.snap.png")).expect("read"),
            [1u8, 2]
        );
        let _ = std::fs::remove_dir_all(&base);
    }
}
