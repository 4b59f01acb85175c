//! The GL calls of a run, as the driver saw them and as C: the source of `umbra repro`'s
//! standalone program.
//!
//! Every GL call of [`crate::render`] goes through [`Gl`], a thin layer over glow with glow's
//! own signatures. Normally it only forwards. While a [`Recorder`] is attached it also writes
//! each call as a C statement with the same arguments: floats as C99 hexadecimal literals
//! (exact, where apitrace's text dump rounds to 7 digits), vertex data as a static array,
//! shader sources verbatim, object names mapped to C variables. So the emitted program makes
//! the calls umbra made, in umbra's order, from the same code path; nothing is re-derived
//! from the case. Results the renderer branches on become checks that end the program with
//! 125 (a shader that does not compile, an incomplete framebuffer, a GL error at one of
//! umbra's checkpoints), and each pixel readback becomes a call to `readback()`, which the
//! probes of `umbra repro` define. Checked against apitrace: the program's calls are umbra's,
//! argument for argument (`apitrace dump` of both), apart from the debug-output setup, which
//! the program makes once its context is current, and uniforms umbra's driver compiled away:
//! glow makes no call for them, the program sets them by name at location -1 (a no-op), so
//! that the program run on another driver that keeps them sets them as umbra would there.

use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;

use glow::HasContext;

/// What a readback holds: the probes' hook in the emitted C (`readback(KIND, layer, ...)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Readback {
    /// The lit pass's colour, RGBA8.
    Color,
    /// The lit pass's visibility (R) and face id + 1 (GBA), RGBA8.
    Visibility,
    /// One layer (face) of the shadow map, DEPTH_COMPONENT as FLOAT.
    MapLayer(u32),
}

impl Readback {
    /// The C constant naming the kind.
    pub fn c_kind(self) -> &'static str {
        match self {
            Readback::Color => "READBACK_COLOR",
            Readback::Visibility => "READBACK_VISIBILITY",
            Readback::MapLayer(_) => "READBACK_MAP",
        }
    }
}

/// The recorded run: C declarations and statements for [`crate::repro_c::program`].
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// GL entry points called, with their C return type and parameter list.
    pub functions: BTreeMap<&'static str, (&'static str, &'static str)>,
    /// GL enum names used, with their values.
    pub enums: BTreeMap<&'static str, u32>,
    /// Static data: vertex arrays and shader sources.
    pub data: String,
    /// C variables for the GL objects.
    pub objects: String,
    /// The statements, in call order.
    pub body: String,
    /// Whether umbra's context had KHR_debug's output on (the program turns it on too).
    pub debug_output: bool,
    /// The polygon-offset clamp entry point umbra loaded, if any.
    pub polygon_offset_clamp: Option<&'static str>,
    /// The EGL device umbra's context was made on (EGL_EXT_platform_device), or None for
    /// Mesa's surfaceless platform.
    pub egl_device: Option<usize>,
}

/// Writes calls as C while a run renders.
#[derive(Default)]
pub struct Recorder {
    rec: Recording,
    /// GL object (kind, name) → its C variable.
    names: HashMap<(&'static str, u32), String>,
    counts: BTreeMap<&'static str, usize>,
    /// (program, location) → uniform name, from glGetUniformLocation.
    uniforms: HashMap<(u32, u32), String>,
    program: u32,
    /// The name of the latest glGetUniformLocation, found or not: the uniform call that
    /// follows it sets that name.
    last_lookup: Option<String>,
    next_readback: Option<Readback>,
    blobs: usize,
}

impl Recorder {
    /// The recording so far.
    pub fn finish(self) -> Recording {
        self.rec
    }

    fn stmt(&mut self, line: &str) {
        self.rec.body.push_str("    ");
        self.rec.body.push_str(line);
        self.rec.body.push('\n');
    }

    fn func(&mut self, name: &'static str) -> &'static str {
        let sig = signature(name);
        self.rec.functions.insert(name, sig);
        name
    }

    fn call(&mut self, name: &'static str, args: &[String]) {
        let f = self.func(name);
        self.stmt(&format!("{f}({});", args.join(", ")));
    }

    /// A GL enum by name (or its value in hex when umbra's table lacks it).
    fn en(&mut self, v: u32) -> String {
        match enum_name(v) {
            Some(n) => {
                self.rec.enums.insert(n, v);
                n.to_string()
            }
            None => format!("0x{v:04X}"),
        }
    }

    fn new_object(&mut self, kind: &'static str, name: u32) -> String {
        let n = self.counts.entry(kind).or_insert(0);
        let var = format!("{kind}{n}");
        *n += 1;
        let _ = writeln!(self.rec.objects, "static GLuint {var};");
        self.names.insert((kind, name), var.clone());
        var
    }

    fn object(&self, kind: &'static str, name: Option<u32>) -> String {
        match name {
            None => "0".into(),
            Some(n) => self
                .names
                .get(&(kind, n))
                .cloned()
                .unwrap_or_else(|| format!("0 /* {kind} {n} made before the recording */")),
        }
    }

    /// A uniform's location as the program looks it up, by name. A uniform umbra's driver
    /// compiled away (no location: glow makes no call) is still set by name, at location -1
    /// there (a no-op, GL 4.6 §7.6.1), so that a driver that keeps it gets the value umbra
    /// would give it.
    fn location(&self, loc: Option<u32>) -> String {
        let name = match loc {
            Some(l) => self.uniforms.get(&(self.program, l)),
            None => self.last_lookup.as_ref(),
        };
        match name {
            Some(name) => format!(
                "glGetUniformLocation({}, \"{name}\")",
                self.object("program", Some(self.program))
            ),
            None => "-1".into(),
        }
    }

    fn floats(&mut self, v: &[f32]) -> String {
        let items: Vec<String> = v.iter().map(|x| hex_f32(*x)).collect();
        format!("(const GLfloat[]){{{}}}", items.join(", "))
    }

    /// A stage's end: umbra checks glGetError there, and so does the program.
    pub fn checkpoint(&mut self, stage: &str) {
        self.func("glGetError");
        self.stmt(&format!("check_gl({});", c_string(stage)));
    }

    /// A call umbra makes through a pointer of its own (an extension entry point).
    pub fn extension_call(&mut self, name: &'static str, args: &[f32]) {
        let a: Vec<String> = args.iter().map(|x| hex_f32(*x)).collect();
        self.call(name, &a);
    }
}

/// glow with every call also written to a [`Recorder`] when one is attached.
pub struct Gl<'a> {
    raw: &'a glow::Context,
    rec: Option<&'a RefCell<Recorder>>,
}

fn n<T: Copy>(o: Option<T>, f: impl Fn(T) -> u32) -> Option<u32> {
    o.map(f)
}

macro_rules! log {
    ($self:ident, |$r:ident| $body:expr) => {
        if let Some(cell) = $self.rec {
            let mut guard = cell.borrow_mut();
            let $r: &mut Recorder = &mut guard;
            $body;
        }
    };
}

/// A glow `create_*` whose GL call is `glGen*(1, &name)`.
macro_rules! generated {
    ($method:ident, $ty:ty, $kind:literal, $gen:literal) => {
        pub unsafe fn $method(&self) -> Result<$ty, String> {
            let object = unsafe { self.raw.$method() }?;
            log!(self, |r| {
                let v = r.new_object($kind, object.0.get());
                r.func($gen);
                r.stmt(&format!("{}(1, &{v});", $gen));
            });
            Ok(object)
        }
    };
}

/// A glow `delete_*` whose GL call is `glDelete*(1, &name)`.
macro_rules! deleted {
    ($method:ident, $ty:ty, $kind:literal, $gl:literal) => {
        pub unsafe fn $method(&self, object: $ty) {
            log!(self, |r| {
                let v = r.object($kind, Some(object.0.get()));
                r.func($gl);
                r.stmt(&format!("{}(1, &{v});", $gl));
            });
            unsafe { self.raw.$method(object) }
        }
    };
}

// Every method has glow's name, signature, documentation and safety contract: it forwards
// the call unchanged (and records it).
#[allow(missing_docs, clippy::missing_safety_doc, clippy::too_many_arguments)]
impl<'a> Gl<'a> {
    /// Wraps `raw`, recording into `rec` when given.
    pub fn new(raw: &'a glow::Context, rec: Option<&'a RefCell<Recorder>>) -> Gl<'a> {
        Gl { raw, rec }
    }

