//! Choosing the adapter for a backend id and opening a device on it, once per process.
//!
//! - `wgpu-vk/NAME`: `Backends::VULKAN`, the adapter named NAME ([`adapter_slug`]):
//!   `lavapipe` for Mesa's CPU adapter, `radv`, `anv`, `nvidia` … on a GPU.
//! - `wgpu-gl/NAME`: `Backends::GL`, which finds the EGL display by itself (Mesa's
//!   surfaceless one here, `llvmpipe`).
//!
//! Adapters are chosen by their names, which come from what the driver reports; no driver is
//! assumed. No adapter is [`Unavailable`] with the packages to install. Optional features
//! (timestamp queries, clamp-to-border) are enabled when the adapter has them and their absence
//! turns the runs that need them into skips.

use std::sync::{Arc, Mutex};

use crate::render::Gpu;

/// Why a device could not be opened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unavailable(pub String);

/// The API a wgpu backend drives: the first part of its id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// wgpu on Vulkan (`wgpu-vk/…`).
    Vulkan,
    /// wgpu's GL backend, OpenGL ES 3 through EGL (`wgpu-gl/…`).
    Gl,
}

impl Kind {
    /// Both kinds, in report order.
    pub const ALL: [Kind; 2] = [Kind::Vulkan, Kind::Gl];

    /// What umbra-wgpu can do on this kind: [0, 1] clip depth and a whole-unit depth-bias
    /// constant on both; a shader compare only on Vulkan (naga's GLSL output has no
    /// `textureLoad` from a depth texture).
    pub fn capabilities(self) -> umbra_case::Capabilities {
        umbra_case::Capabilities {
            driver: true,
            umbra_makes_gl_calls: false,
            gl_texture_units: false,
            zero_to_one_depth: true,
            integer_depth_bias: true,
            manual_compare: self == Kind::Vulkan,
            gles2_technique: false,
        }
    }

    /// The id's first part.
    pub fn prefix(self) -> &'static str {
        match self {
            Kind::Vulkan => "wgpu-vk",
            Kind::Gl => "wgpu-gl",
        }
    }

    /// The kind of a wgpu backend id (`wgpu-vk/radv` is Vulkan), whatever its adapter.
    pub fn parse(id: &str) -> Option<Kind> {
        let (prefix, _) = id.split_once('/')?;
        Kind::ALL.into_iter().find(|k| k.prefix() == prefix)
    }

    fn backends(self) -> wgpu::Backends {
        match self {
            Kind::Vulkan => wgpu::Backends::VULKAN,
            Kind::Gl => wgpu::Backends::GL,
        }
    }

    fn packages(self) -> &'static str {
        match self {
            Kind::Vulkan => "mesa-vulkan-drivers and libvulkan1 (or the GPU's Vulkan driver)",
            Kind::Gl => "libegl1, libegl-mesa0 and libgl1-mesa-dri (or the GPU's EGL driver)",
        }
    }
}

/// A wgpu backend id: a kind and the name of an adapter ([`adapter_slug`]).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Target {
    /// Vulkan or wgpu's GL backend.
    pub kind: Kind,
    /// The adapter's name in ids: `lavapipe`, `radv`, `nvidia`, `radv.2` ….
    pub adapter: String,
}

impl Target {
    /// Mesa's software adapters, the ids a machine without a GPU has: Vulkan on lavapipe
    /// and wgpu's GL backend on llvmpipe.
    pub fn software() -> [Target; 2] {
        [
            Target {
                kind: Kind::Vulkan,
                adapter: "lavapipe".into(),
            },
            Target {
                kind: Kind::Gl,
                adapter: "llvmpipe".into(),
            },
        ]
    }

    /// Parses `wgpu-vk/NAME` or `wgpu-gl/NAME`.
    pub fn parse(id: &str) -> Option<Target> {
        let kind = Kind::parse(id)?;
        let (_, adapter) = id.split_once('/')?;
        umbra_case::BackendId::is_name_part(adapter).then(|| Target {
            kind,
            adapter: adapter.to_string(),
        })
    }

    /// The backend id.
    pub fn id(&self) -> String {
        format!("{}/{}", self.kind.prefix(), self.adapter)
    }

    /// Whether this is one of Mesa's software adapters ([`Target::software`]).
    pub fn is_software(&self) -> bool {
        Target::software().contains(self)
    }
}

/// An adapter's name in backend ids, from what its driver reports. Vulkan: Mesa's CPU
/// adapter (driver `llvmpipe`) is `lavapipe`, Mesa's own name for its Vulkan driver; ANV
/// reports "Intel open-source Mesa driver" and is `anv`; any other driver's name is its
/// first word (`radv`, `nvidia` for "NVIDIA", `nvk` for "NVK"). wgpu's GL backend reports
/// no driver name: the first word of GL_RENDERER (`llvmpipe`, `nvidia`). Lower case,
/// letters, digits, `-` and `_` only; `unknown` when nothing is reported.
pub fn adapter_slug(kind: Kind, driver: &str, name: &str, cpu: bool) -> String {
    let driver_l = driver.to_ascii_lowercase();
    let raw = match kind {
        Kind::Vulkan if cpu && driver_l == "llvmpipe" => "lavapipe".to_string(),
        Kind::Vulkan if driver_l.starts_with("intel open-source mesa") => "anv".to_string(),
        Kind::Vulkan if !driver_l.trim().is_empty() => {
            driver_l.split_whitespace().next().unwrap_or("").to_string()
        }
        _ => name
            .to_ascii_lowercase()
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_string(),
    };
    umbra_case::BackendId::name_part(&raw)
}

