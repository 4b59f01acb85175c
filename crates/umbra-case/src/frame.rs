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
    /// Shaded colour, RGBA8, top row first.
    pub color: Vec<u8>,
    /// The shadow term per pixel, 1 lit .. 0 shadowed; NaN where no surface covers the pixel.
    pub visibility: Vec<f32>,
    /// Per pixel: the covering triangle's face id + 1 (0 = background), where the backend can
    /// write it; the judge uses it to find silhouettes.
    pub surface: Option<Vec<u32>>,
    /// The shadow map as stored, where the backend can read it back.
    pub shadow_map: Option<DepthMap>,
    /// Where the time went.
    pub timings: Timings,
}

impl Frame {
    /// Whether pixel `i` (row-major, top row first) shows a surface.
    pub fn covered(&self, i: usize) -> bool {
        !self.visibility[i].is_nan()
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
