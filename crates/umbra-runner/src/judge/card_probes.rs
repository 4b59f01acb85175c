//! The probes behind a behaviour card ([`crate::judge::card`]): short renders, through the
//! backend's ordinary `render`, of scenes built so that one choice the specs leave to the
//! driver decides what the frame shows, and the arithmetic that reads the choice back.
//!
//! Every probe looks at one floor plane from straight above (a directional light at height
//! H = 4 over an orthographic ±2 m box of 32×32 texels, near 0, far F, so the floor's window
//! depth is H/F exactly in real arithmetic) and asks one question of its visibility:
//!
//! - **Thresholds.** Most probes move the stored depth towards the light by an amount `o` (a
//!   negative polygon offset, or the rounding of a depth that lies between two codes) and
//!   look for the least constant shader bias `b` at which the floor reads lit: the reference
//!   z − b meets the stored z − o where b = o. A bisection over `b` (each step one render)
//!   brackets the crossing of the floor's lit fraction through ½; the bracket is the
//!   measurement's resolution. So `o` is measured through the whole pipeline, as a program
//!   sees it, on every backend alike (GLES 2's packed depth and manual compare included),
//!   with no read-back of the depth texture (which GLES cannot do).
//! - **Levels.** The LINEAR probe counts the distinct visibility values across a shadow edge
//!   seen magnified (≈ 355 camera pixels per texel): bilinear weights of b bits give 2ᵇ − 1
//!   values strictly between 0 and 1.
//! - **One look.** The reference-clamp probe puts the floor beyond the light's far plane and
//!   reads whether the compare clamped its reference (lit) or not (shadowed).
//!
//! - **Edge.** The sub-pixel probe moves an occluder's edge across a texel centre and
//!   bisects the offset at which the centre's coverage flips: 2⁻⁽ᵇ⁺¹⁾ px for vertices snapped
//!   to b bits, about 0 for none.
//!
//! Probes are small (32×32, the LINEAR one 512×32) so that a card costs a few seconds on a
//! software rasterizer: about 265 renders in all, the sampler's probes
//! ([`crate::judge::card_sampler_probes`]: cube-face ties, border, LOD) included.

use std::path::Path;

use serde_json::{Value, json};
use umbra_case::format::DepthFormat;
use umbra_case::{Backend, Frame, Needs, Prepared, Support};

use crate::judge::card::{Entry, Sure};
use crate::judge::card_sampler_probes as sampler;

/// The light's height over the floor.
const H: f64 = 4.0;
/// Bisection steps per threshold: the bracket ends at 2⁻¹³ of the searched range.
const STEPS: u32 = 13;
/// Polygon-offset units of the offset-unit probe (negative: towards the light).
const UNITS: f64 = 64.0;
/// Polygon-offset factor of the slope probes (negative: towards the light).
const FACTOR: f64 = 16.0;
/// The slope probes' tilt: the floor's gradient in world height per world metre.
const TILT: f64 = 0.363_970_234_266_202_4; // tan 20°

/// A probe scene: the floor (flat, or tilted with gradient `tilt` along `diag`onal or x),
/// the light's far plane `far`, the depth format, polygon offset and constant bias.
#[derive(Clone, Copy)]
struct Scene {
    format: DepthFormat,
    far: f64,
    tilt: f64,
    diagonal: bool,
    offset: [f64; 2],
    bias: f64,
    linear_edge: bool,
    /// An occluder over x < the centre of texel column 16 + this many texels (the
    /// sub-pixel probe), seen on the floor beneath that column.
    edge: Option<f64>,
}

impl Scene {
    fn flat(format: DepthFormat, z0: f64) -> Scene {
        Scene {
            format,
            far: H / z0,
            tilt: 0.0,
            diagonal: false,
            offset: [0.0, 0.0],
            bias: 0.0,
            linear_edge: false,
            edge: None,
        }
    }

    /// The case, as JSON.
    fn case(&self) -> Value {
        let normal = if self.tilt == 0.0 {
            [0.0, 1.0, 0.0]
        } else if self.diagonal {
            let g = self.tilt / std::f64::consts::SQRT_2;
            [-g, 1.0, -g]
        } else {
            [-self.tilt, 1.0, 0.0]
        };
        let mut objects = vec![json!({ "plane": {
            "point": [0, 0, 0], "normal": normal, "half_extent": 4 } })];
        let (camera, filter) = if let Some(d) = self.edge {
            // Texel column 16's centre is x = 0.0625 m (window x 16.5); the occluder, 1 m up,
            // ends d texels (of 0.125 m) right of it; the camera, below it, sees the floor
            // inside that column only.
            let e = 0.0625 + d * 0.125;
            objects.push(json!({ "plane": {
                "point": [e - 2.0, 1, 0], "normal": [0, 1, 0], "half_extent": 2 } }));
            (
                json!({ "eye": [0.0625, 0.4, 0.3], "target": [0.0625, 0, 0], "up": [0, 1, 0],
                        "fov_y_deg": 6, "near": 0.05, "far": 10, "size": [32, 32] }),
                "nearest",
            )
        } else if self.linear_edge {
            // An occluder over x < 0, one metre up: its edge on the map's texel boundary
            // u = ½; the camera, below it, looks at the floor across the edge from the side.
            objects.push(json!({ "plane": {
                "point": [-2, 1, 0], "normal": [0, 1, 0], "half_extent": 2 } }));
            (
                json!({ "eye": [0.04, 0.4, 0.5], "target": [0.04, 0, 0], "up": [0, 1, 0],
                        "fov_y_deg": 1.0, "near": 0.05, "far": 10, "size": [512, 32] }),
                "linear",
            )
        } else {
            (
                json!({ "eye": [0, 2.5, 0], "target": [0, 0, 0], "up": [0, 0, -1],
                        "fov_y_deg": 40, "near": 0.1, "far": 10, "size": [32, 32] }),
                "nearest",
            )
        };
        json!({
            "name": "card-probe",
            "about": "a behaviour-card probe (umbra_runner::judge::card_probes)",
            "scene": { "objects": objects },
            "camera": camera,
            "light": { "directional": { "position": [0, H, 0], "target": [0, 0, 0],
                "up": [0, 0, -1],
                "ortho": { "left": -2, "right": 2, "bottom": -2, "top": 2,
                           "near": 0, "far": self.far } } },
            "shadow": { "size": [32, 32], "format": self.format.name(), "filter": filter,
                "bias": { "constant": self.bias, "polygon_offset": self.offset } },
        })
    }
}

