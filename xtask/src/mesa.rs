//! The system packages the GPU backends need (../shared/PLATFORM.md): Mesa's EGL, GL and GLES
//! drivers (llvmpipe, softpipe, zink) and its Vulkan drivers (lavapipe). Installed with apt when
//! missing, if this process may (root, or passwordless sudo); otherwise the exact command is
//! printed and the run goes on: backends that need a missing package report a skip that names
//! it.

use std::process::{Command, Stdio};

/// The packages, as PLATFORM.md lists them.
pub const PACKAGES: &[&str] = &[
    "libegl1",
    "libegl-mesa0",
    "libgl1-mesa-dri",
    "libgles2",
    "mesa-vulkan-drivers",
    "libvulkan1",
];

/// Installs what is missing, when allowed; never fails the caller.
pub fn ensure() {
    if std::env::var_os("UMBRA_SKIP_APT").is_some() {
        return;
    }
    let Some(missing) = missing() else {
        eprintln!(
            "note: dpkg-query is not available; install the equivalents of {} yourself",
            PACKAGES.join(" ")
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
            "note: missing Mesa packages ({}); GPU backends will be skipped. Install them with:\n  sudo apt-get update && sudo {install}",
            missing.join(", ")
        );
        return;
    };
    eprintln!("installing missing Mesa packages: {}", missing.join(" "));
    let script =
        format!("{prefix}apt-get update -qq && DEBIAN_FRONTEND=noninteractive {prefix}{install}");
    match Command::new("sh").args(["-c", &script]).status() {
        Ok(s) if s.success() => {}
        Ok(s) => eprintln!(
            "warning: `{script}` exited with {s}; GPU backends needing these packages will be skipped"
        ),
        Err(e) => eprintln!("warning: cannot run `{script}`: {e}"),
    }
}

fn missing() -> Option<Vec<&'static str>> {
    let mut out = Vec::new();
    for p in PACKAGES {
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
