//! The shadow pass: the map's storage (a depth texture of the case's format, 2D or a cube,
//! with its mip chain; GLES 2: RGBA8 beside a depth renderbuffer), its framebuffer (depth
//! only, or with the dummy colour attachment some drivers needed), the pass's state (depth
//! test and order, culling, the polygon offset, which GLES 2 applies in the shader) and one
//! draw per face and drawn level; averaged mip levels after it.

use umbra_case::BackendError;
use umbra_case::fault::Fault;
use umbra_case::format::{Attachments, DepthFormat, DepthFunc, Mipmaps};

use super::{FRESH_MAP_SAMPLER, Renderer, Resources, RunPlan, gl_err, set_cull, status_name};
use crate::shaders;

/// The shadow pass's programs: the depth pass's, and the down-sampling one for averaged levels.
pub(super) struct ShadowPrograms {
    depth: glow::Program,
    average: Option<glow::Program>,
}

/// The framebuffer's extra attachments: GLES 2's depth renderbuffer, the dummy colour texture.
struct Target {
    depth_rb: Option<glow::Renderbuffer>,
    dummy: Option<glow::Texture>,
    /// GLES 2's cascade textures, drawn face by face in place of the map's face.
    layers: Vec<glow::Texture>,
}

impl Renderer {
    /// Compiles (or finds) the shadow pass's programs.
    pub(super) fn shadow_programs(&mut self, p: &RunPlan) -> Result<ShadowPrograms, BackendError> {
        let api = self.api;
        let depth = self.program(
            shaders::shadow_vertex(api),
            shaders::shadow_fragment(api, p.s.attachments == Attachments::WithColor),
        )?;
        let average = if p.drawn_levels < p.levels {
            Some(self.program(shaders::average_vertex(api), shaders::average_fragment(api))?)
        } else {
            None
        };
        Ok(ShadowPrograms { depth, average })
    }

    /// The run's shadow map: `reuse` (a twin's, reset to a fresh map's sampler state), or a
    /// new one drawn here.
    pub(super) fn shadow_map(
        &self,
        p: &RunPlan,
        programs: &ShadowPrograms,
        res: &mut Resources,
        reuse: Option<glow::Texture>,
    ) -> Result<glow::Texture, BackendError> {
        if let Some(map) = reuse {
            return self.reset_kept(p, map);
        }
        let map = self.map_storage(p, res)?;
        let target = self.shadow_target(p, res)?;
        self.shadow_state(p, programs.depth)?;
        self.draw_faces(p, programs.depth, map, &target)?;
        let gl = &self.g();
        // SAFETY: state of the current context.
        unsafe {
            gl.disable(glow::POLYGON_OFFSET_FILL);
            if self.caps.depth_clamp {
                gl.disable(glow::DEPTH_CLAMP);
            }
            gl.disable(glow::CULL_FACE);
            gl.front_face(glow::CCW);
            gl.color_mask(true, true, true, true);
        }
        if let Some(program) = programs.average {
            self.average_levels(program, map, p, res)?;
        }
        Ok(map)
    }

    /// A kept map (the twin's shadow pass is the case's), with a fresh map's sampler state.
    fn reset_kept(&self, p: &RunPlan, map: glow::Texture) -> Result<glow::Texture, BackendError> {
        let gl = &self.g();
        // SAFETY: a texture of the current context.
        unsafe {
            gl.bind_texture(p.target, Some(map));
            for (param, v) in FRESH_MAP_SAMPLER {
                gl.tex_parameter_i32(p.target, param, v as i32);
            }
            if !p.es2 {
                gl.tex_parameter_i32(p.target, glow::TEXTURE_COMPARE_MODE, glow::NONE as i32);
            }
        }
        self.check("kept shadow map")?;
        Ok(map)
    }

