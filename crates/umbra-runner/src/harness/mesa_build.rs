//! Driver builds as an input: `--mesa PATH` (or `UMBRA_MESA=PATH`) runs every Mesa-backed
//! backend against the Mesa in PATH instead of the system's.
//!
//! PATH may be an install prefix (`meson install --destdir D` gives `D/usr/...`), a Mesa
//! meson build directory (uninstalled: Mesa's build links `*_dri.so` beside libgallium for
//! `meson devenv`), or Debian packages unpacked with `dpkg -x` (`cargo xtask fetch-mesa`).
//! The libraries are found by name, not by layout: `libEGL_mesa.so.0`, a `dri/` directory
//! of `*_dri.so`, `libvulkan_lvp.so`, and the shared libraries beside them.
//!
//! Each worker gets the loader's variables ([`MesaBuild::env`]): `LD_LIBRARY_PATH`, glvnd's
//! `__EGL_VENDOR_LIBRARY_FILENAMES` and the Vulkan loader's `VK_ICD_FILENAMES` /
//! `VK_DRIVER_FILES`, both pointing at JSON files umbra writes with *absolute* library paths
//! (the shipped ones name a bare file, which the loaders would resolve on the system's path),
//! and `LIBGL_DRIVERS_PATH`. Loaders fall back silently, so the worker then checks what it
//! really loaded ([`check_loaded`], from `/proc/self/maps`): a Mesa library from outside the
//! build, or no Mesa driver at all, refuses the run with the path that was loaded. A backend
//! whose driver the build does not have ([`MesaBuild::lacks`]) is a skip that says so.
//!
//! **Hardware drivers.** A build that carries Mesa's hardware drivers (`dri/radeonsi_dri.so`,
//! `libvulkan_radeon.so`: [`crate::harness::hw_driver`]) serves the device ids they name
//! (`gl33/radeonsi`, `wgpu-vk/radv`) the same way, each with its own ICD file; `hw` takes
//! them. A driver the build has whose device the machine lacks is a skip that names the
//! device, checked before anything loads.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use serde::Serialize;

/// The environment variable equivalent of `--mesa` (also how a worker learns its build).
pub const ENV: &str = "UMBRA_MESA";

/// A Mesa build found on disk.
#[derive(Clone, Debug, Serialize)]
pub struct MesaBuild {
    /// The directory given, canonical.
    pub root: PathBuf,
    /// `install prefix`, `build directory` or `fake (tests)`.
    pub layout: &'static str,
    /// The version the tree says it is (meson's project info, a pkg-config file, or the
    /// versioned libgallium's name); the version the driver reports is in each backend's
    /// driver line.
    pub version: Option<String>,
    /// glvnd's Mesa vendor library.
    pub egl: Option<PathBuf>,
    /// The directory of the DRI drivers.
    pub dri: Option<PathBuf>,
    /// The DRI drivers present (`swrast`, `zink`, ...).
    pub dri_drivers: Vec<String>,
    /// Lavapipe's ICD library.
    pub lavapipe: Option<PathBuf>,
    /// The hardware drivers it carries (GL ones from `dri/`, Vulkan ICD libraries), with
    /// their files.
    pub hardware: Vec<Carried>,
    /// Directories for `LD_LIBRARY_PATH`.
    pub lib_dirs: Vec<PathBuf>,
    /// Where umbra's loader JSON files for this build live.
    pub generated: PathBuf,
    /// The build's own dynamic loader (`ld-linux-*.so.*` beside a `libc.so.6`), when it carries
    /// its C library: a Debian suite newer than the machine (`cargo xtask fetch-mesa --suite
    /// sid`). Its processes are started through it ([`MesaBuild::enter`]).
    pub loader: Option<PathBuf>,
    /// What `cargo xtask fetch-mesa` recorded of it ([`FETCHED`]), when it made it.
    pub fetched: Option<Fetched>,
}

