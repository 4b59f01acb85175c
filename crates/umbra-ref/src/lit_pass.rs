//! The lit (camera) pass: rasterize with a 32-bit float depth buffer (LESS, no culling), keep
//! the nearest fragment per pixel, then shade each pixel once. Deferring the shading changes
//! nothing a GPU would show (the lookup does not affect depth) and looks up each pixel once.
//! Varyings (world position, normal) interpolate perspective-correctly and are evaluated in
//! f32, as a GPU's would be. Pixels are shaded a run at a time (the pixels of a row that one
//! triangle won): [`crate::surface`], the run's lookups and its colours, each a loop over
//! independent pixels with the per-pixel arithmetic unchanged (a test holds the frame to the
//! judged render's, which looks every pixel up on its own).
//!
//! A judged render also marks the pixels where another conformant implementation may show
//! another surface ([`crate::lookup::ambiguity::SURFACE`]): within the vertex snapping's
//! reach ([`crate::raster::Tri::reach`]) of an open edge of what covers it, of an edge it
//! shares with another face, or of a surface that may cover it and is nearer or tied in
//! depth within both planes' freedom (the camera's depth buffer: f32, or 24-bit on the GLES 2
//! path). There the lookups of two frames are not of the same point and are not compared.

use glam::Vec3;
use rayon::prelude::*;
use umbra_case::format::Filter;
use umbra_case::{Convention, Geometry, LightRun, Profile};

use crate::bands::for_each_band;
use crate::lookup::{
    Legal, Lookup, Neighbours, Turn, ambiguity, at_window, position_freedom, window_of,
};
use crate::raster::{Coverage, EdgeKind, Rasterizer, Tri};
use crate::shading::{background, shade_linear, shade_run, shade_tolerance};
use crate::shadow_pass::setup_all;
use crate::surface::{Surfaces, interpolate};

const NONE: u32 = u32::MAX;

/// The depth test's survivor at a pixel. Only the depth and the winner are kept (8 bytes a
/// pixel): the winner's fragment, weights and slopes are recomputed for it alone, with the
/// same integer edge functions ([`Tri::fragment_at`]) and the same arithmetic, so nothing a
/// pixel shows changes, while the pass no longer writes (and page-faults in) 40 bytes a pixel.
#[derive(Clone, Copy)]
struct Nearest {
    depth: f32,
    /// Index into the set-up triangles (not the source triangle).
    tri: u32,
}

/// A covered pixel's surface point, for the judged lookup.
struct Point {
    x: i32,
    y: i32,
    /// Index into the set-up triangles.
    tri: u32,
    /// Its source triangle.
    source: u32,
    p: Vec3,
    n: Vec3,
    albedo: Vec3,
    to_light: Vec3,
    to_eye: Vec3,
}

/// What a judged pixel allows (see [`crate::Judged`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelLegal {
    /// The legal visibility interval and why it is wide ([`Legal`]).
    pub lo: f32,
    /// See `lo`.
    pub hi: f32,
    /// [`ambiguity`] flags.
    pub flags: u8,
    /// Unclamped colour for visibility 0 …
    pub c0: [f32; 3],
    /// … and for visibility 1 (affine in between).
    pub c1: [f32; 3],
    /// The colour's arithmetic freedom per channel ([`crate::shading::shade_tolerance`]).
    pub ctol: f32,
}

/// Per pixel, raster row order: colour, visibility (NaN = background), face + 1.
pub struct LitImage {
    /// RGBA8.
    pub color: Vec<u8>,
    /// Shadow term.
    pub visibility: Vec<f32>,
    /// Face id + 1, 0 for background.
    pub surface: Vec<u32>,
    /// What each pixel allows (judged renders; empty otherwise).
    pub legal: Vec<PixelLegal>,
    /// The trace of the explained pixel, if one was asked for.
    pub trace: String,
}

/// The lit pass's rasteriser: the camera's image in `conv`, culling by `camera.cull`, the
/// near and far planes clipping.
fn camera_raster(run: &LightRun, conv: Convention) -> Rasterizer {
    let [width, height] = run.camera.size;
    Rasterizer {
        conv,
        width,
        height,
        cull: run.case().camera.cull,
        depth_clamp: false,
    }
}

