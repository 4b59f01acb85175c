//! The shadow pass: depth of every triangle as seen from each light face, into a map of the
//! case's format.
//!
//! Per fragment: window depth (linear in screen space) + polygon offset
//! o = m·factor + r·units (m = max |∂z/∂x|, |∂z/∂y|; r from [`DepthFormat::offset_unit`]),
//! signed away from the light by the depth order and limited by the clamp if one is given;
//! then clamped to the depth range [0,1], converted to the format and depth-tested (LESS
//! forward, GREATER reversed) against the stored value in the format's own precision.
//!
//! A judged render also computes, per texel, the range of values *any* conformant
//! implementation may store there ([`DepthLayer::lo`], [`DepthLayer::hi`]); see
//! [`Freedom`] for each term and the clause it comes from. The spec's range is computed
//! first; a driver's modelled deviations (a profile that names one) then widen it, each in
//! one function of one block (`Freedom::deviant_unit`, `deviant_offset`, `deviant_stored`).

use glam::Vec4;
use umbra_case::format::{DepthFormat, Shadow};
use umbra_case::{Convention, Geometry, Profile};

use crate::bands::for_each_band;
use crate::raster::{Chord, Coverage, EdgeKind, Rasterizer, Tri};

pub use crate::raster::SNAP_PX;

/// Under [`umbra_case::Deviation::EdgeHoles`], how near a clip fan's diagonal a centre must
/// lie to fall out of both its triangles: well beyond a float span end's rounding (an ULP at
/// a 16k-texel map is 1/512 px).
const HOLE_PX: f64 = 1.0 / 64.0;

/// One rendered face: stored depth per texel, in raster row order (row 0 = window y 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DepthLayer {
    /// Stored values, `width * height`.
    pub values: Vec<f32>,
    /// Judged renders only (else empty): per texel, the smallest window depth a conformant
    /// implementation may store there (rounded down to f32).
    pub lo: Vec<f32>,
    /// Judged renders only: the largest (rounded up to f32).
    pub hi: Vec<f32>,
    /// Judged renders only: whether the range reaches a surface that only *may* cover the
    /// texel (coverage freedom) rather than only depth freedom of the ones that do.
    pub maybe: Vec<bool>,
}

/// The freedom of a stored depth, per candidate triangle and texel centre (docs/platform.md):
///
/// - **Vertex snapping** ([`SNAP_PX`]): the depth plane at the centre moves by up to
///   (|∂z/∂x| + |∂z/∂y|)·δ·Σ|bᵢ|, and the slopes m is made of by up to
///   (|∂z/∂x| + |∂z/∂y|)·2δ/h (h the smallest altitude, in pixels).
/// - **Transform**: each corner's window depth as another implementation computes it
///   ([`depth_error`]: the clip rows' dot products, the divide and the viewport, absolute in
///   the magnitudes they cancel, for GL's clip convention and a [0, 1] one), carried to the
///   centre by the weights; and the interpolation's own roundings, 4 ULP(z).
/// - **Polygon offset, one-sided**: m may be the specs' sqrt(∂x² + ∂y²) or the allowed
///   max(|∂x|, |∂y|) (ours: max), and r ∈ [2⁻ⁿ, 2·2⁻ⁿ] for fixed point (ours: one step) and
///   fixed for float ([`DepthFormat::offset_unit_range`]): a conformant offset lies between
///   the smallest and the largest of m·factor + r·units, clamped like ours.
/// - **Depth range**: fixed-point stores clamp to [0,1]; a float attachment keeps the value
///   (Vulkan "Depth Clamping and Range") or clamps it (GL): both. Under depth clamp
///   (`shadow.depth_clamp`) both APIs clamp every format, after the offset.
/// - **Storage**: fixed point may round to either neighbouring code
///   ([`DepthFormat::code_range`]); float stores the value.
/// - **Clip fans under a card**: a card's sub-pixel reading narrows the snapping to the
///   driver's grid, which holds for the triangles umbra sets up. A clipper without a guard
///   band (Mesa's draw module where it clips at the viewport) fans a triangle crossing the
///   viewport into pieces from a vertex of its own choosing
///   ([`Rasterizer::viewport_chords`]); a piece along a chord can be a sliver a few hundredths
///   of a pixel wide, and llvmpipe derives its plane and its offset slope in f32 from the
///   piece's float corners (`lp_state_setup.c`), an error of about an ULP of z per sliver
///   width in the gradient. soak-45-501 (no offset: five texels along a chord, 3.7–4.7·10⁻⁶
///   above the plane every neighbour matches to 3·10⁻⁷) and soak-42-467 (one texel 0.01 px
///   from a chord, the offset slope 3 % over the triangle's) are such slivers on gl33/llvmpipe.
///   A piece covering a centre that lies farther than the spec's snapping from every chord is
///   at least about that wide, so within [`SNAP_PX`] of a chord the card keeps the spec's
///   snapping for the stored depth and the offset; coverage keeps the card's.
///
/// The GLES 2 path ([`Profile::packed_depth`]) applies umbra's own offset formula in the
/// shader (m from dFdx/dFdy: the differences of two f32 depths, ±2 ULP(z) per pixel; r fixed),
/// packs the offset depth into RGBA8 with error ≤ u·d·(1 + 1/254) + 255⁻⁴ each way (see
/// `umbra-gl`'s packing), and its depth test runs on a 16-bit buffer for depth16 and a 24-bit
/// one otherwise (`umbra-gl`'s `es2_depth`): the nearest surface may lose to one within a step
/// of that buffer.
///
/// Over candidates: the stored value is the nearest of what covers the texel. Every triangle
/// that certainly covers the centre competes; one that only may cover it (within δ of an
/// open edge, or of a vertex) may or may not; near an edge two triangles share, when both are
/// near it and neither near a boundary of its own, exactly one of them covers it (the edge
/// moves as a whole, and the tie rule is the implementation's), so their depths differ there
/// by the polygon offsets of two slopes. So the nearest possible value is the
/// nearest lower bound over all of them, and the farthest possible is the nearest of the
/// certain ones' upper bounds and the farthest upper bound of a shared-edge pair (the clear
/// value when neither covers).
#[derive(Clone, Copy, Debug)]
pub struct Freedom {
    conv: Convention,
    format: DepthFormat,
    factor: f64,
    units: f64,
    clamp: f64,
    depth_clamp: bool,
    packed: bool,
    deviations: umbra_case::Deviations,
    calibration: umbra_case::Calibration,
}

