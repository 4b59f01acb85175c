//! The lit pass's fragment shader, written once for every shading language.
//!
//! Why it exists: the lookup must be the same steps in GLSL and in WGSL, in the same order,
//! with the self-test's faults acting on the same steps, or a difference between backends is
//! the generators' and not the drivers'. [`lit_fragment`] is the only place that decides which
//! steps a [`Technique`] takes and in what order; a [`Dialect`] supplies the language: types,
//! declarations, texture calls, uniform names and entry points. A line that reads the same in
//! both languages but for a uniform's name is written here, with the name from
//! [`Dialect::uniform`]; anything else comes from the dialect.
//!
//! A trait rather than a list of steps that each language prints: each dialect method is one
//! piece of one language, documented once here, so an emitter is a flat list of short
//! snippets with no decisions in it. A method a language does not need (GLSL's accessors for
//! the face matrices, WGSL's cube rows) returns an empty string there.

use std::fmt::Write as _;

use crate::format::{DepthOrder, Outside, Shading, ShadingModel};
pub use crate::technique::CascadeSelect;
use crate::technique::{CompareOp, Coordinate, Taps, Technique};

/// Uniforms that lines written here read, by role.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Uniform {
    /// The map's width in texels (a float).
    MapWidth,
    /// The map's height in texels.
    MapHeight,
    /// The world-space normal offset.
    NormalOffset,
    /// The slope bias's scale.
    SlopeScale,
    /// The N·L bias's scale.
    NdotLScale,
    /// The N·L bias's least value.
    NdotLMin,
    /// The light's position (a vec3; a directional light's eye).
    LightPosition,
}