/// Renders probe scenes on one backend.
pub struct Prober<'a> {
    backend: &'a mut dyn Backend,
    /// Renders made so far.
    pub renders: u32,
}

/// Why a probe could not measure: the backend cannot run the scene, or a render failed.
type Probe<T> = Result<T, String>;

impl<'a> Prober<'a> {
    /// A prober over `backend`.
    pub fn new(backend: &'a mut dyn Backend) -> Prober<'a> {
        Prober {
            backend,
            renders: 0,
        }
    }

    fn render(&mut self, s: &Scene) -> Probe<Frame> {
        self.render_case(&s.case())
    }

    /// Renders one probe case, given as JSON.
    pub(crate) fn render_case(&mut self, case: &Value) -> Probe<Frame> {
        let text = case.to_string();
        let point = umbra_case::load_str(&text, Path::new("<card probe>"))
            .map_err(|e| format!("the probe scene is not a valid case: {e}"))?
            .remove(0);
        if let Support::Unsupported(why) = self.backend.supports(&Needs::of(&point.case)) {
            return Err(format!("not supported here: {why}"));
        }
        self.renders += 1;
        let run = Prepared::new(point);
        let frame = self.backend.render(&run).map_err(|e| e.to_string());
        if frame.is_err() {
            let _ = self.backend.restore();
        }
        frame
    }

    /// The floor's lit fraction: the mean visibility over covered pixels.
    fn lit(&mut self, s: &Scene) -> Probe<f64> {
        let values = covered_values(&self.render(s)?);
        if values.is_empty() {
            return Err("the probe's floor covered no pixel".into());
        }
        Ok(values.iter().sum::<f64>() / values.len() as f64)
    }

    /// The constant bias at which `s`'s floor turns from shadowed to lit, searched in
    /// `[lo, hi]`: the bracket's middle and half-width.
    fn threshold(&mut self, s: Scene, lo: f64, hi: f64) -> Probe<(f64, f64)> {
        self.crossing(&|b| Scene { bias: b, ..s }, lo, hi, STEPS)
    }

    /// The `x` in `[lo, hi]` at which the floor of scene `make(x)` turns from shadowed to lit,
    /// bisected over `steps` renders: the bracket's middle and half-width.
    fn crossing(
        &mut self,
        make: &dyn Fn(f64) -> Scene,
        lo: f64,
        hi: f64,
        steps: u32,
    ) -> Probe<(f64, f64)> {
        let (l, h) = (self.lit(&make(lo))?, self.lit(&make(hi))?);
        if !(l < 0.5 && h >= 0.5) {
            let word = |f: f64| if f < 0.5 { "shadowed" } else { "lit" };
            return Err(format!(
                "no crossing in the searched range: the floor reads {} at its low end and {} at its high end (the choice lies outside what the probe searches, far outside the spec's range)",
                word(l),
                word(h)
            ));
        }
        let (mut a, mut b) = (lo, hi);
        for _ in 0..steps {
            let m = 0.5 * (a + b);
            if self.lit(&make(m))? < 0.5 {
                a = m
            } else {
                b = m
            }
        }
        Ok((0.5 * (a + b), 0.5 * (b - a)))
    }
}

/// The visibility of every pixel a surface covers (NaN-free), every light's (a probe has one),
/// what each probe reads.
fn covered_values(f: &Frame) -> Vec<f64> {
    f.each_light()
        .flat_map(|l| {
            (0..l.visibility.len())
                .filter(move |&i| l.covered(i) && l.visibility[i].is_finite())
                .map(move |i| f64::from(l.visibility[i]))
        })
        .collect()
}

/// The card's entries, measured on `backend` (whose frames the probes render).
pub fn measure(backend: &mut dyn Backend) -> (Vec<Entry>, u32) {
    let mut p = Prober::new(backend);
    let mut entries = Vec::new();
    for format in [
        DepthFormat::Depth16,
        DepthFormat::Depth24,
        DepthFormat::Depth32f,
    ] {
        entries.extend(offset_unit(&mut p, format));
    }
    entries.extend(slope_term(&mut p));
    for format in [DepthFormat::Depth16, DepthFormat::Depth24] {
        entries.extend(rounding(&mut p, format));
    }
    entries.push(linear(&mut p));
    entries.push(subpixel(&mut p));
    let one_tap = entries
        .iter()
        .any(|e| e.key == "linear-compare" && e.value.starts_with("one tap"));
    entries.push(if one_tap {
        Entry::unmeasured(
            "cube-seams",
            "cube map LINEAR at a face edge: filtered per face or across faces",
            "per face (desktop GL) or across faces (GLES 3, Vulkan)",
            "needs a LINEAR compare that blends",
            "not observable here: this driver's LINEAR compare takes one tap, which blends nothing on either side of a seam".into(),
        )
    } else {
        cube_seams(&mut p)
    });
    entries.push(sampler::cube_tie(&mut |c| p.render_case(c)));
    for format in [
        DepthFormat::Depth16,
        DepthFormat::Depth24,
        DepthFormat::Depth32f,
    ] {
        entries.push(reference_clamp(&mut p, format));
    }
    entries.push(sampler::border(&mut |c| p.render_case(c)));
    entries.extend(sampler::lod(&mut |c| p.render_case(c)));
    entries.push(sampler::derivatives(&mut |c| p.render_case(c)));
    entries.push(sampler::depth_clamp(&mut |c| p.render_case(c)));
    if p.backend.profile().packed_depth {
        emulated(&mut entries);
    }
    (entries, p.renders)
}

/// On umbra's GLES 2 technique (depth packed into RGBA8, the polygon offset and the compare
/// in umbra's own shaders), every entry but the rasterizer's sub-pixel bits and the clipper's
/// depth clamp (EXT_depth_clamp, the driver's) measures umbra's emulation, not a choice of
/// the driver's: the spec's clauses do not apply, and it says so.
fn emulated(entries: &mut [Entry]) {
    let drivers = ["subpixel-bits", "depth-clamp"];
    for e in entries
        .iter_mut()
        .filter(|e| !drivers.contains(&e.key.as_str()))
    {
        e.spec = format!(
            "umbra's GLES 2 emulation (packed RGBA8 depth, offset and compare in umbra's shaders), not the driver's choice; for a hardware path: {}",
            e.spec
        );
        e.inside = None;
    }
}

/// Short names of the formats, for entry titles.
fn short(f: DepthFormat) -> &'static str {
    match f {
        DepthFormat::Depth16 => "D16",
        DepthFormat::Depth24 => "D24",
        DepthFormat::Depth32f => "D32F",
        DepthFormat::Unsized => "unsized",
    }
}

