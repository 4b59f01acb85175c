//! The shadow lookup a lit-pass shader does, step by step, in f32 as a GPU would:
//!
//! 1. Normal offset: p' = p + normal_offset · n.
//! 2. Face: the light's only face, or the cube face of p' by major axis.
//! 3. Coordinate: (u, v, depth, w) with the bias matrix before or after the divide.
//! 4. Guard: w ≤ 0 (behind a perspective light) reads lit when the guard is on.
//! 5. Outside: `lit` reads lit when (u, v) leaves [0,1]² (cube faces never do: they clamp);
//!    `beyond_far: lit` reads lit when the depth lies beyond the far plane (> 1, reversed < 0),
//!    tested on the coordinate's depth before any shader bias, as tutorial code tests
//!    `projCoords.z > 1.0`.
//! 6. Reference: depth − (constant + slope bias + N·L bias) away from the light; clamped to [0,1] for a
//!    hardware compare on a fixed-point format (GL 3.3 §3.8.16, Vulkan "Depth Compare"),
//!    never for a manual compare or a float format. The slope bias is
//!    min(s · tan θ, max) with tan θ = sqrt(1 − c²)/c, c = N·L > 0 (0 where c ≤ 0), the
//!    algebraic form of tan(acos(c)): the same number, without acos and tan, whose GLSL and
//!    SPIR-V precision (4096 ULP, absolute 2⁻¹¹) would allow several D24 steps of bias. The
//!    N·L bias is max(s · (1 − c), min), LearnOpenGL's form, c unclamped; its L is the light
//!    direction, or with `light: position` the unit vector to the light's position (a
//!    directional light's eye), as LearnOpenGL writes it for its orthographic light.
//! 7. Filter: NEAREST texel floor(u·size); LINEAR = 2x2 at floor(u·size − ½) with bilinear
//!    weights of the compare results (never of depths); PCF N = N×N NEAREST compares at
//!    offsets (k − (N−1)/2) texels, averaged; Castano's filter = nine weighted LINEAR
//!    compares ([`castano_taps`]); the Vogel disk = five LINEAR compares around the point,
//!    rotated per pixel ([`vogel_taps`], [`vogel_rotation`]).
//! 8. Texels beyond the map: border (clear depth), clamp to edge (also for `lit`), or repeat.
//!    Cube faces: the sampler clamps to the face; taps the shader addresses itself go through
//!    the direction of their texel's centre, so a PCF tap beyond a face's edge reads the
//!    neighbouring face (hardware compare) while a manual fetch clamps its indices first.
//!
//! Manual compare uses the same texel selection and weights as hardware compare: the shader
//! fetches the texels and compares them itself, so the two differ only in the clamp of 6
//! and, on a cube, in where a PCF tap beyond a face's edge reads (8).
//!
//! **Judged lookups** ([`Lookup::judged`]) also return the interval of values any conformant
//! implementation of the given [`Profile`] may return there ([`Legal`]), dEQP-style: each
//! compare is possibly lit, possibly shadowed, or both, from the reference value's interval
//! against the texel's stored-value interval (`crate::shadow_pass::Freedom`); the filter then
//! combines the taps' possibilities with the weights the spec allows; and the lookup point
//! itself may move by [`position_freedom`], over which the interval is the hull.
//!
//! By concern: this file holds the lookup's types and the judged lookup's frame (the region
//! of lookup points, its faces); `steps` the plain lookup, step by step; `precision` the
//! arithmetic's reach (coordinate, depth, reference value); `filters` each filter's
//! interval; `addressing` where a tap reads and what its compare may answer; `mip` and
//! `cascades` the lookups of mipmapped maps and cascaded lights; `grid` a block of taps'
//! answers computed once.

use glam::{DVec2, Vec3};
use std::sync::atomic::{AtomicUsize, Ordering};
use umbra_case::format::{
    BeyondFar, BiasMatrix, Compare, Filter, LightVector, MipFilter, Outside, Shadow,
};
use umbra_case::light::Cascading;
use umbra_case::{Convention, LightKind, LightSetup, LookupMatrices, Profile, ShadowCoord, Spec};

use crate::rounding::{floor_f32, floor_i64};
use crate::shadow_pass::DepthLayer;
use crate::surface::Surfaces;

mod addressing;
mod cascades;
mod filters;
mod grid;
mod mip;
mod precision;
mod steps;
#[cfg(test)]
mod tests;
mod vogel;

