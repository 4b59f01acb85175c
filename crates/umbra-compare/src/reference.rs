//! A backend's frame against the reference's judged render ([`umbra_ref::Judged`]): every
//! pixel's visibility *value* is held to the interval a conformant implementation of the
//! backend's profile may return there, its colour to the shading of the visibility it wrote,
//! and its coverage to the rasterisation freedom. The conformance judge, the twins and the
//! tests use this one function.
//!
//! Per pixel covered in either frame ("compared"):
//! - **NaN** visibility on a covered pixel: illegal, always.
//! - **Coverage**: the backend shows another surface than the reference (or none, or one where
//!   the reference shows none). Legal only where the reference marked the pixel
//!   [`SURFACE`](umbra_ref::lookup::ambiguity::SURFACE) (vertex snapping, depth ties); then
//!   the two lookups are of different points and any answer passes there (blind).
//! - **Value**: on the same surface, the visibility must lie in [lo − ε, hi + ε] (ε the
//!   visibility target's rounding, [`umbra_case::VisibilityStorage::tolerance`]) and, for
//!   filters with discrete results (NEAREST: 0 or 1; PCF N: k/N²), within ε of such a value.
//! - **Colour**: the 8-bit colour must be the shading of the visibility the backend itself
//!   wrote (±ε), within the shading's arithmetic freedom, rounded either way: a check that
//!   holds even where the shadow answer is free.
//!
//! Where both lit/shadowed answers differ from the reference's but are legal, the difference is
//! classified by the freedom that allows it (ties first, then coverage, texel, filter, seam,
//! position). *Blind* pixels are those where any answer would pass; `value_margin` is how
//! close the closest checked value came to its bound. Pixels outside the light's frustum are
//! not exempt: the case's outside policy defines their answer.

use serde::{Deserialize, Serialize};
use umbra_case::format::ColorFormat;
use umbra_case::{Frame, LightFrame};
use umbra_ref::lookup::ambiguity;
use umbra_ref::{Judged, JudgedLight};

use crate::consensus::Failed;
use crate::is_shadowed;

/// Agreement with the reference, with every check's counts.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RefAgreement {
    /// Pixels covered in either frame.
    pub compared: u64,
    /// Of those on the same surface, how many give another lit/shadowed answer.
    pub differ: u64,
    /// Legal differences: a depth tie (offset, snapping, storage, arithmetic, the compare's
    /// precision; GL 4.6 §14.6.5, Vulkan "Depth Bias", "Depth Compare Operation").
    pub legal_tie: u64,
    /// Legal differences: the map's coverage may differ there (4 sub-pixel bits, GL 4.6
    /// §14.5, Vulkan `subPixelPrecisionBits`).
    pub legal_coverage: u64,
    /// Legal differences: the sampler may select another texel (4 sub-texel bits).
    pub legal_texel: u64,
    /// Legal differences: LINEAR weights are the implementation's (GL §3.8.16; Vulkan
    /// bilinear within 1/16).
    pub legal_filter: u64,
    /// Legal differences: a cube corner under seamless filtering.
    pub legal_seam: u64,
    /// Legal differences: the lookup point's interpolation freedom.
    pub legal_position: u64,
    /// Pixels where the backend shows another surface than the reference, legally (not
    /// compared further).
    pub legal_surface: u64,
    /// Legal differences: a mipmapped lookup may read another level (the LOD's freedom:
    /// derivatives, GL's and Vulkan's scale-factor bounds, precision).
    #[serde(default)]
    pub legal_lod: u64,
    /// Pixels where any answer would pass (interval ⊇ {0, 1}, or another surface legally).
    pub blind: u64,
    /// The blind pixels by the freedom that makes them so (same precedence as the legal
    /// classes): `[tie, coverage, texel, filter, seam, position, other surface, mip level]`.
    #[serde(default)]
    pub blind_by: [u64; 8],
    /// Pixels whose value was held to an interval that excludes 0 or 1.
    pub value_checked: u64,
    /// The smallest distance of a checked value from its bound (None: nothing checked).
    pub value_margin: Option<f32>,
    /// Pixels whose colour was checked.
    pub colour_checked: u64,
    /// Illegal: a visibility value outside its interval (or between a filter's results).
    pub illegal_value: u64,
    /// Illegal: NaN visibility on a covered pixel.
    pub illegal_nan: u64,
    /// Illegal: another surface, or coverage, where no rasterisation freedom explains it.
    pub illegal_coverage: u64,
    /// Illegal: a colour that is not the shading of the pixel's own visibility.
    pub illegal_colour: u64,
    /// Shadow-map texels checked (backends that read their map back).
    #[serde(default)]
    pub map_checked: u64,
    /// Illegal: shadow-map texels holding a value no conformant implementation stores there
    /// (texels, not pixels; not part of `illegal`).
    #[serde(default)]
    pub illegal_map: u64,
    /// Every illegal pixel (a pixel counts once, under the first check it fails).
    pub illegal: u64,
}

