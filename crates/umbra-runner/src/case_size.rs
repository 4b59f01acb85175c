//! The size of a case in what it costs to run (triangles, camera pixels, shadow-map texels):
//! the before/after line of `umbra reduce` and the size a repro bundle reports. A leaf, so the
//! reducer and the repro bundle read it without one importing the other.

use std::path::Path;

use serde_json::Value;

/// Size figures of a case, for the before/after line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Size {
    /// Triangles drawn.
    pub triangles: usize,
    /// Camera pixels.
    pub pixels: u64,
    /// Shadow-map texels (all faces).
    pub texels: u64,
}

impl Size {
    /// The size of a case given as JSON (None if it does not load).
    pub fn of(case: &Value) -> Option<Size> {
        let points = umbra_case::load_str(&case.to_string(), Path::new("reduce.json")).ok()?;
        let p = points.into_iter().next()?;
        let g = umbra_case::tessellate(&p.case.scene);
        let faces = if matches!(p.case.light, umbra_case::format::Light::Point(_)) {
            6
        } else {
            1
        };
        Some(Size {
            triangles: g.triangles.len(),
            pixels: u64::from(p.case.camera.size[0]) * u64::from(p.case.camera.size[1]),
            texels: faces * u64::from(p.case.shadow.size[0]) * u64::from(p.case.shadow.size[1]),
        })
    }
}
