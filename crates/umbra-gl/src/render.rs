//! One run on a GL context: the shadow pass into a framebuffer object, the lit pass into a
//! colour and a visibility target, readback. Every GL object is created and deleted inside
//! [`Renderer::render`]; only compiled programs are cached across runs.
//!
//! - **Shadow pass.** A depth texture of the case's format (2D, or a cube map for a point
//!   light), `glDrawBuffers(NONE)` and `glReadBuffer(NONE)` and colour writes off for
//!   `depth_only`; a dummy RGBA8 colour texture beside depth for `with_color`. GLES 2 renders
//!   packed depth into an RGBA8 texture with a depth renderbuffer for the depth test.
//!   Completeness is checked and a failure names the status.
//! - **Lit pass.** Colour (RGBA8) and visibility + face id (RGBA8: R = visibility, GBA = face
//!   id + 1) as two render targets; GLES 2 has one target, so it draws the pass twice, once
//!   per output (the "honest way": same geometry, same lookup, a uniform selects the output).
//!   Visibility is therefore quantised to 8 bits (1/255), which moves a PCF average by at most
//!   half a step: the judge's PCF tolerance accounts for the result bits.
//! - **Errors.** `glGetError` after every stage and, where KHR_debug exists, the driver's
//!   error messages; either fails the run with the stage's name.
//! - **Timings.** `GL_TIME_ELAPSED` queries on GL 3.3; CPU wall time around `glFinish`
//!   elsewhere.
//! - **Readback.** GL rows are bottom first: every image is flipped once, in [`flip_rows`].

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glow::HasContext;
use umbra_case::format::{
    Attachments, Cull, DepthFormat, DepthOrder, Filter, MipFilter, MipSource, Mipmaps, Outside,
};
use umbra_case::technique::CompareOp;
use umbra_case::{
    BackendError, Clock, Convention, DepthMap, Frame, LightKind, LookupMatrices, Prepared,
    Technique, Timings, VisibilityStorage,
};

use crate::api::Api;
use crate::context::{GlContext, Unavailable};
use crate::record::{Gl, Readback, Recorder, Recording};
use crate::shaders;

/// Floats per vertex of `Geometry::interleaved`.
const STRIDE: usize = umbra_case::Geometry::VERTEX_FLOATS;

/// A GL context ready to render runs.
pub struct Renderer {
    ctx: GlContext,
    /// The API flavour.
    pub api: Api,
    programs: HashMap<(String, String), glow::Program>,
    debug: Arc<Mutex<Vec<String>>>,
    /// Whether GL_TIME_ELAPSED queries work.
    pub timer_queries: bool,
    /// The shadow map of the last run rendered by [`Renderer::render`], kept for its twins
    /// ([`Renderer::render_twin`]) and deleted by the next run.
    kept: Option<KeptMap>,
    /// Whether `Renderer::new` turned KHR_debug's output on.
    debug_output: bool,
    /// Attached while [`Renderer::render_recorded`] runs.
    recorder: Option<std::cell::RefCell<Recorder>>,
}

/// A run's shadow map, kept for the twins that share its shadow pass.
struct KeptMap {
    /// The case it was rendered for.
    case: umbra_case::Case,
    texture: glow::Texture,
}

/// A new shadow map's sampler state (the lit pass sets its own; a kept map is reset to this).
const FRESH_MAP_SAMPLER: [(u32, u32); 4] = [
    (glow::TEXTURE_MIN_FILTER, glow::NEAREST),
    (glow::TEXTURE_MAG_FILTER, glow::NEAREST),
    (glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE),
    (glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE),
];

/// The largest shadow map kept for a twin (all faces, 4 bytes a texel): a map beyond it is
/// rendered again for the twin rather than held in memory between runs.
const KEEP_LIMIT: u64 = 256 << 20;

impl Renderer {
    /// Whether glPolygonOffsetClamp[EXT] was loaded.
    pub fn has_offset_clamp(&self) -> bool {
        self.ctx.polygon_offset_clamp.is_some()
    }
}

fn gl_err(stage: &str, message: impl Into<String>) -> BackendError {
    BackendError::Api {
        stage: stage.into(),
        message: message.into(),
    }
}

/// Reverses the row order of an image (GL reads bottom row first; frames are top first).
pub fn flip_rows<T: Clone>(data: &[T], row_len: usize) -> Vec<T> {
    data.chunks(row_len).rev().flatten().cloned().collect()
}

impl Renderer {
    /// Creates a context for `api` in this process's driver.
    pub fn new(api: Api) -> Result<Renderer, Unavailable> {
        let mut ctx = GlContext::new(api)?;
        let debug = Arc::new(Mutex::new(Vec::new()));
        let exts = ctx.gl.supported_extensions().clone();
        if exts.contains("GL_KHR_debug") {
            let sink = Arc::clone(&debug);
            // SAFETY: the context is current; the callback only copies the message.
            unsafe {
                ctx.gl.enable(glow::DEBUG_OUTPUT);
                ctx.gl.enable(glow::DEBUG_OUTPUT_SYNCHRONOUS);
                ctx.gl
                    .debug_message_callback(move |_source, ty, _id, severity, msg| {
                        if ty == glow::DEBUG_TYPE_ERROR || severity == glow::DEBUG_SEVERITY_HIGH {
                            if let Ok(mut v) = sink.lock() {
                                v.push(msg.to_string());
                            }
                        }
                    });
            }
        }
        let timer_queries = api == Api::Gl33;
        Ok(Renderer {
            ctx,
            api,
            programs: HashMap::new(),
            debug,
            timer_queries,
            kept: None,
            debug_output: exts.contains("GL_KHR_debug"),
            recorder: None,
        })
    }

