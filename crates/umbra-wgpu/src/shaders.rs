//! WGSL for both passes, generated per technique. The lit pass is [`umbra_case::lit_shader`]'s:
//! it decides the lookup's steps (mirroring `umbra_ref::lookup`) and the self-test faults'
//! effect on them, the same for GLSL; this file supplies only WGSL (`Wgsl`, a [`Dialect`]),
//! in the zero-to-one convention: the bias matrix maps v = 0.5 − 0.5·y (texture rows
//! run down, as wgpu's framebuffer rows do), depth is clip z / w with no remapping.
//!
//! - Hardware compare: `textureSampleCompareLevel` with a comparison sampler (the `Level`
//!   form has no uniform-control-flow requirement, so the guard and the outside test may
//!   return early).
//! - Manual compare: `textureLoad` of the depth texel and a compare in the shader, with the
//!   wrap policy applied in the shader.
//! - Cube maps: faces are rendered with y flipped
//!   ([`umbra_case::Convention::cube_face_render_flip`]) so that hardware cube sampling by
//!   direction reads them; texel-addressed lookups use row t = 1 − v and reach texel (i, t) of
//!   face f through the direction of its centre (the GL/Vulkan face table inverted), or through
//!   `textureLoad` on a 2D-array view of the same texture for the manual compare.

use std::fmt::Write as _;

use umbra_case::Technique;
use umbra_case::format::{BiasMatrix, Outside, Shading};
use umbra_case::lit_shader::{self, CascadeSelect, Dialect, Uniform};
use umbra_case::technique::{CompareOp, Coordinate, CoordinateStep};

/// The uniform block shared by both passes (std140-compatible layout, 16-byte vectors).
/// `view_row` and `split` serve cascades: the view depth d = view_row · (p, 1) and the split
/// depths s_0 … s_7 in two vectors.
pub const UNIFORMS: &str = "struct U {\n  view_proj: mat4x4<f32>,\n  light: array<mat4x4<f32>, 6>,\n  tex: array<mat4x4<f32>, 6>,\n  light_pos: vec4<f32>,\n  towards: vec4<f32>,\n  eye: vec4<f32>,\n  size: vec4<f32>,\n  bias: vec4<f32>,\n  view_row: vec4<f32>,\n  split: array<vec4<f32>, 2>,\n  offsets: array<vec4<f32>, 2>,\n}\n@group(0) @binding(0) var<uniform> u: U;\n";

/// Size of [`UNIFORMS`] in bytes: 13 matrices and 10 vectors.
pub const UNIFORM_SIZE: u64 = 13 * 64 + 10 * 16;

/// The shadow pass: position only; a constant colour for the `with_color` variant.
pub fn shadow(with_color: bool) -> String {
    let mut s = String::from(UNIFORMS);
    s.push_str("@vertex fn vs(@location(0) pos: vec3<f32>) -> @builtin(position) vec4<f32> { return u.view_proj * vec4<f32>(pos, 1.0); }\n");
    if with_color {
        s.push_str("@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(1.0, 0.0, 1.0, 1.0); }\n");
    }
    s
}

/// A generated mip level (`MipSource::Averaged`): one triangle over the level, each
/// fragment's depth the mean of the 2 × 2 depths of the level above (bound alone as `src`),
/// in the order `umbra_ref::shadow_pass::averaged` computes it.
/// wgpu's GL backend cannot run it: see the backend's `supports`.
pub const AVERAGE: &str = "@group(0) @binding(0) var src: texture_depth_2d;
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
  let c = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
  return vec4<f32>(c * 2.0 - 1.0, 0.0, 1.0);
}
@fragment fn fs(@builtin(position) pos: vec4<f32>) -> @builtin(frag_depth) f32 {
  let last = vec2<i32>(textureDimensions(src)) - 1;
  let p = 2 * vec2<i32>(pos.xy);
  let a = textureLoad(src, min(p, last), 0);
  let b = textureLoad(src, min(p + vec2<i32>(1, 0), last), 0);
  let c = textureLoad(src, min(p + vec2<i32>(0, 1), last), 0);
  let d = textureLoad(src, min(p + vec2<i32>(1, 1), last), 0);
  return 0.25 * (a + b + c + d);
}
";