impl RefAgreement {
    /// Adds `o`'s counts (another light's judgement of the same frame): the smaller margin.
    pub fn absorb(&mut self, o: &RefAgreement) {
        self.compared += o.compared;
        self.differ += o.differ;
        self.legal_tie += o.legal_tie;
        self.legal_coverage += o.legal_coverage;
        self.legal_texel += o.legal_texel;
        self.legal_filter += o.legal_filter;
        self.legal_seam += o.legal_seam;
        self.legal_position += o.legal_position;
        self.legal_surface += o.legal_surface;
        self.legal_lod += o.legal_lod;
        self.blind += o.blind;
        for (a, b) in self.blind_by.iter_mut().zip(o.blind_by) {
            *a += b;
        }
        self.value_checked += o.value_checked;
        self.value_margin = match (self.value_margin, o.value_margin) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        self.colour_checked += o.colour_checked;
        self.illegal_value += o.illegal_value;
        self.illegal_nan += o.illegal_nan;
        self.illegal_coverage += o.illegal_coverage;
        self.illegal_colour += o.illegal_colour;
        self.map_checked += o.map_checked;
        self.illegal_map += o.illegal_map;
        self.illegal += o.illegal;
    }

    /// The legal classes, as every message states them.
    pub fn legal_summary(&self) -> String {
        format!(
            "legal: {} ties, {} coverage, {} texel, {} filter, {} seam, {} position, {} other surface{}",
            self.legal_tie,
            self.legal_coverage,
            self.legal_texel,
            self.legal_filter,
            self.legal_seam,
            self.legal_position,
            self.legal_surface,
            if self.legal_lod > 0 {
                format!(", {} mip level", self.legal_lod)
            } else {
                String::new()
            }
        )
    }

    /// The illegal counts by check, in one phrase (empty when none).
    pub fn illegal_summary(&self) -> String {
        let mut parts = Vec::new();
        for (n, what) in [
            (self.illegal_value, "visibility value"),
            (self.illegal_nan, "NaN visibility"),
            (self.illegal_coverage, "coverage"),
            (self.illegal_colour, "colour"),
            (self.illegal_map, "shadow-map texel"),
        ] {
            if n > 0 {
                parts.push(format!("{n} px {what}"));
            }
        }
        parts.join(", ")
    }

    /// Blind pixels as a share of compared ones.
    pub fn blind_share(&self) -> f64 {
        if self.compared == 0 {
            0.0
        } else {
            self.blind as f64 / self.compared as f64
        }
    }
}

/// What the judge made of one pixel (for pictures and the golden tolerance).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PixelJudgement {
    /// Covered in neither frame.
    #[default]
    NotCompared,
    /// Checked and passed; the shadow answer is the reference's.
    Agrees,
    /// Checked and passed with another shadow answer (a legal difference).
    LegalDifference,
    /// Any answer would have passed here.
    Blind,
    /// Failed a check.
    Illegal,
}

impl PixelJudgement {
    /// How bad a judgement is, for the worst of a pixel's lights: illegal, then a legal
    /// difference, blind, agreement, not compared.
    pub fn rank(self) -> u8 {
        match self {
            PixelJudgement::NotCompared => 0,
            PixelJudgement::Agrees => 1,
            PixelJudgement::Blind => 2,
            PixelJudgement::LegalDifference => 3,
            PixelJudgement::Illegal => 4,
        }
    }
}

/// The names of [`RefAgreement::blind_by`]'s entries.
pub const REASONS: [&str; 8] = [
    "depth tie",
    "map coverage",
    "texel selection",
    "filter weights",
    "cube seam",
    "lookup position",
    "other surface",
    "mip level",
];