    /// The GL calls of this renderer, recorded while a recorder is attached.
    fn g(&self) -> Gl<'_> {
        Gl::new(&self.ctx.gl, self.recorder.as_ref())
    }

    /// Renders `run` as [`Renderer::render`] does, recording every GL call as C
    /// ([`crate::record`]). Cached programs are dropped first, so that the recording compiles
    /// its own; the run has no twin, so no map is reused.
    pub fn render_recorded(&mut self, run: &Prepared) -> Result<(Frame, Recording), BackendError> {
        self.release_kept();
        for (_, p) in self.programs.drain() {
            // SAFETY: a program of this context, in use by no pending draw.
            unsafe { self.ctx.gl.delete_program(p) };
        }
        self.recorder = Some(std::cell::RefCell::new(Recorder::default()));
        let out = self.render_run(run, None);
        self.release_kept();
        let mut rec = self
            .recorder
            .take()
            .map(|r| r.into_inner().finish())
            .unwrap_or_default();
        rec.debug_output = self.debug_output;
        rec.polygon_offset_clamp = self.ctx.polygon_offset_clamp_name;
        out.map(|(f, _)| (f, rec))
    }

    /// The GL function table.
    pub fn gl(&self) -> &glow::Context {
        &self.ctx.gl
    }

    /// GL_VENDOR, GL_RENDERER, GL_VERSION and the EGL strings.
    pub fn strings(&self) -> (String, String, String, String) {
        let gl = self.gl();
        // SAFETY: plain queries on the current context.
        unsafe {
            (
                gl.get_parameter_string(glow::VENDOR),
                gl.get_parameter_string(glow::RENDERER),
                gl.get_parameter_string(glow::VERSION),
                self.ctx.egl_info.clone(),
            )
        }
    }

    /// Fails with every pending GL error and debug message of `stage`.
    pub fn check(&self, stage: &str) -> Result<(), BackendError> {
        self.g().checkpoint(stage);
        let gl = self.gl();
        let mut errors = Vec::new();
        // SAFETY: glGetError on the current context.
        unsafe {
            loop {
                let e = gl.get_error();
                if e == glow::NO_ERROR || errors.len() > 16 {
                    break;
                }
                errors.push(error_name(e).to_string());
            }
        }
        if let Ok(mut d) = self.debug.lock() {
            errors.extend(d.drain(..));
        }
        if errors.is_empty() {
            Ok(())
        } else {
            Err(gl_err(stage, errors.join("; ")))
        }
    }

    fn program(&mut self, vs: String, fs: String) -> Result<glow::Program, BackendError> {
        if let Some(p) = self.programs.get(&(vs.clone(), fs.clone())) {
            return Ok(*p);
        }
        let gl = &self.g();
        // SAFETY: shader objects of the current context, checked after each step.
        let program = unsafe {
            let program = gl.create_program().map_err(|e| gl_err("compile", e))?;
            let mut shaders = Vec::new();
            for (ty, src, what) in [
                (glow::VERTEX_SHADER, &vs, "vertex"),
                (glow::FRAGMENT_SHADER, &fs, "fragment"),
            ] {
                let s = gl.create_shader(ty).map_err(|e| gl_err("compile", e))?;
                gl.shader_source(s, src);
                gl.compile_shader(s);
                if !gl.get_shader_compile_status(s) {
                    let log = gl.get_shader_info_log(s);
                    return Err(gl_err(
                        "compile",
                        format!("{what} shader does not compile: {log}\n--- source ---\n{src}"),
                    ));
                }
                gl.attach_shader(program, s);
                shaders.push(s);
            }
            for (i, name) in ["a_pos", "a_normal", "a_albedo", "a_face"]
                .iter()
                .enumerate()
            {
                gl.bind_attrib_location(program, i as u32, name);
            }
            gl.link_program(program);
            for s in shaders {
                gl.detach_shader(program, s);
                gl.delete_shader(s);
            }
            if !gl.get_program_link_status(program) {
                return Err(gl_err("link", gl.get_program_info_log(program)));
            }
            program
        };
        self.check("compile")?;
        self.programs.insert((vs, fs), program);
        Ok(program)
    }

    /// Fills levels 1.. of the bound 2D `map` (`levels` in all, level 0 drawn) with the
    /// mean of the level above, one down-sampling pass per level, as a program generating
    /// depth mips does ([`shaders::average_fragment`]). The level read is the texture's only
    /// level while the next is drawn (BASE_LEVEL = MAX_LEVEL), so no feedback loop forms.
    fn average_levels(
        &self,
        program: glow::Program,
        map: glow::Texture,
        s: &umbra_case::format::Shadow,
        levels: u32,
        res: &mut Resources,
    ) -> Result<(), BackendError> {
        let gl = &self.g();
        // SAFETY: objects of the current context; the framebuffer's completeness is checked
        // before each draw.
        unsafe {
            let fbo = gl
                .create_framebuffer()
                .map_err(|e| gl_err("mip levels", e))?;
            res.framebuffers.push(fbo);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.draw_buffers(&[glow::NONE]);
            gl.read_buffer(glow::NONE);
            gl.use_program(Some(program));
            gl.uniform_1_i32(gl.get_uniform_location(program, "u_src").as_ref(), 0);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(map));
            gl.tex_parameter_i32(
                glow::TEXTURE_2D,
                glow::TEXTURE_COMPARE_MODE,
                glow::NONE as i32,
            );
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::ALWAYS);
            gl.depth_mask(true);
            for level in 1..levels {
                let [lw, lh] = Mipmaps::level_size(s.size, level);
                let above = level as i32 - 1;
                gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_BASE_LEVEL, above);
                gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_MAX_LEVEL, above);
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    glow::TEXTURE_2D,
                    Some(map),
                    level as i32,
                );
                let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
                if status != glow::FRAMEBUFFER_COMPLETE {
                    return Err(gl_err(
                        "mip levels",
                        format!(
                            "framebuffer of level {level} incomplete: {}",
                            status_name(status)
                        ),
                    ));
                }
                gl.viewport(0, 0, lw as i32, lh as i32);
                gl.draw_arrays(glow::TRIANGLES, 0, 3);
                self.check(&format!("mip level {level} (averaged)"))?;
            }
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_BASE_LEVEL, 0);
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_MAX_LEVEL, levels as i32 - 1);
            gl.depth_func(if s.depth_order == DepthOrder::Forward {
                glow::LESS
            } else {
                glow::GREATER
            });
        }
        self.check("mip levels")
    }

    /// Renders one run.
    pub fn render(&mut self, run: &Prepared) -> Result<Frame, BackendError> {
        self.render_run(run, None).map(|(f, _)| f)
    }

    /// Renders `twin` after `of` (the run [`Renderer::render`] rendered last): where their
    /// shadow passes are the same by construction ([`umbra_case::twin::same_shadow_pass`]),
    /// the lit pass reads the map kept from `of` (`true`, and the frame has no shadow map).
    pub fn render_twin(
        &mut self,
        twin: &Prepared,
        of: &Prepared,
    ) -> Result<(Frame, bool), BackendError> {
        self.render_run(twin, Some(of))
    }

    fn render_run(
        &mut self,
        run: &Prepared,
        twin_of: Option<&Prepared>,
    ) -> Result<(Frame, bool), BackendError> {
        let start = Instant::now();
        self.ctx
            .make_current()
            .map_err(|e| gl_err("make current", e.0))?;
        let reuse = match (twin_of, &self.kept) {
            (Some(of), Some(k))
                if k.case == *of.case()
                    && umbra_case::twin::same_shadow_pass(of.case(), run.case()) =>
            {
                Some(k.texture)
            }
            _ => None,
        };
        if twin_of.is_none() {
            self.release_kept();
        }
        let mut res = Resources::default();
        let out = self.render_with(run, &mut res, start, reuse);
        if twin_of.is_none() && out.is_ok() {
            let [mw, mh] = run.case().shadow.size;
            let bytes = 4 * u64::from(mw) * u64::from(mh) * run.light.views.len() as u64;
            if bytes <= KEEP_LIMIT {
                if let Some(texture) = res.shadow_map.take() {
                    self.kept = Some(KeptMap {
                        case: run.case().clone(),
                        texture,
                    });
                }
            }
        }
        res.delete(&self.g());
        // A failed run must not leave errors behind for the next one.
        let _ = self.check("cleanup");
        out.map(|f| (f, reuse.is_some()))
    }

    /// Deletes the kept shadow map, if any.
    fn release_kept(&mut self) {
        if let Some(k) = self.kept.take() {
            // SAFETY: a texture this renderer created on its own context, bound to nothing
            // that outlives a run.
            unsafe { self.g().delete_texture(k.texture) };
        }
    }

    fn render_with(
        &mut self,
        run: &Prepared,
        res: &mut Resources,
        start: Instant,
        reuse: Option<glow::Texture>,
    ) -> Result<Frame, BackendError> {
        let case = run.case();
        let s = &case.shadow;
        let api = self.api;
        let conv = Convention::GL.with_order(s.depth_order);
        let cube = matches!(run.light.kind, LightKind::Point { .. });
        let es2 = api == Api::Gles2;
        // A deliberate mistake, only under `cargo xtask selftest`.
        let fault = umbra_case::fault::Fault::active();
        let is = |f: umbra_case::fault::Fault| fault == Some(f);
        // The case's bias as the (faulted) backend applies it.
        let bias = fault.map_or_else(
            || run.case().shadow.bias.clone(),
            |f| f.bias(&run.case().shadow.bias),
        );
        self.check("before the run")?;

        let verts = run.geometry.interleaved();
        let count = (verts.len() / STRIDE) as i32;
        let gl = &self.g();
        // SAFETY: buffers and vertex arrays of the current context.
        unsafe {
            let vbo = gl.create_buffer().map_err(|e| gl_err("upload", e))?;
            res.buffers.push(vbo);
            if api != Api::Gles2 {
                let vao = gl.create_vertex_array().map_err(|e| gl_err("upload", e))?;
                res.vaos.push(vao);
                gl.bind_vertex_array(Some(vao));
            }
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.buffer_data_u8_slice(glow::ARRAY_BUFFER, f32_bytes(&verts), glow::STATIC_DRAW);
            for (i, (size, offset)) in [(3, 0), (3, 3), (3, 6), (1, 9)].iter().enumerate() {
                gl.enable_vertex_attrib_array(i as u32);
                gl.vertex_attrib_pointer_f32(
                    i as u32,
                    *size,
                    glow::FLOAT,
                    false,
                    (STRIDE * 4) as i32,
                    offset * 4,
                );
            }
        }
        self.check("upload")?;

        // Shadow pass.
        let [mw, mh] = s.size;
        let faces = run.light.views.len();
        let target = if cube {
            glow::TEXTURE_CUBE_MAP
        } else {
            glow::TEXTURE_2D
        };
        let shadow_program = self.program(
            shaders::shadow_vertex(api),
            shaders::shadow_fragment(api, s.attachments == Attachments::WithColor),
        )?;
        // A mipmapped map's levels, and how many of them shadow passes draw (the rest are
        // averaged from the level above: MipSource::Averaged).
        let levels = s.mipmaps.map_or(1, |m| m.levels);
        let drawn_levels = match s.mipmaps {
            Some(m) if m.source == MipSource::Averaged => 1,
            _ => levels,
        };
        let average_program = if drawn_levels < levels {
            Some(self.program(shaders::average_vertex(api), shaders::average_fragment(api))?)
        } else {
            None
        };
        let gl = &self.g();
        let timer = if self.timer_queries {
            Some(Timer::new(gl)?)
        } else {
            None
        };
        let shadow_start = Instant::now();
        if let Some(t) = &timer {
            t.begin(gl, 0);
        }
        // SAFETY: objects of the current context; completeness is checked before drawing.
        let map = if let Some(map) = reuse {
            // The twin's shadow pass is the case's: its map, with a fresh map's sampler state.
            unsafe {
                gl.bind_texture(target, Some(map));
                for (p, v) in FRESH_MAP_SAMPLER {
                    gl.tex_parameter_i32(target, p, v as i32);
                }
                if !es2 {
                    gl.tex_parameter_i32(target, glow::TEXTURE_COMPARE_MODE, glow::NONE as i32);
                }
            }
            self.check("kept shadow map")?;
            map
        } else {
            unsafe {
                let map = gl.create_texture().map_err(|e| gl_err("shadow map", e))?;
                res.shadow_map = Some(map);
                gl.bind_texture(target, Some(map));
                let face_targets: Vec<u32> = if cube {
                    (0..6)
                        .map(|k| glow::TEXTURE_CUBE_MAP_POSITIVE_X + k)
                        .collect()
                } else {
                    vec![glow::TEXTURE_2D]
                };
                let (internal, format, ty) = if es2 {
                    (glow::RGBA as i32, glow::RGBA, glow::UNSIGNED_BYTE)
                } else {
                    depth_format(s.format)
                };
                for &ft in &face_targets {
                    for level in 0..levels {
                        let [lw, lh] = Mipmaps::level_size(s.size, level);
                        gl.tex_image_2d(
                            ft,
                            level as i32,
                            internal,
                            lw as i32,
                            lh as i32,
                            0,
                            format,
                            ty,
                            glow::PixelUnpackData::Slice(None),
                        );
                    }
                }
                for (p, v) in FRESH_MAP_SAMPLER {
                    gl.tex_parameter_i32(target, p, v as i32);
                }
                if levels > 1 {
                    // Complete with exactly the case's levels (the default MAX_LEVEL, 1000,
                    // would ask for levels below 1 × 1 that a non-square map lacks).
                    gl.tex_parameter_i32(target, glow::TEXTURE_BASE_LEVEL, 0);
                    gl.tex_parameter_i32(target, glow::TEXTURE_MAX_LEVEL, levels as i32 - 1);
                }
                self.check("shadow map storage")?;
                let fbo = gl
                    .create_framebuffer()
                    .map_err(|e| gl_err("shadow pass", e))?;
                res.framebuffers.push(fbo);
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
                let mut depth_rb = None;
                if es2 {
                    let rb = gl
                        .create_renderbuffer()
                        .map_err(|e| gl_err("shadow pass", e))?;
                    res.renderbuffers.push(rb);
                    gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                    gl.renderbuffer_storage(
                        glow::RENDERBUFFER,
                        es2_depth(s.format),
                        mw as i32,
                        mh as i32,
                    );
                    depth_rb = Some(rb);
                }
                let mut dummy = None;
                if s.attachments == Attachments::WithColor && !es2 {
                    let c = gl.create_texture().map_err(|e| gl_err("shadow pass", e))?;
                    res.textures.push(c);
                    gl.bind_texture(glow::TEXTURE_2D, Some(c));
                    gl.tex_image_2d(
                        glow::TEXTURE_2D,
                        0,
                        glow::RGBA8 as i32,
                        mw as i32,
                        mh as i32,
                        0,
                        glow::RGBA,
                        glow::UNSIGNED_BYTE,
                        glow::PixelUnpackData::Slice(None),
                    );
                    dummy = Some(c);
                }
                gl.use_program(Some(shadow_program));
                let vp_loc = gl.get_uniform_location(shadow_program, "u_view_proj");
                gl.enable(glow::DEPTH_TEST);
                gl.depth_func(if s.depth_order == DepthOrder::Forward {
                    glow::LESS
                } else {
                    glow::GREATER
                });
                gl.depth_mask(true);
                gl.front_face(glow::CCW);
                match s.cull {
                    Cull::None => gl.disable(glow::CULL_FACE),
                    Cull::Back => {
                        gl.enable(glow::CULL_FACE);
                        gl.cull_face(glow::BACK);
                    }
                    Cull::Front => {
                        gl.enable(glow::CULL_FACE);
                        gl.cull_face(glow::FRONT);
                    }
                }
                let [factor, units] = bias.polygon_offset;
                let clamp = bias.polygon_offset_clamp;
                if es2 {
                    // Applied in the shader (see shaders::shadow_fragment), clamp included.
                    let sign = conv.toward_far();
                    let r = s.format.offset_unit(0.0);
                    gl.uniform_3_f32(
                        gl.get_uniform_location(shadow_program, "u_offset").as_ref(),
                        sign * factor,
                        sign * r * units,
                        sign * clamp,
                    );
                    gl.disable(glow::POLYGON_OFFSET_FILL);
                } else if factor != 0.0 || units != 0.0 {
                    let sign = conv.toward_far();
                    gl.enable(glow::POLYGON_OFFSET_FILL);
                    match (clamp != 0.0, self.ctx.polygon_offset_clamp) {
                        // SAFETY: the entry point of an advertised extension, on the current
                        // context, with the GL signature (factor, units, clamp).
                        (true, Some(f)) => {
                            gl.extension_call(
                                self.ctx
                                    .polygon_offset_clamp_name
                                    .unwrap_or("glPolygonOffsetClamp"),
                                &[sign * factor, sign * units, sign * clamp],
                            );
                            f(sign * factor, sign * units, sign * clamp)
                        }
                        (true, None) => {
                            return Err(gl_err(
                                "shadow pass",
                                "a polygon-offset clamp without glPolygonOffsetClamp (supports() should have refused it)",
                            ));
                        }
                        (false, _) => gl.polygon_offset(sign * factor, sign * units),
                    }
                } else {
                    gl.disable(glow::POLYGON_OFFSET_FILL);
                }
                // Every face, and on a mipmapped map every level its source draws.
                let passes = face_targets
                    .iter()
                    .enumerate()
                    .flat_map(|(k, ft)| (0..drawn_levels).map(move |level| (k, ft, level)));
                for (k, ft, level) in passes {
                    let [lw, lh] = Mipmaps::level_size(s.size, level);
                    if is(umbra_case::fault::Fault::ShadowViewport) {
                        let [cw, ch] = run.camera.size;
                        gl.viewport(0, 0, cw as i32, ch as i32);
                    } else {
                        gl.viewport(0, 0, lw as i32, lh as i32);
                    }
                    if es2 {
                        gl.framebuffer_texture_2d(
                            glow::FRAMEBUFFER,
                            glow::COLOR_ATTACHMENT0,
                            *ft,
                            Some(map),
                            0,
                        );
                        gl.framebuffer_renderbuffer(
                            glow::FRAMEBUFFER,
                            glow::DEPTH_ATTACHMENT,
                            glow::RENDERBUFFER,
                            depth_rb,
                        );
                    } else {
                        gl.framebuffer_texture_2d(
                            glow::FRAMEBUFFER,
                            glow::DEPTH_ATTACHMENT,
                            *ft,
                            Some(map),
                            level as i32,
                        );
                        if let Some(c) = dummy {
                            gl.framebuffer_texture_2d(
                                glow::FRAMEBUFFER,
                                glow::COLOR_ATTACHMENT0,
                                glow::TEXTURE_2D,
                                Some(c),
                                0,
                            );
                            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0]);
                            gl.color_mask(true, true, true, true);
                        } else {
                            gl.draw_buffers(&[glow::NONE]);
                            gl.read_buffer(glow::NONE);
                            gl.color_mask(false, false, false, false);
                        }
                    }
                    let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
                    if status != glow::FRAMEBUFFER_COMPLETE {
                        return Err(gl_err(
                            "shadow pass",
                            format!(
                                "framebuffer incomplete: {} (format {}, {:?})",
                                status_name(status),
                                s.format.name(),
                                s.attachments
                            ),
                        ));
                    }
                    let clear = conv.clear_depth();
                    gl.clear_depth_f32(clear);
                    gl.clear_color(clear, clear, clear, clear); // GLES 2: packed far plane (1.0 unpacks past 1)
                    gl.clear(
                        glow::DEPTH_BUFFER_BIT
                            | if es2 || dummy.is_some() {
                                glow::COLOR_BUFFER_BIT
                            } else {
                                0
                            },
                    );
                    let mut m = run.light.views[k].view_proj(conv);
                    let [sx, sy] = fault.map_or([0.0; 2], |f| f.shadow_shift_texels());
                    if sx != 0.0 || sy != 0.0 {
                        // Texels to NDC: 2 · t / size.
                        m = glam::Mat4::from_translation(glam::Vec3::new(
                            2.0 * sx / lw as f32,
                            2.0 * sy / lh as f32,
                            0.0,
                        )) * m;
                    }
                    // A face drawn with a wrong orientation (mirrors flip the front face
                    // with it, so that only the face's content moves).
                    let mistake = fault.and_then(|f| f.face_mistake(k, cube));
                    if let Some((wrong, _)) = mistake {
                        m = wrong * m;
                    }
                    let mirrored = mistake.is_some_and(|(_, mirrors)| mirrors);
                    gl.front_face(if mirrored { glow::CW } else { glow::CCW });
                    gl.uniform_matrix_4_f32_slice(vp_loc.as_ref(), false, &m.to_cols_array());
                    gl.draw_arrays(glow::TRIANGLES, 0, count);
                    self.check(&format!("shadow pass (face {k}, level {level})"))?;
                }
                gl.disable(glow::POLYGON_OFFSET_FILL);
                gl.disable(glow::CULL_FACE);
                gl.front_face(glow::CCW);
                gl.color_mask(true, true, true, true);
                if let Some(program) = average_program {
                    self.average_levels(program, map, s, levels, res)?;
                }
                map
            }
        };
        if let Some(t) = &timer {
            t.end(gl);
        }
        // SAFETY: waiting for the pass to finish, for the CPU clock.
        unsafe { gl.finish() };
        let shadow_wall = shadow_start.elapsed();

        // Depth map readback (GL only: GLES cannot read depth with glReadPixels).
        let shadow_map = if api == Api::Gl33 && reuse.is_none() {
            let mut values = Vec::with_capacity((mw * mh) as usize * faces);
            // SAFETY: reading DEPTH_COMPONENT as FLOAT from the complete shadow framebuffer.
            unsafe {
                for k in 0..faces {
                    let ft = if cube {
                        glow::TEXTURE_CUBE_MAP_POSITIVE_X + k as u32
                    } else {
                        glow::TEXTURE_2D
                    };
                    gl.framebuffer_texture_2d(
                        glow::FRAMEBUFFER,
                        glow::DEPTH_ATTACHMENT,
                        ft,
                        Some(map),
                        0,
                    );
                    let mut bytes = vec![0u8; (mw * mh * 4) as usize];
                    gl.tag_readback(Readback::MapLayer(k as u32));
                    gl.read_pixels(
                        0,
                        0,
                        mw as i32,
                        mh as i32,
                        glow::DEPTH_COMPONENT,
                        glow::FLOAT,
                        glow::PixelPackData::Slice(Some(&mut bytes)),
                    );
                    let layer: Vec<f32> = bytes
                        .chunks_exact(4)
                        .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
                        .collect();
                    values.extend(flip_rows(&layer, mw as usize));
                }
            }
            self.check("shadow map readback")?;
            Some(DepthMap {
                width: mw,
                height: mh,
                layers: faces as u32,
                format: s.format,
                values,
            })
        } else {
            None
        };

        // Lit pass.
        let technique = api.technique(Technique::new(run, fault));
        let lit_program = self.program(
            shaders::lit_vertex(api),
            shaders::lit_fragment(api, &technique),
        )?;
        let gl = &self.g();
        let [w, h] = run.camera.size;
        let lit_start = Instant::now();
        if let Some(t) = &timer {
            t.begin(gl, 1);
        }
        let manual = technique.manual();
        // SAFETY: as above.
        let (color, vis) = unsafe {
            gl.bind_texture(target, Some(map));
            let filter = if s.filter == Filter::Linear && !manual {
                glow::LINEAR
            } else {
                glow::NEAREST
            };
            // MipBaseOnly: the sampler ignores the levels (a non-mipmapped min filter).
            let mip_filter = s
                .mipmaps
                .map(|m| m.filter)
                .filter(|_| !is(umbra_case::fault::Fault::MipBaseOnly));
            let min_filter = match (mip_filter, filter) {
                (None, f) => f,
                (Some(MipFilter::Nearest), glow::LINEAR) => glow::LINEAR_MIPMAP_NEAREST,
                (Some(MipFilter::Nearest), _) => glow::NEAREST_MIPMAP_NEAREST,
                (Some(MipFilter::Linear), glow::LINEAR) => glow::LINEAR_MIPMAP_LINEAR,
                (Some(MipFilter::Linear), _) => glow::NEAREST_MIPMAP_LINEAR,
            };
            if s.mipmaps.is_some() {
                let coarse = is(umbra_case::fault::Fault::MipLevelCoarse);
                gl.tex_parameter_i32(target, glow::TEXTURE_BASE_LEVEL, i32::from(coarse));
            }
            gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, min_filter as i32);
            gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, filter as i32);
            if !es2 {
                if manual {
                    gl.tex_parameter_i32(target, glow::TEXTURE_COMPARE_MODE, glow::NONE as i32);
                } else {
                    gl.tex_parameter_i32(
                        target,
                        glow::TEXTURE_COMPARE_MODE,
                        glow::COMPARE_REF_TO_TEXTURE as i32,
                    );
                    let func = match technique.compare_op() {
                        CompareOp::LessEqual => glow::LEQUAL,
                        CompareOp::GreaterEqual => glow::GEQUAL,
                        CompareOp::Less => glow::LESS,
                        CompareOp::Greater => glow::GREATER,
                    };
                    gl.tex_parameter_i32(target, glow::TEXTURE_COMPARE_FUNC, func as i32);
                }
            }
            if !cube && !manual {
                let wrap = match technique.texel_wrap() {
                    Outside::Lit | Outside::ClampToEdge => glow::CLAMP_TO_EDGE,
                    Outside::Repeat => glow::REPEAT,
                    Outside::Border => {
                        let c = conv.clear_depth();
                        gl.tex_parameter_f32_slice(
                            target,
                            glow::TEXTURE_BORDER_COLOR,
                            &[c, c, c, c],
                        );
                        glow::CLAMP_TO_BORDER
                    }
                };
                gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_S, wrap as i32);
                gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_T, wrap as i32);
            }
            self.check("shadow sampler")?;

            gl.use_program(Some(lit_program));
            let loc = |name: &str| gl.get_uniform_location(lit_program, name);
            let cam = run.camera.view_proj(conv);
            gl.uniform_matrix_4_f32_slice(loc("u_view_proj").as_ref(), false, &cam.to_cols_array());
            let mut light = Vec::with_capacity(16 * faces);
            let mut tex = Vec::with_capacity(16 * faces);
            for v in &run.light.views {
                let m = LookupMatrices::new(conv, v.view_proj(conv));
                light.extend_from_slice(&m.light.to_cols_array());
                tex.extend_from_slice(&m.texture.to_cols_array());
            }
            gl.uniform_matrix_4_f32_slice(
                loc("u_light[0]").or_else(|| loc("u_light")).as_ref(),
                false,
                &light,
            );
            gl.uniform_matrix_4_f32_slice(
                loc("u_tex[0]").or_else(|| loc("u_tex")).as_ref(),
                false,
                &tex,
            );
            let (pos, towards) = match run.light.kind {
                // A directional light's eye is read only by an N·L bias towards its position.
                LightKind::Directional { towards, position } => (position, towards),
                LightKind::Spot { position } | LightKind::Point { position } => {
                    (position, glam::Vec3::ZERO)
                }
            };
            gl.uniform_3_f32(loc("u_light_pos").as_ref(), pos.x, pos.y, pos.z);
            gl.uniform_3_f32(loc("u_towards").as_ref(), towards.x, towards.y, towards.z);
            let eye = run.camera.eye;
            gl.uniform_3_f32(loc("u_eye").as_ref(), eye.x, eye.y, eye.z);
            gl.uniform_2_f32(loc("u_size").as_ref(), mw as f32, mh as f32);
            gl.uniform_1_f32(loc("u_constant").as_ref(), bias.constant);
            let (scale, max) = bias.slope.map_or((0.0, 0.0), |sl| (sl.scale, sl.max));
            gl.uniform_1_f32(loc("u_slope_scale").as_ref(), scale);
            gl.uniform_1_f32(loc("u_slope_max").as_ref(), max);
            let (ndl_scale, ndl_min) = bias.n_dot_l.map_or((0.0, 0.0), |b| (b.scale, b.min));
            gl.uniform_1_f32(loc("u_ndl_scale").as_ref(), ndl_scale);
            gl.uniform_1_f32(loc("u_ndl_min").as_ref(), ndl_min);
            gl.uniform_1_f32(loc("u_normal_offset").as_ref(), bias.normal_offset);
            gl.uniform_1_i32(loc("u_map").as_ref(), 0);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(target, Some(map));
            self.check("lit pass uniforms")?;

            let targets = if es2 { 2 } else { 1 };
            let mut images = Vec::new();
            for pass in 0..targets {
                let fbo = gl.create_framebuffer().map_err(|e| gl_err("lit pass", e))?;
                res.framebuffers.push(fbo);
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
                let outputs = if es2 { 1 } else { 2 };
                let mut color_textures = Vec::new();
                for a in 0..outputs {
                    let t = gl.create_texture().map_err(|e| gl_err("lit pass", e))?;
                    res.textures.push(t);
                    gl.bind_texture(glow::TEXTURE_2D, Some(t));
                    let internal = if es2 { glow::RGBA } else { glow::RGBA8 };
                    gl.tex_image_2d(
                        glow::TEXTURE_2D,
                        0,
                        internal as i32,
                        w as i32,
                        h as i32,
                        0,
                        glow::RGBA,
                        glow::UNSIGNED_BYTE,
                        glow::PixelUnpackData::Slice(None),
                    );
                    gl.tex_parameter_i32(
                        glow::TEXTURE_2D,
                        glow::TEXTURE_MIN_FILTER,
                        glow::NEAREST as i32,
                    );
                    gl.framebuffer_texture_2d(
                        glow::FRAMEBUFFER,
                        glow::COLOR_ATTACHMENT0 + a,
                        glow::TEXTURE_2D,
                        Some(t),
                        0,
                    );
                    color_textures.push(t);
                }
                if is(umbra_case::fault::Fault::WrongTextureUnit) {
                    // glActiveTexture(GL_TEXTURE0 + 1) while the sampler uniform says 0.
                    gl.active_texture(glow::TEXTURE0);
                    gl.bind_texture(target, None);
                    gl.active_texture(glow::TEXTURE1);
                } else {
                    gl.active_texture(glow::TEXTURE0);
                }
                gl.bind_texture(target, Some(map));
                let rb = gl
                    .create_renderbuffer()
                    .map_err(|e| gl_err("lit pass", e))?;
                res.renderbuffers.push(rb);
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                let camera_depth = if es2 {
                    es2_depth(DepthFormat::Depth24)
                } else {
                    glow::DEPTH_COMPONENT32F
                };
                gl.renderbuffer_storage(glow::RENDERBUFFER, camera_depth, w as i32, h as i32);
                gl.framebuffer_renderbuffer(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    glow::RENDERBUFFER,
                    Some(rb),
                );
                if !es2 {
                    gl.draw_buffers(&[glow::COLOR_ATTACHMENT0, glow::COLOR_ATTACHMENT1]);
                }
                let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
                if status != glow::FRAMEBUFFER_COMPLETE {
                    return Err(gl_err(
                        "lit pass",
                        format!("framebuffer incomplete: {}", status_name(status)),
                    ));
                }
                gl.viewport(0, 0, w as i32, h as i32);
                gl.enable(glow::DEPTH_TEST);
                gl.depth_func(glow::LESS);
                gl.depth_mask(true);
                gl.clear_depth_f32(1.0);
                if es2 {
                    let bg = if pass == 0 {
                        [0.0, 0.0, 0.0, 1.0]
                    } else {
                        [0.0; 4]
                    };
                    gl.clear_color(bg[0], bg[1], bg[2], bg[3]);
                    gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
                    gl.uniform_1_f32(loc("u_output").as_ref(), pass as f32);
                } else {
                    gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0, 0.0, 0.0, 1.0]);
                    gl.clear_buffer_f32_slice(glow::COLOR, 1, &[0.0, 0.0, 0.0, 0.0]);
                    gl.clear(glow::DEPTH_BUFFER_BIT);
                }
                gl.draw_arrays(glow::TRIANGLES, 0, count);
                self.check("lit pass")?;
                for a in 0..outputs {
                    if !es2 {
                        gl.read_buffer(glow::COLOR_ATTACHMENT0 + a);
                    }
                    let mut bytes = vec![0u8; (w * h * 4) as usize];
                    // GL: attachment 0 colour, 1 visibility; GLES 2: pass 0 colour, 1 visibility.
                    gl.tag_readback(if a + pass as u32 == 0 {
                        Readback::Color
                    } else {
                        Readback::Visibility
                    });
                    gl.read_pixels(
                        0,
                        0,
                        w as i32,
                        h as i32,
                        glow::RGBA,
                        glow::UNSIGNED_BYTE,
                        glow::PixelPackData::Slice(Some(&mut bytes)),
                    );
                    images.push(if is(umbra_case::fault::Fault::NoYFlip) {
                        bytes
                    } else {
                        flip_rows(&bytes, (w * 4) as usize)
                    });
                }
                self.check("readback")?;
            }
            let vis = images.pop().unwrap_or_default();
            let color = images.pop().unwrap_or_default();
            (color, vis)
        };
        if let Some(t) = &timer {
            t.end(gl);
        }
        // SAFETY: as above.
        unsafe { gl.finish() };
        let lit_wall = lit_start.elapsed();
        let mut visibility = Vec::with_capacity((w * h) as usize);
        let mut surface = Vec::with_capacity((w * h) as usize);
        for px in vis.chunks_exact(4) {
            let id = u32::from(px[1]) + 256 * u32::from(px[2]) + 65536 * u32::from(px[3]);
            surface.push(id);
            visibility.push(if id == 0 {
                f32::NAN
            } else {
                f32::from(px[0]) / 255.0
            });
        }
        // A GPU interval cannot exceed the wall time we waited for it (llvmpipe's first query
        // of a context can return garbage): fall back to the CPU clock rather than report it.
        let (shadow_pass, lit_pass, clock) = match timer.as_ref().map(|t| t.read(gl)) {
            Some((a, b)) if a <= shadow_wall && b <= lit_wall => (a, b, Clock::Gpu),
            _ => (shadow_wall, lit_wall, Clock::CpuWall),
        };
        if let Some(t) = timer {
            t.delete(gl);
        }
        self.check("timer queries")?;
        let total = start.elapsed();
        Ok(Frame {
            width: w,
            height: h,
            color,
            visibility,
            surface: Some(surface),
            shadow_map,
            // The visibility target is RGBA8 on every GL flavour.
            visibility_storage: VisibilityStorage::Unorm8,
            timings: Timings {
                shadow_pass,
                lit_pass,
                readback: Duration::ZERO,
                total,
                clock: Some(clock),
            },
        })
    }
}