    /// The map's texture, every face and level allocated, with a fresh map's sampler state.
    fn map_storage(&self, p: &RunPlan, res: &mut Resources) -> Result<glow::Texture, BackendError> {
        if let Some(map) = p.array_map {
            // A later light's layer of the array the first light's pass allocated.
            return Ok(map);
        }
        if p.separate_layers {
            return self.layer_textures(p, res);
        }
        let gl = &self.g();
        let (s, target, levels) = (p.s, p.target, p.levels);
        // SAFETY: objects of the current context.
        let map = unsafe {
            let map = gl.create_texture().map_err(|e| gl_err("shadow map", e))?;
            res.maps.push(map);
            gl.bind_texture(target, Some(map));
            let (internal, format, ty) = if p.es2 {
                (glow::RGBA as i32, glow::RGBA, glow::UNSIGNED_BYTE)
            } else {
                depth_format(s.format)
            };
            if p.layered {
                // One level (validation refuses levels on a cascade array), a layer a cascade.
                gl.tex_image_3d(
                    target,
                    0,
                    internal,
                    s.size[0] as i32,
                    s.size[1] as i32,
                    p.array_layers as i32,
                    0,
                    format,
                    ty,
                    glow::PixelUnpackData::Slice(None),
                );
            }
            // An array's layers were allocated at once above.
            for ft in p.face_targets().into_iter().filter(|_| !p.layered) {
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
            for (param, v) in FRESH_MAP_SAMPLER {
                gl.tex_parameter_i32(target, param, v as i32);
            }
            if levels > 1 {
                // Complete with exactly the case's levels (the default MAX_LEVEL, 1000, would
                // ask for levels below 1 × 1 that a non-square map lacks).
                gl.tex_parameter_i32(target, glow::TEXTURE_BASE_LEVEL, 0);
                gl.tex_parameter_i32(target, glow::TEXTURE_MAX_LEVEL, levels as i32 - 1);
            }
            map
        };
        self.check("shadow map storage")?;
        Ok(map)
    }

    /// GLES 2's cascades: no array textures, so a 2D RGBA8 texture per cascade (one level:
    /// validation refuses levels on cascades), each with a fresh map's sampler state, all in
    /// [`Resources::layer_maps`]; the first is returned as the run's map. None is kept for a
    /// twin (a twin draws its own).
    fn layer_textures(
        &self,
        p: &RunPlan,
        res: &mut Resources,
    ) -> Result<glow::Texture, BackendError> {
        let gl = &self.g();
        let [w, h] = p.s.size;
        for _ in 0..p.faces {
            // SAFETY: objects of the current context.
            unsafe {
                let t = gl.create_texture().map_err(|e| gl_err("shadow map", e))?;
                res.textures.push(t);
                res.layer_maps.push(t);
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                gl.tex_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    glow::RGBA as i32,
                    w as i32,
                    h as i32,
                    0,
                    glow::RGBA,
                    glow::UNSIGNED_BYTE,
                    glow::PixelUnpackData::Slice(None),
                );
                for (param, v) in FRESH_MAP_SAMPLER {
                    gl.tex_parameter_i32(glow::TEXTURE_2D, param, v as i32);
                }
            }
        }
        self.check("shadow map storage")?;
        Ok(res.layer_maps[0])
    }