/// Renders the camera view of `run`, looking shadows up with `lookup`; with `judged` (the
/// camera view's edge kinds and the profile), also what every pixel allows. `settled`
/// (raster row order, judged renders only): what a wider profile already allows at each
/// pixel; where it allows one value and nothing is ambiguous, the judged lookup is not
/// evaluated again ([`settled_value`]).
pub fn render(
    run: &LightRun,
    conv: Convention,
    lookup: &Lookup,
    judged: Option<(&[[EdgeKind; 3]], Profile)>,
    explain: Option<usize>,
    settled: Option<&[PixelLegal]>,
) -> LitImage {
    let [w, h] = run.camera.size;
    let geo: &Geometry = &run.geometry;
    let tris = setup_all(
        &camera_raster(run, conv),
        run.camera.view_proj(conv),
        geo,
        judged.map(|j| j.0),
    );
    let nearest = nearest_surfaces(&tris, w, h);
    let surface_free = judged.map(|(_, profile)| surface_freedom(&tris, &nearest, w, geo, profile));
    let case = run.case();
    let eye = run.camera.eye;
    let format = case.camera.color_format;
    let bg = background(case.camera.clear, format);
    let light = Vec3::from(run.as_written().radiance());
    // The judged lookup at a surface point: its value and what it allows.
    // What the wider profile settles at a pixel (raster index), unless it is explained.
    let settled = settled.filter(|s| s.len() == (w * h) as usize);
    let known = |i: usize| settled.filter(|_| explain != Some(i)).map(|s| &s[i]);
    let judge =
        |pt: &Point, free: u8, i: usize| judged_point(run, &tris, lookup, pt, free, known(i));
    // Shade row by row straight into the outputs, a run of pixels that show the same
    // triangle at a time, in stages (surface points, lookups, colours): each pixel is
    // computed on its own with the same arithmetic, so the result does not depend on the
    // thread count or on the runs, while the pixels of a stage are independent of each other
    // and the compiler and the processor overlap them. What a pixel allows only for judged
    // renders.
    let trace = std::sync::Mutex::new(String::new());
    // The per-pixel lookups know their pixel (the Vogel disk's rotation reads its window
    // position); a run's lookups do not, so a filter that reads it takes the per-pixel path.
    let per_pixel = case.shadow.filter == Filter::Vogel5;
    let n = nearest.len();
    let (wu, hu) = (w as usize, h as usize);
    let mut color = vec![0u8; n * 4];
    let mut visibility = vec![0f32; n];
    let mut surface_ids = vec![0u32; n];
    let mut legal = vec![PixelLegal::default(); if judged.is_some() { n } else { 0 }];
    let legal_rows: Vec<&mut [PixelLegal]> = if judged.is_some() {
        legal.chunks_mut(wu).collect()
    } else {
        (0..hu).map(|_| <&mut [PixelLegal]>::default()).collect()
    };
    color
        .par_chunks_mut(wu * 4)
        .zip(visibility.par_chunks_mut(wu))
        .zip(surface_ids.par_chunks_mut(wu))
        .zip(legal_rows)
        .enumerate()
        .for_each_init(
            || (Surfaces::default(), Vec::new(), Vec::new()),
            |(surfaces, coords, terms), (y, (((c_row, v_row), s_row), l_row))| {
                let row = &nearest[y * wu..(y + 1) * wu];
                let free = |x: usize| surface_free.as_ref().map_or(0, |s| s[y * wu + x]);
                let mut x0 = 0;
                while x0 < wu {
                    let winner = row[x0].tri;
                    let len = row[x0..].iter().take_while(|px| px.tri == winner).count();
                    let xs = x0..x0 + len;
                    x0 += len;
                    if winner == NONE {
                        let row = (&mut *c_row, &mut *v_row, &mut *s_row, &mut *l_row);
                        background_run(xs, row, &bg, case.camera.clear, free);
                        continue;
                    }
                    let tri = &tris[winner as usize];
                    let t = tri.source as usize;
                    surfaces.fill(tri, geo, xs.start as i32, y as i32, len, eye, &run.light);
                    let vis = &mut v_row[xs.clone()];
                    if surface_free.is_none()
                        && explain.is_none()
                        && !lookup.mipmapped()
                        && !per_pixel
                    {
                        lookup.visibility_run(surfaces, vis, coords);
                    } else {
                        for (k, x) in xs.clone().enumerate() {
                            let pt = Point {
                                x: x as i32,
                                y: y as i32,
                                tri: winner,
                                source: tri.source,
                                p: surfaces.position(k),
                                n: surfaces.normal(k),
                                albedo: geo.albedo[geo.object[t] as usize],
                                to_light: surfaces.light_dir(k),
                                to_eye: surfaces.eye_dir(k),
                            };
                            let window = window_of(x as u32, y as u32, h, conv.window_y_down());
                            let look = || {
                                at_window(window, || match &surface_free {
                                    Some(_) => judge(&pt, free(x), y * wu + x),
                                    None if lookup.mipmapped() => (
                                        lookup.visibility_mip(
                                            pt.p,
                                            pt.n,
                                            &neighbours(tri, geo, pt.x, pt.y),
                                        ),
                                        PixelLegal::default(),
                                    ),
                                    None => (lookup.visibility(pt.p, pt.n), PixelLegal::default()),
                                })
                            };
                            let (v, l) = if explain == Some(y * wu + x) {
                                let (out, t) = crate::lookup::explaining(look);
                                if let Ok(mut s) = trace.lock() {
                                    *s = t;
                                }
                                out
                            } else {
                                look()
                            };
                            vis[k] = v;
                            if let Some(slot) = l_row.get_mut(x) {
                                *slot = l;
                            }
                        }
                    }
                    let albedo = geo.albedo[geo.object[t] as usize];
                    shade_run(
                        format,
                        &case.shading,
                        light,
                        albedo,
                        surfaces,
                        vis,
                        &mut c_row[4 * xs.start..4 * xs.end],
                        terms,
                    );
                    s_row[xs].fill(geo.face[t] + 1);
                }
            },
        );
    LitImage {
        color,
        visibility,
        surface: surface_ids,
        legal,
        trace: trace.into_inner().unwrap_or_default(),
    }
}

