//! [`WgpuBackend`]: the [`Backend`] trait over a wgpu device.

use umbra_case::format::{Compare, Outside};
use umbra_case::{
    Backend, BackendError, BackendId, DriverInfo, Frame, Needs, Prepared, Profile, Support,
};

use crate::device::{Kind, Target, Unavailable, open};
use crate::render::Gpu;

/// A wgpu backend.
pub struct WgpuBackend {
    gpu: Gpu,
    target: Target,
    kind: Kind,
    depth24plus: String,
}

impl WgpuBackend {
    /// Opens the device on the adapter `target` names.
    pub fn new(target: Target) -> Result<WgpuBackend, Unavailable> {
        let gpu = open(&target)?;
        let depth24plus = crate::probe::depth24plus(&gpu);
        Ok(WgpuBackend {
            gpu,
            kind: target.kind,
            target,
            depth24plus,
        })
    }
}

impl Backend for WgpuBackend {
    fn id(&self) -> BackendId {
        BackendId(self.target.id())
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
            (wgpu::Features::DEPTH_CLIP_CONTROL, "DEPTH_CLIP_CONTROL"),
        ] {
            if self.gpu.features.contains(f) {
                extensions.push(name.into());
            }
        }
        if self.gpu.cube_arrays {
            extensions.push("CUBE_ARRAY_TEXTURES".into());
        }
        DriverInfo {
            vendor: format!("{:#06x}", i.vendor),
            renderer: i.name.clone(),
            // The driver's version (wgpu's driver_info: "Mesa 22.3.6 (LLVM 15.0.6)" on
            // lavapipe, GL_VERSION on its GL backend).
            version: i.driver_info.clone(),
            extensions,
            device: format!(
                "{:?} adapter, driver {:?}, {:?}, vendor {:#06x} device {:#06x} (PCI ids on a PCI GPU)",
                i.backend, i.driver, i.device_type, i.vendor, i.device
            ),
        }
    }

    fn profile(&self) -> Profile {
        match self.kind {
            Kind::Vulkan => Profile::VULKAN,
            // wgpu's GL backend drives an OpenGL ES 3 context: GL's sampler rules, cube maps
            // always seamless.
            Kind::Gl => Profile::GLES3,
        }
    }

    fn supports(&self, needs: &Needs) -> Support {
        let max = self.gpu.device.limits().max_texture_dimension_2d;
        if needs.map_size.max(needs.image_size) > max {
            return Support::Unsupported(format!(
                "the case needs a {}-texel texture side and this adapter's max_texture_dimension_2d is {max}",
                needs.map_size.max(needs.image_size)
            ));
        }
        if needs.compare == Compare::Manual && self.kind == Kind::Gl {
            return Support::Unsupported("manual compare needs textureLoad from a depth texture, which naga's GLSL output (wgpu's GL backend) does not support".into());
        }
        if needs
            .mipmaps
            .is_some_and(|m| m.source == umbra_case::format::MipSource::Averaged)
            && self.kind == Kind::Gl
        {
            return Support::Unsupported("averaged mip levels are made by a shader that reads the level above, and naga's GLSL output (wgpu's GL backend) declares every depth texture as sampler2DShadow: textureLoad from a depth texture is refused, and a NEAREST sample at the texel's centre becomes textureLod(sampler2DShadow, vec2), which does not compile".into());
        }
        if needs.outside == Outside::Border
            && needs.compare == Compare::Hardware
            && needs.flat_map
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
        if needs.depth_clamp
            && !self
                .gpu
                .features
                .contains(wgpu::Features::DEPTH_CLIP_CONTROL)
        {
            return Support::Unsupported("depth clamp (shadow.depth_clamp) is wgpu's unclipped_depth, which needs the DEPTH_CLIP_CONTROL feature (Vulkan's depthClamp, GL_ARB/EXT_depth_clamp on its GL backend), and this adapter lacks it".into());
        }
        if needs.cube_array > 0 && needs.compare == Compare::Hardware && !self.gpu.cube_arrays {
            return Support::Unsupported("point lights' maps in one cube-map array (shadow.placement \"cube_array\") are sampled through a cube-array view, which needs wgpu's CUBE_ARRAY_TEXTURES downlevel capability (Vulkan's imageCubeArray; GL 4.0 or GLES 3.2 on its GL backend), and this adapter lacks it; \"separate\" runs a cube map per light".into());
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