use addressing::Addressing;
pub use filters::castano_taps;
use filters::span;
use grid::Grid;
pub use mip::Neighbours;
pub use vogel::{at_window, vogel_rotation, vogel_taps, window_of};

thread_local! {
    /// The trace of the lookup being explained on this thread (see [`explaining`]).
    static TRACE: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with this thread's lookups tracing every step, and returns its result and the
/// trace (for `umbra render --explain`).
pub fn explaining<T>(f: impl FnOnce() -> T) -> (T, String) {
    EXPLAINING.fetch_add(1, Ordering::Relaxed);
    TRACE.with(|t| *t.borrow_mut() = Some(String::new()));
    let out = f();
    let trace = TRACE.with(|t| t.borrow_mut().take()).unwrap_or_default();
    EXPLAINING.fetch_sub(1, Ordering::Relaxed);
    (out, trace)
}

/// How many threads are explaining: while none is, [`note`] returns at once instead of
/// looking up its thread's trace (a tenth of a judged render's time in its texel loops).
static EXPLAINING: AtomicUsize = AtomicUsize::new(0);

/// Appends a line to the trace when this thread is explaining.
fn note(line: impl FnOnce() -> String) {
    if EXPLAINING.load(Ordering::Relaxed) == 0 {
        return;
    }
    TRACE.with(|t| {
        if let Some(s) = t.borrow_mut().as_mut() {
            s.push_str(&line());
            s.push('\n');
        }
    });
}

/// The rendered shadow maps of a run and what a lookup needs to read them.
pub struct Lookup<'a> {
    /// Convention the maps were rendered in.
    pub conv: Convention,
    /// The technique.
    pub shadow: &'a Shadow,
    /// The light.
    pub light: &'a LightSetup,
    /// One matrix pair per face.
    pub matrices: Vec<LookupMatrices>,
    /// Per face, the matrix the bias-matrix order multiplies the point by, widened to f64 for
    /// the judged bounds (from [`Lookup::matrices`] by [`Lookup::widened`]).
    pub wide: Vec<glam::DMat4>,
    /// One layer per face.
    pub layers: &'a [DepthLayer],
    /// The case's reach, for the position freedom: the largest of the scene's extent and the
    /// camera's distance from the origin (per axis), and each light view's eye distance.
    pub reach: f32,
    /// The profile the legal intervals are computed for (judged renders).
    pub profile: Profile,
    /// A mipmapped map's levels, level 0 first, each a lookup of one level with no levels of
    /// its own (see [`Lookup::with_levels`]); empty for a map with one level.
    pub levels: Vec<Lookup<'a>>,
}

/// Why a pixel's legal interval is wider than one value (bit flags, kept per pixel).
pub mod ambiguity {
    /// A compared texel's stored value and the reference value are within their freedoms
    /// of each other (polygon offset, snapping, storage, arithmetic, the compare's own
    /// precision).
    pub const DEPTH_TIE: u8 = 1;
    /// The sampler's coordinate (4 sub-texel bits) may select another texel or footprint.
    pub const TEXEL_BOUNDARY: u8 = 2;
    /// Hardware LINEAR: the taps disagree and the spec leaves the weights open (GL: any
    /// weighting, NEAREST included; Vulkan: bilinear within 1/16).
    pub const FILTER: u8 = 4;
    /// Moving the lookup point by [`super::position_freedom`] or by the camera's vertex
    /// snapping changes the interval.
    pub const POSITION: u8 = 8;
    /// A compared texel may hold another surface: a triangle covers it or not within the
    /// vertex snapping's reach (the map's coverage freedom).
    pub const COVERAGE: u8 = 16;
    /// Hardware LINEAR at a cube corner, where the specs leave the result open.
    pub const SEAM: u8 = 32;
    /// The camera pixel itself may show another surface (set by the lit pass).
    pub const SURFACE: u8 = 64;
    /// A mipmapped lookup may read another level: the LOD's freedom
    /// ([`super::Lookup::lod_range`]) reaches it.
    pub const LOD: u8 = 128;
}

/// How a smooth surface's interpolated normal turns across a judged region: the two
/// world-space vectors it moves by when the camera's vertex snapping moves the surface under
/// the pixel by the snapping's reach along screen x and y (as the region's `snap` moves the
/// point). The turn frees two things: N·L, which the slope bias reads (its reach,
/// [`Turn::reach`]), and the normal-offset point p + n·o, which moves by o·Δn
/// ([`Turn::offset_moves`]). A flat face does not turn.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Turn(pub [Vec3; 2]);