    /// The pass's framebuffer, bound, with GLES 2's depth renderbuffer and the dummy colour
    /// texture of `with_color` (the map itself is attached per face and level).
    fn shadow_target(&self, p: &RunPlan, res: &mut Resources) -> Result<Target, BackendError> {
        let gl = &self.g();
        let [mw, mh] = p.s.size;
        // SAFETY: objects of the current context; completeness is checked before drawing.
        unsafe {
            let fbo = gl
                .create_framebuffer()
                .map_err(|e| gl_err("shadow pass", e))?;
            res.framebuffers.push(fbo);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            let mut depth_rb = None;
            if p.es2 {
                let rb = gl
                    .create_renderbuffer()
                    .map_err(|e| gl_err("shadow pass", e))?;
                res.renderbuffers.push(rb);
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                gl.renderbuffer_storage(
                    glow::RENDERBUFFER,
                    es2_depth(p.s.format),
                    mw as i32,
                    mh as i32,
                );
                depth_rb = Some(rb);
            }
            let mut dummy = None;
            if p.s.attachments == Attachments::WithColor && !p.es2 {
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
            Ok(Target {
                depth_rb,
                dummy,
                layers: res.layer_maps.clone(),
            })
        }
    }

    /// The pass's state: its program, the depth test in the case's order, culling, and the
    /// polygon offset (GLES 2: the shader's uniform, its clamp included).
    fn shadow_state(&self, p: &RunPlan, program: glow::Program) -> Result<(), BackendError> {
        let gl = &self.g();
        let (s, bias) = (p.s, &p.bias);
        // SAFETY: state of the current context.
        unsafe {
            gl.use_program(Some(program));
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(gl_depth_func(Fault::depth_func(p.fault, s)));
            gl.depth_mask(true);
            gl.front_face(glow::CCW);
            // GL_DEPTH_CLAMP (ARB_depth_clamp; EXT_depth_clamp's enum has the same value):
            // no near/far clipping, each fragment's depth clamped to the depth range after
            // the offset. GLES 2's shader clamps its own depth too (shaders::shadow_fragment).
            if self.caps.depth_clamp {
                if Fault::depth_clamp(p.fault, s.depth_clamp) {
                    gl.enable(glow::DEPTH_CLAMP);
                } else {
                    gl.disable(glow::DEPTH_CLAMP);
                }
            }
            set_cull(gl, s.cull);
            let [factor, units] = bias.polygon_offset;
            let clamp = bias.polygon_offset_clamp;
            let sign = p.conv.toward_far();
            if p.es2 {
                // Applied in the shader (see shaders::shadow_fragment), clamp included.
                let r = s.format.offset_unit(0.0);
                gl.uniform_3_f32(
                    gl.get_uniform_location(program, "u_offset").as_ref(),
                    sign * factor,
                    sign * r * units,
                    sign * clamp,
                );
                gl.disable(glow::POLYGON_OFFSET_FILL);
            } else if factor != 0.0 || units != 0.0 {
                gl.enable(glow::POLYGON_OFFSET_FILL);
                match (clamp != 0.0, self.ctx.polygon_offset_clamp) {
                    // SAFETY: the entry point of an advertised extension, on the current
                    // context, with the GL signature (factor, units, clamp).
                    (true, Some(f)) => {
                        gl.extension_call(
                            self.caps.offset_clamp.unwrap_or("glPolygonOffsetClamp"),
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
        }
        Ok(())
    }

    /// One draw per face and per level the map's source draws, each into its own attachment
    /// with its viewport, cleared to the far plane of the case's order.
    fn draw_faces(
        &self,
        p: &RunPlan,
        program: glow::Program,
        map: glow::Texture,
        t: &Target,
    ) -> Result<(), BackendError> {
        let gl = &self.g();
        let (s, es2) = (p.s, p.es2);
        // SAFETY: objects of the current context; completeness is checked before drawing.
        unsafe {
            let vp_loc = gl.get_uniform_location(program, "u_view_proj");
            let passes = p
                .face_targets()
                .into_iter()
                .enumerate()
                .flat_map(|(k, ft)| (0..p.drawn_levels).map(move |level| (k, ft, level)));
            for (k, ft, level) in passes {
                let [lw, lh] = Mipmaps::level_size(s.size, level);
                if p.is(Fault::ShadowViewport) {
                    let [cw, ch] = p.run.camera.size;
                    gl.viewport(0, 0, cw as i32, ch as i32);
                } else {
                    gl.viewport(0, 0, lw as i32, lh as i32);
                }
                if es2 {
                    gl.framebuffer_texture_2d(
                        glow::FRAMEBUFFER,
                        glow::COLOR_ATTACHMENT0,
                        ft,
                        Some(t.layers.get(k).copied().unwrap_or(map)),
                        0,
                    );
                    gl.framebuffer_renderbuffer(
                        glow::FRAMEBUFFER,
                        glow::DEPTH_ATTACHMENT,
                        glow::RENDERBUFFER,
                        t.depth_rb,
                    );
                } else {
                    p.attach_depth(gl, ft, k, map, level);
                    if let Some(c) = t.dummy {
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
                let clear = p.conv.clear_depth();
                gl.clear_depth_f32(clear);
                gl.clear_color(clear, clear, clear, clear); // GLES 2: packed far plane (1.0 unpacks past 1)
                gl.clear(
                    glow::DEPTH_BUFFER_BIT
                        | if es2 || t.dummy.is_some() {
                            glow::COLOR_BUFFER_BIT
                        } else {
                            0
                        },
                );
                let m = face_matrix(p, k, lw, lh);
                let mistake = p.fault.and_then(|f| f.face_mistake(k, p.cube));
                // A face drawn with a wrong orientation (mirrors flip the front face with it,
                // so that only the face's content moves).
                let mirrored = mistake.is_some_and(|(_, mirrors)| mirrors);
                gl.front_face(if mirrored { glow::CW } else { glow::CCW });
                gl.uniform_matrix_4_f32_slice(vp_loc.as_ref(), false, &m.to_cols_array());
                gl.draw_arrays(glow::TRIANGLES, 0, p.count);
                self.check(&format!("shadow pass (face {k}, level {level})"))?;
            }
        }
        Ok(())
    }

    /// Fills levels 1.. of the bound 2D `map` (`levels` in all, level 0 drawn) with the
    /// mean of the level above, one down-sampling pass per level, as a program generating
    /// depth mips does ([`shaders::average_fragment`]). The level read is the texture's only
    /// level while the next is drawn (BASE_LEVEL = MAX_LEVEL), so no feedback loop forms.
    fn average_levels(
        &self,
        program: glow::Program,
        map: glow::Texture,
        p: &RunPlan,
        res: &mut Resources,
    ) -> Result<(), BackendError> {
        let (s, levels) = (p.s, p.levels);
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
            gl.depth_func(gl_depth_func(Fault::depth_func(p.fault, s)));
        }
        self.check("mip levels")
    }
}

/// Face `k`'s view-projection at a `lw` × `lh` level, with the self-test's geometric faults
/// (a shift in texels, a wrong orientation) applied.
fn face_matrix(p: &RunPlan, k: usize, lw: u32, lh: u32) -> glam::Mat4 {
    // A layer shift moves a cascade's map; a cube's faces are the face faults' to move.
    let drawn = Fault::drawn_view(p.fault, k, p.faces, p.layered && !p.cube);
    let mut m = p.run.light.views[drawn].view_proj(p.conv);
    let [sx, sy] = p.fault.map_or([0.0; 2], |f| f.shadow_shift_texels());
    if sx != 0.0 || sy != 0.0 {
        // Texels to NDC: 2 · t / size.
        m = glam::Mat4::from_translation(glam::Vec3::new(
            2.0 * sx / lw as f32,
            2.0 * sy / lh as f32,
            0.0,
        )) * m;
    }
    if let Some((wrong, _)) = p.fault.and_then(|f| f.face_mistake(k, p.cube)) {
        m = wrong * m;
    }
    m
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

/// GLES 2 depth renderbuffer: 16 bits, or 24 with OES_depth24 (`Caps::depth24_renderbuffer`:
/// a driver without it skips GLES 2).
pub(super) fn es2_depth(f: DepthFormat) -> u32 {
    match f {
        DepthFormat::Depth16 => glow::DEPTH_COMPONENT16,
        _ => glow::DEPTH_COMPONENT24,
    }
}

/// glDepthFunc's enum for the shadow pass's depth test.
fn gl_depth_func(f: DepthFunc) -> u32 {
    match f {
        DepthFunc::Less => glow::LESS,
        DepthFunc::LessEqual => glow::LEQUAL,
        DepthFunc::Greater => glow::GREATER,
        DepthFunc::GreaterEqual => glow::GEQUAL,
    }
}
