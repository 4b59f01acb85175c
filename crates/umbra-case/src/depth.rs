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
    pub fn store(self, z: f32) -> f32 {
        match self.fixed_bits() {
            Some(n) => {
                let max = f64::from((1u32 << n) - 1);
                let code = (f64::from(z.clamp(0.0, 1.0)) * max).round();
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

    /// The polygon-offset unit r (NUMERICS.md, "Polygon offset"): one step for fixed point;
    /// 2^(e − 23) for float, e the exponent of the primitive's largest |z|.
    pub fn offset_unit(self, max_abs_z: f32) -> f32 {
        match self.fixed_bits() {
            Some(n) => (1.0 / f64::from((1u32 << n) - 1)) as f32,
            None => {
                if max_abs_z == 0.0 {
                    return f32::MIN_POSITIVE;
                }
                let e = max_abs_z.abs().log2().floor() as i32;
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
    }
}