    /// The next `read_pixels` fills `what`.
    pub fn tag_readback(&self, what: Readback) {
        log!(self, |r| r.next_readback = Some(what));
    }

    /// A call through an entry point umbra loaded itself (see [`Recorder::extension_call`]).
    pub fn extension_call(&self, name: &'static str, args: &[f32]) {
        log!(self, |r| r.extension_call(name, args));
    }

    /// A checkpoint (see [`Recorder::checkpoint`]).
    pub fn checkpoint(&self, stage: &str) {
        log!(self, |r| r.checkpoint(stage));
    }

    pub unsafe fn get_error(&self) -> u32 {
        unsafe { self.raw.get_error() }
    }
    generated!(create_buffer, glow::Buffer, "buffer", "glGenBuffers");
    generated!(
        create_vertex_array,
        glow::VertexArray,
        "vao",
        "glGenVertexArrays"
    );
    generated!(create_texture, glow::Texture, "texture", "glGenTextures");
    generated!(
        create_framebuffer,
        glow::Framebuffer,
        "framebuffer",
        "glGenFramebuffers"
    );
    generated!(
        create_renderbuffer,
        glow::Renderbuffer,
        "renderbuffer",
        "glGenRenderbuffers"
    );
    generated!(create_query, glow::Query, "query", "glGenQueries");
    pub unsafe fn create_program(&self) -> Result<glow::Program, String> {
        let b = unsafe { self.raw.create_program() }?;
        log!(self, |r| {
            let v = r.new_object("program", b.0.get());
            r.func("glCreateProgram");
            r.stmt(&format!("{v} = glCreateProgram();"));
        });
        Ok(b)
    }
    pub unsafe fn create_shader(&self, ty: u32) -> Result<glow::Shader, String> {
        let b = unsafe { self.raw.create_shader(ty) }?;
        log!(self, |r| {
            let v = r.new_object("shader", b.0.get());
            let t = r.en(ty);
            r.func("glCreateShader");
            r.stmt(&format!("{v} = glCreateShader({t});"));
        });
        Ok(b)
    }
    pub unsafe fn shader_source(&self, s: glow::Shader, src: &str) {
        log!(self, |r| {
            let v = r.object("shader", Some(s.0.get()));
            let id = r.blobs;
            r.blobs += 1;
            let _ = writeln!(
                r.rec.data,
                "static const char source{id}[] =\n{};",
                c_text(src)
            );
            r.func("glShaderSource");
            r.stmt(&format!(
                "glShaderSource({v}, 1, (const GLchar *const[]){{source{id}}}, NULL);"
            ));
        });
        unsafe { self.raw.shader_source(s, src) }
    }
    pub unsafe fn compile_shader(&self, s: glow::Shader) {
        log!(self, |r| {
            let v = r.object("shader", Some(s.0.get()));
            r.call("glCompileShader", &[v]);
        });
        unsafe { self.raw.compile_shader(s) }
    }
    pub unsafe fn get_shader_compile_status(&self, s: glow::Shader) -> bool {
        log!(self, |r| {
            let v = r.object("shader", Some(s.0.get()));
            r.func("glGetShaderiv");
            r.func("glGetShaderInfoLog");
            r.stmt(&format!("require_compiled({v});"));
        });
        unsafe { self.raw.get_shader_compile_status(s) }
    }
    pub unsafe fn get_shader_info_log(&self, s: glow::Shader) -> String {
        unsafe { self.raw.get_shader_info_log(s) }
    }
    pub unsafe fn attach_shader(&self, p: glow::Program, s: glow::Shader) {
        log!(self, |r| {
            let a = [
                r.object("program", Some(p.0.get())),
                r.object("shader", Some(s.0.get())),
            ];
            r.call("glAttachShader", &a);
        });
        unsafe { self.raw.attach_shader(p, s) }
    }
    pub unsafe fn detach_shader(&self, p: glow::Program, s: glow::Shader) {
        log!(self, |r| {
            let a = [
                r.object("program", Some(p.0.get())),
                r.object("shader", Some(s.0.get())),
            ];
            r.call("glDetachShader", &a);
        });
        unsafe { self.raw.detach_shader(p, s) }
    }
    pub unsafe fn delete_shader(&self, s: glow::Shader) {
        log!(self, |r| {
            let v = r.object("shader", Some(s.0.get()));
            r.call("glDeleteShader", &[v]);
        });
        unsafe { self.raw.delete_shader(s) }
    }
    pub unsafe fn bind_attrib_location(&self, p: glow::Program, i: u32, name: &str) {
        log!(self, |r| {
            let a = [
                r.object("program", Some(p.0.get())),
                i.to_string(),
                c_string(name),
            ];
            r.call("glBindAttribLocation", &a);
        });
        unsafe { self.raw.bind_attrib_location(p, i, name) }
    }
    pub unsafe fn link_program(&self, p: glow::Program) {
        log!(self, |r| {
            let v = r.object("program", Some(p.0.get()));
            r.call("glLinkProgram", &[v]);
        });
        unsafe { self.raw.link_program(p) }
    }
    pub unsafe fn get_program_link_status(&self, p: glow::Program) -> bool {
        log!(self, |r| {
            let v = r.object("program", Some(p.0.get()));
            r.func("glGetProgramiv");
            r.func("glGetProgramInfoLog");
            r.stmt(&format!("require_linked({v});"));
        });
        unsafe { self.raw.get_program_link_status(p) }
    }
    pub unsafe fn get_program_info_log(&self, p: glow::Program) -> String {
        unsafe { self.raw.get_program_info_log(p) }
    }
    pub unsafe fn use_program(&self, p: Option<glow::Program>) {
        log!(self, |r| {
            r.program = p.map_or(0, |p| p.0.get());
            let v = r.object("program", n(p, |p| p.0.get()));
            r.call("glUseProgram", &[v]);
        });
        unsafe { self.raw.use_program(p) }
    }
    pub unsafe fn get_uniform_location(
        &self,
        p: glow::Program,
        name: &str,
    ) -> Option<glow::UniformLocation> {
        let loc = unsafe { self.raw.get_uniform_location(p, name) };
        log!(self, |r| {
            r.func("glGetUniformLocation");
            r.last_lookup = Some(name.to_string());
            if let Some(l) = &loc {
                r.uniforms.insert((p.0.get(), l.0), name.to_string());
            }
        });
        loc
    }
    pub unsafe fn uniform_1_f32(&self, l: Option<&glow::UniformLocation>, x: f32) {
        log!(self, |r| {
            let a = [r.location(l.map(|l| l.0)), hex_f32(x)];
            r.call("glUniform1f", &a);
        });
        unsafe { self.raw.uniform_1_f32(l, x) }
    }
    pub unsafe fn uniform_2_f32(&self, l: Option<&glow::UniformLocation>, x: f32, y: f32) {
        log!(self, |r| {
            let a = [r.location(l.map(|l| l.0)), hex_f32(x), hex_f32(y)];
            r.call("glUniform2f", &a);
        });
        unsafe { self.raw.uniform_2_f32(l, x, y) }
    }
    pub unsafe fn uniform_3_f32(&self, l: Option<&glow::UniformLocation>, x: f32, y: f32, z: f32) {
        log!(self, |r| {
            let a = [
                r.location(l.map(|l| l.0)),
                hex_f32(x),
                hex_f32(y),
                hex_f32(z),
            ];
            r.call("glUniform3f", &a);
        });
        unsafe { self.raw.uniform_3_f32(l, x, y, z) }
    }
    pub unsafe fn uniform_4_f32_slice(&self, l: Option<&glow::UniformLocation>, v: &[f32]) {
        log!(self, |r| {
            let a = [
                r.location(l.map(|l| l.0)),
                (v.len() / 4).to_string(),
                r.floats(v),
            ];
            r.call("glUniform4fv", &a);
        });
        unsafe { self.raw.uniform_4_f32_slice(l, v) }
    }
    pub unsafe fn uniform_1_f32_slice(&self, l: Option<&glow::UniformLocation>, v: &[f32]) {
        log!(self, |r| {
            let a = [r.location(l.map(|l| l.0)), v.len().to_string(), r.floats(v)];
            r.call("glUniform1fv", &a);
        });
        unsafe { self.raw.uniform_1_f32_slice(l, v) }
    }
    pub unsafe fn uniform_1_i32(&self, l: Option<&glow::UniformLocation>, x: i32) {
        log!(self, |r| {
            let a = [r.location(l.map(|l| l.0)), x.to_string()];
            r.call("glUniform1i", &a);
        });
        unsafe { self.raw.uniform_1_i32(l, x) }
    }
    pub unsafe fn uniform_matrix_4_f32_slice(
        &self,
        l: Option<&glow::UniformLocation>,
        transpose: bool,
        v: &[f32],
    ) {
        log!(self, |r| {
            let a = [
                r.location(l.map(|l| l.0)),
                (v.len() / 16).to_string(),
                c_bool(transpose),
                r.floats(v),
            ];
            r.call("glUniformMatrix4fv", &a);
        });
        unsafe { self.raw.uniform_matrix_4_f32_slice(l, transpose, v) }
    }
    pub unsafe fn bind_vertex_array(&self, v: Option<glow::VertexArray>) {
        log!(self, |r| {
            let a = r.object("vao", n(v, |v| v.0.get()));
            r.call("glBindVertexArray", &[a]);
        });
        unsafe { self.raw.bind_vertex_array(v) }
    }
    pub unsafe fn bind_buffer(&self, target: u32, b: Option<glow::Buffer>) {
        log!(self, |r| {
            let a = [r.en(target), r.object("buffer", n(b, |b| b.0.get()))];
            r.call("glBindBuffer", &a);
        });
        unsafe { self.raw.bind_buffer(target, b) }
    }
    pub unsafe fn buffer_data_u8_slice(&self, target: u32, data: &[u8], usage: u32) {
        log!(self, |r| {
            let id = r.blobs;
            r.blobs += 1;
            let floats: Vec<String> = data
                .chunks_exact(4)
                .map(|b| hex_f32(f32::from_ne_bytes([b[0], b[1], b[2], b[3]])))
                .collect();
            let _ = writeln!(
                r.rec.data,
                "static const GLfloat data{id}[{}] = {{",
                floats.len()
            );
            for row in floats.chunks(umbra_case::Geometry::VERTEX_FLOATS) {
                let _ = writeln!(r.rec.data, "    {},", row.join(", "));
            }
            r.rec.data.push_str("};\n");
            let a = [
                r.en(target),
                format!("sizeof data{id}"),
                format!("data{id}"),
                r.en(usage),
            ];
            r.call("glBufferData", &a);
        });
        unsafe { self.raw.buffer_data_u8_slice(target, data, usage) }
    }
    pub unsafe fn enable_vertex_attrib_array(&self, i: u32) {
        log!(self, |r| r
            .call("glEnableVertexAttribArray", &[i.to_string()]));
        unsafe { self.raw.enable_vertex_attrib_array(i) }
    }
    pub unsafe fn vertex_attrib_pointer_f32(
        &self,
        i: u32,
        size: i32,
        ty: u32,
        normalized: bool,
        stride: i32,
        offset: i32,
    ) {
        log!(self, |r| {
            let a = [
                i.to_string(),
                size.to_string(),
                r.en(ty),
                c_bool(normalized),
                stride.to_string(),
                format!("(const void *){offset}"),
            ];
            r.call("glVertexAttribPointer", &a);
        });
        unsafe {
            self.raw
                .vertex_attrib_pointer_f32(i, size, ty, normalized, stride, offset)
        }
    }
    pub unsafe fn bind_texture(&self, target: u32, t: Option<glow::Texture>) {
        log!(self, |r| {
            let a = [r.en(target), r.object("texture", n(t, |t| t.0.get()))];
            r.call("glBindTexture", &a);
        });
        unsafe { self.raw.bind_texture(target, t) }
    }
    pub unsafe fn active_texture(&self, unit: u32) {
        log!(self, |r| {
            let a = if (glow::TEXTURE0..glow::TEXTURE0 + 32).contains(&unit) {
                format!("GL_TEXTURE0 + {}", unit - glow::TEXTURE0)
            } else {
                format!("0x{unit:04X}")
            };
            r.en(glow::TEXTURE0);
            r.call("glActiveTexture", &[a]);
        });
        unsafe { self.raw.active_texture(unit) }
    }
    pub unsafe fn tex_image_2d(
        &self,
        target: u32,
        level: i32,
        internal: i32,
        w: i32,
        h: i32,
        border: i32,
        format: u32,
        ty: u32,
        pixels: glow::PixelUnpackData,
    ) {
        log!(self, |r| {
            let a = [
                r.en(target),
                level.to_string(),
                r.en(internal as u32),
                w.to_string(),
                h.to_string(),
                border.to_string(),
                r.en(format),
                r.en(ty),
                "NULL".into(),
            ];
            r.call("glTexImage2D", &a);
        });
        unsafe {
            self.raw
                .tex_image_2d(target, level, internal, w, h, border, format, ty, pixels)
        }
    }
    pub unsafe fn tex_image_3d(
        &self,
        target: u32,
        level: i32,
        internal: i32,
        w: i32,
        h: i32,
        depth: i32,
        border: i32,
        format: u32,
        ty: u32,
        pixels: glow::PixelUnpackData,
    ) {
        log!(self, |r| {
            let a = [
                r.en(target),
                level.to_string(),
                r.en(internal as u32),
                w.to_string(),
                h.to_string(),
                depth.to_string(),
                border.to_string(),
                r.en(format),
                r.en(ty),
                "NULL".into(),
            ];
            r.call("glTexImage3D", &a);
        });
        unsafe {
            self.raw.tex_image_3d(
                target, level, internal, w, h, depth, border, format, ty, pixels,
            )
        }
    }
    pub unsafe fn tex_parameter_i32(&self, target: u32, p: u32, v: i32) {
        log!(self, |r| {
            let value = if ENUM_VALUED.contains(&p) {
                r.en(v as u32)
            } else {
                v.to_string()
            };
            let a = [r.en(target), r.en(p), value];
            r.call("glTexParameteri", &a);
        });
        unsafe { self.raw.tex_parameter_i32(target, p, v) }
    }
    pub unsafe fn tex_parameter_f32_slice(&self, target: u32, p: u32, v: &[f32]) {
        log!(self, |r| {
            let a = [r.en(target), r.en(p), r.floats(v)];
            r.call("glTexParameterfv", &a);
        });
        unsafe { self.raw.tex_parameter_f32_slice(target, p, v) }
    }
    pub unsafe fn bind_framebuffer(&self, target: u32, f: Option<glow::Framebuffer>) {
        log!(self, |r| {
            let a = [r.en(target), r.object("framebuffer", n(f, |f| f.0.get()))];
            r.call("glBindFramebuffer", &a);
        });
        unsafe { self.raw.bind_framebuffer(target, f) }
    }
    pub unsafe fn bind_renderbuffer(&self, target: u32, b: Option<glow::Renderbuffer>) {
        log!(self, |r| {
            let a = [r.en(target), r.object("renderbuffer", n(b, |b| b.0.get()))];
            r.call("glBindRenderbuffer", &a);
        });
        unsafe { self.raw.bind_renderbuffer(target, b) }
    }
    pub unsafe fn renderbuffer_storage(&self, target: u32, internal: u32, w: i32, h: i32) {
        log!(self, |r| {
            let a = [r.en(target), r.en(internal), w.to_string(), h.to_string()];
            r.call("glRenderbufferStorage", &a);
        });
        unsafe { self.raw.renderbuffer_storage(target, internal, w, h) }
    }
    pub unsafe fn framebuffer_texture_2d(
        &self,
        target: u32,
        attachment: u32,
        tex_target: u32,
        t: Option<glow::Texture>,
        level: i32,
    ) {
        log!(self, |r| {
            let a = [
                r.en(target),
                r.en(attachment),
                r.en(tex_target),
                r.object("texture", n(t, |t| t.0.get())),
                level.to_string(),
            ];
            r.call("glFramebufferTexture2D", &a);
        });
        unsafe {
            self.raw
                .framebuffer_texture_2d(target, attachment, tex_target, t, level)
        }
    }
    pub unsafe fn framebuffer_texture_layer(
        &self,
        target: u32,
        attachment: u32,
        t: Option<glow::Texture>,
        level: i32,
        layer: i32,
    ) {
        log!(self, |r| {
            let a = [
                r.en(target),
                r.en(attachment),
                r.object("texture", n(t, |t| t.0.get())),
                level.to_string(),
                layer.to_string(),
            ];
            r.call("glFramebufferTextureLayer", &a);
        });
        unsafe {
            self.raw
                .framebuffer_texture_layer(target, attachment, t, level, layer)
        }
    }
    pub unsafe fn framebuffer_renderbuffer(
        &self,
        target: u32,
        attachment: u32,
        rb_target: u32,
        b: Option<glow::Renderbuffer>,
    ) {
        log!(self, |r| {
            let a = [
                r.en(target),
                r.en(attachment),
                r.en(rb_target),
                r.object("renderbuffer", n(b, |b| b.0.get())),
            ];
            r.call("glFramebufferRenderbuffer", &a);
        });
        unsafe {
            self.raw
                .framebuffer_renderbuffer(target, attachment, rb_target, b)
        }
    }
    pub unsafe fn check_framebuffer_status(&self, target: u32) -> u32 {
        log!(self, |r| {
            let t = r.en(target);
            r.func("glCheckFramebufferStatus");
            r.stmt(&format!("require_complete({t});"));
        });
        unsafe { self.raw.check_framebuffer_status(target) }
    }
    pub unsafe fn draw_buffers(&self, b: &[u32]) {
        log!(self, |r| {
            let names: Vec<String> = b.iter().map(|x| r.en(*x)).collect();
            let a = [
                b.len().to_string(),
                format!("(const GLenum[]){{{}}}", names.join(", ")),
            ];
            r.call("glDrawBuffers", &a);
        });
        unsafe { self.raw.draw_buffers(b) }
    }
    pub unsafe fn read_buffer(&self, b: u32) {
        log!(self, |r| {
            let a = r.en(b);
            r.call("glReadBuffer", &[a]);
        });
        unsafe { self.raw.read_buffer(b) }
    }
    pub unsafe fn enable(&self, cap: u32) {
        log!(self, |r| {
            let a = r.en(cap);
            r.call("glEnable", &[a]);
        });
        unsafe { self.raw.enable(cap) }
    }
    pub unsafe fn disable(&self, cap: u32) {
        log!(self, |r| {
            let a = r.en(cap);
            r.call("glDisable", &[a]);
        });
        unsafe { self.raw.disable(cap) }
    }
    pub unsafe fn depth_func(&self, f: u32) {
        log!(self, |r| {
            let a = r.en(f);
            r.call("glDepthFunc", &[a]);
        });
        unsafe { self.raw.depth_func(f) }
    }
    /// glBlendFunc: umbra blends only (GL_ONE, GL_ONE), written as such.
    pub unsafe fn blend_func(&self, src: u32, dst: u32) {
        log!(self, |r| {
            let name = |v: u32| {
                if v == glow::ONE {
                    "GL_ONE".to_string()
                } else {
                    format!("0x{v:04X}")
                }
            };
            r.call("glBlendFunc", &[name(src), name(dst)]);
        });
        unsafe { self.raw.blend_func(src, dst) }
    }
    pub unsafe fn depth_mask(&self, m: bool) {
        log!(self, |r| r.call("glDepthMask", &[c_bool(m)]));
        unsafe { self.raw.depth_mask(m) }
    }
    pub unsafe fn color_mask(&self, red: bool, green: bool, blue: bool, alpha: bool) {
        log!(self, |r| r.call(
            "glColorMask",
            &[c_bool(red), c_bool(green), c_bool(blue), c_bool(alpha)]
        ));
        unsafe { self.raw.color_mask(red, green, blue, alpha) }
    }
    pub unsafe fn front_face(&self, f: u32) {
        log!(self, |r| {
            let a = r.en(f);
            r.call("glFrontFace", &[a]);
        });
        unsafe { self.raw.front_face(f) }
    }
    pub unsafe fn cull_face(&self, f: u32) {
        log!(self, |r| {
            let a = r.en(f);
            r.call("glCullFace", &[a]);
        });
        unsafe { self.raw.cull_face(f) }
    }
    pub unsafe fn polygon_offset(&self, factor: f32, units: f32) {
        log!(self, |r| r
            .call("glPolygonOffset", &[hex_f32(factor), hex_f32(units)]));
        unsafe { self.raw.polygon_offset(factor, units) }
    }
    pub unsafe fn viewport(&self, x: i32, y: i32, w: i32, h: i32) {
        log!(self, |r| r.call(
            "glViewport",
            &[x.to_string(), y.to_string(), w.to_string(), h.to_string()]
        ));
        unsafe { self.raw.viewport(x, y, w, h) }
    }
    pub unsafe fn clear_depth_f32(&self, d: f32) {
        log!(self, |r| r.call("glClearDepthf", &[hex_f32(d)]));
        unsafe { self.raw.clear_depth_f32(d) }
    }
    pub unsafe fn clear_color(&self, red: f32, green: f32, blue: f32, alpha: f32) {
        log!(self, |r| r.call(
            "glClearColor",
            &[hex_f32(red), hex_f32(green), hex_f32(blue), hex_f32(alpha)]
        ));
        unsafe { self.raw.clear_color(red, green, blue, alpha) }
    }
    pub unsafe fn clear(&self, mask: u32) {
        log!(self, |r| {
            let mut bits = Vec::new();
            for b in [
                glow::COLOR_BUFFER_BIT,
                glow::DEPTH_BUFFER_BIT,
                glow::STENCIL_BUFFER_BIT,
            ] {
                if mask & b != 0 {
                    bits.push(r.en(b));
                }
            }
            let a = if bits.is_empty() {
                "0".into()
            } else {
                bits.join(" | ")
            };
            r.call("glClear", &[a]);
        });
        unsafe { self.raw.clear(mask) }
    }
    pub unsafe fn clear_buffer_f32_slice(&self, target: u32, draw_buffer: u32, v: &[f32]) {
        log!(self, |r| {
            let a = [r.en(target), draw_buffer.to_string(), r.floats(v)];
            r.call("glClearBufferfv", &a);
        });
        unsafe { self.raw.clear_buffer_f32_slice(target, draw_buffer, v) }
    }
    pub unsafe fn draw_arrays(&self, mode: u32, first: i32, count: i32) {
        log!(self, |r| {
            let a = [r.en(mode), first.to_string(), count.to_string()];
            r.call("glDrawArrays", &a);
        });
        unsafe { self.raw.draw_arrays(mode, first, count) }
    }
    pub unsafe fn read_pixels(
        &self,
        x: i32,
        y: i32,
        w: i32,
        h: i32,
        format: u32,
        ty: u32,
        pixels: glow::PixelPackData,
    ) {
        log!(self, |r| {
            let what = r.next_readback.take();
            let a = [
                x.to_string(),
                y.to_string(),
                w.to_string(),
                h.to_string(),
                r.en(format),
                r.en(ty),
                "pixels".into(),
            ];
            let f = r.func("glReadPixels");
            r.stmt("{");
            r.stmt(&format!(
                "    void *pixels = xmalloc((size_t){w} * {h} * 4);"
            ));
            r.stmt(&format!("    {f}({});", a.join(", ")));
            if let Some(k) = what {
                let layer = match k {
                    Readback::MapLayer(l) => l,
                    _ => 0,
                };
                r.stmt(&format!(
                    "    readback({}, {layer}, pixels, {w}, {h});",
                    k.c_kind()
                ));
            }
            r.stmt("    free(pixels);");
            r.stmt("}");
        });
        unsafe { self.raw.read_pixels(x, y, w, h, format, ty, pixels) }
    }
    pub unsafe fn finish(&self) {
        log!(self, |r| r.call("glFinish", &[]));
        unsafe { self.raw.finish() }
    }
    pub unsafe fn begin_query(&self, target: u32, q: glow::Query) {
        log!(self, |r| {
            let a = [r.en(target), r.object("query", Some(q.0.get()))];
            r.call("glBeginQuery", &a);
        });
        unsafe { self.raw.begin_query(target, q) }
    }
    pub unsafe fn end_query(&self, target: u32) {
        log!(self, |r| {
            let a = r.en(target);
            r.call("glEndQuery", &[a]);
        });
        unsafe { self.raw.end_query(target) }
    }
    pub unsafe fn get_query_parameter_u64(&self, q: glow::Query, p: u32) -> u64 {
        log!(self, |r| {
            let v = r.object("query", Some(q.0.get()));
            let p = r.en(p);
            let f = r.func("glGetQueryObjectui64v");
            r.stmt(&format!("{{ GLuint64 result; {f}({v}, {p}, &result); }}"));
        });
        unsafe { self.raw.get_query_parameter_u64(q, p) }
    }
    deleted!(delete_texture, glow::Texture, "texture", "glDeleteTextures");
    deleted!(
        delete_framebuffer,
        glow::Framebuffer,
        "framebuffer",
        "glDeleteFramebuffers"
    );
    deleted!(
        delete_renderbuffer,
        glow::Renderbuffer,
        "renderbuffer",
        "glDeleteRenderbuffers"
    );
    deleted!(
        delete_vertex_array,
        glow::VertexArray,
        "vao",
        "glDeleteVertexArrays"
    );
    deleted!(delete_buffer, glow::Buffer, "buffer", "glDeleteBuffers");
    deleted!(delete_query, glow::Query, "query", "glDeleteQueries");
}

