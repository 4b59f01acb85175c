//! The shadow lookup a lit-pass shader does, step by step, in f32 as a GPU would:
//!
//! 1. Normal offset: p' = p + normal_offset · n.
//! 2. Face: the light's only face, or the cube face of p' by major axis.
//! 3. Coordinate: (u, v, depth, w) with the bias matrix before or after the divide.
//! 4. Guard: w ≤ 0 (behind a perspective light) reads lit when the guard is on.
//! 5. Outside: `lit` reads lit when (u, v) leaves [0,1]² (cube faces never do: they clamp).
//! 6. Reference: depth − (constant + slope bias) away from the light; clamped to [0,1] for a
//!    hardware compare on a fixed-point format (GL 3.3 §3.8.16, Vulkan "Depth Compare"),
//!    never for a manual compare or a float format.
//! 7. Filter: NEAREST texel floor(u·size); LINEAR = 2x2 at floor(u·size − ½) with bilinear
//!    weights of the compare results (never of depths); PCF N = N×N NEAREST compares at
//!    offsets (k − (N−1)/2) texels, averaged.
//! 8. Texels beyond the map: border (clear depth), clamp to edge (also for `lit` and cube
//!    faces), or repeat.
//!
//! Manual compare uses the same texel selection and weights as hardware compare: the shader
//! fetches the texels and compares them itself, so the two differ only in the clamp of 6.

use glam::Vec3;
use umbra_case::format::{Compare, DepthFormat, Filter, Outside, Shadow};
use umbra_case::{Convention, LightSetup, LookupMatrices};

use crate::shadow_pass::DepthLayer;

/// The rendered shadow maps of a run and what a lookup needs to read them.
pub struct Lookup<'a> {
    /// Convention the maps were rendered in.
    pub conv: Convention,
    /// The technique.
    pub shadow: &'a Shadow,
    /// The light.
    pub light: &'a LightSetup,
    /// One matrix pair per face.
    pub matrices: Vec<LookupMatrices>,
    /// One layer per face.
    pub layers: &'a [DepthLayer],
}

/// Why a lookup's answer is one that a conformant implementation could give differently.
pub mod ambiguity {
    /// A compared texel is within the stored-depth freedom of the reference value.
    pub const DEPTH_TIE: u8 = 1;
    /// The coordinate is within 1/16 texel (the minimum sub-texel precision) of a texel
    /// whose compare differs.
    pub const TEXEL_BOUNDARY: u8 = 2;
    /// LINEAR taps disagree (weights are implementation-defined, NEAREST is allowed), or a
    /// PCF average lies within one 8-bit result step of the 0.5 threshold.
    pub const FILTER: u8 = 4;
}

/// Sub-texel precision the specs guarantee (4 bits).
const SUBTEXEL: f32 = 1.0 / 16.0;