/// Pixels `xs` of a row that show no surface: the clear colour, no visibility, no surface,
/// and, for a judged render, the clear colour exactly (the judge holds the background to it)
/// with the pixel's surface freedoms `free`.
fn background_run(
    xs: std::ops::Range<usize>,
    (color, vis, surface, legal): (&mut [u8], &mut [f32], &mut [u32], &mut [PixelLegal]),
    bg: &[u8; 4],
    clear: [f32; 3],
    free: impl Fn(usize) -> u8,
) {
    for x in xs {
        color[4 * x..4 * x + 4].copy_from_slice(bg);
        vis[x] = f32::NAN;
        surface[x] = 0;
        if let Some(slot) = legal.get_mut(x) {
            *slot = PixelLegal {
                flags: free(x),
                c0: clear,
                c1: clear,
                ..Default::default()
            };
        }
    }
}

/// Which triangle is nearest the camera at each pixel, and its depth (the lit pass's depth
/// test, LESS, depth clamped to [0, 1]).
fn nearest_surfaces(tris: &[Tri], w: u32, h: u32) -> Vec<Nearest> {
    let mut nearest = vec![
        Nearest {
            depth: 1.0,
            tri: NONE,
        };
        (w * h) as usize
    ];
    for_each_band(
        &mut nearest,
        w as usize,
        1,
        tris,
        false,
        |rows, band, touching| {
            let mut depths = Vec::new();
            for (index, t) in touching {
                t.scan_spans(rows.clone(), |span| {
                    let start = (span.y - rows.start) as usize * w as usize + span.x as usize;
                    let pixels = &mut band[start..start + span.len];
                    span.depths(t, &mut depths);
                    for (px, z) in pixels.iter_mut().zip(&depths) {
                        let z = z.clamp(0.0, 1.0);
                        let nearer = z < px.depth;
                        *px = Nearest {
                            depth: if nearer { z } else { px.depth },
                            tri: if nearer { index as u32 } else { px.tri },
                        };
                    }
                });
            }
        },
    );
    nearest
}