/// The format's unit of r at depth `z`: one code (fixed point) or 2^(⌊log₂ z⌋ − 23) (float).
fn unit_of(f: DepthFormat, z: f64) -> f64 {
    match f.fixed_bits() {
        Some(n) => 1.0 / f64::from((1u32 << n) - 1),
        None => 2f64.powi(umbra_case::math::log2(z).floor() as i32 - 23),
    }
}

/// Polygon-offset unit r of `format` at window depths ⅜ and ¾, and whether it differs. Not
/// ¼: a power of two, where a depth one f32 step low would halve a float format's unit.
fn offset_unit(p: &mut Prober, format: DepthFormat) -> Vec<Entry> {
    let mut out = Vec::new();
    let mut seen = Vec::new();
    for z0 in [0.375, 0.75] {
        let unit = unit_of(format, z0);
        let (lo, hi) = format.offset_unit_range(z0 as f32);
        let scene = Scene {
            offset: [0.0, -UNITS],
            ..Scene::flat(format, z0)
        };
        let key = format!("offset-unit.{}.z{z0}", format.name());
        let what = format!("polygon-offset unit r, {}, z ≈ {z0}", short(format));
        let unit_name = if format.is_fixed() {
            "codes"
        } else {
            "× 2^(⌊log₂ z⌋ − 23)"
        };
        let spec = if format.is_fixed() {
            format!(
                "{:.3} to {:.3} codes: 2⁻ⁿ ≤ r ≤ 2·2⁻ⁿ (Vulkan \"Depth Bias\"; umbra holds GL to it)",
                lo / unit,
                hi / unit
            )
        } else {
            "1 or 2: r = 2^(e − 23), e the exponent of the primitive's largest |z| (GL 4.6 §14.6.5, Vulkan \"Depth Bias\"), read as ⌊log₂ z⌋ by GL drivers and as ⌊log₂ z⌋ + 1 by the WebGPU CTS (dawn:2076)".to_string()
        };
        let probe = format!(
            "flat floor at z = {z0}, polygon offset units −{UNITS}: the least constant bias that reads it lit, ÷ {UNITS}"
        );
        let measured = p.threshold(scene, 0.0, UNITS * 8.0 * hi);
        let entry = match measured {
            Ok((b, half)) => {
                let x = b / UNITS / unit;
                // The bracket, and a code of storage rounding and of the reference's f32
                // arithmetic, each spread over the 64 units.
                let err = half / UNITS / unit + 2.0 / UNITS;
                seen.push(x);
                let value = whole_or_decimal(x, 0.1, unit_name);
                let inside = if format.is_fixed() {
                    x >= lo / unit - err && x <= hi / unit + err
                } else {
                    (x - 1.0).abs() <= err || (x - 2.0).abs() <= err
                };
                let sure = Sure::Within(err);
                Entry::new(
                    &key,
                    &what,
                    value,
                    Some(x),
                    &spec,
                    Some(inside),
                    &probe,
                    sure,
                )
            }
            Err(why) => Entry::unmeasured(&key, &what, &spec, &probe, why),
        };
        out.push(entry);
    }
    if let [a, b] = seen[..] {
        let key = format!("offset-unit.{}.depends-on-depth", format.name());
        let what = format!(
            "polygon-offset unit r, {}: changes with depth",
            short(format)
        );
        let same = (a - b).abs() <= 0.1 * a.abs().max(b.abs());
        let value = if same { "no" } else { "yes" }.to_string();
        let spec = if format.is_fixed() {
            "no: constant over the range (GL 4.6 §14.6.5)"
        } else {
            "no, in units of 2^(e − 23) (r itself follows z's exponent)"
        };
        out.push(Entry::new(
            &key,
            &what,
            value,
            None,
            spec,
            Some(same),
            "the two offset-unit probes, z ≈ 0.375 and 0.75",
            Sure::Exact,
        ));
    }
    out
}

