//! Mesa's hardware drivers, as a `--mesa` build carries them: which backend ids each one
//! serves, what device it needs, and whether this machine has one.
//!
//! A radeonsi, iris, RADV or ANV developer builds Mesa with their driver and runs umbra on
//! it: `--mesa DIR` finds the build's hardware drivers (`dri/radeonsi_dri.so`,
//! `libvulkan_radeon.so`, …) beside its software ones, and the device ids those drivers
//! serve (`gl33/radeonsi`, `wgpu-vk/radv`) then load them from DIR, as the software ids do,
//! with the same check of what was really loaded. Loaders fall back silently; so does a
//! driver whose device is absent, so the device is checked first ([`missing_device`]): a
//! driver the build has but the machine cannot drive is a skip that names the device.
//!
//! The device check reads the kernel's DRM render nodes (`/sys/class/drm/renderD*`): Mesa's
//! loader picks a hardware driver by the kernel driver of the node it opens (`amdgpu` →
//! radeonsi and RADV, `i915`/`xe` → iris, crocus and ANV), so a node bound to one of the
//! driver's kernel drivers is what the driver needs, and nothing less will do.

use std::path::Path;

/// One Mesa hardware driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct HwDriver {
    /// The backend ids' name for it: its DRI driver's name for GL (`radeonsi` in `gl33/radeonsi`,
    /// as EGL_MESA_query_driver reports it), wgpu's for Vulkan (`radv` in `wgpu-vk/radv`).
    pub name: &'static str,
    /// Where the build holds it: `dri/NAME_dri.so` (a GL driver) or the Vulkan ICD library.
    pub file: &'static str,
    /// Whether it is a Vulkan driver (reached through wgpu-vk), else a GL one (EGL devices).
    pub vulkan: bool,
    /// The devices it drives, in words.
    pub device: &'static str,
    /// The kernel DRM drivers whose render nodes it drives.
    pub kernel: &'static [&'static str],
}

const fn gl(
    name: &'static str,
    file: &'static str,
    device: &'static str,
    kernel: &'static [&'static str],
) -> HwDriver {
    HwDriver {
        name,
        file,
        vulkan: false,
        device,
        kernel,
    }
}

const fn vk(
    name: &'static str,
    file: &'static str,
    device: &'static str,
    kernel: &'static [&'static str],
) -> HwDriver {
    HwDriver {
        name,
        file,
        vulkan: true,
        device,
        kernel,
    }
}

const AMD: &[&str] = &["amdgpu", "radeon"];
const INTEL: &[&str] = &["i915", "xe"];