impl Freedom {
    /// The freedom of `shadow`'s pass for an implementation of `profile`.
    pub fn new(conv: Convention, shadow: &Shadow, profile: Profile) -> Freedom {
        let [factor, units] = shadow.bias.polygon_offset;
        Freedom {
            conv,
            format: shadow.format,
            factor: f64::from(factor),
            units: f64::from(units),
            clamp: f64::from(shadow.bias.polygon_offset_clamp),
            depth_clamp: shadow.depth_clamp,
            packed: profile.packed_depth,
            deviations: profile.deviations,
            calibration: profile.calibration,
        }
    }

    /// The smallest and largest offset (a distance away from the light) for triangle `t`.
    fn offset(&self, t: &Tri) -> (f64, f64) {
        if self.factor == 0.0 && self.units == 0.0 {
            return (0.0, 0.0);
        }
        let (dx, dy) = t.depth_slopes();
        let m_max = dx.abs().max(dy.abs());
        let snap = (dx.abs() + dy.abs()) * 2.0 * t.reach() / t.min_altitude().max(1e-9);
        let z = t.max_abs_z();
        let (m_lo, m_hi, r_lo, r_hi) = if self.packed {
            // umbra's GLES 2 shader: m = max(|dFdx z|, |dFdy z|), r = one step of the format.
            let diff = 2.0 * f64::from(umbra_case::depth::f32_spacing(z));
            let r = f64::from(self.format.offset_unit(0.0));
            ((m_max - snap - diff).max(0.0), m_max + snap + diff, r, r)
        } else {
            let c = self.calibration;
            // The unit's range: the spec's (a card may narrow it), then a deviation's.
            let spec = c.offset_unit(self.format, self.format.offset_unit_range(z));
            let (r_lo, r_hi) = self.deviant_unit(spec);
            let exact = umbra_case::math::hypot(dx, dy);
            // The slope form a card read picks one end: max, or the exact gradient.
            let (m_lo, m_hi) = match c.slope {
                None => (m_max, exact),
                Some(umbra_case::calibration::SlopeForm::Max) => (m_max, m_max),
                Some(umbra_case::calibration::SlopeForm::Exact) => (exact, exact),
            };
            ((m_lo - snap).max(0.0), m_hi + snap, r_lo, r_hi)
        };
        let ends = |a: f64, b: f64, k: f64| {
            let (x, y) = (a * k, b * k);
            (x.min(y), x.max(y))
        };
        let (fm_lo, fm_hi) = ends(m_lo, m_hi, self.factor);
        let (ur_lo, ur_hi) = ends(r_lo, r_hi, self.units);
        let (mut lo, mut hi) = (fm_lo + ur_lo, fm_hi + ur_hi);
        if self.clamp > 0.0 {
            (lo, hi) = (lo.min(self.clamp), hi.min(self.clamp));
        } else if self.clamp < 0.0 {
            (lo, hi) = (lo.max(self.clamp), hi.max(self.clamp));
        }
        // The spec's offset, then what a modelled deviation adds to it.
        self.deviant_offset(t, (lo, hi))
    }