/// `x` as a whole number of `unit` when within `tol` of one, else to one decimal (`≈`): a
/// value is compared as text, so it carries no digit the probe's noise could move.
fn whole_or_decimal(x: f64, tol: f64, unit: &str) -> String {
    let k = x.round();
    if (x - k).abs() < tol && k > 0.0 {
        let unit = if k == 1.0 {
            unit.trim_end_matches('s')
        } else {
            unit
        };
        format!("{k:.0} {unit}")
    } else {
        format!("≈{x:.1} {unit}")
    }
}

/// The slope term m: its magnitude along an axis (where every form agrees), and max or exact
/// over a diagonal gradient.
fn slope_term(p: &mut Prober) -> Vec<Entry> {
    let format = DepthFormat::Depth24;
    let z0 = 0.25;
    let tilted = |diagonal| Scene {
        tilt: TILT,
        diagonal,
        offset: [-FACTOR, 0.0],
        ..Scene::flat(format, z0)
    };
    // Window depth per texel along the tilt: TILT m of height per m, 4/32 m per texel, 1/F
    // of depth per m of height.
    let s = TILT * (4.0 / 32.0) / (H / z0);
    let probe = format!(
        "a floor tilted 20° (D24, z ≈ 0.25, polygon offset factor −{FACTOR}) along x, and along the diagonal: the least biases that read it lit"
    );
    let (axis_key, axis_what) = (
        "slope-term.axis",
        "polygon-offset slope m along an axis, ÷ |∂z/∂x|",
    );
    let axis_spec = "1: along an axis max(|∂z/∂x|, |∂z/∂y|) and √(∂z/∂x² + ∂z/∂y²) agree (GL 4.6 §14.6.5, Vulkan \"Depth Bias\"), up to vertex snapping";
    let (diag_key, diag_what) = (
        "slope-term.diagonal",
        "polygon-offset slope m over a diagonal gradient, ÷ m along an axis",
    );
    let diag_spec = "0.707 (max(|∂z/∂x|, |∂z/∂y|)) to 1 (√(∂z/∂x² + ∂z/∂y²)): GL 4.6 §14.6.5, Vulkan \"Depth Bias\"";
    let both = p
        .threshold(tilted(false), 0.0, 4.0 * FACTOR * s)
        .and_then(|ax| Ok((ax, p.threshold(tilted(true), 0.0, 4.0 * FACTOR * s)?)));
    let ((ax, hx), (dg, hd)) = match both {
        Ok(b) => b,
        Err(why) => {
            return vec![
                Entry::unmeasured(axis_key, axis_what, axis_spec, &probe, why.clone()),
                Entry::unmeasured(diag_key, diag_what, diag_spec, &probe, why),
            ];
        }
    };
    // The stored depth is the texel centre's, the reference the pixel's: half a texel of
    // slope each way, which the median crossing averages out to well under 1 %.
    let axis = ax / (FACTOR * s);
    let axis_err = hx / (FACTOR * s) + 0.01;
    let axis_entry = Entry::new(
        axis_key,
        axis_what,
        classify(axis, &[(1.0, "1 × |∂z/∂x|")], 0.03, "× |∂z/∂x|"),
        Some(axis),
        axis_spec,
        Some((axis - 1.0).abs() <= 0.03 + axis_err),
        &probe,
        Sure::Within(axis_err),
    );
    let r = dg / ax;
    let err = r * (hx / ax + hd / dg) + 0.01;
    let diag_entry = Entry::new(
        diag_key,
        diag_what,
        classify(
            r,
            &[
                (std::f64::consts::FRAC_1_SQRT_2, "max(|∂z/∂x|, |∂z/∂y|)"),
                (1.0, "√(∂z/∂x² + ∂z/∂y²), exact"),
                (std::f64::consts::SQRT_2, "|∂z/∂x| + |∂z/∂y|"),
            ],
            0.03,
            "(ratio)",
        ),
        Some(r),
        diag_spec,
        Some((std::f64::consts::FRAC_1_SQRT_2 - err..=1.0 + err).contains(&r)),
        &probe,
        Sure::Within(err),
    );
    vec![axis_entry, diag_entry]
}

