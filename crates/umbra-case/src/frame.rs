//! What every backend returns: the same [`Frame`] whatever the API, so that one judge reads
//! them all. Images are stored top row first; a backend whose API stores rows bottom first
//! flips once, when it reads back.

use std::time::Duration;

use crate::format::DepthFormat;

/// One rendered run.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Shaded colour, every light's pass added, RGBA8, top row first.
    pub color: Vec<u8>,
    /// Every light's own outputs, in the case's order: one light's frame has one.
    pub lights: Vec<LightPlane>,
    /// How the visibility values were stored before they were read back (the judge widens
    /// the legal values by that storage's rounding).
    pub visibility_storage: VisibilityStorage,
    /// Where the time went (every light's passes).
    pub timings: Timings,
}

/// One light's own outputs in a frame ([`Frame::lights`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LightPlane {
    /// The light's shadow term per pixel, 1 lit .. 0 shadowed; NaN where no surface covers
    /// the pixel.
    pub visibility: Vec<f32>,
    /// The light's shadow map as stored, where the backend reads it back.
    pub shadow_map: Option<DepthMap>,
    /// Per pixel: the covering triangle's face id + 1 (0 = background) as the light's own
    /// pass drew it, where the backend can write it; the judge uses it to find silhouettes.
    /// Each light's is its own: a later light's pass redraws the depth, and on an exact tie
    /// of two surfaces may show the other one (soak-43-398).
    pub surface: Option<Vec<u32>>,
}

/// One light's view of a frame ([`Frame::light`]): the frame's size and storage, that light's
/// visibility, map and surfaces. What the judge reads of a light, whatever the count.
#[derive(Clone, Copy, Debug)]
pub struct LightFrame<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The light's shadow term per pixel ([`LightPlane::visibility`]).
    pub visibility: &'a [f32],
    /// The light's map as stored, where the backend reads it back.
    pub shadow_map: Option<&'a DepthMap>,
    /// The surface id per pixel as the light's pass drew it ([`LightPlane::surface`]).
    pub surface: Option<&'a [u32]>,
    /// How the visibility values were stored ([`Frame::visibility_storage`]).
    pub visibility_storage: VisibilityStorage,
}

impl Frame {
    /// Light `k`'s view; `None` where the frame has no plane for it (a backend that wrote
    /// fewer planes than the case has lights).
    pub fn light(&self, k: usize) -> Option<LightFrame<'_>> {
        self.lights.get(k).map(|p| LightFrame {
            width: self.width,
            height: self.height,
            visibility: &p.visibility,
            shadow_map: p.shadow_map.as_ref(),
            surface: p.surface.as_deref(),
            visibility_storage: self.visibility_storage,
        })
    }

    /// Every light's view, in the case's order.
    pub fn each_light(&self) -> impl Iterator<Item = LightFrame<'_>> {
        (0..self.lights.len()).filter_map(|k| self.light(k))
    }

    /// Whether pixel `i` (row-major, top row first) shows a surface in any light's pass
    /// ([`LightFrame::covered`]; every pass draws the same triangles).
    pub fn covered(&self, i: usize) -> bool {
        self.lights
            .iter()
            .any(|p| covered(p.surface.as_deref(), &p.visibility, i))
    }
}

/// Whether pixel `i` shows a surface: its surface id where there are ids (so that a NaN
/// visibility on a covered pixel is seen as what it is), else a visibility that is a number.
fn covered(surface: Option<&[u32]>, visibility: &[f32], i: usize) -> bool {
    match surface {
        Some(s) => s[i] != 0,
        None => !visibility[i].is_nan(),
    }
}

impl LightFrame<'_> {
    /// Whether pixel `i` (row-major, top row first) shows a surface in this light's pass.
    pub fn covered(&self, i: usize) -> bool {
        covered(self.surface, self.visibility, i)
    }
}

/// The render target a backend's visibility values went through.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VisibilityStorage {
    /// 32-bit float: written as computed.
    #[default]
    Float32,
    /// 8-bit unsigned normalised (GL's RGBA8 visibility target, GLES 2's packed output).
    Unorm8,
}

impl VisibilityStorage {
    /// How far a stored value may lie from the value the shader wrote.
    ///
    /// - `Unorm8`: float → unorm conversion rounds to nearest by preference, but the specs
    ///   allow either neighbour (Vulkan "Conversion from Floating-Point to Normalized
    ///   Fixed-Point", GL 4.6 §2.3.5.2): |stored − v| < 1/255.
    /// - `Float32`: written as computed; the filtered value's own last operation (a division
    ///   by N² for PCF, ≤ 2.5 ULP in GLSL 4.60 §4.7.1 and SPIR-V's precision table) and the
    ///   reference's rounding: 4 ULP of 1.
    pub fn tolerance(self) -> f32 {
        match self {
            VisibilityStorage::Unorm8 => 1.0 / 255.0,
            VisibilityStorage::Float32 => 4.0 * f32::EPSILON,
        }
    }

    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            VisibilityStorage::Float32 => "f32",
            VisibilityStorage::Unorm8 => "unorm8",
        }
    }
}

/// A depth map read back: one or six layers (cube faces +x, −x, +y, −y, +z, −z).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthMap {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// 1, or 6 for a cube map.
    pub layers: u32,
    /// The format the values were stored in.
    pub format: DepthFormat,
    /// Stored depth values, layer after layer, each top row first (row 0 = light-view +y).
    pub values: Vec<f32>,
}

/// Which clock measured a [`Timings`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// CPU wall time around the work (includes submission and waiting).
    CpuWall,
    /// GPU timer or timestamp queries.
    Gpu,
}

/// Time per stage of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Shadow pass (all faces).
    pub shadow_pass: Duration,
    /// Lit (camera) pass.
    pub lit_pass: Duration,
    /// Reading results back.
    pub readback: Duration,
    /// Everything from the start of `render` to the end.
    pub total: Duration,
    /// The clock of the pass figures.
    pub clock: Option<Clock>,
}