/// A hardware driver a build carries, and its file.
#[derive(Clone, Debug, Serialize)]
pub struct Carried {
    /// Which driver.
    pub driver: &'static crate::harness::hw_driver::HwDriver,
    /// Its library in the build.
    pub lib: PathBuf,
}

/// The file `cargo xtask fetch-mesa` writes at the root of what it unpacks.
pub const FETCHED: &str = "umbra-mesa.json";

/// What `cargo xtask fetch-mesa` recorded of a build it unpacked.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Fetched {
    /// The Debian suite (`sid`, `trixie`, `bookworm-backports`).
    pub suite: String,
    /// The version of its Mesa packages (`26.2.6-1`).
    pub mesa: String,
    /// The version of its C library (`2.43-7`) where the build carries it, else none: the
    /// machine's is used.
    #[serde(default)]
    pub own_libc: Option<String>,
    /// Every package unpacked, `name=version`.
    #[serde(default)]
    pub packages: Vec<String>,
}

static SELECTED: OnceLock<Option<MesaBuild>> = OnceLock::new();

/// The build this process runs its workers against (none: the system's Mesa).
pub fn selected() -> Option<&'static MesaBuild> {
    SELECTED.get().and_then(Option::as_ref)
}

/// A Mesa to run on, as `--mesa` (parsed by clap) or `UMBRA_MESA` gives it: the system's
/// (`system`), or a directory (an install prefix, a meson build directory, unpacked Debian
/// packages). Whether the directory holds a Mesa is [`select`]'s to say.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum MesaChoice {
    /// The system's Mesa.
    #[default]
    System,
    /// The Mesa under this directory.
    Dir(PathBuf),
}

impl std::str::FromStr for MesaChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<MesaChoice, String> {
        match s {
            "" => Err(
                "give a Mesa install prefix, build directory or unpacked packages, or `system`"
                    .into(),
            ),
            "system" => Ok(MesaChoice::System),
            dir => Ok(MesaChoice::Dir(PathBuf::from(dir))),
        }
    }
}

impl std::fmt::Display for MesaChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MesaChoice::System => f.write_str("system"),
            MesaChoice::Dir(d) => write!(f, "{}", d.display()),
        }
    }
}

/// Selects the build from `--mesa`, else from `UMBRA_MESA`; `system` (or nothing) means the
/// system's Mesa. Call once, before any worker starts.
pub fn select(flag: Option<&MesaChoice>) -> Result<Option<&'static MesaBuild>, String> {
    let env = std::env::var(ENV)
        .ok()
        .filter(|v| !v.is_empty())
        .map(|v| v.parse::<MesaChoice>().unwrap_or(MesaChoice::Dir(v.into())));
    let (value, from) = match (flag, env) {
        (Some(v), _) => (Some(v.clone()), "--mesa"),
        (None, Some(v)) => (Some(v), ENV),
        _ => (None, ""),
    };
    let build = match value {
        None | Some(MesaChoice::System) => None,
        Some(MesaChoice::Dir(dir)) => {
            let v = dir.display();
            let build = MesaBuild::open(&dir).map_err(|e| format!("{from} {v}: {e}"))?;
            if build.layout != "fake (tests)" {
                crate::harness::own_libc::check_loadable(
                    &build.root,
                    build.loader.as_deref(),
                    &build.lib_dirs,
                    &build.key_libraries(),
                )
                .map_err(|e| format!("{from} {v}: {e}"))?;
            }
            Some(build)
        }
    };
    let _ = SELECTED.set(build);
    Ok(selected())
}

