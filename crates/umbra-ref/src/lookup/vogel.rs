//! three.js's PCF filter (`Filter::Vogel5`): five LINEAR compares on a Vogel disk of one
//! texel along each axis (r187's `vec2 radius = shadowRadius * texelSize`), rotated per pixel by interleaved gradient noise of the pixel's window position,
//! as r187's `shadowmap_pars_fragment` writes it (`getShadow`, `vogelDiskSample`,
//! `interleavedGradientNoise`).
//!
//! Why the window position reaches the lookup through this thread: it is the only input of
//! any filter that is not a function of the surface point, and every other caller of the
//! lookup (the judged region, the mip levels, the settled pixels, `--explain`) passes only
//! the point. The lit pass sets it for the pixel it is shading ([`at_window`]); a lookup
//! with none set (a unit test's, say) reads φ = 0 for its value and allows every rotation
//! in its judged interval, so the value still lies inside the interval.
//!
//! The judged interval, per tap: the rotation φ is known to the noise's own f32 arithmetic
//! (two fract steps; where the inner fract's argument is within its error of a whole
//! number, both branches are taken, each an arc of angles, the outer fract's jump a whole
//! turn and so no jump at all); tap k's angle spans k · 2.3999632 + that arc, and its
//! offset moves by at most its radius times the arc (a chord is never longer than its arc)
//! plus the radius times 2⁻¹¹ for each of sin and cos. 2⁻¹¹ is Vulkan's absolute bound for
//! sin and cos on [−π, π] (the SPIR-V environment's precision table); beyond [−π, π]
//! neither GL, GLSL ES nor Vulkan bound them, and tap k's angle reaches 4 · 2.4 + 2π. umbra
//! holds drivers to 2⁻¹¹ there too: every Mesa driver reduces the argument first (a
//! driver that does not would show as this filter's failures alone, and be recorded as an
//! expectation). Each tap is then a LINEAR compare at a coordinate that uncertain, judged as
//! [`Lookup::linear_hardware`] (or the shader's, under a manual compare) judges one, and
//! the five are summed and scaled by 0.2 with the sums' roundings on top.

use std::cell::Cell;
use std::f64::consts::TAU;

use super::addressing::Addressing;
use super::*;

thread_local! {
    /// The window position of the pixel this thread is shading (see the module notes).
    static WINDOW: Cell<Option<[f32; 2]>> = const { Cell::new(None) };
}

/// Runs `f` with this thread's lookups at the pixel whose window position is `window`
/// (GL's gl_FragCoord.xy: the pixel's centre, y up from the frame's bottom row).
pub fn at_window<T>(window: [f32; 2], f: impl FnOnce() -> T) -> T {
    let before = WINDOW.with(|w| w.replace(Some(window)));
    let out = f();
    WINDOW.with(|w| w.set(before));
    out
}

/// GL's window position of raster pixel (x, y) of a frame `height` pixels high, its row y
/// counted down from the top row where the raster's rows run down (`rows_down`, the zero-to-one
/// convention's window) and up from the bottom row where they run up (GL's).
pub fn window_of(x: u32, y: u32, height: u32, rows_down: bool) -> [f32; 2] {
    let row = if rows_down { height - 1 - y } else { y };
    [x as f32 + 0.5, row as f32 + 0.5]
}

/// The golden angle three.js's `vogelDiskSample` turns each tap by.
const GOLDEN_ANGLE: f32 = 2.399_963_2;
/// The noise's weights and scale (`interleavedGradientNoise`: 0.06711056, 0.00583715 and
/// 52.9829189, the last the f32 written here).
const NOISE: [f32; 3] = [0.067_110_56, 0.005_837_15, 52.982_918];
/// Taps.
const TAPS: u32 = 5;
/// Vulkan's absolute error bound for sin and cos (see the module notes).
const TRIG: f64 = 1.0 / 2048.0;

