//! `cargo xtask fetch-mesa [--suite SUITE] [--dir DIR]`: any Debian suite's Mesa, beside the
//! system's and without changing it, for `--mesa DIR` (docs/platform.md, last section;
//! docs/platform.md, "Current Mesa on this machine kind").
//!
//! apt is pointed at the one suite through a private sources list, lists directory, cache and
//! an empty dpkg status (`-o Dir::Etc::sourcelist=…`), so the system's apt configuration and
//! state are not changed and the suite's own versions are the candidates. The mirror is the
//! system's (from /etc/apt), so a snapshot mirror stays a snapshot; its Release files may have
//! expired, so `Acquire::Check-Valid-Until` is off (the signatures are still checked).
//!
//! **Which packages.** A suite whose C library is no newer than the machine's (bookworm-
//! backports on Debian 12) needs only Mesa's own packages ([`PACKAGES`]): the machine's
//! libraries serve the rest. A newer one (trixie: glibc 2.41, sid: 2.43, with LLVM 19 or
//! 22) links against libraries the machine does not have in those versions, so the whole
//! dependency closure of Mesa and the GL/Vulkan loaders ([`LOADERS`]) is unpacked, the
//! suite's glibc and dynamic loader included; umbra then starts the build's driver processes
//! through that loader (`umbra_runner::harness::own_libc`). No chroot, so no root: apt's
//! download and `dpkg-deb -x` run as any user.
//!
//! **What it leaves.** DIR (default `target/mesa/SUITE`) holds the unpacked packages and
//! `umbra-mesa.json` (suite, Mesa and glibc versions, every package with its version), which
//! `--mesa DIR` reports in drivers.txt. The new tree is unpacked beside the old one and
//! renamed into place, so an interrupted fetch (or a full disk) never leaves a half build
//! under DIR; a fetch that finds the same package versions already there does nothing; a
//! second fetch of the same suite while one runs is refused with the first one's pid.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The packages that make a complete Mesa for umbra's drivers (docs/platform.md): EGL (glvnd
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

/// The loaders a process on a suite's own C library needs from that suite too: glvnd's EGL
/// and GLES dispatch, and the Vulkan loader.
pub const LOADERS: &[&str] = &["libegl1", "libglvnd0", "libgles2", "libvulkan1"];

/// The file the fetch writes at DIR's root (`umbra_runner::harness::mesa_build::FETCHED`).
const FETCHED: &str = "umbra-mesa.json";

