//! The runner's layers, checked from its sources (as rust-analyzer's `tidy` checks its tree):
//! the leaves (`args`, `glob`, `atomic_file`, `run_dir`, `case_size`) know nothing above them, `judge` (one
//! point judged, goldens, expectations) knows neither the harness nor a command, `harness`
//! (workers, pool, registry, Mesa builds), `shards` and `repro` know no command, and no two
//! modules import each other in a circle. Every module has a layer ([`layer`]): a new one that
//! is not given one fails here. Imports are read through `crate::` and `super::` paths alike.
//! Reporting is its own crate (`umbra-report`) and never names the runner. A `use` that points
//! up a layer fails here with the file and the import.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (`harness::worker`) → the modules it names through `crate::`.
fn imports(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).expect("read src") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if !name.ends_with(".rs") || ["lib.rs", "main.rs"].contains(&name) {
                continue;
            }
            // `repro/mod.rs` is module `repro`: its code counts like any other's.
            let file = if name == "mod.rs" {
                p.parent().expect("a directory").to_path_buf()
            } else {
                p.with_extension("")
            };
            let module = file
                .strip_prefix(src)
                .expect("under src")
                .to_string_lossy()
                .replace('/', "::");
            let text = std::fs::read_to_string(&p).expect("read module");
            // A module's tests may reach anything: only its code counts.
            let text = text.split("#[cfg(test)]").next().unwrap_or("");
            // `super::x` in `a::b` is `crate::a::x` (the parent of a top-level module is the
            // crate itself).
            let parent = module.rsplit_once("::").map_or("", |(p, _)| p);
            let mut named = BTreeSet::new();
            for line in text.lines() {
                let code = line.split("//").next().unwrap_or("");
                let mut found: Vec<String> = code
                    .match_indices("crate::")
                    .map(|(i, _)| code[i + 7..].to_string())
                    .collect();
                found.extend(code.match_indices("super::").map(|(i, _)| {
                    let rest = &code[i + 7..];
                    if parent.is_empty() {
                        rest.to_string()
                    } else {
                        format!("{parent}::{rest}")
                    }
                }));
                for found in &found {
                    let path: Vec<&str> = found
                        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                        .next()
                        .unwrap_or("")
                        .split("::")
                        .collect();
                    let target = match path.as_slice() {
                        [
                            layer @ ("judge" | "harness" | "commands" | "shards" | "repro"),
                            m,
                            ..,
                        ] if !m.is_empty() && *m != "*" => {
                            format!("{layer}::{m}")
                        }
                        [m, ..] => (*m).to_string(),
                        [] => continue,
                    };
                    // `super::*` in a test module, an `{` group: not a module.
                    if target.is_empty() || target.contains('{') {
                        continue;
                    }
                    if target != module && !target.is_empty() {
                        named.insert(target);
                    }
                }
            }
            out.insert(module, named);
        }
    }
    out
}

/// Every module's layer; one this does not know fails the test (give it one here).
fn layer(module: &str) -> u8 {
    match module.split("::").next().unwrap_or("") {
        // Leaves: parsing, globbing, files; used anywhere, using nothing above them.
        "args" | "glob" | "atomic_file" | "run_dir" | "case_size" => 0,
        "judge" => 1,
        "harness" | "shards" | "repro" => 2,
        // The command line's tables name the commands' help only; `commands` run it all.
        "cli" | "commands" => 3,
        other => panic!("module {module} ({other}) has no layer: give it one in layers.rs"),
    }
}

#[test]
fn layers_point_one_way() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = imports(&src);
    assert!(graph.contains_key("harness::worker") && graph.contains_key("judge::run"));
    let mut upward = Vec::new();
    for (m, named) in &graph {
        for t in named {
            if layer(t) > layer(m) {
                upward.push(format!("{m} imports {t}"));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "imports up a layer (leaves < judge < harness, shards, repro < cli, commands): {upward:#?}"
    );
}

/// No circle in the runner, nor in the two crates whose modules once had one (umbra-case's
/// loader and twins, umbra-gl's context and platform).
#[test]
fn no_module_imports_in_a_circle() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for src in [
        root.join("src"),
        root.join("../umbra-case/src"),
        root.join("../umbra-gl/src"),
    ] {
        no_circle(&src);
    }
}

fn no_circle(src: &Path) {
    let graph = imports(src);
    // Depth-first search for a back edge; report the circle it closes.
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == m) {
            let mut circle = path[i..].to_vec();
            circle.push(m.to_string());
            return Some(circle);
        }
        if done.contains(m) {
            return None;
        }
        path.push(m.to_string());
        for t in graph.get(m).into_iter().flatten() {
            if let Some(c) = visit(t, graph, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(m.to_string());
        None
    }
    let mut done = BTreeSet::new();
    for m in graph.keys() {
        if let Some(circle) = visit(m, &graph, &mut Vec::new(), &mut done) {
            panic!(
                "{}: modules import each other in a circle: {}",
                src.display(),
                circle.join(" → ")
            );
        }
    }
}

#[test]
fn reporting_never_names_the_runner() {
    let report = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../umbra-report");
    let manifest = std::fs::read_to_string(report.join("Cargo.toml")).expect("manifest");
    assert!(
        !manifest.contains("umbra-runner"),
        "umbra-report depends on the runner"
    );
    for e in std::fs::read_dir(report.join("src")).expect("src") {
        let p = e.expect("entry").path();
        let text = std::fs::read_to_string(&p).expect("read");
        assert!(
            !text.contains("umbra_runner"),
            "{} names umbra_runner",
            p.display()
        );
    }
}
