//! The probes of a repro: the pixels and texels where the driver broke the judge's bounds,
//! each with exactly the numbers the judge held it to, as C.
//!
//! A pixel probe repeats [`umbra_compare::reference::judge`] at one pixel: the surface shown
//! (face id + 1 in the visibility target's GBA) must be the reference's unless another surface
//! may legally show there; on the same surface the visibility must satisfy `value_ok` (the
//! interval [lo, hi] widened by the target's rounding ε, and for a discrete filter within ε of
//! a multiple of the quantum) and the colour must be the shading of that visibility
//! (`colour_ok`). A texel probe repeats [`umbra_compare::reference::map_failures`]: the stored
//! depth within [`map_range`] (the judge's one function for it), both ends embedded as f32
//! so the C compares the same floats. The C ports each test line for line, so a probe can
//! be neither wider nor narrower than the judge; `tests/repro.rs` checks the exit codes on a
//! deviating driver and a conforming one.

use std::fmt::Write as _;

use umbra_case::Frame;
use umbra_compare::reference::{PixelJudgement, light_of, map_range};
use umbra_gl::record::hex_f32;
use umbra_ref::Judged;

/// At most this many probes of each kind (spread over the failures, first and last kept).
pub const MAX_PROBES: usize = 48;

/// A probe's surface when the reference records no surface ids (any covered pixel is its).
const ANY_SURFACE: u32 = u32::MAX;

/// One pixel the driver got wrong, with the judge's numbers there.
#[derive(Clone, Debug)]
pub struct PixelProbe {
    /// Column, row (top row 0, as umbra's pictures).
    pub x: u32,
    /// Row.
    pub y: u32,
    /// The reference's surface id + 1 there (0: no surface).
    pub surface: u32,
    /// Whether another surface may legally show there.
    pub surface_free: bool,
    /// The legal visibility interval.
    pub lo: f32,
    /// Its upper end.
    pub hi: f32,
    /// Shading at visibility 0 and 1, and the shading's arithmetic freedom.
    pub c0: [f32; 3],
    /// Shading at visibility 1.
    pub c1: [f32; 3],
    /// The colour tolerance.
    pub ctol: f32,
    /// What umbra's driver run gave: visibility (NaN: no surface) and surface id.
    pub got: (f32, u32),
}

/// One shadow-map texel the driver stored out of range.
#[derive(Clone, Debug)]
pub struct TexelProbe {
    /// Face (layer).
    pub layer: u32,
    /// Column.
    pub x: u32,
    /// Row (top row 0).
    pub y: u32,
    /// The allowed range, widened by one f32 spacing each side as the judge does.
    pub lo: f32,
    /// Upper end.
    pub hi: f32,
    /// What umbra's driver run stored.
    pub got: f32,
}

/// The probes of a judged frame.
#[derive(Clone, Debug, Default)]
pub struct Probes {
    /// Pixels, at most [`MAX_PROBES`].
    pub pixels: Vec<PixelProbe>,
    /// Of how many illegal pixels.
    pub pixels_total: usize,
    /// Texels, at most [`MAX_PROBES`].
    pub texels: Vec<TexelProbe>,
    /// Of how many illegal texels.
    pub texels_total: usize,
    /// The visibility target's rounding.
    pub eps: f32,
    /// The discrete filter's step (0: continuous).
    pub quantum: f32,
    /// An sRGB colour target (`camera.color_format`): the colour test encodes its bounds.
    pub srgb: bool,
    /// Frame and map sizes.
    pub frame: [u32; 2],
    /// Map size.
    pub map: [u32; 2],
}

/// Up to `n` items of `v`, evenly spread, the first and the last among them.
fn spread<T: Clone>(v: &[T], n: usize) -> Vec<T> {
    if v.len() <= n {
        return v.to_vec();
    }
    (0..n)
        .map(|k| v[k * (v.len() - 1) / (n - 1)].clone())
        .collect()
}