/// The mirror the system's apt uses for Debian (deb822 or one-line format), unless
/// `UMBRA_DEBIAN_MIRROR` names another (a local mirror or proxy).
fn mirror() -> String {
    if let Some(m) = std::env::var("UMBRA_DEBIAN_MIRROR")
        .ok()
        .filter(|m| !m.is_empty())
    {
        return m;
    }
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

/// apt with a private configuration for one suite.
struct Apt {
    /// The private state: sources list, lists, cache, empty status, downloaded packages.
    dir: PathBuf,
    /// The suite whose versions are preferred.
    suite: String,
}

impl Apt {
    fn new(dir: PathBuf, suite: &str) -> Result<Apt, String> {
        for d in [
            dir.join("lists").join("partial"),
            dir.join("cache").join("archives").join("partial"),
            dir.join("debs"),
            dir.join("sources.list.d"),
            dir.join("preferences.d"),
        ] {
            std::fs::create_dir_all(&d)
                .map_err(|e| format!("cannot create {}: {e}", d.display()))?;
        }
        // A backports suite holds only the backported packages: what they link against comes
        // from its base suite (trixie for trixie-backports), with the backports preferred
        // (APT::Default-Release).
        let mirror = mirror();
        let mut line = String::new();
        for s in std::iter::once(suite).chain(suite.strip_suffix("-backports")) {
            line.push_str(&format!(
                "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] {mirror} {s} main\n"
            ));
        }
        std::fs::write(dir.join("sources.list"), &line)
            .and_then(|()| std::fs::write(dir.join("status"), ""))
            .map_err(|e| format!("cannot write under {}: {e}", dir.display()))?;
        for l in line.lines() {
            println!("fetch-mesa: {l}");
        }
        Ok(Apt {
            dir,
            suite: suite.to_string(),
        })
    }

    /// `program` (apt-get or apt-cache) with the private configuration.
    fn command(&self, program: &str) -> Command {
        let mut cmd = Command::new(program);
        // apt's own state, each a path under the private directory. The preferences are
        // private too: the system's pins would choose other versions than the suite's own.
        for (option, path) in [
            ("Dir::Etc::sourcelist", "sources.list"),
            ("Dir::Etc::sourceparts", "sources.list.d"),
            ("Dir::State::Lists", "lists"),
            ("Dir::State::status", "status"),
            ("Dir::Etc::preferences", "preferences"),
            ("Dir::Etc::preferencesparts", "preferences.d"),
            ("Dir::Cache", "cache"),
        ] {
            cmd.arg("-o")
                .arg(format!("{option}={}", self.dir.join(path).display()));
        }
        for option in [
            "Debug::NoLocking=1".to_string(),
            // A snapshot mirror's Release files carry a Valid-Until long past.
            "Acquire::Check-Valid-Until=false".to_string(),
            // As root apt would hand downloads to the _apt user, who cannot write here.
            "APT::Sandbox::User=root".to_string(),
            format!("APT::Default-Release={}", self.suite),
        ] {
            cmd.arg("-o").arg(option);
        }
        cmd
    }

    fn output(&self, program: &str, args: &[&str]) -> Result<String, String> {
        let o = self
            .command(program)
            .args(args)
            .output()
            .map_err(|e| format!("cannot run {program}: {e}"))?;
        if !o.status.success() {
            return Err(format!(
                "{program} {} failed: {}",
                args.join(" "),
                String::from_utf8_lossy(&o.stderr).trim()
            ));
        }
        Ok(String::from_utf8_lossy(&o.stdout).into_owned())
    }

    /// The suite's version of each package (`apt-cache show`).
    fn versions(&self, packages: &[String]) -> Result<Vec<(String, String)>, String> {
        let mut args = vec!["show", "--no-all-versions"];
        args.extend(packages.iter().map(String::as_str));
        Ok(parse_versions(&self.output("apt-cache", &args)?))
    }

    /// The packages `roots` need, recursively (Depends only; virtual packages are left to
    /// the real packages that provide them, which apt lists too).
    fn closure(&self, roots: &[&str]) -> Result<Vec<String>, String> {
        let mut args = vec![
            "depends",
            "--recurse",
            "--no-recommends",
            "--no-suggests",
            "--no-conflicts",
            "--no-breaks",
            "--no-replaces",
            "--no-enhances",
        ];
        args.extend(roots);
        Ok(parse_closure(&self.output("apt-cache", &args)?))
    }
}

/// `(package, version)` of each stanza of `apt-cache show`, sorted.
fn parse_versions(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut name = None;
    for line in text.lines() {
        if let Some(n) = line.strip_prefix("Package: ") {
            name = Some(n.trim().to_string());
        } else if let Some(v) = line.strip_prefix("Version: ") {
            if let Some(n) = name.take() {
                out.push((n, v.trim().to_string()));
            }
        }
    }
    out.sort();
    out.dedup();
    out
}

/// The real packages `apt-cache depends --recurse` lists (its unindented lines; `<virtual>`
/// ones are left to the packages that provide them, which it lists too), sorted.
fn parse_closure(text: &str) -> Vec<String> {
    let mut names: Vec<String> = text
        .lines()
        .filter(|l| !l.starts_with(' ') && !l.starts_with('<') && !l.trim().is_empty())
        .map(|l| l.trim().to_string())
        .collect();
    names.sort();
    names.dedup();
    names
}

/// One fetch of a suite at a time: a lock file made whole, its owner's pid inside, by
/// `link(2)`ing a file already written into place (which fails if the lock is there). A lock
/// directory whose pid was written after it was made let two fetches both run in 3 of 33
/// trials: the second saw the directory before its pid and took it as abandoned. A lock whose
/// process is gone is moved aside under a name of this process's own, and only if what was
/// moved is still that dead process's lock is it discarded; a live one is put back. Removed
/// when dropped, if it is still this process's.
struct Lock(PathBuf);

impl Lock {
    fn take(path: &Path, suite: &str) -> Result<Lock, String> {
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
        }
        let me = std::process::id().to_string();
        let tmp = beside(path, &format!(".{me}"));
        std::fs::write(&tmp, &me).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
        let taken = (|| {
            for _ in 0..3 {
                match std::fs::hard_link(&tmp, path) {
                    Ok(()) => return Ok(Lock(path.to_path_buf())),
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                    Err(e) => return Err(format!("cannot create {}: {e}", path.display())),
                }
                let holder = std::fs::read_to_string(path).unwrap_or_default();
                let holder = holder.trim();
                if holder.is_empty() || Path::new("/proc").join(holder).exists() {
                    return Err(format!(
                        "another fetch-mesa (pid {holder}) is fetching {suite} now; wait for it to end"
                    ));
                }
                // Left by a process that is gone: moved aside, and discarded only if it is.
                let aside = beside(path, &format!(".stale.{me}"));
                if std::fs::rename(path, &aside).is_ok() {
                    let moved = std::fs::read_to_string(&aside).unwrap_or_default();
                    if moved.trim() == holder {
                        let _ = std::fs::remove_file(&aside);
                    } else {
                        let _ = std::fs::rename(&aside, path);
                    }
                }
            }
            Err(format!("cannot take {}", path.display()))
        })();
        let _ = std::fs::remove_file(&tmp);
        taken
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        if std::fs::read_to_string(&self.0)
            .is_ok_and(|p| p.trim() == std::process::id().to_string())
        {
            let _ = std::fs::remove_file(&self.0);
        }
    }
}