    /// The range of stored values triangle `t` may leave at a centre with edge values `e`.
    fn stored(&self, t: &Tri, e: [i64; 3], offset: (f64, f64)) -> (f64, f64) {
        let z = t.depth_at(e);
        let (dx, dy) = t.depth_slopes();
        let norm = t.weight_norm(e);
        // The plane's snapping and its corners' transform ([`depth_error`]), carried to the
        // centre by the weights, and the interpolation's own roundings of z.
        let err = (dx.abs() + dy.abs()) * t.reach() * norm
            + t.depth_error_at(e)
            + 4.0 * f64::from(umbra_case::depth::f32_spacing(z as f32));
        let away = f64::from(self.conv.toward_far());
        let (o1, o2) = (away * offset.0, away * offset.1);
        let (lo, hi) = (z - err + o1.min(o2), z + err + o1.max(o2));
        if self.packed {
            let pack = |d: f64| 2f64.powi(-24) * d.abs() * (1.0 + 1.0 / 254.0) + 255f64.powi(-4);
            let (lo, hi) = (lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0));
            // The pass's depth test (a 16-bit renderbuffer for depth16, 24-bit otherwise:
            // umbra-gl's es2_depth) may keep a surface up to one step behind the nearest.
            let bits = if self.format == DepthFormat::Depth16 {
                16
            } else {
                24
            };
            let step = 1.0 / f64::from((1u32 << bits) - 1);
            return (lo - pack(lo) - step, hi + pack(hi) + step);
        }
        // The spec's value, then what a modelled deviation adds to it, before the format
        // stores it.
        let (lo, hi) = self.deviant_stored(t, e, err, (o1, o2), (lo, hi));
        // Depth clamp clamps every format's value on both APIs (GL 4.6, "Depth Buffer Test":
        // to the depth range; Vulkan, "Depth Clamping and Range Adjustment": to the
        // viewport's).
        let (lo, hi) = if self.format.is_fixed() || self.depth_clamp {
            (lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0))
        } else {
            (lo.min(lo.clamp(0.0, 1.0)), hi.max(hi.clamp(0.0, 1.0)))
        };
        self.format
            .code_range_rounded(lo, hi, self.calibration.rounding_of(self.format))
    }
}

/// The modelled deviations ([`umbra_case::Deviation`]), in one place: each takes a range the
/// spec gave (above) and widens it by what the driver is known to do outside it, for a
/// profile that names the deviation; without one, each returns the range it was given.
impl Freedom {
    /// The offset unit's range `spec`, widened by `OffsetUnitX4`: the deviation's unit, where
    /// the format has codes (module note of Deviation).
    fn deviant_unit(&self, spec: (f64, f64)) -> (f64, f64) {
        let (lo, mut hi) = spec;
        if self.deviations.has(umbra_case::Deviation::OffsetUnitX4) {
            if let Some(n) = self.format.fixed_bits() {
                hi = hi.max(4.0 / f64::from((1u32 << n) - 1));
            }
        }
        (lo, hi)
    }

    /// Triangle `t`'s offset range `spec`, widened by `OffsetVertexClamp`: a vertex whose
    /// offset depth leaves [0, 1] keeps none of it; the fragments between keep part:
    /// anything from no offset to the whole.
    fn deviant_offset(&self, t: &Tri, spec: (f64, f64)) -> (f64, f64) {
        let (mut lo, mut hi) = spec;
        if self
            .deviations
            .has(umbra_case::Deviation::OffsetVertexClamp)
        {
            let away = f64::from(self.conv.toward_far());
            let leaves = t.z.iter().any(|&z| {
                let moved = f64::from(z) + away * hi;
                !(0.0..=1.0).contains(&moved)
            });
            if leaves {
                (lo, hi) = (lo.min(0.0), hi.max(0.0));
            }
        }
        (lo, hi)
    }

    /// The range `spec` of values triangle `t` may leave at a centre with edge values `e`
    /// (its own freedom `err`, its offsets `o`), before the format stores it, widened by the
    /// deviations of the stored value.
    fn deviant_stored(
        &self,
        t: &Tri,
        e: [i64; 3],
        err: f64,
        o: (f64, f64),
        spec: (f64, f64),
    ) -> (f64, f64) {
        let (mut lo, mut hi) = spec;
        if self.depth_clamp
            && (self.factor != 0.0 || self.units != 0.0)
            && self
                .deviations
                .has(umbra_case::Deviation::OffsetVertexClamp)
        {
            // The deviation's per-vertex SATURATE(z + offset) under depth clamp: a vertex in
            // front of the near plane (z < 0, unclipped) is moved to 0 itself, so the plane
            // between the clamped corners is what the pass interpolates; as wide as the
            // corners' own freedom around it.
            let a = t.area as f64;
            for o in [o.0, o.1] {
                let v: f64 = (0..3)
                    .map(|i| e[i] as f64 / a * (f64::from(t.z[i]) + o).clamp(0.0, 1.0))
                    .sum();
                (lo, hi) = (lo.min(v - err), hi.max(v + err));
            }
        }
        if self.deviations.has(umbra_case::Deviation::Z16SpanStep)
            && self.format.fixed_bits() == Some(16)
        {
            // Up to 30 pixels of the truncated step's lost fraction, the depth lagging
            // behind its slope along x (module note of the deviation).
            let (dx, _) = t.depth_slopes();
            let steps = dx.abs() * 65535.0;
            let lag = 30.0 * (steps - steps.floor()) / 65535.0;
            if dx > 0.0 {
                lo -= lag;
            } else {
                hi += lag;
            }
        }
        (lo, hi)
    }
}

