//! How far another implementation's arithmetic may move what the lookup computes: the
//! coordinate in texels, the coordinate's depth and the compare's reference value (its
//! biases included), from the shader's f32 operations as GLSL and SPIR-V bound them.

use super::*;

impl Lookup<'_> {
    /// The point a lookup transforms (after the normal offset), in f32 and as f64 (p, 1),
    /// and the matrix it goes through on `face` (texture matrix, or light matrix when the bias
    /// matrix comes after the divide): what the error bounds below are computed from.
    pub(super) fn lookup_point(
        &self,
        p: Vec3,
        n: Vec3,
        face: usize,
    ) -> (Vec3, glam::DVec4, glam::DMat4) {
        let q = self.moved(p, n, face);
        (q, q.as_dvec3().extend(1.0), self.wide[face])
    }

    /// [`Lookup::wide`] of `matrices` under `order`: the texture matrix before the divide, the
    /// light's after it.
    pub fn widened(matrices: &[LookupMatrices], order: BiasMatrix) -> Vec<glam::DMat4> {
        matrices
            .iter()
            .map(|m| match order {
                BiasMatrix::BeforeDivide => m.texture.as_dmat4(),
                BiasMatrix::AfterDivide => m.light.as_dmat4(),
            })
            .collect()
    }

    /// How far the texel coordinates (u·size, v·size) another implementation computes for
    /// this point may lie from ours: like the reference value's depth, each of t.x, t.y and
    /// t.w is a 4-term f32 dot product of the same uploaded matrix row with (p, 1), rounded
    /// within γ₄·Σ|mᵢ·pᵢ| on either side, then divided (2.5 ULP); the bias matrix after the
    /// divide halves that and adds a product and a sum; then scaled by the size.
    pub(super) fn coord_error(&self, p: Vec3, n: Vec3, st: &Setup) -> (f64, f64) {
        let s = self.shadow;
        let (_, p4, m) = self.lookup_point(p, n, st.face);
        let row_abs = |r: usize| -> f64 { (0..4).map(|k| (m.col(k)[r] * p4[k]).abs()).sum() };
        let row = |r: usize| -> f64 { (0..4).map(|k| m.col(k)[r] * p4[k]).sum() };
        let wv = row(3).abs().max(1e-30);
        let err = |r: usize| {
            let ratio = row(r) / wv;
            let e =
                2.0 * gamma(4.0) * (row_abs(r) + ratio.abs() * row_abs(3)) / wv + 3.0 * ulp(ratio);
            match s.bias_matrix {
                BiasMatrix::BeforeDivide => e,
                BiasMatrix::AfterDivide => 0.5 * e + 2.0 * ulp(0.5 * ratio + 0.5),
            }
        };
        let [w, h] = s.size;
        (err(0) * f64::from(w), err(1) * f64::from(h))
    }

    /// The interval of the compare's reference value another implementation may compute at
    /// this point (the point itself fixed; see [`position_freedom`] for its moves):
    ///
    /// - the coordinate: each of t.z and t.w is a 4-term f32 dot product of the same uploaded
    ///   matrix row with (p, 1), rounded within γ₄·Σ|mᵢ·pᵢ| by either side, so twice that,
    ///   then a division (2.5 ULP, GLSL 4.60 §4.7.1, SPIR-V) and our own rounding;
    /// - the bias: the constant is exact; the slope and N·L biases move with c = N·L, whose error is
    ///   the normal's interpolation and normalisation (≈ 12u), the light direction's (4u, plus
    ///   the position freedom over the light's distance for a positional light) and the dot
    ///   product's (3u), and `turn`, how far the normal turns across the region; then sqrt,
    ///   a division and a product (8u relative);
    /// - `extra`: the point's own freedom, measured by the caller;
    /// - a hardware compare on a fixed-point format clamps the result to [0,1], and may
    ///   compare in the format's own fixed point: the reference value rounded to a code
    ///   either way. No spec sets the compare's precision; dEQP and the VK-CTS allow 2⁻¹⁶
    ///   (`referenceBits`), umbra only the texture's own codes.
    pub(super) fn reference_range(
        &self,
        p: Vec3,
        n: Vec3,
        turn: f32,
        st: &Setup,
        extra: f64,
    ) -> (f64, f64) {
        let s = self.shadow;
        let q = self.lookup_point(p, n, st.face).0;
        let err = self.depth_error(p, n, st.face, st.c.depth);
        let depth = f64::from(st.c.depth);
        let (mut b_lo, mut b_hi) = (f64::from(s.bias.constant), f64::from(s.bias.constant));
        // c = N·L as the shader computes it (with the light vector `which`), and how far it
        // may be off.
        let cosine = |which: LightVector| {
            let to_light = self.light.bias_light_vector(q, which);
            let c = f64::from(n.dot(to_light));
            let dist = match (self.light.kind, which) {
                (LightKind::Directional { .. }, LightVector::Direction) => f64::INFINITY,
                _ => f64::from((self.light.position() - q).length()),
            };
            // The normal turns by up to `turn` across the region (an interpolated normal
            // is another point's), moving c by as much (L is a unit vector): at c near 0
            // that decides whether a slope bias is its cap or nothing (soak-47-845).
            (
                c,
                19.0 * U + f64::from(position_freedom(p, self.reach)) / dist + f64::from(turn),
            )
        };
        if let Some(nl) = s.bias.n_dot_l {
            // max(s·(1 − c), min) decreases in c; a product, a sum and a max (3u relative).
            let (c, dc) = cosine(nl.light);
            let f = |c: f64| (f64::from(nl.scale) * (1.0 - c)).max(f64::from(nl.min));
            b_lo += f(c + dc) * (1.0 - 3.0 * U);
            b_hi += f(c - dc) * (1.0 + 3.0 * U);
        }
        if let Some(slope) = s.bias.slope {
            let (c, dc) = cosine(LightVector::Direction);
            let tan = |c: f64| {
                if c > 0.0 {
                    (1.0 - c * c).max(0.0).sqrt() / c
                } else {
                    f64::INFINITY
                }
            };
            let clamp = |t: f64| (f64::from(slope.scale) * t).clamp(0.0, f64::from(slope.max));
            // tan is decreasing in c on (0, 1]; c ≤ 0 reads 0 bias, the other end of the range.
            let (c_lo, c_hi) = (c - dc, c + dc);
            let hi_t = if c_lo > 0.0 {
                clamp(tan(c_lo)) * (1.0 + 8.0 * U)
            } else {
                f64::from(slope.max)
            };
            let lo_t = if c_hi > 0.0 {
                clamp(tan(c_hi.min(1.0))) * (1.0 - 8.0 * U)
            } else {
                0.0
            };
            let lo_t = if c_lo <= 0.0 { 0.0 } else { lo_t };
            b_lo += lo_t.min(hi_t);
            b_hi += hi_t.max(lo_t);
        }
        let away = f64::from(self.conv.toward_far());
        let (o1, o2) = (away * b_lo, away * b_hi);
        let bias_err = ulp(depth) + extra;
        let mut lo = depth - err - o1.max(o2) - bias_err;
        let mut hi = depth + err - o1.min(o2) + bias_err;
        if s.compare == Compare::Hardware && s.format.is_fixed() {
            lo = lo.clamp(0.0, 1.0);
            hi = hi.clamp(0.0, 1.0);
            if !self.profile.packed_depth {
                (lo, hi) = s.format.code_range(lo, hi);
            }
        }
        (lo, hi)
    }

    /// How far another implementation's coordinate depth (before any shader bias) may lie
    /// from `depth` at this point: t.z and t.w are each a 4-term f32 dot product of the same
    /// uploaded matrix row with (p, 1), rounded within γ₄·Σ|mᵢ·pᵢ| by either side, so twice
    /// that, then a division (2.5 ULP, GLSL 4.60 §4.7.1, SPIR-V) and our own rounding; the
    /// bias matrix after the divide adds a product and a sum.
    pub(super) fn depth_error(&self, p: Vec3, n: Vec3, face: usize, depth: f32) -> f64 {
        let s = self.shadow;
        let (_, p4, m) = self.lookup_point(p, n, face);
        let row = |r: usize| -> f64 { (0..4).map(|k| (m.col(k)[r] * p4[k]).abs()).sum() };
        let (sz, sw) = (row(2), row(3));
        let wv = (0..4)
            .map(|k| m.col(k)[3] * p4[k])
            .sum::<f64>()
            .abs()
            .max(1e-30);
        let zv = (0..4).map(|k| m.col(k)[2] * p4[k]).sum::<f64>();
        let ratio = zv / wv;
        let mut err = 2.0 * gamma(4.0) * (sz + ratio.abs() * sw) / wv + 3.0 * ulp(ratio);
        if s.bias_matrix == BiasMatrix::AfterDivide {
            // depth = scale·ndc + offset: one more product and sum.
            let scale = match self.conv.clip {
                umbra_case::ClipDepth::MinusOneToOne => 0.5,
                umbra_case::ClipDepth::ZeroToOne => 1.0,
            };
            err = err * scale + 2.0 * ulp(f64::from(depth));
        }
        err
    }
}