/// The name of the known value `x` is within `tol` of, else `≈x` to one decimal and `unit`.
fn classify(x: f64, known: &[(f64, &str)], tol: f64, unit: &str) -> String {
    known
        .iter()
        .find(|(v, _)| (x - v).abs() < tol)
        .map_or_else(|| format!("≈{x:.1} {unit}"), |(_, n)| (*n).to_string())
}

/// How a fixed-point format rounds a depth that lies between two codes, and at what
/// precision the compare takes its reference.
///
/// Three flat floors at code c + f, f = 0, ¼, ¾, no offset; t_f is the least bias (in codes)
/// that reads each lit. A reference compared as it is gives t_f = (c + f) − stored: t₀ = 0
/// (an exact code is stored exactly whatever the rounding), and t_¼, t_¾ = ¼, −¼ (to nearest),
/// ¼, ¾ (truncated) or −¾, −¼ (up). A reference rounded to a code first shifts every t by
/// −½, truncated by −1: t₀ measures the shift, and the rounding is read from t_¼ and t_¾
/// less it.
fn rounding(p: &mut Prober, format: DepthFormat) -> Vec<Entry> {
    let n = format.fixed_bits().unwrap_or(24);
    let m = f64::from((1u32 << n) - 1);
    // D16 mid-range; D24 near 0, where f32 has 32 values per code (near ½ it has one).
    let base = if n == 16 { 0.3 } else { 0.02 };
    let code = (base * m).floor();
    let (rkey, rwhat) = (
        format!("depth-rounding.{}", format.name()),
        format!("depth rounding, {}", short(format)),
    );
    let rspec = "to either neighbouring code; to nearest preferred (Vulkan \"Conversion from Floating-Point to Normalized Fixed-Point\", GL 4.6 §2.3.5.2)";
    let (qkey, qwhat) = (
        format!("reference-precision.{}", format.name()),
        format!("compare reference's precision, {}", short(format)),
    );
    let qspec = "not specified: GL 3.3 §3.8.16 and Vulkan \"Depth Compare Operation\" clamp a fixed-point format's reference to [0, 1] and say nothing of its precision";
    let probe = format!(
        "flat floors at codes {code:.0} + 0, ¼ and ¾, no offset: the least bias that reads each lit, in codes"
    );
    let mut t = Vec::new();
    for frac in [0.0, 0.25, 0.75] {
        let scene = Scene::flat(format, (code + frac) / m);
        match p.threshold(scene, -2.0 / m, 2.0 / m) {
            Ok((b, _)) => t.push(b * m),
            Err(why) => {
                return vec![
                    Entry::unmeasured(&qkey, &qwhat, qspec, &probe, why.clone()),
                    Entry::unmeasured(&rkey, &rwhat, rspec, &probe, why),
                ];
            }
        }
    }
    let probe = format!("{probe}: {:+.3}, {:+.3}, {:+.3}", t[0], t[1], t[2]);
    // Against the code's own threshold every rounding puts ¼ at +¼ or −¾ and ¾ at −¼ or +¾;
    // anything else is f32 noise of about a code (D24 through GL's clip convention).
    let near = |x: f64, of: [f64; 2]| of.iter().any(|v| (x - v).abs() < 0.1);
    let consistent = near(t[1] - t[0], [0.25, -0.75]) && near(t[2] - t[0], [-0.25, 0.75]);
    // A stored value not quantised to the format at all (GLES 2's packed depth) puts every
    // threshold at the floor's own depth.
    if t.iter().all(|x| x.abs() < 0.1) {
        let why = "not observable here: the stored depth is not quantised to this format's codes (every threshold lies at the floor's own depth)".to_string();
        return vec![
            Entry::unmeasured(&qkey, &qwhat, qspec, &probe, why.clone()),
            Entry::unmeasured(&rkey, &rwhat, rspec, &probe, why),
        ];
    }
    let shift = [
        (0.0, "compared as it is, or rounded up"),
        (-0.5, "rounded to a code"),
        (-1.0, "truncated to a code"),
    ]
    .into_iter()
    .find(|(s, _)| consistent && (t[0] - s).abs() < 0.1);
    let Some((shift, precision)) = shift else {
        let why = "not observable here: the thresholds fit no rounding (f32 arithmetic rounds at about this format's step; the probe line has them)".to_string();
        return vec![
            Entry::unmeasured(&qkey, &qwhat, qspec, &probe, why.clone()),
            Entry::unmeasured(&rkey, &rwhat, rspec, &probe, why),
        ];
    };
    let quantisation = Entry::new(
        &qkey,
        &qwhat,
        precision.to_string(),
        Some(t[0]),
        qspec,
        None,
        &probe,
        Sure::Margin(0.5 - (t[0] - shift).abs()),
    );
    let (a, b) = (t[1] - shift, t[2] - shift);
    let closest = a.abs().min(b.abs());
    if closest < 0.1 {
        let why = "not observable here: a threshold within 0.1 code of the floor's own depth (the probe line has them)".to_string();
        return vec![
            quantisation,
            Entry::unmeasured(&rkey, &rwhat, rspec, &probe, why),
        ];
    }
    let value = match (a > 0.0, b > 0.0) {
        (true, false) => "to nearest",
        (true, true) => "truncated (towards 0)",
        (false, false) => "up (away from 0)",
        (false, true) => "non-uniform (¼ rounds up, ¾ down)",
    };
    let rounding = Entry::new(
        &rkey,
        &rwhat,
        value.to_string(),
        None,
        rspec,
        // Either neighbouring code is allowed for each conversion on its own.
        Some(true),
        &probe,
        Sure::Margin(closest),
    );
    vec![quantisation, rounding]
}

