//! How EGL reaches the driver: Mesa's surfaceless platform (EGL_MESA_platform_surfaceless),
//! or an EGL device (EGL_EXT_platform_device over EGL_EXT_device_enumeration), which is what
//! EGL implementations without the surfaceless platform offer (NVIDIA's, docs/platform.md) and
//! how a machine's render nodes are reached one by one.
//!
//! The choice is made once per process: `UMBRA_EGL_PLATFORM=surfaceless|device|device:N`, or
//! by default surfaceless where the client extensions offer it and the first device
//! otherwise. Both are probed, not assumed: a platform the EGL library lacks is an
//! [`Unavailable`] naming the missing extension.

use std::ffi::c_void;

use khronos_egl as egl;

/// Why a context could not be made: always a reason a person can act on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unavailable(pub String);

/// Loads libEGL (1.5), or says which packages to install.
pub fn load_egl() -> Result<egl::DynamicInstance<egl::EGL1_5>, Unavailable> {
    // SAFETY: loading libEGL runs its initialisers; it is the system's EGL library.
    unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }.map_err(|e| {
        Unavailable(format!(
            "cannot load libEGL 1.5 ({e}); install the Debian packages libegl1 and libegl-mesa0"
        ))
    })
}

/// `EGL_PLATFORM_SURFACELESS_MESA`.
pub const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;
/// `EGL_PLATFORM_DEVICE_EXT`.
pub const PLATFORM_DEVICE_EXT: egl::Enum = 0x313F;
/// `EGL_DRM_DEVICE_FILE_EXT`.
const DRM_DEVICE_FILE_EXT: egl::Int = 0x3233;
/// `EGL_DRM_RENDER_NODE_FILE_EXT`.
const DRM_RENDER_NODE_FILE_EXT: egl::Int = 0x3377;

/// The environment variable that chooses the platform.
pub const ENV: &str = "UMBRA_EGL_PLATFORM";

/// How EGL reaches the driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Platform {
    /// Mesa's surfaceless platform: no device named, the driver chosen by Mesa's variables.
    Surfaceless,
    /// The EGL device of this index in `eglQueryDevicesEXT`'s list.
    Device(usize),
}

/// One EGL device, as `eglQueryDeviceStringEXT` describes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EglDevice {
    /// Its index in `eglQueryDevicesEXT`'s list.
    pub index: usize,
    /// Its device extensions.
    pub extensions: String,
    /// Its DRM primary node, when it has one (EGL_EXT_device_drm).
    pub drm_device: Option<String>,
    /// Its DRM render node, when it has one (EGL_EXT_device_drm_render_node).
    pub render_node: Option<String>,
}

impl EglDevice {
    /// Mesa's software device (EGL_MESA_device_software): llvmpipe or softpipe.
    pub fn software(&self) -> bool {
        self.extensions
            .split_whitespace()
            .any(|e| e == "EGL_MESA_device_software")
    }

    /// The PCI vendor and device ids of its DRM node (`0x10de:0x2330`), read from sysfs
    /// (`/sys/class/drm/NODE/device/{vendor,device}`); None for a device without a node
    /// (Mesa's software device) or where sysfs does not say.
    pub fn pci_id(&self) -> Option<String> {
        let node = self.render_node.as_ref().or(self.drm_device.as_ref())?;
        let name = std::path::Path::new(node).file_name()?.to_str()?;
        let read = |f: &str| {
            std::fs::read_to_string(format!("/sys/class/drm/{name}/device/{f}"))
                .ok()
                .map(|s| s.trim().to_string())
        };
        Some(format!("{}:{}", read("vendor")?, read("device")?))
    }

    /// How it is reached, in words, with its PCI id where it has one.
    pub fn describe_with_pci(&self) -> String {
        match self.pci_id() {
            Some(pci) => format!("{}, PCI {pci}", self.describe()),
            None => self.describe(),
        }
    }

    /// How it is reached, in words.
    pub fn describe(&self) -> String {
        match (&self.render_node, &self.drm_device, self.software()) {
            (Some(n), _, _) => format!("EGL device {} ({n})", self.index),
            (None, Some(d), _) => format!("EGL device {} ({d})", self.index),
            (None, None, true) => format!("EGL device {} (Mesa's software device)", self.index),
            (None, None, false) => format!("EGL device {}", self.index),
        }
    }
}