/// The index in [`REASONS`] of the first freedom a pixel's flags name (ties first).
pub fn reason_index(f: u8) -> usize {
    if f & ambiguity::DEPTH_TIE != 0 {
        0
    } else if f & ambiguity::COVERAGE != 0 {
        1
    } else if f & ambiguity::TEXEL_BOUNDARY != 0 {
        2
    } else if f & ambiguity::FILTER != 0 {
        3
    } else if f & ambiguity::SEAM != 0 {
        4
    } else if f & ambiguity::SURFACE != 0 {
        6
    } else if f & ambiguity::LOD != 0 {
        7
    } else {
        5
    }
}

impl RefAgreement {
    /// The freedom that accounts for most blind pixels, and its share of them.
    pub fn main_blind_reason(&self) -> Option<(&'static str, f64)> {
        let (i, n) = self.blind_by.iter().enumerate().max_by_key(|(_, n)| **n)?;
        (*n > 0).then(|| (REASONS[i], *n as f64 / self.blind.max(1) as f64))
    }
}

/// Whether `v` is a value the interval allows: within ε of [lo, hi] and, for a filter with
/// discrete results (`quantum` > 0), within ε of a multiple of the quantum in the interval.
pub fn value_ok(v: f32, lo: f32, hi: f32, quantum: f32, eps: f32) -> bool {
    if !(lo - eps <= v && v <= hi + eps) {
        return false;
    }
    if quantum <= 0.0 {
        return true;
    }
    let k = umbra_ref::rounding::round_f32(v / quantum) * quantum;
    (v - k).abs() <= eps + 4.0 * f32::EPSILON && lo - eps <= k && k <= hi + eps
}

/// Judges `frame` against the judged reference `basis` (same size, the backend's profile).
/// Returns the counts and each pixel's judgement.
///
/// Each light's visibility and map are judged against that light's run
/// ([`Judged::lights`]), the counts added up over the lights (a pixel is compared once per
/// light); a pixel's judgement is the worst of its lights'. Its colour, the sum of the
/// lights' passes, is checked once against all of them ([`colour_ok_lights`]); the background
/// against the clear colour, once.
pub fn judge(basis: &Judged, frame: &Frame) -> (RefAgreement, Vec<PixelJudgement>) {
    assert_eq!(
        (basis.frame.width, basis.frame.height),
        (frame.width, frame.height),
        "frame and reference sizes differ"
    );
    let n = (frame.width * frame.height) as usize;
    let missing = vec![f32::NAN; n];
    let lights: Vec<(LightFrame, LightFrame, &JudgedLight)> = basis
        .lights
        .iter()
        .enumerate()
        .map(|(k, l)| {
            (
                light_of(&basis.frame, k, &missing),
                light_of(frame, k, &missing),
                l,
            )
        })
        .collect();
    let mut r = RefAgreement::default();
    let mut px = vec![PixelJudgement::NotCompared; n];
    for &(reference, f, light) in &lights {
        let (rk, pk) = judge_light(reference, light, f);
        r.absorb(&rk);
        for (a, b) in px.iter_mut().zip(pk) {
            if b.rank() > a.rank() {
                *a = b;
            }
        }
    }
    let eps = frame.visibility_storage.tolerance();
    // Each light's value and legal terms at the pixel, refilled pixel by pixel (one
    // allocation for the frame, not one a pixel).
    let mut values: Vec<(f32, &umbra_ref::PixelLegal)> = Vec::with_capacity(lights.len());
    for (i, j) in px.iter_mut().enumerate() {
        let rgb = &frame.color[i * 4..i * 4 + 3];
        let (ref_cov, b_cov) = (basis.frame.covered(i), frame.covered(i));
        if !ref_cov && !b_cov {
            // The background: the clear colour (`camera.clear`), the only thing a backend
            // writes there (a clear value converted as any colour is: either code of a value
            // halfway between two; in an sRGB target encoded, or on desktop GL and GLES 2
            // possibly not: Profile::srgb_clear_may_be_unencoded). The clear colour is the
            // first light's pass's, whose terms hold the ambient one.
            r.colour_checked += 1;
            let clear = &basis.lights[0].legal[i];
            let cleared = |format| colour_ok(rgb, 0.0, 0.0, clear, format);
            if !(cleared(basis.color_format)
                || (basis.profile.srgb_clear_may_be_unencoded() && cleared(ColorFormat::Rgba8)))
            {
                r.illegal_colour += 1;
                r.illegal += 1;
                *j = PixelJudgement::Illegal;
            }
            continue;
        }
        // A colour is checked where both frames show the same surface, in every light's pass
        // (a later pass may show the other surface of an exact tie).
        let same_surface =
            lights
                .iter()
                .all(|(reference, f, _)| match (reference.surface, f.surface) {
                    (Some(a), Some(b)) => a[i] == b[i],
                    _ => true,
                });
        if !ref_cov || !b_cov || !same_surface {
            continue;
        }
        values.clear();
        values.extend(
            lights
                .iter()
                .map(|(_, f, l)| (f.visibility[i], &l.legal[i])),
        );
        if values.iter().any(|(v, _)| v.is_nan()) {
            continue;
        }
        r.colour_checked += 1;
        if !colour_ok_lights(rgb, &values, eps, basis.color_format) {
            r.illegal_colour += 1;
            if *j != PixelJudgement::Illegal {
                r.illegal += 1;
                *j = PixelJudgement::Illegal;
            }
        }
    }
    (r, px)
}

