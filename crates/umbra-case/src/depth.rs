//! Depth storage per format: quantisation, step size and the polygon-offset unit `r`.
//!
//! Fixed-point formats store k/(2^n − 1), rounded to nearest (the specs prefer rounding and
//! allow ±1 step; the tolerance model in the judge accounts for that, not this module).
//! Stored values are kept as f32, which is exact for D16 and injective and monotone for D24
//! (the D24 spacing 1/(2^24 − 1) is slightly wider than f32's 2^-24 in [0.5, 1)), so a compare
//! in f32 against a stored value orders exactly as a compare of codes would.
//! `Unsized` (`DEPTH_COMPONENT`, the driver picks) is modelled as 24 bits; a backend records
//! what its driver chose.

use crate::format::DepthFormat;

/// `x.round()` (half away from zero) for 0 ≤ x < 2⁵², bit for bit, without the libm call that
/// baseline x86-64 makes for it (SSE2 has no rounding instruction): x − trunc(x) is exact in
/// that range, so the half-way test is exact too; −0 stays −0. Other x go to `round`.
#[inline]
pub fn round_nonneg_f64(x: f64) -> f64 {
    if (0.0..4_503_599_627_370_496.0).contains(&x) {
        let t = x as i64 as f64; // truncation, exact here
        if x - t >= 0.5 { t + 1.0 } else { t.copysign(x) }
    } else {
        x.round()
    }
}

impl DepthFormat {
    /// Bits of a fixed-point format; `None` for float.
    pub fn fixed_bits(self) -> Option<u32> {
        match self {
            DepthFormat::Depth16 => Some(16),
            DepthFormat::Unsized | DepthFormat::Depth24 => Some(24),
            DepthFormat::Depth32f => None,
        }
    }

    /// Whether the format is fixed point (the compare then clamps its reference to [0,1]).
    pub fn is_fixed(self) -> bool {
        self.fixed_bits().is_some()
    }

    /// The value stored for window depth `z` (already clamped to [0,1] by the pass).
    #[inline]
    pub fn store(self, z: f32) -> f32 {
        match self.fixed_bits() {
            Some(n) => {
                let max = f64::from((1u32 << n) - 1);
                let code = round_nonneg_f64(f64::from(z.clamp(0.0, 1.0)) * max);
                (code / max) as f32
            }
            None => z,
        }
    }

    /// One storage step at depth `z`: 1/(2^n − 1) fixed, the f32 spacing at `z` float.
    pub fn step(self, z: f32) -> f64 {
        match self.fixed_bits() {
            Some(n) => 1.0 / f64::from((1u32 << n) - 1),
            None => f64::from(f32_spacing(z)),
        }
    }

    /// The range of the polygon-offset unit r a conformant implementation may use.
    ///
    /// - Fixed point: r is "the smallest difference in window z guaranteed to remain distinct
    ///   in the depth buffer", constant over the range; Vulkan 1.3 "Depth Bias" bounds it by
    ///   r ≤ 2·2⁻ⁿ (the scaling VK_EXT_depth_bias_control's `depthBiasExact` forbids), and GL
    ///   gives no other bound, so umbra holds GL drivers to Vulkan's. Distinctness needs
    ///   r ≥ 2⁻ⁿ (a smaller r can map two offset depths to one code). So r ∈ [2⁻ⁿ, 2·2⁻ⁿ].
    /// - Float: r = 2^(e − 23), e the exponent of the primitive's largest |z| (GL 4.6
    ///   §14.6.5, Vulkan "Depth Bias"): fixed, no freedom. (Which exponent "e" means for
    ///   z ∈ [2ᵉ, 2ᵉ⁺¹) is read as floor(log₂|z|), as GL drivers do; Dawn records that the
    ///   WebGPU CTS reads e + 1, dawn:2076.)
    /// - Unsized (`DEPTH_COMPONENT`): the GL stores it "with internal component resolutions
    ///   of its own choosing" (GL 4.6 §8.5), so r is that choice's: 24-bit fixed point as
    ///   umbra models the storage, or 32-bit (llvmpipe and softpipe pick Z32_UNORM for an
    ///   UNSIGNED_INT upload, a Vulkan driver D32F: a soak found llvmpipe storing no visible
    ///   units offset on an unsized map): from the float or 2⁻³² unit up to 2·2⁻²⁴. The set
    ///   {24, 32} is an observation, not a spec clause: the GL backend probes the driver's
    ///   choice (GL_TEXTURE_DEPTH_SIZE, `umbra_gl::caps::Caps::unsized_depth_bits`) and a
    ///   driver choosing another resolution skips the unsized points instead of failing.
    pub fn offset_unit_range(self, max_abs_z: f32) -> (f64, f64) {
        if self == DepthFormat::Unsized {
            let float = f64::from(DepthFormat::Depth32f.offset_unit(max_abs_z));
            return (float.min(2f64.powi(-32)), 2.0 * 2f64.powi(-24));
        }
        match self.fixed_bits() {
            Some(n) => {
                let r = 2f64.powi(-(n as i32));
                (r, 2.0 * r)
            }
            None => {
                let r = f64::from(self.offset_unit(max_abs_z));
                (r, r)
            }
        }
    }