/// Renders one light face with view-projection `light`; with `judged` (the edge kinds of
/// this view and the profile judged for), also the freedom of every texel.
pub fn render_face(
    conv: Convention,
    shadow: &Shadow,
    light: glam::Mat4,
    geo: &Geometry,
    judged: Option<(&[[EdgeKind; 3]], Profile)>,
) -> DepthLayer {
    let [w, h] = shadow.size;
    let raster = Rasterizer {
        conv,
        width: w,
        height: h,
        cull: shadow.cull,
        depth_clamp: shadow.depth_clamp,
    };
    let mut tris = setup_all(&raster, light, geo, judged.map(|j| j.0));
    // The GLES 2 path stores the offset depth itself (packed to about 32 bits), not a code.
    let packed = judged.is_some_and(|j| j.1.packed_depth);
    let values = stored_values(conv, shadow, &tris, packed);
    let Some((_, profile)) = judged else {
        return DepthLayer {
            values,
            ..Default::default()
        };
    };
    // A card's sub-pixel reading narrows how far another rasterizer's vertices may lie.
    let snap = profile.calibration.snap_px(SNAP_PX);
    for t in &mut tris {
        t.snap = snap;
    }
    let freedom = Freedom::new(conv, shadow, profile);
    let fans = Fans::new(&raster, light, geo, profile, snap);
    let forward = conv.toward_far() > 0.0;
    let clear = f64::from(conv.clear_depth());
    let start = Acc {
        near: clear,
        far_certain: None,
        far_pair: None,
        uncertain: false,
    };
    let mut acc = vec![start; (w * h) as usize];
    let nearer = |a: f64, b: f64| if forward { a.min(b) } else { a.max(b) };
    let farther = |a: f64, b: f64| if forward { a.max(b) } else { a.min(b) };
    let is_nearer = |a: f64, b: f64| if forward { a < b } else { a > b };
    for_each_band(
        &mut acc,
        w as usize,
        1,
        &tris,
        true,
        |rows, band, touching| {
            // Pair visits waiting for their partner, per texel of the band: (this triangle,
            // the partner, this one's farthest value). A pair guarantees coverage only when both
            // members are near their shared edge (neither near a boundary of its own).
            let mut pending: std::collections::HashMap<usize, Vec<(u32, u32, f64)>> =
                std::collections::HashMap::new();
            for (_, t) in touching {
                let offset = freedom.offset(t);
                let spec = fans.at_spec_snapping(t, &freedom);
                t.scan_near(rows.clone(), t.reach(), |x, y, e, coverage| {
                    let coverage = fans.coverage(t, x, y, e, coverage);
                    let (lo, hi) = match &spec {
                        Some((wide, o)) if fans.near(t.source, x, y, SNAP_PX) => {
                            freedom.stored(wide, e, *o)
                        }
                        _ => freedom.stored(t, e, offset),
                    };
                    let (near, far) = if forward { (lo, hi) } else { (hi, lo) };
                    let i = (y - rows.start) as usize * w as usize + x as usize;
                    let a = &mut band[i];
                    if is_nearer(near, a.near) {
                        a.near = near;
                        a.uncertain = coverage != Coverage::Certain;
                    }
                    match coverage {
                        Coverage::Certain => {
                            a.far_certain = Some(a.far_certain.map_or(far, |f| nearer(f, far)));
                        }
                        Coverage::Pair(partner) => {
                            let list = pending.entry(i).or_default();
                            match list
                                .iter()
                                .position(|(me, p, _)| *me == partner && *p == t.source)
                            {
                                Some(k) => {
                                    let (_, _, other) = list.swap_remove(k);
                                    let worst = farther(far, other);
                                    a.far_pair =
                                        Some(a.far_pair.map_or(worst, |f| farther(f, worst)));
                                }
                                None => list.push((t.source, partner, far)),
                            }
                        }
                        Coverage::Maybe => {}
                    }
                });
            }
        },
    );
    let mut lo = Vec::with_capacity(acc.len());
    let mut hi = Vec::with_capacity(acc.len());
    let mut maybe = Vec::with_capacity(acc.len());
    for a in acc {
        let (near, by_maybe) = (a.near, a.uncertain);
        let far = match (a.far_certain, a.far_pair) {
            (Some(c), Some(p)) => nearer(c, p),
            (Some(f), None) | (None, Some(f)) => f,
            (None, None) => clear,
        };
        let far = nearer(far, clear);
        let (a, b) = if forward { (near, far) } else { (far, near) };
        lo.push(down(a));
        hi.push(up(b));
        maybe.push(by_maybe);
    }
    DepthLayer {
        values,
        lo,
        hi,
        maybe,
    }
}

/// Per texel while a face is judged: the nearest possible value, the farthest possible over
/// the certain coverers and over shared-edge pairs (None = none yet), and whether the nearest
/// comes from a triangle that is not certain to cover.
#[derive(Clone, Copy)]
struct Acc {
    near: f64,
    far_certain: Option<f64>,
    far_pair: Option<f64>,
    uncertain: bool,
}

/// Where a clipper without a guard band may fan each source triangle ([`hole_chords`]), for
/// the two things that depend on it: the edge-holes deviation's coverage, and a card's depth
/// beside a chord ([`Freedom`], "Clip fans under a card"). Empty when neither applies.
struct Fans {
    chords: Vec<Vec<Chord>>,
    holes: bool,
    narrowed: bool,
}

impl Fans {
    fn new(
        raster: &Rasterizer,
        light: glam::Mat4,
        geo: &Geometry,
        profile: Profile,
        snap: f64,
    ) -> Fans {
        let holes = profile.deviations.has(umbra_case::Deviation::EdgeHoles);
        let narrowed = snap < SNAP_PX;
        let chords = if holes || narrowed {
            hole_chords(raster, light, geo)
        } else {
            Vec::new()
        };
        Fans {
            chords,
            holes,
            narrowed,
        }
    }

