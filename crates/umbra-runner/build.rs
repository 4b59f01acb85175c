//! Computes the key of the judging basis from the sources that compute it
//! (`src/judge/basis_key.rs`, compiled here too) and hands it to the crate as
//! `UMBRA_BASIS_KEY`, with the toolchain it folded in as `UMBRA_BASIS_TOOLCHAIN`. Outside a
//! workspace (a packaged crate, no sibling sources) the key is empty and the cache falls back
//! to keying by the executable. It also hands over `UMBRA_BUILD_KEY`, the key of every
//! crate's sources, which names this build for `umbra merge`.

#[path = "src/judge/basis_key.rs"]
#[allow(dead_code)]
mod basis_key;

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default());
    let root = manifest.join("../..");
    for p in basis_key::watched(&root) {
        println!("cargo:rerun-if-changed={}", p.display());
    }
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = std::process::Command::new(rustc)
        .arg("-V")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let toolchain = format!("{version} {}", std::env::var("TARGET").unwrap_or_default());
    let key = match basis_key::sources_key(&root, &toolchain) {
        Ok(k) => k,
        Err(e) => {
            println!(
                "cargo:warning=the judging cache is keyed by the executable instead of the sources: {e}"
            );
            String::new()
        }
    };
    println!("cargo:rustc-env=UMBRA_BASIS_KEY={key}");
    // The build's own key (every crate's sources): what `umbra merge` compares across shards.
    for p in basis_key::workspace_watched(&root) {
        println!("cargo:rerun-if-changed={}", p.display());
    }
    // The build's own key also folds in the profile and RUSTFLAGS: they change the code,
    // not the judge's arithmetic (the basis key leaves them out).
    let flavour = format!(
        "{toolchain} profile={} rustflags={}",
        std::env::var("PROFILE").unwrap_or_default(),
        std::env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default()
    );
    let build = basis_key::workspace_key(&root, &flavour).unwrap_or_else(|e| {
        println!("cargo:warning=umbra's build key could not be computed: {e}");
        String::new()
    });
    println!("cargo:rustc-env=UMBRA_BUILD_KEY={build}");
    println!("cargo:rustc-env=UMBRA_BASIS_TOOLCHAIN={toolchain}");
}
