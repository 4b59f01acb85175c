//! Perspective aliasing, the error measure of Lloyd et al.'s work on warping and partitioning
//! shadow maps ("Warping and partitioning for low error shadow maps", EGSR 2006; "Logarithmic
//! perspective shadow maps", ACM TOG 2008): at each receiver, how many screen pixels one
//! shadow-map texel spans, m = (texel width at the point) / (pixel width at the point). Above
//! 1 a texel covers several pixels and shadow edges show its steps.
//!
//! Both widths are measured across the view and light directions, not along the surface: the
//! surface's orientation (projection aliasing) multiplies both and is left out, as Lloyd et
//! al. separate it. A pixel at view depth d is 2·d·tan(fov_y / 2) / H wide; a texel of an
//! orthographic face is (right − left) / width wide (the larger of its two sides), of a
//! perspective face 2·z·tan(fov_y / 2)·aspect / width at light-view depth z. The face is the
//! one the lookup reads (the cube face, or the cascade of the receiver's view depth).
//!
//! For cascades split at s_0 = n … s_N = f, a slice's box is about as wide as its far end,
//! so the worst pixel of slice k (at its near end) has m ∝ s_{k+1} / s_k: logarithmic splits
//! make that ratio (f/n)^(1/N) in every slice, the least possible maximum; uniform splits
//! leave the first slice with 1 + (f − n)/(N·n).

use glam::Vec3;
use umbra_case::LightRun;
use umbra_case::light::Projection;

use super::Truth;

/// The perspective aliasing of one frame's judged pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aliasing {
    /// The largest m: screen pixels per texel at the worst judged pixel.
    pub max: f64,
    /// The mean m over the judged pixels.
    pub mean: f64,
    /// Judged pixels.
    pub pixels: u64,
    /// The nearest and farthest judged view depths.
    pub depths: (f64, f64),
}

/// The perspective aliasing of `run` at the truth's judged pixels, or `None` without any
/// (the points are found again by [`super::camera_hits`]: a cached truth keeps none).
pub fn perspective_aliasing(run: &LightRun, truth: &Truth) -> Option<Aliasing> {
    let hits = super::camera_hits(run);
    let cam = &run.camera;
    let tan_y = umbra_case::math::tan(0.5 * f64::from(cam.fov_y));
    let height = f64::from(cam.size[1]);
    let [mw, mh] = run.case().shadow.size.map(f64::from);
    let (mut max, mut sum, mut pixels) = (0.0f64, 0.0f64, 0u64);
    let mut depths = (f64::INFINITY, 0.0f64);
    for (i, hit) in hits.iter().enumerate() {
        let Some(p) = hit.filter(|_| truth.judged(i)) else {
            continue;
        };
        let p = &p;
        let q = p.as_vec3();
        let d = -cam.view.as_dmat4().transform_point3(*p).z;
        let pixel = 2.0 * d * tan_y / height;
        let view = &run.light.views[run.light.face_for(q)];
        let texel = texel_width(view.view, view.projection, q, mw, mh);
        if pixel > 0.0 && texel.is_finite() {
            let m = texel / pixel;
            max = max.max(m);
            sum += m;
            pixels += 1;
            depths = (depths.0.min(d), depths.1.max(d));
        }
    }
    (pixels > 0).then(|| Aliasing {
        max,
        mean: sum / pixels as f64,
        pixels,
        depths,
    })
}

/// The world width of one texel of a face at `p` (the larger of its two sides).
fn texel_width(view: glam::Mat4, projection: Projection, p: Vec3, mw: f64, mh: f64) -> f64 {
    match projection {
        Projection::Ortho {
            bounds: [l, r, b, t, ..],
        } => (f64::from(r - l) / mw).max(f64::from(t - b) / mh),
        Projection::Perspective { fov_y, aspect, .. } => {
            let z = -f64::from(view.transform_point3(p).z);
            let h = 2.0 * z * umbra_case::math::tan(0.5 * f64::from(fov_y));
            (h * f64::from(aspect) / mw).max(h / mh)
        }
    }
}
