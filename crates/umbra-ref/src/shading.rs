//! The illumination model of EDGE_CASES.md 17, shared by every backend's shader.
//!
//! `dimmed`: (ambient + (dimming + (1 − dimming)·shade)·diffuse)·albedo + shade·specular,
//! diffuse = max(N·L, 0), specular = k·max(N·H, 0)^shininess where N·L > 0 (Blinn-Phong, white
//! light). `classic`: (ambient + diffuse)·albedo·(f + (1 − f)·shade). Colour is linear, clamped
//! to [0,1] and rounded to 8 bits; the background is opaque black.

use glam::Vec3;
use umbra_case::format::{Shading, ShadingModel};

use crate::rounding::unorm8;

/// Background colour of every backend.
pub const BACKGROUND: [u8; 4] = [0, 0, 0, 255];

/// Shaded colour of a surface point, RGBA8.
pub fn shade(
    s: &Shading,
    albedo: Vec3,
    n: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
    visibility: f32,
) -> [u8; 4] {
    let c = shade_linear(s, albedo, n, to_light, to_eye, visibility);
    // (x.clamp(0, 1)·255).round() as u8, without libm's roundf (crate::rounding).
    [unorm8(c.x), unorm8(c.y), unorm8(c.z), 255]
}

/// The shading before it is clamped and stored: affine in `visibility` for both models,
/// which is what lets the judge bound a colour by the visibility a backend wrote.
pub fn shade_linear(
    s: &Shading,
    albedo: Vec3,
    n: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
    visibility: f32,
) -> Vec3 {
    let ndl = n.dot(to_light);
    let diffuse = ndl.max(0.0);
    match s.model {
        ShadingModel::Dimmed => {
            let kept = s.dimming + (1.0 - s.dimming) * visibility;
            let spec = if ndl > 0.0 {
                let h = (to_light + to_eye).normalize_or_zero();
                s.specular * n.dot(h).max(0.0).powf(s.shininess)
            } else {
                0.0
            };
            (s.ambient + kept * diffuse) * albedo + Vec3::splat(visibility * spec)
        }
        ShadingModel::Classic => {
            (s.ambient + diffuse)
                * albedo
                * (s.shadowed_factor + (1.0 - s.shadowed_factor) * visibility)
        }
    }
}

/// How far another implementation's unclamped colour may lie from ours, per channel, from
/// the arithmetic the specs leave open (GLSL 4.60 §4.7.1, SPIR-V's precision table; derivation
/// beside each term):
/// - N·L and N·H: the interpolated normal (≈ 8u relative) and its normalisation (inversesqrt
///   2 ULP and a product), the light and half vectors (4u each, plus `moved`, the position
///   freedom over the light's and the eye's distance), the dot product (3u): `dot_err`;
/// - the diffuse term moves by albedo·`dot_err`; the specular term k·x^e by k·e·x^(e−1)·
///   `dot_err` plus pow's own error (exp2(e·log2 x): log2 within 2⁻²¹ absolute near 1, so
///   e·2⁻²¹ relative, and exp2's few ULP);
/// - every sum and product of the model: 16u of the result.
pub fn shade_tolerance(
    s: &Shading,
    albedo: Vec3,
    n: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
    moved: f32,
) -> f32 {
    let u = f32::EPSILON * 0.5;
    let dot_err = 24.0 * u + moved;
    let diffuse = albedo.max_element() * dot_err;
    let spec = match s.model {
        ShadingModel::Dimmed if n.dot(to_light) > 0.0 => {
            let h = (to_light + to_eye).normalize_or_zero();
            let x = n.dot(h).max(0.0);
            let e = s.shininess;
            s.specular
                * (e * x.powf((e - 1.0).max(0.0)) * dot_err
                    + x.powf(e) * (e * 2f32.powi(-21) + 8.0 * u))
        }
        _ => 0.0,
    };
    diffuse + spec + 16.0 * u * 2.0
}
