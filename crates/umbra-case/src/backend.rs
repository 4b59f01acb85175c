//! The one interface every backend implements, object-safe so the runner can hold a
//! `Box<dyn Backend>` per worker. A backend that cannot do what a case needs says so with
//! [`Support::Unsupported`] and a reason: a skip, never a silent pass.

use std::fmt;

use crate::format::{Case, Compare, DepthFormat, DepthOrder, Filter, Light, Outside};
use crate::frame::Frame;
use crate::prepare::Prepared;
use crate::profile::Profile;

/// A backend's identifier, `api/driver` (`ref`, `gl33/llvmpipe`, `wgpu-vk/lavapipe`).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BackendId(pub String);

impl BackendId {
    /// What a driver reports (`radeonsi`, `NVIDIA`, `Intel open-source …`'s first word) as
    /// the second part of an id: lower case, letters, digits, `-` and `_` only (anything
    /// else becomes `-`); `unknown` for nothing. One rule for EGL devices and wgpu adapters.
    pub fn name_part(raw: &str) -> String {
        let part: String = raw
            .trim()
            .to_ascii_lowercase()
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '-'
                }
            })
            .collect();
        if part.is_empty() {
            "unknown".into()
        } else {
            part
        }
    }

    /// Whether `s` can be an id's second part: [`BackendId::name_part`]'s characters, and
    /// `.` before a second device's number (`radeonsi.2`).
    pub fn is_name_part(s: &str) -> bool {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || "-_.".contains(c))
    }
}

impl fmt::Display for BackendId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// What a family of backends can do, as its own crate declares it (`umbra_gl::Api::capabilities`,
/// `umbra_wgpu::Kind::capabilities`): the runner's registry reads these rather than parsing
/// an id, and the self-test's faults, the repro's capture and `umbra backends` follow it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Capabilities {
    /// Draws through a driver, whose shaders a self-test fault can be injected into.
    pub driver: bool,
    /// umbra makes the GL calls itself, so a repro can capture and replay them as C.
    pub umbra_makes_gl_calls: bool,
    /// Samples the map through GL texture units and picks a texture component (GL's binding
    /// model; wgpu binds by group).
    pub gl_texture_units: bool,
    /// Clip depth in [0, 1], where GL's [-1, 1] mapping is a fault.
    pub zero_to_one_depth: bool,
    /// Takes the depth bias's constant as a whole number of units (wgpu's `DepthBiasState`),
    /// so a fractional offset is rounded.
    pub integer_depth_bias: bool,
    /// Can compare in the shader, with its own LINEAR filter.
    pub manual_compare: bool,
    /// The technique GLES 2 forces: no float depth, no mipmapped compare, every compare done
    /// by hand in the shader (which clamps the reference itself).
    pub gles2_technique: bool,
}

/// What the driver says about itself, verbatim.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DriverInfo {
    /// Vendor string.
    pub vendor: String,
    /// Renderer / adapter name.
    pub renderer: String,
    /// Version string.
    pub version: String,
    /// Extensions or features that matter to umbra.
    pub extensions: Vec<String>,
    /// The device and how it is reached (EGL device and DRM node, Vulkan adapter), with its
    /// PCI id where the driver gives one; drivers.txt records it.
    pub device: String,
}

/// What a case asks of a backend; derived from the case, so a case asks only for what its
/// scene needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Needs {
    /// A cube depth map (a point light among the case's lights).
    pub cube_map: bool,
    /// A 2D depth map (a spot or directional light among the case's lights): what a
    /// clamp-to-border wrap applies to (a cube map clamps to its edges).
    pub flat_map: bool,
    /// The depth format.
    pub format: DepthFormat,
    /// Hardware or manual compare.
    pub compare: Compare,
    /// The filter.
    pub filter: Filter,
    /// The outside policy (clamp to border is optional on some APIs).
    pub outside: Outside,
    /// Forward or reversed depth.
    pub depth_order: DepthOrder,
    /// A polygon-offset clamp (Vulkan's depthBiasClamp).
    pub polygon_offset_clamp: bool,
    /// A polygon-offset `units` that is not a whole number (glPolygonOffset takes a float;
    /// Vulkan's depthBiasConstantFactor too, but wgpu's `DepthBiasState::constant` is an
    /// integer).
    pub fractional_offset_units: bool,
    /// A mipmapped map (levels, their filter, how they are filled).
    pub mipmaps: Option<crate::format::Mipmaps>,
    /// Depth clamp in the shadow pass (GL 3.2 core / EXT_depth_clamp on GLES, Vulkan's
    /// depthClamp feature, wgpu's DEPTH_CLIP_CONTROL).
    pub depth_clamp: bool,
    /// The layers of a 2D array map: a cascaded light's cascades, or several lights' maps in
    /// one array (`shadow.placement` `array`); 0: no array.
    pub array_layers: u32,
    /// Cubes of a cube-map array: several point lights' maps in one (`shadow.placement`
    /// `cube_array`); 0: none.
    pub cube_array: u32,
    /// Lights, each a lit pass and a map (1, or `lights`' count).
    pub lights: u32,
    /// The shadow map's larger side (each cube face's, for a point light).
    pub map_size: u32,
    /// The camera image's larger side.
    pub image_size: u32,
    /// An sRGB colour target for the lit pass (`camera.color_format` `srgb8_alpha8`): core
    /// in GL 3.0 and GLES 3.0, GL_EXT_sRGB on GLES 2.
    pub srgb_target: bool,
}

