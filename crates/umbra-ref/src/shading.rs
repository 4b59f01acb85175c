//! The illumination model of EDGE_CASES.md 17, shared by every backend's shader.
//!
//! `dimmed`: (ambient + (dimming + (1 − dimming)·shade)·diffuse)·albedo + shade·specular,
//! diffuse = max(N·L, 0), specular = k·max(N·H, 0)^shininess where N·L > 0 (Blinn-Phong, white
//! light). `classic`: (ambient + diffuse)·albedo·(f + (1 − f)·shade). Colour is linear, clamped
//! to [0,1] and rounded to 8 bits; the background is opaque black.

use glam::Vec3;
use umbra_case::format::{Shading, ShadingModel};

/// Background colour of every backend.
pub const BACKGROUND: [u8; 4] = [0, 0, 0, 255];

/// Shaded colour of a surface point.
pub fn shade(
    s: &Shading,
    albedo: Vec3,
    n: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
    visibility: f32,
) -> [u8; 4] {
    let ndl = n.dot(to_light);
    let diffuse = ndl.max(0.0);
    let c = match s.model {
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
    };
    let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    [q(c.x), q(c.y), q(c.z), 255]
}