impl MesaBuild {
    /// Finds the Mesa libraries under `path` and writes the loader files for them.
    pub fn open(path: &Path) -> Result<MesaBuild, String> {
        let root = std::fs::canonicalize(path).map_err(|e| {
            format!(
                "{e}; fix: give a Mesa install prefix (meson install --destdir DIR), a Mesa build directory, or a directory of unpacked Debian packages (cargo xtask fetch-mesa)"
            )
        })?;
        let generated = std::env::temp_dir().join(build_tag(&root));
        if let Some(fake) =
            crate::harness::fake::marker(&root).filter(|_| crate::harness::fake::enabled())
        {
            return Ok(MesaBuild {
                version: Some(fake?.0),
                root,
                layout: "fake (tests)",
                egl: None,
                dri: None,
                dri_drivers: Vec::new(),
                lavapipe: None,
                hardware: Vec::new(),
                lib_dirs: Vec::new(),
                generated,
                loader: None,
                fetched: None,
            });
        }
        let mut found = Found::default();
        walk(&root, 0, &mut found);
        if found.egl.is_none() && found.lavapipe.is_none() && found.dri.is_none() {
            return Err(
                "no Mesa library under it (looked for libEGL_mesa.so.0, dri/*_dri.so and libvulkan_lvp.so); fix: give the prefix or build directory that holds them".into(),
            );
        }
        let mut hardware: Vec<Carried> = found
            .hardware_vk
            .iter()
            .filter_map(|lib| {
                let name = lib.file_name()?.to_string_lossy().into_owned();
                let driver = crate::harness::hw_driver::of_vulkan_lib(&name)?;
                Some(Carried {
                    driver,
                    lib: lib.clone(),
                })
            })
            .collect();
        if let Some(dri) = &found.dri {
            hardware.extend(found.dri_drivers.iter().filter_map(|d| {
                crate::harness::hw_driver::of_dri(d).map(|driver| Carried {
                    driver,
                    lib: dri.join(format!("{d}_dri.so")),
                })
            }));
        }
        hardware.sort_by_key(|c| (c.driver.vulkan, c.driver.name));
        let mut lib_dirs: Vec<PathBuf> = Vec::new();
        for lib in found
            .egl
            .iter()
            .chain(&found.lavapipe)
            .chain(&found.hardware_vk)
            .chain(&found.shared)
        {
            if let Some(d) = lib.parent() {
                if !lib_dirs.iter().any(|x| x == d) {
                    lib_dirs.push(d.to_path_buf());
                }
            }
        }
        let layout = if root.join("meson-info").is_dir() || root.join("build.ninja").is_file() {
            "build directory"
        } else {
            "install prefix"
        };
        // A C library and its loader side by side: the build carries its own, and every
        // directory of shared libraries in it is searched first.
        let loader = found
            .loaders
            .iter()
            .find(|l| found.libcs.iter().any(|c| c.parent() == l.parent()))
            .cloned();
        if loader.is_some() {
            for d in &found.so_dirs {
                if !lib_dirs.contains(d) {
                    lib_dirs.push(d.clone());
                }
            }
        }
        let fetched = std::fs::read_to_string(root.join(FETCHED))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
        let build = MesaBuild {
            version: version_of(&root, &found),
            root,
            layout,
            egl: found.egl,
            dri: found.dri,
            dri_drivers: found.dri_drivers,
            lavapipe: found.lavapipe,
            hardware,
            lib_dirs,
            generated,
            loader,
            fetched,
        };
        build.write_loader_files(found.icd_api.as_deref())?;
        Ok(build)
    }

    /// Every worker writes these (the same bytes for the same build) while others may be
    /// loading them, so through [`crate::atomic_file`]: a truncated one made a concurrently
    /// starting worker's EGL find no vendor.
    fn write_loader_files(&self, icd_api: Option<&str>) -> Result<(), String> {
        let fail = |e: std::io::Error| format!("cannot write {}: {e}", self.generated.display());
        std::fs::create_dir_all(&self.generated).map_err(fail)?;
        let write = |name: &str, json: serde_json::Value| {
            crate::atomic_file::write(&self.generated.join(name), json.to_string().as_bytes())
                .map_err(fail)
        };
        if let Some(egl) = &self.egl {
            let json = serde_json::json!({
                "file_format_version": "1.0.0",
                "ICD": { "library_path": egl }
            });
            write("50_mesa.json", json)?;
        }
        if let Some(lvp) = &self.lavapipe {
            let json = serde_json::json!({
                "file_format_version": "1.0.0",
                "ICD": { "library_path": lvp, "api_version": icd_api.unwrap_or("1.3.0") }
            });
            write("lvp_icd.json", json)?;
        }
        for c in self.hardware.iter().filter(|c| c.driver.vulkan) {
            let json = serde_json::json!({
                "file_format_version": "1.0.0",
                "ICD": { "library_path": c.lib, "api_version": icd_api.unwrap_or("1.3.0") }
            });
            write(&format!("{}_icd.json", c.driver.name), json)?;
        }
        Ok(())
    }