/// LINEAR with compare: how the 2×2 compare results are combined, and the weights' bits.
fn linear(p: &mut Prober) -> Entry {
    let key = "linear-compare";
    let what = "LINEAR with compare: what is filtered, weight bits";
    let spec = "GL: any weighting of the 2×2 compare results (GL 3.3 §3.8.16); Vulkan: bilinear weights of ≥ 4 bits (subTexelPrecisionBits)";
    let probe = "a shadow edge on a texel boundary (D24) seen magnified, ≈ 355 px per texel: the distinct values between 0 and 1";
    let scene = Scene {
        linear_edge: true,
        bias: 0.01,
        ..Scene::flat(DepthFormat::Depth24, 0.25)
    };
    let frame = match p.render(&scene) {
        Ok(f) => f,
        Err(why) => return Entry::unmeasured(key, what, spec, probe, why),
    };
    let tol = f64::from(frame.visibility_storage.tolerance());
    let mut levels: Vec<f64> = covered_values(&frame)
        .into_iter()
        .filter(|v| *v > tol && *v < 1.0 - tol)
        .collect();
    levels.sort_by(f64::total_cmp);
    levels.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let n = levels.len();
    let vulkan = p.backend.profile().spec == umbra_case::Spec::Vulkan;
    let float = frame.visibility_storage == umbra_case::VisibilityStorage::Float32;
    // The weights' bits: the fewest k for which every value is a multiple of 2⁻ᵏ. Only a
    // float visibility target shows them; an 8-bit one holds j/255 whatever the weights.
    // Through an 8-bit target only weights of up to 6 bits stand apart from j/255.
    // A float target holds them exactly (a thousandth of a step of slack).
    let max_bits = if float { 16 } else { 6 };
    let bits = (1..=max_bits).find(|k| {
        let q = f64::from(1u32 << k);
        let slack = if float { 1e-3 / q } else { 0.6 / 255.0 };
        levels
            .iter()
            .all(|v| (v - (v * q).round() / q).abs() < slack)
    });
    let (value, sure) = match (n, float, bits) {
        (0, _, _) => (
            "one tap (NEAREST), or depths filtered before the compare: only 0 and 1".to_string(),
            Sure::Exact,
        ),
        (1..=2, _, _) => (format!("{n} values between 0 and 1"), Sure::Exact),
        (_, _, Some(k)) => (
            format!("bilinear of the compare results, {k}-bit weights"),
            Sure::Exact,
        ),
        (_, true, None) => (
            "bilinear of the compare results, weights finer than 16 bits".to_string(),
            Sure::AtLeast,
        ),
        (_, false, _) => (
            "bilinear of the compare results (weight bits hidden by the 8-bit visibility target)"
                .to_string(),
            Sure::AtLeast,
        ),
    };
    // GL allows any weighting; Vulkan bilinear weights of at least 4 bits.
    let inside = !vulkan || (n > 2 && bits.is_none_or(|k| k >= 4));
    Entry::new(
        key,
        what,
        value,
        Some(n as f64),
        spec,
        Some(inside),
        &if n <= 8 {
            let v: Vec<String> = levels.iter().map(|v| format!("{v:.4}")).collect();
            format!("{probe} ({n} found: {})", v.join(", "))
        } else {
            format!("{probe} ({n} found)")
        },
        sure,
    )
}