/// Texture parameters whose value is an enum (printed by name).
const ENUM_VALUED: [u32; 6] = [
    glow::TEXTURE_MIN_FILTER,
    glow::TEXTURE_MAG_FILTER,
    glow::TEXTURE_WRAP_S,
    glow::TEXTURE_WRAP_T,
    glow::TEXTURE_COMPARE_MODE,
    glow::TEXTURE_COMPARE_FUNC,
];

/// A C99 hexadecimal float literal that reads back as exactly `x`.
pub fn hex_f32(x: f32) -> String {
    if x.is_nan() {
        return "NAN".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "INFINITY" } else { "-INFINITY" }.into();
    }
    let bits = x.to_bits();
    let sign = if bits >> 31 != 0 { "-" } else { "" };
    let exp = ((bits >> 23) & 0xff) as i32;
    let man = bits & 0x7f_ffff;
    if exp == 0 && man == 0 {
        return format!("{sign}0x0p+0f");
    }
    // 23 mantissa bits, shifted to 24 so they print as 6 hex digits, trailing zeros dropped.
    let digits = format!("{:06x}", man << 1);
    let digits = digits.trim_end_matches('0');
    let (lead, e) = if exp == 0 { (0, -126) } else { (1, exp - 127) };
    let frac = if digits.is_empty() {
        String::new()
    } else {
        format!(".{digits}")
    };
    format!("{sign}0x{lead}{frac}p{e:+}f")
}

