//! `cargo xtask fetch-mesa [--dir DIR] [--suite SUITE]`: a second, real Mesa without touching
//! the system's (../shared/PLATFORM.md, last section).
//!
//! apt is pointed at one extra suite through a private sources list, lists directory and
//! cache (`-o Dir::Etc::sourcelist=…`), so the system's apt configuration and state are not
//! changed; the Mesa packages of that suite are downloaded and unpacked with `dpkg -x` into
//! DIR (default `target/mesa/SUITE`), which `--mesa DIR` then loads. The mirror is the
//! system's own (from /etc/apt), so a snapshot mirror stays a snapshot.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The packages that make a complete Mesa for umbra's drivers (PLATFORM.md): EGL (glvnd
/// vendor), gallium (llvmpipe, softpipe, zink), the DRI loaders, lavapipe, and the libdrm
/// they were built against.
pub const PACKAGES: &[&str] = &[
    "libegl-mesa0",
    "mesa-libgallium",
    "libgbm1",
    "libgl1-mesa-dri",
    "mesa-vulkan-drivers",
    "libdrm2",
    "libdrm-amdgpu1",
    "libdrm-intel1",
];

/// The mirror the system's apt uses for Debian (deb822 or one-line format).
fn mirror() -> String {
    for f in [
        "/etc/apt/sources.list.d/debian.sources",
        "/etc/apt/sources.list",
    ] {
        let Ok(text) = std::fs::read_to_string(f) else {
            continue;
        };
        for line in text.lines() {
            let line = line.trim();
            if let Some(uri) = line.strip_prefix("URIs:") {
                if let Some(u) = uri.split_whitespace().find(|u| !u.contains("security")) {
                    return u.to_string();
                }
            }
            if line.starts_with("deb ") && !line.contains("security") {
                if let Some(u) = line.split_whitespace().find(|w| w.starts_with("http")) {
                    return u.to_string();
                }
            }
        }
    }
    "http://deb.debian.org/debian".into()
}

/// Runs the command; returns the exit code.
pub fn main(suite: &str, dir: Option<PathBuf>, root: &Path) -> i32 {
    let dir = dir.unwrap_or_else(|| root.join("target").join("mesa").join(suite));
    let apt = dir.join(".apt");
    let debs = apt.join("debs");
    for d in [
        apt.join("lists").join("partial"),
        apt.join("cache").join("archives").join("partial"),
        debs.clone(),
    ] {
        if let Err(e) = std::fs::create_dir_all(&d) {
            eprintln!("error: cannot create {}: {e}", d.display());
            return 125;
        }
    }
    let list = apt.join("sources.list");
    let line = format!(
        "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] {} {suite} main\n",
        mirror()
    );
    if let Err(e) = std::fs::write(&list, &line) {
        eprintln!("error: cannot write {}: {e}", list.display());
        return 125;
    }
    let opts = |cmd: &mut Command| {
        cmd.arg("-o")
            .arg(format!("Dir::Etc::sourcelist={}", list.display()))
            .args(["-o", "Dir::Etc::sourceparts=-"])
            .arg("-o")
            .arg(format!("Dir::State::Lists={}", apt.join("lists").display()))
            .arg("-o")
            .arg(format!("Dir::Cache={}", apt.join("cache").display()))
            .args(["-o", "Debug::NoLocking=1"]);
    };
    println!("fetch-mesa: {}", line.trim());
    let mut update = Command::new("apt-get");
    opts(&mut update);
    update.arg("update");
    if !update.status().is_ok_and(|s| s.success()) {
        eprintln!(
            "error: apt-get update of the private list failed (network, or no apt here); fix: check the mirror in {}",
            list.display()
        );
        return 125;
    }
    let mut download = Command::new("apt-get");
    opts(&mut download);
    download.arg("download").current_dir(&debs);
    for p in PACKAGES {
        download.arg(format!("{p}/{suite}"));
    }
    if !download.status().is_ok_and(|s| s.success()) {
        eprintln!(
            "error: apt-get download failed; {suite} may not carry every package of {}",
            PACKAGES.join(" ")
        );
        return 125;
    }
    let Ok(entries) = std::fs::read_dir(&debs) else {
        return 125;
    };
    let mut version = String::new();
    for e in entries.filter_map(Result::ok) {
        let p = e.path();
        if p.extension().is_none_or(|x| x != "deb") {
            continue;
        }
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with("mesa-libgallium_") {
            version = name.split('_').nth(1).unwrap_or("").to_string();
        }
        if !Command::new("dpkg-deb")
            .arg("-x")
            .arg(&p)
            .arg(&dir)
            .status()
            .is_ok_and(|s| s.success())
        {
            eprintln!("error: dpkg-deb -x {} failed", p.display());
            return 125;
        }
    }
    println!(
        "fetch-mesa: Mesa {version} unpacked in {}\nfetch-mesa: use it with --mesa {} (e.g. cargo xtask drivers --baseline system --candidate {})",
        dir.display(),
        dir.display(),
        dir.display()
    );
    0
}