    /// The stored codes an implementation may write for exact depths in `[lo, hi]` (already
    /// clamped to [0,1]), as values: fixed point may round either way (round to nearest is
    /// preferred, not required: Vulkan "Conversion from Floating-Point to Normalized
    /// Fixed-Point"), so [floor(lo·M)/M, ceil(hi·M)/M] with M = 2ⁿ − 1; float stores the
    /// value itself.
    pub fn code_range(self, lo: f64, hi: f64) -> (f64, f64) {
        match self.fixed_bits() {
            Some(n) => {
                let m = f64::from((1u32 << n) - 1);
                (
                    (lo.clamp(0.0, 1.0) * m).floor() / m,
                    (hi.clamp(0.0, 1.0) * m).ceil() / m,
                )
            }
            None => (lo, hi),
        }
    }

    /// [`DepthFormat::code_range`] for an implementation whose rounding a card read: the
    /// stored code of x codes is ⌊x + t⌋ with t in the reading's range
    /// ([`crate::calibration::Rounding::t_range`]); without one, either neighbouring code.
    pub fn code_range_rounded(
        self,
        lo: f64,
        hi: f64,
        rounding: Option<crate::calibration::Rounding>,
    ) -> (f64, f64) {
        let (Some(n), Some(r)) = (self.fixed_bits(), rounding) else {
            return self.code_range(lo, hi);
        };
        let m = f64::from((1u32 << n) - 1);
        let (t_lo, t_hi) = r.t_range();
        let (lo, hi) = (lo.clamp(0.0, 1.0) * m, hi.clamp(0.0, 1.0) * m);
        (
            (lo + t_lo).floor().min(m) / m,
            (hi + t_hi).floor().min(hi.ceil()) / m,
        )
    }

    /// The polygon-offset unit r umbra's reference uses: 1/(2ⁿ − 1) for fixed point (one
    /// code step; the GLES 2 path's shader uses the same); 2^(e − 23) for float, e the
    /// exponent of the primitive's largest |z|.
    pub fn offset_unit(self, max_abs_z: f32) -> f32 {
        match self.fixed_bits() {
            Some(n) => (1.0 / f64::from((1u32 << n) - 1)) as f32,
            None => {
                if max_abs_z == 0.0 {
                    return f32::MIN_POSITIVE;
                }
                let e = crate::math::log2f(max_abs_z.abs()).floor() as i32;
                2f32.powi(e - 23)
            }
        }
    }

    /// Name as in the case format.
    pub fn name(self) -> &'static str {
        match self {
            DepthFormat::Unsized => "unsized",
            DepthFormat::Depth16 => "depth16",
            DepthFormat::Depth24 => "depth24",
            DepthFormat::Depth32f => "depth32f",
        }
    }
}