    /// The loader variables a worker for backend `id` needs to load this build (and
    /// `UMBRA_MESA`, so the worker checks what it loaded). A hardware Vulkan id's loader sees
    /// its driver's ICD alone; every other id's sees lavapipe's (or none).
    pub fn env(&self, id: &str) -> Vec<(String, String)> {
        let mut env = vec![(ENV.to_string(), self.root.to_string_lossy().into_owned())];
        // A build with its own C library is found through its loader's `--library-path`, which
        // no child inherits: in LD_LIBRARY_PATH its libc would meet the machine's loader.
        if !self.lib_dirs.is_empty() && self.loader.is_none() {
            let mut dirs: Vec<String> = self
                .lib_dirs
                .iter()
                .map(|d| d.to_string_lossy().into_owned())
                .collect();
            if let Ok(old) = std::env::var("LD_LIBRARY_PATH") {
                dirs.extend(old.split(':').filter(|s| !s.is_empty()).map(str::to_string));
            }
            env.push(("LD_LIBRARY_PATH".into(), dirs.join(":")));
        }
        if self.egl.is_some() {
            env.push((
                "__EGL_VENDOR_LIBRARY_FILENAMES".into(),
                self.generated.join("50_mesa.json").to_string_lossy().into(),
            ));
        }
        if let Some(dri) = &self.dri {
            env.push(("LIBGL_DRIVERS_PATH".into(), dri.to_string_lossy().into()));
        }
        // Without lavapipe in the build, point the Vulkan loader at nothing rather than at the
        // system's ICDs: wgpu-vk and zink then skip instead of silently using the system.
        let hardware_icd = self
            .carried(id)
            .filter(|c| c.driver.vulkan)
            .map(|c| format!("{}_icd.json", c.driver.name));
        let icd = if let Some(file) = hardware_icd {
            self.generated.join(file).to_string_lossy().into_owned()
        } else if self.lavapipe.is_some() {
            self.generated
                .join("lvp_icd.json")
                .to_string_lossy()
                .into_owned()
        } else {
            self.generated
                .join("no-icd.json")
                .to_string_lossy()
                .into_owned()
        };
        env.push(("VK_ICD_FILENAMES".into(), icd.clone()));
        env.push(("VK_DRIVER_FILES".into(), icd));
        env.extend(shader_cache_env(&self.root, |k| std::env::var_os(k)));
        env
    }

    /// The hardware driver of device id `id` that this build carries, if it does.
    pub fn carried(&self, id: &str) -> Option<&Carried> {
        let driver = crate::harness::hw_driver::of_backend_id(id)?;
        self.hardware.iter().find(|c| c.driver == driver)
    }

    /// The device ids of the hardware drivers this build carries, in order.
    pub fn hardware_ids(&self) -> Vec<String> {
        self.hardware
            .iter()
            .flat_map(|c| c.driver.backend_ids())
            .collect()
    }

