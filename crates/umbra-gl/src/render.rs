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
//!
//! [`Renderer::render`] runs the stages in order over a [`RunPlan`] (what every stage reads,
//! decided once): `upload`, [`shadow_pass`], [`readback`] of the map, [`lit_pass`], the frame.
//! Every GL call goes through [`crate::record::Gl`], so `umbra repro` can record a run.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glow::HasContext;
use umbra_case::fault::Fault;
use umbra_case::format::MipSource;
use umbra_case::{
    BackendError, Clock, Convention, Frame, LightRun, Prepared, Technique, Timings,
    VisibilityStorage,
};

use crate::api::Api;
use crate::caps::Caps;
use crate::context::{GlContext, Unavailable};
use crate::record::{Gl, Recorder, Recording};

mod lit_pass;
mod readback;
mod shadow_pass;

use shadow_pass::ShadowPrograms;

/// Floats per vertex of `Geometry::interleaved`.
const STRIDE: usize = umbra_case::Geometry::VERTEX_FLOATS;

/// A GL context ready to render runs.
pub struct Renderer {
    ctx: GlContext,
    /// The API flavour.
    pub api: Api,
    /// What the driver can do, probed once.
    pub caps: Caps,
    /// Compiled programs by source, at most [`PROGRAM_CACHE`] of them.
    programs: HashMap<(String, String), glow::Program>,
    debug: Arc<Mutex<Vec<String>>>,
    /// The shadow map of the last run rendered by [`Renderer::render`], kept for its twins
    /// ([`Renderer::render_twin`]) and deleted by the next run.
    kept: Option<KeptMap>,
    /// Attached while [`Renderer::render_recorded`] runs.
    recorder: Option<std::cell::RefCell<Recorder>>,
}

/// A run's shadow maps, kept for the twins that share its shadow pass.
struct KeptMap {
    /// The case it was rendered for.
    case: umbra_case::Case,
    /// Each light's map, in the case's order (the lights of an array share one texture).
    maps: Vec<glow::Texture>,
    /// The textures themselves, each once (deleted when the maps are released).
    textures: Vec<glow::Texture>,
}

/// The most compiled programs a renderer keeps between runs, all dropped at once when
/// reached: a catalogue worker recompiles now and then (the catalogue's wall time did not
/// move: 284 s on 22.3.6), a soak's one-off programs no longer pile up.
const PROGRAM_CACHE: usize = 32;

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