/// Whether `suite` is a Debian suite's name as its archive spells them (`sid`, `trixie`,
/// `bookworm-backports`, `stable-updates`): a lower-case letter, then lower-case letters,
/// digits and single `-`, at most 64 bytes. The name becomes a path under `target/mesa` and an
/// apt option, so nothing else (`../../x`, `sid/`, ` `) may pass.
pub fn check_suite(suite: &str) -> Result<(), String> {
    let ok = suite.len() <= 64
        && suite.starts_with(|c: char| c.is_ascii_lowercase())
        && !suite.ends_with('-')
        && !suite.contains("--")
        && suite
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "{suite:?} is not a Debian suite name; fix: give one as Debian spells it (lower-case letters, digits and '-': sid, trixie, bookworm-backports)"
        ))
    }
}

/// What made a fetched tree's directory, in its [`umbra_owned::MARKER`].
const WHAT: &str = "cargo xtask fetch-mesa";

/// `dir` as fetch-mesa may replace it: not there, empty, or made by umbra. A tree fetched
/// before the marker existed is recognised by its [`FETCHED`] record and marked now.
fn own_target(dir: &Path) -> Result<(), String> {
    let before_marker = !umbra_owned::owned(dir)
        && std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir())
        && std::fs::symlink_metadata(dir.join(FETCHED)).is_ok_and(|m| m.is_file());
    if before_marker {
        umbra_owned::mark(dir, WHAT).map_err(|e| format!("cannot mark {}: {e}", dir.display()))?;
    }
    umbra_owned::claim(dir, WHAT).map_err(|e| format!("--dir: {e}"))
}

/// Whether Debian version `a` is newer than `b` (`dpkg --compare-versions`).
fn newer(a: &str, b: &str) -> bool {
    Command::new("dpkg")
        .args(["--compare-versions", a, "gt", b])
        .status()
        .is_ok_and(|s| s.success())
}

/// Whether the machine has package `name` installed (for its architecture).
fn installed(name: &str) -> bool {
    Command::new("dpkg-query")
        .args(["-W", "-f=${Status}", name])
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains("install ok installed"))
}

/// The machine's C library version (dpkg's libc6), if dpkg knows it.
fn machine_libc() -> Option<String> {
    let o = Command::new("dpkg-query")
        .args(["-W", "-f=${Version}", "libc6"])
        .output()
        .ok()?;
    let v = String::from_utf8_lossy(&o.stdout).trim().to_string();
    (o.status.success() && !v.is_empty()).then_some(v)
}

/// Runs the command; returns the exit code.
pub fn main(suite: &str, dir: Option<PathBuf>, root: &Path) -> i32 {
    match fetch(suite, dir, root) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: fetch-mesa --suite {suite}: {e}");
            125
        }
    }
}

