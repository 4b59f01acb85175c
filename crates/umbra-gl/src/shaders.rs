//! GLSL for both passes, generated per API and technique. The lit-pass lookup mirrors
//! `umbra_ref::lookup` step by step (normal offset, face, coordinate with the bias matrix
//! before or after the divide, guard, outside test, bias, the compare's clamp, filter), so a
//! difference from the reference is a driver's, not a transcription's.
//!
//! - GL 3.3 (`#version 330 core`) and GLES 3.0 (`#version 300 es`): hardware compare through
//!   `sampler2DShadow`/`samplerCubeShadow` (`textureProj` when the bias matrix is applied
//!   before the divide, as the classic code does), or a manual compare of `texelFetch(...).r`
//!   (never `.z`: a core depth read returns (d, 0, 0, 1)).
//! - GLES 2.0 (`#version 100`): no shadow samplers, so the shadow pass packs
//!   `gl_FragCoord.z` into RGBA8 and the lit pass unpacks texels fetched at their centres
//!   and compares in the shader. A "hardware" case keeps its semantics there (the reference is
//!   clamped to [0,1] for fixed-point formats); only the mechanism is the shader's.
//!
//! Texels the shader addresses itself (manual compare, PCF, cube faces) are selected exactly
//! as the reference selects them, floor(u·size), with the wrap policy applied in the shader.
//! Cube-map texels are reached through the direction of their centre (the inverse of the GL
//! cube-map face table), which selects exactly that texel with NEAREST filtering.

use std::fmt::Write as _;

use umbra_case::fault::Fault;
use umbra_case::format::{BiasMatrix, Compare, DepthOrder, Filter, Outside, Shading, ShadingModel};

use crate::api::Api;

/// Everything that changes the generated source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Key {
    /// API flavour.
    pub api: Api,
    /// A cube map (point light).
    pub cube: bool,
    /// Directional light (parallel rays).
    pub directional: bool,
    /// Filter.
    pub filter: Filter,
    /// Compare mechanism (GLES 2 is always manual).
    pub compare: Compare,
    /// Clamp the reference to [0,1] (hardware semantics on a fixed-point format).
    pub clamp_reference: bool,
    /// Outside policy.
    pub outside: Outside,
    /// w > 0 guard.
    pub guard: bool,
    /// Bias matrix order.
    pub bias_matrix: BiasMatrix,
    /// Depth order.
    pub order: DepthOrder,
    /// Slope bias present.
    pub slope: bool,
    /// N·L bias present.
    pub n_dot_l: bool,
    /// Shading model.
    pub model: ShadingModel,
    /// An injected fault (self-test only).
    pub fault: Option<Fault>,
}

fn header(api: Api, fragment: bool) -> String {
    let mut s = String::new();
    match api {
        Api::Gl33 => s.push_str("#version 330 core\n"),
        Api::Gles3 => s.push_str(
            "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler2D;\n\
             precision highp sampler2DShadow;\nprecision highp samplerCube;\nprecision highp samplerCubeShadow;\n",
        ),
        Api::Gles2 => s.push_str("#version 100\nprecision highp float;\n"),
    }
    if api == Api::Gles2 {
        s.push_str(if fragment {
            "#define IN varying\n"
        } else {
            "#define IN attribute\n#define OUT varying\n"
        });
        s.push_str("#define FLAT\n");
    } else {
        s.push_str(if fragment {
            "#define IN in\n"
        } else {
            "#define IN in\n#define OUT out\n"
        });
        s.push_str("#define FLAT flat\n");
    }
    s
}

/// Vertex shader of the shadow pass: position only.
pub fn shadow_vertex(api: Api) -> String {
    let mut s = header(api, false);
    s.push_str("IN vec3 a_pos;\nuniform mat4 u_view_proj;\nvoid main() { gl_Position = u_view_proj * vec4(a_pos, 1.0); }\n");
    s
}