    /// What backend `id` needs that this build lacks, if anything: its driver, or (for a
    /// hardware driver the build has) the device this machine lacks.
    pub fn lacks(&self, id: &str) -> Option<String> {
        if self.layout == "fake (tests)" {
            return (!id.starts_with("fake/"))
                .then(|| format!("{} is a fake build (tests only)", self.root.display()));
        }
        if let Some(driver) = crate::harness::hw_driver::of_backend_id(id) {
            return match self.carried(id) {
                None => Some(format!(
                    "the Mesa build in {} has no {} ({})",
                    self.root.display(),
                    driver.name,
                    if driver.vulkan {
                        driver.file.to_string()
                    } else {
                        format!("dri/{}", driver.file)
                    }
                )),
                Some(c) => crate::harness::hw_driver::missing_device(
                    driver,
                    Path::new(crate::harness::hw_driver::SYS_DRM),
                )
                .map(|why| {
                    format!(
                        "{why}; the Mesa build in {} has the driver ({})",
                        self.root.display(),
                        c.lib.display()
                    )
                }),
            };
        }
        let dri = |name: &str| self.dri_drivers.iter().any(|d| d == name);
        let need_lvp = || {
            self.lavapipe.is_none().then(|| {
                format!(
                    "the Mesa build in {} has no lavapipe (libvulkan_lvp.so)",
                    self.root.display()
                )
            })
        };
        let need_dri = |name: &str| {
            (self.egl.is_none() || !dri(name)).then(|| {
                format!(
                    "the Mesa build in {} has no {} (libEGL_mesa.so.0 and dri/{name}_dri.so)",
                    self.root.display(),
                    if name == "swrast" {
                        "llvmpipe/softpipe"
                    } else {
                        name
                    }
                )
            })
        };
        match (
            umbra_wgpu::Target::parse(id).filter(umbra_wgpu::Target::is_software),
            umbra_gl::parse_id(id),
        ) {
            (Some(t), _) if t.kind == umbra_wgpu::Kind::Vulkan => need_lvp(),
            (Some(_), _) => need_dri("swrast"),
            (None, Some((_, umbra_gl::Driver::Zink))) => need_dri("zink").or_else(need_lvp),
            (None, Some(_)) => need_dri("swrast"),
            _ => None,
        }
    }

    /// The build's own C library, when it carries one ([`crate::harness::own_libc`]).
    pub fn own_libc(&self) -> Option<crate::harness::own_libc::Own<'_>> {
        self.loader
            .as_deref()
            .map(|loader| crate::harness::own_libc::Own {
                root: &self.root,
                loader,
                dirs: &self.lib_dirs,
            })
    }

    /// Moves this process onto the build's own C library where it carries one (re-executed
    /// through its loader; on success this does not return), and checks that it runs there.
    pub fn enter(&self) -> Result<(), String> {
        match self.own_libc() {
            Some(own) => crate::harness::own_libc::enter(&own)
                .and_then(|()| crate::harness::own_libc::check_on_build_libc(&own)),
            None => Ok(()),
        }
    }

    /// The libraries a backend's driver loads from the build: glvnd's EGL vendor, lavapipe,
    /// gallium and its siblings, one DRI driver (what [`select`] has the loader list).
    fn key_libraries(&self) -> Vec<PathBuf> {
        let mut libs: Vec<PathBuf> = self.egl.iter().chain(&self.lavapipe).cloned().collect();
        for d in &self.lib_dirs {
            let Ok(rd) = std::fs::read_dir(d) else {
                continue;
            };
            let mut gallium: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name().is_some_and(|n| {
                        let n = n.to_string_lossy();
                        n.starts_with("libgallium") && n.contains(".so")
                    })
                })
                .collect();
            gallium.sort();
            libs.extend(gallium);
        }
        if let (Some(dri), Some(first)) = (&self.dri, self.dri_drivers.first()) {
            libs.push(dri.join(format!("{first}_dri.so")));
        }
        libs.dedup();
        libs
    }

    /// One line for reports: where the build is and what it says it is.
    pub fn describe(&self) -> String {
        let layout = match &self.fetched {
            Some(f) => format!("Debian {} packages", f.suite),
            None => self.layout.to_string(),
        };
        let libc = match (
            &self.loader,
            self.fetched.as_ref().and_then(|f| f.own_libc.as_ref()),
        ) {
            (Some(_), Some(v)) => format!(", its own C library glibc {v}"),
            (Some(_), None) => ", its own C library".to_string(),
            (None, _) => String::new(),
        };
        format!(
            "{} ({layout}, {}{libc})",
            self.root.display(),
            self.version.as_deref().unwrap_or("version unknown")
        )
    }
}