fn fetch(suite: &str, dir: Option<PathBuf>, root: &Path) -> Result<(), String> {
    let started = Instant::now();
    check_suite(suite)?;
    let mesa_dir = root.join("target").join("mesa");
    let dir = dir.unwrap_or_else(|| mesa_dir.join(suite));
    let _lock = Lock::take(&mesa_dir.join(format!(".{suite}.lock")), suite)?;
    own_target(&dir)?;
    let apt = Apt::new(mesa_dir.join(".apt").join(suite), suite)?;
    update(&apt, suite)?;
    let (own_libc, names) = packages_to_unpack(&apt, suite)?;
    let versions = suite_versions(&apt, suite, &names)?;
    let mesa = versions
        .iter()
        .find(|(p, _)| p == "mesa-libgallium" || p == "libegl-mesa0")
        .map(|(_, v)| v.clone())
        .unwrap_or_default();
    let packages: Vec<String> = versions.iter().map(|(p, v)| format!("{p}={v}")).collect();
    let record = serde_json::json!({
        "suite": suite,
        "mesa": mesa,
        "own_libc": own_libc,
        "packages": packages,
    });
    if std::fs::read_to_string(dir.join(FETCHED))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .is_some_and(|old| old == record)
    {
        println!(
            "fetch-mesa: Mesa {mesa} from {suite} is already in {} (the same {} packages); use it with --mesa {}",
            dir.display(),
            packages.len(),
            dir.display()
        );
        return Ok(());
    }
    let debs = download(&apt, suite, &packages)?;
    // This process's own staging directory: two fetches into one DIR never share it.
    let partial = beside(&dir, &format!(".partial.{}", std::process::id()));
    let (unpacked, downloaded) = unpack(&debs, &partial)?;
    let text = serde_json::to_string_pretty(&record).unwrap_or_default() + "\n";
    std::fs::write(partial.join(FETCHED), text)
        .map_err(|e| format!("cannot write {}: {e}", partial.join(FETCHED).display()))?;
    replace(&dir, &partial)?;
    println!(
        "fetch-mesa: Mesa {mesa} from {suite}: {} packages ({:.0} MB downloaded){} unpacked in {} in {:.0} s\nfetch-mesa: use it with --mesa {} (e.g. cargo xtask conformance --mesa {}, cargo xtask drivers --baseline system --candidate {})",
        unpacked,
        downloaded as f64 / 1e6,
        own_libc
            .as_deref()
            .map(|v| format!(", its own glibc {v},"))
            .unwrap_or_default(),
        dir.display(),
        started.elapsed().as_secs_f64(),
        dir.display(),
        dir.display(),
        dir.display()
    );
    Ok(())
}

/// `apt-get update` of the private list. apt reports a mirror it cannot reach as a warning
/// and may still exit 0, and the fetch then ended on apt-cache's "'sid' is invalid for
/// APT::Default-Release"; so the update must leave the suite's Release file in the lists, and
/// an update that does not says the mirror could not be reached, with apt's own words.
fn update(apt: &Apt, suite: &str) -> Result<(), String> {
    let o = apt
        .command("apt-get")
        .args(["-q", "update"])
        .output()
        .map_err(|e| format!("cannot run apt-get: {e}; fix: run on a Debian machine with apt"))?;
    let text =
        String::from_utf8_lossy(&o.stderr).into_owned() + &String::from_utf8_lossy(&o.stdout);
    let said: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("W:") || l.starts_with("E:") || l.starts_with("Err:"))
        .collect();
    // apt names a list file after its URI without the scheme, `/` as `_`: the Release file
    // of this mirror's suite, not one a fetch from another mirror left.
    let uri = mirror();
    let stem = uri
        .split_once("://")
        .map_or(uri.as_str(), |(_, rest)| rest)
        .trim_end_matches('/')
        .replace('/', "_");
    let fetched = ["InRelease", "Release"].iter().any(|f| {
        apt.dir
            .join("lists")
            .join(format!("{stem}_dists_{suite}_{f}"))
            .is_file()
    });
    let unreachable = said.iter().any(|l| {
        [
            "Could not resolve",
            "Temporary failure resolving",
            "Could not connect",
            "Failed to fetch",
            "Connection failed",
            "Network is unreachable",
        ]
        .iter()
        .any(|w| l.contains(w))
    });
    if fetched && o.status.success() && !unreachable {
        return Ok(());
    }
    let apt_said = if said.is_empty() {
        String::new()
    } else {
        format!(" (apt: {})", said.join(" | "))
    };
    if unreachable
        || !fetched
            && said
                .iter()
                .all(|l| !l.contains("does not have a Release file"))
    {
        return Err(format!(
            "the mirror {uri} could not be reached for suite {suite:?}: apt-get update fetched no Release file{apt_said}; fix: check this machine's network and its apt mirror, or skip current Mesa (UMBRA_SKIP_CURRENT_MESA=1 for cargo xtask test)"
        ));
    }
    Err(format!(
        "apt-get update of the private list failed{apt_said}; fix: check that the mirror serves suite {suite:?} ({}/sources.list)",
        apt.dir.display()
    ))
}

