//! Backend ids and how to make them.
//!
//! - **This build's ids** ([`known`]): `ref`; `API/DRIVER` for Mesa's software drivers
//!   (`gl33/llvmpipe`, `gles2/zink`, …), chosen by environment on EGL's surfaceless
//!   platform; `wgpu-vk/lavapipe` and `wgpu-gl/llvmpipe`.
//! - **This machine's devices** ([`discover`]): every EGL device as `API/NAME` and every
//!   wgpu adapter as `wgpu-vk/NAME` or `wgpu-gl/NAME`, NAME from what the driver reports
//!   (`gl33/radeonsi`, `gles3/iris.2`, `gl33/nvidia`, `wgpu-vk/radv`; Mesa's software EGL
//!   device is `gl33/swrast`). Listed by `umbra backends`, taken by `--backend` like the
//!   others, and by the aliases `hw` (every hardware device) and `all` (this build's ids and
//!   every hardware device; the software EGL device is the same driver as `gl33/llvmpipe`
//!   reached another way, so it is run only when named).
//!
//! A Mesa driver is chosen by environment before EGL loads, so a process hosts one driver.
//! [`driver_env`] says which environment an id needs; the commands run ids whose driver this
//! process did not load in a child process of their own ([`crate::harness::child`]). A
//! device id sets no driver environment: the device's own driver answers.

use std::io::Read as _;

use umbra_case::Backend;

/// What a backend id means, answered here once so that no command parses ids or names the
/// GL and wgpu crates to learn it: which family draws it (and so which technique the judge
/// sees: its depth range, its compare, its filters), whether it is a machine's device or one
/// of Mesa's software drivers. A new wgpu kind or GL API is taught here, and the self-test's
/// faults, the repro's capture and `umbra backends` follow.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Descriptor {
    /// Who draws it.
    pub family: Family,
    /// A device of this machine (`gl33/radeonsi`), not one of this build's Mesa software ids.
    pub device: bool,
}

/// Who draws a backend's pictures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// umbra's CPU reference.
    Reference,
    /// umbra-gl on EGL, with this API.
    Gl(umbra_gl::Api),
    /// umbra-wgpu, on this kind of wgpu backend.
    Wgpu(umbra_wgpu::Kind),
    /// A test double (`UMBRA_FAKE_BACKENDS=1`).
    Fake,
}

impl Descriptor {
    /// The descriptor of `id`, or `None` for an id no family knows.
    pub fn of(id: &str) -> Option<Descriptor> {
        let family = if id == "ref" {
            Family::Reference
        } else if let Some(target) = umbra_wgpu::Target::parse(id) {
            Family::Wgpu(target.kind)
        } else if let Some((api, _)) = umbra_gl::parse_id(id) {
            Family::Gl(api)
        } else if let Some((api, _)) = umbra_gl::parse_device_id(id) {
            Family::Gl(api)
        } else if crate::harness::fake::enabled() && crate::harness::fake::Fake::new(id).is_some() {
            Family::Fake
        } else {
            return None;
        };
        Some(Descriptor {
            family,
            device: is_device_id(id),
        })
    }

    /// What the family can do, as its crate declares it (the reference and the test doubles
    /// draw through no driver: nothing).
    pub fn capabilities(&self) -> umbra_case::Capabilities {
        match self.family {
            Family::Gl(api) => api.capabilities(),
            Family::Wgpu(kind) => kind.capabilities(),
            Family::Reference | Family::Fake => umbra_case::Capabilities::default(),
        }
    }

    /// A driver's backend (GL or wgpu), whose shaders a fault can be injected into.
    pub fn renders_on_a_driver(&self) -> bool {
        self.capabilities().driver
    }

    /// Draws through GL calls umbra makes itself (umbra-gl), which a repro can capture and
    /// replay as a C program.
    pub fn umbra_makes_the_gl_calls(&self) -> bool {
        self.capabilities().umbra_makes_gl_calls
    }

    /// Samples the map through GL texture units and picks a texture component (GL's binding
    /// model; wgpu binds by group).
    pub fn binds_gl_texture_units(&self) -> bool {
        self.capabilities().gl_texture_units
    }

    /// Runs on Vulkan (wgpu's Vulkan backend).
    pub fn vulkan(&self) -> bool {
        self.family == Family::Wgpu(umbra_wgpu::Kind::Vulkan)
    }

    /// The technique GLES 2 forces ([`umbra_case::Capabilities::gles2_technique`]).
    pub fn gles2_technique(&self) -> bool {
        self.capabilities().gles2_technique
    }

