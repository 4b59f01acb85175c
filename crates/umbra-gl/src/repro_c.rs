//! A [`Recording`] as a whole C program: EGL set up as [`crate::context`] does it (Mesa's
//! surfaceless platform, a pbuffer-capable config, the same context version, profile and
//! debug flag), every GL entry point loaded through `eglGetProcAddress`, the recorded calls,
//! and the probes the caller supplies. It needs only libEGL and a C99 compiler:
//! `cc repro.c -o repro -lEGL -lm`.
//!
//! Exit codes follow `git bisect run`: 0 every probe inside its interval, 1 one outside, 125
//! the program could not run (no display, no context, a shader that does not compile, a GL
//! error or a KHR_debug error message at a checkpoint).
//!
//! The probes' C (from `umbra repro`) defines `readback(kind, layer, pixels, w, h)`, called
//! after each `glReadPixels`, and `probes_result()`, the exit code.

use std::fmt::Write as _;

use crate::api::Api;
use crate::record::{PROLOGUE_ENUMS, Recording, signature};

/// The whole program: `header` (a C comment) first, then the prologue, `probes`, the
/// recorded data and calls, and `main`.
pub fn program(rec: &Recording, api: Api, header: &str, probes: &str) -> String {
    let mut c = String::new();
    c.push_str(header);
    c.push_str(INCLUDES);
    c.push_str("\n/* GL types and the enums this program uses (values from the GL registry). */\n");
    c.push_str(TYPES);
    let mut enums: Vec<(&str, u32)> = rec.enums.iter().map(|(n, v)| (*n, *v)).collect();
    for (n, v) in PROLOGUE_ENUMS {
        if !enums.iter().any(|(m, _)| m == n) {
            enums.push((n, *v));
        }
    }
    enums.sort();
    for (n, v) in enums {
        let _ = writeln!(c, "#define {n} 0x{v:04X}");
    }
    c.push_str(
        "\n/* GL entry points, loaded through eglGetProcAddress (no GL library is linked). */\n",
    );
    let mut functions = rec.functions.clone();
    // The prologue's and the checks' own calls.
    for f in [
        "glGetString",
        "glGetError",
        "glGetShaderiv",
        "glGetShaderInfoLog",
        "glGetProgramiv",
        "glGetProgramInfoLog",
        "glCheckFramebufferStatus",
    ] {
        functions.insert(f, signature(f));
    }
    let mut loader = String::new();
    c.push_str(HELPERS);
    for (name, (ret, params)) in &functions {
        let _ = writeln!(c, "static {ret} (*{name})({params});");
        let _ = writeln!(
            loader,
            "    {name} = ({ret} (*)({params}))eglGetProcAddress(\"{name}\");\n    if (!{name}) fail(\"eglGetProcAddress(\\\"{name}\\\") returned NULL\");"
        );
    }
    c.push_str(CHECKS);
    c.push_str("\nstatic void load_gl(void)\n{\n");
    c.push_str(&loader);
    c.push_str("}\n");
    c.push_str("\n/* ---- probes: umbra's judge's intervals at the pixels and texels the driver broke ---- */\n");
    c.push_str(probes);
    c.push_str("\n/* ---- data: vertices and shaders exactly as umbra sent them ---- */\n");
    c.push_str(&rec.data);
    c.push_str("\n/* GL objects */\n");
    c.push_str(&rec.objects);
    c.push_str(
        "\n/* ---- the run: umbra's GL calls in umbra's order ---- */\nstatic void run(void)\n{\n",
    );
    c.push_str(&rec.body);
    c.push_str("}\n");
    let (major, minor) = api.version();
    let (bind, renderable) = match api {
        Api::Gl33 => ("EGL_OPENGL_API", "EGL_OPENGL_BIT"),
        Api::Gles3 => ("EGL_OPENGL_ES_API", "EGL_OPENGL_ES3_BIT"),
        Api::Gles2 => ("EGL_OPENGL_ES_API", "EGL_OPENGL_ES2_BIT"),
    };
    let profile = if api == Api::Gl33 {
        "EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, "
    } else {
        ""
    };
    let debug_name = if api.is_es() {
        "glDebugMessageCallbackKHR"
    } else {
        "glDebugMessageCallback"
    };
    let debug = if rec.debug_output {
        format!(
            "    /* umbra turns KHR_debug's output on and fails a run on any error it reports. */\n    {{\n        void (*cb)(void (*)(GLenum, GLenum, GLuint, GLenum, GLsizei, const GLchar *, const void *), const void *) =\n            (void (*)(void (*)(GLenum, GLenum, GLuint, GLenum, GLsizei, const GLchar *, const void *), const void *))eglGetProcAddress(\"{debug_name}\");\n        void (*enable)(GLenum) = (void (*)(GLenum))eglGetProcAddress(\"glEnable\");\n        if (cb && enable) {{\n            enable(GL_DEBUG_OUTPUT);\n            enable(GL_DEBUG_OUTPUT_SYNCHRONOUS);\n            cb(on_debug, NULL);\n        }}\n    }}\n"
        )
    } else {
        String::new()
    };
    let display = match rec.egl_device {
        None => "    /* Mesa's surfaceless platform, as umbra opens it (crates/umbra-gl/src/platform.rs).\n     * Mesa's variables choose the driver (GALLIUM_DRIVER=softpipe, llvmpipe or zink). */\n    EGLDisplay dpy = eglGetPlatformDisplay(0x31DD /* EGL_PLATFORM_SURFACELESS_MESA */, EGL_DEFAULT_DISPLAY, NULL);\n    if (dpy == EGL_NO_DISPLAY) fail(\"no surfaceless EGL display (Mesa's libegl-mesa0 missing?)\");\n".to_string(),
        Some(index) => format!(
            "    /* EGL device {index} (EGL_EXT_platform_device), as umbra opened it\n     * (crates/umbra-gl/src/platform.rs). */\n    EGLBoolean (*query_devices)(EGLint, void **, EGLint *) =\n        (EGLBoolean (*)(EGLint, void **, EGLint *))eglGetProcAddress(\"eglQueryDevicesEXT\");\n    void *devices[64];\n    EGLint n_devices = 0;\n    if (!query_devices || !query_devices(64, devices, &n_devices) || n_devices <= {index})\n        fail(\"no EGL device {index} (EGL_EXT_device_enumeration)\");\n    EGLDisplay dpy = eglGetPlatformDisplay(0x313F /* EGL_PLATFORM_DEVICE_EXT */, devices[{index}], NULL);\n    if (dpy == EGL_NO_DISPLAY) fail(\"no EGL display on device {index}\");\n"
        ),
    };
    let _ = write!(
        c,
        r#"
int main(void)
{{
{display}
    if (!eglInitialize(dpy, NULL, NULL)) fail("eglInitialize failed");
    if (!eglBindAPI({bind})) fail("eglBindAPI failed");
    const EGLint config_attribs[] = {{EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, {renderable}, EGL_NONE}};
    EGLConfig config;
    EGLint configs = 0;
    if (!eglChooseConfig(dpy, config_attribs, &config, 1, &configs) || configs < 1)
        fail("no EGL config renders this API to a pbuffer");
    /* A debug context where EGL offers one, as umbra asks; without the flag otherwise. */
    const EGLint debug_attribs[] = {{EGL_CONTEXT_MAJOR_VERSION, {major}, EGL_CONTEXT_MINOR_VERSION, {minor}, {profile}EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE, EGL_NONE}};
    const EGLint plain_attribs[] = {{EGL_CONTEXT_MAJOR_VERSION, {major}, EGL_CONTEXT_MINOR_VERSION, {minor}, {profile}EGL_NONE}};
    EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, debug_attribs);
    if (ctx == EGL_NO_CONTEXT) ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, plain_attribs);
    if (ctx == EGL_NO_CONTEXT) fail("this driver offers no {api} context");
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) fail("eglMakeCurrent without a surface failed");
    load_gl();
    printf("GL_VENDOR:   %s\nGL_RENDERER: %s\nGL_VERSION:  %s\n", (const char *)glGetString(GL_VENDOR),
           (const char *)glGetString(GL_RENDERER), (const char *)glGetString(GL_VERSION));
{debug}    run();
    int result = probes_result();
    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    return result;
}}
"#,
        api = api.name()
    );
    c
}

