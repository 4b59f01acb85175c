//! EGL without a window system or display server, one context per process: Mesa's
//! surfaceless platform, or an EGL device ([`crate::platform`]; docs/platform.md, "EGL
//! facts").
//!
//! libEGL is loaded at run time (khronos-egl's `dynamic` feature), so a machine without Mesa
//! builds and tests umbra and reports the GL backends as unsupported, naming the package to
//! install, instead of failing to link. The config asks for `PBUFFER_BIT` (a surfaceless
//! display has no window configs) and the context is made current with no surface where the
//! display has EGL_KHR_surfaceless_context, on a 1×1 pbuffer elsewhere; all rendering goes to
//! framebuffer objects.

use glow::HasContext as _;
use khronos_egl as egl;

use crate::api::Api;
use crate::platform::Platform;

/// Set to make the context current on a 1×1 pbuffer even where the display offers
/// surfaceless contexts: the path a display without EGL_KHR_surfaceless_context takes, for a
/// driver whose surfaceless contexts misbehave, and for the test that holds both paths to the
/// same pictures.
pub const PBUFFER_ENV: &str = "UMBRA_EGL_PBUFFER";

// Why a context could not be made, and loading libEGL: the platform's, below this module.
pub use crate::platform::{Unavailable, load_egl};

/// A current GL context and the EGL objects that keep it alive.
pub struct GlContext {
    /// The GL function table.
    pub gl: glow::Context,
    /// `glPolygonOffsetClamp` (GL 4.6, ARB_polygon_offset_clamp) or
    /// `glPolygonOffsetClampEXT` (EXT_polygon_offset_clamp, also on GLES), loaded by name
    /// because glow does not carry it; None when the driver advertises neither.
    pub polygon_offset_clamp: Option<PolygonOffsetClamp>,
    /// The name `polygon_offset_clamp` was loaded by.
    pub polygon_offset_clamp_name: Option<&'static str>,
    egl: egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    context: egl::Context,
    /// The 1×1 pbuffer made current where the display has no surfaceless contexts.
    surface: Option<egl::Surface>,
    /// EGL's vendor and version strings (and the device, on the device platform).
    pub egl_info: String,
    /// How EGL reached the driver.
    pub platform: Platform,
    /// The EGL device, on the device platform.
    pub device: Option<crate::platform::EglDevice>,
    /// The API the context is for.
    pub api: Api,
}

impl GlContext {
    /// Creates and makes current a context for `api` on this process's EGL platform
    /// ([`Platform::choose`]).
    pub fn new(api: Api) -> Result<GlContext, Unavailable> {
        let egl = load_egl()?;
        let platform = Platform::choose(&egl)?;
        GlContext::on(egl, api, platform)
    }

    /// Creates and makes current a context for `api` on `platform`.
    pub fn on(
        egl: egl::DynamicInstance<egl::EGL1_5>,
        api: Api,
        platform: Platform,
    ) -> Result<GlContext, Unavailable> {
        let (display, device) = platform.display(&egl)?;
        egl.initialize(display).map_err(|e| {
            Unavailable(format!(
                "eglInitialize failed ({e}); install libgl1-mesa-dri (Mesa's drivers)"
            ))
        })?;
        let mut egl_info = format!(
            "{} {}{}",
            egl.query_string(Some(display), egl::VENDOR)
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            egl.query_string(Some(display), egl::VERSION)
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            device
                .as_ref()
                .map_or(String::new(), |d| format!(" on {}", d.describe()))
        );
        let (bind, renderable) = match api {
            Api::Gl33 => (egl::OPENGL_API, egl::OPENGL_BIT),
            Api::Gles3 => (egl::OPENGL_ES_API, egl::OPENGL_ES3_BIT),
            Api::Gles2 => (egl::OPENGL_ES_API, egl::OPENGL_ES2_BIT),
        };
        egl.bind_api(bind)
            .map_err(|e| Unavailable(format!("eglBindAPI({}) failed: {e}", api.name())))?;
        let config_attribs = [
            egl::SURFACE_TYPE,
            egl::PBUFFER_BIT,
            egl::RENDERABLE_TYPE,
            renderable,
            egl::NONE,
        ];
        let config = egl
            .choose_first_config(display, &config_attribs)
            .map_err(|e| Unavailable(format!("eglChooseConfig failed: {e}")))?
            .ok_or_else(|| {
                Unavailable(format!(
                    "no EGL config renders {} to a pbuffer on this driver",
                    api.name()
                ))
            })?;
        let (major, minor) = api.version();
        let mut ctx_attribs = vec![
            egl::CONTEXT_MAJOR_VERSION,
            major,
            egl::CONTEXT_MINOR_VERSION,
            minor,
        ];
        if api == Api::Gl33 {
            ctx_attribs.extend([
                egl::CONTEXT_OPENGL_PROFILE_MASK,
                egl::CONTEXT_OPENGL_CORE_PROFILE_BIT,
            ]);
        }
        // A debug context where EGL 1.5 offers one (KHR_debug then reports every error the
        // driver sees); EGL 1.4 displays (softpipe's) reject the attribute, so retry without.
        let mut debug_attribs = ctx_attribs.clone();
        debug_attribs.extend([egl::CONTEXT_OPENGL_DEBUG, egl::TRUE as egl::Int, egl::NONE]);
        ctx_attribs.push(egl::NONE);
        let context = egl
            .create_context(display, config, None, &debug_attribs)
            .or_else(|_| egl.create_context(display, config, None, &ctx_attribs))
            .map_err(|e| {
                Unavailable(format!(
                    "this driver offers no {} context ({e})",
                    api.name()
                ))
            })?;
        let surface = surface_for(&egl, display, config)?;
        if surface.is_some() {
            egl_info.push_str(", current on a 1x1 pbuffer");
        }
        egl.make_current(display, surface, surface, Some(context))
            .map_err(|e| {
                Unavailable(format!(
                    "eglMakeCurrent failed ({e}){}",
                    if surface.is_none() {
                        " without a surface"
                    } else {
                        " on a 1×1 pbuffer"
                    }
                ))
            })?;
        // SAFETY: the context is current on this thread; the loader returns EGL's pointers.
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                egl.get_proc_address(name)
                    .map_or(std::ptr::null(), |f| f as *const _)
            })
        };
        // Only an advertised extension's pointer is usable: Mesa hands out a pointer for
        // any name it knows, supported by this context or not.
        let exts = gl.supported_extensions();
        let clamp_name = if exts.contains("GL_ARB_polygon_offset_clamp") {
            Some("glPolygonOffsetClamp")
        } else if exts.contains("GL_EXT_polygon_offset_clamp") {
            Some("glPolygonOffsetClampEXT")
        } else {
            None
        };
        let polygon_offset_clamp = clamp_name.and_then(|n| egl.get_proc_address(n)).map(|f| {
            // SAFETY: EGL returned the entry point for this name, whose GL signature is
            // void (GLfloat factor, GLfloat units, GLfloat clamp), calling convention APIENTRY.
            unsafe { std::mem::transmute::<extern "system" fn(), PolygonOffsetClamp>(f) }
        });
        Ok(GlContext {
            gl,
            polygon_offset_clamp,
            polygon_offset_clamp_name: clamp_name.filter(|_| polygon_offset_clamp.is_some()),
            egl,
            display,
            context,
            surface,
            egl_info,
            platform,
            device,
            api,
        })
    }
}

