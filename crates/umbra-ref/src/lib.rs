//! umbra's CPU reference renderer and exact shadow-ray ground truth.
//!
//! The reference *defines* the conventions the GPU backends are held to; it is written to be
//! read next to the GL and Vulkan specs, stage by stage:
//! [`raster`] (clipping, 8 sub-pixel bits, the tie rule, interpolation),
//! [`shadow_pass`] (depth per format, polygon offset), [`lookup`] (bias matrix order, guard,
//! outside policy, compare with the spec's clamp, NEAREST/LINEAR/PCF), [`lit_pass`] (with
//! [`surface`], the varyings of a run of pixels) and [`shading`]. Work is split in bands of
//! rows ([`bands`]) so it is parallel and still bit-identical whatever the thread count.
//!
//! [`truth`] is independent of all of that: it shoots f64 rays through pixel centres and
//! shadow rays to the light against the same triangles, with a watertight ray/triangle test so
//! that touching cubes cannot leak. It is what "error" is measured against.
//!
//! The reference renders in the GL clip convention by default (the write-ups' convention, with
//! the 0.5/0.5 bias matrix); [`render`] takes the other one too, and the two agree (tested).

pub mod adjacency;
pub mod bands;
pub mod lit_pass;
pub mod lookup;
pub mod raster;
pub mod rounding;
pub mod shading;
pub mod shadow_pass;
pub mod surface;
#[cfg(test)]
mod test_rng;
pub mod truth;

use std::time::Instant;

use umbra_case::fault::Fault;
use umbra_case::format::{Case, ColorFormat, Cull, MipSource, Mipmaps, Shadow};
use umbra_case::{
    Backend, BackendError, BackendId, ClipDepth, Clock, Convention, DepthMap, DriverInfo, Frame,
    LightPlane, LightRun, Needs, Prepared, Profile, Support, Timings, VisibilityStorage,
};

pub use lit_pass::PixelLegal;

/// The reference's convention for a case: `clip` with the case's depth order.
pub fn convention(case: &Case, clip: ClipDepth) -> Convention {
    Convention {
        clip,
        order: case.shadow.depth_order,
    }
}

/// Renders both passes of `run` in clip convention `clip`.
pub fn render(run: &Prepared, clip: ClipDepth) -> Frame {
    each_light(run, |one| render_inner(one, clip, None, None, None, None).0)
}

/// A case as every backend renders it: each light's run ([`Prepared::lights`]) by `one`, the
/// lights' colours added where a surface shows ([`add_lights`]).
fn each_light(run: &Prepared, one: impl Fn(&LightRun) -> Frame) -> Frame {
    add_lights(
        run.lights.iter().map(one).collect(),
        run.case().camera.color_format,
    )
}

/// One frame from each light's (`frames`, in the case's order, each one light's): every
/// light's plane, the timings added, and the colours added as a blend (ONE, ONE) into a
/// `format` target adds each pass's colour to the stored one, from the first pass's (its
/// background too) on, where each later pass covers a pixel: codes added, saturating, on
/// RGBA8; on an sRGB target both decoded, added in linear and encoded again. Each pass's
/// colour is its own frame's stored code, a legal rendering of it (the judge allows each
/// pass its rounding: `colour_ok_lights`).
pub fn add_lights(frames: Vec<Frame>, format: ColorFormat) -> Frame {
    let mut frames = frames.into_iter();
    let mut sum = frames.next().expect("a case has a light");
    for f in frames {
        for (i, (dst, src)) in sum
            .color
            .chunks_exact_mut(4)
            .zip(f.color.chunks_exact(4))
            .enumerate()
        {
            if f.covered(i) {
                for c in 0..3 {
                    dst[c] = match format {
                        ColorFormat::Rgba8 => dst[c].saturating_add(src[c]),
                        ColorFormat::Srgb8Alpha8 => {
                            let linear =
                                |code: u8| umbra_case::colour::srgb_decode(f32::from(code) / 255.0);
                            rounding::unorm8(format.encode(linear(dst[c]) + linear(src[c])))
                        }
                    };
                }
            }
        }
        let t = &mut sum.timings;
        t.shadow_pass += f.timings.shadow_pass;
        t.lit_pass += f.timings.lit_pass;
        t.readback += f.timings.readback;
        t.total += f.timings.total;
        sum.lights.extend(f.lights);
    }
    sum
}