    /// Whether the centre of (x, y) lies within `delta_px` of a chord of triangle `source`.
    fn near(&self, source: u32, x: i32, y: i32, delta_px: f64) -> bool {
        self.chords
            .get(source as usize)
            .is_some_and(|c| c.iter().any(|c| c.near(x, y, delta_px)))
    }

    /// Triangle `t` at the spec's snapping and its offset range, where a card narrowed it and
    /// a chord crosses it: what centres beside a chord are held to.
    fn at_spec_snapping(&self, t: &Tri, freedom: &Freedom) -> Option<(Tri, (f64, f64))> {
        let crossed = self
            .chords
            .get(t.source as usize)
            .is_some_and(|c| !c.is_empty());
        (self.narrowed && crossed).then(|| {
            let wide = Tri {
                snap: SNAP_PX,
                ..*t
            };
            (wide, freedom.offset(&wide))
        })
    }

    /// Holes on edges (the deviation): a shared edge's centres, and those on a clip fan's
    /// diagonal, only may be covered.
    fn coverage(&self, t: &Tri, x: i32, y: i32, e: [i64; 3], coverage: Coverage) -> Coverage {
        match coverage {
            Coverage::Pair(_) if self.holes => Coverage::Maybe,
            Coverage::Certain
                if self.holes
                    && (t.near_internal(e, HOLE_PX) || self.near(t.source, x, y, HOLE_PX)) =>
            {
                Coverage::Maybe
            }
            c => c,
        }
    }
}

/// Per source triangle of `geo` seen through `light`: where a clipper without a guard band
/// may put its fan's diagonals ([`Rasterizer::viewport_chords`]), besides the ones umbra's
/// own clipper puts there.
fn hole_chords(raster: &Rasterizer, light: glam::Mat4, geo: &Geometry) -> Vec<Vec<Chord>> {
    geo.triangles
        .iter()
        .map(|t| raster.viewport_chords(t.map(|k| light * geo.positions[k as usize].extend(1.0))))
        .collect()
}

/// The shadow pass's stored values: every triangle of `tris` through the polygon offset, the
/// clamp, the format's store (`packed`: GLES 2's offset depth itself) and the depth test.
fn stored_values(conv: Convention, shadow: &Shadow, tris: &[Tri], packed: bool) -> Vec<f32> {
    let format = shadow.format;
    let [w, h] = shadow.size;
    let [factor, units] = shadow.bias.polygon_offset;
    let clamp = shadow.bias.polygon_offset_clamp;
    let sign = conv.toward_far();
    let mut values = vec![format.store(conv.clear_depth()); (w * h) as usize];
    // The format's store and the depth test, chosen once for the pass (each a few branch-free
    // operations, so that the per-span loop below vectorises).
    let max = format.fixed_bits().map(|n| f64::from((1u32 << n) - 1));
    let forward = conv.toward_far() > 0.0;
    for_each_band(
        &mut values,
        w as usize,
        1,
        tris,
        false,
        |rows, band, touching| {
            let mut depths = Vec::new();
            for (_, t) in touching {
                let offset = if factor != 0.0 || units != 0.0 {
                    polygon_offset(t, format, factor, units, clamp)
                } else {
                    0.0
                };
                let offset = f64::from(sign) * offset;
                t.scan_spans(rows.clone(), |span| {
                    let start = (span.y - rows.start) as usize * w as usize + span.x as usize;
                    let texels = &mut band[start..start + span.len];
                    span.depths(t, &mut depths);
                    match (packed, max) {
                        (true, _) => depth_test_run(texels, &depths, offset, forward, |z| z),
                        (false, Some(max)) => {
                            let inv = 1.0 / max;
                            depth_test_run(texels, &depths, offset, forward, |z| {
                                store_fixed(z, max, inv)
                            })
                        }
                        (false, None) => depth_test_run(texels, &depths, offset, forward, |z| z),
                    }
                });
            }
        },
    );
    values
}

/// One span's fragments through the offset, the clamp to the depth range, the format's
/// `store` and the depth test (LESS forward, GREATER reversed) against `texels`. It is the
/// inclusive functions' run too (`shadow.depth_func` LEQUAL, GEQUAL): they differ only where
/// the stored value equals the texel's, and replace it by itself.
#[inline(always)]
fn depth_test_run(
    texels: &mut [f32],
    depths: &[f32],
    offset: f64,
    forward: bool,
    store: impl Fn(f32) -> f32,
) {
    for (texel, &d) in texels.iter_mut().zip(depths) {
        let z = (f64::from(d) + offset) as f32;
        let stored = store(z.clamp(0.0, 1.0));
        let pass = if forward {
            stored < *texel
        } else {
            stored > *texel
        };
        *texel = if pass { stored } else { *texel };
    }
}