/// Whether backend `id` runs on Mesa (and so on the selected build): Mesa's software
/// drivers, and the device ids of Mesa's hardware drivers ([`crate::harness::hw_driver`]).
/// Any other device id's driver is another vendor's (`gl33/nvidia`): `--mesa` leaves it to
/// the machine's loader, whose variables the build's would hide.
pub fn is_mesa_backed(id: &str) -> bool {
    umbra_gl::parse_id(id).is_some()
        || umbra_wgpu::Target::parse(id).is_some_and(|t| t.is_software())
        || crate::harness::hw_driver::of_backend_id(id).is_some()
        || id == crate::harness::fake::MESA
}

#[derive(Default)]
struct Found {
    egl: Option<PathBuf>,
    dri: Option<PathBuf>,
    dri_drivers: Vec<String>,
    lavapipe: Option<PathBuf>,
    /// Mesa's hardware Vulkan ICD libraries (`libvulkan_radeon.so`, …).
    hardware_vk: Vec<PathBuf>,
    icd_api: Option<String>,
    /// Mesa's other shared libraries (glapi, gbm, gallium): their directories join
    /// LD_LIBRARY_PATH.
    shared: Vec<PathBuf>,
    pkg_version: Option<String>,
    project_version: Option<String>,
    /// Dynamic loaders (`ld-linux-*.so.*`) and C libraries (`libc.so.6`) in the tree.
    loaders: Vec<PathBuf>,
    libcs: Vec<PathBuf>,
    /// Every directory holding a shared library (`*.so*`), in walk order.
    so_dirs: Vec<PathBuf>,
}

/// Walks `dir` (not into `.git`, meson's private directories or symlinked directories) for
/// the libraries, to a depth that covers `usr/lib/x86_64-linux-gnu/dri` and a build
/// directory's `src/gallium/targets/dri`.
fn walk(dir: &Path, depth: usize, found: &mut Found) {
    if depth > 6 {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.filter_map(Result::ok).collect();
    entries.sort_by_key(|e| e.file_name());
    let mut drivers_here = Vec::new();
    for e in entries {
        let path = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        let Ok(ft) = e.file_type() else { continue };
        if ft.is_dir() {
            if name.starts_with('.')
                || name.ends_with(".p")
                || name == "meson-private"
                || name == "include"
            {
                continue;
            }
            walk(&path, depth + 1, found);
            continue;
        }
        if name.contains(".so")
            && !found.so_dirs.iter().any(|d| d == dir)
            && dir.file_name().is_some_and(|d| d != "dri")
        {
            found.so_dirs.push(dir.to_path_buf());
        }
        if name.starts_with("ld-linux") && name.contains(".so") {
            found.loaders.push(path.clone());
        } else if name == "libc.so.6" {
            found.libcs.push(path.clone());
        }
        if name == "libEGL_mesa.so.0" && found.egl.is_none() {
            found.egl = Some(path);
        } else if name == "libvulkan_lvp.so" && found.lavapipe.is_none() {
            found.lavapipe = Some(path);
        } else if crate::harness::hw_driver::of_vulkan_lib(&name).is_some()
            && !found
                .hardware_vk
                .iter()
                .any(|p| p.file_name() == path.file_name())
        {
            found.hardware_vk.push(path);
        } else if let Some(d) = name.strip_suffix("_dri.so") {
            if !d.starts_with("lib") {
                drivers_here.push(d.to_string());
            }
        } else if (name.starts_with("libglapi.so.") || name.starts_with("libgbm.so."))
            || (name.starts_with("libgallium") && name.contains(".so"))
        {
            if name.starts_with("libgallium-") && found.pkg_version.is_none() {
                found.pkg_version = name
                    .strip_prefix("libgallium-")
                    .and_then(|v| v.strip_suffix(".so"))
                    .map(str::to_string);
            }
            found.shared.push(path);
        } else if name.starts_with("lvp_") && name.ends_with(".json") && found.icd_api.is_none() {
            found.icd_api = std::fs::read_to_string(&path)
                .ok()
                .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
                .and_then(|v| v["ICD"]["api_version"].as_str().map(str::to_string));
        } else if (name == "dri.pc" || name == "egl.pc") && found.pkg_version.is_none() {
            found.pkg_version = std::fs::read_to_string(&path).ok().and_then(|t| {
                t.lines()
                    .find_map(|l| l.strip_prefix("Version:").map(|v| v.trim().to_string()))
            });
        } else if name == "intro-projectinfo.json" {
            found.project_version = std::fs::read_to_string(&path)
                .ok()
                .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
                .and_then(|v| v["version"].as_str().map(str::to_string));
        }
    }
    if !drivers_here.is_empty() && found.dri.is_none() {
        found.dri = Some(dir.to_path_buf());
        found.dri_drivers = drivers_here;
    }
}

fn version_of(_root: &Path, found: &Found) -> Option<String> {
    found
        .project_version
        .clone()
        .or_else(|| found.pkg_version.clone())
}

/// The Mesa libraries this process has mapped (`/proc/self/maps`), by name: glvnd's vendor
/// library, glapi, gbm, gallium, the DRI drivers and lavapipe.
pub fn loaded_libs() -> Vec<PathBuf> {
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap_or_default();
    let mut libs: Vec<PathBuf> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.starts_with('/'))
        .map(PathBuf::from)
        .filter(|p| is_mesa_lib(p))
        .collect();
    libs.sort();
    libs.dedup();
    libs
}