/// The disk's rotation φ at `window`, in f32 as the shader computes it.
pub fn vogel_rotation(window: [f32; 2]) -> f32 {
    let t = window[0] * NOISE[0] + window[1] * NOISE[1];
    let f = t - crate::rounding::floor_f32(t);
    let t = NOISE[2] * f;
    (t - crate::rounding::floor_f32(t)) * std::f32::consts::TAU
}

/// The five taps' offsets from the lookup point in texels, in f32 as the shader computes
/// them (`vec2(cos θ, sin θ) * r`, before `* radius`, one texel along each axis), at
/// rotation `phi`.
pub fn vogel_taps(phi: f32) -> [[f32; 2]; 5] {
    std::array::from_fn(|k| {
        let r = ((k as f32 + 0.5) / TAPS as f32).sqrt();
        // The angle in f32 as the shader adds it; its cosine and sine correctly rounded
        // (umbra_case::math, the same on every machine).
        let theta = f64::from(k as f32 * GOLDEN_ANGLE + phi);
        [
            umbra_case::math::cos(theta) as f32 * r,
            umbra_case::math::sin(theta) as f32 * r,
        ]
    })
}

/// The window position this thread's lookup is at, if the lit pass set one.
fn window() -> Option<[f32; 2]> {
    WINDOW.with(Cell::get)
}

/// The arcs of rotations the shader may compute at `window` (one, or two where the inner
/// fract's argument is within its error of a whole number), each as (start, end) in
/// radians, end ≥ start; every rotation when no window is known.
fn rotations(window: Option<[f32; 2]>) -> Vec<(f64, f64)> {
    let Some([x, y]) = window else {
        return vec![(0.0, TAU)];
    };
    let [a, b, k] = NOISE.map(f64::from);
    let t = f64::from(x) * a + f64::from(y) * b;
    // The dot product's roundings, fused or not (γ₂ of its terms), and the subtraction of
    // its floor (exact); then the product by k and its floor, and the product by 2π.
    let e = 4.0 * U * (f64::from(x) * a + f64::from(y) * b) + ulp(t);
    let whole = t.floor();
    let branches = if t - e < whole {
        vec![(0.0, t + e - whole), (t - e - (whole - 1.0), 1.0)]
    } else if t + e >= whole + 1.0 {
        vec![(t - e - whole, 1.0), (0.0, t + e - (whole + 1.0))]
    } else {
        vec![(t - e - whole, t + e - whole)]
    };
    branches
        .into_iter()
        .map(|(lo, hi)| {
            let (lo, hi) = (lo.max(0.0) * k, hi.min(1.0) * k);
            let (lo, hi) = (lo - 2.0 * ulp(lo) - ulp(k), hi + 2.0 * ulp(hi) + ulp(k));
            // An angle: a whole turn is no turn, so the outer fract's jump is none.
            let turns = lo.floor();
            let (lo, hi) = ((lo - turns) * TAU, (hi - turns) * TAU);
            (lo - 8.0 * U * TAU, hi + 8.0 * U * TAU)
        })
        .collect()
}