/// Light `k` of `frame`; a light the frame lacks (a backend that wrote fewer planes than the
/// case has lights) reads `missing` (NaN everywhere, which the judge finds illegal) on the
/// surfaces another light's pass drew.
pub fn light_of<'a>(frame: &'a Frame, k: usize, missing: &'a [f32]) -> LightFrame<'a> {
    frame.light(k).unwrap_or(LightFrame {
        width: frame.width,
        height: frame.height,
        visibility: missing,
        shadow_map: None,
        surface: frame.lights.iter().find_map(|p| p.surface.as_deref()),
        visibility_storage: frame.visibility_storage,
    })
}

/// [`judge`] for one light: its visibility (against `light`'s intervals, on the surfaces
/// `reference`'s pass drew) and its map; colours are [`judge`]'s.
fn judge_light(
    reference: LightFrame,
    light: &JudgedLight,
    frame: LightFrame,
) -> (RefAgreement, Vec<PixelJudgement>) {
    let n = (frame.width * frame.height) as usize;
    let eps = frame.visibility_storage.tolerance();
    let q = light.quantum;
    let mut r = RefAgreement::default();
    let mut px = vec![PixelJudgement::NotCompared; n];
    let surface_of = |f: LightFrame, i: usize| f.surface.map(|s| s[i]);
    // Pixels are visited by index: each reads five parallel arrays of two frames.
    #[allow(clippy::needless_range_loop)]
    for i in 0..n {
        let (ref_cov, b_cov) = (reference.covered(i), frame.covered(i));
        if !ref_cov && !b_cov {
            continue;
        }
        r.compared += 1;
        let l = light.legal[i];
        let v = frame.visibility[i];
        if b_cov && v.is_nan() {
            r.illegal_nan += 1;
            r.illegal += 1;
            px[i] = PixelJudgement::Illegal;
            continue;
        }
        let same_surface = ref_cov
            && b_cov
            && match (surface_of(reference, i), surface_of(frame, i)) {
                (Some(a), Some(b)) => a == b,
                _ => true,
            };
        if !same_surface {
            if l.flags & ambiguity::SURFACE != 0 {
                r.legal_surface += 1;
                r.blind += 1;
                r.blind_by[6] += 1;
                px[i] = PixelJudgement::Blind;
            } else {
                r.illegal_coverage += 1;
                r.illegal += 1;
                px[i] = PixelJudgement::Illegal;
            }
            continue;
        }
        let ok = value_ok(v, l.lo, l.hi, q, eps);
        let blind = l.lo - eps <= 0.0 && l.hi + eps >= 1.0;
        let differs = is_shadowed(v) != is_shadowed(reference.visibility[i]);
        if differs {
            r.differ += 1;
        }
        if !ok {
            r.illegal_value += 1;
            r.illegal += 1;
            px[i] = PixelJudgement::Illegal;
        } else {
            if blind {
                r.blind += 1;
                r.blind_by[reason_index(l.flags)] += 1;
            } else {
                r.value_checked += 1;
                let margin = (v - (l.lo - eps)).min(l.hi + eps - v);
                r.value_margin = Some(r.value_margin.map_or(margin, |m| m.min(margin)));
            }
            if differs {
                let class = match reason_index(l.flags) {
                    0 => &mut r.legal_tie,
                    1 => &mut r.legal_coverage,
                    2 => &mut r.legal_texel,
                    3 => &mut r.legal_filter,
                    4 => &mut r.legal_seam,
                    7 => &mut r.legal_lod,
                    _ => &mut r.legal_position,
                };
                *class += 1;
            }
            px[i] = match (blind, differs) {
                (true, _) => PixelJudgement::Blind,
                (false, true) => PixelJudgement::LegalDifference,
                (false, false) => PixelJudgement::Agrees,
            };
        }
    }
    if let Some(map) = light_map_failures(light, frame) {
        r.map_checked = light.map.len() as u64;
        r.illegal_map = map.total;
    }
    (r, px)
}