    /// Depth in [0, 1] clip space, where GL's [-1, 1] mapping is a fault.
    pub fn zero_to_one_depth(&self) -> bool {
        self.capabilities().zero_to_one_depth
    }

    /// Takes the depth bias's constant as a whole number of units, so a fractional offset is
    /// rounded.
    pub fn integer_depth_bias(&self) -> bool {
        self.capabilities().integer_depth_bias
    }

    /// Can compare in the shader, with its own LINEAR filter.
    pub fn manual_compare(&self) -> bool {
        self.capabilities().manual_compare
    }

    /// How the id is reached, in words (`umbra backends`).
    pub fn how_reached(&self) -> &'static str {
        match self.family {
            Family::Wgpu(umbra_wgpu::Kind::Vulkan) => "wgpu on Vulkan, the adapter of this name",
            Family::Wgpu(umbra_wgpu::Kind::Gl) => "wgpu's GL backend on EGL",
            Family::Gl(_) if self.device => {
                "EGL device platform (EGL_EXT_platform_device), the device of this name"
            }
            _ => match std::env::var(umbra_gl::platform::ENV).ok().as_deref() {
                Some(p) if p.starts_with("device") => "EGL device (UMBRA_EGL_PLATFORM)",
                _ => "EGL surfaceless (or the first EGL device where surfaceless is not offered)",
            },
        }
    }
}

/// Whether `id` names a backend of this build (fake ones only where enabled), or has the
/// form of a device's id ([`is_device_id`]; whether the device exists is the worker's to
/// find, and a missing one is a skip that lists what the machine has).
pub fn is_known(id: &str) -> bool {
    known().iter().any(|k| k == id)
        || (crate::harness::fake::enabled() && crate::harness::fake::Fake::new(id).is_some())
        || is_device_id(id)
}

/// Whether `id` has the form of a device's id: an EGL device's (`gl33/radeonsi`) or a wgpu
/// adapter's (`wgpu-vk/radv`), not one of this build's Mesa software ids.
pub fn is_device_id(id: &str) -> bool {
    !known().iter().any(|k| k == id)
        && (umbra_gl::parse_device_id(id).is_some() || umbra_wgpu::Target::parse(id).is_some())
}

/// Variables that make Mesa pick a driver or a software path. A device id's processes run
/// without them: an inherited `LIBGL_ALWAYS_SOFTWARE=1` (common in CI files) would turn a GPU
/// into `kms_swrast`, another name and another driver.
pub const MESA_SELECTION: [&str; 3] = [
    "LIBGL_ALWAYS_SOFTWARE",
    "GALLIUM_DRIVER",
    "MESA_LOADER_DRIVER_OVERRIDE",
];

/// The variables a process for `id` must not inherit ([`MESA_SELECTION`] for a device id).
pub fn env_removed(id: &str) -> &'static [&'static str] {
    if is_device_id(id) {
        &MESA_SELECTION
    } else {
        &[]
    }
}

/// How long discovery may take: enumerating devices initialises each one's driver, and a
/// hung driver must cost the listing, not the run.
const DISCOVERY_LIMIT: std::time::Duration = std::time::Duration::from_secs(60);

/// A backend id found on this machine by [`discover`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Discovered {
    /// The id.
    pub id: String,
    /// A hardware device (not Mesa's software device or CPU adapter).
    pub hardware: bool,
    /// How it is reached, in words.
    pub reached: String,
}