fn c_bool(b: bool) -> String {
    if b { "GL_TRUE" } else { "GL_FALSE" }.into()
}

/// A C string literal.
pub fn c_string(s: &str) -> String {
    let mut out = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if c.is_ascii() && !c.is_ascii_control() => out.push(c),
            c => {
                let mut buf = [0u8; 4];
                for b in c.encode_utf8(&mut buf).bytes() {
                    let _ = write!(out, "\\{b:03o}");
                }
            }
        }
    }
    out.push('"');
    out
}

/// A multi-line text (a shader) as adjacent C string literals, one per line.
fn c_text(s: &str) -> String {
    let mut lines: Vec<String> = s
        .split_inclusive('\n')
        .map(|l| format!("    {}", c_string(l)))
        .collect();
    if lines.is_empty() {
        lines.push("    \"\"".into());
    }
    lines.join("\n")
}

/// The C return type and parameters of each GL entry point [`Gl`] can emit.
pub(crate) fn signature(name: &str) -> (&'static str, &'static str) {
    SIGNATURES
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, r, p)| (*r, *p))
        .unwrap_or(("void", "void"))
}

const SIGNATURES: &[(&str, &str, &str)] = &[
    ("glActiveTexture", "void", "GLenum"),
    ("glAttachShader", "void", "GLuint, GLuint"),
    ("glBeginQuery", "void", "GLenum, GLuint"),
    (
        "glBindAttribLocation",
        "void",
        "GLuint, GLuint, const GLchar *",
    ),
    ("glBindBuffer", "void", "GLenum, GLuint"),
    ("glBindFramebuffer", "void", "GLenum, GLuint"),
    ("glBindRenderbuffer", "void", "GLenum, GLuint"),
    ("glBindTexture", "void", "GLenum, GLuint"),
    ("glBindVertexArray", "void", "GLuint"),
    (
        "glBufferData",
        "void",
        "GLenum, GLsizeiptr, const void *, GLenum",
    ),
    ("glCheckFramebufferStatus", "GLenum", "GLenum"),
    ("glClear", "void", "GLbitfield"),
    ("glClearBufferfv", "void", "GLenum, GLint, const GLfloat *"),
    ("glClearColor", "void", "GLfloat, GLfloat, GLfloat, GLfloat"),
    ("glClearDepthf", "void", "GLfloat"),
    (
        "glColorMask",
        "void",
        "GLboolean, GLboolean, GLboolean, GLboolean",
    ),
    ("glCompileShader", "void", "GLuint"),
    ("glCreateProgram", "GLuint", "void"),
    ("glCreateShader", "GLuint", "GLenum"),
    ("glCullFace", "void", "GLenum"),
    ("glDeleteBuffers", "void", "GLsizei, const GLuint *"),
    ("glDeleteFramebuffers", "void", "GLsizei, const GLuint *"),
    ("glDeleteQueries", "void", "GLsizei, const GLuint *"),
    ("glDeleteRenderbuffers", "void", "GLsizei, const GLuint *"),
    ("glDeleteShader", "void", "GLuint"),
    ("glDeleteTextures", "void", "GLsizei, const GLuint *"),
    ("glDeleteVertexArrays", "void", "GLsizei, const GLuint *"),
    ("glDepthFunc", "void", "GLenum"),
    ("glDepthMask", "void", "GLboolean"),
    ("glBlendFunc", "void", "GLenum, GLenum"),
    ("glDetachShader", "void", "GLuint, GLuint"),
    ("glDisable", "void", "GLenum"),
    ("glDrawArrays", "void", "GLenum, GLint, GLsizei"),
    ("glDrawBuffers", "void", "GLsizei, const GLenum *"),
    ("glEnable", "void", "GLenum"),
    ("glEnableVertexAttribArray", "void", "GLuint"),
    ("glEndQuery", "void", "GLenum"),
    ("glFinish", "void", "void"),
    (
        "glFramebufferRenderbuffer",
        "void",
        "GLenum, GLenum, GLenum, GLuint",
    ),
    (
        "glFramebufferTexture2D",
        "void",
        "GLenum, GLenum, GLenum, GLuint, GLint",
    ),
    (
        "glFramebufferTextureLayer",
        "void",
        "GLenum, GLenum, GLuint, GLint, GLint",
    ),
    ("glFrontFace", "void", "GLenum"),
    ("glGenBuffers", "void", "GLsizei, GLuint *"),
    ("glGenFramebuffers", "void", "GLsizei, GLuint *"),
    ("glGenQueries", "void", "GLsizei, GLuint *"),
    ("glGenRenderbuffers", "void", "GLsizei, GLuint *"),
    ("glGenTextures", "void", "GLsizei, GLuint *"),
    ("glGenVertexArrays", "void", "GLsizei, GLuint *"),
    ("glGetError", "GLenum", "void"),
    (
        "glGetProgramInfoLog",
        "void",
        "GLuint, GLsizei, GLsizei *, GLchar *",
    ),
    ("glGetProgramiv", "void", "GLuint, GLenum, GLint *"),
    (
        "glGetQueryObjectui64v",
        "void",
        "GLuint, GLenum, GLuint64 *",
    ),
    (
        "glGetShaderInfoLog",
        "void",
        "GLuint, GLsizei, GLsizei *, GLchar *",
    ),
    ("glGetShaderiv", "void", "GLuint, GLenum, GLint *"),
    ("glGetString", "const GLubyte *", "GLenum"),
    ("glGetUniformLocation", "GLint", "GLuint, const GLchar *"),
    ("glLinkProgram", "void", "GLuint"),
    ("glPolygonOffset", "void", "GLfloat, GLfloat"),
    ("glPolygonOffsetClamp", "void", "GLfloat, GLfloat, GLfloat"),
    (
        "glPolygonOffsetClampEXT",
        "void",
        "GLfloat, GLfloat, GLfloat",
    ),
    ("glReadBuffer", "void", "GLenum"),
    (
        "glReadPixels",
        "void",
        "GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void *",
    ),
    (
        "glRenderbufferStorage",
        "void",
        "GLenum, GLenum, GLsizei, GLsizei",
    ),
    (
        "glShaderSource",
        "void",
        "GLuint, GLsizei, const GLchar *const *, const GLint *",
    ),
    (
        "glTexImage2D",
        "void",
        "GLenum, GLint, GLint, GLsizei, GLsizei, GLint, GLenum, GLenum, const void *",
    ),
    (
        "glTexImage3D",
        "void",
        "GLenum, GLint, GLint, GLsizei, GLsizei, GLsizei, GLint, GLenum, GLenum, const void *",
    ),
    (
        "glTexParameterfv",
        "void",
        "GLenum, GLenum, const GLfloat *",
    ),
    ("glTexParameteri", "void", "GLenum, GLenum, GLint"),
    ("glUniform1f", "void", "GLint, GLfloat"),
    ("glUseProgram", "void", "GLuint"),
    ("glUniform1i", "void", "GLint, GLint"),
    ("glUniform2f", "void", "GLint, GLfloat, GLfloat"),
    ("glUniform1fv", "void", "GLint, GLsizei, const GLfloat *"),
    ("glUniform3f", "void", "GLint, GLfloat, GLfloat, GLfloat"),
    ("glUniform4fv", "void", "GLint, GLsizei, const GLfloat *"),
    (
        "glUniformMatrix4fv",
        "void",
        "GLint, GLsizei, GLboolean, const GLfloat *",
    ),
    (
        "glVertexAttribPointer",
        "void",
        "GLuint, GLint, GLenum, GLboolean, GLsizei, const void *",
    ),
    ("glViewport", "void", "GLint, GLint, GLsizei, GLsizei"),
];

