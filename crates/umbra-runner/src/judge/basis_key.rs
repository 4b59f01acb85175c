//! What the judging basis is computed by, as one key: the cache of truths and judged renders
//! ([`crate::judge::judge_cache`]) is valid exactly as long as this key is.
//!
//! The basis depends on the case point and on the code that computes truth and reference:
//! the sources of `umbra-case`, `umbra-ref` and `umbra-compare` (every file under their
//! `src/`, and their manifests), the cache's own file format (`judge_cache.rs`), and the
//! locked versions of every crate those three depend on, directly or not (from Cargo.lock).
//! A change anywhere else (the runner, a backend, the report, xtask) keeps the key, so a
//! CI job after such a commit reads the basis the last job computed; a change to any of
//! those files or versions, committed or not, makes a new key. The compiler and target are
//! part of it too (`rustc -V`, the target triple), since the truth's arithmetic is theirs.
//!
//! A second key, [`workspace_key`], covers every crate's sources and the whole Cargo.lock: it
//! names the build of umbra a run came from, so `umbra merge` can refuse shards of
//! different builds (two CI jobs that compiled the same commit with the same toolchain get the
//! same key, whatever their paths or machines).
//!
//! This file is compiled twice: into the runner (tests call [`sources_key`] on a copy of the
//! tree) and into its build script, which computes the key of the tree being built and
//! hands it to the crate as `UMBRA_BASIS_KEY`. It uses the standard library only.

use std::path::{Path, PathBuf};

/// The crates whose sources the basis is computed by.
pub const BASIS_CRATES: [&str; 3] = ["umbra-case", "umbra-ref", "umbra-compare"];

/// The runner's own file that fixes the cache's format.
pub const FORMAT_FILE: &str = "crates/umbra-runner/src/judge/judge_cache.rs";

/// FNV-1a's offset basis: where a fresh hash starts.
pub const FNV_START: u64 = 0xcbf2_9ce4_8422_2325;