/// Renders like [`render`] with a geometric `fault` in the shadow pass (a face drawn with a
/// wrong orientation, [`umbra_case::fault::Fault::face_mistake`]): what a backend making that
/// mistake would show, for the face/orientation test. The reference backend itself never
/// reads `UMBRA_FAULT`.
pub fn render_with_fault(run: &Prepared, clip: ClipDepth, fault: Fault) -> Frame {
    each_light(run, |one| {
        render_inner(one, clip, None, None, Some(fault), None).0
    })
}

/// A judged reference render: the reference's frame and, for each light, per pixel (top row
/// first) what a conformant implementation of `profile` may show there ([`PixelLegal`]): the
/// interval of its visibility, why the interval is wide ([`lookup::ambiguity`]), and its
/// colour as a function of the visibility it wrote. The judge in `umbra-compare` reads
/// nothing else.
#[derive(Clone, Debug)]
pub struct Judged {
    /// The reference's own frame (one legal rendering among many), a plane per light.
    pub frame: Frame,
    /// Each light's judged run ([`Prepared::lights`]), in the case's order.
    pub lights: Vec<JudgedLight>,
    /// The profile the case is judged for.
    pub profile: Profile,
    /// The colour target the case asks for (`camera.color_format`): how the judge turns a
    /// pixel's linear colour bounds into the codes it may store.
    pub color_format: ColorFormat,
}

/// What one light's run allows ([`Judged::lights`]).
#[derive(Clone, Debug)]
pub struct JudgedLight {
    /// Per pixel, what is legal (the colour terms: this light's, the ambient term in the
    /// first light's only).
    pub legal: Vec<PixelLegal>,
    /// The step between the values the case's filter produces ([`lookup::quantum`]).
    pub quantum: f32,
    /// The profile the light's intervals are for (its effective profile).
    pub profile: Profile,
    /// Per shadow-map texel, layer after layer, each top row first (as
    /// [`umbra_case::DepthMap`] holds them): the range of values a conformant implementation
    /// may store there ([`shadow_pass::Freedom`]). Empty when not kept.
    pub map: Vec<(f32, f32)>,
}

impl Judged {
    /// A case's judged run from its lights' (`each`, in the case's order, each one light's
    /// and at least one): every light's judged run, the frame's colour all lights'
    /// ([`add_lights`]), judged for `profile`.
    pub fn of_lights(each: Vec<Judged>, profile: Profile, format: ColorFormat) -> Judged {
        let mut frames = Vec::with_capacity(each.len());
        let mut lights = Vec::with_capacity(each.len());
        for j in each {
            frames.push(j.frame);
            lights.extend(j.lights);
        }
        Judged {
            frame: add_lights(frames, format),
            lights,
            profile,
            color_format: format,
        }
    }
}

/// Renders like [`render`] and also computes what every pixel allows for `profile`.
pub fn render_judged(run: &Prepared, clip: ClipDepth, profile: Profile) -> Judged {
    explain(run, clip, profile, None).0
}

/// Like [`render_judged`], and with `pixel` (x, y, top row first) also the step-by-step
/// trace of that pixel's judged lookup: the point, its moves, every tap's stored range and
/// what the compare may answer.
pub fn explain(
    run: &Prepared,
    clip: ClipDepth,
    profile: Profile,
    pixel: Option<(u32, u32)>,
) -> (Judged, String) {
    let mut judged = Vec::new();
    let mut traces = String::new();
    for (k, light) in run.lights.iter().enumerate() {
        let (j, trace) = explain_light(light, clip, profile, pixel);
        if !trace.is_empty() {
            traces += &format!("light {k}:\n{trace}");
        }
        judged.push(j);
    }
    (
        Judged::of_lights(judged, profile, run.case().camera.color_format),
        traces,
    )
}