/// The device ids of this machine, found in a child process (`umbra backends --ids`) so that
/// no driver loads in this one: every EGL device with each GL API, every wgpu adapter that is
/// not one of this build's ids. Empty where nothing can be listed.
pub fn discover() -> Result<Vec<Discovered>, String> {
    let exe = crate::harness::own_libc::self_exe()
        .map_err(|e| format!("cannot find this executable: {e}"))?;
    let mut cmd = std::process::Command::new(exe);
    cmd.args(["backends", "--ids"])
        .env("NODEVICE_SELECT", "1")
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    for v in MESA_SELECTION {
        cmd.env_remove(v);
    }
    let mut child = cmd
        .spawn()
        .map_err(|e| format!("cannot start device discovery: {e}"))?;
    let read = |pipe: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_string(&mut text);
            }
            text
        })
    };
    let stdout = read(child.stdout.take().map(|p| Box::new(p) as _));
    let stderr = read(child.stderr.take().map(|p| Box::new(p) as _));
    let started = std::time::Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if started.elapsed() > DISCOVERY_LIMIT => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "device discovery (`umbra backends --ids`) hung for {} s: a driver did not answer eglInitialize or Vulkan enumeration",
                    DISCOVERY_LIMIT.as_secs()
                ));
            }
            Ok(None) => std::thread::sleep(std::time::Duration::from_millis(20)),
            Err(e) => return Err(format!("device discovery: {e}")),
        }
    };
    let (stdout, stderr) = (
        stdout.join().unwrap_or_default(),
        stderr.join().unwrap_or_default(),
    );
    if !status.success() {
        return Err(format!(
            "device discovery (`umbra backends --ids`) failed ({status}): {}",
            stderr.trim()
        ));
    }
    Ok(stdout
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| {
            Some(Discovered {
                id: v["id"].as_str()?.to_string(),
                hardware: v["hardware"].as_bool()?,
                reached: v["reached"].as_str().unwrap_or("").to_string(),
            })
        })
        .collect())
}

/// [`discover`]'s list, computed in this process (what `umbra backends --ids` prints).
pub fn discover_here() -> Vec<Discovered> {
    let mut found = Vec::new();
    if let Ok(egl) = umbra_gl::context::load_egl() {
        for d in umbra_gl::platform::named_devices(&egl).unwrap_or_default() {
            for api in umbra_gl::Api::ALL {
                found.push(Discovered {
                    id: format!("{}/{}", api.name(), d.name),
                    hardware: !d.device.software(),
                    reached: d.device.describe_with_pci(),
                });
            }
        }
    }
    for kind in umbra_wgpu::Kind::ALL {
        for (name, adapter) in umbra_wgpu::device::named_adapters(kind) {
            let id = format!("{}/{name}", kind.prefix());
            if known().contains(&id) {
                continue;
            }
            let (hardware, reached) = umbra_wgpu::device::describe(&adapter);
            found.push(Discovered {
                id,
                hardware,
                reached,
            });
        }
    }
    found
}

