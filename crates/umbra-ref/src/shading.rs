//! The illumination model of docs/catalogue.md §17, shared by every backend's shader.
//!
//! `dimmed`: (ambient + (dimming + (1 − dimming)·shade)·diffuse·C)·albedo + C·shade·specular,
//! diffuse = max(N·L, 0), specular = k·max(N·H, 0)^shininess where N·L > 0 (Blinn-Phong; C the
//! light's colour times its intensity, white by default). `classic`: (ambient + diffuse·C)·
//! albedo·(f + (1 − f)·shade). Colour is linear, clamped to [0,1] and rounded to 8 bits; the
//! background is the case's clear colour (`camera.clear`, black by default), opaque.

use glam::Vec3;
use umbra_case::format::{ColorFormat, Shading, ShadingModel};
use umbra_case::math::powf;

use crate::rounding::unorm8;
use crate::surface::Surfaces;

/// The background colour of `clear` (`camera.clear`) as every backend stores it in a
/// `format` target, rounded to the nearest code (the judge allows either neighbour of a
/// value halfway).
pub fn background(clear: [f32; 3], format: ColorFormat) -> [u8; 4] {
    store(format, Vec3::from(clear))
}

/// A linear colour as a `format` target stores it, opaque: clamped, encoded, rounded to the
/// nearest code ((x.clamp(0, 1)·255).round() as u8 for `rgba8`, without libm's roundf,
/// crate::rounding).
#[inline]
pub fn store(format: ColorFormat, c: Vec3) -> [u8; 4] {
    [
        unorm8(format.encode(c.x)),
        unorm8(format.encode(c.y)),
        unorm8(format.encode(c.z)),
        255,
    ]
}

/// Shaded colour of a surface point, RGBA8 as a `format` target stores it.
#[allow(clippy::too_many_arguments)]
pub fn shade(
    format: ColorFormat,
    s: &Shading,
    light: Vec3,
    albedo: Vec3,
    n: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
    visibility: f32,
) -> [u8; 4] {
    store(
        format,
        shade_linear(s, light, albedo, n, to_light, to_eye, visibility),
    )
}

/// [`shade`] for every pixel of a run of one object (`albedo`): the normals, light and eye
/// vectors from `surfaces`, the visibilities from `vis`, RGBA8 into `out` (4 bytes a pixel).
/// The same operations as [`shade_linear`] in the same order, in passes over the run (the
/// vector parts, then each `powf`, then the colours) so that the compiler vectorises all but
/// the library call.
#[allow(clippy::too_many_arguments)]
pub fn shade_run(
    format: ColorFormat,
    s: &Shading,
    light: Vec3,
    albedo: Vec3,
    surfaces: &Surfaces,
    vis: &[f32],
    out: &mut [u8],
    scratch: &mut Vec<[f32; 3]>,
) {
    let len = vis.len();
    match s.model {
        ShadingModel::Dimmed => {
            // Per pixel: the diffuse term, N·H (NaN where N·L ≤ 0: no specular there).
            scratch.clear();
            scratch.resize(len, [0.0; 3]);
            let [nx, ny, nz] = &surfaces.n;
            let [lx, ly, lz] = &surfaces.to_light;
            let [ex, ey, ez] = &surfaces.to_eye;
            for k in 0..len {
                let n = Vec3::new(nx[k], ny[k], nz[k]);
                let l = Vec3::new(lx[k], ly[k], lz[k]);
                let ndl = n.dot(l);
                let h = (l + Vec3::new(ex[k], ey[k], ez[k])).normalize_or_zero();
                scratch[k] = [ndl, ndl.max(0.0), n.dot(h).max(0.0)];
            }
            for [ndl, _, x] in scratch.iter_mut() {
                *x = if *ndl > 0.0 {
                    s.specular * powf(*x, s.shininess)
                } else {
                    0.0
                };
            }
            for (k, (&[_, diffuse, spec], &v)) in scratch.iter().zip(vis).enumerate() {
                let kept = s.dimming + (1.0 - s.dimming) * v;
                let c = (s.ambient + kept * diffuse * light) * albedo + light * (v * spec);
                out[4 * k..4 * k + 4].copy_from_slice(&store(format, c));
            }
        }
        ShadingModel::Classic => {
            for k in 0..len {
                let c = shade_linear(
                    s,
                    light,
                    albedo,
                    surfaces.normal(k),
                    surfaces.light_dir(k),
                    surfaces.eye_dir(k),
                    vis[k],
                );
                out[4 * k..4 * k + 4].copy_from_slice(&store(format, c));
            }
        }
    }
}

