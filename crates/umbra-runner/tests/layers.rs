//! The runner's layers, checked from its sources (as rust-analyzer's `tidy` checks its tree):
//! the leaves (`exit`, `glob`, `atomic_file`, `run_dir`, `case_size`, `version`) know nothing
//! above them, `judge` (one point judged, goldens, expectations, cards) knows neither the
//! harness nor a command, `harness` (workers, pool, registry, Mesa builds), `shards` and
//! `repro` know no command, `conformance` and `reduction` (a run and a reduction as
//! libraries) are called by the commands and call none, a command imports no other command,
//! and no two modules import each other in a circle. Every module has a layer ([`layer`]): a
//! new one that is not given one fails here. Imports are read through `crate::` and `super::`
//! paths alike. Reporting is its own crate (`umbra-report`) and never names the runner. A
//! `use` that points up a layer fails here with the file and the import.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (`harness::worker`) → the modules it names through `crate::`.
fn imports(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut out = BTreeMap::new();
    for (p, text) in sources(src) {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if ["lib.rs", "main.rs"].contains(&name) {
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
        // `super::x` in `a::b` is `crate::a::x` (the parent of a top-level module is the
        // crate itself).
        let parent = module.rsplit_once("::").map_or("", |(p, _)| p);
        let mut named = BTreeSet::new();
        for code in text.lines() {
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
                        layer @ ("judge" | "harness" | "commands" | "conformance" | "shards"
                        | "repro"),
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
    out
}

/// Every `.rs` file under `src`, with its code: the text before its tests (a module's tests
/// may reach anything), `//` comments removed.
fn sources(src: &Path) -> Vec<(PathBuf, String)> {
    umbra_runner::judge::basis_key::files_under(src)
        .expect("read src")
        .into_iter()
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("read module");
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            let code = code
                .lines()
                .map(|l| l.split("//").next().unwrap_or(""))
                .collect::<Vec<_>>()
                .join("\n");
            (p, code)
        })
        .collect()
}

/// Every module's layer; one this does not know fails the test (give it one here).
fn layer(module: &str) -> u8 {
    known_layer(module)
        .unwrap_or_else(|| panic!("module {module} has no layer: give it one in layers.rs"))
}

/// A module's layer, where this file gives it one.
fn known_layer(module: &str) -> Option<u8> {
    Some(match module.split("::").next().unwrap_or("") {
        // Leaves: parsing, globbing, files; used anywhere, using nothing above them.
        "exit" | "glob" | "atomic_file" | "run_dir" | "case_size" | "version" => 0,
        "judge" => 1,
        "harness" | "shards" | "repro" => 2,
        // The pre-merge tiers: files of catches and durations, and the choice from them.
        "tier" => 2,
        // The command line's tables name the commands' help only.
        "cli" => 3,
        // A conformance run and a reduction as libraries (plan, execution, gathering,
        // summary; the reducer), which the commands call.
        "conformance" | "reduction" => 4,
        // The commands: each calls the layers below, none another command
        // ([`commands_import_no_command`]).
        "commands" => 5,
        _ => return None,
    })
}

/// The first circle among `graph`'s modules, if any.
fn circle_in(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
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
    graph
        .keys()
        .find_map(|m| visit(m, graph, &mut Vec::new(), &mut done))
}

/// Prints the runner's import graph (`cargo test -p umbra-runner --test layers -- --ignored
/// --nocapture the_import_graph`): each module with its layer and what it imports, the arrows that point
/// up a layer, the circles, and the largest files. `UMBRA_LAYERS_SRC=DIR` prints another
/// tree's (an older checkout's `crates/umbra-runner/src`), for a before-and-after.
#[test]
#[ignore = "a report, not a check: run it with --ignored --nocapture"]
fn the_import_graph() {
    let src = std::env::var_os("UMBRA_LAYERS_SRC")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src"));
    let graph = imports(&src);
    let name = |m: &str| match known_layer(m) {
        Some(l) => format!("{m} [{l}]"),
        None => format!("{m} [?]"),
    };
    println!("import graph of {} (layer in brackets):", src.display());
    for (m, named) in &graph {
        let to: Vec<String> = named.iter().map(|t| name(t)).collect();
        println!("  {} -> {}", name(m), to.join(", "));
    }
    let upward: Vec<String> = graph
        .iter()
        .flat_map(|(m, named)| named.iter().map(move |t| (m, t)))
        .filter(|(m, t)| matches!((known_layer(m), known_layer(t)), (Some(a), Some(b)) if b > a))
        .map(|(m, t)| format!("{m} -> {t}"))
        .collect();
    println!("arrows up a layer: {}", upward.len());
    for u in &upward {
        println!("  {u}");
    }
    let among = between_commands(&graph);
    println!("arrows between commands: {}", among.len());
    for a in &among {
        println!("  {a}");
    }
    for tree in [
        src.clone(),
        src.join("../../umbra-case/src"),
        src.join("../../umbra-gl/src"),
    ] {
        match circle_in(&imports(&tree)) {
            Some(c) => println!("circle in {}: {}", tree.display(), c.join(" -> ")),
            None => println!("no circle in {}", tree.display()),
        }
    }
    let mut sizes: Vec<(usize, String)> = umbra_runner::judge::basis_key::files_under(&src)
        .expect("read src")
        .into_iter()
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .map(|p| {
            let n = std::fs::read_to_string(&p).map_or(0, |t| t.lines().count());
            (n, p.strip_prefix(&src).unwrap_or(&p).display().to_string())
        })
        .collect();
    sizes.sort_by(|a, b| b.cmp(a));
    println!(
        "largest files ({} lines in {} files):",
        sizes.iter().map(|s| s.0).sum::<usize>(),
        sizes.len()
    );
    for (n, f) in sizes.iter().take(10) {
        println!("  {n:5} {f}");
    }
    assert!(!graph.is_empty(), "no module found under {}", src.display());
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
        "imports up a layer (leaves < judge < harness, shards, repro < cli < conformance < commands): {upward:#?}"
    );
}