/// The shadow-map texels of `frame` outside the ranges a conformant implementation may store
/// (each within one f32 spacing), side = above; `None` where the map is not checked (the
/// backend reads none back, or the basis kept no ranges). Every light's map against its own
/// run's ranges, light after light (a texel's index counts on from the previous lights'
/// texels); `None` if any light's map is not checked.
pub fn map_failures(basis: &Judged, frame: &Frame) -> Option<Failed> {
    let mut all = Failed::default();
    let mut offset = 0;
    for (k, light) in basis.lights.iter().enumerate() {
        let failed = light_map_failures(light, frame.light(k)?)?;
        all.total += failed.total - failed.entries.len() as u64;
        for e in failed.entries {
            all.push(offset + (e >> 1) as usize, e & 1 == 1);
        }
        offset += light.map.len();
    }
    Some(all)
}

fn light_map_failures(light: &JudgedLight, frame: LightFrame) -> Option<Failed> {
    let map = frame.shadow_map?;
    if map.values.len() != light.map.len() || light.map.is_empty() {
        return None;
    }
    let mut failed = Failed::default();
    for (k, (v, &(lo, hi))) in map.values.iter().zip(&light.map).enumerate() {
        let (lo, hi) = map_range(lo, hi);
        if !(lo <= *v && *v <= hi) {
            failed.push(k, *v > hi);
        }
    }
    Some(failed)
}

/// A texel's legal range as [`map_failures`] holds it: the basis's [lo, hi] widened by one
/// f32 spacing at each end (`umbra repro`'s probes embed exactly these bounds).
pub fn map_range(lo: f32, hi: f32) -> (f32, f32) {
    let slack = umbra_case::depth::f32_spacing;
    (lo - slack(lo), hi + slack(hi))
}

/// The pixels [`judge`] found illegal (`px`), side = shadowed by the first light's map (the
/// side a fingerprint has always recorded): a fingerprint's frame part.
pub fn frame_failures(frame: &Frame, px: &[PixelJudgement]) -> Failed {
    let mut failed = Failed::default();
    let first = frame.lights.first().map(|p| &p.visibility[..]);
    for (i, j) in px.iter().enumerate() {
        if *j == PixelJudgement::Illegal {
            failed.push(i, first.is_some_and(|v| is_shadowed(v[i])));
        }
    }
    failed
}

/// Whether an RGB8 colour is the shading of visibility `v` (± `eps`) at this pixel, stored
/// in a `format` target: each channel within the codes that the unclamped colour's range,
/// widened by the shading's arithmetic freedom, clamped, encoded with the encoding's own
/// freedom ([`ColorFormat::encoded_bounds`]: nothing for `rgba8`), rounds to either way.
pub fn colour_ok(
    rgb: &[u8],
    v: f32,
    eps: f32,
    l: &umbra_ref::PixelLegal,
    format: ColorFormat,
) -> bool {
    let (v0, v1) = ((v - eps).clamp(0.0, 1.0), (v + eps).clamp(0.0, 1.0));
    (0..3).all(|c| {
        let at = |v: f32| l.c0[c] + (l.c1[c] - l.c0[c]) * v;
        let (a, b) = (at(v0), at(v1));
        let lo = (a.min(b) - l.ctol).clamp(0.0, 1.0);
        let hi = (a.max(b) + l.ctol).clamp(0.0, 1.0);
        let (lo, hi) = format.encoded_bounds(lo, hi);
        within_codes(lo, hi, rgb[c])
    })
}