/// GL objects of one run, deleted at its end whatever happened.
#[derive(Default)]
struct Resources {
    /// The run's shadow map (taken out when it is kept for the run's twins).
    shadow_map: Option<glow::Texture>,
    buffers: Vec<glow::Buffer>,
    vaos: Vec<glow::VertexArray>,
    textures: Vec<glow::Texture>,
    framebuffers: Vec<glow::Framebuffer>,
    renderbuffers: Vec<glow::Renderbuffer>,
}

impl Resources {
    fn delete(self, gl: &Gl) {
        // SAFETY: deleting objects this run created on the current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            for f in self.framebuffers {
                gl.delete_framebuffer(f);
            }
            for r in self.renderbuffers {
                gl.delete_renderbuffer(r);
            }
            for t in self.textures.into_iter().chain(self.shadow_map) {
                gl.delete_texture(t);
            }
            for v in self.vaos {
                gl.delete_vertex_array(v);
            }
            for b in self.buffers {
                gl.delete_buffer(b);
            }
        }
    }
}

/// Two GL_TIME_ELAPSED queries (shadow pass, lit pass).
struct Timer {
    queries: [glow::Query; 2],
}

impl Timer {
    fn new(gl: &Gl) -> Result<Timer, BackendError> {
        // SAFETY: query objects of the current context.
        unsafe {
            Ok(Timer {
                queries: [
                    gl.create_query().map_err(|e| gl_err("timer", e))?,
                    gl.create_query().map_err(|e| gl_err("timer", e))?,
                ],
            })
        }
    }
    fn begin(&self, gl: &Gl, i: usize) {
        // SAFETY: one query active at a time.
        unsafe { gl.begin_query(glow::TIME_ELAPSED, self.queries[i]) }
    }
    fn end(&self, gl: &Gl) {
        // SAFETY: ends the active query.
        unsafe { gl.end_query(glow::TIME_ELAPSED) }
    }
    fn read(&self, gl: &Gl) -> (Duration, Duration) {
        // SAFETY: the queries have ended; the result waits for them.
        let ns = |q| unsafe { gl.get_query_parameter_u64(q, glow::QUERY_RESULT) };
        (
            Duration::from_nanos(ns(self.queries[0])),
            Duration::from_nanos(ns(self.queries[1])),
        )
    }
    fn delete(self, gl: &Gl) {
        // SAFETY: deleting this timer's queries.
        unsafe {
            for q in self.queries {
                gl.delete_query(q);
            }
        }
    }
}