/// Fragment shader of the shadow pass: nothing (depth only), a constant (the dummy colour
/// attachment), or packed depth (GLES 2).
///
/// GLES 2 packs `gl_FragCoord.z`, and whether that value carries the fixed-function polygon
/// offset differs between drivers (the GLSL ES 1.00 wording is loose), so the GLES 2 path
/// applies the case's offset itself with the spec's formula, o = m·factor + r·units with
/// m = max(|∂z/∂x|, |∂z/∂y|) from screen-space derivatives (OES_standard_derivatives),
/// limited by the case's clamp as glPolygonOffsetClamp does, and leaves glPolygonOffset off. The offset depth is also written to `gl_FragDepthEXT`
/// (EXT_frag_depth), so the shadow pass's depth test compares offset depths as the
/// fixed-function offset would: otherwise another surface can win near contacts.
pub fn shadow_fragment(api: Api, with_color: bool) -> String {
    let mut s = header(api, true);
    match api {
        Api::Gles2 => {
            s = s.replacen(
                "#version 100\n",
                "#version 100\n#extension GL_OES_standard_derivatives : enable\n#extension GL_EXT_frag_depth : enable\n",
                1,
            );
            s.push_str(
                "// Depth in [0,1) as four base-255 digits, each stored as (k + 1/4)/255 so that\n\
                 // a unorm8 conversion that rounds and one that truncates both give back k\n\
                 // (the classic fract() packing relies on rounding, and llvmpipe truncates).\n\
                 vec4 pack_depth(float d) {\n\
                   vec4 k;\n  float x = d * 255.0;\n\
                   k.x = floor(x); x = (x - k.x) * 255.0;\n\
                   k.y = floor(x); x = (x - k.y) * 255.0;\n\
                   k.z = floor(x); x = (x - k.z) * 255.0;\n\
                   k.w = floor(x);\n\
                   return (k + 0.25) / 255.0;\n}\n\
                 // (factor, r * units, clamp), signed away from the light; clamp 0 is none,\n\
                 // otherwise the offset is limited to it as glPolygonOffsetClamp does.\n\
                 uniform vec3 u_offset;\n\
                 void main() {\n\
                   float z = gl_FragCoord.z;\n\
                   float m = max(abs(dFdx(z)), abs(dFdy(z)));\n\
                   float o = u_offset.x * m + u_offset.y;\n\
                   if (u_offset.z > 0.0) o = min(o, u_offset.z);\n\
                   if (u_offset.z < 0.0) o = max(o, u_offset.z);\n\
                   z = clamp(z + o, 0.0, 1.0);\n\
                   gl_FragDepthEXT = z;\n\
                   gl_FragColor = z >= 1.0 ? vec4(1.0) : pack_depth(z);\n}\n",
            )
        }
        _ if with_color => {
            s.push_str("out vec4 o_color;\nvoid main() { o_color = vec4(1.0, 0.0, 1.0, 1.0); }\n")
        }
        _ => s.push_str("void main() {}\n"),
    }
    s
}

/// Vertex shader of the lit pass.
pub fn lit_vertex(api: Api) -> String {
    let mut s = header(api, false);
    s.push_str(
        "IN vec3 a_pos;\nIN vec3 a_normal;\nIN vec3 a_albedo;\nIN float a_face;\n\
         uniform mat4 u_view_proj;\n\
         OUT vec3 v_pos;\nOUT vec3 v_normal;\nOUT vec3 v_albedo;\nFLAT OUT float v_face;\n\
         void main() {\n  v_pos = a_pos;\n  v_normal = a_normal;\n  v_albedo = a_albedo;\n  v_face = a_face;\n\
           gl_Position = u_view_proj * vec4(a_pos, 1.0);\n}\n",
    );
    s
}