/// The probes of `frame`, judged by `basis` into `pixels`.
pub fn select(basis: &Judged, frame: &Frame, pixels: &[PixelJudgement]) -> Probes {
    let w = frame.width;
    // The program probes the first light's pass, which draws the colour target first: a
    // reduced case keeps one light, where its failure allows (light-swap keeps two).
    let missing = vec![f32::NAN; (w * frame.height) as usize];
    let reference = light_of(&basis.frame, 0, &missing);
    let frame_light = light_of(frame, 0, &missing);
    let judged = &basis.lights[0];
    let illegal: Vec<usize> = pixels
        .iter()
        .enumerate()
        .filter(|(_, j)| **j == PixelJudgement::Illegal)
        .map(|(i, _)| i)
        .collect();
    let pixel = |i: usize| {
        let l = judged.legal[i];
        PixelProbe {
            x: i as u32 % w,
            y: i as u32 / w,
            surface: if reference.covered(i) {
                reference.surface.map_or(ANY_SURFACE, |s| s[i])
            } else {
                0
            },
            surface_free: l.flags & umbra_ref::lookup::ambiguity::SURFACE != 0,
            lo: l.lo,
            hi: l.hi,
            c0: l.c0,
            c1: l.c1,
            ctol: l.ctol,
            got: (
                frame_light.visibility[i],
                frame_light.surface.map_or(0, |s| s[i]),
            ),
        }
    };
    let mut texels = Vec::new();
    let mut texels_total = 0;
    let mut map = [0, 0];
    if let Some(m) = frame_light.shadow_map {
        if m.values.len() == judged.map.len() && !judged.map.is_empty() {
            map = [m.width, m.height];
            let bad: Vec<usize> = m
                .values
                .iter()
                .zip(&judged.map)
                .enumerate()
                .filter(|(_, (v, (lo, hi)))| {
                    let (lo, hi) = map_range(*lo, *hi);
                    !(lo <= **v && **v <= hi)
                })
                .map(|(k, _)| k)
                .collect();
            texels_total = bad.len();
            let per_layer = (m.width * m.height) as usize;
            texels = spread(&bad, MAX_PROBES)
                .into_iter()
                .map(|k| {
                    let (lo, hi) = map_range(judged.map[k].0, judged.map[k].1);
                    let at = k % per_layer;
                    TexelProbe {
                        layer: (k / per_layer) as u32,
                        x: at as u32 % m.width,
                        y: at as u32 / m.width,
                        lo,
                        hi,
                        got: m.values[k],
                    }
                })
                .collect();
        }
    }
    Probes {
        pixels: spread(&illegal, MAX_PROBES)
            .into_iter()
            .map(pixel)
            .collect(),
        pixels_total: illegal.len(),
        texels,
        texels_total,
        eps: frame.visibility_storage.tolerance(),
        quantum: judged.quantum,
        srgb: basis.color_format == umbra_case::format::ColorFormat::Srgb8Alpha8,
        frame: [frame.width, frame.height],
        map,
    }
}