/// One light's judged run ([`explain`]), with its pixel's trace.
pub fn explain_light(
    run: &LightRun,
    clip: ClipDepth,
    profile: Profile,
    pixel: Option<(u32, u32)>,
) -> (Judged, String) {
    judged_of(run, clip, profile, pixel, None)
}

/// [`explain_light`] for `profile`, a behaviour card's narrowing of the specs' freedom
/// ([`umbra_case::calibration`]), given `spec`: the same light's run judged for the specs
/// (`profile` without its calibration). Where `spec` allows the reference's value alone and
/// marks nothing ambiguous, so does the card (a calibration only narrows, and the reference
/// lies inside its own card's interval), and the judged lookup is not evaluated again; the
/// map's ranges, every other pixel and every pixel's colour bounds are computed as
/// [`explain_light`] computes them. The result is [`explain_light`]'s value for value, but
/// where its card model is wider than the specs at a pixel the specs settle (it should never
/// be: a card is the specs' freedom narrowed; three-lights has one such pixel, where the
/// card's map model lets a texel's coverage go that the specs' does not): there it is the
/// specs' value, the intersection the card stands for (tests/card_within.rs). Most of a
/// frame is settled so: a card's judged render costs its shadow pass and its few open
/// pixels. A `spec` of another size is not used.
pub fn judged_light_within(
    run: &LightRun,
    clip: ClipDepth,
    profile: Profile,
    spec: &JudgedLight,
) -> Judged {
    judged_of(run, clip, profile, None, Some(&spec.legal)).0
}

fn judged_of(
    run: &LightRun,
    clip: ClipDepth,
    profile: Profile,
    pixel: Option<(u32, u32)>,
    settled: Option<&[PixelLegal]>,
) -> (Judged, String) {
    let (frame, legal, map, trace) = render_inner(run, clip, Some(profile), pixel, None, settled);
    (
        Judged {
            frame,
            lights: vec![JudgedLight {
                legal,
                quantum: lookup::quantum(&run.case().shadow, &run.light),
                profile,
                map,
            }],
            profile,
            color_format: run.case().camera.color_format,
        },
        trace,
    )
}

/// The judged shadow pass alone: per face, the stored values and the range of values a
/// conformant implementation of `profile` may store in each texel (raster row order, row 0 =
/// window y 0 of `clip`'s convention).
pub fn judged_layers(
    run: &LightRun,
    clip: ClipDepth,
    profile: Profile,
) -> Vec<shadow_pass::DepthLayer> {
    let case = run.case();
    let conv = convention(case, clip);
    let adjacency = adjacency::Adjacency::new(&run.geometry);
    run.light
        .views
        .iter()
        .map(|v| {
            let vp = v.view_proj(conv);
            let kinds = adjacency.edge_kinds(&run.geometry, vp, case.shadow.cull);
            shadow_pass::render_face(
                conv,
                &case.shadow,
                vp,
                &run.geometry,
                Some((&kinds, profile)),
            )
        })
        .collect()
}