impl Turn {
    /// No turn: a flat face, or a lookup judged at one point.
    pub const NONE: Turn = Turn([Vec3::ZERO; 2]);

    /// How far the normal may turn across the region: the sum of its moves' lengths.
    pub fn reach(&self) -> f32 {
        self.0[0].length() + self.0[1].length()
    }

    /// The moves of a point offset along the normal by up to `offset` (either sign): o·Δn
    /// along each of the turn's two directions.
    fn offset_moves(&self, offset: f32) -> [Vec3; 2] {
        [self.0[0] * offset, self.0[1] * offset]
    }
}

/// The values a conformant implementation may return for one lookup, before the target
/// stores them: any v in [lo, hi] that is a multiple of the case's quantum
/// ([`quantum`]), within the storage's tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Legal {
    /// Smallest legal value.
    pub lo: f32,
    /// Largest legal value.
    pub hi: f32,
    /// [`ambiguity`] flags: why the interval is wider than a point.
    pub flags: u8,
}

impl Legal {
    const LIT: Legal = Legal {
        lo: 1.0,
        hi: 1.0,
        flags: 0,
    };
    fn hull(self, o: Legal) -> Legal {
        Legal {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            flags: self.flags | o.flags,
        }
    }
}

/// The step between the values a filter can produce: NEAREST returns 0 or 1, PCF N sums of
/// N² results over N², LINEAR, Castano's filter and the Vogel disk anything (0); a blend of two mip levels
/// anything too, and so does a blend of two cascades (`light`'s blend band).
pub fn quantum(shadow: &Shadow, light: &LightSetup) -> f32 {
    // A band exists where there are two cascades or more.
    let blends_cascades = light
        .cascading
        .as_ref()
        .is_some_and(|c| c.blend > 0.0 && c.splits.len() > 2);
    if blends_cascades
        || shadow
            .mipmaps
            .is_some_and(|m| m.filter == MipFilter::Linear)
    {
        return 0.0;
    }
    match shadow.filter {
        Filter::Nearest => 1.0,
        Filter::Linear | Filter::Castano13 | Filter::Vogel5 => 0.0,
        Filter::Pcf(n) => 1.0 / (n * n) as f32,
    }
}

/// How far the point a backend looks up for a pixel may lie from the reference's, per world
/// axis, from f32 arithmetic the specs leave to the implementation:
/// - varying interpolation ("implementation-dependent" accuracy): barycentrics carry a few
///   ulps of relative error, and Σ bᵢ·aᵢ inherits it scaled by the vertex values (|p| plus
///   the triangle's spread, at most the reach), about 8u·(|p|∞ + reach);
/// - the camera and light transforms: V·p cancels |R·p| against the translation |t| ≈ the
///   eye's distance, so the fragment's position and its shadow coordinate each move by up to
///   γ₄·(|p|∞ + reach) in world units.
///
/// Together 16u·(|p|∞ + reach), u = 2⁻²⁴: about 0.1 mm for a 50 m scene at the origin, and
/// 10 cm at 1e5 m from it, which is why scenes far from the origin lose shadow detail on every
/// backend (numerics/far-from-origin shows how fast).
pub fn position_freedom(p: Vec3, reach: f32) -> f32 {
    16.0 * (f32::EPSILON * 0.5) * (p.abs().max_element() + reach)
}

/// How many times [`Lookup::judged`] halves the region of a lookup whose position matters
/// (each level four quarters, only where a quarter is still wider than its centre).
const SPLITS: u32 = 2;

/// Sub-texel precision the specs guarantee (4 bits): a sampler may select texels and weights
/// as if the coordinate were anywhere within 1/16 texel (Vulkan `subTexelPrecisionBits`,
/// GL's equivalent in the texture chapter's precision note).
const SUBTEXEL: f64 = 1.0 / 16.0;

/// Beyond this many texels of coordinate freedom a lookup's legal interval is taken as
/// [0, 1] rather than enumerated (far-from-origin scenes at 1e5 m and more).
const MAX_SPAN: f64 = 8.0;

/// u = 2⁻²⁴, the unit roundoff of f32.
const U: f64 = 1.0 / 16_777_216.0;