/// The lit pass: its vertex stage and the shared lookup and shading
/// ([`umbra_case::lit_shader`]) in WGSL.
pub fn lit(t: &Technique) -> String {
    lit_shader::lit_fragment(
        &Wgsl {
            layered: t.flat_array(),
            cube_array: t.cube_array(),
        },
        t,
    )
}

/// WGSL, in the zero-to-one convention, for one technique's map.
struct Wgsl {
    /// The map is a 2D array (cascades, or several spot or directional lights' maps).
    layered: bool,
    /// The map is a cube-map array (several point lights' maps): cube LAYER is the light's,
    /// its faces layers 6 · LAYER + f of the 2D-array view a manual compare reads.
    cube_array: bool,
}

impl Dialect for Wgsl {
    fn declarations(&self, t: &Technique) -> String {
        let mut s = String::from(UNIFORMS);
        let texture = match (t.cube, t.manual()) {
            (true, false) if self.cube_array => "texture_depth_cube_array",
            _ if self.layered => "texture_depth_2d_array",
            (false, _) => "texture_depth_2d",
            (true, false) => "texture_depth_cube",
            (true, true) => "texture_depth_2d_array",
        };
        let _ = writeln!(s, "@group(0) @binding(1) var map: {texture};");
        if self.layered || self.cube_array {
            // The layer of face f is f + LAYER: a cascade's, or a light's among several (the
            // cube LAYER of a cube-map array).
            let _ = writeln!(s, "const LAYER: i32 = {};", t.layer_base());
        }
        if !t.manual() {
            s.push_str("@group(0) @binding(2) var samp: sampler_comparison;\n");
        }
        s.push_str(
            "struct VOut {\n  @builtin(position) clip: vec4<f32>,\n  @location(0) pos: vec3<f32>,\n  @location(1) normal: vec3<f32>,\n\
               @location(2) albedo: vec3<f32>,\n  @location(3) @interpolate(flat) face: f32,\n}\n\
             @vertex fn vs(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) albedo: vec3<f32>, @location(3) face: f32) -> VOut {\n\
               var o: VOut;\n  o.clip = u.view_proj * vec4<f32>(pos, 1.0);\n  o.pos = pos;\n  o.normal = normal;\n  o.albedo = albedo;\n  o.face = face;\n  return o;\n}\n",
        );
        s
    }

    fn constant(&self, name: &str, value: &str) -> String {
        format!("const {name}: f32 = {value};\n")
    }