/// Distance from `z` to the next larger f32.
pub fn f32_spacing(z: f32) -> f32 {
    let a = z.abs();
    f32::from_bits(a.to_bits() + 1) - a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_rounding_is_libms() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut values: Vec<f64> = (0..1_000_000)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                f64::from(f32::from_bits(state as u32 & 0x7fff_ffff)) // every f32 ≥ 0
            })
            .collect();
        for k in 0..2000 {
            let h = f64::from(k) * 0.5;
            values.extend([h, h.next_up(), h.next_down(), -0.0, f64::NAN, f64::INFINITY]);
        }
        values.extend([4_503_599_627_370_495.5, 4_503_599_627_370_496.0, 1e300]);
        for x in values {
            for y in [x, x * 65_535.0, x * 16_777_215.0] {
                assert_eq!(round_nonneg_f64(y).to_bits(), y.round().to_bits(), "{y:e}");
            }
        }
    }

    #[test]
    fn fixed_point_stores_are_exact_codes_and_monotone() {
        let f = DepthFormat::Depth24;
        let max = (1u32 << 24) - 1;
        for range in [0..5000, max - 5000..max + 1] {
            let mut last = -1.0f32;
            for k in range {
                let z = (f64::from(k) / f64::from(max)) as f32;
                let s = f.store(z);
                assert_eq!((f64::from(s) * f64::from(max)).round() as u32, k);
                assert!(s > last, "not monotone at code {k}");
                last = s;
            }
        }
        assert_eq!(
            DepthFormat::Depth16.store(0.5),
            (32768.0f64 / 65535.0) as f32
        );
        assert_eq!(DepthFormat::Depth16.store(2.0), 1.0);
    }

    #[test]
    fn offset_unit_follows_the_spec() {
        assert_eq!(
            DepthFormat::Depth16.offset_unit(0.3),
            (1.0f64 / 65535.0) as f32
        );
        assert_eq!(DepthFormat::Depth32f.offset_unit(0.75), 2f32.powi(-24));
        assert_eq!(DepthFormat::Depth32f.offset_unit(0.2), 2f32.powi(-26));
        assert_eq!(
            DepthFormat::Depth16.offset_unit_range(0.3),
            (2f64.powi(-16), 2f64.powi(-15))
        );
        let r = f64::from(DepthFormat::Depth32f.offset_unit(0.75));
        assert_eq!(DepthFormat::Depth32f.offset_unit_range(0.75), (r, r));
        // The driver's choice: 24 bits or 32, fixed or float.
        assert_eq!(
            DepthFormat::Unsized.offset_unit_range(0.75),
            (2f64.powi(-32), 2f64.powi(-23))
        );
    }

    #[test]
    fn a_read_rounding_narrows_the_codes() {
        use crate::calibration::Rounding;
        let m = 65535.0;
        let f = DepthFormat::Depth16;
        let at = |x: f64, r| f.code_range_rounded(x / m, x / m, Some(r));
        assert_eq!(at(100.4, Rounding::Nearest), (100.0 / m, 101.0 / m));
        assert_eq!(at(100.1, Rounding::Nearest), (100.0 / m, 100.0 / m));
        assert_eq!(at(100.9, Rounding::Nearest), (101.0 / m, 101.0 / m));
        assert_eq!(at(100.6, Rounding::Truncate), (100.0 / m, 100.0 / m));
        assert_eq!(at(100.3, Rounding::Up), (101.0 / m, 101.0 / m));
        assert_eq!(at(100.0, Rounding::Up), (100.0 / m, 100.0 / m));
        assert_eq!(f.code_range_rounded(0.1, 0.2, None), f.code_range(0.1, 0.2));
        assert_eq!(
            DepthFormat::Depth32f.code_range_rounded(0.1, 0.2, Some(Rounding::Up)),
            (0.1, 0.2)
        );
    }

    #[test]
    fn code_ranges_cover_both_roundings() {
        let m = 65535.0;
        let (lo, hi) = DepthFormat::Depth16.code_range(100.4 / m, 100.6 / m);
        assert_eq!((lo * m, hi * m), (100.0, 101.0));
        // An exact code has one legal code; the clear value too.
        let (lo, hi) = DepthFormat::Depth16.code_range(1.0, 1.0);
        assert_eq!((lo, hi), (1.0, 1.0));
        assert_eq!(DepthFormat::Depth32f.code_range(0.25, 0.5), (0.25, 0.5));
    }
}
