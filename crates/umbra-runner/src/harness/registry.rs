//! Backend ids and how to make them: `ref`, `API/DRIVER` for GL (`gl33/llvmpipe`,
//! `gles2/zink`, ...), and `wgpu-vk/lavapipe`, `wgpu-gl/llvmpipe`.
//!
//! A Mesa driver is chosen by environment before EGL loads, so a process hosts one driver.
//! [`driver_env`] says which environment an id needs; the commands run ids whose driver this
//! process did not load in a child process of their own ([`crate::harness::child`]).

use umbra_case::Backend;

/// Whether `id` names a backend of this build (fake ones only where enabled).
pub fn is_known(id: &str) -> bool {
    known().iter().any(|k| k == id)
        || (crate::harness::fake::enabled() && crate::harness::fake::Fake::new(id).is_some())
}

/// The backends a command was asked for: the `--backend` values, `default` when there are
/// none; `all` anywhere means every known backend. An unknown id is an error naming the
/// known ones.
pub fn selected(named: &[&str], default: Vec<String>) -> Result<Vec<String>, String> {
    let ids: Vec<String> = if named.is_empty() {
        default
    } else if named.contains(&"all") {
        known()
    } else {
        named.iter().map(|s| s.to_string()).collect()
    };
    match ids.iter().find(|b| !is_known(b)) {
        Some(bad) => Err(format!(
            "unknown backend {bad:?}; this build has: {}",
            known().join(", ")
        )),
        None => Ok(ids),
    }
}

/// Every backend id this build knows, in report order.
pub fn known() -> Vec<String> {
    let mut ids = vec!["ref".to_string()];
    ids.extend(umbra_gl::ids());
    ids.extend(umbra_wgpu::Kind::ALL.iter().map(|k| k.id().to_string()));
    ids
}

/// The environment the id's driver needs, if any (wgpu's GL backend loads Mesa's EGL, so it
/// needs llvmpipe's).
pub fn driver_env(id: &str) -> Option<Vec<(&'static str, &'static str)>> {
    match umbra_wgpu::Kind::parse(id) {
        Some(umbra_wgpu::Kind::GlLlvmpipe) => Some(umbra_gl::Driver::Llvmpipe.env()),
        // The Vulkan device-select layer only complains about DISPLAY and XDG_RUNTIME_DIR.
        Some(umbra_wgpu::Kind::VulkanLavapipe) => Some(vec![("NODEVICE_SELECT", "1")]),
        None => umbra_gl::parse_id(id).map(|(_, d)| d.env()),
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
            env.extend(build.env());
        }
    }
    env.push((
        crate::harness::memory_limit::ENV.to_string(),
        crate::harness::memory_limit::budget().to_string(),
    ));
    if std::env::var_os("GLIBC_TUNABLES").is_none() {
        env.push(("GLIBC_TUNABLES".into(), MALLOC_TUNABLES.into()));
    }
    // insta's whole environment is umbra's (the inherited one is removed at the spawn).
    env.extend(crate::judge::golden::insta_env(false));
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
    match (umbra_wgpu::Kind::parse(id), umbra_gl::parse_id(id)) {
        (Some(umbra_wgpu::Kind::GlLlvmpipe), _) => umbra_gl::Driver::Llvmpipe.is_selected(),
        (Some(umbra_wgpu::Kind::VulkanLavapipe), _) => {
            std::env::var("NODEVICE_SELECT").is_ok_and(|v| v == "1")
        }
        (None, Some((_, d))) => d.is_selected(),
        (None, None) => true,
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
    if let Some(kind) = umbra_wgpu::Kind::parse(id) {
        return umbra_wgpu::WgpuBackend::new(kind)
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