type QueryDevices =
    unsafe extern "system" fn(egl::Int, *mut *mut c_void, *mut egl::Int) -> egl::Boolean;
type QueryDeviceString =
    unsafe extern "system" fn(*mut c_void, egl::Int) -> *const std::ffi::c_char;

/// EGL's client extensions (EGL_EXT_client_extensions), empty where it has none.
pub fn client_extensions(egl: &egl::DynamicInstance<egl::EGL1_5>) -> String {
    egl.query_string(None, egl::EXTENSIONS)
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn has(extensions: &str, name: &str) -> bool {
    extensions.split_whitespace().any(|e| e == name)
}

impl Platform {
    /// The platform this process uses: `UMBRA_EGL_PLATFORM`, else surfaceless where the
    /// client extensions offer it, else the first device.
    pub fn choose(egl: &egl::DynamicInstance<egl::EGL1_5>) -> Result<Platform, Unavailable> {
        let client = client_extensions(egl);
        match std::env::var(ENV).ok().as_deref() {
            None | Some("") => Ok(if has(&client, "EGL_MESA_platform_surfaceless") {
                Platform::Surfaceless
            } else {
                Platform::Device(0)
            }),
            Some("surfaceless") => Ok(Platform::Surfaceless),
            Some("device") => Ok(Platform::Device(0)),
            Some(v) => v
                .strip_prefix("device:")
                .and_then(|n| n.parse().ok())
                .map(Platform::Device)
                .ok_or_else(|| {
                    Unavailable(format!(
                        "{ENV}={v:?}: give surfaceless, device (the first EGL device) or device:N"
                    ))
                }),
        }
    }

    /// The display of this platform.
    pub fn display(
        self,
        egl: &egl::DynamicInstance<egl::EGL1_5>,
    ) -> Result<(egl::Display, Option<EglDevice>), Unavailable> {
        match self {
            Platform::Surfaceless => {
                // SAFETY: the surfaceless platform takes the default (null) native display.
                let d = unsafe {
                    egl.get_platform_display(
                        PLATFORM_SURFACELESS_MESA,
                        egl::DEFAULT_DISPLAY,
                        &[egl::ATTRIB_NONE],
                    )
                }
                .map_err(|e| Unavailable(format!("no surfaceless EGL display ({e}); install libegl-mesa0 (Mesa's EGL) and libgl1-mesa-dri, or set {ENV}=device where the EGL library offers devices instead")))?;
                Ok((d, None))
            }
            Platform::Device(index) => {
                if !has(&client_extensions(egl), "EGL_EXT_platform_device") {
                    return Err(Unavailable(
                        "this EGL library lacks EGL_EXT_platform_device: no display on a device"
                            .into(),
                    ));
                }
                let devices = devices(egl)?;
                let Some((device, handle)) = devices.into_iter().nth(index) else {
                    return Err(Unavailable(format!(
                        "{ENV}: there is no EGL device {index} (`umbra backends` lists them)"
                    )));
                };
                // SAFETY: an EGLDeviceEXT handle from eglQueryDevicesEXT, valid for the
                // process's lifetime.
                let d = unsafe {
                    egl.get_platform_display(PLATFORM_DEVICE_EXT, handle, &[egl::ATTRIB_NONE])
                }
                .map_err(|e| {
                    Unavailable(format!("no EGL display on {} ({e})", device.describe()))
                })?;
                Ok((d, Some(device)))
            }
        }
    }
}

/// Every EGL device, with its handle; Unavailable where EGL has no device enumeration.
pub fn devices(
    egl: &egl::DynamicInstance<egl::EGL1_5>,
) -> Result<Vec<(EglDevice, *mut c_void)>, Unavailable> {
    let client = client_extensions(egl);
    if !(has(&client, "EGL_EXT_device_enumeration") || has(&client, "EGL_EXT_device_base")) {
        return Err(Unavailable(
            "this EGL library lacks EGL_EXT_device_enumeration: no EGL devices to list".into(),
        ));
    }
    let (Some(query), Some(string)) = (
        egl.get_proc_address("eglQueryDevicesEXT"),
        egl.get_proc_address("eglQueryDeviceStringEXT"),
    ) else {
        return Err(Unavailable(
            "eglQueryDevicesEXT or eglQueryDeviceStringEXT is missing".into(),
        ));
    };
    // SAFETY: the entry points EGL returned for these names, with their EGL signatures.
    let (query, string) = unsafe {
        (
            std::mem::transmute::<extern "system" fn(), QueryDevices>(query),
            std::mem::transmute::<extern "system" fn(), QueryDeviceString>(string),
        )
    };
    let mut n: egl::Int = 0;
    // SAFETY: a count query (null list), then a list of that many handles.
    let handles = unsafe {
        if query(0, std::ptr::null_mut(), &mut n) == egl::FALSE || n <= 0 {
            return Ok(Vec::new());
        }
        let mut handles = vec![std::ptr::null_mut(); n as usize];
        if query(n, handles.as_mut_ptr(), &mut n) == egl::FALSE {
            return Err(Unavailable("eglQueryDevicesEXT failed".into()));
        }
        handles.truncate(n.max(0) as usize);
        handles
    };
    let text = |h: *mut c_void, name: egl::Int| -> Option<String> {
        // SAFETY: a device handle from the list; EGL returns a static string or null.
        let p = unsafe { string(h, name) };
        (!p.is_null())
            // SAFETY: a NUL-terminated string EGL owns.
            .then(|| {
                unsafe { std::ffi::CStr::from_ptr(p) }
                    .to_string_lossy()
                    .into_owned()
            })
    };
    Ok(handles
        .into_iter()
        .enumerate()
        .map(|(index, h)| {
            let extensions = text(h, egl::EXTENSIONS).unwrap_or_default();
            let drm_device = has(&extensions, "EGL_EXT_device_drm")
                .then(|| text(h, DRM_DEVICE_FILE_EXT))
                .flatten();
            let render_node = has(&extensions, "EGL_EXT_device_drm_render_node")
                .then(|| text(h, DRM_RENDER_NODE_FILE_EXT))
                .flatten();
            (
                EglDevice {
                    index,
                    extensions,
                    drm_device,
                    render_node,
                },
                h,
            )
        })
        .collect())
}

/// `EGL_MESA_query_driver`'s `eglGetDisplayDriverName`.
type GetDisplayDriverName = unsafe extern "system" fn(egl::EGLDisplay) -> *const std::ffi::c_char;

/// An EGL device with the name its backend ids carry (`gl33/NAME`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NamedDevice {
    /// The device.
    pub device: EglDevice,
    /// Its name in backend ids: the driver's own name, `.2`, `.3` … for a second and third
    /// device of one driver ([`names`]).
    pub name: String,
    /// The display's EGL_VENDOR.
    pub vendor: String,
    /// What `eglGetDisplayDriverName` (EGL_MESA_query_driver) says, where the display has it.
    pub driver: Option<String>,
}

