//! [`GlBackend`]: the [`Backend`] trait over a [`Renderer`], with the driver's strings and
//! what each API can and cannot do, decided before a run starts.

use umbra_case::format::{Compare, DepthFormat, Outside};
use umbra_case::{
    Backend, BackendError, BackendId, DriverInfo, Frame, Needs, Prepared, Profile, ReproProgram,
    Support,
};

use crate::api::Api;
use crate::context::Unavailable;
use crate::driver::Driver;
use crate::render::Renderer;

/// Extensions worth recording in a report.
const NOTABLE: &[&str] = &[
    "GL_KHR_debug",
    "GL_ARB_timer_query",
    "GL_EXT_disjoint_timer_query",
    "GL_ARB_clip_control",
    "GL_ARB_seamless_cube_map",
    "GL_ARB_polygon_offset_clamp",
    "GL_EXT_polygon_offset_clamp",
    "GL_EXT_texture_border_clamp",
    "GL_OES_texture_border_clamp",
    "GL_EXT_shadow_samplers",
    "GL_OES_depth_texture",
    "GL_OES_depth24",
    "GL_OES_packed_depth_stencil",
    "GL_OES_standard_derivatives",
    "GL_EXT_frag_depth",
];

/// A GL backend: one API on the driver this process loaded.
pub struct GlBackend {
    renderer: Renderer,
    id: BackendId,
    info: DriverInfo,
}

impl GlBackend {
    /// Opens `api` on `driver`. The driver must be the one this process's environment
    /// selects (see [`Driver::env`]): Mesa reads it when EGL loads.
    pub fn new(api: Api, driver: Driver) -> Result<GlBackend, Unavailable> {
        if !driver.is_selected() {
            return Err(Unavailable(format!(
                "{} needs its own process with {}; run it through `umbra` (which starts one per driver)",
                driver.name(),
                driver.env_text()
            )));
        }
        let renderer = Renderer::new(api)?;
        let (_, renderer_name, _, _) = renderer.strings();
        if !driver.matches_renderer(&renderer_name) {
            return Err(Unavailable(format!(
                "asked for {} but the driver reports {renderer_name:?}",
                driver.name()
            )));
        }
        Ok(GlBackend::with(
            renderer,
            BackendId(format!("{}/{}", api.name(), driver.name())),
        ))
    }

    /// Opens `api` on the EGL device whose backend-id name is `name`
    /// ([`crate::platform::named_devices`]): no environment is set and no driver assumed;
    /// the device's own driver answers, whatever vendor's it is.
    pub fn on_device(api: Api, name: &str) -> Result<GlBackend, Unavailable> {
        let egl = crate::context::load_egl()?;
        let devices = crate::platform::named_devices(&egl)?;
        let Some(found) = devices.iter().find(|d| d.name == name) else {
            let have: Vec<String> = devices
                .iter()
                .map(|d| format!("{}/{} ({})", api.name(), d.name, d.device.describe()))
                .collect();
            return Err(Unavailable(format!(
                "no EGL device is named {name:?} on this machine; it has {} (`umbra backends` lists them)",
                if have.is_empty() {
                    "none".to_string()
                } else {
                    have.join(", ")
                }
            )));
        };
        let renderer = Renderer::on(api, crate::platform::Platform::Device(found.device.index))?;
        Ok(GlBackend::with(
            renderer,
            BackendId(format!("{}/{name}", api.name())),
        ))
    }

    fn with(renderer: Renderer, id: BackendId) -> GlBackend {
        let (vendor, renderer_name, version, egl) = renderer.strings();
        let mut extensions: Vec<String> = NOTABLE
            .iter()
            .filter(|e| renderer.caps.has(e))
            .map(|e| e.to_string())
            .collect();
        if let Some(bits) = renderer.caps.unsized_depth_bits {
            extensions.push(format!("DEPTH_COMPONENT={bits}bit"));
        }
        extensions.push(format!("EGL {egl}"));
        let info = DriverInfo {
            vendor,
            renderer: renderer_name,
            version,
            extensions,
            device: renderer.reached(),
        };
        GlBackend { renderer, id, info }
    }
}

impl Backend for GlBackend {
    fn id(&self) -> BackendId {
        self.id.clone()
    }

    fn info(&self) -> DriverInfo {
        self.info.clone()
    }

    fn profile(&self) -> Profile {
        match self.renderer.api {
            // Seamless cube filtering is off unless enabled, and umbra leaves it off.
            Api::Gl33 => Profile::GL,
            Api::Gles3 => Profile::GLES3,
            Api::Gles2 => Profile::GLES2,
        }
    }