/// Face culling as `cull` asks (the winding that counts as front is the caller's): the shadow
/// pass's `shadow.cull` and the lit pass's `camera.cull`.
fn set_cull(gl: &Gl, cull: umbra_case::format::Cull) {
    use umbra_case::format::Cull;
    // SAFETY: state of the current context.
    unsafe {
        match cull {
            Cull::None => gl.disable(glow::CULL_FACE),
            Cull::Back | Cull::Front => {
                gl.enable(glow::CULL_FACE);
                gl.cull_face(if cull == Cull::Back {
                    glow::BACK
                } else {
                    glow::FRONT
                });
            }
        }
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
        Renderer::with(GlContext::new(api)?)
    }

    /// Creates a context for `api` on `platform` (an EGL device named by its backend id).
    pub fn on(api: Api, platform: crate::platform::Platform) -> Result<Renderer, Unavailable> {
        Renderer::with(GlContext::on(crate::context::load_egl()?, api, platform)?)
    }

    /// How EGL reached the driver ([`GlContext::reached`]).
    pub fn reached(&self) -> String {
        self.ctx.reached()
    }

    fn with(mut ctx: GlContext) -> Result<Renderer, Unavailable> {
        let api = ctx.api;
        let caps = Caps::probe(&ctx.gl, api, ctx.polygon_offset_clamp_name);
        let debug = Arc::new(Mutex::new(Vec::new()));
        if caps.debug_output {
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
        Ok(Renderer {
            ctx,
            api,
            caps,
            programs: HashMap::new(),
            debug,
            kept: None,
            recorder: None,
        })
    }

    /// The GL calls of this renderer, recorded while a recorder is attached.
    fn g(&self) -> Gl<'_> {
        Gl::new(&self.ctx.gl, self.recorder.as_ref())
    }

    /// Deletes every cached program.
    fn drop_programs(&mut self) {
        for (_, p) in self.programs.drain() {
            // SAFETY: a program of this context, in use by no pending draw.
            unsafe { self.ctx.gl.delete_program(p) };
        }
    }

    /// Renders `run` as [`Renderer::render`] does, recording every GL call as C
    /// ([`crate::record`]). Cached programs are dropped first, so that the recording compiles
    /// its own; the run has no twin, so no map is reused.
    pub fn render_recorded(&mut self, run: &Prepared) -> Result<(Frame, Recording), BackendError> {
        self.release_kept();
        self.drop_programs();
        self.recorder = Some(std::cell::RefCell::new(Recorder::default()));
        let out = self.render_run(run, None);
        self.release_kept();
        let mut rec = self
            .recorder
            .take()
            .map(|r| r.into_inner().finish())
            .unwrap_or_default();
        rec.debug_output = self.caps.debug_output;
        rec.polygon_offset_clamp = self.caps.offset_clamp;
        rec.egl_device = match self.ctx.platform {
            crate::platform::Platform::Device(i) => Some(i),
            crate::platform::Platform::Surfaceless => None,
        };
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
                k.maps.clone()
            }
            _ => Vec::new(),
        };
        if twin_of.is_none() {
            self.release_kept();
            // A case's constants are in its lit shader (a light's colour among several), so
            // generated cases each compile their own: unbounded, the cache held every one, and
            // a soak's zink worker grew past its memory budget (soak-43-978: 5.6 GiB).
            if self.programs.len() >= PROGRAM_CACHE {
                self.drop_programs();
            }
        }
        let mut res = Resources::default();
        let shared = !reuse.is_empty();
        let out = self.render_with(run, &mut res, start, &reuse);
        let out = match out {
            Ok((frame, maps)) => {
                let [mw, mh] = run.case().shadow.size;
                let faces: u64 = run.lights.iter().map(|l| l.light.views.len() as u64).sum();
                let bytes = 4 * u64::from(mw) * u64::from(mh) * faces;
                // Kept where every light's map is a texture of its own run (not GLES 2's
                // cascades, a texture each).
                let whole = maps.iter().all(|m| res.maps.contains(m));
                if twin_of.is_none() && bytes <= KEEP_LIMIT && whole {
                    self.kept = Some(KeptMap {
                        case: run.case().clone(),
                        maps,
                        textures: std::mem::take(&mut res.maps),
                    });
                }
                Ok(frame)
            }
            Err(e) => Err(e),
        };
        res.delete(&self.g());
        // A failed run must not leave errors behind for the next one.
        let _ = self.check("cleanup");
        out.map(|f| (f, shared))
    }

    /// Deletes the kept shadow map, if any.
    fn release_kept(&mut self) {
        if let Some(k) = self.kept.take() {
            for t in k.textures {
                // SAFETY: a texture this renderer created on its own context, bound to
                // nothing that outlives a run.
                unsafe { self.g().delete_texture(t) };
            }
        }
    }

    /// After a failed run: the context as a fresh run needs it (errors drained, the default
    /// framebuffer, program and vertex array bound), then proved by a timer query begun and
    /// ended without an error. An error means the context cannot be trusted for another run:
    /// the worker is replaced.
    pub fn restore(&mut self) -> Result<(), String> {
        self.ctx
            .make_current()
            .map_err(|e| format!("make current: {}", e.0))?;
        self.release_kept();
        let drained = self.check("restore").err();
        let gl = &self.g();
        // SAFETY: binding defaults and a probe query on the current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.use_program(None);
            if self.api != Api::Gles2 {
                gl.bind_vertex_array(None);
            }
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            gl.active_texture(glow::TEXTURE0);
            // A run that failed inside its shadow pass may leave the pass's clamp on.
            if self.caps.depth_clamp {
                gl.disable(glow::DEPTH_CLAMP);
            }
            if self.caps.timer_queries {
                let probe = Timer::new(gl).map_err(|e| e.to_string())?;
                probe.begin(gl, 0);
                probe.end(gl);
                probe.delete(gl);
            }
        }
        self.check("restore").map_err(|e| match drained {
            Some(before) => format!("{e} (after {before})"),
            None => e.to_string(),
        })
    }

    /// One run, in stages, as engines' forward renderers with a pass per light do (Unity's
    /// forward-add, Doom 3's interactions): the triangles uploaded once; every light's shadow
    /// pass (timed together) into its own map (`separate`) or its layer of one 2D array
    /// (`array`), or the maps kept from the run `reuse` is of (a twin's: none read back);
    /// every map read back (GL 3.3); every light's lit pass (timed together), the first into
    /// a fresh colour target and each later one added into it ([`Renderer::add_light`]),
    /// each light's visibility read back on its own; the colour read back once. The frame,
    /// and each light's map texture.
    fn render_with(
        &mut self,
        run: &Prepared,
        res: &mut Resources,
        start: Instant,
        reuse: &[glow::Texture],
    ) -> Result<(Frame, Vec<glow::Texture>), BackendError> {
        let mut plans: Vec<RunPlan> = run
            .lights
            .iter()
            .map(|r| RunPlan::new(r, self.api))
            .collect();
        self.check("before the run")?;
        self.upload(&run.geometry, res)?;
        // Programs are compiled (or found in the cache) before the stage that runs them, so
        // that no stage's time counts a compile.
        let shadow_programs = plans
            .iter()
            .map(|p| self.shadow_programs(p))
            .collect::<Result<Vec<_>, _>>()?;
        let (timer, shadow_start) = self.begin_stages(run, res)?;
        let maps = self.shadow_passes(&mut plans, &shadow_programs, res, reuse)?;
        let shadow_wall = self.end_stage(timer.as_ref(), shadow_start);
        // Each map read back after the timed stage (GL 3.3; none for a twin's kept maps).
        let mut stored = Vec::new();
        for (k, p) in plans.iter().enumerate() {
            stored.push(if p.api == Api::Gl33 && reuse.get(k).is_none() {
                Some(self.read_map(p, maps[k])?)
            } else {
                None
            });
        }
        let lit_programs = plans
            .iter()
            .map(|p| self.lit_program(p))
            .collect::<Result<Vec<_>, _>>()?;
        let lit_start = Instant::now();
        if let Some(t) = &timer {
            t.begin(&self.g(), 1);
        }
        let (color, planes) = self.lit_passes(&plans, lit_programs, &maps, res)?;
        let lit_wall = self.end_stage(timer.as_ref(), lit_start);
        let (shadow_pass, lit_pass, clock) =
            self.stage_times(timer.as_ref(), shadow_wall, lit_wall)?;
        let [w, h] = run.camera.size;
        let lights = planes.iter().zip(stored).map(|(v, shadow_map)| {
            let (visibility, surface) = readback::decode_visibility(v);
            umbra_case::LightPlane {
                visibility,
                shadow_map,
                surface: Some(surface),
            }
        });
        let frame = Frame {
            width: w,
            height: h,
            color,
            lights: lights.collect(),
            // The visibility target is RGBA8 on every GL flavour.
            visibility_storage: VisibilityStorage::Unorm8,
            timings: Timings {
                shadow_pass,
                lit_pass,
                readback: Duration::ZERO,
                total: start.elapsed(),
                clock: Some(clock),
            },
        };
        Ok((frame, maps))
    }

    /// Every light's shadow pass, in order: its map (a layer of the array the first light's
    /// pass allocated, where the maps share one), or the map kept for it (`reuse`). Each
    /// light's map texture.
    fn shadow_passes(
        &mut self,
        plans: &mut [RunPlan],
        programs: &[ShadowPrograms],
        res: &mut Resources,
        reuse: &[glow::Texture],
    ) -> Result<Vec<glow::Texture>, BackendError> {
        let mut maps: Vec<glow::Texture> = Vec::new();
        for (k, (p, programs)) in plans.iter_mut().zip(programs).enumerate() {
            if p.layered {
                p.array_map = maps.first().copied();
            }
            maps.push(self.shadow_map(p, programs, res, reuse.get(k).copied())?);
        }
        Ok(maps)
    }

    /// Every light's lit pass over its map: the first into a fresh colour target, each later
    /// one added into it ([`Renderer::add_light`]), each light's visibility read back on its
    /// own; the colour read once, after the last. The colour and each light's visibility.
    fn lit_passes(
        &self,
        plans: &[RunPlan],
        programs: Vec<(Technique, glow::Program)>,
        maps: &[glow::Texture],
        res: &mut Resources,
    ) -> Result<(Vec<u8>, Vec<Vec<u8>>), BackendError> {
        let mut planes = Vec::new();
        let mut target = None;
        for (k, (p, (technique, program))) in plans.iter().zip(programs).enumerate() {
            // The map light k reads: its own, unless the self-test mixes the lights up (in an
            // array, the layer is the shader's: Technique::layer).
            let read = if p.layered {
                maps[k]
            } else {
                maps[Fault::map_of_light(p.fault, k, maps.len(), false, |j| plans[j].cube)]
            };
            match target {
                None => {
                    let (fbo, vis) = self.lit_pass(p, &technique, program, read, res)?;
                    target = Some(fbo);
                    planes.push(vis);
                }
                Some(fbo) => planes.push(self.add_light(p, &technique, program, read, fbo, res)?),
            }
        }
        let target = target.ok_or_else(|| BackendError::Other("a case without a light".into()))?;
        Ok((self.read_colour(&plans[0], target)?, planes))
    }

    /// The stages' timer (where the context has timer queries), begun on the shadow pass,
    /// and the shadow pass's start; the self-test's injected GL error comes right after.
    ///
    /// The timer belongs to the run's resources: a stage that fails with its query open
    /// leaves it to `Resources::delete`, which ends it (a query left active makes every later
    /// glBeginQuery of the context fail).
    fn begin_stages(
        &self,
        run: &Prepared,
        res: &mut Resources,
    ) -> Result<(Option<Timer>, Instant), BackendError> {
        if self.caps.timer_queries {
            res.timer = Some(Timer::new(&self.g())?);
        }
        let timer = res.timer.clone();
        let shadow_start = Instant::now();
        if let Some(t) = &timer {
            t.begin(&self.g(), 0);
        }
        crate::inject::gl_error(&self.g(), run.case());
        Ok((timer, shadow_start))
    }

    /// The shadow and lit passes' times and their clock: the timer's, unless an interval
    /// exceeds the wall time waited for it (llvmpipe's first query of a context can return
    /// garbage), then the CPU clock's rather than report it.
    fn stage_times(
        &self,
        timer: Option<&Timer>,
        shadow_wall: Duration,
        lit_wall: Duration,
    ) -> Result<(Duration, Duration, Clock), BackendError> {
        let times = match timer.map(|t| t.read(&self.g())) {
            Some((a, b)) if a <= shadow_wall && b <= lit_wall => (a, b, Clock::Gpu),
            _ => (shadow_wall, lit_wall, Clock::CpuWall),
        };
        self.check("timer queries")?;
        Ok(times)
    }

    /// Ends a timed stage: its query, then glFinish for the CPU clock; the wall time.
    fn end_stage(&self, timer: Option<&Timer>, since: Instant) -> Duration {
        let gl = &self.g();
        if let Some(t) = timer {
            t.end(gl);
        }
        // SAFETY: waiting for the stage to finish, for the CPU clock.
        unsafe { gl.finish() };
        since.elapsed()
    }

    /// The run's vertices into a buffer, with the four attributes of
    /// `Geometry::interleaved` (position, normal, albedo, face id).
    fn upload(
        &self,
        geometry: &umbra_case::Geometry,
        res: &mut Resources,
    ) -> Result<(), BackendError> {
        let verts = geometry.interleaved();
        let gl = &self.g();
        // SAFETY: buffers and vertex arrays of the current context.
        unsafe {
            let vbo = gl.create_buffer().map_err(|e| gl_err("upload", e))?;
            res.buffers.push(vbo);
            if self.api != Api::Gles2 {
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
        self.check("upload")
    }
}

/// What every stage of a run reads, decided once from the case and the API.
struct RunPlan<'a> {
    run: &'a LightRun,
    s: &'a umbra_case::format::Shadow,
    api: Api,
    /// GL's clip range in the case's depth order.
    conv: Convention,
    /// A cube map (point light).
    cube: bool,
    /// An array: a 2D array with one layer per cascade or the lights' maps in its layers, or
    /// (with `cube`) a cube-map array with the point lights' cubes.
    layered: bool,
    /// The array's layer of face 0: the first of the light's among several (light k's faces
    /// are layers k · faces to k · faces + faces − 1: one per spot or directional light, six
    /// per point light in a `cube_array`), else 0.
    layer_base: usize,
    /// The array's layers: the faces, or the lights sharing it (six layer-faces each in a
    /// cube-map array).
    array_layers: usize,
    /// The array the lights share, once the first light's pass has allocated it.
    array_map: Option<glow::Texture>,
    es2: bool,
    /// GLES 2's cascades: no array textures, so each cascade is a 2D texture of its own
    /// ([`Resources::layer_maps`]), bound to unit k and read as `u_map` (k = 0) or `u_mapk`.
    separate_layers: bool,
    /// A deliberate mistake, only under `cargo xtask selftest`.
    fault: Option<Fault>,
    /// The case's bias as the (faulted) backend applies it.
    bias: umbra_case::format::Bias,
    /// Faces (views) of the light.
    faces: usize,
    /// TEXTURE_2D, TEXTURE_CUBE_MAP, TEXTURE_2D_ARRAY or TEXTURE_CUBE_MAP_ARRAY.
    target: u32,
    /// Vertices drawn.
    count: i32,
    /// The map's mip levels, and how many of them shadow passes draw (the rest are averaged
    /// from the level above: MipSource::Averaged).
    levels: u32,
    drawn_levels: u32,
}