/// Mesa's hardware drivers, by the file a build holds. The Vulkan names are the wgpu-vk
/// ids' names (docs/backends.md, "Device ids": `anv` for Intel's, else the driver's first
/// word).
pub const ALL: &[HwDriver] = &[
    gl(
        "radeonsi",
        "radeonsi_dri.so",
        "an AMD Radeon GPU (GCN or newer)",
        AMD,
    ),
    gl(
        "r600",
        "r600_dri.so",
        "an AMD Radeon HD 2000–6000 GPU",
        &["radeon"],
    ),
    gl(
        "r300",
        "r300_dri.so",
        "an ATI Radeon R300–R500 GPU",
        &["radeon"],
    ),
    gl("iris", "iris_dri.so", "an Intel GPU (Gen8 or newer)", INTEL),
    gl(
        "crocus",
        "crocus_dri.so",
        "an Intel GPU (Gen4–Gen7)",
        &["i915"],
    ),
    gl("i915", "i915_dri.so", "an Intel GMA 3xx GPU", &["i915"]),
    gl(
        "nouveau",
        "nouveau_dri.so",
        "an NVIDIA GPU (nouveau)",
        &["nouveau"],
    ),
    gl(
        "virtio_gpu",
        "virtio_gpu_dri.so",
        "a virtio-gpu device (a virtual machine's virgl)",
        &["virtio_gpu"],
    ),
    gl(
        "vmwgfx",
        "vmwgfx_dri.so",
        "a VMware SVGA device",
        &["vmwgfx"],
    ),
    gl(
        "msm",
        "msm_dri.so",
        "a Qualcomm Adreno GPU (freedreno)",
        &["msm"],
    ),
    gl(
        "panfrost",
        "panfrost_dri.so",
        "an Arm Mali GPU (Midgard or newer)",
        &["panfrost", "panthor"],
    ),
    gl("lima", "lima_dri.so", "an Arm Mali Utgard GPU", &["lima"]),
    gl("v3d", "v3d_dri.so", "a Broadcom VideoCore VI GPU", &["v3d"]),
    gl("vc4", "vc4_dri.so", "a Broadcom VideoCore IV GPU", &["vc4"]),
    gl("etnaviv", "etnaviv_dri.so", "a Vivante GPU", &["etnaviv"]),
    gl("asahi", "asahi_dri.so", "an Apple GPU", &["asahi"]),
    vk(
        "radv",
        "libvulkan_radeon.so",
        "an AMD Radeon GPU (GCN or newer)",
        AMD,
    ),
    vk(
        "anv",
        "libvulkan_intel.so",
        "an Intel GPU (Gen9 or newer)",
        INTEL,
    ),
    vk(
        "hasvk",
        "libvulkan_intel_hasvk.so",
        "an Intel GPU (Gen7 or Gen8)",
        &["i915"],
    ),
    vk(
        "nvk",
        "libvulkan_nouveau.so",
        "an NVIDIA GPU (nouveau)",
        &["nouveau"],
    ),
    vk(
        "turnip",
        "libvulkan_freedreno.so",
        "a Qualcomm Adreno GPU",
        &["msm"],
    ),
    vk(
        "panvk",
        "libvulkan_panfrost.so",
        "an Arm Mali GPU",
        &["panfrost", "panthor"],
    ),
    vk(
        "v3dv",
        "libvulkan_broadcom.so",
        "a Broadcom VideoCore VI GPU",
        &["v3d"],
    ),
    vk(
        "venus",
        "libvulkan_virtio.so",
        "a virtio-gpu device with Venus",
        &["virtio_gpu"],
    ),
    vk(
        "honeykrisp",
        "libvulkan_asahi.so",
        "an Apple GPU",
        &["asahi"],
    ),
];

/// The GL driver a build's `dri/NAME_dri.so` is, if it is a hardware one.
pub fn of_dri(dri_name: &str) -> Option<&'static HwDriver> {
    let file = format!("{dri_name}_dri.so");
    ALL.iter().find(|d| !d.vulkan && d.file == file)
}

/// The Vulkan driver a library file is, if it is one of Mesa's hardware ICDs.
pub fn of_vulkan_lib(file_name: &str) -> Option<&'static HwDriver> {
    ALL.iter().find(|d| d.vulkan && d.file == file_name)
}

/// The hardware driver a device id names (`gl33/radeonsi`, `gles3/iris.2`, `wgpu-vk/radv`),
/// if it is one of Mesa's.
pub fn of_backend_id(id: &str) -> Option<&'static HwDriver> {
    let (api, name) = id.split_once('/')?;
    // A second device of one driver is `NAME.2`.
    let name = name.split_once('.').map_or(name, |(n, _)| n);
    let vulkan = match api {
        "wgpu-vk" => true,
        "gl33" | "gles3" | "gles2" => false,
        _ => return None,
    };
    ALL.iter().find(|d| d.vulkan == vulkan && d.name == name)
}

impl HwDriver {
    /// The backend ids it serves: one per GL API, or wgpu's Vulkan one.
    pub fn backend_ids(&self) -> Vec<String> {
        if self.vulkan {
            vec![format!("wgpu-vk/{}", self.name)]
        } else {
            ["gl33", "gles3", "gles2"]
                .iter()
                .map(|api| format!("{api}/{}", self.name))
                .collect()
        }
    }
}