fn is_mesa_lib(p: &Path) -> bool {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.starts_with("libEGL_mesa")
        || name.starts_with("libglapi")
        || name.starts_with("libgbm")
        || name.starts_with("libgallium")
        || name.starts_with("libvulkan_lvp")
        || name.starts_with("libdril")
        || name.ends_with("_dri.so")
        || crate::harness::hw_driver::of_vulkan_lib(&name).is_some()
}

fn is_driver_lib(p: &Path) -> bool {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.ends_with("_dri.so")
        || name.starts_with("libgallium")
        || name.starts_with("libvulkan_lvp")
        || crate::harness::hw_driver::of_vulkan_lib(&name).is_some()
}

/// Checks that every Mesa library in `libs` lies under `root` and that a driver is among
/// them; the error names what was loaded instead.
pub fn check_loaded(root: &Path, libs: &[PathBuf]) -> Result<(), String> {
    let outside: Vec<String> = libs
        .iter()
        .filter(|l| !l.starts_with(root))
        .map(|l| l.display().to_string())
        .collect();
    if !outside.is_empty() {
        return Err(format!(
            "the worker fell back to a Mesa outside the build in {}: it loaded {}; fix: check that the build has the driver's libraries (libEGL_mesa.so.0, dri/*_dri.so, libvulkan_lvp.so) and that they load (ldd on them names what is missing)",
            root.display(),
            outside.join(", ")
        ));
    }
    if !libs.iter().any(|l| is_driver_lib(l)) {
        return Err(format!(
            "no Mesa driver from {} was loaded (loaded: {}); the backend did not reach the build's driver",
            root.display(),
            if libs.is_empty() {
                "none".to_string()
            } else {
                libs.iter()
                    .map(|l| l.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        ));
    }
    Ok(())
}

/// The name umbra gives what it keeps for the build at `root` (its loader files in the temp
/// directory, its shader cache): `umbra-mesa-` and the hash of the path.
fn build_tag(root: &Path) -> String {
    format!(
        "umbra-mesa-{:08x}",
        umbra_report::names::fnv1a(&root.to_string_lossy())
    )
}

/// Mesa's on-disk shader cache for the build at `root`, apart from every other Mesa's:
/// `MESA_SHADER_CACHE_DIR` under the user's cache directory, named for the build's path.
/// Two releases sharing the default `~/.cache/mesa_shader_cache` tear each other's index: a
/// worker of sid's 26.2.6 died of SIGBUS in `libgallium` reading that index while 22.3.6's
/// workers wrote it (a catalogue and a bless on the two releases at once; the rerun on a
/// fresh worker passed, a flake). Left as it is where the user chose a cache or turned it
/// off (`environ` reads the environment).
fn shader_cache_env(
    root: &Path,
    environ: impl Fn(&str) -> Option<std::ffi::OsString>,
) -> Option<(String, String)> {
    let chosen = ["MESA_SHADER_CACHE_DIR", "MESA_SHADER_CACHE_DISABLE"]
        .iter()
        .any(|k| environ(k).is_some());
    if chosen {
        return None;
    }
    let base = environ("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| environ("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join(build_tag(root));
    Some((
        "MESA_SHADER_CACHE_DIR".into(),
        dir.to_string_lossy().into_owned(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_build_keeps_its_own_shader_cache_unless_the_user_chose_one() {
        let home = |k: &str| (k == "HOME").then(|| std::ffi::OsString::from("/home/u"));
        let (k, a) = shader_cache_env(Path::new("/m/sid"), home).expect("a cache of its own");
        assert_eq!(k, "MESA_SHADER_CACHE_DIR");
        assert!(a.starts_with("/home/u/.cache/umbra-mesa-"), "{a}");
        let (_, b) = shader_cache_env(Path::new("/m/25.0"), home).expect("a cache of its own");
        assert_ne!(a, b, "two builds, two caches");
        let chosen = |k: &str| (k == "MESA_SHADER_CACHE_DISABLE").then(|| "1".into());
        assert_eq!(shader_cache_env(Path::new("/m/sid"), chosen), None);
    }

    #[test]
    fn a_library_outside_the_build_is_refused_by_path() {
        let root = Path::new("/opt/mesa");
        let ok = [PathBuf::from("/opt/mesa/usr/lib/dri/swrast_dri.so")];
        assert!(check_loaded(root, &ok).is_ok());
        let fell_back = [
            PathBuf::from("/opt/mesa/usr/lib/libEGL_mesa.so.0"),
            PathBuf::from("/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so"),
        ];
        let e = check_loaded(root, &fell_back).expect_err("a system library must be refused");
        assert!(
            e.contains("fell back") && e.contains("/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so"),
            "{e}"
        );
        // A hardware driver's fallback is refused the same way: RADV from the system, not
        // the build.
        let hw_fell_back = [
            PathBuf::from("/opt/mesa/usr/lib/libEGL_mesa.so.0"),
            PathBuf::from("/usr/lib/x86_64-linux-gnu/libvulkan_radeon.so"),
        ];
        let e = check_loaded(root, &hw_fell_back).expect_err("the system's RADV must be refused");
        assert!(
            e.contains("fell back") && e.contains("libvulkan_radeon.so"),
            "{e}"
        );
        assert!(
            check_loaded(
                root,
                &[PathBuf::from("/opt/mesa/usr/lib/libvulkan_intel.so")]
            )
            .is_ok()
        );
        let no_driver = [PathBuf::from("/opt/mesa/usr/lib/libEGL_mesa.so.0")];
        assert!(
            check_loaded(root, &no_driver)
                .expect_err("no driver loaded must be refused")
                .contains("no Mesa driver")
        );
    }

    #[test]
    fn a_directory_without_mesa_is_refused_with_the_fix() {
        let dir = std::env::temp_dir().join(format!("umbra-no-mesa-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("usr/lib")).expect("temp dir");
        let e = MesaBuild::open(&dir).expect_err("an empty dir is no build");
        assert!(e.contains("no Mesa library") && e.contains("fix:"), "{e}");
        let e = MesaBuild::open(&dir.join("missing")).expect_err("a missing dir is no build");
        assert!(e.contains("fix:"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