    fn supports(&self, needs: &Needs) -> Support {
        let api = self.renderer.api;
        // GLES 2 applies the offset (and its clamp) in the shader; the others need the
        // extension's entry point, loaded by name (glow does not carry it).
        let caps = &self.renderer.caps;
        // Several lights may need both kinds of map: the smaller limit holds.
        let (map_limit, map_name) = match (needs.cube_map, needs.flat_map) {
            (true, true) if caps.max_texture < caps.max_cube => {
                (caps.max_texture, "GL_MAX_TEXTURE_SIZE")
            }
            (true, _) => (caps.max_cube, "GL_MAX_CUBE_MAP_TEXTURE_SIZE"),
            (false, _) => (caps.max_texture, "GL_MAX_TEXTURE_SIZE"),
        };
        if needs.map_size > map_limit {
            return Support::Unsupported(format!(
                "the shadow map is {} texels on a side and this driver's {map_name} is {map_limit}",
                needs.map_size
            ));
        }
        if needs.image_size > caps.max_renderbuffer.min(caps.max_texture) {
            return Support::Unsupported(format!(
                "the camera image is {} pixels on a side and this driver's GL_MAX_RENDERBUFFER_SIZE/GL_MAX_TEXTURE_SIZE is {}",
                needs.image_size,
                caps.max_renderbuffer.min(caps.max_texture)
            ));
        }
        if needs.format == DepthFormat::Unsized {
            if let Some(bits) = caps.unsized_depth_bits.filter(|b| ![24, 32].contains(b)) {
                return Support::Unsupported(format!(
                    "this driver stores an unsized DEPTH_COMPONENT map in {bits} bits (GL_TEXTURE_DEPTH_SIZE); GL 4.6 §8.5 lets it choose, and umbra models 24- and 32-bit storage only, so judging it would fail a correct driver"
                ));
            }
        }
        if needs.polygon_offset_clamp && api != Api::Gles2 && caps.offset_clamp.is_none() {
            return Support::Unsupported("a polygon-offset clamp needs glPolygonOffsetClamp (GL 4.6, ARB_polygon_offset_clamp) or glPolygonOffsetClampEXT (EXT_polygon_offset_clamp), which this driver does not advertise".into());
        }
        if needs.depth_clamp && !caps.depth_clamp {
            return Support::Unsupported("depth clamp (shadow.depth_clamp) needs GL_DEPTH_CLAMP: core in GL 3.2, GL_EXT_depth_clamp on GLES, which this driver does not advertise".into());
        }
        if needs.cube_array > 0 && api == Api::Gles3 && !caps.cube_map_array {
            let (major, minor) = caps.version;
            return Support::Unsupported(format!(
                "point lights' maps in one cube-map array (shadow.placement \"cube_array\") need samplerCubeArrayShadow, core in GLES 3.2 (ESSL 3.20, which umbra's lit program is then written in), and this driver's context is GLES {major}.{minor}; \"separate\" runs a cube map per light"
            ));
        }
        if needs.cube_array > 0 && api == Api::Gl33 && !caps.cube_map_array {
            return Support::Unsupported(format!(
                "point lights' maps in one cube-map array (shadow.placement \"cube_array\") need {} (core in GL 4.0 and GLES 3.2), which this driver does not advertise in this context; \"separate\" runs a cube map per light",
                crate::shaders::CUBE_ARRAY_EXTENSION
            ));
        }
        if needs.srgb_target && !caps.srgb_target {
            return Support::Unsupported("an sRGB colour target (camera.color_format srgb8_alpha8) needs GL_EXT_sRGB on GLES 2 (core in GLES 3.0 and GL 3.0), which this driver does not advertise".into());
        }
        if !caps.depth24_renderbuffer {
            return Support::Unsupported("the GLES 2 path renders into 24-bit depth renderbuffers (the packed-depth profile models them), which need OES_depth24, and this driver does not advertise it".into());
        }
        if api == Api::Gles2 && !caps.shader_offset {
            return Support::Unsupported("the GLES 2 path needs OES_standard_derivatives and EXT_frag_depth to apply the polygon offset to packed depth".into());
        }
        match api {
            // GLES 2 has no array textures: it draws cascades into a texture each, and several
            // lights into separate textures only.
            Api::Gles2 if needs.cube_array > 0 => Support::Unsupported(
                "several point lights' maps in one cube-map array (shadow.placement \"cube_array\") need array textures (GL 4.0, GLES 3.2), which GLES 2 lacks; GLES 2 runs the \"separate\" placement"
                    .into(),
            ),
            Api::Gles2 if needs.array_layers > 0 && needs.lights > 1 => Support::Unsupported(
                "several lights' maps in one 2D array (shadow.placement \"array\") need array textures (GL 3.0, GLES 3.0), which GLES 2 lacks; GLES 2 runs the \"separate\" placement"
                    .into(),
            ),
            // OES_depth_texture (issue 1) gives GLES 2 no compare sampler, and its path keeps
            // depth packed in RGBA8: a mip chain of packed depths would be filtered as
            // colours, which is neither mipmapped compare nor anything a program relies on.
            Api::Gles2 if needs.mipmaps.is_some() => Support::Unsupported(
                "GLES 2 has no depth-compare sampler (OES_depth_texture, issue 1) and packs depth in RGBA8: no mipmapped compare filter to test"
                    .into(),
            ),
            Api::Gles2 if needs.format == DepthFormat::Depth32f => Support::Unsupported(
                "GLES 2 has no float depth: the shadow pass packs depth into RGBA8 (about 24 bits)"
                    .into(),
            ),
            Api::Gles3
                if needs.outside == Outside::Border
                    && needs.compare == Compare::Hardware
                    && needs.flat_map =>
            {
                if caps.border_clamp {
                    Support::Supported
                } else {
                    Support::Unsupported(
                        "GLES 3.0 has no CLAMP_TO_BORDER without EXT/OES_texture_border_clamp"
                            .into(),
                    )
                }
            }
            _ => Support::Supported,
        }
    }

    fn render(&mut self, run: &Prepared) -> Result<Frame, BackendError> {
        self.renderer.render(run)
    }

    fn restore(&mut self) -> Result<(), String> {
        self.renderer.restore()
    }

    fn render_twin(
        &mut self,
        twin: &Prepared,
        of: &Prepared,
    ) -> Result<(Frame, bool), BackendError> {
        self.renderer.render_twin(twin, of)
    }

    fn render_recorded(&mut self, run: &Prepared) -> Result<(Frame, ReproProgram), BackendError> {
        let api = self.renderer.api;
        let (frame, rec) = self.renderer.render_recorded(run)?;
        Ok((
            frame,
            Box::new(move |header, probes| crate::repro_c::program(&rec, api, header, probes)),
        ))
    }
}
