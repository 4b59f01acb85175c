//! Choosing the adapter for a backend id and opening a device on it, once per process.
//!
//! - `wgpu-vk/lavapipe`: `Backends::VULKAN`, the CPU adapter (Mesa's lavapipe).
//! - `wgpu-gl/llvmpipe`: `Backends::GL`, which finds Mesa's surfaceless EGL display by itself.
//!
//! No adapter is [`Unavailable`] with the packages to install. Optional features
//! (timestamp queries, clamp-to-border) are enabled when the adapter has them and their absence
//! turns the runs that need them into skips.

use std::sync::{Arc, Mutex};

use crate::render::Gpu;

/// Why a device could not be opened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unavailable(pub String);

/// A wgpu backend kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// Vulkan on lavapipe.
    VulkanLavapipe,
    /// wgpu's GL backend on llvmpipe.
    GlLlvmpipe,
}

impl Kind {
    /// Every kind, in report order.
    pub const ALL: [Kind; 2] = [Kind::VulkanLavapipe, Kind::GlLlvmpipe];

    /// The backend id.
    pub fn id(self) -> &'static str {
        match self {
            Kind::VulkanLavapipe => "wgpu-vk/lavapipe",
            Kind::GlLlvmpipe => "wgpu-gl/llvmpipe",
        }
    }

    /// Parses a backend id.
    pub fn parse(id: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.id() == id)
    }

    fn backends(self) -> wgpu::Backends {
        match self {
            Kind::VulkanLavapipe => wgpu::Backends::VULKAN,
            Kind::GlLlvmpipe => wgpu::Backends::GL,
        }
    }

    fn packages(self) -> &'static str {
        match self {
            Kind::VulkanLavapipe => "mesa-vulkan-drivers and libvulkan1",
            Kind::GlLlvmpipe => "libegl1, libegl-mesa0 and libgl1-mesa-dri",
        }
    }
}

/// Opens a device of `kind`.
pub fn open(kind: Kind) -> Result<Gpu, Unavailable> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = kind.backends();
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(kind.backends()));
    let adapter = adapters
        .into_iter()
        .find(|a| {
            let i = a.get_info();
            i.device_type == wgpu::DeviceType::Cpu || i.name.contains("llvmpipe")
        })
        .ok_or_else(|| {
            Unavailable(format!(
                "no CPU adapter on {:?}; install the Debian packages {}",
                kind.backends(),
                kind.packages()
            ))
        })?;
    let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::ADDRESS_MODE_CLAMP_TO_BORDER;
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
    Ok(Gpu {
        device,
        queue,
        info: adapter.get_info(),
        features,
        uncaptured,
        vis_format,
        depth_copies,
        depth_bias_clamp,
    })
}

/// Every adapter wgpu enumerates on Vulkan and on its GL backend, as it describes itself
/// (`umbra backends`).
pub fn adapters() -> Vec<wgpu::AdapterInfo> {
    let backends = wgpu::Backends::VULKAN | wgpu::Backends::GL;
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    let instance = wgpu::Instance::new(desc);
    pollster::block_on(instance.enumerate_adapters(backends))
        .into_iter()
        .map(|a| a.get_info())
        .collect()
}
