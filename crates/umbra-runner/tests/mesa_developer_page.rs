//! docs/mesa-developer.md stays true: every `umbra` and `cargo xtask` command in its shell
//! blocks is one umbra's command line takes (xtask's own commands, `fetch-mesa` and
//! `mesa-ci`, are xtask's: their flags are checked against its source), each names a test
//! that runs it in the page's table, and the recorded tier (`tiers/`) covers every fault ×
//! backend pair it was chosen from and runs as chosen, kept with the run.

mod common;

use common::{scratch, text};
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The command lines of the page's ```sh blocks.
fn commands(page: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in page.lines() {
        if line.starts_with("```") {
            inside = line == "```sh";
            continue;
        }
        if inside && !line.trim().is_empty() {
            out.push(line.trim().to_string());
        }
    }
    out
}

/// A shell line's words (single quotes kept together, as the shell would).
fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '\'' => quoted = !quoted,
            ' ' if !quoted => {
                if !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
            }
            c => word.push(c),
        }
    }
    if !word.is_empty() {
        out.push(word);
    }
    out
}

#[test]
fn every_command_on_the_page_parses_and_names_the_test_that_runs_it() {
    let page = std::fs::read_to_string(repo().join("docs/mesa-developer.md")).expect("the page");
    let xtask = std::fs::read_to_string(repo().join("xtask/src/main.rs")).expect("xtask");
    let tests: String = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests"))
        .expect("tests")
        .filter_map(|e| std::fs::read_to_string(e.ok()?.path()).ok())
        .collect();
    let lines = commands(&page);
    assert!(lines.len() >= 10, "{lines:?}");
    for line in &lines {
        for part in line.split(" && ") {
            let w = words(part);
            let argv: Vec<String> = match w.first().map(String::as_str) {
                Some("umbra") => w.clone(),
                Some("cargo") if w.get(1).is_some_and(|x| x == "xtask") => {
                    std::iter::once("umbra".to_string())
                        .chain(w[2..].iter().cloned())
                        .collect()
                }
                // Mesa's own build tools: their options are what --configure-only printed.
                Some("ninja" | "meson") => continue,
                _ => panic!("a command the page runs that this test does not know: {part}"),
            };
            let sub = argv[1].as_str();
            if matches!(sub, "mesa-ci" | "fetch-mesa") {
                // xtask's own: each flag is declared in its command line.
                for f in argv.iter().filter(|a| a.starts_with("--")) {
                    assert!(
                        xtask.contains(&format!(".long(\"{}\")", f.trim_start_matches("--"))),
                        "{part}: xtask {sub} has no {f}"
                    );
                }
            } else {
                umbra_runner::cli::command()
                    .try_get_matches_from(&argv)
                    .unwrap_or_else(|e| panic!("{part}: {e}"));
            }
            // The table names a test for the command, and that test exists.
            let row = page
                .lines()
                .filter(|l| l.starts_with("| `"))
                .find(|l| {
                    let cmd = l.split('`').nth(1).unwrap_or("");
                    let head: Vec<&str> = cmd.split(' ').filter(|x| *x != "…").collect();
                    let head = head.join(" ");
                    part.starts_with(head.split(" --").next().unwrap_or(&head))
                })
                .unwrap_or_else(|| panic!("{part}: no row of the table names its test"));
            let named = row.split('`').nth(3).unwrap_or("");
            let test = named.rsplit("::").next().unwrap_or(named);
            if !named.starts_with("xtask ") {
                assert!(
                    tests.contains(&format!("fn {test}(")),
                    "{row}: no test {test}"
                );
            }
        }
    }
}

/// The recorded tier, chosen for the pre-merge budget, covers every pair the self-test's
/// catch matrix holds; a budgeted conformance run makes only the tier's runs and keeps the
/// tier file with the run.
#[test]
fn the_recorded_tier_covers_every_pair_and_runs_as_chosen() {
    let out = scratch("tier");
    let file = out.join("premerge.json");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .current_dir(repo())
        .args(["tier", "--budget", "premerge", "--out"])
        .arg(&file)
        .output()
        .expect("umbra tier");
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let tier: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).expect("tier file")).expect("json");
    let pairs = tier["pairs"].as_u64().unwrap_or(0);
    assert!(pairs >= 400, "{tier}");
    assert_eq!(tier["covered"][0].as_u64(), Some(pairs), "{t}");
    assert!(
        tier["uncovered"].as_array().is_some_and(Vec::is_empty),
        "{t}"
    );
    assert!(
        tier["expected_wall_s"].as_f64().is_some_and(|w| w <= 300.0),
        "{t}"
    );
    assert!(
        t.contains("480 of 480") || t.contains(&format!("{pairs} of {pairs}")),
        "{t}"
    );
    // A file that is not a tier is never written over.
    let foreign = out.join("notes.json");
    std::fs::write(&foreign, "my notes").expect("write");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .current_dir(repo())
        .args(["tier", "--budget", "smoke", "--out"])
        .arg(&foreign)
        .output()
        .expect("umbra tier");
    assert_eq!(o.status.code(), Some(125), "{}", text(&o));
    assert!(text(&o).contains("is not a tier file"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&foreign).expect("kept"), "my notes");
    // The same inputs, the same tier.
    let again = out.join("again.json");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .current_dir(repo())
        .args(["tier", "--budget", "premerge", "--out"])
        .arg(&again)
        .output()
        .expect("umbra tier");
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(
        std::fs::read(&file).expect("tier"),
        std::fs::read(&again).expect("tier again")
    );
    // A budgeted run of one case: its runs are the tier's, and the tier is kept.
    let run = out.join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .current_dir(repo())
        .args([
            "conformance",
            "--budget",
            "premerge",
            "--backend",
            "gl33/llvmpipe",
            "--filter",
            "l-occluder*",
            "--golden",
            "none",
            "--out",
        ])
        .arg(&run)
        .output()
        .expect("umbra conformance");
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("tier (by catches):"), "{t}");
    let kept: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(run.join("latest/tier.json")).expect("the tier kept with the run"),
    )
    .expect("json");
    let runs: Vec<&str> = kept["runs"]
        .as_array()
        .map(|a| a.iter().filter_map(|r| r.as_str()).collect())
        .unwrap_or_default();
    let results = std::fs::read_to_string(run.join("latest/results.csv")).expect("results.csv");
    for line in results.lines() {
        let name = line.rsplitn(3, ',').nth(2).unwrap_or("").trim_matches('"');
        assert!(runs.contains(&name), "{name} is not a run of the tier");
    }
}