/// The kernel drivers of this machine's DRM render nodes (`/sys/class/drm/renderD*`).
pub fn render_node_drivers(sys_drm: &Path) -> Vec<String> {
    let Ok(rd) = std::fs::read_dir(sys_drm) else {
        return Vec::new();
    };
    let mut drivers: Vec<String> = rd
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with("renderD"))
        .filter_map(|e| std::fs::read_link(e.path().join("device/driver")).ok())
        .filter_map(|l| l.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    drivers.sort();
    drivers.dedup();
    drivers
}

/// Why `driver` cannot run on this machine (no render node bound to one of its kernel
/// drivers), naming the device it needs and what the machine has; `None` when it has one.
pub fn missing_device(driver: &HwDriver, sys_drm: &Path) -> Option<String> {
    let have = render_node_drivers(sys_drm);
    if have.iter().any(|k| driver.kernel.contains(&k.as_str())) {
        return None;
    }
    Some(format!(
        "this machine has no device for {}: it needs {}, a DRM render node on the {} kernel driver; {} has {}",
        driver.name,
        driver.device,
        driver.kernel.join(" or "),
        sys_drm.display(),
        if have.is_empty() {
            "no render node".to_string()
        } else {
            format!("render nodes on {}", have.join(", "))
        }
    ))
}

/// Where the kernel lists DRM devices.
pub const SYS_DRM: &str = "/sys/class/drm";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_ids_name_their_driver() {
        assert_eq!(
            of_backend_id("gl33/radeonsi").map(|d| d.file),
            Some("radeonsi_dri.so")
        );
        assert_eq!(of_backend_id("gles3/iris.2").map(|d| d.name), Some("iris"));
        assert_eq!(
            of_backend_id("wgpu-vk/radv").map(|d| d.file),
            Some("libvulkan_radeon.so")
        );
        // Not Mesa's, or not a hardware driver: the system's driver answers.
        assert_eq!(of_backend_id("gl33/nvidia"), None);
        assert_eq!(of_backend_id("wgpu-vk/lavapipe"), None);
        assert_eq!(of_backend_id("wgpu-gl/radeonsi"), None);
        assert_eq!(of_dri("swrast"), None);
        assert_eq!(of_dri("zink"), None);
        assert_eq!(of_vulkan_lib("libvulkan_lvp.so"), None);
        assert_eq!(
            of_dri("nouveau")
                .map(HwDriver::backend_ids)
                .unwrap_or_default()
                .len(),
            3
        );
    }

    /// A fake sysfs: one render node on amdgpu serves radeonsi and RADV, not iris.
    #[test]
    fn the_device_check_reads_the_render_nodes_kernel_driver() {
        let sys = std::env::temp_dir().join(format!("umbra-sys-drm-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&sys);
        let none =
            missing_device(of_dri("radeonsi").expect("radeonsi"), &sys).expect("no node: missing");
        assert!(
            none.contains("AMD Radeon") && none.contains("no render node"),
            "{none}"
        );
        let node = sys.join("renderD128/device");
        std::fs::create_dir_all(&node).expect("mkdir");
        std::os::unix::fs::symlink("../../bus/pci/drivers/amdgpu", node.join("driver"))
            .expect("symlink");
        assert_eq!(
            missing_device(of_dri("radeonsi").expect("radeonsi"), &sys),
            None
        );
        assert_eq!(
            missing_device(of_vulkan_lib("libvulkan_radeon.so").expect("radv"), &sys),
            None
        );
        let iris = missing_device(of_dri("iris").expect("iris"), &sys).expect("iris: missing");
        assert!(
            iris.contains("i915 or xe") && iris.contains("render nodes on amdgpu"),
            "{iris}"
        );
        let _ = std::fs::remove_dir_all(&sys);
    }
}