/// `settled` (judged renders, top row first): what the specs allow at each pixel, for a
/// card's render ([`judged_light_within`]).
fn render_inner(
    run: &LightRun,
    clip: ClipDepth,
    profile: Option<Profile>,
    pixel: Option<(u32, u32)>,
    fault: Option<Fault>,
    settled: Option<&[PixelLegal]>,
) -> (Frame, Vec<PixelLegal>, Vec<(f32, f32)>, String) {
    let start = Instant::now();
    let case = run.case();
    let conv = convention(case, clip);
    let adjacency = profile.map(|_| adjacency::Adjacency::new(&run.geometry));
    let layers: Vec<_> = run
        .light
        .views
        .iter()
        .enumerate()
        .map(|(k, _)| {
            let (vp, cull) = face_view(run, conv, k, fault);
            let kinds = adjacency
                .as_ref()
                .map(|a| a.edge_kinds(&run.geometry, vp, cull));
            shadow_pass::render_face(
                conv,
                &Shadow {
                    cull,
                    ..case.shadow.clone()
                },
                vp,
                &run.geometry,
                kinds.as_deref().zip(profile),
            )
        })
        .collect();
    let (level_shadows, below) =
        mip_levels(run, conv, &layers, adjacency.as_ref().zip(profile), fault);
    let shadow_done = Instant::now();
    let mut lookup = lookup::Lookup::new(run, conv, &layers, profile.unwrap_or_default());
    if !level_shadows.is_empty() {
        lookup = lookup.with_levels(&level_shadows, &below);
    }
    let camera_kinds = adjacency
        .as_ref()
        .map(|a| a.edge_kinds(&run.geometry, run.camera.view_proj(conv), case.camera.cull));
    let [cw, ch] = run.camera.size;
    // The raster row of a top-first pixel: rows run up in the GL convention.
    let explain = pixel.map(|(x, y)| {
        let row = if conv.window_y_down() { y } else { ch - 1 - y };
        (row * cw + x) as usize
    });
    // The lit pass walks raster rows: rows run up in the GL convention.
    let settled = settled
        .filter(|s| s.len() == (cw * ch) as usize)
        .map(|s| top_first(s.to_vec(), cw as usize, 1, !conv.window_y_down()));
    let lit = lit_pass::render(
        run,
        conv,
        &lookup,
        camera_kinds.as_deref().zip(profile),
        explain,
        settled.as_deref(),
    );
    let lit_done = Instant::now();
    let [w, h] = run.camera.size;
    let flip = !conv.window_y_down();
    let [mw, mh] = case.shadow.size;
    let faces = layers.len() as u32;
    let mut values = Vec::new();
    let mut map = Vec::new();
    for layer in layers {
        let pairs: Vec<(f32, f32)> = layer.lo.into_iter().zip(layer.hi).collect();
        // One face (every light but a point light's) is moved, not copied.
        if values.is_empty() {
            values = top_first(layer.values, mw as usize, 1, flip);
        } else {
            values.extend(top_first(layer.values, mw as usize, 1, flip));
        }
        if profile.is_some() {
            map.extend(top_first(pairs, mw as usize, 1, flip));
        }
    }
    let frame = Frame {
        width: w,
        height: h,
        color: top_first(lit.color, w as usize, 4, flip),
        lights: vec![LightPlane {
            visibility: top_first(lit.visibility, w as usize, 1, flip),
            surface: Some(top_first(lit.surface, w as usize, 1, flip)),
            shadow_map: Some(DepthMap {
                width: mw,
                height: mh,
                layers: faces,
                format: case.shadow.format,
                values,
            }),
        }],
        visibility_storage: VisibilityStorage::Float32,
        timings: Timings::default(),
    };
    let legal = top_first(lit.legal, w as usize, 1, flip);
    let end = Instant::now();
    let frame = Frame {
        timings: Timings {
            shadow_pass: shadow_done - start,
            lit_pass: lit_done - shadow_done,
            readback: end - lit_done,
            total: end - start,
            clock: Some(Clock::CpuWall),
        },
        ..frame
    };
    (frame, legal, map, lit.trace)
}

/// Face `k`'s view-projection in `conv` and the cull its shadow pass uses: with a
/// geometric `fault` ([`Fault::face_mistake`]) the face drawn with a wrong orientation, and a
/// mirror turning the front face with it, so that the same triangles are culled.
fn face_view(
    run: &LightRun,
    conv: Convention,
    k: usize,
    fault: Option<Fault>,
) -> (glam::Mat4, Cull) {
    let cube = run.light.is_cube();
    let layered = run.light.cascading.is_some();
    let drawn = Fault::drawn_view(fault, k, run.light.views.len(), layered);
    let vp = run.light.views[drawn].view_proj(conv);
    let cull = run.case().shadow.cull;
    match fault.and_then(|f| f.face_mistake(k, cube)) {
        None => (vp, cull),
        Some((wrong, false)) => (wrong * vp, cull),
        Some((wrong, true)) => (wrong * vp, cull.flipped()),
    }
}