/// [`DepthFormat::store`] of a fixed-point format with largest code `max` = 2ⁿ − 1 (n ≤ 24)
/// and `inv` = 1/max rounded to f64, for `z` in [0, 1] or NaN, bit for bit: the code rounded
/// half up from a truncation, its sign kept as `round_nonneg_f64` keeps it, NaN staying NaN (a NaN fails every depth test, as the store's NaN does).
///
/// The store divides, code/max in f64 then to f32; this multiplies by `inv`, which gives the
/// same f32 for every code: code/max is never a dyadic rational (max is odd; codes 0 and max
/// aside, both exact), so it lies at least 2⁻⁵⁰ of itself from every f32 rounding midpoint,
/// while the product is within 2⁻⁵² of it. Both round to the same f32 (checked for every
/// code of D16 and D24 in the tests). Divisions were half of the pass's time.
#[inline(always)]
fn store_fixed(z: f32, max: f64, inv: f64) -> f32 {
    let x = f64::from(z) * max;
    // The truncation of x ≥ 0 (below 2²⁵ here) in f64 alone, so that it vectorises (`as i32`
    // saturates, which compiles to a scalar conversion and checks per lane): adding and
    // removing 2⁵² rounds x to an integer (exactly: the sum's ulp is 1), one less where that
    // rounded up. NaN stays NaN.
    const TWO52: f64 = 4_503_599_627_370_496.0;
    let r = (x + TWO52) - TWO52;
    let t = if r > x { r - 1.0 } else { r };
    let code = if x - t >= 0.5 { t + 1.0 } else { t.copysign(x) };
    let code = if x.is_nan() { x } else { code };
    (code * inv) as f32
}

/// The largest f32 not above `x`.
pub fn down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x { f.next_down() } else { f }
}

/// The smallest f32 not below `x`.
pub fn up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x { f.next_up() } else { f }
}

/// The polygon offset of a triangle, as a positive distance away from the light.
fn polygon_offset(t: &Tri, format: DepthFormat, factor: f32, units: f32, clamp: f32) -> f64 {
    let o = t.max_depth_slope() * f64::from(factor)
        + f64::from(format.offset_unit(t.max_abs_z())) * f64::from(units);
    if clamp > 0.0 {
        o.min(f64::from(clamp))
    } else {
        o
    }
}

