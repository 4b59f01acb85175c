//! The runner's layers, checked from its sources (as rust-analyzer's `tidy` checks its tree):
//! `judge` (one point judged, goldens, expectations) knows neither the harness nor a command,
//! `harness` (workers, pool, registry, Mesa builds) knows no command, and no two modules import
//! each other in a circle. Reporting is its own crate (`umbra-report`) and never names the
//! runner. A `use` that points up a layer fails here with the file and the import.

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
            if !name.ends_with(".rs") || ["lib.rs", "main.rs", "mod.rs"].contains(&name) {
                continue;
            }
            let module = p
                .strip_prefix(src)
                .expect("under src")
                .with_extension("")
                .to_string_lossy()
                .replace('/', "::");
            let text = std::fs::read_to_string(&p).expect("read module");
            let mut named = BTreeSet::new();
            for line in text.lines() {
                let code = line.split("//").next().unwrap_or("");
                for (i, _) in code.match_indices("crate::") {
                    let path: Vec<&str> = code[i + 7..]
                        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                        .next()
                        .unwrap_or("")
                        .split("::")
                        .collect();
                    let target = match path.as_slice() {
                        [layer @ ("judge" | "harness" | "commands"), m, ..] => {
                            format!("{layer}::{m}")
                        }
                        [m, ..] => (*m).to_string(),
                        [] => continue,
                    };
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

fn layer(module: &str) -> u8 {
    match module.split("::").next() {
        Some("judge") => 1,
        Some("harness") => 2,
        Some("commands") => 3,
        _ => 0, // args, glob, cli: leaves used anywhere
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
            if layer(t) > layer(m) && layer(m) > 0 {
                upward.push(format!("{m} imports {t}"));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "imports up a layer (judge < harness < commands): {upward:#?}"
    );
}

#[test]
fn no_module_imports_in_a_circle() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = imports(&src);
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
                "modules import each other in a circle: {}",
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