/// The shadow pass's sub-pixel precision: an occluder's edge moved across a texel centre by
/// δ; vertices snapped to 2⁻ᵇ of a pixel (round to nearest) leave the centre's coverage as
/// at δ = 0 while |δ| < 2⁻⁽ᵇ⁺¹⁾, so the coverage flips at |δ| = 2⁻⁽ᵇ⁺¹⁾ (on the side the tie
/// rule gives the centre). No snapping flips it at δ ≈ 0; below 2⁻¹⁷ px the f32 window
/// coordinates themselves (a step of 2⁻¹⁹ px near x = 16.5) blur what the bisection sees, so
/// that is read as 16 bits or more.
fn subpixel(p: &mut Prober) -> Entry {
    let key = "subpixel-bits";
    let what = "shadow-pass rasterization: sub-pixel bits of a vertex";
    let spec = "at least 4 (Vulkan subPixelPrecisionBits; GL SUBPIXEL_BITS, GL 4.6 §14.5)";
    let probe = "an occluder's edge moved across a texel centre (D24): the offset, in pixels, at which the centre's coverage flips";
    // A bias of 100 D24 codes keeps the floor off its own texels (a driver that truncates
    // depth would shadow it), far below the occluder's 0.0625 in front of it.
    let flat = Scene {
        bias: 100.0 / f64::from((1u32 << 24) - 1),
        ..Scene::flat(DepthFormat::Depth24, 0.25)
    };
    // x = −δ: as x grows the edge leaves the centre, which turns lit.
    let make = |x: f64| Scene {
        edge: Some(-x),
        ..flat
    };
    match p.crossing(&make, -0.25, 0.25, 18) {
        Ok((x, half)) => {
            let d = x.abs();
            let (value, sure, inside) = if d < 2f64.powi(-17) {
                (
                    "16 bits or more: no snapping seen".to_string(),
                    Sure::AtLeast,
                    true,
                )
            } else {
                let b = -umbra_case::math::log2(d) - 1.0;
                let k = b.round();
                let side = if x > 0.0 { "covered" } else { "not covered" };
                let v = if (b - k).abs() < 0.1 {
                    format!("{k:.0} bits (a centre on the edge is {side})")
                } else {
                    format!(
                        "between {:.0} and {:.0} bits, not a power-of-two grid (a centre on the edge is {side})",
                        b.floor(),
                        b.ceil()
                    )
                };
                (v, Sure::Within(half), k >= 4.0)
            };
            Entry::new(
                key,
                what,
                value,
                Some(x),
                spec,
                Some(inside),
                &format!("{probe}: {x:+.3e} px"),
                sure,
            )
        }
        Err(why) => Entry::unmeasured(key, what, spec, probe, why),
    }
}

/// Whether LINEAR reads across a cube map's face edges: a point light's −y face sees the
/// floor, its +x face, along its bottom edge, a small occluder (x = 0.5, y from −0.5 to
/// −0.3); the floor's true shadow edge then lies exactly on the faces' seam (x = 1 at
/// y = −1). Filtered per face, the floor steps from lit to shadowed there; across faces, it
/// blends over half a texel each side. The camera sees a band of ±0.085 m about the seam,
/// away from the occluder's sides; the share of its pixels strictly between 0 and 1 tells.
fn cube_seams(p: &mut Prober) -> Entry {
    let key = "cube-seams";
    let what = "cube map LINEAR at a face edge: filtered per face or across faces";
    let profile = p.backend.profile();
    let (seamless, vulkan) = (
        profile.seamless_cube,
        profile.spec == umbra_case::Spec::Vulkan,
    );
    let spec = match (seamless, vulkan) {
        (true, true) => "across faces (Vulkan \"Cube Map Edge Handling\", bilinear weights)",
        (true, false) => {
            "across faces (GLES 3.0 §3.8.9); GL's any weighting of the 2×2 results lets a per-face answer pass too"
        }
        (false, _) => {
            "per face: desktop GL with TEXTURE_CUBE_MAP_SEAMLESS disabled, as umbra leaves it (GL 4.6 §8.13.1)"
        }
    };
    let probe = "a point light's −y and +x faces (32² texels, D24, LINEAR), a shadow edge exactly on their seam, seen magnified: the share of floor pixels between 0 and 1";
    let case = json!({
        "name": "card-probe",
        "about": "a behaviour-card probe (umbra_runner::judge::card_probes)",
        "scene": { "objects": [
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0], "half_extent": 3 } },
            { "plane": { "point": [0.5, -0.4, 0], "normal": [-1, 0, 0], "half_extent": 0.1 } }
        ] },
        "camera": { "eye": [1.0, -0.6, 0.0], "target": [1.0, -1, 0], "up": [0, 0, -1],
                    "fov_y_deg": 20, "near": 0.05, "far": 10, "size": [64, 64] },
        "light": { "point": { "position": [0, 0, 0], "near": 0.05, "far": 10 } },
        "shadow": { "size": [32, 32], "format": "depth24", "filter": "linear",
                    "bias": { "constant": 0.002 } },
    });
    let frame = match p.render_case(&case) {
        Ok(f) => f,
        Err(why) => return Entry::unmeasured(key, what, spec, probe, why),
    };
    let tol = 2.0 * f64::from(frame.visibility_storage.tolerance());
    let covered = covered_values(&frame);
    let blended = covered
        .iter()
        .filter(|v| **v > tol && **v < 1.0 - tol)
        .count();
    let share = blended as f64 / covered.len().max(1) as f64;
    // Across faces blends about a third of the band; per face only the seam's own column.
    let across = if share > 0.1 {
        Some(true)
    } else if share < 0.05 {
        Some(false)
    } else {
        None
    };
    let value = match across {
        Some(true) => "across faces",
        Some(false) => "per face",
        None => "unclear: between per face and across faces",
    };
    let inside = across.map(|a| match (seamless, vulkan) {
        (false, _) => !a,
        (true, false) => true,
        (true, true) => a,
    });
    Entry::new(
        key,
        what,
        value.to_string(),
        Some(share),
        spec,
        inside,
        &format!("{probe}: {:.1} %", 100.0 * share),
        Sure::Exact,
    )
}