impl<'a> RunPlan<'a> {
    fn new(run: &'a LightRun, api: Api) -> RunPlan<'a> {
        let s = &run.case().shadow;
        let fault = Fault::active();
        let cube = run.light.is_cube();
        let array = Some(run.of_lights).filter(|o| o.array);
        let layered = run.light.cascading.is_some() || array.is_some();
        let levels = s.mipmaps.map_or(1, |m| m.levels);
        RunPlan {
            run,
            s,
            api,
            conv: Convention::GL.with_order(s.depth_order),
            cube,
            layered,
            layer_base: array.map_or(0, |o| o.light * run.light.views.len()),
            array_layers: array.map_or(1, |o| o.lights) * run.light.views.len(),
            array_map: None,
            es2: api == Api::Gles2,
            separate_layers: api == Api::Gles2 && layered && !cube,
            fault,
            bias: fault.map_or_else(|| s.bias.clone(), |f| f.bias(&s.bias)),
            faces: run.light.views.len(),
            target: if cube && layered {
                glow::TEXTURE_CUBE_MAP_ARRAY
            } else if cube {
                glow::TEXTURE_CUBE_MAP
            } else if layered && api != Api::Gles2 {
                // GLES 2's cascades are 2D textures of their own (separate_layers).
                glow::TEXTURE_2D_ARRAY
            } else {
                glow::TEXTURE_2D
            },
            count: (run.geometry.triangles.len() * 3) as i32,
            levels,
            drawn_levels: match s.mipmaps {
                Some(m) if m.source == MipSource::Averaged => 1,
                _ => levels,
            },
        }
    }

    /// Whether `f` is the active self-test fault.
    fn is(&self, f: Fault) -> bool {
        self.fault == Some(f)
    }

    /// The texture target of each face: the six cube faces in GL's order, TEXTURE_2D, or
    /// the array's target for its layers (allocated at once, attached by layer).
    fn face_targets(&self) -> Vec<u32> {
        if self.cube && self.layered {
            vec![glow::TEXTURE_CUBE_MAP_ARRAY; 6]
        } else if self.separate_layers {
            vec![glow::TEXTURE_2D; self.faces]
        } else if self.cube {
            (0..6)
                .map(|k| glow::TEXTURE_CUBE_MAP_POSITIVE_X + k)
                .collect()
        } else if self.layered {
            vec![glow::TEXTURE_2D_ARRAY; self.faces]
        } else {
            vec![glow::TEXTURE_2D]
        }
    }

    /// Attaches face `k` (target `ft`) of `map` at `level` as the bound framebuffer's depth.
    fn attach_depth(&self, gl: &Gl, ft: u32, k: usize, map: glow::Texture, level: u32) {
        // SAFETY: attaching a texture of the current context to its bound framebuffer.
        unsafe {
            if self.layered {
                gl.framebuffer_texture_layer(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    Some(map),
                    level as i32,
                    (self.layer_base + k) as i32,
                );
            } else {
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    ft,
                    Some(map),
                    level as i32,
                );
            }
        }
    }
}