/// The value a pixel's judged lookup would give, without evaluating it, where `known` (what a
/// wider profile allows there: the specs', of which `lookup`'s profile is a behaviour card's
/// narrowing) settles it: one value, no ambiguity flag, and the reference's own value under
/// `lookup`'s profile that same value, bit for bit. A calibration only narrows the specs'
/// freedom ([`umbra_case::calibration`]) and the reference lies inside its own interval, so
/// the narrowed interval there is that one value too. Anywhere else, `None`: the lookup is
/// judged in full.
fn settled_value(lookup: &Lookup, p: Vec3, n: Vec3, known: Option<&PixelLegal>) -> Option<f32> {
    let k = known.filter(|k| k.flags == 0 && k.lo.to_bits() == k.hi.to_bits())?;
    let vis = lookup.visibility(p, n);
    (vis.to_bits() == k.lo.to_bits()).then_some(vis)
}

/// The judged lookup at surface point `pt` (its pixel's surface freedoms `free`): the value
/// the reference computes and everything the specs allow there, colour included; where
/// `known` settles the lookup ([`settled_value`]), it is not evaluated.
fn judged_point(
    run: &LightRun,
    tris: &[Tri],
    lookup: &Lookup,
    pt: &Point,
    free: u8,
    known: Option<&PixelLegal>,
) -> (f32, PixelLegal) {
    let (geo, case, eye) = (&run.geometry, run.case(), run.camera.eye);
    let (tri, t) = (&tris[pt.tri as usize], pt.source as usize);
    let (p, n) = (pt.p, pt.n);
    // Vertex snapping (4 sub-pixel bits) moves the triangle under the pixel centre by up
    // to its reach along x and y: the interpolated position (and normal) are those of a
    // point up to that far away on the surface.
    let (x, y) = (f64::from(pt.x) + 0.5, f64::from(pt.y) + 0.5);
    let (px_, nx) = interpolate(geo, t, tri.source_weights_at(x + 1.0, y));
    let (py_, ny) = interpolate(geo, t, tri.source_weights_at(x, y + 1.0));
    let snap = tri.reach() as f32;
    let moves = [(px_ - p) * snap, (py_ - p) * snap];
    let turn = Turn([(nx - n) * snap, (ny - n) * snap]);
    let normal_moves = turn.reach();
    let settled = (!lookup.mipmapped())
        .then(|| settled_value(lookup, p, n, known))
        .flatten();
    let (vis, l): (f32, Legal) = if let Some(v) = settled {
        (
            v,
            Legal {
                lo: v,
                hi: v,
                flags: 0,
            },
        )
    } else if lookup.mipmapped() {
        lookup.judged_mip(p, n, moves, turn, &neighbours(tri, geo, pt.x, pt.y))
    } else {
        lookup.judged(p, n, moves, turn)
    };
    let (albedo, to_light, to_eye) = (pt.albedo, pt.to_light, pt.to_eye);
    let light = Vec3::from(run.as_written().radiance());
    let c0 = shade_linear(&case.shading, light, albedo, n, to_light, to_eye, 0.0);
    let c1 = shade_linear(&case.shading, light, albedo, n, to_light, to_eye, 1.0);
    let d = position_freedom(p, lookup.reach) + moves[0].length() + moves[1].length();
    let moved = normal_moves
        + d / (eye - p).length().max(1e-6)
        + match run.light.kind {
            umbra_case::LightKind::Directional { .. } => 0.0,
            umbra_case::LightKind::Spot { position }
            | umbra_case::LightKind::Point { position } => d / (position - p).length().max(1e-6),
        };
    let ctol = shade_tolerance(&case.shading, light, albedo, n, to_light, to_eye, moved);
    (
        vis,
        PixelLegal {
            lo: l.lo,
            hi: l.hi,
            flags: l.flags | free,
            c0: c0.to_array(),
            c1: c1.to_array(),
            ctol,
        },
    )
}

/// The points (and normals) of `tri`'s surface at the centres of pixel (x, y) and its eight neighbours,
/// the triangle's plane extrapolated beyond its edges as a quad's helper invocations
/// extrapolate its varyings: what a mipmapped lookup's derivatives are taken over.
fn neighbours(tri: &Tri, geo: &Geometry, x: i32, y: i32) -> Neighbours {
    let t = tri.source as usize;
    let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
    Neighbours(std::array::from_fn(|j| {
        std::array::from_fn(|i| {
            let w = tri.source_weights_at(cx + i as f64 - 1.0, cy + j as f64 - 1.0);
            interpolate(geo, t, w)
        })
    }))
}