/// Fragment shader of the lit pass.
pub fn lit_fragment(k: &Key, shading: &Shading) -> String {
    let api = k.api;
    let es2 = api == Api::Gles2;
    let mut s = header(api, true);
    let manual = es2 || k.compare == Compare::Manual;
    let faces = if k.cube { 6 } else { 1 };
    let _ = writeln!(
        s,
        "IN vec3 v_pos;\nIN vec3 v_normal;\nIN vec3 v_albedo;\nFLAT IN float v_face;"
    );
    let _ = writeln!(
        s,
        "uniform mat4 u_light[{faces}];\nuniform mat4 u_tex[{faces}];"
    );
    s.push_str("uniform vec3 u_light_pos;\nuniform vec3 u_towards;\nuniform vec3 u_eye;\nuniform vec2 u_size;\n");
    s.push_str("uniform float u_constant;\nuniform float u_slope_scale;\nuniform float u_slope_max;\nuniform float u_normal_offset;\nuniform float u_ndl_scale;\nuniform float u_ndl_min;\n");
    s.push_str("uniform float u_output;\n"); // GLES 2: 0 colour, 1 visibility + face
    let sampler = match (k.cube, manual, es2) {
        (false, false, _) => "sampler2DShadow",
        (true, false, _) => "samplerCubeShadow",
        (false, true, _) => "sampler2D",
        (true, true, _) => "samplerCube",
    };
    let _ = writeln!(s, "uniform {sampler} u_map;");
    if !es2 {
        s.push_str(
            "layout(location = 0) out vec4 o_color;\nlayout(location = 1) out vec4 o_vis;\n",
        );
    }
    let far = if k.order == DepthOrder::Forward {
        "1.0"
    } else {
        "-1.0"
    };
    let clear = if k.order == DepthOrder::Forward {
        "1.0"
    } else {
        "0.0"
    };
    let cmp = match (k.order == DepthOrder::Forward, k.fault) {
        (true, Some(Fault::CompareFlipped)) => ">",
        (false, Some(Fault::CompareFlipped)) => "<",
        (true, Some(Fault::CompareStrict)) => "<",
        (false, Some(Fault::CompareStrict)) => ">",
        (true, _) => "<=",
        (false, _) => ">=",
    };
    let _ = writeln!(
        s,
        "const float TOWARD_FAR = {far};\nconst float CLEAR = {clear};"
    );
    // Light direction.
    if k.directional {
        s.push_str("vec3 to_light(vec3 p) { return u_towards; }\n");
    } else {
        s.push_str("vec3 to_light(vec3 p) { return normalize(u_light_pos - p); }\n");
    }
    // Matrices per face (if-chain: GLSL ES 1.00 only promises constant indexing in fragments).
    s.push_str("mat4 light_m(int f) {\n");
    for f in 0..faces {
        let _ = writeln!(s, "  if (f == {f}) return u_light[{f}];");
    }
    s.push_str("  return u_light[0];\n}\nmat4 tex_m(int f) {\n");
    for f in 0..faces {
        let _ = writeln!(s, "  if (f == {f}) return u_tex[{f}];");
    }
    s.push_str("  return u_tex[0];\n}\n");
    if k.cube {
        s.push_str(
            "int cube_face(vec3 d) {\n  vec3 a = abs(d);\n\
               if (a.x >= a.y && a.x >= a.z) return d.x < 0.0 ? 1 : 0;\n\
               if (a.y >= a.z) return d.y < 0.0 ? 3 : 2;\n  return d.z < 0.0 ? 5 : 4;\n}\n\
             // Direction of the centre of texel (i, j) of face f: the GL cube-map table inverted.\n\
             vec3 texel_dir(int f, float i, float j) {\n\
               float sc = 2.0 * (i + 0.5) / u_size.x - 1.0;\n  float tc = 2.0 * (j + 0.5) / u_size.y - 1.0;\n\
               if (f == 0) return vec3(1.0, -tc, -sc);\n  if (f == 1) return vec3(-1.0, -tc, sc);\n\
               if (f == 2) return vec3(sc, 1.0, tc);\n  if (f == 3) return vec3(sc, -1.0, -tc);\n\
               if (f == 4) return vec3(sc, -tc, 1.0);\n  return vec3(-sc, -tc, -1.0);\n}\n",
        );
    }
    if es2 {
        s.push_str(
            "float unpack_depth(vec4 c) {\n  vec4 k = floor(c * 255.0 + 0.5);\n\
               if (k.x >= 255.0) return 1.0; // the cleared far plane\n\
               return dot(k, vec4(1.0 / 255.0, 1.0 / 65025.0, 1.0 / 16581375.0, 1.0 / 4228250625.0));\n}\n",
        );
    }
    // Texel fetch with the wrap policy, returning the stored depth (manual compare only: the
    // hardware path's taps go through the sampler, whose wrap mode is the policy).
    if manual {
        let outside = if k.fault == Some(Fault::Repeat) {
            Outside::Repeat
        } else if k.cube {
            Outside::ClampToEdge
        } else {
            k.outside
        };
        s.push_str("float fetch(int f, float i, float j) {\n");
        match outside {
            Outside::Border => s.push_str(
                "  if (i < 0.0 || j < 0.0 || i >= u_size.x || j >= u_size.y) return CLEAR;\n",
            ),
            Outside::Repeat => s.push_str("  i = mod(i, u_size.x);\n  j = mod(j, u_size.y);\n"),
            Outside::Lit | Outside::ClampToEdge => s.push_str(
                "  i = clamp(i, 0.0, u_size.x - 1.0);\n  j = clamp(j, 0.0, u_size.y - 1.0);\n",
            ),
        }
        let wrong = k.fault == Some(Fault::WrongComponent);
        let read = match (k.cube, es2, wrong) {
            (false, false, false) => "texelFetch(u_map, ivec2(int(i), int(j)), 0).r",
            (false, false, true) => "texelFetch(u_map, ivec2(int(i), int(j)), 0).g",
            (false, true, false) => "unpack_depth(texture2D(u_map, (vec2(i, j) + 0.5) / u_size))",
            (false, true, true) => {
                "unpack_depth(texture2D(u_map, (vec2(i, j) + 0.5) / u_size).gbar)"
            }
            (true, false, false) => "texture(u_map, texel_dir(f, i, j)).r",
            (true, false, true) => "texture(u_map, texel_dir(f, i, j)).g",
            (true, true, false) => "unpack_depth(textureCube(u_map, texel_dir(f, i, j)))",
            (true, true, true) => "unpack_depth(textureCube(u_map, texel_dir(f, i, j)).gbar)",
        };
        let _ = writeln!(s, "  return {read};\n}}");
    }
    // One compare at texel (i, j).
    if manual {
        let _ = writeln!(
            s,
            "float tap(int f, float i, float j, float r) {{ return r {cmp} fetch(f, i, j) ? 1.0 : 0.0; }}"
        );
    } else if k.cube {
        s.push_str("float tap(int f, float i, float j, float r) { return texture(u_map, vec4(texel_dir(f, i, j), r)); }\n");
    } else {
        s.push_str("float tap(int f, float i, float j, float r) { return texture(u_map, vec3((vec2(i, j) + 0.5) / u_size, r)); }\n");
    }
    // The lookup.
    if k.fault == Some(Fault::NormalOffsetShort) {
        s.push_str("float visibility(vec3 p, vec3 n) {\n  p = p + n * (0.75 * u_normal_offset);\n");
    } else {
        s.push_str("float visibility(vec3 p, vec3 n) {\n  p = p + n * u_normal_offset;\n");
    }
    if k.cube {
        s.push_str("  int f = cube_face(p - u_light_pos);\n");
    } else {
        s.push_str("  int f = 0;\n");
    }
    let f = k.fault;
    match (k.bias_matrix, f) {
        (BiasMatrix::BeforeDivide, Some(Fault::NoDivide)) => s.push_str("  vec4 t = tex_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(t.xyz, t.w);\n"),
        (BiasMatrix::BeforeDivide, Some(Fault::NoBias)) => s.push_str("  vec4 t = light_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(t.xyz / t.w, t.w);\n"),
        (BiasMatrix::BeforeDivide, _) => s.push_str("  vec4 t = tex_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(t.xyz / t.w, t.w);\n"),
        (BiasMatrix::AfterDivide, Some(Fault::NoDivide)) => s.push_str("  vec4 l = light_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(0.5 * l.xyz + 0.5, l.w);\n"),
        (BiasMatrix::AfterDivide, Some(Fault::NoBias)) => s.push_str("  vec4 l = light_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(l.xyz / l.w, l.w);\n"),
        (BiasMatrix::AfterDivide, _) => s.push_str(
            "  vec4 l = light_m(f) * vec4(p, 1.0);\n  vec3 ndc = vec3(l.x / l.w, l.y / l.w, l.z / l.w);\n\
               vec4 c = vec4(0.5 * ndc + 0.5, l.w);\n",
        ),
    }
    if f == Some(Fault::BiasTwice) {
        s.push_str("  c.xyz = 0.5 * c.xyz + 0.5;\n");
    }
    if f == Some(Fault::QuarterTexel) {
        s.push_str("  c.x += 0.25 / u_size.x;\n");
    }
    if k.guard && f != Some(Fault::NoGuard) {
        s.push_str("  if (c.w <= 0.0) return 1.0;\n");
    }
    if !k.cube && k.outside == Outside::Lit {
        s.push_str("  if (c.x < 0.0 || c.x > 1.0 || c.y < 0.0 || c.y > 1.0) return 1.0;\n");
    }
    s.push_str("  float bias = u_constant;\n");
    if k.slope {
        // tan(acos(c)) in its algebraic form (umbra_ref::lookup, step 6).
        let scale = if f == Some(Fault::SlopeShort) {
            "0.8 * u_slope_scale"
        } else {
            "u_slope_scale"
        };
        let _ = writeln!(
            s,
            "  float cosine = dot(n, to_light(p));\n  if (cosine > 0.0) bias += clamp({scale} * sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine, 0.0, u_slope_max);"
        );
    }
    if k.n_dot_l {
        // LearnOpenGL's max(s·(1 − N·L), min), N·L unclamped (umbra_ref::lookup, step 6).
        s.push_str("  bias += max(u_ndl_scale * (1.0 - dot(n, to_light(p))), u_ndl_min);\n");
    }
    s.push_str("  float r = c.z - TOWARD_FAR * bias;\n");
    if manual && k.clamp_reference && f != Some(Fault::NoClamp) {
        s.push_str("  r = clamp(r, 0.0, 1.0);\n"); // hardware semantics emulated (GLES 2)
    }
    if !manual && !k.clamp_reference && f == Some(Fault::ClampFloat) {
        s.push_str("  r = clamp(r, 0.0, 1.0);\n"); // a float format clamped like a fixed one
    }
    let hw_direct = !manual && !matches!(k.filter, Filter::Pcf(_));
    match k.filter {
        _ if hw_direct && k.cube => {
            s.push_str("  return texture(u_map, vec4(p - u_light_pos, r));\n")
        }
        _ if hw_direct && k.bias_matrix == BiasMatrix::BeforeDivide && f.is_none() => {
            s.push_str("  return textureProj(u_map, vec4(t.xy, t.w * r, t.w));\n")
        }
        _ if hw_direct => s.push_str("  return texture(u_map, vec3(c.xy, r));\n"),
        Filter::Nearest => {
            s.push_str("  return tap(f, floor(c.x * u_size.x), floor(c.y * u_size.y), r);\n")
        }
        Filter::Linear => {
            s.push_str(
                "  vec2 x = c.xy * u_size - 0.5;\n  vec2 i0 = floor(x);\n  vec2 a = x - i0;\n",
            );
            if f == Some(Fault::BilinearCoarse) {
                s.push_str("  a = floor(a * 4.0) / 4.0;\n");
            }
            s.push_str(
                "  return (1.0 - a.x) * (1.0 - a.y) * tap(f, i0.x, i0.y, r) + a.x * (1.0 - a.y) * tap(f, i0.x + 1.0, i0.y, r)\n\
                    + (1.0 - a.x) * a.y * tap(f, i0.x, i0.y + 1.0, r) + a.x * a.y * tap(f, i0.x + 1.0, i0.y + 1.0, r);\n",
            );
        }
        Filter::Pcf(n) => {
            let centre = if f == Some(Fault::PcfOffCentre) {
                format!("{n}.0 * 0.5")
            } else {
                format!("({n}.0 - 1.0) * 0.5")
            };
            let _ = writeln!(
                s,
                "  float sum = 0.0;\n  float h = {centre};\n\
                   for (int dy = 0; dy < {n}; dy++) {{\n    for (int dx = 0; dx < {n}; dx++) {{\n\
                       vec2 uv = c.xy + (vec2(float(dx), float(dy)) - h) / u_size;\n\
                       sum += tap(f, floor(uv.x * u_size.x), floor(uv.y * u_size.y), r);\n    }}\n  }}"
            );
            if f == Some(Fault::PcfDoubleCentre) {
                s.push_str(
                    "  vec2 uv0 = c.xy + (vec2(0.0) - h) / u_size;\n\
                       sum += tap(f, floor(c.x * u_size.x), floor(c.y * u_size.y), r) - tap(f, floor(uv0.x * u_size.x), floor(uv0.y * u_size.y), r);\n",
                );
            }
            let _ = writeln!(s, "  return sum / float({n} * {n});");
        }
    }
    s.push_str("}\n");
    // Shading (umbra_ref::shading).
    let _ = writeln!(
        s,
        "vec3 shade(vec3 albedo, vec3 n, vec3 l, vec3 e, float vis) {{\n  float ndl = dot(n, l);\n  float diffuse = max(ndl, 0.0);"
    );
    match k.model {
        ShadingModel::Dimmed => {
            let kept = if k.fault == Some(Fault::DimmingOff) {
                "vis".to_string()
            } else {
                format!("{d:.9} + (1.0 - {d:.9}) * vis", d = shading.dimming)
            };
            let lit_spec = if k.fault == Some(Fault::SpecularUnshadowed) {
                "spec"
            } else {
                "vis * spec"
            };
            let _ = writeln!(
                s,
                "  float kept = {kept};\n  float spec = 0.0;\n\
                   if (ndl > 0.0) {{ vec3 hv = l + e; float len = length(hv); if (len > 0.0) spec = {ks:.9} * pow(max(dot(n, hv / len), 0.0), {sh:.9}); }}\n\
                   return ({a:.9} + kept * diffuse) * albedo + vec3({lit_spec});",
                ks = shading.specular,
                sh = shading.shininess,
                a = shading.ambient
            );
        }
        ShadingModel::Classic => {
            let _ = writeln!(
                s,
                "  return ({a:.9} + diffuse) * albedo * ({f:.9} + (1.0 - {f:.9}) * vis);",
                a = shading.ambient,
                f = shading.shadowed_factor
            );
        }
    }
    s.push_str("}\n");
    // Outputs: colour; visibility in R and face id + 1 in G, B, A (base 256).
    s.push_str(
        "vec4 encode(float vis, float face) {\n  float id = face + 1.0;\n\
           return vec4(vis, mod(id, 256.0) / 255.0, mod(floor(id / 256.0), 256.0) / 255.0, floor(id / 65536.0) / 255.0);\n}\n\
         void main() {\n  vec3 n = normalize(v_normal);\n  float vis = visibility(v_pos, n);\n",
    );
    if k.fault == Some(Fault::Vis4Bit) {
        s.push_str("  vis = floor(vis * 16.0 + 0.5) / 16.0;\n");
    }
    s.push_str(
        "  vec3 e = normalize(u_eye - v_pos);\n  vec3 col = clamp(shade(v_albedo, n, to_light(v_pos), e, vis), 0.0, 1.0);\n\
           float face = floor(v_face + 0.5);\n",
    );
    if k.fault == Some(Fault::ColourGamma) {
        s.push_str("  col = sqrt(col);\n");
    }
    if es2 {
        s.push_str("  gl_FragColor = u_output < 0.5 ? vec4(col, 1.0) : encode(vis, face);\n}\n");
    } else {
        s.push_str("  o_color = vec4(col, 1.0);\n  o_vis = encode(vis, face);\n}\n");
    }
    s
}
