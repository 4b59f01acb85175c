//! The judging cache survives commits that do not touch what the judge reads, and only
//! those: the key the build script gave this build is `basis_key::sources_key` of this tree,
//! and on a copy of the tree a change to the report (or the runner, or a dependency only they
//! use) keeps the key while a change to umbra-ref's sources, umbra-case's manifest, the
//! cache's format or a dependency the reference uses drops it.

mod common;

use std::path::{Path, PathBuf};

use umbra_runner::judge::basis_key::{BASIS_CRATES, FORMAT_FILE, locked_dependencies, sources_key};

/// One edit of the copied tree.
type Change<'a> = Box<dyn Fn() + 'a>;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("dir");
    for e in std::fs::read_dir(from).expect("read").flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).expect("copy");
        }
    }
}

/// The parts of the tree the key could read, and two it must not: umbra-report's sources and
/// the runner's own sources.
fn copy_tree(to: &Path) {
    let root = repo();
    for c in BASIS_CRATES.iter().chain(&["umbra-report", "umbra-runner"]) {
        let dir = Path::new("crates").join(c);
        copy_dir(&root.join(&dir).join("src"), &to.join(&dir).join("src"));
        std::fs::copy(
            root.join(&dir).join("Cargo.toml"),
            to.join(&dir).join("Cargo.toml"),
        )
        .expect("manifest");
    }
    std::fs::copy(root.join("Cargo.lock"), to.join("Cargo.lock")).expect("lock");
}

fn append(file: &Path, text: &str) {
    let mut s = std::fs::read_to_string(file).expect("read");
    s.push_str(text);
    std::fs::write(file, s).expect("write");
}

#[test]
fn this_build_s_cache_key_is_the_key_of_its_sources() {
    let key = sources_key(&repo(), env!("UMBRA_BASIS_TOOLCHAIN")).expect("key");
    assert_eq!(
        umbra_runner::judge::judge_cache::build_id(),
        format!("{key}-src")
    );
}

#[test]
fn a_change_outside_the_judge_keeps_the_key_and_a_change_inside_drops_it() {
    let tree = common::scratch("basis-key");
    copy_tree(&tree);
    let toolchain = "rustc 1.0.0 (test) x86_64-unknown-linux-gnu";
    let key = || sources_key(&tree, toolchain).expect("key");
    let first = key();
    assert_eq!(first, sources_key(&repo(), toolchain).expect("repo key"));

    // Kept: the report, the runner (but for the cache's format file), a lock entry of a
    // crate the judge does not use.
    append(
        &tree.join("crates/umbra-report/src/lib.rs"),
        "\n// a report change\n",
    );
    append(
        &tree.join("crates/umbra-runner/src/main.rs"),
        "\n// a runner change\n",
    );
    let lock = tree.join("Cargo.lock");
    let original_lock = std::fs::read_to_string(&lock).expect("lock");
    let wgpu_version = original_lock
        .split("[[package]]")
        .find(|b| b.contains("\nname = \"wgpu\"\n"))
        .and_then(|b| b.lines().find_map(|l| l.strip_prefix("version = \"")))
        .map(|v| v.trim_end_matches('"').to_string())
        .expect("wgpu in the lock");
    assert!(
        !locked_dependencies(&original_lock)
            .iter()
            .any(|d| d.starts_with("wgpu ")),
        "the judge does not depend on wgpu"
    );
    std::fs::write(
        &lock,
        original_lock.replacen(
            &format!("name = \"wgpu\"\nversion = \"{wgpu_version}\""),
            "name = \"wgpu\"\nversion = \"999.0.0\"",
            1,
        ),
    )
    .expect("lock");
    assert_eq!(key(), first, "a change outside the judge kept the key");
    std::fs::write(&lock, &original_lock).expect("lock");

    // Dropped: each of these alone.
    let glam = locked_dependencies(&original_lock)
        .into_iter()
        .find(|d| d.starts_with("glam "))
        .expect("the reference depends on glam");
    let glam_version = glam.trim_start_matches("glam ");
    let changes: Vec<(&str, Change)> = vec![
        (
            "umbra-ref's source",
            Box::new(|| append(&tree.join("crates/umbra-ref/src/lib.rs"), "\n// x\n")),
        ),
        (
            "umbra-case's manifest",
            Box::new(|| append(&tree.join("crates/umbra-case/Cargo.toml"), "\n# x\n")),
        ),
        (
            "umbra-compare's source",
            Box::new(|| append(&tree.join("crates/umbra-compare/src/lib.rs"), "\n// x\n")),
        ),
        (
            "the cache's format",
            Box::new(|| append(&tree.join(FORMAT_FILE), "\n// x\n")),
        ),
        (
            "a new file in umbra-ref",
            Box::new(|| std::fs::write(tree.join("crates/umbra-ref/src/new.rs"), "").expect("new")),
        ),
        (
            "glam's locked version",
            Box::new(|| {
                std::fs::write(
                    tree.join("Cargo.lock"),
                    original_lock.replacen(
                        &format!("name = \"glam\"\nversion = \"{glam_version}\""),
                        "name = \"glam\"\nversion = \"999.0.0\"",
                        1,
                    ),
                )
                .expect("lock")
            }),
        ),
    ];
    for (what, change) in changes {
        let _ = std::fs::remove_dir_all(&tree);
        copy_tree(&tree);
        assert_eq!(key(), first);
        change();
        assert_ne!(key(), first, "{what} changed and the key did not");
    }
    // And the toolchain.
    assert_ne!(
        sources_key(&tree, "rustc 2.0.0 (test) x86_64-unknown-linux-gnu").expect("key"),
        key()
    );
}

/// The build script hands both watch lists to cargo as `rerun-if-changed`, and cargo counts a
/// missing path as always out of date: one missing path re-ran the build script, and so
/// rebuilt umbra-runner (about 50 s on 2 cores), on every `cargo run` of umbra. Every path
/// named must exist, and every crate's build script that exists must be named.
#[test]
fn every_watched_path_exists_so_a_build_is_not_redone_on_every_run() {
    use umbra_runner::judge::basis_key::{watched, workspace_watched};
    let root = repo();
    let all = workspace_watched(&root);
    for p in watched(&root).iter().chain(&all) {
        assert!(p.exists(), "{} is watched but missing", p.display());
    }
    let runner_script = root.join("crates/umbra-runner/build.rs");
    assert!(
        all.contains(&runner_script),
        "{} is not watched",
        runner_script.display()
    );
}
