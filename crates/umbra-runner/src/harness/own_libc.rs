//! A Mesa build whose libraries need a newer C library than the machine's, and one that
//! carries its own.
//!
//! Debian sid's Mesa 26.2 links against glibc 2.43; a Debian 12 machine has 2.36. Unpacking
//! the Mesa packages alone gives a build whose every library fails to load, and glvnd then
//! says only that EGL lacks the device platform. Two things follow:
//!
//! - **Every build is checked before a worker starts** ([`check_loadable`]): the loader that
//!   will load it (the build's own, else the machine's) lists the libraries each backend's
//!   driver needs (`ld.so --list`), and whatever it cannot find or whose symbol version the
//!   C library lacks is named, with the fix, before a single run is spent.
//! - **A build with its own C library** (`cargo xtask fetch-mesa --suite sid` unpacks the
//!   suite's Mesa with everything it links against, glibc and its dynamic loader included)
//!   runs its driver processes through that loader, no chroot and no root needed:
//!   [`enter`] re-executes the process as `LOADER --library-path DIRS --argv0 ARGV0 EXE
//!   ARGS`, so this process (umbra, built against an older glibc, which a newer one runs)
//!   and every library it loads come from the build. `--library-path` is not inherited, so
//!   a program this process starts gets the machine's libraries again; such a process finds
//!   umbra's executable through [`self_exe`] (its `/proc/self/exe` is the loader).

use std::path::{Path, PathBuf};

/// A build that carries its own C library: where it is, its loader, and the directories its
/// libraries are searched in, in order.
pub struct Own<'a> {
    /// The build's directory.
    pub root: &'a Path,
    /// Its dynamic loader (`ld-linux-*.so.*`).
    pub loader: &'a Path,
    /// Every directory of its shared libraries.
    pub dirs: &'a [PathBuf],
}

/// Set in a process re-executed through a build's loader: the umbra executable.
pub const EXE_ENV: &str = "UMBRA_EXE";

/// This executable: umbra's, also in a process started through a build's loader (whose
/// `/proc/self/exe` is the loader).
pub fn self_exe() -> std::io::Result<PathBuf> {
    let exe = std::env::current_exe()?;
    if is_loader(&exe) {
        if let Some(p) = std::env::var_os(EXE_ENV) {
            return Ok(PathBuf::from(p));
        }
    }
    Ok(exe)
}

fn is_loader(p: &Path) -> bool {
    p.file_name()
        .is_some_and(|n| n.to_string_lossy().starts_with("ld-linux"))
}

/// Whether this process already runs on `build`'s C library.
fn on_build_libc(build: &Own) -> bool {
    mapped()
        .iter()
        .any(|p| p.file_name().is_some_and(|n| n == "libc.so.6") && p.starts_with(build.root))
}

/// For a build with its own C library: checks that this process runs on it (the re-execution
/// through its loader took), naming the C library it has otherwise.
pub fn check_on_build_libc(build: &Own) -> Result<(), String> {
    if on_build_libc(build) {
        return Ok(());
    }
    let libc = mapped()
        .into_iter()
        .find(|p| p.file_name().is_some_and(|n| n == "libc.so.6"));
    Err(format!(
        "the worker runs on the C library {} instead of the build's own in {}; fix: unpack the suite again (`cargo xtask fetch-mesa --suite SUITE`)",
        libc.map_or_else(|| "unknown".into(), |p| p.display().to_string()),
        build.root.display()
    ))
}

/// The files this process has mapped (`/proc/self/maps`).
fn mapped() -> Vec<PathBuf> {
    std::fs::read_to_string("/proc/self/maps")
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.starts_with('/'))
        .map(PathBuf::from)
        .collect()
}

/// Moves this process onto `build`'s own C library when it is not on it yet: re-executes it
/// through the build's loader (on success this does not return). `Ok` when there is nothing
/// to do.
pub fn enter(build: &Own) -> Result<(), String> {
    let loader = build.loader;
    if on_build_libc(build) {
        return Ok(());
    }
    // Started through a loader already, yet not on the build's C library: executing again
    // would loop; say what this process runs on instead.
    if std::env::current_exe().is_ok_and(|e| is_loader(&e)) {
        return check_on_build_libc(build);
    }
    let exe = self_exe().map_err(|e| format!("cannot find this executable: {e}"))?;
    let mut args = std::env::args_os();
    let argv0 = args.next().unwrap_or_else(|| exe.clone().into_os_string());
    let mut cmd = std::process::Command::new(loader);
    cmd.arg("--library-path")
        .arg(search_path(build.dirs))
        .arg("--argv0")
        .arg(argv0)
        .arg(&exe)
        .args(args)
        .env(EXE_ENV, &exe);
    let e = std::os::unix::process::CommandExt::exec(&mut cmd);
    Err(format!(
        "cannot start through the build's own loader {}: {e}; fix: unpack the suite again with `cargo xtask fetch-mesa --suite SUITE`",
        loader.display()
    ))
}