/// Whether Mesa needs the suite's own C library (its version, when so), and the packages to
/// unpack: the whole closure of Mesa and the loaders then, else Mesa's own packages and what
/// they link against that this machine lacks.
fn packages_to_unpack(apt: &Apt, suite: &str) -> Result<(Option<String>, Vec<String>), String> {
    let libc = apt
        .versions(&["libc6".to_string()])?
        .into_iter()
        .next()
        .map(|(_, v)| v);
    let machine = machine_libc();
    let own_libc = match (&libc, &machine) {
        (Some(s), Some(m)) => newer(s, m).then(|| s.clone()),
        // No dpkg to ask: carry the suite's C library to be safe.
        (Some(s), None) => Some(s.clone()),
        (None, _) => None,
    };
    let names: Vec<String> = match &own_libc {
        Some(v) => {
            println!(
                "fetch-mesa: {suite}'s C library (libc6 {v}) is newer than this machine's ({}): unpacking Mesa with everything it links against, the suite's glibc and loader included",
                machine.as_deref().unwrap_or("unknown")
            );
            let roots: Vec<&str> = PACKAGES.iter().chain(LOADERS).copied().collect();
            apt.closure(&roots)?
        }
        // Mesa's own packages, and whatever else they link against that this machine lacks
        // (a newer LLVM, say): the machine's libraries serve the rest.
        None => {
            let mut names: Vec<String> = PACKAGES.iter().map(|p| p.to_string()).collect();
            let lacking: Vec<String> = apt
                .closure(PACKAGES)?
                .into_iter()
                .filter(|p| !names.contains(p) && !installed(p))
                .collect();
            if !lacking.is_empty() {
                println!(
                    "fetch-mesa: this machine lacks {} of what {suite}'s Mesa links against: unpacked too",
                    lacking.join(", ")
                );
            }
            names.extend(lacking);
            names
        }
    };
    Ok((own_libc, names))
}

/// The suite's version of each of `names`; an error names those the suite does not carry.
fn suite_versions(
    apt: &Apt,
    suite: &str,
    names: &[String],
) -> Result<Vec<(String, String)>, String> {
    let versions = apt.versions(names)?;
    let missing: Vec<&String> = names
        .iter()
        .filter(|n| !versions.iter().any(|(p, _)| p == *n))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "suite {suite} does not carry {}; fix: choose a suite that has Mesa's packages (bookworm-backports, trixie, sid)",
            missing
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok(versions)
}

/// `apt-get download` of `packages` (`NAME=VERSION`) into a fresh `debs` directory of the
/// private state, which it returns.
fn download(apt: &Apt, suite: &str, packages: &[String]) -> Result<PathBuf, String> {
    let debs = apt.dir.join("debs");
    let _ = std::fs::remove_dir_all(&debs);
    std::fs::create_dir_all(&debs).map_err(|e| format!("cannot create {}: {e}", debs.display()))?;
    let downloaded = apt
        .command("apt-get")
        .args(["-qq", "download"])
        .args(packages)
        .current_dir(&debs)
        .status()
        .map_err(|e| format!("cannot run apt-get: {e}"))?;
    if !downloaded.success() {
        return Err(format!(
            "apt-get download failed for {} packages of {suite}",
            packages.len()
        ));
    }
    Ok(debs)
}

/// The path beside `dir`, named after it with `suffix` (DIR.partial, DIR.old), whatever dots
/// its name has.
fn beside(dir: &Path, suffix: &str) -> PathBuf {
    let mut name = dir.file_name().unwrap_or_default().to_os_string();
    name.push(suffix);
    dir.with_file_name(name)
}

/// Every `.deb` in `debs` unpacked (`dpkg-deb -x`, in name order) into a fresh `partial`:
/// how many packages, and their bytes downloaded.
fn unpack(debs: &Path, partial: &Path) -> Result<(usize, u64), String> {
    umbra_owned::fresh(partial, WHAT).map_err(|e| e.to_string())?;
    let mut downloaded = 0u64;
    let mut files: Vec<PathBuf> = std::fs::read_dir(debs)
        .map_err(|e| format!("cannot read {}: {e}", debs.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "deb"))
        .collect();
    files.sort();
    for p in &files {
        downloaded += std::fs::metadata(p).map_or(0, |m| m.len());
        let ok = Command::new("dpkg-deb")
            .arg("-x")
            .arg(p)
            .arg(partial)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            return Err(format!("dpkg-deb -x {} failed", p.display()));
        }
    }
    Ok((files.len(), downloaded))
}