/// (internal format, format, type) of a depth texture.
fn depth_format(f: DepthFormat) -> (i32, u32, u32) {
    match f {
        DepthFormat::Unsized => (
            glow::DEPTH_COMPONENT as i32,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_INT,
        ),
        DepthFormat::Depth16 => (
            glow::DEPTH_COMPONENT16 as i32,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_SHORT,
        ),
        DepthFormat::Depth24 => (
            glow::DEPTH_COMPONENT24 as i32,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_INT,
        ),
        DepthFormat::Depth32f => (
            glow::DEPTH_COMPONENT32F as i32,
            glow::DEPTH_COMPONENT,
            glow::FLOAT,
        ),
    }
}

/// GLES 2 depth renderbuffer: 16 bits, or 24 with OES_depth24 (Mesa has it).
fn es2_depth(f: DepthFormat) -> u32 {
    match f {
        DepthFormat::Depth16 => glow::DEPTH_COMPONENT16,
        _ => glow::DEPTH_COMPONENT24,
    }
}

fn f32_bytes(v: &[f32]) -> &[u8] {
    // SAFETY: f32 has no padding and any byte pattern is a valid u8.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
}

/// The name of a GL error code.
pub fn error_name(e: u32) -> &'static str {
    match e {
        glow::INVALID_ENUM => "GL_INVALID_ENUM",
        glow::INVALID_VALUE => "GL_INVALID_VALUE",
        glow::INVALID_OPERATION => "GL_INVALID_OPERATION",
        glow::INVALID_FRAMEBUFFER_OPERATION => "GL_INVALID_FRAMEBUFFER_OPERATION",
        glow::OUT_OF_MEMORY => "GL_OUT_OF_MEMORY",
        glow::STACK_OVERFLOW => "GL_STACK_OVERFLOW",
        glow::STACK_UNDERFLOW => "GL_STACK_UNDERFLOW",
        _ => "unknown GL error",
    }
}

fn status_name(s: u32) -> &'static str {
    match s {
        glow::FRAMEBUFFER_INCOMPLETE_ATTACHMENT => "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT",
        glow::FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT => {
            "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT"
        }
        glow::FRAMEBUFFER_INCOMPLETE_DRAW_BUFFER => "GL_FRAMEBUFFER_INCOMPLETE_DRAW_BUFFER",
        glow::FRAMEBUFFER_INCOMPLETE_READ_BUFFER => "GL_FRAMEBUFFER_INCOMPLETE_READ_BUFFER",
        glow::FRAMEBUFFER_UNSUPPORTED => "GL_FRAMEBUFFER_UNSUPPORTED",
        glow::FRAMEBUFFER_INCOMPLETE_MULTISAMPLE => "GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE",
        _ => "unknown framebuffer status",
    }
}
