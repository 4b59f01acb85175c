//! The transcendental functions umbra's numbers go through, the same bit for bit on every C
//! library.
//!
//! Rust's `f32::tan`, `f64::sin`, `powf`, `log2`, `hypot` … call the C library's libm, and
//! C libraries differ in their last bits: glibc 2.41 replaced `tanf` and other float
//! functions with correctly rounded ones, so the same umbra binary computed another camera
//! projection on Debian sid's glibc 2.43 (where a build with its own C library runs its
//! workers, `harness::own_libc`) than on Debian 12's 2.36. On `packed-cubes@azimuth 90`,
//! whose cubes touch exactly, that moved the truth by 469 pixels (2727 → 2258 px of false
//! shadow with the same frame), and every matrix a backend uploads moved with it, so a
//! driver comparison across releases would have charged the C library's change to the driver.
//!
//! Every such function the case, the reference, the truth and the judge use comes from here:
//! the `libm` crate, a pure-Rust port of musl's libm, compiled into umbra (glam uses it too,
//! through its `libm` feature). `tests/deterministic_math.rs` holds these crates to it.

/// sin, f64.
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// cos, f64.
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// tan, f64.
pub fn tan(x: f64) -> f64 {
    libm::tan(x)
}

/// tan, f32.
pub fn tanf(x: f32) -> f32 {
    libm::tanf(x)
}

/// xʸ, f32.
pub fn powf(x: f32, y: f32) -> f32 {
    libm::powf(x, y)
}

/// xʸ, f64.
pub fn pow(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// log₂, f32.
pub fn log2f(x: f32) -> f32 {
    libm::log2f(x)
}

/// log₂, f64.
pub fn log2(x: f64) -> f64 {
    libm::log2(x)
}

/// log₁₀, f64.
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}

/// Natural logarithm, f64.
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// eˣ, f64.
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// √(x² + y²) without undue overflow, f64.
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// √(x² + y²) without undue overflow, f32.
pub fn hypotf(x: f32, y: f32) -> f32 {
    libm::hypotf(x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_functions_are_musl_s_and_exact_where_it_is() {
        assert_eq!(sin(0.0), 0.0);
        assert_eq!(cos(0.0), 1.0);
        assert_eq!(pow(10.0, 2.0), 100.0);
        assert_eq!(log2(8.0), 3.0);
        assert_eq!(log2f(0.25), -2.0);
        assert_eq!(hypotf(3.0, 4.0), 5.0);
        // The camera's tan(fov/2) for a 60° field of view: musl's tanf, whatever the libc.
        assert_eq!(
            tanf(30f32.to_radians()).to_bits(),
            libm::tanf(30f32.to_radians()).to_bits()
        );
    }
}