/// One shading language's pieces of the lit pass. A dialect is made for one technique's
/// map: where that is a 2D array (cascades), `fetch`, `tap` and the samples read layer `f`. Each method returns source text, whole
/// lines ending in `\n`; the functions named are those every dialect defines (`to_light`,
/// `cube_face`, `texel_dir`, `fetch`, `tap`, `visibility`, `shade`) and the locals are those
/// of `umbra_ref::lookup` (`p`, `n`, `f`, `c`, `bias`, `r`).
pub trait Dialect {
    /// Everything before the constants: version, inputs, uniforms, the map's binding, outputs
    /// (and the vertex stage where the language keeps both in one module).
    fn declarations(&self, t: &Technique) -> String;
    /// One float constant.
    fn constant(&self, name: &str, value: &str) -> String;
    /// `to_light(p)`: the unit vector from `p` towards the light.
    fn to_light(&self, directional: bool) -> &'static str;
    /// Accessors for the `faces` light and texture matrices (and, with `offsets`, the faces'
    /// normal offsets in world units), where the language cannot index them directly.
    fn face_matrices(&self, faces: usize, offsets: bool) -> String;
    /// `cube_face(d)` and `texel_dir(f, i, j)` (the GL cube-map face table and its inverse).
    fn cube_helpers(&self) -> &'static str;
    /// Decoding of depth stored in colour, where the map is not a depth texture.
    fn depth_decoder(&self) -> &'static str;
    /// `fetch(f, i, j)`: the stored depth of texel (i, j) of face f, out-of-range texels
    /// addressed by `wrap`, read from the wrong component if `wrong_component`.
    fn fetch(&self, cube: bool, wrap: Outside, wrong_component: bool) -> String;
    /// `tap(f, i, j, r)`: one compare of reference `r` at texel (i, j) of face f, by the
    /// shader with `op` (`manual`) or by the sampler.
    fn tap(&self, manual: bool, cube: bool, op: CompareOp) -> String;
    /// `compare_at(f, uv, r)`: one bilinear compare of reference `r` at `uv` in face f, by
    /// the sampler (a LINEAR compare sampler) or, `manual`, by the shader's four `tap`s with
    /// bilinear weights ([`Taps::Castano13`]'s taps).
    fn compare_at(&self, manual: bool) -> String;
    /// Castano's nine-sample filter at `c.xy`, written as Bevy's
    /// `sample_shadow_map_castano_thirteen` writes it (same operations, same order), each
    /// of its nine taps a `compare_at`; returns the sum over 144.
    fn castano(&self) -> &'static str;
    /// The pixel's window position as GL's gl_FragCoord.xy gives it (its centre, y up from
    /// the frame's bottom row; `FRAME_HEIGHT` the frame's height), or with y down from the
    /// top row (`y_down`, the self-test's NoiseYDown).
    fn window(&self, y_down: bool) -> &'static str;
    /// A two-component float vector's constructor.
    fn vec2(&self) -> &'static str;
    /// The lookup coordinate's v runs down the map's rows, against GL's texture v (the
    /// zero-to-one convention's bias matrix, `Convention::bias_matrix`): an offset meant
    /// along GL's v is negated.
    fn v_down(&self) -> bool;
    /// What declares a mutable local of GLSL type `glsl` (that type, or WGSL's `var`).
    fn local(&self, glsl: &'static str) -> &'static str;
    /// A uniform's name (with its component where the language packs it in a vector).
    fn uniform(&self, u: Uniform) -> &'static str;
    /// Opens `visibility(p, n)` and moves `p` by `offset` along `n`.
    fn lookup_start(&self, offset: &str) -> String;
    /// `f`: the face (`cube_face` of the direction from the light, or 0).
    fn face(&self, cube: bool) -> &'static str;
    /// Opens `lookup(p, n, f)`, a layered map's lookup in layer `f` of the already offset
    /// point `p`, moved further by `extra` ([`Dialect::world_offsets`]) where it is not empty.
    fn layer_lookup_start(&self, extra: &str) -> String;
    /// What face `f`'s lookup adds to the point after the face is chosen: the texel-scaled
    /// normal offset of that face and the offset towards the light (in that order, as Bevy's
    /// `frag_position + normal_offset + depth_offset` does), each term with its leading ` + `.
    fn world_offsets(&self, f: &str) -> String;
    /// `visibility(p, n)` of a cascaded light: moves `p` by `offset` along `n`, takes its
    /// view depth d (the camera view matrix's third row, negated), reads lit beyond the
    /// shadow distance, picks the cascade `f` (a depth on a split goes to the nearer one, as
    /// `umbra_case::light::Cascading::cascade_of` decides) with its range [lo, hi], returns
    /// `lookup(p, n, f)`, blended in the band into `lookup(p, n, f + 1)` as
    /// `Cascading::blend_weight` weighs it.
    fn cascaded_visibility(&self, offset: &str, c: &CascadeSelect) -> String;
    /// `c` = (u, v, depth, w) from `p` (reads `bias_matrix` and `left_out`).
    fn coordinate(&self, c: &Coordinate) -> &'static str;
    /// The bias matrix applied to `c` again.
    fn bias_again(&self) -> &'static str;
    /// `u` moved by `texels` texels.
    fn nudge_u(&self, texels: &str) -> String;
    /// Returns lit where w ≤ 0.
    fn guard(&self) -> &'static str;
    /// Returns lit outside [0,1]².
    fn outside_test(&self) -> &'static str;
    /// On a cube map, after the tests: rows as the backend's face images hold them.
    fn cube_rows(&self) -> &'static str;
    /// `bias`, starting with the constant bias.
    fn bias_start(&self) -> &'static str;
    /// Adds the slope bias, `scale` · tan(θ) capped.
    fn slope_bias(&self, scale: &str) -> String;
    /// `r`, the reference: `c.z` moved by `bias` towards the light.
    fn reference(&self) -> &'static str;
    /// Returns the sampler's compare at the direction from the light ([`Taps::HardwareCube`]).
    fn sample_cube(&self) -> &'static str;
    /// Returns the sampler's projective compare ([`Taps::HardwareProjective`]).
    fn sample_projective(&self) -> &'static str;
    /// Returns the sampler's compare at `c` ([`Taps::Hardware`]).
    fn sample(&self) -> &'static str;
    /// Declares `m`, the sampler's compare at `c` with implicit derivatives on a mipmapped
    /// map ([`Taps::HardwareMipmapped`]).
    fn sample_mipmapped(&self) -> &'static str;
    /// The bilinear position: `i0`, the first texel, and `a`, the weights.
    fn bilinear_start(&self) -> &'static str;
    /// `n` as a float.
    fn float_of(&self, n: u32) -> String;
    /// `sum` of the N × N taps with offsets k − `centre`, `h` = `centre`.
    fn pcf_sum(&self, n: u32, centre: &str) -> String;
    /// Replaces the first corner's tap in `sum` by the centre's.
    fn pcf_double_centre(&self) -> &'static str;
    /// Returns `sum` over N².
    fn pcf_mean(&self, n: u32) -> String;
    /// Opens `shade(albedo, n, l, e, vis)`: `ndl` and `diffuse`.
    fn shade_start(&self) -> &'static str;
    /// The dimmed model: `kept` of diffuse in shadow, `lit_spec` the specular term; with
    /// `light` (a vec3 expression), both terms multiplied by it.
    fn dimmed(&self, kept: &str, lit_spec: &str, light: Option<&str>, shading: &Shading) -> String;
    /// A vec3 literal.
    fn vec3(&self, v: [f32; 3]) -> String;
    /// Opens `main`: the normal `n` (renormalised), and `vis` from `visibility(p, N)` with
    /// `N` the renormalised normal, or the raw interpolant when `raw_normal` (a fault); with
    /// `window`, first keeps the fragment's position where [`Dialect::window`] reads it.
    fn main_start(&self, raw_normal: bool, window: bool) -> String;
    /// The shaded colour `col` (and the face id) from `vis`.
    fn main_colour(&self) -> &'static str;
    /// Writes the outputs and closes the entry point.
    fn main_end(&self) -> &'static str;
}

/// The lit pass's fragment shader for `t` in dialect `d`: the lookup mirrors
/// `umbra_ref::lookup` step by step, the shading `umbra_ref::shading`.
pub fn lit_fragment(d: &impl Dialect, t: &Technique) -> String {
    let mut s = d.declarations(t);
    let forward = t.order == DepthOrder::Forward;
    s += &d.constant("TOWARD_FAR", if forward { "1.0" } else { "-1.0" });
    s += &d.constant("CLEAR", if forward { "1.0" } else { "0.0" });
    s += d.to_light(t.directional);
    s += &d.face_matrices(if t.cube { 6 } else { t.cascades.max(1) }, t.world_offsets);
    if t.cube {
        s += d.cube_helpers();
    }
    s += d.depth_decoder();
    if t.manual() {
        s += &d.fetch(t.cube, t.texel_wrap(), t.reads_wrong_component());
    }
    s += &d.tap(t.manual(), t.cube, t.compare_op());
    let disk = matches!(t.taps(), Taps::Vogel5 { .. });
    if t.taps() == Taps::Castano13 || disk {
        s += &d.compare_at(t.manual());
    }
    if disk {
        s += &d.constant("FRAME_HEIGHT", &format!("{:?}", t.frame_height as f32));
    }
    lookup(&mut s, d, t);
    shade(&mut s, d, t);
    s += &d.main_start(t.lookup_normal_raw(), disk);
    if let Some(steps) = t.visibility_steps() {
        s += &format!("  vis = floor(vis * {steps}.0 + 0.5) / {steps}.0;\n");
    }
    s += d.main_colour();
    if t.encodes_gamma() {
        s += "  col = sqrt(col);\n";
    }
    s += d.main_end();
    s
}

/// A float literal both languages read the same way (fixed point, nine decimals).
fn literal(x: f32) -> String {
    format!("{x:.9}")
}

/// `visibility(p, n)`: normal offset, face, coordinate, guard, outside test, bias,
/// reference, taps.
fn lookup(s: &mut String, d: &impl Dialect, t: &Technique) {
    let offset = d.uniform(Uniform::NormalOffset);
    let offset = match t.normal_offset_scale() {
        1.0 => offset.to_string(),
        k => format!("({k} * {offset})"),
    };
    let cascades = t.cascade_select();
    let face = if cascades.is_some() { "f" } else { "0" };
    let extra = if t.world_offsets {
        d.world_offsets(face)
    } else {
        String::new()
    };
    if cascades.is_some() {
        *s += &d.layer_lookup_start(&extra);
    } else {
        *s += &d.lookup_start(&format!("{offset}{extra}"));
        *s += d.face(t.cube);
    }
    let c = t.coordinate();
    *s += d.coordinate(&c);
    if c.bias_again {
        *s += d.bias_again();
    }
    if c.u_nudge_texels != 0.0 {
        // `{:?}` always writes a point or an exponent ("0.25", "1.0"): a float in both
        // languages, where Display would write "1".
        *s += &d.nudge_u(&format!("{:?}", c.u_nudge_texels));
    }
    if c.v_nudge_texels != 0.0 {
        *s += &format!(
            "  c.y = c.y + {} / {};\n",
            literal(c.v_nudge_texels),
            d.uniform(Uniform::MapHeight)
        );
    }
    // A mipmapped sample comes before the tests (uniform control flow for its derivatives)
    // and is returned after them: the same value wherever the tests do not return lit.
    let sample_first = t.taps() == Taps::HardwareMipmapped;
    if !sample_first {
        tests(s, d, t);
    }
    if t.cube {
        *s += d.cube_rows();
    }
    *s += d.bias_start();
    if let Some(k) = t.slope_scale() {
        // tan(acos(c)) in its algebraic form (umbra_ref::lookup, step 6).
        let scale = d.uniform(Uniform::SlopeScale);
        let scale = match k {
            1.0 => scale.to_string(),
            k => format!("{k} * {scale}"),
        };
        *s += &d.slope_bias(&scale);
    }
    if t.n_dot_l {
        // LearnOpenGL's max(s·(1 − N·L), min), N·L unclamped (umbra_ref::lookup, step 6);
        // its L is the vector to the light's position even for an orthographic light.
        let l = if t.n_dot_l_from_position {
            format!("normalize({} - p)", d.uniform(Uniform::LightPosition))
        } else {
            "to_light(p)".to_string()
        };
        *s += &format!(
            "  bias += max({} * (1.0 - dot(n, {l})), {});\n",
            d.uniform(Uniform::NdotLScale),
            d.uniform(Uniform::NdotLMin)
        );
    }
    *s += d.reference();
    if t.shader_clamps_reference() {
        *s += "  r = clamp(r, 0.0, 1.0);\n";
    }
    let (w, h) = (d.uniform(Uniform::MapWidth), d.uniform(Uniform::MapHeight));
    match t.taps() {
        Taps::HardwareCube => *s += d.sample_cube(),
        Taps::HardwareProjective => *s += d.sample_projective(),
        Taps::Hardware => *s += d.sample(),
        Taps::HardwareMipmapped => {
            *s += d.sample_mipmapped();
            tests(s, d, t);
            *s += "  return m;\n";
        }
        Taps::Nearest => {
            *s += &format!("  return tap(f, floor(c.x * {w}), floor(c.y * {h}), r);\n")
        }
        Taps::Bilinear {
            coarse_weights,
            weight_gain_ppm,
        } => {
            *s += d.bilinear_start();
            if coarse_weights {
                *s += "  a = floor(a * 4.0) / 4.0;\n";
            }
            if weight_gain_ppm != 0 {
                let k = 1.0 + weight_gain_ppm as f32 / 1e6;
                // Kept in [0, 1] (`a * 0.0` is the zero vector in both languages): a wrong
                // weight, not a negative one.
                *s += &format!(
                    "  a = min(max(0.5 + (a - 0.5) * {}, a * 0.0), a * 0.0 + 1.0);\n",
                    literal(k)
                );
            }
            *s += "  return (1.0 - a.x) * (1.0 - a.y) * tap(f, i0.x, i0.y, r) + a.x * (1.0 - a.y) * tap(f, i0.x + 1.0, i0.y, r)\n\
                    + (1.0 - a.x) * a.y * tap(f, i0.x, i0.y + 1.0, r) + a.x * a.y * tap(f, i0.x + 1.0, i0.y + 1.0, r);\n";
        }
        Taps::Castano13 => *s += d.castano(),
        Taps::Vogel5 {
            rotated,
            window_y_down,
            sqrt_radius,
        } => vogel(s, d, rotated, window_y_down, sqrt_radius),
        Taps::Pcf {
            n,
            off_centre,
            double_centre,
        } => {
            let size = d.float_of(n);
            let centre = if off_centre {
                format!("{size} * 0.5")
            } else {
                format!("({size} - 1.0) * 0.5")
            };
            *s += &d.pcf_sum(n, &centre);
            if double_centre {
                *s += d.pcf_double_centre();
            }
            *s += &d.pcf_mean(n);
        }
    }
    *s += "}\n";
    if let Some(c) = cascades {
        *s += &d.cascaded_visibility(&offset, &c);
    }
}

/// three.js's PCF (`umbra_ref::lookup`'s `vogel`): `getShadow`'s five `texture` compares at
/// `shadowCoord.xy + vogelDiskSample(k, 5, phi) * radius`, same operations, same order, the
/// sum times 0.2; `phi` from `interleavedGradientNoise(gl_FragCoord.xy)` unless the disk
/// is not `rotated`, the window read with y down under `window_y_down`, the taps' radii
/// without their square root unless `sqrt_radius` (the self-test's faults).
fn vogel(s: &mut String, d: &impl Dialect, rotated: bool, window_y_down: bool, sqrt_radius: bool) {
    let (v2, f) = (d.vec2(), d.local("float"));
    let phi = if rotated {
        // A highp copy of the window position: ESSL 1.00 declares gl_FragCoord mediump, and
        // an operation takes its operands' precision (literals have none), so the noise would
        // be computed in mediump, fp16 on Mesa's llvmpipe and zink, which scrambles it; WebGL 2
        // (three.js's only target since r163) and every other language here have it highp.
        // Pixel centres are exact in fp16 below 1024.
        let _ = writeln!(
            s,
            "  {} window = {};",
            d.local("highp vec2"),
            d.window(window_y_down)
        );
        format!(
            "fract(52.982918900 * fract(dot(window, {v2}(0.067110560, 0.005837150)))) * 6.283185307"
        )
    } else {
        "0.0".to_string()
    };
    let _ = writeln!(s, "  {f} phi = {phi};");
    // `shadowRadius * texelSize`, shadow.radius 1 (three.js's default), a vec2 since r187.
    let _ = writeln!(
        s,
        "  {} radius = 1.0 * ({v2}(1.0) / {v2}({}, {}));",
        d.local("vec2"),
        d.uniform(Uniform::MapWidth),
        d.uniform(Uniform::MapHeight)
    );
    let _ = writeln!(s, "  {f} sum = 0.0;");
    for k in 0..5 {
        let share = format!("({k}.0 + 0.5) / 5.0");
        let rk = if sqrt_radius {
            format!("sqrt({share})")
        } else {
            format!("({share})")
        };
        // three.js adds the disk along GL's texture v (WebGL's shadowCoord).
        let sin = if d.v_down() { "-sin" } else { "sin" };
        let _ = writeln!(
            s,
            "  {f} theta{k} = {k}.0 * 2.399963230 + phi;\n  \
             sum += compare_at(f, c.xy + {v2}(cos(theta{k}), {sin}(theta{k})) * {rk} * radius, r);"
        );
    }
    *s += "  return sum * 0.2;\n";
}

/// The guard, the outside test and the beyond-far test: each returns lit.
fn tests(s: &mut String, d: &impl Dialect, t: &Technique) {
    if t.guards() {
        *s += d.guard();
    }
    if t.tests_outside() {
        *s += d.outside_test();
    }
    if t.beyond_far_lit {
        // Tutorial code's `if (projCoords.z > 1.0) shadow = 0.0`, before any shader bias
        // (umbra_ref::lookup, step 5).
        *s += match t.order {
            DepthOrder::Forward => "  if (c.z > 1.0) { return 1.0; }\n",
            DepthOrder::Reversed => "  if (c.z < 0.0) { return 1.0; }\n",
        };
    }
}

/// `shade(albedo, n, l, e, vis)` (umbra_ref::shading).
fn shade(s: &mut String, d: &impl Dialect, t: &Technique) {
    let shading = &t.shading;
    let light = t.light_colour().map(|c| d.vec3(c));
    *s += d.shade_start();
    match shading.model {
        ShadingModel::Dimmed => {
            let kept = if t.keeps_diffuse_in_shadow() {
                format!("{k:.9} + (1.0 - {k:.9}) * vis", k = shading.dimming)
            } else {
                "vis".to_string()
            };
            let lit_spec = if t.shadows_specular() {
                "vis * spec"
            } else {
                "spec"
            };
            *s += &d.dimmed(&kept, lit_spec, light.as_deref(), shading);
        }
        ShadingModel::Classic => {
            let diffuse = match &light {
                Some(l) => format!("diffuse * {l}"),
                None => "diffuse".to_string(),
            };
            *s += &format!(
                "  return ({a:.9} + {diffuse}) * albedo * ({f:.9} + (1.0 - {f:.9}) * vis);\n",
                a = shading.ambient,
                f = shading.shadowed_factor
            );
        }
    }
    *s += "}\n";
}