/// The shading before it is clamped and stored: affine in `visibility` for both models,
/// which is what lets the judge bound a colour by the visibility a backend wrote.
pub fn shade_linear(
    s: &Shading,
    light: Vec3,
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
                s.specular * powf(n.dot(h).max(0.0), s.shininess)
            } else {
                0.0
            };
            (s.ambient + kept * diffuse * light) * albedo + light * (visibility * spec)
        }
        ShadingModel::Classic => {
            (s.ambient + diffuse * light)
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
/// - where N·L is within that error of 0 (the terminator), the specular gate (N·L > 0) may
///   fall either way: the whole specular term, on or off (a soak of generated scenes found
///   every driver 5 codes below the model's highlight at a sphere's terminator);
/// - the light's colour times its intensity (C) scales both terms, and their errors, by its
///   largest channel;
/// - every sum and product of the model: 16u of the result (up to 2, or C's largest channel
///   where that is more).
pub fn shade_tolerance(
    s: &Shading,
    light: Vec3,
    albedo: Vec3,
    n: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
    moved: f32,
) -> f32 {
    let u = f32::EPSILON * 0.5;
    let dot_err = 24.0 * u + moved;
    let c = light.max_element().max(0.0);
    let diffuse = albedo.max_element() * dot_err * c;
    let ndl = n.dot(to_light);
    let spec = match s.model {
        ShadingModel::Dimmed if ndl > -dot_err => {
            let h = (to_light + to_eye).normalize_or_zero();
            let x = n.dot(h).max(0.0);
            let e = s.shininess;
            let moves = s.specular
                * (e * powf(x, (e - 1.0).max(0.0)) * dot_err
                    + powf(x, e) * (e * 2f32.powi(-21) + 8.0 * u));
            // The gate itself undecided: the term may be there or not.
            let gate = if ndl.abs() <= dot_err {
                s.specular * powf(x, e)
            } else {
                0.0
            };
            moves + gate
        }
        _ => 0.0,
    };
    diffuse + spec * c + 16.0 * u * 2.0 * c.max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run's colours are [`shade`]'s, pixel by pixel, bit for bit, for both models, lit and
    /// back-facing pixels, visibilities 0, 1 and between, and both colour targets.
    #[test]
    fn a_run_is_shaded_as_its_pixels_are() {
        let mut next = crate::test_rng::uniform(0x853c_49e6_748f_ea9b);
        for model in [ShadingModel::Dimmed, ShadingModel::Classic] {
            for _ in 0..200 {
                let s = Shading {
                    model,
                    ambient: next() * 0.3,
                    dimming: next(),
                    shadowed_factor: next(),
                    specular: next(),
                    shininess: 1.0 + next() * 64.0,
                };
                let albedo = Vec3::new(next(), next(), next());
                // White in a third of the draws, a colour up to 3× in the rest.
                let light = if next() < 0.33 {
                    Vec3::ONE
                } else {
                    Vec3::new(next(), next(), next()) * (3.0 * next())
                };
                let mut run = Surfaces::default();
                let len = 37;
                let mut vis = Vec::new();
                for k in 0..len {
                    let mut dir =
                        || Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or_zero();
                    let (n, l, e) = (dir(), dir(), dir());
                    for a in 0..3 {
                        run.n[a].push(n[a]);
                        run.to_light[a].push(l[a]);
                        run.to_eye[a].push(e[a]);
                        run.p[a].push(0.0);
                    }
                    vis.push([0.0, 1.0, next()][k % 3]);
                }
                let mut out = vec![0u8; 4 * len];
                // Linear in half the draws, sRGB in the rest.
                let format = if next() < 0.5 {
                    ColorFormat::Rgba8
                } else {
                    ColorFormat::Srgb8Alpha8
                };
                shade_run(
                    format,
                    &s,
                    light,
                    albedo,
                    &run,
                    &vis,
                    &mut out,
                    &mut Vec::new(),
                );
                for k in 0..len {
                    let want = shade(
                        format,
                        &s,
                        light,
                        albedo,
                        run.normal(k),
                        run.light_dir(k),
                        run.eye_dir(k),
                        vis[k],
                    );
                    assert_eq!(out[4 * k..4 * k + 4], want, "{model:?} pixel {k}");
                }
            }
        }
    }
}