impl Lookup<'_> {
    /// The shadow term at world point `p` with unit normal `n`: 1 lit .. 0 shadowed.
    pub fn visibility(&self, p: Vec3, n: Vec3) -> f32 {
        self.lookup(p, n, false).0
    }

    /// The shadow term and the [`ambiguity`] flags of its decision.
    pub fn visibility_judged(&self, p: Vec3, n: Vec3) -> (f32, u8) {
        self.lookup(p, n, true)
    }

    fn lookup(&self, p: Vec3, n: Vec3, judge: bool) -> (f32, u8) {
        let s = self.shadow;
        let p = p + n * s.bias.normal_offset;
        let face = self.light.face_for(p);
        let cube = self.layers.len() == 6;
        let c = self.matrices[face].coord(self.conv, s.bias_matrix, p);
        if s.guard_behind_light && c.w <= 0.0 {
            return (1.0, 0);
        }
        if !cube
            && s.outside == Outside::Lit
            && !((0.0..=1.0).contains(&c.u) && (0.0..=1.0).contains(&c.v))
        {
            return (1.0, 0);
        }
        let mut bias = s.bias.constant;
        if let Some(slope) = s.bias.slope {
            let cos = n.dot(self.light.to_light(p)).clamp(-1.0, 1.0);
            bias += (slope.scale * cos.acos().tan()).clamp(0.0, slope.max);
        }
        let mut reference = c.depth - self.conv.toward_far() * bias;
        if s.compare == Compare::Hardware && s.format.is_fixed() {
            reference = reference.clamp(0.0, 1.0);
        }
        let layer = &self.layers[face];
        let [w, h] = s.size;
        let outside = if cube {
            Outside::ClampToEdge
        } else {
            s.outside
        };
        let clear = self.conv.clear_depth();
        // One compare: (passes, within the stored depth's freedom).
        let tap = |i: i64, j: i64| -> (bool, bool) {
            let (d, slack) = texel(layer, w, h, i, j, outside, clear, s.format);
            let pass = self.conv.compare_lit(reference, d);
            let tie = judge
                && (reference - d).abs()
                    <= slack
                        + s.format.step(reference) as f32
                        + 4.0 * umbra_case::depth::f32_spacing(reference);
            (pass, tie)
        };
        let (fw, fh) = (w as f32, h as f32);
        let mut flags = 0u8;
        // NEAREST at (x, y) texels: the texel, and whether a neighbour within the sub-texel
        // precision decides differently.
        let nearest = |x: f32, y: f32, flags: &mut u8| -> f32 {
            let (i, j) = (x.floor() as i64, y.floor() as i64);
            let (pass, tie) = tap(i, j);
            if judge {
                if tie {
                    *flags |= ambiguity::DEPTH_TIE;
                }
                let (fx, fy) = (x - x.floor(), y - y.floor());
                let near_x = if fx < SUBTEXEL {
                    Some(i - 1)
                } else if fx > 1.0 - SUBTEXEL {
                    Some(i + 1)
                } else {
                    None
                };
                let near_y = if fy < SUBTEXEL {
                    Some(j - 1)
                } else if fy > 1.0 - SUBTEXEL {
                    Some(j + 1)
                } else {
                    None
                };
                let others = [
                    near_x.map(|k| (k, j)),
                    near_y.map(|k| (i, k)),
                    near_x.zip(near_y),
                ];
                if others.iter().flatten().any(|&(a, b)| tap(a, b).0 != pass) {
                    *flags |= ambiguity::TEXEL_BOUNDARY;
                }
            }
            if pass { 1.0 } else { 0.0 }
        };
        let vis = match s.filter {
            Filter::Nearest => nearest(c.u * fw, c.v * fh, &mut flags),
            Filter::Linear => {
                let (x, y) = (c.u * fw - 0.5, c.v * fh - 0.5);
                let (i0, j0) = (x.floor(), y.floor());
                let (a, b) = (x - i0, y - j0);
                let (i0, j0) = (i0 as i64, j0 as i64);
                let taps = [
                    tap(i0, j0),
                    tap(i0 + 1, j0),
                    tap(i0, j0 + 1),
                    tap(i0 + 1, j0 + 1),
                ];
                let v = |t: (bool, bool)| if t.0 { 1.0 } else { 0.0 };
                if judge {
                    if taps.iter().any(|t| t.1) {
                        flags |= ambiguity::DEPTH_TIE;
                    }
                    if taps.iter().any(|t| t.0 != taps[0].0) {
                        flags |= ambiguity::FILTER;
                    }
                }
                (1.0 - a) * (1.0 - b) * v(taps[0])
                    + a * (1.0 - b) * v(taps[1])
                    + (1.0 - a) * b * v(taps[2])
                    + a * b * v(taps[3])
            }
            Filter::Pcf(k) => {
                let half = (k as f32 - 1.0) * 0.5;
                let mut sum = 0.0;
                for dy in 0..k {
                    for dx in 0..k {
                        let u = c.u + (dx as f32 - half) / fw;
                        let v = c.v + (dy as f32 - half) / fh;
                        sum += nearest(u * fw, v * fh, &mut flags);
                    }
                }
                let avg = sum / (k * k) as f32;
                if judge && (avg - 0.5).abs() <= 1.0 / 255.0 {
                    flags |= ambiguity::FILTER;
                }
                avg
            }
        };
        (vis, flags)
    }
}

/// The stored depth and its slack at texel (i, j) under the wrap policy (border texels hold
/// the clear depth, exactly).
#[allow(clippy::too_many_arguments)]
fn texel(
    layer: &DepthLayer,
    w: u32,
    h: u32,
    i: i64,
    j: i64,
    outside: Outside,
    clear: f32,
    format: DepthFormat,
) -> (f32, f32) {
    let (w, h) = (i64::from(w), i64::from(h));
    let (i, j) = match outside {
        Outside::Border => {
            if i < 0 || j < 0 || i >= w || j >= h {
                return (format.store(clear), 0.0);
            }
            (i, j)
        }
        Outside::Lit | Outside::ClampToEdge => (i.clamp(0, w - 1), j.clamp(0, h - 1)),
        Outside::Repeat => (i.rem_euclid(w), j.rem_euclid(h)),
    };
    let k = (j * w + i) as usize;
    (layer.values[k], layer.slack[k])
}