/// [`colour_ok`] for a colour that is the sum of several lights' passes (`lights`: each
/// light's visibility as the backend wrote it and its run's [`umbra_ref::PixelLegal`], whose
/// `c0`/`c1` hold that light's terms, the ambient term in the first light's only). Per
/// channel, an interval carried pass by pass: each light adds its range at its own
/// visibility (± `eps`) widened by its shading freedom; between passes the sum is what the
/// target stored and a blend (ONE, ONE) reads back ([`ColorFormat::stored_linear_range`]:
/// either neighbouring code, decoded to linear on an sRGB target), and clamped to [0, 1] as
/// a fixed-point target clamps the blend's result; the last pass's sum is stored as
/// [`colour_ok`] stores one. Every term is ≥ 0.
pub fn colour_ok_lights(
    rgb: &[u8],
    lights: &[(f32, &umbra_ref::PixelLegal)],
    eps: f32,
    format: ColorFormat,
) -> bool {
    (0..3).all(|c| {
        let (mut lo, mut hi) = (0.0f32, 0.0f32);
        for (k, (v, l)) in lights.iter().enumerate() {
            if k > 0 {
                (lo, hi) = format.stored_linear_range(lo, hi);
            }
            let (v0, v1) = ((v - eps).clamp(0.0, 1.0), (v + eps).clamp(0.0, 1.0));
            let at = |v: f32| l.c0[c] + (l.c1[c] - l.c0[c]) * v;
            let (a, b) = (at(v0), at(v1));
            lo += a.min(b) - l.ctol;
            hi += a.max(b) + l.ctol;
        }
        let (lo, hi) = format.encoded_bounds(lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0));
        within_codes(lo, hi, rgb[c])
    })
}

/// ⌊lo·255⌋ ≤ code ≤ ⌈hi·255⌉, without libm's floor and ceil (a call each at baseline
/// x86-64): for an integer c, ⌊x⌋ ≤ c ⟺ x < c + 1 and c ≤ ⌈y⌉ ⟺ y > c − 1, and NaN fails
/// both as it fails the rounded forms.
#[inline]
fn within_codes(lo: f32, hi: f32, code: u8) -> bool {
    let code = f32::from(code);
    lo * 255.0 < code + 1.0 && hi * 255.0 > code - 1.0
}

/// Per pixel: whether the shadow answer may legally differ from the reference's there (its
/// interval straddles 0.5, or another surface may show; with several lights, for any of
/// them): the golden check's tolerance.
pub fn free_pixels(basis: &Judged) -> Vec<bool> {
    let n = (basis.frame.width * basis.frame.height) as usize;
    let mut free = vec![false; n];
    for light in &basis.lights {
        for (f, l) in free.iter_mut().zip(&light.legal) {
            *f |= self::free(l);
        }
    }
    free
}

fn free(l: &umbra_ref::PixelLegal) -> bool {
    l.flags & ambiguity::SURFACE != 0 || (l.lo < 0.5 && l.hi >= 0.5)
}

/// Two backend frames against each other: wherever their surfaces or lit/shadowed answers
/// differ, the judged renders of both frames' profiles (`ja` for `a`, `jb` for `b`) must allow
/// the answer to be free there (its interval straddles 0.5, or another surface may show).
/// Counts as [`judge`] does; the legal classes follow `ja`'s flags.
/// Light by light, each against its own runs' freedom, the counts added.
pub fn judge_pair(a: &Frame, ja: &Judged, b: &Frame, jb: &Judged) -> RefAgreement {
    let missing = vec![f32::NAN; (a.width * a.height) as usize];
    let mut r = RefAgreement::default();
    for (k, (la, lb)) in ja.lights.iter().zip(&jb.lights).enumerate() {
        r.absorb(&pair_light(
            light_of(a, k, &missing),
            &la.legal,
            light_of(b, k, &missing),
            &lb.legal,
        ));
    }
    r
}