/// A mipmapped map's levels below level 0 (`layers`, a 2D map's only face): the technique
/// at every level (its size, no levels) and the layers of levels 1 and on, each rendered by
/// its own shadow pass at its own size or averaged from the level above
/// ([`umbra_case::format::MipSource`]); nothing for a map with one level. `judged`: the
/// scene's adjacency and the profile, for the levels' stored ranges.
pub(crate) fn mip_levels(
    run: &LightRun,
    conv: Convention,
    layers: &[shadow_pass::DepthLayer],
    judged: Option<(&adjacency::Adjacency, Profile)>,
    fault: Option<Fault>,
) -> (Vec<Shadow>, Vec<shadow_pass::DepthLayer>) {
    let case = run.case();
    let Some(m) = case.shadow.mipmaps else {
        return (Vec::new(), Vec::new());
    };
    let shadows: Vec<Shadow> = (0..m.levels)
        .map(|k| Shadow {
            size: Mipmaps::level_size(case.shadow.size, k),
            mipmaps: None,
            ..case.shadow.clone()
        })
        .collect();
    let (vp, cull) = face_view(run, conv, 0, fault);
    let kinds = judged.map(|(a, _)| a.edge_kinds(&run.geometry, vp, cull));
    let profile = judged.map(|(_, p)| p);
    let mut below: Vec<shadow_pass::DepthLayer> = Vec::new();
    for k in 1..m.levels as usize {
        let level = match m.source {
            MipSource::Rendered => shadow_pass::render_face(
                conv,
                &Shadow {
                    cull,
                    ..shadows[k].clone()
                },
                vp,
                &run.geometry,
                kinds.as_deref().zip(profile),
            ),
            MipSource::Averaged => shadow_pass::averaged(
                below.last().unwrap_or(&layers[0]),
                shadows[k - 1].size,
                case.shadow.format,
                judged.is_some(),
            ),
        };
        below.push(level);
    }
    (shadows, below)
}

/// Rows in top-first order: reversed in place when the raster's row 0 is the bottom (the one
/// Y flip).
fn top_first<T>(mut rows: Vec<T>, width: usize, per_pixel: usize, flip: bool) -> Vec<T> {
    let stride = width * per_pixel;
    if flip && stride > 0 {
        let n = rows.len() / stride;
        for r in 0..n / 2 {
            let (upper, lower) = rows.split_at_mut((n - 1 - r) * stride);
            upper[r * stride..(r + 1) * stride].swap_with_slice(&mut lower[..stride]);
        }
    }
    rows
}

/// The reference as a [`Backend`] (id `ref`, GL clip convention).
#[derive(Debug, Default)]
pub struct RefBackend;

impl Backend for RefBackend {
    fn id(&self) -> BackendId {
        BackendId("ref".into())
    }

    fn info(&self) -> DriverInfo {
        DriverInfo {
            vendor: "umbra".into(),
            renderer: format!("CPU reference ({} threads)", rayon::current_num_threads()),
            version: env!("CARGO_PKG_VERSION").into(),
            extensions: Vec::new(),
            device: "this process's CPU".into(),
        }
    }

    fn profile(&self) -> Profile {
        Profile::GL
    }

    fn supports(&self, _needs: &Needs) -> Support {
        Support::Supported
    }

    fn render(&mut self, run: &Prepared) -> Result<Frame, BackendError> {
        Ok(render(run, ClipDepth::MinusOneToOne))
    }

    /// The reference has no framebuffer objects: `shadow.attachments` (whether a GL or
    /// Vulkan shadow pass also binds a colour target) is never read by it.
    fn renders_identically(&self, a: &umbra_case::Case, b: &umbra_case::Case) -> bool {
        let mut b = b.clone();
        b.shadow.attachments = a.shadow.attachments;
        *a == b
    }
}