/// The backends a command was asked for: the `--backend` values, `default` when there are
/// none. The aliases: `all`, this build's ids and every hardware device of this machine;
/// `hw`, every hardware device, and the device ids of the hardware drivers a `--mesa` build
/// carries. An unknown id is an error naming the known ones; a device id this machine lacks
/// is an error naming the devices it has, unless the build carries its driver (its worker
/// then skips, naming the device).
pub fn selected(named: &[&str], default: Vec<String>) -> Result<Vec<String>, String> {
    if named.is_empty() {
        return Ok(default);
    }
    let needs_devices = named
        .iter()
        .any(|n| *n == "all" || *n == "hw" || is_device_id(n));
    let devices = if needs_devices {
        discover()?
    } else {
        Vec::new()
    };
    // A `--mesa` build's hardware drivers are hardware backends too, whether or not this
    // machine has their device: one it lacks is the worker's skip, naming the device.
    let carried: Vec<String> = crate::harness::mesa_build::selected()
        .map(crate::harness::mesa_build::MesaBuild::hardware_ids)
        .unwrap_or_default();
    let mut hardware: Vec<String> = devices
        .iter()
        .filter(|d| d.hardware)
        .map(|d| d.id.clone())
        .collect();
    for id in &carried {
        if !hardware.contains(id) {
            hardware.push(id.clone());
        }
    }
    let mut ids: Vec<String> = Vec::new();
    let add = |id: String, ids: &mut Vec<String>| {
        if !ids.contains(&id) {
            ids.push(id);
        }
    };
    for n in named {
        match *n {
            "all" => known()
                .into_iter()
                .chain(hardware.iter().cloned())
                .for_each(|i| add(i, &mut ids)),
            "hw" if hardware.is_empty() => {
                return Err(format!(
                    "--backend hw: this machine has no hardware device that EGL or wgpu lists{} (`umbra backends` shows what it has)",
                    if devices.is_empty() {
                        String::new()
                    } else {
                        format!(
                            "; its devices are {}",
                            devices
                                .iter()
                                .map(|d| d.id.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        )
                    }
                ));
            }
            "hw" => hardware.iter().cloned().for_each(|i| add(i, &mut ids)),
            id if is_device_id(id) && carried.iter().any(|c| c == id) => {
                add(id.to_string(), &mut ids)
            }
            id if is_device_id(id) && !devices.iter().any(|d| d.id == id) => {
                let have: Vec<&str> = devices.iter().map(|d| d.id.as_str()).collect();
                return Err(format!(
                    "--backend {id}: no such device on this machine; it has {} (`umbra backends` lists them)",
                    if have.is_empty() {
                        "none".to_string()
                    } else {
                        have.join(", ")
                    }
                ));
            }
            id if is_known(id) => add(id.to_string(), &mut ids),
            bad => {
                return Err(format!(
                    "unknown backend {bad:?}; this build has: {}, the aliases hw and all, and this machine's devices (`umbra backends`)",
                    known().join(", ")
                ));
            }
        }
    }
    Ok(ids)
}

/// Every backend id this build knows, in report order.
pub fn known() -> Vec<String> {
    let mut ids = vec!["ref".to_string()];
    ids.extend(umbra_gl::ids());
    ids.extend(umbra_wgpu::Target::software().iter().map(|t| t.id()));
    ids
}

/// The environment the id's driver needs, if any (wgpu's GL backend loads Mesa's EGL, so it
/// needs llvmpipe's).
pub fn driver_env(id: &str) -> Option<Vec<(&'static str, &'static str)>> {
    match umbra_wgpu::Target::parse(id) {
        // wgpu's GL backend takes EGL's default display, where Mesa's variables choose.
        Some(t) if t.kind == umbra_wgpu::Kind::Gl && t.is_software() => {
            Some(umbra_gl::Driver::Llvmpipe.env())
        }
        Some(t) if t.kind == umbra_wgpu::Kind::Gl => Some(Vec::new()),
        // The Vulkan device-select layer only complains about DISPLAY and XDG_RUNTIME_DIR.
        Some(_) => Some(vec![("NODEVICE_SELECT", "1")]),
        None => umbra_gl::parse_id(id)
            .map(|(_, d)| d.env())
            .or_else(|| umbra_gl::parse_device_id(id).map(|_| Vec::new())),
    }
}

/// glibc's allocator thresholds for every worker (unless `GLIBC_TUNABLES` is set already).
///
/// A worker renders and judges hundreds of frames, each allocating and freeing the same large
/// buffers (a 1024² map is 4 MB, a view's outputs 1–2 MB, a judged entry up to 16 MB). With
/// glibc's defaults a freed block above the dynamic mmap threshold goes back to the kernel,
/// and the heap's top is trimmed above twice that, so the next run faults the same memory in
/// again page by page: on the standard frame a fifth of the reference's time on two threads
/// was page faults and the kernel's page lock (perf), and the same held for warm judging.
/// Allocations below 64 MiB come from the heap and up to 256 MiB of free memory stays mapped
/// per arena: resident memory a worker keeps, well inside its budget
/// ([`crate::harness::memory_limit`]), which the watchdog still enforces.
pub const MALLOC_TUNABLES: &str =
    "glibc.malloc.mmap_threshold=67108864:glibc.malloc.trim_threshold=268435456";

/// Everything a worker process for `id` needs in its environment: the driver's variables,
/// when a Mesa build is selected ([`crate::harness::mesa_build`]) and the backend runs on
/// Mesa, the build's loader variables, and the allocator's thresholds ([`MALLOC_TUNABLES`]).
pub fn worker_env(id: &str) -> Vec<(String, String)> {
    let mut env: Vec<(String, String)> = driver_env(id)
        .unwrap_or_default()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    if let Some(build) = crate::harness::mesa_build::selected() {
        if crate::harness::mesa_build::is_mesa_backed(id) {
            env.extend(build.env(id));
        }
    }
    env.push((
        crate::harness::memory_limit::ENV.to_string(),
        format!("{}B", crate::harness::memory_limit::budget()),
    ));
    if std::env::var_os("GLIBC_TUNABLES").is_none() {
        env.push(("GLIBC_TUNABLES".into(), MALLOC_TUNABLES.into()));
    }
    // insta's whole environment is umbra's (the inherited one is removed at the spawn).
    env.extend(crate::judge::golden::insta_env(false));
    env
}

/// Prefixes of the variables that steer a driver (Mesa's, the Vulkan loader's, glvnd's,
/// wgpu's, the NVIDIA and AMD drivers'): a run's behaviour can depend on any of them.
pub const DRIVER_VARIABLES: &[&str] = &[
    "MESA_",
    "LP_",
    "GALLIUM_",
    "ZINK_",
    "VK_",
    "LIBGL_",
    "EGL_",
    "GBM_",
    "NIR_",
    "RADV_",
    "ANV_",
    "AMD_",
    "RADEON",
    "NOUVEAU_",
    "__GL",
    "__EGL",
    "DRI_",
    "WGPU_",
    "vblank_mode",
];

/// The driver variables a worker for `id` inherits from this process's environment (an
/// `LP_NATIVE_VECTOR_WIDTH=128` in the shell, a CI file's `MESA_DEBUG`): those umbra neither
/// sets itself ([`worker_env`]) nor removes ([`env_removed`]). A run's reproduce command and
/// its repro bundle carry them, since without them the run may not reproduce.
pub fn inherited_driver_env(id: &str) -> Vec<(String, String)> {
    let own: Vec<String> = worker_env(id).into_iter().map(|(k, _)| k).collect();
    let removed = env_removed(id);
    // vars_os: a variable that is not UTF-8 (any program may set one) is skipped, not a panic.
    let mut env: Vec<(String, String)> = std::env::vars_os()
        .filter_map(|(k, v)| Some((k.into_string().ok()?, v.into_string().ok()?)))
        .filter(|(k, _)| DRIVER_VARIABLES.iter().any(|p| k.starts_with(p)))
        .filter(|(k, _)| !own.contains(k) && !removed.contains(&k.as_str()))
        .collect();
    env.sort();
    env
}

/// Whether this process can host the id (its driver environment is in place, and the
/// selected Mesa build's, which only a fresh process can load).
pub fn hostable_here(id: &str) -> bool {
    if let Some(build) = crate::harness::mesa_build::selected() {
        let here = std::env::var(crate::harness::mesa_build::ENV).ok();
        if crate::harness::mesa_build::is_mesa_backed(id)
            && (here.as_deref() != Some(&*build.root.to_string_lossy())
                || std::env::var_os("LIBGL_DRIVERS_PATH").as_deref()
                    != build.dri.as_deref().map(|d| d.as_os_str()))
        {
            return false;
        }
    }
    match (umbra_wgpu::Target::parse(id), umbra_gl::parse_id(id)) {
        (Some(t), _) if t.kind == umbra_wgpu::Kind::Gl && t.is_software() => {
            umbra_gl::Driver::Llvmpipe.is_selected()
        }
        (Some(t), _) if t.kind == umbra_wgpu::Kind::Vulkan => {
            std::env::var("NODEVICE_SELECT").is_ok_and(|v| v == "1")
        }
        (None, Some((_, d))) => d.is_selected(),
        // A device id needs no environment of its own, only none of Mesa's selection.
        _ => MESA_SELECTION.iter().all(|v| std::env::var_os(v).is_none()),
    }
}

/// Creates the backend `id` in this process. `Err` says why it cannot exist here: an unknown
/// id (with the list), or a driver that is unavailable (with the package to install).
pub fn create(id: &str) -> Result<Box<dyn Backend>, CreateError> {
    if id == "ref" {
        return Ok(Box::new(umbra_ref::RefBackend));
    }
    if crate::harness::fake::enabled() {
        if let Some(f) = crate::harness::fake::Fake::new(id) {
            return Ok(Box::new(f));
        }
    }
    if let Some(target) = umbra_wgpu::Target::parse(id) {
        return umbra_wgpu::WgpuBackend::new(target)
            .map(|b| Box::new(b) as Box<dyn Backend>)
            .map_err(|e| CreateError::Unavailable(e.0));
    }
    if let Some((api, name)) = umbra_gl::parse_device_id(id) {
        return umbra_gl::GlBackend::on_device(api, name)
            .map(|b| Box::new(b) as Box<dyn Backend>)
            .map_err(|e| CreateError::Unavailable(e.0));
    }
    match umbra_gl::parse_id(id) {
        Some((api, driver)) => umbra_gl::GlBackend::new(api, driver)
            .map(|b| Box::new(b) as Box<dyn Backend>)
            .map_err(|e| CreateError::Unavailable(e.0)),
        None => Err(CreateError::Unknown(format!(
            "unknown backend {id:?}; this build has: {}",
            known().join(", ")
        ))),
    }
}

/// Why a backend could not be created.
#[derive(Debug)]
pub enum CreateError {
    /// No such id: a usage error.
    Unknown(String),
    /// The backend exists but cannot run here: every run is a skip with this reason.
    Unavailable(String),
}

impl std::fmt::Display for CreateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CreateError::Unknown(s) | CreateError::Unavailable(s) => f.write_str(s),
        }
    }
}
