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
    /// The case's reach, for the position freedom: the largest of the scene's extent and the
    /// camera's and the light's distances from the origin (per axis).
    pub reach: f32,
}

/// Why a lookup's answer is one that a conformant implementation could give differently.
pub mod ambiguity {
    /// A compared texel is within the stored-depth freedom of the reference value.
    pub const DEPTH_TIE: u8 = 1;
    /// The coordinate is within 1/16 texel (the minimum sub-texel precision) of a texel
    /// whose compare differs.
    pub const TEXEL_BOUNDARY: u8 = 2;
    /// LINEAR taps disagree (weights are implementation-defined, NEAREST is allowed), a
    /// LINEAR lookup lies within a texel of a cube face's edge (seamless or per-face
    /// filtering), or a PCF average lies within one 8-bit result step of the 0.5 threshold.
    pub const FILTER: u8 = 4;
    /// Moving the lookup point by the interpolation freedom of its position (see
    /// [`super::position_freedom`]) along any axis changes the answer.
    pub const POSITION: u8 = 8;
}

/// How far the point a backend looks up for a pixel may lie from the reference's, per world
/// axis, from f32 arithmetic the specs leave to the implementation:
/// - varying interpolation ("implementation-dependent" accuracy): barycentrics carry a few
///   ulps of relative error, and Σ bᵢ·aᵢ inherits it scaled by the vertex values (|p| plus
///   the triangle's spread, at most the reach), about 8u·(|p|∞ + reach);
/// - the camera and light transforms: V·p cancels |R·p| against the translation |t| ≈ the
///   eye's distance, so the fragment's position and its shadow coordinate each move by up to
///   γ₄·(|p|∞ + reach) in world units.
///
/// Together 16u·(|p|∞ + reach), u = 2⁻²⁴: about 0.1 mm for a 50 m scene at the origin, and
/// 10 cm at 1e5 m from it, which is why scenes far from the origin lose shadow detail on every
/// backend (numerics/far-from-origin shows how fast).
pub fn position_freedom(p: Vec3, reach: f32) -> f32 {
    16.0 * (f32::EPSILON * 0.5) * (p.abs().max_element() + reach)
}

/// The lit/shadowed answer of a visibility (the judge's threshold).
fn shadowed(v: f32) -> bool {
    v < 0.5
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
        let (vis, mut flags) = self.lookup_at(p, n, judge);
        if judge {
            let d = position_freedom(p, self.reach);
            let moved = [Vec3::X, Vec3::Y, Vec3::Z]
                .into_iter()
                .flat_map(|e| [p + e * d, p - e * d]);
            if moved
                .map(|q| self.lookup_at(q, n, false).0)
                .any(|v| shadowed(v) != shadowed(vis))
            {
                flags |= ambiguity::POSITION;
            }
        }
        (vis, flags)
    }

    fn lookup_at(&self, p: Vec3, n: Vec3, judge: bool) -> (f32, u8) {
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
                // Within a texel of a cube face's edge, GL (seamless off unless enabled)
                // clamps to the face while GLES 3 and Vulkan filter across faces: both legal.
                let at_seam = cube && (x < 0.5 || y < 0.5 || x > fw - 1.5 || y > fh - 1.5);
                if judge && at_seam && taps.iter().any(|t| t.0) {
                    flags |= ambiguity::FILTER;
                }
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