fn pair_light(
    a: LightFrame,
    ja: &[umbra_ref::PixelLegal],
    b: LightFrame,
    jb: &[umbra_ref::PixelLegal],
) -> RefAgreement {
    let n = (a.width * a.height) as usize;
    let fa: Vec<bool> = ja.iter().map(free).collect();
    let fb: Vec<bool> = jb.iter().map(free).collect();
    let mut r = RefAgreement::default();
    for i in 0..n {
        if !a.covered(i) && !b.covered(i) {
            continue;
        }
        r.compared += 1;
        let same_surface = a.covered(i)
            && b.covered(i)
            && match (a.surface, b.surface) {
                (Some(x), Some(y)) => x[i] == y[i],
                _ => true,
            };
        let differs = !same_surface || is_shadowed(a.visibility[i]) != is_shadowed(b.visibility[i]);
        if !differs {
            continue;
        }
        r.differ += 1;
        if !(fa[i] && fb[i]) {
            r.illegal += 1;
            if same_surface {
                r.illegal_value += 1;
            } else {
                r.illegal_coverage += 1;
            }
            continue;
        }
        let f = ja[i].flags | jb[i].flags;
        let class = if !same_surface || f & ambiguity::SURFACE != 0 {
            &mut r.legal_surface
        } else if f & ambiguity::DEPTH_TIE != 0 {
            &mut r.legal_tie
        } else if f & ambiguity::COVERAGE != 0 {
            &mut r.legal_coverage
        } else if f & ambiguity::TEXEL_BOUNDARY != 0 {
            &mut r.legal_texel
        } else if f & ambiguity::FILTER != 0 {
            &mut r.legal_filter
        } else if f & ambiguity::SEAM != 0 {
            &mut r.legal_seam
        } else {
            &mut r.legal_position
        };
        *class += 1;
    }
    r
}

#[cfg(test)]
mod colour_tests {
    use super::*;

    /// An sRGB target's codes are the encoded colour's (linear mid-grey 0.5 is code 188,
    /// 187.5 exactly, so either neighbour), never the linear code; a linear target's are
    /// the linear ones. The encoding's 0.6-code freedom reaches one code further at most.
    #[test]
    fn an_srgb_target_is_held_to_the_encoded_codes() {
        let grey = umbra_ref::PixelLegal {
            lo: 1.0,
            hi: 1.0,
            flags: 0,
            c0: [0.5; 3],
            c1: [0.5; 3],
            ctol: 0.0,
        };
        let ok = |code: u8, format| colour_ok(&[code; 3], 1.0, 0.0, &grey, format);
        let srgb: Vec<u8> = (0..=255)
            .filter(|&c| ok(c, ColorFormat::Srgb8Alpha8))
            .collect();
        let linear: Vec<u8> = (0..=255).filter(|&c| ok(c, ColorFormat::Rgba8)).collect();
        assert_eq!(linear, vec![127, 128]);
        assert!(srgb.contains(&187) && srgb.contains(&188), "{srgb:?}");
        assert!(srgb.iter().all(|c| (186..=189).contains(c)), "{srgb:?}");
        // The dark end: linear 0.002 is on the linear segment, 12.92 · 0.002 · 255 = 6.6.
        let dark = umbra_ref::PixelLegal {
            c0: [0.002; 3],
            c1: [0.002; 3],
            ..grey
        };
        let ok = |code: u8| colour_ok(&[code; 3], 1.0, 0.0, &dark, ColorFormat::Srgb8Alpha8);
        assert!(ok(6) && ok(7) && !ok(1) && !ok(9));
    }