/// γₙ = n·u/(1 − n·u): the bound of an n-term f32 dot product's rounding, fused or not.
fn gamma(n: f64) -> f64 {
    n * U / (1.0 - n * U)
}

fn ulp(x: f64) -> f64 {
    f64::from(umbra_case::depth::f32_spacing(x as f32))
}

/// Where a lookup reads, before filtering.
#[derive(Clone, Copy)]
struct Setup {
    face: usize,
    c: ShadowCoord,
    /// The compare's reference value, as the shader computes it (clamped if the compare is).
    reference: f32,
}

/// What one compare may answer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Possible {
    lit: bool,
    shadow: bool,
    /// Both, and only through a surface that may or may not cover the texel.
    by_coverage: bool,
}

impl Possible {
    fn or(self, o: Possible) -> Possible {
        Possible {
            lit: self.lit || o.lit,
            shadow: self.shadow || o.shadow,
            by_coverage: self.by_coverage || o.by_coverage,
        }
    }
    fn min(self) -> f64 {
        if self.shadow { 0.0 } else { 1.0 }
    }
    fn max(self) -> f64 {
        if self.lit { 1.0 } else { 0.0 }
    }
    fn flags(self) -> u8 {
        match (self.lit && self.shadow, self.by_coverage) {
            (false, _) => 0,
            (true, false) => ambiguity::DEPTH_TIE,
            (true, true) => ambiguity::COVERAGE,
        }
    }
}

impl<'a> Lookup<'a> {
    /// The lookup of `run`'s lit pass in convention `conv` over the rendered `layers` (one per
    /// light face), its judged intervals for `profile`.
    pub fn new(
        run: &'a umbra_case::LightRun,
        conv: Convention,
        layers: &'a [DepthLayer],
        profile: Profile,
    ) -> Lookup<'a> {
        let shadow = &run.case().shadow;
        let matrices: Vec<LookupMatrices> = run
            .light
            .views
            .iter()
            .map(|v| LookupMatrices::new(conv, v.view_proj(conv)))
            .collect();
        let (lo, hi) = run.geometry.bounds();
        // The view's translation column is −R·eye: its length is the eye's distance.
        let eyes = run
            .light
            .views
            .iter()
            .map(|v| v.view.w_axis.truncate().length());
        let reach = eyes.fold(
            (hi - lo)
                .max_element()
                .max(run.camera.eye.abs().max_element()),
            f32::max,
        );
        Lookup {
            conv,
            shadow,
            light: &run.light,
            wide: Lookup::widened(&matrices, shadow.bias_matrix),
            matrices,
            layers,
            reach,
            profile,
            levels: Vec::new(),
        }
    }

    /// The lookup of a mipmapped map: `shadows[k]` is the technique at level k (its size,
    /// no levels), `below[k − 1]` the rendered (or averaged) layer of level k ≥ 1; level 0
    /// is this lookup's own layer.
    pub fn with_levels(mut self, shadows: &'a [Shadow], below: &'a [DepthLayer]) -> Lookup<'a> {
        let top = self.layers;
        self.levels = shadows
            .iter()
            .enumerate()
            .map(|(k, shadow)| Lookup {
                conv: self.conv,
                shadow,
                light: self.light,
                matrices: self.matrices.clone(),
                wide: self.wide.clone(),
                layers: if k == 0 { top } else { &below[k - 1..k] },
                reach: self.reach,
                profile: self.profile,
                levels: Vec::new(),
            })
            .collect();
        self
    }
}

