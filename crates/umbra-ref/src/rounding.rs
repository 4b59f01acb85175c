//! Integer forms of the roundings the reference does per pixel (the lookup's texel index,
//! the 8-bit colour), bit for bit what `floor` and `round` return, without the libm calls that
//! baseline x86-64 makes for them (SSE2 has no rounding instruction). The reference is bound
//! by the number of instructions it executes, and each call was a dozen or two. The depth
//! store's `round` is `umbra_case::depth::round_nonneg_f64` (umbra-case stores depth codes).

/// `x.floor()`, bit for bit (−0 included), without a libm call for |x| < 2²³ (where every
/// f32 with a fraction lies).
#[inline]
pub fn floor_f32(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32; // truncation, exact here
        // floor(x) has x's sign: 0 only for x in [0, 1) or −0, ≤ −1 for x < 0.
        (if t > x { t - 1.0 } else { t }).copysign(x)
    } else {
        x.floor()
    }
}

/// `x.floor() as i64`, bit for bit (the saturating cast included): the integer itself for
/// |x| < 2²³ (no sign of zero to keep, no saturation to check).
#[inline]
pub fn floor_i64(x: f32) -> i64 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32; // truncation, exact here
        i64::from(if t as f32 > x { t - 1 } else { t })
    } else {
        x.floor() as i64
    }
}

/// `x.round()` (half away from zero), bit for bit (−0 and NaN included), without a libm call
/// for |x| < 2²³ (beyond, every f32 is an integer).
#[inline]
pub fn round_f32(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32; // truncation, exact here
        let r = if (x - t).abs() >= 0.5 {
            t + 1.0f32.copysign(x)
        } else {
            t
        };
        r.copysign(x)
    } else {
        x.round()
    }
}

/// `(x.clamp(0.0, 1.0) * 255.0).round() as u8`, bit for bit (NaN gives 0, as the cast does).
#[inline]
pub fn unorm8(x: f32) -> u8 {
    let y = x.clamp(0.0, 1.0) * 255.0;
    if y.is_nan() {
        return 0;
    }
    let t = y as i32; // 0..=255, truncation (a signed conversion is one instruction)
    (t + i32::from(y - t as f32 >= 0.5)) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic spread of f32 bit patterns: every exponent, edge mantissas, and a
    /// walk through the rest (plus the values the helpers' thresholds sit on).
    fn samples() -> Vec<f32> {
        let mut v = Vec::new();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..2_000_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            v.push(f32::from_bits(state as u32));
        }
        for e in 0..255u32 {
            for m in [0u32, 1, 0x3f_ffff, 0x40_0000, 0x40_0001, 0x7f_ffff] {
                for s in [0u32, 1 << 31] {
                    v.push(f32::from_bits(s | e << 23 | m));
                }
            }
        }
        for k in -600..600 {
            let x = k as f32 * 0.5;
            v.extend([x, x.next_up(), x.next_down()]);
        }
        v.extend([
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            8_388_608.0,
            -8_388_608.0,
        ]);
        v
    }

    #[test]
    fn floor_matches_libm() {
        for x in samples() {
            assert_eq!(floor_f32(x).to_bits(), x.floor().to_bits(), "{x:e}");
            assert_eq!(floor_i64(x), x.floor() as i64, "{x:e}");
        }
    }

    #[test]
    fn round_matches_libm() {
        for x in samples() {
            assert_eq!(round_f32(x).to_bits(), x.round().to_bits(), "{x:e}");
        }
    }

    #[test]
    fn unorm8_matches_libm() {
        for x in samples() {
            for y in [x, x / 255.0] {
                let want = (y.clamp(0.0, 1.0) * 255.0).round() as u8;
                assert_eq!(unorm8(y), want, "{y:e}");
            }
        }
    }
}