/// Per pixel, [`ambiguity::SURFACE`] where another implementation may show another surface
/// (or none, or one where we show none).
fn surface_freedom(
    tris: &[Tri],
    nearest: &[Nearest],
    w: u32,
    geo: &Geometry,
    profile: Profile,
) -> Vec<u8> {
    // The camera's depth buffer: f32 everywhere but the GLES 2 path's 24-bit renderbuffer.
    let storage = if profile.packed_depth {
        1.0 / f64::from((1u32 << 24) - 1)
    } else {
        0.0
    };
    // The plane's snapping and its corners' transform error (`Tri::z_err`), carried to the
    // centre by the weights (`None`: the winner, whose weights at the centre are not kept,
    // takes its largest), a few roundings of z, and the buffer's storage.
    let tol = |t: &Tri, z: f64, e: Option<[i64; 3]>| {
        let (dx, dy) = t.depth_slopes();
        let (norm, transform) = match e {
            Some(e) => (t.weight_norm(e), t.depth_error_at(e)),
            None => (1.0, t.z_err.iter().copied().fold(0.0, f64::max)),
        };
        (dx.abs() + dy.abs()) * t.reach() * norm
            + transform
            + 4.0 * f64::from(umbra_case::depth::f32_spacing(z as f32))
            + storage
    };
    let mut free = vec![0u8; nearest.len()];
    for_each_band(
        &mut free,
        w as usize,
        1,
        tris,
        true,
        |rows, band, touching| {
            // The winner's pair visits, and every pair visit, per pixel of the band: a winner
            // near an edge it shares is sure to be replaced by its partner only if the partner is
            // near that edge too (not near a boundary of its own).
            let mut winner_pairs: Vec<(usize, u32, u32)> = Vec::new();
            let mut pair_visits: std::collections::HashSet<(usize, u32, u32)> =
                std::collections::HashSet::new();
            for (_, t) in touching {
                let face = geo.face[t.source as usize];
                t.scan_near(rows.clone(), t.reach(), |x, y, e, coverage| {
                    let certain = coverage != Coverage::Maybe;
                    let i = (y - rows.start) as usize * w as usize + x as usize;
                    if let Coverage::Pair(partner) = coverage {
                        pair_visits.insert((i, t.source, partner));
                    }
                    let gi = y as usize * w as usize + x as usize;
                    let win = nearest[gi];
                    let win_source = if win.tri == NONE {
                        NONE
                    } else {
                        tris[win.tri as usize].source
                    };
                    let flag = if win.tri == NONE {
                        true
                    } else if win_source == t.source {
                        // Ours: it may not cover, or an edge it shares with another face may move.
                        if let Coverage::Pair(partner) = coverage {
                            winner_pairs.push((i, t.source, partner));
                        }
                        !certain || near_other_face(t, e, face)
                    } else if geo.face[win_source as usize] == face {
                        false
                    } else {
                        let z = t.depth_at(e);
                        let zw = f64::from(win.depth);
                        z - tol(t, z, Some(e)) <= zw + tol(&tris[win.tri as usize], zw, None)
                    };
                    if flag {
                        band[i] |= ambiguity::SURFACE;
                    }
                });
            }
            for (i, me, partner) in winner_pairs {
                if !pair_visits.contains(&(i, partner, me)) {
                    band[i] |= ambiguity::SURFACE;
                }
            }
        },
    );
    free
}

/// Whether the centre with edge values `e` lies within the snapping's reach of an edge that
/// `t` shares with a triangle of another face than `face`.
fn near_other_face(t: &Tri, e: [i64; 3], face: u32) -> bool {
    (0..3).any(|i| match t.edges[i] {
        EdgeKind::Shared { face: other, .. } if other != face => {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (t.x[b] - t.x[a], t.y[b] - t.y[a]);
            let reach = t.reach()
                * f64::from(1u32 << crate::raster::SUBPIXEL_BITS)
                * (dx.abs() + dy.abs()) as f64;
            (e[i] as f64).abs() <= reach
        }
        _ => false,
    })
}
