//! The CI examples in `docs/ci/` stay in step with the command line: every `umbra` command
//! they run (through `cargo xtask conformance` or `cargo run --bin umbra -- merge`) uses
//! only flags that command takes, the shard jobs pass `--shard` and `--judge-cache`, and
//! each file has a merge step. (Their commands were run by hand as written; README,
//! "Sharded in CI".)

use std::path::Path;

/// Each `(command, flags)` an example's lines run.
fn commands(text: &str) -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.split(" #").next().unwrap_or("");
        for (marker, command) in [
            ("cargo xtask conformance", "conformance"),
            ("--bin umbra -- merge", "merge"),
        ] {
            if let Some((_, rest)) = line.split_once(marker) {
                let flags = rest
                    .split_whitespace()
                    .filter(|w| w.starts_with("--"))
                    .map(|w| w.trim_start_matches("--").to_string())
                    .collect();
                out.push((command.to_string(), flags));
            }
        }
    }
    out
}

#[test]
fn the_ci_examples_run_only_flags_umbra_takes_and_merge_their_shards() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/ci");
    for file in ["gitlab-ci.yml", "github-actions.yml"] {
        let text = std::fs::read_to_string(dir.join(file)).expect("a CI example");
        let found = commands(&text);
        assert!(
            found.iter().any(|(c, f)| c == "conformance"
                && f.contains(&"shard".to_string())
                && f.contains(&"judge-cache".to_string())),
            "{file}: a shard job runs conformance with --shard and --judge-cache: {found:?}"
        );
        assert!(
            found.iter().any(|(c, _)| c == "merge"),
            "{file}: a merge step: {found:?}"
        );
        for (command, flags) in &found {
            let cli = umbra_runner::cli::command();
            let spec = cli.find_subcommand(command).expect("a command of umbra");
            for f in flags {
                assert!(
                    spec.get_arguments()
                        .any(|a| a.get_long() == Some(f.as_str())),
                    "{file}: `umbra {command}` has no flag --{f}"
                );
            }
        }
    }
}