/// The surface a context is made current on: none where the display has
/// EGL_KHR_surfaceless_context (Mesa's, NVIDIA's) and [`PBUFFER_ENV`] is unset; elsewhere a
/// 1×1 pbuffer, which rendering never touches (it goes to framebuffer objects).
fn surface_for(
    egl: &egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    config: egl::Config,
) -> Result<Option<egl::Surface>, Unavailable> {
    let surfaceless = egl
        .query_string(Some(display), egl::EXTENSIONS)
        .is_ok_and(|e| {
            e.to_string_lossy()
                .split_whitespace()
                .any(|x| x == "EGL_KHR_surfaceless_context")
        })
        && std::env::var_os(PBUFFER_ENV).is_none();
    if surfaceless {
        return Ok(None);
    }
    egl.create_pbuffer_surface(display, config, &[egl::WIDTH, 1, egl::HEIGHT, 1, egl::NONE])
        .map(Some)
        .map_err(|e| {
            Unavailable(format!(
                "this display lacks EGL_KHR_surfaceless_context (or {PBUFFER_ENV} is set) and refused a 1×1 pbuffer ({e})"
            ))
        })
}

/// The signature of `glPolygonOffsetClamp[EXT]`.
pub type PolygonOffsetClamp = unsafe extern "system" fn(f32, f32, f32);

impl GlContext {
    /// How EGL reached the driver, in words, for drivers.txt: the device with its DRM node
    /// and PCI id, or the surfaceless platform.
    pub fn reached(&self) -> String {
        match &self.device {
            Some(d) => d.describe_with_pci(),
            None => "EGL surfaceless platform (Mesa)".into(),
        }
    }

    /// GL_VENDOR, GL_RENDERER and GL_VERSION.
    pub fn strings(&self) -> [String; 3] {
        // SAFETY: plain queries on this process's current context.
        unsafe {
            [glow::VENDOR, glow::RENDERER, glow::VERSION].map(|s| self.gl.get_parameter_string(s))
        }
    }

    /// Makes this context current on the calling thread again: another library in the same
    /// process (wgpu's GL backend uses EGL too) may have made its own current meanwhile.
    pub fn make_current(&self) -> Result<(), Unavailable> {
        self.egl
            .make_current(self.display, self.surface, self.surface, Some(self.context))
            .map_err(|e| Unavailable(format!("eglMakeCurrent failed ({e})")))
    }
}

impl Drop for GlContext {
    fn drop(&mut self) {
        let _ = self.egl.make_current(self.display, None, None, None);
        let _ = self.egl.destroy_context(self.display, self.context);
        if let Some(s) = self.surface {
            let _ = self.egl.destroy_surface(self.display, s);
        }
        let _ = self.egl.terminate(self.display);
    }
}

/// What a context made on one EGL device reports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceContext {
    /// The API asked for.
    pub api: crate::api::Api,
    /// GL_VENDOR, GL_RENDERER, GL_VERSION, or why no context could be made.
    pub strings: Result<[String; 3], String>,
}

/// Every EGL device this process's EGL library lists, each with the GL 3.3 core, GLES 3 and
/// GLES 2 contexts it can make (`umbra backends`). Mesa's software device renders with the
/// driver this process's environment selects (llvmpipe by default).
pub fn discover() -> Result<Vec<(crate::platform::EglDevice, Vec<DeviceContext>)>, Unavailable> {
    let egl = load_egl()?;
    let list: Vec<crate::platform::EglDevice> = crate::platform::devices(&egl)?
        .into_iter()
        .map(|(d, _)| d)
        .collect();
    Ok(list
        .into_iter()
        .map(|d| {
            let contexts = crate::api::Api::ALL
                .into_iter()
                .map(|api| DeviceContext {
                    api,
                    strings: load_egl()
                        .and_then(|egl| GlContext::on(egl, api, Platform::Device(d.index)))
                        .map(|ctx| ctx.strings())
                        .map_err(|e| e.0),
                })
                .collect();
            (d, contexts)
        })
        .collect())
}