/// The command a module belongs to (`commands::selftest::thresholds` → `selftest`), if any.
fn command_of(module: &str) -> Option<&str> {
    module.strip_prefix("commands::")?.split("::").next()
}

/// Every import from one command's modules into another command's.
fn between_commands(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<String> {
    graph
        .iter()
        .flat_map(|(m, named)| named.iter().map(move |t| (m, t)))
        .filter(|(m, t)| matches!((command_of(m), command_of(t)), (Some(a), Some(b)) if a != b))
        .map(|(m, t)| format!("{m} imports {t}"))
        .collect()
}

/// A command imports no command: what two commands share is a library module below them
/// (`conformance`, `harness::cards`, `judge::card_row`), and a command's own parts sit in
/// its folder (`commands/selftest/thresholds.rs`).
#[test]
fn commands_import_no_command() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = imports(&src);
    assert!(graph.contains_key("commands::selftest::thresholds"));
    let among = between_commands(&graph);
    assert!(
        among.is_empty(),
        "commands import commands; move what they share below them: {among:#?}"
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
    if let Some(circle) = circle_in(&imports(src)) {
        panic!(
            "{}: modules import each other in a circle: {}",
            src.display(),
            circle.join(" → ")
        );
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

/// Backend identity stays in the registry (`harness::registry::Descriptor`): the files that
/// may name the GL or wgpu crates, each for a reason of its own. A command that needs to know
/// what a backend is asks its descriptor; a new wgpu kind or GL API is taught in the registry.
#[test]
fn only_the_registry_and_its_neighbours_name_the_backend_crates() {
    const ALLOWED: &[(&str, &str)] = &[
        (
            "harness/registry.rs",
            "the descriptor, and creating backends",
        ),
        (
            "harness/mesa_build.rs",
            "which of a Mesa build's libraries a driver needs",
        ),
        (
            "commands/backends.rs",
            "lists the machine's EGL devices and wgpu adapters",
        ),
        (
            "repro/mod.rs",
            "the repro replays umbra-gl's recorded GL calls as C",
        ),
        (
            "repro/probes.rs",
            "writes the probes' floats as umbra-gl's recorder does",
        ),
        (
            "judge/expectations.rs",
            "below the registry's layer: tells a device id's form from a misspelling",
        ),
    ];
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let naming: Vec<String> = sources(&src)
        .into_iter()
        .filter(|(_, code)| code.contains("umbra_gl::") || code.contains("umbra_wgpu::"))
        .map(|(p, _)| p.strip_prefix(&src).unwrap_or(&p).display().to_string())
        .collect();
    let stray: Vec<&String> = naming
        .iter()
        .filter(|f| !ALLOWED.iter().any(|(a, _)| a == f))
        .collect();
    assert!(
        stray.is_empty(),
        "these runner files name umbra_gl or umbra_wgpu; ask harness::registry::Descriptor instead: {stray:?}"
    );
    assert!(
        naming.iter().any(|f| f == "harness/registry.rs"),
        "{naming:?}"
    );
}

/// One scheduler (`harness::scheduler`): no command starts or feeds a worker itself, so
/// restarts, timeouts, reruns and flakes are handled in one place.
#[test]
fn only_the_scheduler_starts_workers() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut starting: Vec<String> = sources(&src)
        .into_iter()
        .filter(|(_, code)| code.contains("Worker::start") || code.contains("pool::Worker"))
        .map(|(p, _)| p.strip_prefix(&src).unwrap_or(&p).display().to_string())
        .collect();
    starting.sort();
    assert_eq!(
        starting,
        ["harness/pool.rs", "harness/scheduler.rs"],
        "start workers through harness::scheduler::Session"
    );
}
