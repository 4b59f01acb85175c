//! The system packages the GPU backends need (docs/platform.md): Mesa's EGL, GL and GLES
//! drivers (llvmpipe, softpipe, zink) and its Vulkan drivers (lavapipe). Installed with apt when
//! missing, if this process may (root, or passwordless sudo); otherwise the exact command is
//! printed and the run goes on: backends that need a missing package report a skip that names
//! it.

use std::process::{Command, Stdio};

/// The packages, as docs/platform.md lists them.
pub const PACKAGES: &[&str] = &[
    "libegl1",
    "libegl-mesa0",
    "libgl1-mesa-dri",
    "libgles2",
    "mesa-vulkan-drivers",
    "libvulkan1",
];

/// What the test suite needs beyond the backends: a real browser for report.html's test
/// (`umbra-report/tests/gallery_browser.rs`); a C compiler, EGL's headers and link library,
/// and apitrace for `umbra repro`'s test (`umbra-runner/tests/repro.rs`: the bundle's
/// `repro.c` is compiled with `cc … -lEGL`, and its capture replayed with eglretrace).
pub const TEST_PACKAGES: &[&str] = &["chromium", "gcc", "libegl-dev", "apitrace"];

/// Installs the Mesa packages that are missing, when allowed; never fails the caller.
pub fn ensure() {
    ensure_packages(PACKAGES, "Mesa packages", "GPU backends will be skipped");
}

/// Installs the packages the tests need that are missing, when allowed.
pub fn ensure_test_tools() {
    ensure_packages(
        TEST_PACKAGES,
        "test packages",
        "the report's browser test will fail until they are installed",
    );
}

/// Installs what is missing of `packages`, when allowed; never fails the caller. `what` names
/// them and `otherwise` says what happens without them.
fn ensure_packages(packages: &[&str], what: &str, otherwise: &str) {
    if std::env::var_os("UMBRA_SKIP_APT").is_some() {
        return;
    }
    let Some(missing) = missing(packages) else {
        eprintln!(
            "note: dpkg-query is not available; install the equivalents of {} yourself",
            packages.join(" ")
        );
        return;
    };
    if missing.is_empty() {
        return;
    }
    let install = format!(
        "apt-get install -y --no-install-recommends {}",
        missing.join(" ")
    );
    let prefix = if is_root() {
        Some("")
    } else if sudo_without_password() {
        Some("sudo ")
    } else {
        None
    };
    let Some(prefix) = prefix else {
        eprintln!(
            "note: missing {what} ({}); {otherwise}. Install them with:\n  sudo apt-get update && sudo {install}",
            missing.join(", ")
        );
        return;
    };
    eprintln!("installing missing {what}: {}", missing.join(" "));
    let script =
        format!("{prefix}apt-get update -qq && DEBIAN_FRONTEND=noninteractive {prefix}{install}");
    match Command::new("sh").args(["-c", &script]).status() {
        Ok(s) if s.success() => {}
        Ok(s) => eprintln!("warning: `{script}` exited with {s}; {otherwise}"),
        Err(e) => eprintln!("warning: cannot run `{script}`: {e}"),
    }
}

fn missing<'a>(packages: &[&'a str]) -> Option<Vec<&'a str>> {
    let mut out = Vec::new();
    for p in packages {
        let o = Command::new("dpkg-query")
            .args(["-W", "-f=${Status}", p])
            .stderr(Stdio::null())
            .output()
            .ok()?;
        if !String::from_utf8_lossy(&o.stdout).contains("install ok installed") {
            out.push(*p);
        }
    }
    Some(out)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

fn sudo_without_password() -> bool {
    Command::new("sudo")
        .args(["-n", "true"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}