/// Clip-space corners of every triangle under `view_proj`, set up in source order; `edges`
/// gives what lies across each source edge in this view (judged renders), else all open.
pub fn setup_all(
    raster: &Rasterizer,
    view_proj: glam::Mat4,
    geo: &Geometry,
    edges: Option<&[[EdgeKind; 3]]>,
) -> Vec<Tri> {
    let clip: Vec<Vec4> = geo
        .positions
        .iter()
        .map(|p| view_proj * p.extend(1.0))
        .collect();
    // Judged renders: per vertex, the clip z and w rows' terms (Σ|mᵢ·pᵢ| and how many are
    // non-zero), what bounds how far another implementation's transform of the same vertex
    // may land ([`depth_error`]).
    let rows: Vec<[Row; 4]> = if edges.is_some() {
        let m = view_proj.as_dmat4();
        geo.positions
            .iter()
            .map(|p| {
                let p4 = p.as_dvec3().extend(1.0);
                let row = |r: usize| {
                    let terms = (0..4).map(|k| m.col(k)[r] * p4[k]);
                    Row {
                        sum: terms.clone().map(f64::abs).sum(),
                        terms: terms.filter(|t| *t != 0.0).count() as u32,
                    }
                };
                [row(0), row(1), row(2), row(3)]
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut tris = Vec::with_capacity(geo.triangles.len());
    for (i, t) in geo.triangles.iter().enumerate() {
        let kinds = edges.map_or([EdgeKind::Open; 3], |e| e[i]);
        let first = tris.len();
        raster.setup(t.map(|k| clip[k as usize]), i as u32, kinds, &mut tris);
        if !rows.is_empty() {
            let src = t.map(|k| rows[k as usize]);
            for tri in &mut tris[first..] {
                let corners = [0, 1, 2].map(|v| corner_rows(&src, tri.weights[v]));
                tri.z_err = [0, 1, 2].map(|v| {
                    let [_, _, z, w] = corners[v];
                    depth_error(raster.conv, z, w, 1.0 / tri.inv_w[v], tri.z[v])
                });
                tri.xy_err = (0..3)
                    .map(|v| {
                        let [x, y, _, w] = corners[v];
                        xy_error(raster, x, y, w, 1.0 / tri.inv_w[v])
                    })
                    .fold(0.0, f64::max);
            }
        }
    }
    tris
}

/// The clip rows of a corner at `weights` on the source triangle's corners `src`: for an
/// original corner its own; for one the clipper made, the weighted sums of the source's and
/// the clipper's interpolation (a difference, a product and a sum) on top of their terms.
fn corner_rows(src: &[[Row; 4]; 3], weights: glam::DVec3) -> [Row; 4] {
    let lam = weights.abs();
    let clipped = lam.max_element() < 1.0;
    [0, 1, 2, 3].map(|r| Row {
        sum: lam.x * src[0][r].sum + lam.y * src[1][r].sum + lam.z * src[2][r].sum,
        terms: (0..3)
            .filter(|&k| lam[k] != 0.0)
            .map(|k| src[k][r].terms)
            .max()
            .unwrap_or(4)
            + if clipped { 3 } else { 0 },
    })
}

/// How far, in pixels, another implementation's window x and y of a corner with clip rows
/// `x_row`, `y_row`, `w_row` and clip w `w` may lie from ours through the transform alone
/// (the snapping is [`SNAP_PX`]): each of x_c, y_c and w_c within γₖ·Σ∣mᵢ·pᵢ∣ of the exact
/// value by either side, then the divide, in NDC units of the half-viewport (|x_ndc| taken up
/// to 4, the guard band the corners stay in). Negligible near the origin; in a scene 10⁴ m
/// away, whose rows cancel terms of that size, a vertex lands a good fraction of a texel off
/// and coverage along every edge is free that far (a soak of generated scenes found
/// wgpu-vk/lavapipe's maps covering texels beyond the snapping's reach there).
pub fn xy_error(raster: &Rasterizer, x_row: Row, y_row: Row, w_row: Row, w: f64) -> f64 {
    const U: f64 = 1.0 / 16_777_216.0;
    let gamma = |k: u32| f64::from(k) * U / (1.0 - f64::from(k) * U);
    let w = w.abs().max(1e-30);
    let px = |r: Row, half: f64| {
        2.0 * (gamma(r.terms) * r.sum + 4.0 * gamma(w_row.terms) * w_row.sum) / w * half
    };
    px(x_row, 0.5 * f64::from(raster.width)).max(px(y_row, 0.5 * f64::from(raster.height)))
}

/// One row of a vertex's clip transform: Σ|mₖ·pₖ| over its terms and how many are non-zero
/// (an axis-aligned light view has two or three, a rotated one four).
#[derive(Clone, Copy, Debug)]
pub struct Row {
    /// Σ|mₖ·pₖ|.
    pub sum: f64,
    /// Non-zero terms (each a rounding, and one more for each sum).
    pub terms: u32,
}

/// How far another implementation's window depth of a vertex may lie from ours, for a vertex
/// whose clip z and w rows are `z_row` and `w_row` ([`Row`]: the magnitudes the dot products
/// cancel), with clip w `w` and window depth `z` in convention `conv`.
///
/// Each of z_c and w_c is a dot product of an uploaded matrix row with (p, 1), rounded within
/// γₖ·Σ|mᵢ·pᵢ| of the exact value (k its non-zero terms, fused or not; GLSL 4.60 §4.7.1, Vulkan
/// "Precision and Operation of SPIR-V Instructions"), by ours and by theirs, so the two
/// differ by twice that; then the divide and the viewport transform, a few roundings of
/// z_ndc and z. The error is absolute in the sums, not relative to the depth: where they
/// cancel (a scene far from the origin; reversed depth's far values near 0 in GL's [−1, 1]
/// clip space, where ½·z_ndc + ½ loses the bits ½ holds) the depth keeps only the precision
/// of the terms. The judged render is in GL's clip convention and a [0, 1] API computes
/// z' = ½(z_c + w_c) with its own rounding and no ½ on the way to the window, so the bound is
/// the larger of the two (the [0, 1] one, about twice GL's, where nothing cancels).
pub fn depth_error(conv: Convention, z_row: Row, w_row: Row, w: f64, z: f32) -> f64 {
    const U: f64 = 1.0 / 16_777_216.0;
    let gamma = |k: u32| f64::from(k) * U / (1.0 - f64::from(k) * U);
    let w = w.abs().max(1e-30);
    let ulp = |x: f64| f64::from(umbra_case::depth::f32_spacing(x as f32));
    let z = f64::from(z);
    let window = |z_row: Row, ndc: f64, scale: f64| {
        let e_ndc =
            2.0 * (gamma(z_row.terms) * z_row.sum + ndc.abs() * gamma(w_row.terms) * w_row.sum) / w
                + 3.0 * ulp(ndc);
        scale * e_ndc + ulp(z)
    };
    // This convention's rows, and the other's: ½(z + w) and w, or 2·z' − w and w (its own
    // matrix, whose z row has terms where either of ours has).
    let (own, other) = match conv.clip {
        umbra_case::ClipDepth::MinusOneToOne => (
            window(z_row, 2.0 * z - 1.0, 0.5),
            window(
                Row {
                    sum: 0.5 * (z_row.sum + w_row.sum),
                    terms: (z_row.terms + w_row.terms).min(4),
                },
                z,
                1.0,
            ),
        ),
        umbra_case::ClipDepth::ZeroToOne => (
            window(z_row, z, 1.0),
            window(
                Row {
                    sum: 2.0 * z_row.sum + w_row.sum,
                    terms: (z_row.terms + w_row.terms).min(4),
                },
                2.0 * z - 1.0,
                0.5,
            ),
        ),
    };
    own.max(other)
}

/// The next level of a generated (averaged) mip chain: each texel the mean of the 2 × 2
/// stored depths of `prev` (a `size` map) above it, as a program's down-sampling shader
/// computes it (`0.25 * (a + b + c + d)` in f32, written as the fragment's depth and stored
/// in `format`). With `judged`, the range a conformant implementation may store: the mean of
/// the four ranges, widened by the sum's and the product's f32 roundings (3 ULP of a sum ≤ 4
/// and the scaling, below 2⁻²¹ absolute) and rounded out to the format's codes.
pub fn averaged(
    prev: &DepthLayer,
    size: [u32; 2],
    format: DepthFormat,
    judged: bool,
) -> DepthLayer {
    let [w, h] = size;
    let [nw, nh] = size.map(|n| (n / 2).max(1));
    let w = w as usize;
    let at = |i: usize, j: usize| {
        [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
            .map(|(a, b)| b.min(h as usize - 1) * w + a.min(w - 1))
    };
    let mut out = DepthLayer::default();
    for j in 0..nh as usize {
        for i in 0..nw as usize {
            let k = at(2 * i, 2 * j);
            let [a, b, c, d] = k.map(|k| prev.values[k]);
            out.values.push(format.store(0.25 * (a + b + c + d)));
            if judged {
                let lo: f64 = k.iter().map(|&k| f64::from(prev.lo[k])).sum::<f64>() * 0.25;
                let hi: f64 = k.iter().map(|&k| f64::from(prev.hi[k])).sum::<f64>() * 0.25;
                let e = 1.0 / f64::from(1u32 << 21);
                let (lo, hi) = format.code_range(lo - e, hi + e);
                out.lo.push(down(lo));
                out.hi.push(up(hi));
                out.maybe.push(k.iter().any(|&k| prev.maybe[k]));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pass's store is the format's, bit for bit, over every kind of depth it meets:
    /// the ends, −0, values on and next to code midpoints, a sweep of [0, 1], and NaN.
    #[test]
    fn the_inlined_store_is_the_formats() {
        for format in [
            DepthFormat::Depth16,
            DepthFormat::Depth24,
            DepthFormat::Unsized,
        ] {
            let bits = format.fixed_bits().expect("fixed point");
            let max = f64::from((1u32 << bits) - 1);
            let mut zs = vec![0.0f32, -0.0, 1.0, f32::MIN_POSITIVE, 1.0f32.next_down()];
            for k in 0..200_000u32 {
                let z = k as f32 / 200_000.0;
                zs.extend([z, z.next_up(), z.next_down()]);
            }
            for code in (0..(1u32 << bits)).step_by(97) {
                let mid = ((f64::from(code) + 0.5) / max) as f32;
                zs.extend([mid, mid.next_up(), mid.next_down()]);
            }
            for z in zs.into_iter().filter(|z| (0.0..=1.0).contains(z)) {
                assert_eq!(
                    store_fixed(z, max, 1.0 / max).to_bits(),
                    format.store(z).to_bits(),
                    "{format:?} {z:e}"
                );
            }
            assert!(
                store_fixed(f32::NAN, max, 1.0 / max).is_nan() && format.store(f32::NAN).is_nan()
            );
            // The product for the quotient, every code.
            let inv = 1.0 / max;
            for code in 0..(1u32 << bits) {
                let c = f64::from(code);
                assert_eq!(
                    ((c * inv) as f32).to_bits(),
                    ((c / max) as f32).to_bits(),
                    "{code}"
                );
            }
        }
    }

    /// soak-42-467 reduced to its sphere: gl33/llvmpipe stores 0.9755897 in one texel of face
    /// +z, 0.009 px from the diagonal two coplanar triangles share, where that triangle's fan
    /// at the viewport's edge puts a sliver (llvmpipe's value, read back on Mesa 22.3.6). Its
    /// card (max slope, 8 sub-pixel bits) held the texel to ≤ 0.97558814 before chords kept
    /// the spec's depth snapping; the spec's judgement always allowed it.
    #[test]
    fn a_card_keeps_the_specs_depth_beside_a_clip_fans_chord() {
        const CASE: &str = r#"{"name": "sphere", "about": "soak-42-467 reduced", "scene": {"objects": [{"sphere": {"center": [0.0, 0.0, 0.0], "radius": 1.22, "segments": 12, "color": [0.85, 0.85, 0.31], "transform": {"translate": [1.47, 1.22, 3.5], "rotate_deg": {"axis": [-0.4, -0.89, -0.47], "angle": -149.9}, "scale": 1.32}}}]},
            "camera": {"eye": [-1.64, 16.96, -10.47], "target": [-1.27, 1.4, -1.2], "up": [0.0, 1.0, 0.0], "fov_y_deg": 59.0, "near": 0.76, "far": 92.0, "size": [200, 150]},
            "light": {"point": {"position": [1.42, 6.22, -1.43], "near": 0.16, "far": 55.0}},
            "shadow": {"size": [512, 512], "format": "depth32f", "filter": "linear", "bias": {"polygon_offset": [3.2, 6.0]}, "cull": "front", "depth_func": "less_equal"}}"#;
        let point = umbra_case::load::load_str(CASE, std::path::Path::new("sphere.json"))
            .expect("the case")
            .remove(0);
        let run = umbra_case::Prepared::new(point).lights.remove(0);
        let clip = umbra_case::ClipDepth::MinusOneToOne;
        let mut card = Profile::GL;
        card.calibration.slope = Some(umbra_case::calibration::SlopeForm::Max);
        card.calibration.subpixel_bits = Some(8);
        let layers = crate::judged_layers(&run, clip, card);
        // Face +z, column 305, row 5 from the top: raster row 506.
        let k = 506 * 512 + 305;
        let (lo, hi) = (layers[4].lo[k], layers[4].hi[k]);
        let stored = 0.975_589_7f32;
        assert!(
            lo <= stored && stored <= hi,
            "{stored} outside the card's [{lo}, {hi}]"
        );
        // Away from the chords the card still narrows: the texel two columns over.
        let spec = crate::judged_layers(&run, clip, Profile::GL);
        let k = 506 * 512 + 303;
        assert!(
            layers[4].hi[k] - layers[4].lo[k] < 0.5 * (spec[4].hi[k] - spec[4].lo[k]),
            "card [{}, {}] against the spec's [{}, {}]",
            layers[4].lo[k],
            layers[4].hi[k],
            spec[4].lo[k],
            spec[4].hi[k]
        );
    }
}