    /// Two lights' passes added: the sum of their shadings at the visibilities written,
    /// each pass after the first its stored code; a pass whose colour never arrived (or a
    /// light's shading at another visibility) is caught. On an sRGB target the sum is taken
    /// in linear light, not of the codes.
    #[test]
    fn several_lights_are_held_to_the_sum_of_their_passes() {
        // Light 0: ambient 0.1, lit adds 0.3 (linear); light 1: lit adds 0.2.
        let l0 = umbra_ref::PixelLegal {
            lo: 0.0,
            hi: 1.0,
            flags: 0,
            c0: [0.1; 3],
            c1: [0.4; 3],
            ctol: 0.0,
        };
        let l1 = umbra_ref::PixelLegal {
            c0: [0.0; 3],
            c1: [0.2; 3],
            ..l0
        };
        let ok = |code: u8, v1: f32, format| {
            colour_ok_lights(&[code; 3], &[(1.0, &l0), (v1, &l1)], 0.0, format)
        };
        let linear: Vec<u8> = (0..=255)
            .filter(|&c| ok(c, 1.0, ColorFormat::Rgba8))
            .collect();
        // 0.6 · 255 = 153: light 0's stored 0.4 (102) read back, 0.2 (51) added.
        assert!(linear.contains(&153) && linear.iter().all(|c| (152..=154).contains(c)));
        assert!(
            !ok(102, 1.0, ColorFormat::Rgba8),
            "light 1's pass is missing"
        );
        assert!(
            ok(102, 0.0, ColorFormat::Rgba8),
            "light 1 in shadow adds nothing"
        );
        // sRGB: encode(0.6) · 255 = 203.1, not the sum of the codes (170 + 124).
        let srgb: Vec<u8> = (0..=255)
            .filter(|&c| ok(c, 1.0, ColorFormat::Srgb8Alpha8))
            .collect();
        assert!(
            srgb.contains(&203) && srgb.iter().all(|c| (200..=206).contains(c)),
            "{srgb:?}"
        );
    }

    /// Desktop GL and GLES 2 may leave an sRGB clear unencoded (GL 3.3 §4.2.3), GLES 3 and
    /// Vulkan may not.
    #[test]
    fn only_gl_and_gles2_may_clear_an_srgb_target_unencoded() {
        use umbra_case::Profile;
        assert!(Profile::GL.srgb_clear_may_be_unencoded());
        assert!(Profile::GLES2.srgb_clear_may_be_unencoded());
        assert!(!Profile::GLES3.srgb_clear_may_be_unencoded());
        assert!(!Profile::VULKAN.srgb_clear_may_be_unencoded());
    }

    /// The comparison form of the colour test is the rounded form, for every code and a
    /// spread of bounds (the ends, just inside and outside each code, NaN).
    #[test]
    fn colour_bounds_without_rounding_calls() {
        let mut bounds = vec![0.0f32, 1.0, f32::NAN, 0.5];
        for k in 0..=256 {
            let x = k as f32 / 255.0;
            bounds.extend([x, x.next_up(), x.next_down(), x + 0.3 / 255.0]);
        }
        for &lo in &bounds {
            for &hi in bounds.iter().step_by(7) {
                for code in 0..=255u8 {
                    let c = f32::from(code);
                    let rounded = (lo * 255.0).floor() <= c && c <= (hi * 255.0).ceil();
                    assert_eq!(rounded, within_codes(lo, hi, code), "{lo:e} {hi:e} {code}");
                }
            }
        }
    }
}

#[cfg(test)]
mod technique_tests {
    use super::*;
    use umbra_case::{ClipDepth, Prepared, Profile};

    /// The techniques as programs write them are told apart: a backend that ignores one of a
    /// case's settings (the N·L bias's light vector, the beyond-far policy) renders what the
    /// case with the other value renders, and that frame must be illegal under the case's own
    /// intervals. Each point of `cases/bias/learnopengl.json` is rendered by the reference and
    /// judged against every other point's intervals (GL profile); its own frame passes.
    #[test]
    fn learnopengl_settings_are_each_seen() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/bias/learnopengl.json");
        let points = umbra_case::load_file(&file).expect("a valid case");
        assert_eq!(points.len(), 4, "two settings, two values each");
        let runs: Vec<Prepared> = points.into_iter().map(Prepared::new).collect();
        let bases: Vec<Judged> = runs
            .iter()
            .map(|r| umbra_ref::render_judged(r, ClipDepth::MinusOneToOne, Profile::GL))
            .collect();
        let mut table = String::new();
        for (i, basis) in bases.iter().enumerate() {
            let (own, _) = judge(basis, &basis.frame);
            assert_eq!(own.illegal, 0, "{}", runs[i].point.id());
            for (j, other) in bases.iter().enumerate().filter(|(j, _)| *j != i) {
                let (a, _) = judge(basis, &other.frame);
                table += &format!(
                    "{} judged as {}: {} illegal px\n",
                    runs[j].point.id(),
                    runs[i].point.id(),
                    a.illegal
                );
                assert!(
                    a.illegal > 0,
                    "{} passes as {}:\n{table}",
                    runs[j].point.id(),
                    runs[i].point.id()
                );
            }
        }
        println!("{table}");
    }
}