/// A command that runs `program` on `build`'s libraries: through the build's own loader
/// when it carries one (`LOADER --library-path DIRS PROGRAM`), else the program itself (the
/// build's loader variables then point the GL and Vulkan loaders at it).
pub fn command(build: Option<&Own>, program: &Path) -> std::process::Command {
    match build {
        Some(b) => {
            let mut cmd = std::process::Command::new(b.loader);
            cmd.arg("--library-path")
                .arg(search_path(b.dirs))
                .arg(program);
            cmd
        }
        None => std::process::Command::new(program),
    }
}

/// Library directories as one `:`-separated search path.
pub fn search_path(dirs: &[PathBuf]) -> String {
    dirs.iter()
        .map(|d| d.to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join(":")
}

/// The machine's dynamic loader: the one that loaded this process.
fn machine_loader() -> Option<PathBuf> {
    mapped().into_iter().find(|p| is_loader(p)).or_else(|| {
        ["/lib64/ld-linux-x86-64.so.2", "/lib/ld-linux-aarch64.so.1"]
            .iter()
            .map(PathBuf::from)
            .find(|p| p.exists())
    })
}

/// Checks that the loader the workers will use (the build's own, else this machine's) finds
/// every library of `libs` (the ones the build's drivers load) and what they link against,
/// with the symbol versions they need. `dirs` are the build's library directories. `Err`
/// names what is missing and the fix.
pub fn check_loadable(
    root: &Path,
    loader: Option<&Path>,
    dirs: &[PathBuf],
    libs: &[PathBuf],
) -> Result<(), String> {
    let (loader, own) = match loader {
        Some(l) => (l.to_path_buf(), true),
        None => match machine_loader() {
            Some(l) => (l, false),
            None => return Ok(()),
        },
    };
    let machine = machine_glibc();
    let mut problems: Vec<(String, String)> = match (&machine, own) {
        (Some(m), false) => newer_glibc(libs, m),
        _ => Vec::new(),
    };
    for lib in libs {
        let mut cmd = std::process::Command::new(&loader);
        if own {
            cmd.arg("--library-path").arg(search_path(dirs));
        } else {
            // What a worker gets: the build's directories before the machine's.
            let mut dirs = search_path(dirs);
            if let Ok(old) = std::env::var("LD_LIBRARY_PATH") {
                dirs = format!("{dirs}:{old}");
            }
            cmd.env("LD_LIBRARY_PATH", dirs);
        }
        let out = match cmd.arg("--list").arg(lib).output() {
            Ok(out) => out,
            Err(e) => {
                problems.push((
                    format!("the loader {} cannot run ({e})", loader.display()),
                    String::new(),
                ));
                continue;
            }
        };
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        problems.extend(missing(&text));
    }
    if problems.is_empty() {
        return Ok(());
    }
    let glibc = problems
        .iter()
        .any(|(p, _)| p.contains("glibc") || p.contains("GLIBC_"));
    let fix = if own {
        "fix: unpack the suite again (`cargo xtask fetch-mesa --suite SUITE`), which brings every package the Mesa packages depend on".to_string()
    } else if glibc {
        format!(
            "the build was made for a newer C library than this machine's (glibc {}); fix: `cargo xtask fetch-mesa --suite SUITE --dir {}` unpacks the suite's Mesa with everything it links against, its own C library and loader included, and umbra starts the build's driver processes through that loader",
            machine.as_deref().unwrap_or("version unknown"),
            root.display()
        )
    } else {
        "fix: install or unpack the libraries named (for Debian packages, `cargo xtask fetch-mesa --suite SUITE` brings them)".to_string()
    };
    Err(format!(
        "the Mesa in {} cannot be loaded here ({}): {}; {fix}",
        root.display(),
        if own {
            "through its own loader"
        } else {
            "by this machine's loader"
        },
        grouped(&problems)
    ))
}

/// Problems as one phrase each, with every library that meets it: `glibc 2.43 is needed (by
/// libgallium-26.2.6-1.so)`, `libLLVM.so.22.1 is not found (needed by libEGL_mesa.so.0,
/// libvulkan_lvp.so)`.
fn grouped(problems: &[(String, String)]) -> String {
    let mut groups: Vec<(&str, Vec<&str>)> = Vec::new();
    for (what, by) in problems {
        let i = match groups.iter().position(|(w, _)| w == what) {
            Some(i) => i,
            None => {
                groups.push((what, Vec::new()));
                groups.len() - 1
            }
        };
        if !by.is_empty() && !groups[i].1.contains(&by.as_str()) {
            groups[i].1.push(by);
        }
    }
    groups
        .iter()
        .map(|(what, by)| match by.as_slice() {
            [] => what.to_string(),
            by => format!("{what} (by {})", by.join(", ")),
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// What an `ld.so --list` transcript says is missing, as (what, needed by) pairs: a library
/// not found, or a symbol version a library lacks (`libc.so.6 lacks GLIBC_2.43`,
/// `libgallium-26.2.6-1.so`).
fn missing(text: &str) -> Vec<(String, String)> {
    let name = |p: &str| {
        Path::new(p.trim()).file_name().map_or_else(
            || p.trim().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    };
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if let Some((lib, _)) = line.split_once(" => not found") {
            out.push((format!("{} is not found", lib.trim()), String::new()));
        } else if let Some(i) = line.find(": version `") {
            // `LIB: TARGET: version `V' not found (required by USER)`
            let head = &line[..i];
            let target = head.rsplit(": ").next().unwrap_or(head);
            let rest = &line[i + ": version `".len()..];
            let version = rest.split('\'').next().unwrap_or("");
            let user = rest
                .split("(required by ")
                .nth(1)
                .map(|u| u.trim_end_matches(')'))
                .unwrap_or("");
            out.push((format!("{} lacks {version}", name(target)), name(user)));
        } else if let Some((user, rest)) =
            line.split_once(": error while loading shared libraries: ")
        {
            // ld.so stops at the first library it cannot open: `LIB: WHY`.
            let (lib, why) = rest.split_once(": ").unwrap_or((rest, ""));
            let what = if why.starts_with("cannot open shared object file") {
                format!("{} is not found", name(lib))
            } else {
                format!("{} cannot be loaded ({why})", name(lib))
            };
            out.push((what, name(user)));
        }
    }
    out
}

/// The libraries of `libs` built for a newer glibc than the machine's, as (the version it
/// needs, the library): the highest `GLIBC_2.N` each names.
fn newer_glibc(libs: &[PathBuf], machine: &str) -> Vec<(String, String)> {
    let have = crate::version::parts(machine);
    libs.iter()
        .filter_map(|l| {
            let need = highest_glibc(&std::fs::read(l).ok()?)?;
            (crate::version::parts(&need) > have).then(|| {
                (
                    format!("glibc {need} is needed"),
                    l.file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
                )
            })
        })
        .collect()
}

/// The machine's glibc version, from the C library this process loaded (its highest
/// `GLIBC_2.N` version definition).
pub fn machine_glibc() -> Option<String> {
    let libc = mapped()
        .into_iter()
        .find(|p| p.file_name().is_some_and(|n| n == "libc.so.6"))?;
    highest_glibc(&std::fs::read(libc).ok()?)
}

/// The highest `GLIBC_2.N[.M]` named in an ELF file's bytes.
fn highest_glibc(bytes: &[u8]) -> Option<String> {
    let pat = b"GLIBC_2.";
    let mut best: Option<Vec<u32>> = None;
    let mut i = 0;
    while let Some(off) = bytes[i..].windows(pat.len()).position(|w| w == pat) {
        let start = i + off + pat.len() - 2;
        let end = bytes[start..]
            .iter()
            .position(|b| !(b.is_ascii_digit() || *b == b'.'))
            .map_or(bytes.len(), |n| start + n);
        let v: Vec<u32> = String::from_utf8_lossy(&bytes[start..end])
            .split('.')
            .map_while(|p| p.parse().ok())
            .collect();
        if v.len() >= 2 && best.as_ref().is_none_or(|b| v > *b) {
            best = Some(v);
        }
        i = end.max(i + off + 1);
    }
    best.map(|v| v.iter().map(u32::to_string).collect::<Vec<_>>().join("."))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loader_transcript_names_what_is_missing() {
        let text = "\
/m/libgallium-26.2.6-1.so: /lib/x86_64-linux-gnu/libm.so.6: version `GLIBC_2.43' not found (required by /m/libgallium-26.2.6-1.so)
\tlibLLVM.so.22.1 => not found
\tlibdrm.so.2 => /m/libdrm.so.2 (0x00007f)
/m/libEGL_mesa.so.0: error while loading shared libraries: libLLVM.so.22.1: cannot open shared object file: No such file or directory
";
        let found = missing(text);
        assert_eq!(
            grouped(&found),
            "libm.so.6 lacks GLIBC_2.43 (by libgallium-26.2.6-1.so); libLLVM.so.22.1 is not found (by libEGL_mesa.so.0)"
        );
        assert!(missing("\tlibz.so.1 => /lib/libz.so.1 (0x1)\n").is_empty());
    }

    #[test]
    fn the_highest_glibc_version_is_read_from_the_bytes() {
        let bytes = b"\0GLIBC_2.2.5\0GLIBC_2.36\0GLIBC_PRIVATE\0GLIBC_2.4\0";
        assert_eq!(highest_glibc(bytes).as_deref(), Some("2.36"));
        assert_eq!(highest_glibc(b"nothing"), None);
        // This process's own C library has a version.
        assert!(machine_glibc().is_some_and(|v| v.starts_with("2.")));
    }

    #[test]
    fn only_a_loader_is_taken_for_one() {
        assert!(is_loader(Path::new("/x/ld-linux-x86-64.so.2")));
        assert!(!is_loader(Path::new("/x/umbra")));
    }
}
