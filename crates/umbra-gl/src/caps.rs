//! What a GL driver can do, probed once when its context is made, in the style of wgpu-hal's
//! gles backend: the renderer and `GlBackend::supports` read these fields, never the
//! driver's name, so a driver's differences have one home. Each field says which version or
//! extension grants it; a case needing what a driver lacks is a skip that names it.

use std::collections::HashSet;

use glow::HasContext as _;

use crate::api::Api;

/// A GL context's capabilities.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Caps {
    /// The API flavour the context was made for.
    pub api: Api,
    /// The context's version (major, minor): what the driver gave for the flavour's request,
    /// often more (a GLES 3.0 request gets Mesa's highest GLES, 3.2 on llvmpipe).
    pub version: (u32, u32),
    /// Every extension the context advertises.
    pub extensions: HashSet<String>,
    /// KHR_debug: the driver's error messages fail a run's stage.
    pub debug_output: bool,
    /// GL_TIME_ELAPSED queries (GL 3.3 core, ARB_timer_query). GLES has them only through
    /// EXT_disjoint_timer_query, whose results a disjoint event voids: umbra times GLES with
    /// the CPU clock around glFinish instead.
    pub timer_queries: bool,
    /// The polygon-offset clamp's entry point name (glPolygonOffsetClamp, GL 4.6 or
    /// ARB_polygon_offset_clamp; glPolygonOffsetClampEXT, EXT_polygon_offset_clamp), when
    /// the context advertises one and EGL returned its pointer.
    pub offset_clamp: Option<&'static str>,
    /// CLAMP_TO_BORDER: core in GL 3.3; GLES 3.0 needs EXT/OES_texture_border_clamp.
    pub border_clamp: bool,
    /// Depth textures with a compare sampler: GL 3.3 and GLES 3.0 core. GLES 2 has neither
    /// (OES_depth_texture, issue 1), so it packs depth into RGBA8 and compares in the shader.
    pub depth_compare: bool,
    /// GLES 2's packed-depth path: the polygon offset applied in the shader needs
    /// OES_standard_derivatives (the depth slope) and EXT_frag_depth.
    pub shader_offset: bool,
    /// Seamless cube filtering: GLES 3.0 always; GL 3.3 only when enabled
    /// (ARB_seamless_cube_map), which umbra leaves off (the GL profile models it off).
    pub seamless_cube_always: bool,
    /// Depth clamping (ARB_depth_clamp, core in GL 3.2; EXT_depth_clamp on GLES 2 and 3):
    /// `shadow.depth_clamp` enables GL_DEPTH_CLAMP in the shadow pass; without it such a case
    /// is a skip that names the extension.
    pub depth_clamp: bool,
    /// Cube-map arrays (`shadow.placement` `cube_array`): GL_ARB_texture_cube_map_array on
    /// GL 3.3 (core in GL 4.0), the extension the lit shader enables; on GLES a 3.2 context,
    /// where they are core and the lit program is written in ESSL 3.20 (the extensions
    /// GL_EXT/OES_texture_cube_map_array are written against ESSL 3.10, and Mesa refuses them
    /// in `#version 300 es`). Without it such a case is a skip that names what is missing.
    pub cube_map_array: bool,
    /// sRGB colour targets (`camera.color_format` `srgb8_alpha8`): SRGB8_ALPHA8 is
    /// colour-renderable in GL 3.0 and GLES 3.0 core; GLES 2 needs GL_EXT_sRGB (SRGB_ALPHA_EXT).
    pub srgb_target: bool,
    /// 24-bit depth renderbuffers: core in GL 3.3 and GLES 3.0, OES_depth24 on GLES 2, whose
    /// path renders both passes into DEPTH_COMPONENT24 renderbuffers (the packed-depth
    /// profile models a 24-bit camera depth buffer); without it GLES 2 is a skip.
    pub depth24_renderbuffer: bool,
    /// GL_MAX_TEXTURE_SIZE, GL_MAX_CUBE_MAP_TEXTURE_SIZE and GL_MAX_RENDERBUFFER_SIZE: a
    /// case whose map or image is larger is a skip (umbra's own limits, 16384 and 8192, are
    /// llvmpipe's; other drivers may stop lower).
    pub max_texture: u32,
    /// See `max_texture`.
    pub max_cube: u32,
    /// See `max_texture`.
    pub max_renderbuffer: u32,
    /// The depth bits the driver chose for an unsized `DEPTH_COMPONENT` texture uploaded as
    /// UNSIGNED_INT (GL_TEXTURE_DEPTH_SIZE; GL 3.3 and GLES 3.1 can ask, GLES 3.0 cannot):
    /// GL 4.6 §8.5 leaves the resolution to the GL, and umbra's model covers 24 and 32 bits
    /// (`DepthFormat::offset_unit_range`), so another answer makes unsized cases a skip that
    /// names it rather than a failure of a correct driver. None where it cannot be asked.
    pub unsized_depth_bits: Option<u32>,
}