/// A wgpu instance on `backends`, without the indirect-call validation wgpu turns on by
/// default: umbra draws nothing indirect, and that validation builds compute pipelines at
/// `request_device`, which wgpu's GL backend cannot compile on a desktop GL 3.3 context that
/// advertises ARB_compute_shader (naga wants GLSL 4.20 for compute) and reports as "Parent
/// device is lost": seen on NVIDIA 580.159.04 (H200), gfx-rs/wgpu#8616 and #4751.
fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    desc.flags = desc
        .flags
        .difference(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
    wgpu::Instance::new(desc)
}

/// Every adapter of `kind` with its name in ids: [`adapter_slug`], and `.2`, `.3` … for a
/// second and third adapter of one driver, in wgpu's enumeration order (the Vulkan loader's
/// physical-device order), which is not tied to a PCI slot: drivers.txt records each
/// adapter's vendor and device ids.
pub fn named_adapters(kind: Kind) -> Vec<(String, wgpu::Adapter)> {
    let instance = instance(kind.backends());
    let adapters = pollster::block_on(instance.enumerate_adapters(kind.backends()));
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    adapters
        .into_iter()
        .map(|a| {
            let i = a.get_info();
            let slug = adapter_slug(
                kind,
                &i.driver,
                &i.name,
                i.device_type == wgpu::DeviceType::Cpu,
            );
            let n = seen.entry(slug.clone()).or_default();
            *n += 1;
            let name = if *n == 1 { slug } else { format!("{slug}.{n}") };
            (name, a)
        })
        .collect()
}

/// Whether the adapter is a hardware device (not a CPU adapter such as lavapipe), and how
/// it is reached, in words, with its PCI ids.
pub fn describe(adapter: &wgpu::Adapter) -> (bool, String) {
    let i = adapter.get_info();
    (
        i.device_type != wgpu::DeviceType::Cpu,
        format!(
            "{:?} adapter {:?}, driver {:?} {:?}, vendor {:#06x} device {:#06x}",
            i.backend, i.name, i.driver, i.driver_info, i.vendor, i.device
        ),
    )
}

/// Opens a device on the adapter `target` names.
pub fn open(target: &Target) -> Result<Gpu, Unavailable> {
    let kind = target.kind;
    let named = named_adapters(kind);
    let have: Vec<String> = named
        .iter()
        .map(|(n, _)| format!("{}/{n}", kind.prefix()))
        .collect();
    let Some((_, adapter)) = named.into_iter().find(|(n, _)| *n == target.adapter) else {
        return Err(Unavailable(if have.is_empty() {
            format!(
                "no adapter on {:?}; install the Debian packages {}",
                kind.backends(),
                kind.packages()
            )
        } else {
            format!(
                "no adapter named {:?} on {:?}; this machine has {} (`umbra backends` lists them)",
                target.adapter,
                kind.backends(),
                have.join(", ")
            )
        }));
    };
    let wanted = wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::ADDRESS_MODE_CLAMP_TO_BORDER
        | wgpu::Features::DEPTH_CLIP_CONTROL;
    let features = adapter.features() & wanted;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("umbra"),
        required_features: features,
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .map_err(|e| Unavailable(format!("the adapter refused a device: {e}")))?;
    let uncaptured = Arc::new(Mutex::new(Vec::new()));
    let sink = Arc::clone(&uncaptured);
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        if let Ok(mut v) = sink.lock() {
            v.push(e.to_string());
        }
    }));
    let renderable = |f| {
        adapter
            .get_texture_format_features(f)
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
    };
    let vis_format = if renderable(wgpu::TextureFormat::R32Float) {
        wgpu::TextureFormat::R32Float
    } else {
        wgpu::TextureFormat::Rgba8Unorm
    };
    let downlevel = adapter.get_downlevel_capabilities().flags;
    let depth_copies = downlevel.contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
    let depth_bias_clamp = downlevel.contains(wgpu::DownlevelFlags::DEPTH_BIAS_CLAMP);
    let cube_arrays = downlevel.contains(wgpu::DownlevelFlags::CUBE_ARRAY_TEXTURES);
    Ok(Gpu {
        device,
        queue,
        info: adapter.get_info(),
        features,
        uncaptured,
        vis_format,
        depth_copies,
        depth_bias_clamp,
        cube_arrays,
    })
}

/// Every adapter wgpu enumerates on Vulkan and on its GL backend, as it describes itself
/// (`umbra backends`).
pub fn adapters() -> Vec<wgpu::AdapterInfo> {
    let backends = wgpu::Backends::VULKAN | wgpu::Backends::GL;
    let instance = instance(backends);
    pollster::block_on(instance.enumerate_adapters(backends))
        .into_iter()
        .map(|a| a.get_info())
        .collect()
}