const INCLUDES: &str = r#"
#include <EGL/egl.h>
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
"#;

const TYPES: &str = r#"/* The probes repeat umbra's f32 arithmetic: no fused multiply-adds (the pragma for clang;
 * for gcc, which ignores it, the probes round each product through a volatile float) and no
 * extended precision. */
#ifdef __clang__
#pragma STDC FP_CONTRACT OFF
#endif
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD != 0
#error "the probes need float arithmetic in float (FLT_EVAL_METHOD 0): build for x86-64 or aarch64, or with -msse2 -mfpmath=sse"
#endif
typedef unsigned int GLenum;
typedef unsigned int GLuint;
typedef unsigned int GLbitfield;
typedef int GLint;
typedef int GLsizei;
typedef float GLfloat;
typedef unsigned char GLboolean;
typedef unsigned char GLubyte;
typedef char GLchar;
typedef ptrdiff_t GLsizeiptr;
typedef uint64_t GLuint64;
"#;

const HELPERS: &str = r#"
/* What a readback holds (the probes' readback() dispatches on it). */
enum {
    READBACK_COLOR,      /* the lit pass's colour, RGBA8, rows bottom first */
    READBACK_VISIBILITY, /* visibility in R (0..255), face id + 1 in G + 256 B + 65536 A */
    READBACK_MAP         /* one face of the shadow map, DEPTH_COMPONENT as FLOAT */
};