impl Lookup<'_> {
    /// Whether the light is a point light: six cube faces, looked up by direction.
    fn cube(&self) -> bool {
        self.light.is_cube()
    }

    /// Whether the compare is the sampler's (a depth-compare sampler on a depth texture); the
    /// packed-depth profile's colour target is always compared by the shader.
    fn hardware(&self) -> bool {
        self.shadow.compare == Compare::Hardware && !self.profile.packed_depth
    }

    /// The shadow term and the values a conformant implementation of the profile may return
    /// instead, the lookup point anywhere in the zonotope of its moves: the arithmetic
    /// position freedom ([`position_freedom`], a box along the world axes) and `snap`, the
    /// two world-space vectors the point moves by when the camera's vertex snapping moves the
    /// surface under the pixel by the snapping's reach along screen x and y (the point is then
    /// anywhere in the parallelogram they span), and `turn`, the normal's turn across that
    /// region, which swings the normal-offset point and frees N·L. See [`Lookup::legal_at`]
    /// for how a region of points is judged as a whole.
    pub fn judged(&self, p: Vec3, n: Vec3, snap: [Vec3; 2], turn: Turn) -> (f32, Legal) {
        let vis = self.visibility(p, n);
        let d = position_freedom(p, self.reach) + self.offsets_reach() * 16.0 * f32::EPSILON;
        let arithmetic = [Vec3::X * d, Vec3::Y * d, Vec3::Z * d];
        let here = self.legal_at(p, n, &arithmetic, 0.0);
        let [sx, sy] = snap;
        let [tx, ty] = turn.offset_moves(self.normal_offsets_reach());
        let moved = [arithmetic[0], arithmetic[1], arithmetic[2], sx, sy, tx, ty];
        note(|| {
            format!(
                "lookup at p = {p}, n = {n}: value {vis}, legal {here:?} with the arithmetic freedom {d} per axis; with the snapping's moves {snap:?} and the normal offset's turn {:?} too:",
                [tx, ty]
            )
        });
        let mut all = self.legal_at(p, n, &moved, turn.reach());
        if (all.lo, all.hi) != (here.lo, here.hi) {
            // The region judged as a whole decouples what varies together across it (the
            // weights, the texel, the reference value); its quarters, each judged the same
            // way, still cover it, and their hull is as sound and often narrower.
            all = self
                .legal_split(p, n, &arithmetic, [sx, sy], turn, SPLITS)
                .unwrap_or(all);
        }
        note(|| format!("hull: {all:?}"));
        if (all.lo, all.hi) != (here.lo, here.hi) {
            all.flags |= ambiguity::POSITION;
        }
        (vis, all)
    }

    /// The hull of [`Lookup::legal_at`] over the four quarters of the parallelogram `snap`
    /// spans around `p` (each with the arithmetic moves too), split again `depth − 1` times
    /// where a quarter's interval is still wider than its centre's; never `None` (there are
    /// always four quarters).
    pub(super) fn legal_split(
        &self,
        p: Vec3,
        n: Vec3,
        arithmetic: &[Vec3; 3],
        snap: [Vec3; 2],
        turn: Turn,
        depth: u32,
    ) -> Option<Legal> {
        let [sx, sy] = [snap[0] * 0.5, snap[1] * 0.5];
        // Each quarter keeps the whole turn: its normals lie within it.
        let [tx, ty] = turn.offset_moves(self.normal_offsets_reach());
        let mut out: Option<Legal> = None;
        for c in [p + sx + sy, p + sx - sy, p - sx + sy, p - sx - sy] {
            let moves = [arithmetic[0], arithmetic[1], arithmetic[2], sx, sy, tx, ty];
            let mut l = self.legal_at(c, n, &moves, turn.reach());
            if depth > 1 && l.lo < l.hi {
                let centre = self.legal_at(c, n, arithmetic, 0.0);
                if (centre.lo, centre.hi) != (l.lo, l.hi) {
                    l = self
                        .legal_split(c, n, arithmetic, [sx, sy], turn, depth - 1)
                        .unwrap_or(l);
                }
            }
            out = Some(out.map_or(l, |o| o.hull(l)));
        }
        out
    }

    /// The legal interval over a region of lookup points: `p` moved by any a₁·m₁ + … + aₖ·mₖ
    /// with every |aᵢ| ≤ 1, the zonotope of `moves`. At that scale the coordinate, the
    /// reference value and w are affine in the point, so each ranges over the centre's value
    /// ± Σ |its change along mᵢ| (measured by moving the point), and the region is judged as
    /// a whole: every texel within the coordinate's range, every tap possibly lit and
    /// shadowed where the reference value's range straddles its stored range, every weight
    /// within the coordinate's range, each independently of the others. That bounds the
    /// value at every point of the region, not just at its corners: a LINEAR or PCF value is
    /// a product of weights and decisions that each change across the region, so its extreme
    /// can lie inside it, where a tap's decision flips after the weights have moved (hulling
    /// the centre and the corners missed those, and failed correct drivers on generated
    /// scenes: the soak's largest class). The guard (w ≤ 0) and the `lit` outside test are
    /// undecided when w or (u, v) lie within that reach of their bound. Where the region
    /// reaches another cube face, each face's share is judged in that face's projection and
    /// the intervals are hulled. Across the region the normal turns by up to `turn` (see
    /// [`Lookup::reference_range`]); a cascaded light's interval is
    /// [`Lookup::legal_cascaded`]'s.
    pub(super) fn legal_at(&self, p: Vec3, n: Vec3, moves: &[Vec3], turn: f32) -> Legal {
        if let Some(c) = &self.light.cascading {
            return self.legal_cascaded(c, p, n, moves, turn);
        }
        let face = self.probe(p, n).0;
        let mut faces = vec![face];
        if self.cube() {
            for m in moves {
                for q in [p + *m, p - *m] {
                    let f = self.probe(q, n).0;
                    if !faces.contains(&f) {
                        faces.push(f);
                    }
                }
            }
        }
        let mut out: Option<Legal> = None;
        for f in faces {
            let l = self.legal_on(p, n, moves, turn, f);
            out = Some(out.map_or(l, |o| o.hull(l)));
        }
        out.unwrap_or(Legal::LIT)
    }

    /// [`Lookup::legal_at`] on face `face` (the only face of a 2D map).
    pub(super) fn legal_on(
        &self,
        p: Vec3,
        n: Vec3,
        moves: &[Vec3],
        turn: f32,
        face: usize,
    ) -> Legal {
        let s = self.shadow;
        let (c, raw) = self.probe_on(p, n, face);
        let (mut du, mut dv, mut dr, mut dw) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut dz = 0.0f64;
        for m in moves {
            let (c2, r2) = self.probe_on(p + *m, n, face);
            du += f64::from((c2.u - c.u).abs());
            dv += f64::from((c2.v - c.v).abs());
            dr += f64::from((r2 - raw).abs());
            dw += f64::from((c2.w - c.w).abs());
            dz += f64::from((c2.depth - c.depth).abs());
        }
        // `beyond_far: lit`: the coordinate's depth free within its arithmetic and the
        // point's moves; beyond the far plane for all of them reads lit, for some of them
        // may.
        let (mut far_sure, mut far_maybe) = (false, false);
        if s.beyond_far == BeyondFar::Lit {
            let e = dz + self.depth_error(p, n, face, c.depth);
            let z = f64::from(c.depth);
            let (near_end, far_end) = if self.conv.toward_far() > 0.0 {
                (z - e, z + e)
            } else {
                (-(z + e), -(z - e))
            };
            let bound = if self.conv.toward_far() > 0.0 {
                1.0
            } else {
                0.0
            };
            far_sure = near_end > bound && self.beyond_far(c.depth);
            far_maybe = far_end > bound || self.beyond_far(c.depth);
        }
        let guard_maybe = s.guard_behind_light && f64::from(c.w) - dw <= 0.0;
        if s.guard_behind_light && f64::from(c.w) + dw <= 0.0 {
            note(|| "    behind the light: lit".into());
            return Legal::LIT;
        }
        let (u, v) = (f64::from(c.u), f64::from(c.v));
        let outside_maybe = self.outside_lit((u - du) as f32, v as f32)
            || self.outside_lit((u + du) as f32, v as f32)
            || self.outside_lit(u as f32, (v - dv) as f32)
            || self.outside_lit(u as f32, (v + dv) as f32);
        let corners_out = [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .iter()
            .all(|(a, b)| self.outside_lit((u + a * du) as f32, (v + b * dv) as f32));
        if corners_out && self.outside_lit(c.u, c.v) {
            note(|| "    outside the map: lit".into());
            return Legal::LIT;
        }
        if far_sure {
            note(|| "    beyond the far plane: lit".into());
            return Legal::LIT;
        }
        let mut reference = raw;
        if s.compare == Compare::Hardware && s.format.is_fixed() {
            reference = reference.clamp(0.0, 1.0);
        }
        let st = Setup { face, c, reference };
        let mut l = self.legal_taps(p, n, turn, &st, (du, dv, dr));
        if guard_maybe || outside_maybe || far_maybe {
            l = l.hull(Legal::LIT);
        }
        l
    }
}

/// A [`Legal`] of f64 bounds, rounded outward to f32.
fn legal(lo: f64, hi: f64, flags: u8) -> Legal {
    Legal {
        lo: crate::shadow_pass::down(lo),
        hi: crate::shadow_pass::up(hi),
        flags,
    }
}