/// The new tree `partial` moved into place as `dir`, the old one (if any) set aside as
/// DIR.old until then.
fn replace(dir: &Path, partial: &Path) -> Result<(), String> {
    // The old tree moves aside only once the new one is whole; a fetch that died between
    // the two renames left DIR.old as the only whole build, and it stays until this one is
    // in place.
    // Only trees umbra made are moved or removed ([`own_target`] claimed `dir`).
    let old = beside(dir, ".old");
    umbra_owned::remove(&old).map_err(|e| e.to_string())?;
    if dir.exists() {
        std::fs::rename(dir, &old).map_err(|e| format!("cannot move {}: {e}", dir.display()))?;
    }
    std::fs::rename(partial, dir)
        .map_err(|e| format!("cannot move {} into place: {e}", partial.display()))?;
    umbra_owned::remove(&old).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrity round three: two fetches of one suite both ran in 3 of 33 trials (a lock
    /// directory whose pid was not yet written read as abandoned). The kernel's lock is
    /// taken whole or not at all: a second taker is refused, naming the first, while the
    /// first holds it, and gets it once the first lets go.
    #[test]
    fn a_second_fetch_of_one_suite_is_refused_while_the_first_runs() {
        let dir = std::env::temp_dir().join(format!("umbra-fetch-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join(".sid.lock");
        for _ in 0..50 {
            let first = Lock::take(&path, "sid").expect("the first fetch takes it");
            let e = Lock::take(&path, "sid")
                .err()
                .expect("the second is refused");
            assert!(
                e.contains(&format!("pid {}", std::process::id())) && e.contains("is fetching sid"),
                "{e}"
            );
            drop(first);
        }
        Lock::take(&path, "sid").expect("free again");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn suite_names_follow_debians_grammar() {
        for ok in [
            "sid",
            "trixie",
            "bookworm-backports",
            "stable-updates",
            "trixie-proposed-updates",
        ] {
            assert!(check_suite(ok).is_ok(), "{ok}");
        }
        for bad in [
            "",
            "../../../../x",
            "sid/",
            "Sid",
            "-sid",
            "sid-",
            "a--b",
            "sid x",
            "a.b",
            &"x".repeat(65),
        ] {
            let e = check_suite(bad).expect_err(bad);
            assert!(e.contains("not a Debian suite name"), "{e}");
        }
    }

    /// Each fetch stages in a directory of its own (`DIR.partial.PID`), so two never share
    /// one; and a directory umbra did not make is never replaced.
    #[test]
    fn staging_is_per_process_and_a_users_dir_is_refused() {
        let root = std::env::temp_dir().join(format!("umbra-fetch-dir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let dir = root.join("sid");
        let a = beside(&dir, &format!(".partial.{}", 1));
        let b = beside(&dir, &format!(".partial.{}", 2));
        assert_ne!(a, b);
        std::fs::create_dir_all(&dir).expect("mkdir");
        std::fs::write(dir.join("precious.txt"), "p").expect("write");
        let e = own_target(&dir).expect_err("a user's directory");
        assert!(e.contains("--dir") && e.contains("did not write"), "{e}");
        assert!(dir.join("precious.txt").exists());
        // A tree fetched before the marker existed is recognised by its record.
        let old = root.join("old");
        std::fs::create_dir_all(&old).expect("mkdir");
        std::fs::write(old.join(FETCHED), "{}").expect("write");
        own_target(&old).expect("fetch-mesa's own tree");
        assert!(umbra_owned::owned(&old));
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn apt_cache_output_is_read_stanza_by_stanza() {
        // A field between Package and Version (Source) once lost every version.
        let show = "Package: libc6\nSource: glibc\nVersion: 2.43-7\n\nPackage: mesa-libgallium\nSource: mesa\nVersion: 26.2.6-1\n";
        assert_eq!(
            parse_versions(show),
            vec![
                ("libc6".to_string(), "2.43-7".to_string()),
                ("mesa-libgallium".to_string(), "26.2.6-1".to_string()),
            ]
        );
        let depends = "libegl-mesa0\n  Depends: libc6\n  |Depends: libx\nlibc6\n  Depends: libgcc-s1\n<libgl-provider>\nlibgcc-s1\n";
        assert_eq!(
            parse_closure(depends),
            vec!["libc6", "libegl-mesa0", "libgcc-s1"]
        );
    }
}