/// 64-bit FNV-1a, continued from `h`.
pub fn fnv(mut h: u64, bytes: &[u8]) -> u64 {
    for b in bytes {
        h = (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// `h` continued over each of `files` in order: its path relative to `root` (with `/`), its
/// length and its bytes. An error names the file that could not be read.
pub fn hash_files(mut h: u64, root: &Path, files: &[PathBuf]) -> Result<u64, String> {
    for f in files {
        let bytes = std::fs::read(f).map_err(|e| format!("{}: {e}", f.display()))?;
        let rel = f.strip_prefix(root).unwrap_or(f).to_string_lossy();
        h = fnv(h, rel.replace('\\', "/").as_bytes());
        h = fnv(h, &(bytes.len() as u64).to_le_bytes());
        h = fnv(h, &bytes);
    }
    Ok(h)
}

/// Every file under `dir`, sorted.
pub fn files_under(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d)? {
            let p = e?.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The files the key reads, under the workspace `root`: the basis crates' manifests and
/// sources, and the format file. Build scripts watch them.
pub fn watched(root: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = BASIS_CRATES
        .iter()
        .flat_map(|c| {
            [
                root.join("crates").join(c).join("Cargo.toml"),
                root.join("crates").join(c).join("src"),
            ]
        })
        .collect();
    v.push(root.join(FORMAT_FILE));
    v.push(root.join("Cargo.lock"));
    v
}

/// The files [`workspace_key`] reads: every crate's manifest, build script and sources, the
/// workspace manifest and Cargo.lock.
///
/// Only paths that exist are named. The build script hands this list to cargo as
/// `rerun-if-changed`, and cargo counts a missing path as always out of date: a
/// `crates/X/build.rs` named for a crate without one re-ran the build script, and so rebuilt
/// umbra-runner (about 50 s on 2 cores), on every `cargo run` of umbra, so on every phase of
/// `cargo xtask test` and every `cargo xtask conformance`. A build script added later to a
/// crate that had none is therefore not watched until another watched file changes (its
/// manifest, Cargo.lock); the key is used to name builds for `umbra merge`, not to judge.
pub fn workspace_watched(root: &Path) -> Vec<PathBuf> {
    let mut v = vec![root.join("Cargo.toml"), root.join("Cargo.lock")];
    if let Ok(entries) = std::fs::read_dir(root.join("crates")) {
        let mut crates: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        crates.sort();
        for c in crates {
            v.extend([c.join("Cargo.toml"), c.join("build.rs"), c.join("src")]);
        }
    }
    v.retain(|p| p.exists());
    v
}

/// The key of every crate's sources under `root` (see [`workspace_watched`]) with
/// `toolchain`: 16 hexadecimal digits naming this build of umbra.
pub fn workspace_key(root: &Path, toolchain: &str) -> Result<String, String> {
    let mut h = fnv(0xcbf2_9ce4_8422_2325, toolchain.as_bytes());
    let mut files = Vec::new();
    for p in workspace_watched(root) {
        if p.is_dir() {
            files.extend(files_under(&p).map_err(|e| format!("{}: {e}", p.display()))?);
        } else {
            files.push(p);
        }
    }
    h = hash_files(h, root, &files)?;
    Ok(format!("{h:016x}"))
}

/// The packages of Cargo.lock: name → (version, dependency names).
fn lock_packages(lock: &str) -> Vec<(String, String, Vec<String>)> {
    let mut out = Vec::new();
    for block in lock.split("[[package]]").skip(1) {
        let field = |name: &str| {
            block
                .lines()
                .find_map(|l| l.strip_prefix(&format!("{name} = \"")))
                .map(|v| v.trim_end_matches('"').to_string())
                .unwrap_or_default()
        };
        let deps = block
            .split_once("dependencies = [")
            .map(|(_, rest)| {
                rest.split(']')
                    .next()
                    .unwrap_or("")
                    .lines()
                    .filter_map(|l| {
                        let l = l.trim().trim_end_matches(',').trim_matches('"');
                        // "name" or "name version" (two versions of one crate in the lock).
                        (!l.is_empty()).then(|| l.split(' ').next().unwrap_or(l).to_string())
                    })
                    .collect()
            })
            .unwrap_or_default();
        out.push((field("name"), field("version"), deps));
    }
    out
}

/// `name version` of every package the basis crates depend on, directly or not, sorted
/// (every version of a name the lock holds, where it holds more than one).
pub fn locked_dependencies(lock: &str) -> Vec<String> {
    let packages = lock_packages(lock);
    let mut seen: Vec<String> = Vec::new();
    let mut todo: Vec<String> = BASIS_CRATES.iter().map(|s| s.to_string()).collect();
    while let Some(name) = todo.pop() {
        if seen.contains(&name) {
            continue;
        }
        for (_, _, deps) in packages.iter().filter(|(n, _, _)| *n == name) {
            todo.extend(deps.iter().cloned());
        }
        seen.push(name);
    }
    let mut out: Vec<String> = packages
        .iter()
        .filter(|(n, _, _)| seen.contains(n) && !BASIS_CRATES.contains(&n.as_str()))
        .map(|(n, v, _)| format!("{n} {v}"))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// The key of the workspace at `root`, with `toolchain` (the compiler's version and target)
/// folded in: 16 hexadecimal digits. An error names the file that could not be read.
pub fn sources_key(root: &Path, toolchain: &str) -> Result<String, String> {
    let mut h = fnv(0xcbf2_9ce4_8422_2325, toolchain.as_bytes());
    let mut files = Vec::new();
    for c in BASIS_CRATES {
        let dir = root.join("crates").join(c);
        files.push(dir.join("Cargo.toml"));
        files.extend(
            files_under(&dir.join("src"))
                .map_err(|e| format!("{}: {e}", dir.join("src").display()))?,
        );
    }
    files.push(root.join(FORMAT_FILE));
    h = hash_files(h, root, &files)?;
    let lock_path = root.join("Cargo.lock");
    let lock =
        std::fs::read_to_string(&lock_path).map_err(|e| format!("{}: {e}", lock_path.display()))?;
    for dep in locked_dependencies(&lock) {
        h = fnv(h, dep.as_bytes());
        h = fnv(h, b"\n");
    }
    Ok(format!("{h:016x}"))
}
