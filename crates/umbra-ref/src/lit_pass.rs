//! The lit (camera) pass: rasterize with a 32-bit float depth buffer (LESS, no culling), keep
//! the nearest fragment per pixel, then shade each pixel once. Deferring the shading changes
//! nothing a GPU would show (the lookup does not affect depth) and looks up each pixel once.
//! Varyings (world position, normal) interpolate perspective-correctly and are evaluated in
//! f32, as a GPU's would be.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use umbra_case::format::Cull;
use umbra_case::{Convention, Geometry, Prepared};

use crate::bands::for_each_band;
use crate::lookup::Lookup;
use crate::raster::Rasterizer;
use crate::shading::{BACKGROUND, shade};
use crate::shadow_pass::setup_all;

const NONE: u32 = u32::MAX;

#[derive(Clone, Copy)]
struct Nearest {
    depth: f32,
    tri: u32,
    weights: DVec3,
}

/// Per pixel, raster row order: colour, visibility (NaN = background), face + 1.
pub struct LitImage {
    /// RGBA8.
    pub color: Vec<u8>,
    /// Shadow term.
    pub visibility: Vec<f32>,
    /// Face id + 1, 0 for background.
    pub surface: Vec<u32>,
    /// [`crate::lookup::ambiguity`] flags per pixel (all 0 unless judged).
    pub ambiguity: Vec<u8>,
}

/// Renders the camera view of `run`, looking shadows up with `lookup`; with `judge`, also
/// records why each lookup's answer could legally differ.
pub fn render(run: &Prepared, conv: Convention, lookup: &Lookup, judge: bool) -> LitImage {
    let [w, h] = run.camera.size;
    let geo: &Geometry = &run.geometry;
    let raster = Rasterizer {
        conv,
        width: w,
        height: h,
        cull: Cull::None,
    };
    let tris = setup_all(&raster, run.camera.view_proj(conv), geo);
    let mut nearest = vec![
        Nearest {
            depth: 1.0,
            tri: NONE,
            weights: DVec3::ZERO
        };
        (w * h) as usize
    ];
    for_each_band(
        &mut nearest,
        w as usize,
        1,
        &tris,
        |rows, band, touching| {
            for t in touching {
                t.scan(rows.clone(), |x, y, frag| {
                    let z = t.depth(frag).clamp(0.0, 1.0);
                    let i = (y - rows.start) as usize * w as usize + x as usize;
                    if z < band[i].depth {
                        band[i] = Nearest {
                            depth: z,
                            tri: t.source,
                            weights: t.source_weights(frag),
                        };
                    }
                });
            }
        },
    );
    let case = run.case();
    let eye = run.camera.eye;
    let pixels: Vec<([u8; 4], f32, u32, u8)> = nearest
        .par_iter()
        .map(|px| {
            if px.tri == NONE {
                return (BACKGROUND, f32::NAN, 0, 0);
            }
            let t = px.tri as usize;
            let idx = geo.triangles[t].map(|k| k as usize);
            let wt = px.weights.as_vec3();
            let p = geo.positions[idx[0]] * wt.x
                + geo.positions[idx[1]] * wt.y
                + geo.positions[idx[2]] * wt.z;
            let n = (geo.normals[idx[0]] * wt.x
                + geo.normals[idx[1]] * wt.y
                + geo.normals[idx[2]] * wt.z)
                .normalize_or_zero();
            let (vis, flags) = if judge {
                lookup.visibility_judged(p, n)
            } else {
                (lookup.visibility(p, n), 0)
            };
            let albedo: Vec3 = geo.albedo[geo.object[t] as usize];
            let color = shade(
                &case.shading,
                albedo,
                n,
                run.light.to_light(p),
                (eye - p).normalize_or_zero(),
                vis,
            );
            (color, vis, geo.face[t] + 1, flags)
        })
        .collect();
    let n = pixels.len();
    let mut out = LitImage {
        color: Vec::with_capacity(n * 4),
        visibility: Vec::with_capacity(n),
        surface: Vec::with_capacity(n),
        ambiguity: Vec::with_capacity(n),
    };
    for (c, v, s, a) in pixels {
        out.color.extend_from_slice(&c);
        out.visibility.push(v);
        out.surface.push(s);
        out.ambiguity.push(a);
    }
    out
}