/// The GL enum names umbra's calls use. A value shared by two names (GL_NONE/GL_ZERO) is
/// printed by the first.
const ENUMS: &[(u32, &str)] = &[
    (glow::NONE, "GL_NONE"),
    (glow::TEXTURE_2D, "GL_TEXTURE_2D"),
    (glow::TEXTURE_CUBE_MAP, "GL_TEXTURE_CUBE_MAP"),
    (glow::TEXTURE_2D_ARRAY, "GL_TEXTURE_2D_ARRAY"),
    (glow::TEXTURE_CUBE_MAP_ARRAY, "GL_TEXTURE_CUBE_MAP_ARRAY"),
    (
        glow::TEXTURE_CUBE_MAP_POSITIVE_X,
        "GL_TEXTURE_CUBE_MAP_POSITIVE_X",
    ),
    (
        glow::TEXTURE_CUBE_MAP_NEGATIVE_X,
        "GL_TEXTURE_CUBE_MAP_NEGATIVE_X",
    ),
    (
        glow::TEXTURE_CUBE_MAP_POSITIVE_Y,
        "GL_TEXTURE_CUBE_MAP_POSITIVE_Y",
    ),
    (
        glow::TEXTURE_CUBE_MAP_NEGATIVE_Y,
        "GL_TEXTURE_CUBE_MAP_NEGATIVE_Y",
    ),
    (
        glow::TEXTURE_CUBE_MAP_POSITIVE_Z,
        "GL_TEXTURE_CUBE_MAP_POSITIVE_Z",
    ),
    (
        glow::TEXTURE_CUBE_MAP_NEGATIVE_Z,
        "GL_TEXTURE_CUBE_MAP_NEGATIVE_Z",
    ),
    (glow::TEXTURE_MIN_FILTER, "GL_TEXTURE_MIN_FILTER"),
    (glow::TEXTURE_MAG_FILTER, "GL_TEXTURE_MAG_FILTER"),
    (glow::TEXTURE_WRAP_S, "GL_TEXTURE_WRAP_S"),
    (glow::TEXTURE_WRAP_T, "GL_TEXTURE_WRAP_T"),
    (glow::TEXTURE_BASE_LEVEL, "GL_TEXTURE_BASE_LEVEL"),
    (glow::TEXTURE_MAX_LEVEL, "GL_TEXTURE_MAX_LEVEL"),
    (glow::TEXTURE_COMPARE_MODE, "GL_TEXTURE_COMPARE_MODE"),
    (glow::TEXTURE_COMPARE_FUNC, "GL_TEXTURE_COMPARE_FUNC"),
    (glow::TEXTURE_BORDER_COLOR, "GL_TEXTURE_BORDER_COLOR"),
    (glow::COMPARE_REF_TO_TEXTURE, "GL_COMPARE_REF_TO_TEXTURE"),
    (glow::NEAREST, "GL_NEAREST"),
    (glow::LINEAR, "GL_LINEAR"),
    (glow::NEAREST_MIPMAP_NEAREST, "GL_NEAREST_MIPMAP_NEAREST"),
    (glow::LINEAR_MIPMAP_NEAREST, "GL_LINEAR_MIPMAP_NEAREST"),
    (glow::NEAREST_MIPMAP_LINEAR, "GL_NEAREST_MIPMAP_LINEAR"),
    (glow::LINEAR_MIPMAP_LINEAR, "GL_LINEAR_MIPMAP_LINEAR"),
    (glow::CLAMP_TO_EDGE, "GL_CLAMP_TO_EDGE"),
    (glow::CLAMP_TO_BORDER, "GL_CLAMP_TO_BORDER"),
    (glow::REPEAT, "GL_REPEAT"),
    (glow::LEQUAL, "GL_LEQUAL"),
    (glow::GEQUAL, "GL_GEQUAL"),
    (glow::LESS, "GL_LESS"),
    (glow::GREATER, "GL_GREATER"),
    (glow::ALWAYS, "GL_ALWAYS"),
    (glow::EQUAL, "GL_EQUAL"),
    (glow::BLEND, "GL_BLEND"),
    (glow::DEPTH_COMPONENT, "GL_DEPTH_COMPONENT"),
    (glow::DEPTH_COMPONENT16, "GL_DEPTH_COMPONENT16"),
    (glow::DEPTH_COMPONENT24, "GL_DEPTH_COMPONENT24"),
    (glow::DEPTH_COMPONENT32F, "GL_DEPTH_COMPONENT32F"),
    (glow::RGBA, "GL_RGBA"),
    (glow::RGBA8, "GL_RGBA8"),
    (glow::SRGB8_ALPHA8, "GL_SRGB8_ALPHA8"),
    (glow::SRGB_ALPHA, "GL_SRGB_ALPHA_EXT"),
    (glow::FRAMEBUFFER_SRGB, "GL_FRAMEBUFFER_SRGB"),
    (glow::UNSIGNED_BYTE, "GL_UNSIGNED_BYTE"),
    (glow::UNSIGNED_SHORT, "GL_UNSIGNED_SHORT"),
    (glow::UNSIGNED_INT, "GL_UNSIGNED_INT"),
    (glow::FLOAT, "GL_FLOAT"),
    (glow::ARRAY_BUFFER, "GL_ARRAY_BUFFER"),
    (glow::STATIC_DRAW, "GL_STATIC_DRAW"),
    (glow::FRAMEBUFFER, "GL_FRAMEBUFFER"),
    (glow::RENDERBUFFER, "GL_RENDERBUFFER"),
    (glow::COLOR_ATTACHMENT0, "GL_COLOR_ATTACHMENT0"),
    (glow::COLOR_ATTACHMENT1, "GL_COLOR_ATTACHMENT1"),
    (glow::DEPTH_ATTACHMENT, "GL_DEPTH_ATTACHMENT"),
    (glow::COLOR, "GL_COLOR"),
    (glow::DEPTH_TEST, "GL_DEPTH_TEST"),
    (glow::CULL_FACE, "GL_CULL_FACE"),
    (glow::DEPTH_CLAMP, "GL_DEPTH_CLAMP"),
    (glow::POLYGON_OFFSET_FILL, "GL_POLYGON_OFFSET_FILL"),
    (glow::BACK, "GL_BACK"),
    (glow::FRONT, "GL_FRONT"),
    (glow::CCW, "GL_CCW"),
    (glow::CW, "GL_CW"),
    (glow::TRIANGLES, "GL_TRIANGLES"),
    (glow::COLOR_BUFFER_BIT, "GL_COLOR_BUFFER_BIT"),
    (glow::DEPTH_BUFFER_BIT, "GL_DEPTH_BUFFER_BIT"),
    (glow::STENCIL_BUFFER_BIT, "GL_STENCIL_BUFFER_BIT"),
    (glow::VERTEX_SHADER, "GL_VERTEX_SHADER"),
    (glow::FRAGMENT_SHADER, "GL_FRAGMENT_SHADER"),
    (glow::TIME_ELAPSED, "GL_TIME_ELAPSED"),
    (glow::QUERY_RESULT, "GL_QUERY_RESULT"),
    (glow::TEXTURE0, "GL_TEXTURE0"),
];