    fn to_light(&self, directional: bool) -> &'static str {
        if directional {
            "fn to_light(p: vec3<f32>) -> vec3<f32> { return u.towards.xyz; }\n"
        } else {
            "fn to_light(p: vec3<f32>) -> vec3<f32> { return normalize(u.light_pos.xyz - p); }\n"
        }
    }

    /// WGSL indexes `u.light` and `u.tex` with `f` directly.
    fn face_matrices(&self, _faces: usize, _offsets: bool) -> String {
        String::new()
    }

    fn cube_helpers(&self) -> &'static str {
        "fn cube_face(d: vec3<f32>) -> i32 {\n  let a = abs(d);\n\
           if (a.x >= a.y && a.x >= a.z) { return select(0, 1, d.x < 0.0); }\n\
           if (a.y >= a.z) { return select(2, 3, d.y < 0.0); }\n  return select(4, 5, d.z < 0.0);\n}\n\
         fn texel_dir(f: i32, i: f32, j: f32) -> vec3<f32> {\n\
           let sc = 2.0 * (i + 0.5) / u.size.x - 1.0;\n  let tc = 2.0 * (j + 0.5) / u.size.y - 1.0;\n\
           if (f == 0) { return vec3<f32>(1.0, -tc, -sc); }\n  if (f == 1) { return vec3<f32>(-1.0, -tc, sc); }\n\
           if (f == 2) { return vec3<f32>(sc, 1.0, tc); }\n  if (f == 3) { return vec3<f32>(sc, -1.0, -tc); }\n\
           if (f == 4) { return vec3<f32>(sc, -tc, 1.0); }\n  return vec3<f32>(-sc, -tc, -1.0);\n}\n"
    }

    /// The map is always a depth texture.
    fn depth_decoder(&self) -> &'static str {
        ""
    }

    /// A depth texture's `textureLoad` returns one value: there is no wrong component to read.
    fn fetch(&self, cube: bool, wrap: Outside, _wrong_component: bool) -> String {
        let mut s = String::from(
            "fn fetch(f: i32, i_in: f32, j_in: f32) -> f32 {\n  var i = i_in;\n  var j = j_in;\n",
        );
        s.push_str(match wrap {
            Outside::Border => "  if (i < 0.0 || j < 0.0 || i >= u.size.x || j >= u.size.y) { return CLEAR; }\n",
            Outside::Repeat => "  i = i - u.size.x * floor(i / u.size.x);\n  j = j - u.size.y * floor(j / u.size.y);\n",
            Outside::Lit | Outside::ClampToEdge => "  i = clamp(i, 0.0, u.size.x - 1.0);\n  j = clamp(j, 0.0, u.size.y - 1.0);\n",
        });
        if self.layered {
            s.push_str("  return textureLoad(map, vec2<i32>(i32(i), i32(j)), f + LAYER, 0);\n}\n");
        } else if cube && self.cube_array {
            s.push_str(
                "  return textureLoad(map, vec2<i32>(i32(i), i32(j)), 6 * LAYER + f, 0);\n}\n",
            );
        } else if cube {
            s.push_str("  return textureLoad(map, vec2<i32>(i32(i), i32(j)), f, 0);\n}\n");
        } else {
            s.push_str("  return textureLoad(map, vec2<i32>(i32(i), i32(j)), 0);\n}\n");
        }
        s
    }

    fn tap(&self, manual: bool, cube: bool, op: CompareOp) -> String {
        let head = "fn tap(f: i32, i: f32, j: f32, r: f32) -> f32";
        match (manual, cube) {
            (true, _) => format!(
                "{head} {{ return select(0.0, 1.0, r {} fetch(f, i, j)); }}\n",
                op.symbol()
            ),
            (false, true) if self.cube_array => format!(
                "{head} {{ return textureSampleCompareLevel(map, samp, texel_dir(f, i, j), LAYER, r); }}\n"
            ),
            (false, true) => format!(
                "{head} {{ return textureSampleCompareLevel(map, samp, texel_dir(f, i, j), r); }}\n"
            ),
            (false, false) if self.layered => format!(
                "{head} {{ return textureSampleCompareLevel(map, samp, (vec2<f32>(i, j) + 0.5) / u.size.xy, f + LAYER, r); }}\n"
            ),
            (false, false) => format!(
                "{head} {{ return textureSampleCompareLevel(map, samp, (vec2<f32>(i, j) + 0.5) / u.size.xy, r); }}\n"
            ),
        }
    }

    fn compare_at(&self, manual: bool) -> String {
        let head = "fn compare_at(f: i32, uv: vec2<f32>, r: f32) -> f32";
        match manual {
            true => format!(
                "{head} {{\n  let x = uv * u.size.xy - 0.5;\n  let i0 = floor(x);\n  let a = x - i0;\n  \
                   return (1.0 - a.x) * (1.0 - a.y) * tap(f, i0.x, i0.y, r) + a.x * (1.0 - a.y) * tap(f, i0.x + 1.0, i0.y, r)\n  \
                   + (1.0 - a.x) * a.y * tap(f, i0.x, i0.y + 1.0, r) + a.x * a.y * tap(f, i0.x + 1.0, i0.y + 1.0, r);\n}}\n"
            ),
            false if self.layered => format!(
                "{head} {{ return textureSampleCompareLevel(map, samp, uv, f + LAYER, r); }}\n"
            ),
            false => format!("{head} {{ return textureSampleCompareLevel(map, samp, uv, r); }}\n"),
        }
    }

    fn castano(&self) -> &'static str {
        "  let uv = c.xy * u.size.xy;\n  var base = floor(uv + 0.5);\n  let st = uv + 0.5 - base;\n  \
           let inv = 1.0 / u.size.xy;\n  base = (base - 0.5) * inv;\n  \
           let uw = vec3<f32>(4.0 - 3.0 * st.x, 7.0, 1.0 + 3.0 * st.x);\n  \
           let vw = vec3<f32>(4.0 - 3.0 * st.y, 7.0, 1.0 + 3.0 * st.y);\n  \
           let uo = vec3<f32>((3.0 - 2.0 * st.x) / uw.x - 2.0, (3.0 + st.x) / uw.y, st.x / uw.z + 2.0);\n  \
           let vo = vec3<f32>((3.0 - 2.0 * st.y) / vw.x - 2.0, (3.0 + st.y) / vw.y, st.y / vw.z + 2.0);\n  \
           var sum = 0.0;\n  \
           sum += uw.x * vw.x * compare_at(f, base + vec2<f32>(uo.x, vo.x) * inv, r);\n  \
           sum += uw.y * vw.x * compare_at(f, base + vec2<f32>(uo.y, vo.x) * inv, r);\n  \
           sum += uw.z * vw.x * compare_at(f, base + vec2<f32>(uo.z, vo.x) * inv, r);\n  \
           sum += uw.x * vw.y * compare_at(f, base + vec2<f32>(uo.x, vo.y) * inv, r);\n  \
           sum += uw.y * vw.y * compare_at(f, base + vec2<f32>(uo.y, vo.y) * inv, r);\n  \
           sum += uw.z * vw.y * compare_at(f, base + vec2<f32>(uo.z, vo.y) * inv, r);\n  \
           sum += uw.x * vw.z * compare_at(f, base + vec2<f32>(uo.x, vo.z) * inv, r);\n  \
           sum += uw.y * vw.z * compare_at(f, base + vec2<f32>(uo.y, vo.z) * inv, r);\n  \
           sum += uw.z * vw.z * compare_at(f, base + vec2<f32>(uo.z, vo.z) * inv, r);\n  \
           return sum * (1.0 / 144.0);\n"
    }

    /// `frag` is the fragment's `@builtin(position).xy`, y down from the top row, kept by
    /// [`Dialect::main_start`].
    fn window(&self, y_down: bool) -> &'static str {
        if y_down {
            "frag"
        } else {
            "vec2<f32>(frag.x, FRAME_HEIGHT - frag.y)"
        }
    }

    fn vec2(&self) -> &'static str {
        "vec2<f32>"
    }

    /// The zero-to-one bias matrix: v runs down the rows.
    fn v_down(&self) -> bool {
        true
    }

    fn local(&self, _glsl: &'static str) -> &'static str {
        "var"
    }

    fn uniform(&self, u: Uniform) -> &'static str {
        match u {
            Uniform::MapWidth => "u.size.x",
            Uniform::MapHeight => "u.size.y",
            Uniform::NormalOffset => "u.bias.w",
            Uniform::SlopeScale => "u.bias.y",
            Uniform::NdotLScale => "u.size.z",
            Uniform::NdotLMin => "u.size.w",
            Uniform::LightPosition => "u.light_pos.xyz",
        }
    }

    fn lookup_start(&self, offset: &str) -> String {
        format!(
            "fn visibility(p_in: vec3<f32>, n: vec3<f32>) -> f32 {{\n  let p = p_in + n * {offset};\n"
        )
    }

    fn face(&self, cube: bool) -> &'static str {
        if cube {
            "  let f = cube_face(p - u.light_pos.xyz);\n"
        } else {
            "  let f = 0;\n"
        }
    }

    /// WGSL's parameters are immutable: with `extra`, the parameter is `p_at` and `p` the
    /// moved point.
    fn layer_lookup_start(&self, extra: &str) -> String {
        if extra.is_empty() {
            "fn lookup(p: vec3<f32>, n: vec3<f32>, f: i32) -> f32 {\n".to_string()
        } else {
            format!(
                "fn lookup(p_at: vec3<f32>, n: vec3<f32>, f: i32) -> f32 {{\n  let p = p_at{extra};\n"
            )
        }
    }

    /// The faces' offsets are `u.offsets` (four to a vector), the distance towards the light
    /// `u.towards.w`.
    fn world_offsets(&self, f: &str) -> String {
        format!(" + n * u.offsets[{f} / 4][{f} % 4] + u.towards.xyz * u.towards.w")
    }

    fn cascaded_visibility(&self, offset: &str, c: &CascadeSelect) -> String {
        let n = c.count;
        let split = |k: usize| format!("u.split[{}][{}]", k / 4, k % 4);
        let mut s = format!(
            "fn visibility(p_in: vec3<f32>, n: vec3<f32>) -> f32 {{\n  let p = p_in + n * {offset};\n"
        );
        s.push_str(if c.by_distance {
            "  let d = length(p - u.eye.xyz);\n"
        } else {
            "  let d = dot(u.view_row.xyz, p) + u.view_row.w;\n"
        });
        if c.beyond {
            let _ = writeln!(s, "  if (d > {}) {{ return 1.0; }}", split(n));
        }
        let _ = writeln!(
            s,
            "  var f = 0;\n  var lo = {};\n  var hi = {};",
            split(0),
            split(1)
        );
        for k in 1..n {
            let _ = writeln!(
                s,
                "  if (d > {a}) {{ f = {k}; lo = {a}; hi = {b}; }}",
                a = split(k),
                b = split(k + 1)
            );
        }
        s.push_str("  var v = lookup(p, n, f);\n");
        if let Some(b) = c.blend_literal() {
            let _ = write!(
                s,
                "  let band = {b} * {};\n  let t = (d - (hi - band)) / band;\n\
                   if (f < {} && t > 0.0) {{ v = mix(v, lookup(p, n, f + 1), min(t, 1.0)); }}\n",
                c.band_of(),
                n - 1
            );
        }
        s.push_str("  return v;\n}\n");
        s
    }

    /// The bias matrix maps v = 0.5 − 0.5·y and leaves depth alone (zero-to-one).
    fn coordinate(&self, c: &Coordinate) -> &'static str {
        use CoordinateStep::{Bias, Divide};
        match (c.bias_matrix, c.left_out) {
            (BiasMatrix::BeforeDivide, Some(Divide)) => {
                "  let t = u.tex[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(t.xyz, t.w);\n"
            }
            (BiasMatrix::BeforeDivide, Some(Bias)) => {
                "  let t = u.light[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(t.xyz / t.w, t.w);\n"
            }
            (BiasMatrix::BeforeDivide, None) => {
                "  let t = u.tex[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(t.xyz / t.w, t.w);\n"
            }
            (BiasMatrix::AfterDivide, Some(Divide)) => {
                "  let l = u.light[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(0.5 * l.x + 0.5, 0.5 - 0.5 * l.y, l.z, l.w);\n"
            }
            (BiasMatrix::AfterDivide, Some(Bias)) => {
                "  let l = u.light[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(l.xyz / l.w, l.w);\n"
            }
            (BiasMatrix::AfterDivide, None) => {
                "  let l = u.light[f] * vec4<f32>(p, 1.0);\n  let ndc = l.xyz / l.w;\n\
               var c = vec4<f32>(0.5 * ndc.x + 0.5, 0.5 - 0.5 * ndc.y, ndc.z, l.w);\n"
            }
        }
    }

    fn bias_again(&self) -> &'static str {
        "  c = vec4<f32>(0.5 * c.x + 0.5, 0.5 - 0.5 * c.y, c.z, c.w);\n"
    }

    fn nudge_u(&self, texels: &str) -> String {
        format!("  c.x = c.x + {texels} / u.size.x;\n")
    }

    fn guard(&self) -> &'static str {
        "  if (c.w <= 0.0) { return 1.0; }\n"
    }

    fn outside_test(&self) -> &'static str {
        "  if (c.x < 0.0 || c.x > 1.0 || c.y < 0.0 || c.y > 1.0) { return 1.0; }\n"
    }

    /// Faces are rendered with y flipped, so texel rows run with the cube table's t = 1 − v.
    fn cube_rows(&self) -> &'static str {
        "  c.y = 1.0 - c.y; // face rows run with the cube table's t\n"
    }

    fn bias_start(&self) -> &'static str {
        "  var bias = u.bias.x;\n"
    }

    fn slope_bias(&self, scale: &str) -> String {
        format!(
            "  let cosine = dot(n, to_light(p));\n  if (cosine > 0.0) {{ bias += clamp({scale} * sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine, 0.0, u.bias.z); }}\n"
        )
    }

    fn reference(&self) -> &'static str {
        "  var r = c.z - TOWARD_FAR * bias;\n"
    }

    fn sample_cube(&self) -> &'static str {
        if self.cube_array {
            "  return textureSampleCompareLevel(map, samp, p - u.light_pos.xyz, LAYER, r);\n"
        } else {
            "  return textureSampleCompareLevel(map, samp, p - u.light_pos.xyz, r);\n"
        }
    }

    /// WGSL has no projective compare: c is already divided, so the ordinary one.
    fn sample_projective(&self) -> &'static str {
        self.sample()
    }

    fn sample(&self) -> &'static str {
        if self.layered {
            "  return textureSampleCompareLevel(map, samp, c.xy, f + LAYER, r);\n"
        } else {
            "  return textureSampleCompareLevel(map, samp, c.xy, r);\n"
        }
    }

    fn sample_mipmapped(&self) -> &'static str {
        "  let m = textureSampleCompare(map, samp, c.xy, r);\n"
    }

    fn bilinear_start(&self) -> &'static str {
        "  let x = c.xy * u.size.xy - 0.5;\n  let i0 = floor(x);\n  var a = x - i0;\n"
    }

    fn float_of(&self, n: u32) -> String {
        format!("f32({n})")
    }

    fn pcf_sum(&self, n: u32, centre: &str) -> String {
        format!(
            "  var sum = 0.0;\n  let h = {centre};\n\
               for (var dy = 0; dy < {n}; dy++) {{\n    for (var dx = 0; dx < {n}; dx++) {{\n\
                   let uv = c.xy + (vec2<f32>(f32(dx), f32(dy)) - h) / u.size.xy;\n\
                   sum += tap(f, floor(uv.x * u.size.x), floor(uv.y * u.size.y), r);\n    }}\n  }}\n"
        )
    }

    fn pcf_double_centre(&self) -> &'static str {
        "  let uv0 = c.xy + (vec2<f32>(0.0) - h) / u.size.xy;\n\
           sum += tap(f, floor(c.x * u.size.x), floor(c.y * u.size.y), r) - tap(f, floor(uv0.x * u.size.x), floor(uv0.y * u.size.y), r);\n"
    }

    fn pcf_mean(&self, n: u32) -> String {
        format!("  return sum / f32({n} * {n});\n")
    }

    fn shade_start(&self) -> &'static str {
        "fn shade(albedo: vec3<f32>, n: vec3<f32>, l: vec3<f32>, e: vec3<f32>, vis: f32) -> vec3<f32> {\n  let ndl = dot(n, l);\n  let diffuse = max(ndl, 0.0);\n"
    }

    fn dimmed(&self, kept: &str, lit_spec: &str, light: Option<&str>, shading: &Shading) -> String {
        let (ld, ls) = match light {
            Some(l) => (format!(" * {l}"), format!("{l} * ")),
            None => (String::new(), String::new()),
        };
        format!(
            "  let kept = {kept};\n  var spec = 0.0;\n\
               if (ndl > 0.0) {{ let hv = l + e; let len = length(hv); if (len > 0.0) {{ spec = {ks:.9} * pow(max(dot(n, hv / len), 0.0), {sh:.9}); }} }}\n\
               return ({a:.9} + kept * diffuse{ld}) * albedo + {ls}vec3<f32>({lit_spec});\n",
            ks = shading.specular,
            sh = shading.shininess,
            a = shading.ambient
        )
    }

    fn vec3(&self, v: [f32; 3]) -> String {
        format!("vec3<f32>({:.9}, {:.9}, {:.9})", v[0], v[1], v[2])
    }

    fn main_start(&self, raw_normal: bool, window: bool) -> String {
        let (frag, keep) = if window {
            ("var<private> frag: vec2<f32>;\n", "  frag = v.clip.xy;\n")
        } else {
            ("", "")
        };
        format!(
            "{frag}struct FOut {{\n  @location(0) color: vec4<f32>,\n  @location(1) vis: vec4<f32>,\n  @location(2) face: u32,\n}}\n\
             @fragment fn fs(v: VOut) -> FOut {{\n{keep}  let n = normalize(v.normal);\n  var vis = visibility(v.pos, {});\n",
            if raw_normal { "v.normal" } else { "n" }
        )
    }

    fn main_colour(&self) -> &'static str {
        "  let e = normalize(u.eye.xyz - v.pos);\n  var o: FOut;\n\
           var col = clamp(shade(v.albedo, n, to_light(v.pos), e, vis), vec3<f32>(0.0), vec3<f32>(1.0));\n"
    }

    fn main_end(&self) -> &'static str {
        "  o.color = vec4<f32>(col, 1.0);\n\
           o.vis = vec4<f32>(vis, 0.0, 0.0, 1.0);\n  o.face = u32(floor(v.face + 0.5)) + 1u;\n  return o;\n}\n"
    }
}
