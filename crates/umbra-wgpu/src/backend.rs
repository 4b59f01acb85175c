//! [`WgpuBackend`]: the [`Backend`] trait over a wgpu device.

use umbra_case::format::{Compare, Outside};
use umbra_case::{
    Backend, BackendError, BackendId, DriverInfo, Frame, Needs, Prepared, Profile, Support,
};

use crate::device::{Kind, Unavailable, open};
use crate::render::Gpu;

/// A wgpu backend.
pub struct WgpuBackend {
    gpu: Gpu,
    kind: Kind,
    depth24plus: String,
}

impl WgpuBackend {
    /// Opens the device for `kind`.
    pub fn new(kind: Kind) -> Result<WgpuBackend, Unavailable> {
        let gpu = open(kind)?;
        let depth24plus = crate::probe::depth24plus(&gpu);
        Ok(WgpuBackend {
            gpu,
            kind,
            depth24plus,
        })
    }
}

impl Backend for WgpuBackend {
    fn id(&self) -> BackendId {
        BackendId(self.kind.id().into())
    }

    fn info(&self) -> DriverInfo {
        let i = &self.gpu.info;
        let mut extensions = vec![
            format!("backend {:?}", i.backend),
            format!("driver_info {}", i.driver_info),
            self.depth24plus.clone(),
        ];
        for (f, name) in [
            (wgpu::Features::TIMESTAMP_QUERY, "TIMESTAMP_QUERY"),
            (
                wgpu::Features::ADDRESS_MODE_CLAMP_TO_BORDER,
                "ADDRESS_MODE_CLAMP_TO_BORDER",
            ),
        ] {
            if self.gpu.features.contains(f) {
                extensions.push(name.into());
            }
        }
        DriverInfo {
            vendor: format!("{:#06x}", i.vendor),
            renderer: i.name.clone(),
            version: i.driver.clone(),
            extensions,
        }
    }

    fn profile(&self) -> Profile {
        match self.kind {
            Kind::VulkanLavapipe => Profile::VULKAN,
            // wgpu's GL backend drives an OpenGL ES 3 context: GL's sampler rules, cube maps
            // always seamless.
            Kind::GlLlvmpipe => Profile::GLES3,
        }
    }

    fn supports(&self, needs: &Needs) -> Support {
        if needs.compare == Compare::Manual && self.kind == Kind::GlLlvmpipe {
            return Support::Unsupported("manual compare needs textureLoad from a depth texture, which naga's GLSL output (wgpu's GL backend) does not support".into());
        }
        if needs
            .mipmaps
            .is_some_and(|m| m.source == umbra_case::format::MipSource::Averaged)
            && self.kind == Kind::GlLlvmpipe
        {
            return Support::Unsupported("averaged mip levels are made by a shader that reads the level above, and naga's GLSL output (wgpu's GL backend) declares every depth texture as sampler2DShadow: textureLoad from a depth texture is refused, and a NEAREST sample at the texel's centre becomes textureLod(sampler2DShadow, vec2), which does not compile".into());
        }
        if needs.outside == Outside::Border
            && needs.compare == Compare::Hardware
            && !needs.cube_map
            && !self
                .gpu
                .features
                .contains(wgpu::Features::ADDRESS_MODE_CLAMP_TO_BORDER)
        {
            return Support::Unsupported("clamp-to-border needs wgpu's ADDRESS_MODE_CLAMP_TO_BORDER feature, which this adapter lacks".into());
        }
        if needs.polygon_offset_clamp && !self.gpu.depth_bias_clamp {
            return Support::Unsupported("a polygon-offset clamp needs wgpu's DEPTH_BIAS_CLAMP downlevel capability, which this adapter lacks (wgpu's GL backend does not offer it)".into());
        }
        if needs.fractional_offset_units {
            return Support::Unsupported("wgpu's depth bias constant (DepthBiasState::constant) is an integer, and this case's polygon_offset units is not a whole number".into());
        }
        Support::Supported
    }

    fn render(&mut self, run: &Prepared) -> Result<Frame, BackendError> {
        let units = run.case().shadow.bias.polygon_offset[1];
        if units.fract() != 0.0 {
            // `supports` refuses such a case; a caller that renders anyway gets the same reason.
            return Err(BackendError::Unsupported(format!(
                "wgpu's depth bias constant is an integer; polygon_offset units {units} is not"
            )));
        }
        self.gpu.render(run)
    }
}