/// The name of a device's driver as backend ids carry it, from what the driver reports:
/// the DRI driver's name where EGL_MESA_query_driver gives one (`radeonsi`, `iris`, `swrast`
/// for Mesa's software device), else the first word of the display's EGL_VENDOR (`nvidia`
/// for "NVIDIA"), lower case, letters, digits, `-` and `_` only.
pub fn driver_slug(driver: Option<&str>, vendor: &str) -> String {
    let raw = match driver {
        Some(d) if !d.trim().is_empty() => d.trim().to_string(),
        _ => vendor
            .split_whitespace()
            .next()
            .unwrap_or("unknown")
            .to_string(),
    };
    umbra_case::BackendId::name_part(&raw)
}

/// A device's name where its driver's name is one of this build's Mesa software ids'
/// (`llvmpipe`, `softpipe`, `zink`, chosen by environment): `zink-device` for zink on a GPU
/// (NVK, or any hardware Vulkan driver Mesa loads zink over), so that `gl33/zink` stays
/// software zink and the GPU keeps an id of its own.
pub fn device_slug(slug: String) -> String {
    if crate::Driver::parse(&slug).is_some() {
        format!("{slug}-device")
    } else {
        slug
    }
}

/// Names for devices whose driver slugs are `slugs` (in list order), with the keys that
/// order two devices of one driver (their DRM node path, so the names stay with the nodes
/// whatever order EGL lists them in): the first keeps the slug, the next get `.2`, `.3` ….
pub fn names(slugs: &[(String, String)]) -> Vec<String> {
    slugs
        .iter()
        .enumerate()
        .map(|(i, (slug, key))| {
            let before = slugs
                .iter()
                .enumerate()
                .filter(|(j, (s, k))| s == slug && (k, *j) < (key, i))
                .count();
            if before == 0 {
                slug.clone()
            } else {
                format!("{slug}.{}", before + 1)
            }
        })
        .collect()
}