/// GL objects of one run, deleted at its end whatever happened.
#[derive(Default)]
struct Resources {
    /// The stages' timer queries (ended if a stage failed with one active).
    timer: Option<Timer>,
    /// Every light's map the run allocated, deleted with it unless taken out to be kept for
    /// the run's twins.
    maps: Vec<glow::Texture>,
    /// GLES 2's cascades, a 2D texture each, in cascade order (also in `textures`, and
    /// never kept for a twin); empty otherwise.
    layer_maps: Vec<glow::Texture>,
    buffers: Vec<glow::Buffer>,
    vaos: Vec<glow::VertexArray>,
    textures: Vec<glow::Texture>,
    framebuffers: Vec<glow::Framebuffer>,
    renderbuffers: Vec<glow::Renderbuffer>,
}

impl Resources {
    fn delete(self, gl: &Gl) {
        if let Some(t) = self.timer {
            t.delete(gl);
        }
        // SAFETY: deleting objects this run created on the current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            for f in self.framebuffers {
                gl.delete_framebuffer(f);
            }
            for r in self.renderbuffers {
                gl.delete_renderbuffer(r);
            }
            for t in self.textures.into_iter().chain(self.maps) {
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

/// Two GL_TIME_ELAPSED queries (shadow pass, lit pass), and which one is active. Cloned
/// handles share the state.
#[derive(Clone)]
struct Timer {
    queries: [glow::Query; 2],
    active: std::rc::Rc<std::cell::Cell<bool>>,
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
                active: Default::default(),
            })
        }
    }
    fn begin(&self, gl: &Gl, i: usize) {
        // SAFETY: one query active at a time.
        unsafe { gl.begin_query(glow::TIME_ELAPSED, self.queries[i]) }
        self.active.set(true);
    }
    fn end(&self, gl: &Gl) {
        // SAFETY: ends the active query.
        unsafe { gl.end_query(glow::TIME_ELAPSED) }
        self.active.set(false);
    }
    fn read(&self, gl: &Gl) -> (Duration, Duration) {
        // SAFETY: the queries have ended; the result waits for them.
        let ns = |q| unsafe { gl.get_query_parameter_u64(q, glow::QUERY_RESULT) };
        (
            Duration::from_nanos(ns(self.queries[0])),
            Duration::from_nanos(ns(self.queries[1])),
        )
    }
    /// Ends the active query, if a stage failed with one open, and deletes both.
    fn delete(self, gl: &Gl) {
        if self.active.get() {
            self.end(gl);
        }
        // SAFETY: deleting this timer's queries.
        unsafe {
            for q in self.queries {
                gl.delete_query(q);
            }
        }
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