impl Caps {
    /// Probes the current context.
    pub fn probe(gl: &glow::Context, api: Api, offset_clamp: Option<&'static str>) -> Caps {
        let extensions = gl.supported_extensions().clone();
        let has = |e: &str| extensions.contains(e);
        // SAFETY: plain queries on the current context.
        let limit = |name| unsafe { gl.get_parameter_i32(name) }.max(0) as u32;
        let version = gl.version();
        let can_ask_level = !version.is_embedded || (version.major, version.minor) >= (3, 1);
        Caps {
            depth24_renderbuffer: api != Api::Gles2 || has("GL_OES_depth24"),
            max_texture: limit(glow::MAX_TEXTURE_SIZE),
            max_cube: limit(glow::MAX_CUBE_MAP_TEXTURE_SIZE),
            max_renderbuffer: limit(glow::MAX_RENDERBUFFER_SIZE),
            unsized_depth_bits: (api != Api::Gles2 && can_ask_level)
                .then(|| unsized_depth_bits(gl))
                .flatten(),
            api,
            version: (version.major, version.minor),
            debug_output: has("GL_KHR_debug"),
            timer_queries: api == Api::Gl33,
            offset_clamp,
            border_clamp: api == Api::Gl33
                || has("GL_EXT_texture_border_clamp")
                || has("GL_OES_texture_border_clamp"),
            depth_compare: api != Api::Gles2,
            shader_offset: has("GL_OES_standard_derivatives") && has("GL_EXT_frag_depth"),
            seamless_cube_always: api == Api::Gles3,
            depth_clamp: api == Api::Gl33 || has("GL_EXT_depth_clamp"),
            srgb_target: api != Api::Gles2 || has("GL_EXT_sRGB"),
            cube_map_array: match api {
                Api::Gl33 => has(crate::shaders::CUBE_ARRAY_EXTENSION),
                Api::Gles3 => (version.major, version.minor) >= (3, 2),
                Api::Gles2 => false,
            },
            extensions,
        }
    }

    /// Whether the context advertises `ext`.
    pub fn has(&self, ext: &str) -> bool {
        self.extensions.contains(ext)
    }
}

/// GL_TEXTURE_DEPTH_SIZE of a 1×1 unsized DEPTH_COMPONENT texture uploaded as UNSIGNED_INT,
/// as the shadow pass makes it; None if the driver refuses (the error is cleared).
fn unsized_depth_bits(gl: &glow::Context) -> Option<u32> {
    // SAFETY: a texture of this context, made, queried and deleted here; the previous
    // binding of TEXTURE_2D on unit 0 is restored (nothing is bound yet at probe time).
    unsafe {
        let tex = gl.create_texture().ok()?;
        gl.bind_texture(glow::TEXTURE_2D, Some(tex));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            glow::DEPTH_COMPONENT as i32,
            1,
            1,
            0,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_INT,
            glow::PixelUnpackData::Slice(None),
        );
        let bits = gl.get_tex_level_parameter_i32(glow::TEXTURE_2D, 0, glow::TEXTURE_DEPTH_SIZE);
        let ok = gl.get_error() == glow::NO_ERROR;
        while gl.get_error() != glow::NO_ERROR {}
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.delete_texture(tex);
        (ok && bits > 0).then_some(bits as u32)
    }
}