impl Probes {
    /// Whether there is anything to probe.
    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty() && self.texels.is_empty()
    }

    /// The probes as C: tables, the judge's tests, `readback()` and `probes_result()`.
    /// `profile` names the judged profile and `clauses` the spec text each kind is held to.
    pub fn c_source(&self, profile: &str, value_clause: &str, map_clause: &str) -> String {
        let mut c = String::new();
        let [w, h] = self.frame;
        let [mw, mh] = self.map;
        let _ = writeln!(
            c,
            "#define FRAME_W {w}\n#define FRAME_H {h}\n#define MAP_W {mw}\n#define MAP_H {mh}"
        );
        let _ = writeln!(
            c,
            "/* The visibility target is RGBA8: the judge allows its rounding, eps = 1/255. */\nstatic const float EPS = {};",
            hex_f32(self.eps)
        );
        let _ = writeln!(
            c,
            "/* A discrete filter's step (NEAREST: 1, PCF n: 1/n^2; 0: continuous). */\nstatic const float QUANTUM = {};",
            hex_f32(self.quantum)
        );
        let _ = writeln!(
            c,
            "/* The colour target is sRGB (1) or linear RGBA8 (0); an sRGB encoding may lie\n * within SRGB_TOL of the exact transfer function (umbra_case::colour). */\n#define SRGB_TARGET {}\nstatic const float SRGB_TOL = {};",
            i32::from(self.srgb),
            hex_f32(umbra_case::colour::SRGB_ENCODE_TOLERANCE)
        );
        c.push_str(PIXEL_STRUCT);
        let _ = writeln!(
            c,
            "/* Pixels where umbra saw the driver outside what a conformant {profile}\n * implementation may return ({value_clause}).\n * x, y from the top-left; surface: the reference's face id + 1 (0: background);\n * lo, hi: the legal visibility; c0, c1: the shading at visibility 0 and 1; ctol: its\n * arithmetic freedom. umbra's driver run gave the value in the comment. */"
        );
        let _ = writeln!(c, "static const struct pixel_probe PIXELS[] = {{");
        for p in &self.pixels {
            let v = |a: [f32; 3]| {
                format!(
                    "{{{}, {}, {}}}",
                    hex_f32(a[0]),
                    hex_f32(a[1]),
                    hex_f32(a[2])
                )
            };
            let _ = writeln!(
                c,
                "    {{{}, {}, {}, {}, {}, {}, {}, {}, {}}}, /* got {} on surface {}; allowed [{:.6}, {:.6}] */",
                p.x,
                p.y,
                p.surface,
                i32::from(p.surface_free),
                hex_f32(p.lo),
                hex_f32(p.hi),
                v(p.c0),
                v(p.c1),
                hex_f32(p.ctol),
                if p.got.0.is_nan() {
                    "no surface".to_string()
                } else {
                    format!("{:.6}", p.got.0)
                },
                p.got.1,
                p.lo,
                p.hi
            );
        }
        if self.pixels.is_empty() {
            c.push_str("    {0, 0, 0, 0, 0, 0, {0, 0, 0}, {0, 0, 0}, 0} /* none: placeholder */\n");
        }
        c.push_str("};\n");
        let _ = writeln!(c, "static const int N_PIXELS = {};\n", self.pixels.len());
        let _ = writeln!(
            c,
            "/* Shadow-map texels the driver stored outside the depths a conformant {profile}\n * implementation may store ({map_clause}); lo and hi are already widened by one f32\n * spacing, as the judge widens them. Rows from the top (umbra's orientation). */"
        );
        c.push_str("struct texel_probe { int layer, x, y; float lo, hi; };\n");
        c.push_str("static const struct texel_probe TEXELS[] = {\n");
        for t in &self.texels {
            let _ = writeln!(
                c,
                "    {{{}, {}, {}, {}, {}}}, /* got {:.9}; allowed [{:.9}, {:.9}] */",
                t.layer,
                t.x,
                t.y,
                hex_f32(t.lo),
                hex_f32(t.hi),
                t.got,
                t.lo,
                t.hi
            );
        }
        if self.texels.is_empty() {
            c.push_str("    {0, 0, 0, 0, 0} /* none: placeholder */\n");
        }
        c.push_str("};\n");
        let _ = writeln!(c, "static const int N_TEXELS = {};", self.texels.len());
        c.push_str(PROBE_FUNCTIONS);
        c
    }
}

const PIXEL_STRUCT: &str = r#"
struct pixel_probe {
    int x, y;
    unsigned surface;
    int surface_free;
    float lo, hi;
    float c0[3], c1[3], ctol;
};
"#;

const PROBE_FUNCTIONS: &str = r#"
static unsigned char *color_image, *visibility_image;
static float *map_layers[6];

/* Keeps each readback for the probes (rows stay bottom first, as GL returns them). */
static void readback(int kind, int layer, const void *pixels, int w, int h)
{
    size_t bytes = (size_t)w * h * 4;
    void *copy = xmalloc(bytes);
    memcpy(copy, pixels, bytes);
    if (kind == READBACK_COLOR) color_image = copy;
    else if (kind == READBACK_VISIBILITY) visibility_image = copy;
    else if (layer >= 0 && layer < 6) map_layers[layer] = copy;
    else free(copy);
}

/* umbra_ref::rounding::round_f32: half away from zero, in f32. */
static float round_f32(float x)
{
    if (fabsf(x) < 8388608.0f) {
        float t = (float)(int)x;
        float r = fabsf(x - t) >= 0.5f ? t + copysignf(1.0f, x) : t;
        return copysignf(r, x);
    }
    return x;
}

/* umbra_compare::reference::value_ok */
static int value_ok(float v, float lo, float hi)
{
    if (!(lo - EPS <= v && v <= hi + EPS)) return 0;
    if (QUANTUM <= 0.0f) return 1;
    volatile float k = round_f32(v / QUANTUM) * QUANTUM; /* rounded before v - k: no FMA */
    return fabsf(v - k) <= EPS + 4.0f * 1.1920929e-7f && lo - EPS <= k && k <= hi + EPS;
}

static float clamp01(float x) { return x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x; }

/* umbra_case::colour::srgb_encode: the sRGB transfer function of a clamped linear value, in
 * double, rounded once to float (the C library's pow may differ from umbra's musl port in
 * its last bit, far below SRGB_TOL). */
