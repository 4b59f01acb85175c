//! The shadow pass: depth of every triangle as seen from each light face, into a map of the
//! case's format.
//!
//! Per fragment: window depth (linear in screen space) + polygon offset
//! o = m·factor + r·units (m = max |∂z/∂x|, |∂z/∂y|; r from [`DepthFormat::offset_unit`]),
//! signed away from the light by the depth order and limited by the clamp if one is given;
//! then clamped to the depth range [0,1], converted to the format and depth-tested (LESS
//! forward, GREATER reversed) against the stored value in the format's own precision.

use glam::Vec4;
use umbra_case::format::{DepthFormat, Shadow};
use umbra_case::{Convention, Geometry};

use crate::bands::for_each_band;
use crate::raster::{Rasterizer, Tri};

/// One rendered face: stored depth per texel, in raster row order (row 0 = window y 0).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthLayer {
    /// Stored values, `width * height`.
    pub values: Vec<f32>,
    /// Per texel, how far another conformant implementation's stored value may lie from
    /// ours (see [`slack`]); 0 where nothing was drawn.
    pub slack: Vec<f32>,
}

/// The freedom the specs leave in a stored depth, for the winning triangle `t`
/// (NUMERICS.md): the polygon-offset slope may be m = sqrt(dx² + dy²) instead of our
/// max(|dx|, |dy|), which adds up to (sqrt − max)·|factor|; the unit r is an implementation
/// constant (Vulkan allows up to 2 steps), so r·|units| either way; and storage may round
/// either way (±1 step). f32 rounding of the interpolation adds a few ulps of z. And vertex
/// snapping: GL and Vulkan require only 4 sub-pixel bits, so another implementation's vertex
/// window coordinates may lie up to 1/32 pixel from the exact ones (ours: 1/512, 8 bits);
/// the triangle's depth plane at a texel centre then moves by up to (|dx| + |dy|) times that.
/// It matters on faces steep to the light, where depth changes fast across a texel.
fn slack(t: &Tri, format: DepthFormat, factor: f32, units: f32) -> f32 {
    let (dx, dy) = t.depth_slopes();
    let m_freedom = (dx.hypot(dy) - dx.abs().max(dy.abs())) * f64::from(factor.abs());
    let snap = (dx.abs() + dy.abs()) * (1.0 / 32.0 + 1.0 / 512.0);
    let z = t.max_abs_z();
    let r = f64::from(format.offset_unit(z));
    let step = format.step(z);
    (m_freedom
        + snap
        + r * f64::from(units.abs())
        + step
        + 4.0 * f64::from(umbra_case::depth::f32_spacing(z))) as f32
}

/// Renders one light face with view-projection `light`.
pub fn render_face(
    conv: Convention,
    shadow: &Shadow,
    light: glam::Mat4,
    geo: &Geometry,
) -> DepthLayer {
    let [w, h] = shadow.size;
    let raster = Rasterizer {
        conv,
        width: w,
        height: h,
        cull: shadow.cull,
    };
    let tris = setup_all(&raster, light, geo);
    let format = shadow.format;
    let [factor, units] = shadow.bias.polygon_offset;
    let clamp = shadow.bias.polygon_offset_clamp;
    let sign = conv.toward_far();
    // (stored value, slack) per texel.
    let mut texels = vec![(format.store(conv.clear_depth()), 0.0f32); (w * h) as usize];
    for_each_band(&mut texels, w as usize, 1, &tris, |rows, band, touching| {
        for t in touching {
            let offset = if factor != 0.0 || units != 0.0 {
                polygon_offset(t, format, factor, units, clamp)
            } else {
                0.0
            };
            let freedom = slack(t, format, factor, units);
            t.scan(rows.clone(), |x, y, frag| {
                let z = (f64::from(t.depth(frag)) + f64::from(sign) * offset) as f32;
                let stored = format.store(z.clamp(0.0, 1.0));
                let i = (y - rows.start) as usize * w as usize + x as usize;
                if conv.depth_test(stored, band[i].0) {
                    band[i] = (stored, freedom);
                }
            });
        }
    });
    let (values, slack) = texels.into_iter().unzip();
    DepthLayer { values, slack }
}

/// The polygon offset of a triangle, as a positive distance away from the light.
fn polygon_offset(t: &Tri, format: DepthFormat, factor: f32, units: f32, clamp: f32) -> f64 {
    let o = t.max_depth_slope() * f64::from(factor)
        + f64::from(format.offset_unit(t.max_abs_z())) * f64::from(units);
    if clamp > 0.0 {
        o.min(f64::from(clamp))
    } else {
        o
    }
}

/// Clip-space corners of every triangle under `view_proj`, set up in source order.
pub fn setup_all(raster: &Rasterizer, view_proj: glam::Mat4, geo: &Geometry) -> Vec<Tri> {
    let clip: Vec<Vec4> = geo
        .positions
        .iter()
        .map(|p| view_proj * p.extend(1.0))
        .collect();
    let mut tris = Vec::with_capacity(geo.triangles.len());
    for (i, t) in geo.triangles.iter().enumerate() {
        raster.setup(t.map(|k| clip[k as usize]), i as u32, &mut tris);
    }
    tris
}