impl Needs {
    /// The needs of `case`.
    pub fn of(case: &Case) -> Self {
        let s = &case.shadow;
        Needs {
            cube_map: case.lights.iter().any(|l| matches!(l, Light::Point(_))),
            flat_map: case.lights.iter().any(|l| !matches!(l, Light::Point(_))),
            format: s.format,
            compare: s.compare,
            filter: s.filter,
            outside: s.outside,
            depth_order: s.depth_order,
            polygon_offset_clamp: s.bias.polygon_offset_clamp != 0.0,
            fractional_offset_units: s.bias.polygon_offset[1].fract() != 0.0,
            mipmaps: s.mipmaps,
            depth_clamp: s.depth_clamp,
            array_layers: if case.maps_share_array()
                && s.placement == crate::format::Placement::Array
            {
                case.lights.len() as u32
            } else {
                // Several lights never have cascades (validation): a light's cascades are
                // its map's layers.
                case.lights
                    .iter()
                    .map(|l| match l {
                        Light::Directional(d) => d.cascades.as_ref().map_or(0, |c| c.count),
                        _ => 0,
                    })
                    .max()
                    .unwrap_or(0)
            },
            cube_array: if case.maps_share_array()
                && s.placement == crate::format::Placement::CubeArray
            {
                case.lights.len() as u32
            } else {
                0
            },
            lights: case.lights.len() as u32,
            map_size: s.size[0].max(s.size[1]),
            image_size: case.camera.size[0].max(case.camera.size[1]),
            srgb_target: case.camera.color_format == crate::format::ColorFormat::Srgb8Alpha8,
        }
    }
}

/// Whether a backend can run a case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Support {
    /// It can.
    Supported,
    /// It cannot, and why (with the package or feature that would help).
    Unsupported(String),
}

/// Why a render failed.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    /// The backend cannot run this case on this driver.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The API reported an error at a stage.
    #[error("{stage}: {message}")]
    Api {
        /// Which stage (`shadow pass`, `readback`, ...).
        stage: String,
        /// The API's message.
        message: String,
    },
    /// Anything else the driver or the backend got wrong.
    #[error("{0}")]
    Other(String),
}

/// A renderer of cases.
pub trait Backend {
    /// Its identifier.
    fn id(&self) -> BackendId;
    /// What its driver reports.
    fn info(&self) -> DriverInfo;
    /// Which freedoms its API gives the driver: the judge computes the legal answers of this
    /// backend's frames for this profile.
    fn profile(&self) -> Profile;
    /// Whether it can run a case with these needs.
    fn supports(&self, needs: &Needs) -> Support;
    /// Renders one run. Per-run GPU state is created and destroyed inside.
    fn render(&mut self, run: &Prepared) -> Result<Frame, BackendError>;

    /// After a run that failed: returns the backend to the state a fresh one has, or says why
    /// it cannot (then the worker is replaced, so one run's error never reaches the next).
    fn restore(&mut self) -> Result<(), String> {
        Ok(())
    }

    /// Whether `a` and `b` render identically on this backend *by construction*: they differ
    /// only in settings it never reads, so a metamorphic twin between them would be the same
    /// render twice and is not rendered (the report says so). By default only equal cases do;
    /// a backend that overrides this must never read the settings it lets differ.
    fn renders_identically(&self, a: &Case, b: &Case) -> bool {
        a == b
    }

    /// Renders `twin`, a metamorphic twin of `of`, right after `of` was rendered by
    /// [`Backend::render`]. Where the twin's shadow pass is the case's by construction
    /// ([`crate::twin::same_shadow_pass`]: the bias-order twin changes only the lit pass's
    /// lookup), a backend may draw the lit pass over the shadow map it kept from `of` instead
    /// of rendering the same map again; it then says so (`true`) and the frame carries no
    /// shadow map. The default renders the twin afresh.
    fn render_twin(
        &mut self,
        twin: &Prepared,
        of: &Prepared,
    ) -> Result<(Frame, bool), BackendError> {
        let _ = of;
        self.render(twin).map(|f| (f, false))
    }

    /// Renders `run` as [`Backend::render`] does while recording every API call, and returns
    /// the frame with a standalone C program making the same calls (`umbra repro`): given a
    /// header comment and the probes' C, the builder returns the whole source. Only backends
    /// that can emit one override this; the default says why there is none.
    fn render_recorded(&mut self, run: &Prepared) -> Result<(Frame, ReproProgram), BackendError> {
        let _ = run;
        Err(BackendError::Unsupported(format!(
            "{} records no API calls as a standalone program (only the GL backends do)",
            self.id()
        )))
    }
}

/// A recorded run's standalone C program: `(header comment, probes' C) -> source`.
pub type ReproProgram = Box<dyn Fn(&str, &str) -> String>;