static float srgb_encode(float x)
{
    double c = clamp01(x);
    double e = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
    return (float)(e < 0.0 ? 0.0 : e > 1.0 ? 1.0 : e);
}

/* umbra_compare::reference::colour_ok: each channel within the codes the shading of
 * [v - eps, v + eps], widened by its arithmetic freedom (and encoded for an sRGB target),
 * rounds to either way. */
static int colour_ok(const unsigned char *rgb, float v, const struct pixel_probe *p)
{
    float v0 = clamp01(v - EPS), v1 = clamp01(v + EPS);
    for (int c = 0; c < 3; c++) {
        /* Each product rounded to float before the sum, as Rust computes it: a compiler
         * that fuses a*b+c (gcc on aarch64 by default) would round once. */
        volatile float pa = (p->c1[c] - p->c0[c]) * v0, pb = (p->c1[c] - p->c0[c]) * v1;
        float a = p->c0[c] + pa;
        float b = p->c0[c] + pb;
        float lo = clamp01((a < b ? a : b) - p->ctol);
        float hi = clamp01((a > b ? a : b) + p->ctol);
        if (SRGB_TARGET) { /* umbra_case::format::ColorFormat::encoded_bounds */
            lo = srgb_encode(lo) - SRGB_TOL;
            hi = srgb_encode(hi) + SRGB_TOL;
            lo = lo < 0.0f ? 0.0f : lo;
            hi = hi > 1.0f ? 1.0f : hi;
        }
        float code = (float)rgb[c];
        if (!(lo * 255.0f < code + 1.0f && hi * 255.0f > code - 1.0f)) return 0;
    }
    return 1;
}

/* Prints every probe; returns 0 when all are inside, 1 otherwise. */
static int probes_result(void)
{
    int outside = 0;
    if (N_PIXELS > 0 && (!color_image || !visibility_image)) fail("the lit pass was not read back");
    for (int i = 0; i < N_PIXELS; i++) {
        const struct pixel_probe *p = &PIXELS[i];
        size_t at = ((size_t)(FRAME_H - 1 - p->y) * FRAME_W + p->x) * 4;
        const unsigned char *vis = visibility_image + at, *rgb = color_image + at;
        unsigned id = vis[1] + 256u * vis[2] + 65536u * vis[3];
        float v = vis[0] / 255.0f;
        int ok;
        const char *why = "";
        if (p->surface == 0 && id == 0) {
            ok = 1;
        } else if (p->surface == 0 || id == 0 || (p->surface != 0xFFFFFFFFu && id != p->surface)) {
            ok = p->surface_free;
            why = " (another surface than the reference's, where none other may show)";
        } else if (!value_ok(v, p->lo, p->hi)) {
            ok = 0;
            why = " (visibility)";
        } else {
            ok = colour_ok(rgb, v, p);
            why = ok ? "" : " (colour is not the shading of the visibility written)";
        }
        if (id == 0)
            printf("pixel (%d, %d): no surface (reference: surface %u), allowed visibility [%.6f, %.6f] +- %.6f: %s%s\n",
                   p->x, p->y, p->surface, p->lo, p->hi, EPS, ok ? "inside" : "OUTSIDE", why);
        else
            printf("pixel (%d, %d): visibility %.6f (code %d) on surface %u, colour (%d, %d, %d); allowed [%.6f, %.6f] +- %.6f on surface %u: %s%s\n",
                   p->x, p->y, v, vis[0], id, rgb[0], rgb[1], rgb[2], p->lo, p->hi, EPS, p->surface,
                   ok ? "inside" : "OUTSIDE", why);
        outside += !ok;
    }
    for (int i = 0; i < N_TEXELS; i++) {
        const struct texel_probe *t = &TEXELS[i];
        if (!map_layers[t->layer]) fail("the shadow map was not read back");
        float d = map_layers[t->layer][(size_t)(MAP_H - 1 - t->y) * MAP_W + t->x];
        int ok = t->lo <= d && d <= t->hi;
        printf("texel (%d, %d) of face %d: depth %.9g (%a), allowed [%.9g, %.9g]: %s\n",
               t->x, t->y, t->layer, d, d, t->lo, t->hi, ok ? "inside" : "OUTSIDE");
        outside += !ok;
    }
    printf("%d of %d probes outside what the spec allows\n", outside, N_PIXELS + N_TEXELS);
    return outside ? 1 : 0;
}
"#;