impl Lookup<'_> {
    /// Which way three.js's +y offset runs along this convention's texture v: with v (GL's
    /// texture coordinate, the light's up), or against it where v runs down the rows (the
    /// zero-to-one convention's bias matrix, [`Convention::bias_matrix`]); the shaders add
    /// it to GL's v in both languages.
    fn v_up(&self) -> f32 {
        if self.conv.window_y_down() { -1.0 } else { 1.0 }
    }

    /// The Vogel disk's value at `st` (the reference's, in f32): `bilinear` is the
    /// reference's LINEAR compare at a coordinate.
    pub(super) fn vogel_value(&self, st: &Setup, bilinear: impl Fn(f32, f32) -> f32) -> f32 {
        let phi = window().map_or(0.0, vogel_rotation);
        let [w, h] = self.shadow.size;
        // `shadowRadius * texelSize`, a vec2 since r187.
        let radius = [1.0 * (1.0 / w as f32), 1.0 * (1.0 / h as f32)];
        let up = self.v_up();
        let mut sum = 0.0;
        for [ox, oy] in vogel_taps(phi) {
            sum += bilinear(st.c.u + ox * radius[0], st.c.v + up * (oy * radius[1]));
        }
        sum * 0.2
    }

    /// The Vogel disk's legal interval at `st` (see the module notes): `r` the reference
    /// value's interval, `err` the coordinate's own uncertainty in texels.
    pub(super) fn vogel(
        &self,
        st: &Setup,
        r: (f64, f64),
        err: (f64, f64),
        addressing: Addressing,
    ) -> Legal {
        let [w, h] = self.shadow.size;
        let (fw, fh) = (f64::from(w), f64::from(h));
        let (x, y) = (f64::from(st.c.u) * fw, f64::from(st.c.v) * fh);
        let up = f64::from(self.v_up());
        let mut out: Option<Legal> = None;
        for (a, b) in rotations(window()) {
            let (mut lo, mut hi, mut flags) = (0.0, 0.0, 0);
            for k in 0..TAPS {
                let rk = ((f64::from(k) + 0.5) / f64::from(TAPS)).sqrt();
                let base = f64::from(k) * f64::from(GOLDEN_ANGLE);
                let mid = base + 0.5 * (a + b);
                // Half the arc's chord bound, sin's and cos's error, and the angle's sum.
                let move_by = rk * (0.5 * (b - a) + TRIG + 4.0 * U * (base + b));
                let (ox, oy) = (
                    rk * umbra_case::math::cos(mid),
                    rk * umbra_case::math::sin(mid),
                );
                // The sampler's coordinate (the first texel's centre at 0), and how far it
                // may be: the point's own error, the tap's move, and the roundings of the
                // offset's product by the radius, of its sum with c and of the sampler's
                // product by the size (each within an ulp of the coordinate in texels).
                let (tx, ty) = (x + ox - 0.5, y + up * oy - 0.5);
                let (ex, ey) = (
                    err.0 + move_by + 4.0 * ulp(x.abs() + 2.0),
                    err.1 + move_by + 4.0 * ulp(y.abs() + 2.0),
                );
                let t = self.linear_compare(st.face, (tx, ty), (ex, ey), r, addressing);
                lo += f64::from(t.lo);
                hi += f64::from(t.hi);
                flags |= t.flags;
            }
            let l = legal(0.2 * lo - 8.0 * U, 0.2 * hi + 8.0 * U, flags);
            out = Some(out.map_or(l, |o| o.hull(l)));
        }
        out.unwrap_or(Legal::LIT)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rotation_lies_in_its_judged_arcs_and_the_taps_on_the_disk() {
        for (x, y) in [(0u32, 0u32), (17, 3), (239, 159), (100, 71), (5, 150)] {
            let w = window_of(x, y, 160, true);
            let phi = f64::from(vogel_rotation(w));
            let arcs = rotations(Some(w));
            assert!(
                arcs.iter().any(|&(a, b)| {
                    let turns = ((phi - a) / TAU).floor();
                    let p = phi - turns * TAU;
                    (a..=b).contains(&p)
                }),
                "{phi} outside {arcs:?} at {w:?}"
            );
            for (k, [ox, oy]) in vogel_taps(phi as f32).into_iter().enumerate() {
                let r = ((k as f32 + 0.5) / 5.0).sqrt();
                assert!(((ox * ox + oy * oy).sqrt() - r).abs() < 1e-5);
            }
        }
        // Row 0 of a 160-row frame is GL's y = 159.5 where rows run down, 0.5 where they run
        // up (GL's own raster).
        assert_eq!(window_of(0, 0, 160, true), [0.5, 159.5]);
        assert_eq!(window_of(3, 159, 160, true), [3.5, 0.5]);
        assert_eq!(window_of(3, 0, 160, false), [3.5, 0.5]);
        assert_eq!(rotations(None), vec![(0.0, TAU)]);
    }
}