static void fail(const char *why)
{
    fprintf(stderr, "repro: cannot run: %s\n", why);
    exit(125);
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n);
    if (!p) fail("out of memory");
    return p;
}

static const char *gl_error_name(GLenum e)
{
    switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    default: return "a GL error";
    }
}

/* The driver's error and high-severity messages fail the next checkpoint, as they fail
 * umbra's run. */
static int debug_errors;
static void on_debug(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                     const GLchar *message, const void *user)
{
    (void)source; (void)id; (void)length; (void)user;
    if (type == GL_DEBUG_TYPE_ERROR || severity == GL_DEBUG_SEVERITY_HIGH) {
        fprintf(stderr, "repro: driver says: %s\n", message);
        debug_errors++;
    }
}
"#;

/// Helpers that need entry points: defined after the pointers.
const CHECKS: &str = r#"
/* umbra checks glGetError at the end of each stage; a GL error there means the run cannot be
 * judged (125), as it fails umbra's run. */
static void check_gl(const char *stage)
{
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
        fprintf(stderr, "repro: %s after stage \"%s\"\n", gl_error_name(e), stage);
        exit(125);
    }
    if (debug_errors) {
        fprintf(stderr, "repro: the driver reported an error by KHR_debug in stage \"%s\"\n", stage);
        exit(125);
    }
}

static void require_compiled(GLuint shader)
{
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = "";
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        fprintf(stderr, "repro: a shader does not compile: %s\n", log);
        exit(125);
    }
}

static void require_linked(GLuint program)
{
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = "";
        glGetProgramInfoLog(program, sizeof log, NULL, log);
        fprintf(stderr, "repro: a program does not link: %s\n", log);
        exit(125);
    }
}

static void require_complete(GLenum target)
{
    GLenum status = glCheckFramebufferStatus(target);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        fprintf(stderr, "repro: framebuffer incomplete (0x%04X)\n", status);
        exit(125);
    }
}
"#;