/// Whether the compare clamps a reference beyond the far plane (> 1) to 1.
fn reference_clamp(p: &mut Prober, format: DepthFormat) -> Entry {
    let key = format!("reference-clamp.{}", format.name());
    let what = format!("compare reference beyond the far plane, {}", short(format));
    let spec = if format.is_fixed() {
        "clamped to [0, 1]: reads lit against the cleared map (GL 3.3 §3.8.16, Vulkan \"Depth Compare Operation\")"
    } else {
        "not clamped: reads shadowed against the cleared map (a float format's reference is compared as it is)"
    };
    let probe = "a floor at z = 4/3, beyond the light's far plane, over a map holding nothing but its clear value";
    let scene = Scene {
        far: 3.0,
        ..Scene::flat(format, 0.25)
    };
    match p.lit(&scene) {
        Ok(lit) => {
            let clamped = lit > 0.5;
            let value = if clamped { "clamped" } else { "not clamped" };
            Entry::new(
                &key,
                &what,
                value.to_string(),
                Some(lit),
                spec,
                Some(clamped == format.is_fixed()),
                &format!("{probe}: lit fraction {lit:.3}"),
                Sure::Exact,
            )
        }
        Err(why) => Entry::unmeasured(&key, &what, spec, probe, why),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference's card is what umbra's model says it does, entry by entry, each
    /// expectation from the model's own documentation: so the probes read the conventions
    /// right, and a change to either shows here.
    #[test]
    fn the_reference_card_is_the_model() {
        let mut backend = umbra_ref::RefBackend;
        let (entries, renders) = measure(&mut backend);
        assert!(renders > 100, "{renders} renders");
        let model: &[(&str, &str)] = &[
            // DepthFormat::offset_unit: one code step for fixed point, 2^(e − 23) for float.
            ("offset-unit.depth16.z0.375", "1 code"),
            ("offset-unit.depth16.z0.75", "1 code"),
            ("offset-unit.depth16.depends-on-depth", "no"),
            ("offset-unit.depth24.z0.375", "1 code"),
            ("offset-unit.depth24.z0.75", "1 code"),
            ("offset-unit.depth24.depends-on-depth", "no"),
            ("offset-unit.depth32f.z0.375", "1 × 2^(⌊log₂ z⌋ − 23)"),
            ("offset-unit.depth32f.z0.75", "1 × 2^(⌊log₂ z⌋ − 23)"),
            ("offset-unit.depth32f.depends-on-depth", "no"),
            // shadow_pass: m = max(|∂z/∂x|, |∂z/∂y|) ("ours: max").
            ("slope-term.axis", "1 × |∂z/∂x|"),
            ("slope-term.diagonal", "max(|∂z/∂x|, |∂z/∂y|)"),
            // DepthFormat::store: round to nearest; lookup step 6 compares the f32 reference.
            (
                "reference-precision.depth16",
                "compared as it is, or rounded up",
            ),
            ("depth-rounding.depth16", "to nearest"),
            // lookup: bilinear weights of the compare results in f32.
            (
                "linear-compare",
                "bilinear of the compare results, weights finer than 16 bits",
            ),
            // raster (SNAP_PX's note): vertices snapped to 8 bits by rounding; a centre on an
            // edge is covered by the top-left rule only, and this edge is a right edge.
            (
                "subpixel-bits",
                "8 bits (a centre on the edge is not covered)",
            ),
            // Desktop GL's profile: cube faces filtered one by one (seamless off).
            ("cube-seams", "per face"),
            // light::cube_face: a tie goes to x, then y.
            ("cube-face-ties", "x over y over z"),
            // lookup step 6: clamped for a fixed-point hardware compare, never for float.
            ("reference-clamp.depth16", "clamped"),
            ("reference-clamp.depth24", "clamped"),
            ("reference-clamp.depth32f", "not clamped"),
            // lookup: a border texel holds the clear depth and is compared like any other.
            ("border-compare", "compared"),
            // Lookup::lod: ρ = the longer of |∂(s, t)/∂x| and |∂(s, t)/∂y|, λ = log₂ ρ.
            ("lod-scale-factor", "the exact length √(∂s² + ∂t²)"),
            ("lod-offset", "+0.00 levels"),
            // Lookup::lod: forward differences to the next pixel, each pixel its own.
            ("lod-derivatives", "per pixel (fine)"),
            // raster: the near plane clips unless depth_clamp trades it for w > 0.
            ("depth-clamp", "off: clipped, on: clamped"),
        ];
        for (key, value) in model {
            let e = entries
                .iter()
                .find(|e| e.key == *key)
                .unwrap_or_else(|| panic!("no entry {key}"));
            assert_eq!(e.value, *value, "{key}: {e:?}");
            assert_ne!(e.inside, Some(false), "{key}");
        }
        // D24's rounding and reference precision cannot be seen through GL's clip
        // convention, which the reference follows: f32 arithmetic rounds at about a D24 code
        // there. It says so.
        for key in ["reference-precision.depth24", "depth-rounding.depth24"] {
            let d24 = entries.iter().find(|e| e.key == key).expect("a D24 entry");
            assert!(
                d24.value.starts_with("not measured: not observable"),
                "{d24:?}"
            );
        }
        assert_eq!(entries.len(), model.len() + 2);
    }
}