fn enum_name(v: u32) -> Option<&'static str> {
    ENUMS.iter().find(|(x, _)| *x == v).map(|(_, n)| *n)
}

/// The GL constants the C prologue itself uses, whatever the run called.
pub const PROLOGUE_ENUMS: &[(&str, u32)] = &[
    ("GL_NO_ERROR", glow::NO_ERROR),
    ("GL_INVALID_ENUM", glow::INVALID_ENUM),
    ("GL_INVALID_VALUE", glow::INVALID_VALUE),
    ("GL_INVALID_OPERATION", glow::INVALID_OPERATION),
    (
        "GL_INVALID_FRAMEBUFFER_OPERATION",
        glow::INVALID_FRAMEBUFFER_OPERATION,
    ),
    ("GL_OUT_OF_MEMORY", glow::OUT_OF_MEMORY),
    ("GL_FRAMEBUFFER_COMPLETE", glow::FRAMEBUFFER_COMPLETE),
    ("GL_COMPILE_STATUS", glow::COMPILE_STATUS),
    ("GL_LINK_STATUS", glow::LINK_STATUS),
    ("GL_VENDOR", glow::VENDOR),
    ("GL_RENDERER", glow::RENDERER),
    ("GL_VERSION", glow::VERSION),
    (
        "GL_SHADING_LANGUAGE_VERSION",
        glow::SHADING_LANGUAGE_VERSION,
    ),
    ("GL_DEBUG_OUTPUT", glow::DEBUG_OUTPUT),
    (
        "GL_DEBUG_OUTPUT_SYNCHRONOUS",
        glow::DEBUG_OUTPUT_SYNCHRONOUS,
    ),
    ("GL_DEBUG_TYPE_ERROR", glow::DEBUG_TYPE_ERROR),
    ("GL_DEBUG_SEVERITY_HIGH", glow::DEBUG_SEVERITY_HIGH),
    ("GL_TRUE", 1),
    ("GL_FALSE", 0),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_floats_are_exact_c99_literals() {
        assert_eq!(hex_f32(1.0), "0x1p+0f");
        assert_eq!(hex_f32(-0.5), "-0x1p-1f");
        assert_eq!(hex_f32(3.0), "0x1.8p+1f");
        assert_eq!(hex_f32(0.0), "0x0p+0f");
        assert_eq!(hex_f32(-0.0), "-0x0p+0f");
        assert_eq!(hex_f32(f32::MIN_POSITIVE / 2.0), "0x0.8p-126f");
        assert_eq!(hex_f32(0.1), "0x1.99999ap-4f");
        // Parse them back the way a C compiler does, through the bits.
        for x in [0.1f32, 1.0e-30, 123456.79, f32::MAX, -7.25e-41] {
            let s = hex_f32(x);
            let body = s.trim_end_matches('f');
            let (neg, body) = body.strip_prefix('-').map_or((false, body), |b| (true, b));
            let (mant, exp) = body
                .trim_start_matches("0x")
                .split_once('p')
                .expect("an exponent");
            let (lead, frac) = mant.split_once('.').unwrap_or((mant, ""));
            let mut m = f64::from(u8::from_str_radix(lead, 16).expect("a hex digit"));
            for (i, d) in frac.chars().enumerate() {
                m += f64::from(d.to_digit(16).expect("a hex digit")) / 16f64.powi(i as i32 + 1);
            }
            let v = m * 2f64.powi(exp.parse().expect("a decimal exponent"));
            let v = if neg { -v } else { v };
            assert_eq!(v as f32, x, "{s}");
        }
    }

    #[test]
    fn every_entry_point_written_has_a_prototype() {
        // Every quoted GL entry-point name in this module (each is written as a call).
        let src = include_str!("record.rs");
        let mut missing = Vec::new();
        for piece in src.split('"').skip(1).step_by(2) {
            let is_name = piece.starts_with("gl")
                && piece.len() > 3
                && piece[2..].starts_with(|c: char| c.is_ascii_uppercase())
                && piece.chars().all(|c| c.is_ascii_alphanumeric());
            if is_name && !SIGNATURES.iter().any(|(n, _, _)| *n == piece) {
                missing.push(piece.to_string());
            }
        }
        assert!(missing.is_empty(), "no prototype for {missing:?}");
    }

    #[test]
    fn c_strings_escape() {
        assert_eq!(c_string("a\"b\\c\n"), "\"a\\\"b\\\\c\\n\"");
        assert_eq!(c_string("é"), "\"\\303\\251\"");
    }
}
