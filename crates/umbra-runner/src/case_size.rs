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
    /// Shadow-map texels (every light's, all faces).
    pub texels: u64,
}

impl Size {
    /// The size of a case given as JSON (None if it does not load).
    pub fn of(case: &Value) -> Option<Size> {
        let points = umbra_case::load_str(&case.to_string(), Path::new("reduce.json")).ok()?;
        let p = points.into_iter().next()?;
        let g = umbra_case::tessellate(&p.case.scene);
        // Every light's map, each face (a cube's six, a cascade's layers): a case's size
        // once counted its first light's alone.
        let faces: u64 = p.case.lights.iter().map(|l| u64::from(l.map_faces())).sum();
        Some(Size {
            triangles: g.triangles.len(),
            pixels: u64::from(p.case.camera.size[0]) * u64::from(p.case.camera.size[1]),
            texels: faces * u64::from(p.case.shadow.size[0]) * u64::from(p.case.shadow.size[1]),
        })
    }
}