/// Every EGL device with its backend-id name ([`driver_slug`], [`names`]). Each device's
/// display is initialised to ask its driver's name and vendor, then terminated; a device
/// whose display does not initialise is named `unknown` and listed, so that its index still
/// reaches it.
pub fn named_devices(
    egl: &egl::DynamicInstance<egl::EGL1_5>,
) -> Result<Vec<NamedDevice>, Unavailable> {
    let get_name = egl.get_proc_address("eglGetDisplayDriverName");
    let listed = devices(egl)?;
    let mut found = Vec::new();
    for (device, handle) in listed {
        // SAFETY: a device handle from eglQueryDevicesEXT.
        let display =
            unsafe { egl.get_platform_display(PLATFORM_DEVICE_EXT, handle, &[egl::ATTRIB_NONE]) }
                .ok();
        let mut vendor = String::new();
        let mut driver = None;
        if let Some(d) = display.filter(|d| egl.initialize(*d).is_ok()) {
            vendor = egl
                .query_string(Some(d), egl::VENDOR)
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let exts = egl
                .query_string(Some(d), egl::EXTENSIONS)
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if let Some(f) = get_name.filter(|_| has(&exts, "EGL_MESA_query_driver")) {
                // SAFETY: the entry point EGL returned for this name, with its signature
                // (const char *(EGLDisplay)); the display is initialised.
                let p = unsafe {
                    std::mem::transmute::<extern "system" fn(), GetDisplayDriverName>(f)(d.as_ptr())
                };
                if !p.is_null() {
                    // SAFETY: a NUL-terminated string the driver owns.
                    driver = Some(
                        unsafe { std::ffi::CStr::from_ptr(p) }
                            .to_string_lossy()
                            .into_owned(),
                    );
                }
            }
            let _ = egl.terminate(d);
        }
        found.push((device, vendor, driver));
    }
    let keys: Vec<(String, String)> = found
        .iter()
        .map(|(d, v, drv)| {
            (
                device_slug(driver_slug(drv.as_deref(), v)),
                d.render_node
                    .clone()
                    .or_else(|| d.drm_device.clone())
                    .unwrap_or_else(|| format!("~{:04}", d.index)),
            )
        })
        .collect();
    Ok(found
        .into_iter()
        .zip(names(&keys))
        .map(|((device, vendor, driver), name)| NamedDevice {
            device,
            name,
            vendor,
            driver,
        })
        .collect())
}

#[cfg(test)]
mod naming_tests {
    use super::*;

    #[test]
    fn a_driver_names_its_devices_and_two_of_one_driver_stay_apart_by_node() {
        assert_eq!(driver_slug(Some("radeonsi"), "Mesa Project"), "radeonsi");
        assert_eq!(driver_slug(Some("swrast"), "Mesa Project"), "swrast");
        assert_eq!(driver_slug(None, "NVIDIA"), "nvidia");
        assert_eq!(driver_slug(Some(""), "Some Vendor Inc."), "some");
        assert_eq!(driver_slug(None, ""), "unknown");
        // zink over a GPU's Vulkan driver is not this build's software zink.
        assert_eq!(
            device_slug(driver_slug(Some("zink"), "Mesa")),
            "zink-device"
        );
        assert_eq!(device_slug("radeonsi".into()), "radeonsi");
        // Listed out of node order: the names follow the nodes, not the list.
        let keys = [
            ("radeonsi".to_string(), "/dev/dri/renderD129".to_string()),
            ("iris".to_string(), "/dev/dri/renderD130".to_string()),
            ("radeonsi".to_string(), "/dev/dri/renderD128".to_string()),
        ];
        assert_eq!(names(&keys), ["radeonsi.2", "iris", "radeonsi"]);
    }
}
