//! GLSL for both passes, generated per API and technique. The lit pass is
//! [`umbra_case::lit_shader`]'s: it decides the lookup's steps (mirroring `umbra_ref::lookup`:
//! normal offset, face, coordinate with the bias matrix before or after the divide, guard,
//! outside test, bias, the compare's clamp, filter) and the self-test faults' effect on them,
//! the same for WGSL; this file supplies only GLSL (`Glsl`, one [`Dialect`] per API
//! flavour). The shadow pass and the lit pass's vertex stage are GLSL-only and written here.
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

use umbra_case::Technique;
use umbra_case::format::{BiasMatrix, Outside, Shading};
use umbra_case::lit_shader::{self, CascadeSelect, Dialect, Uniform};
use umbra_case::technique::{CompareOp, Coordinate, CoordinateStep};

use crate::api::Api;

fn header(api: Api, fragment: bool) -> String {
    header_for(api, fragment, false)
}

/// [`header`], for a lit program that reads a cube-map array when `cube_array`: on GLES that
/// is ESSL 3.20's (`samplerCubeArrayShadow` is core in GLES 3.2; ESSL 3.00 has no way to it,
/// and Mesa refuses GL_EXT_texture_cube_map_array there), and both stages of a program must
/// share their `#version`. GL 3.3 enables GL_ARB_texture_cube_map_array instead
/// ([`Glsl::declarations`]).
fn header_for(api: Api, fragment: bool, cube_array: bool) -> String {
    const ES_PRECISION: &str = "precision highp float;\nprecision highp int;\nprecision highp sampler2D;\n\
         precision highp sampler2DShadow;\nprecision highp samplerCube;\nprecision highp samplerCubeShadow;\n";
    let mut s = String::new();
    match api {
        Api::Gl33 => s.push_str("#version 330 core\n"),
        Api::Gles3 if cube_array => s.push_str(&format!("#version 320 es\n{ES_PRECISION}")),
        Api::Gles3 => s.push_str(&format!("#version 300 es\n{ES_PRECISION}")),
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

/// The extension that gives GL 3.3's GLSL its cube-map array samplers (core in GL 4.0). GLES
/// needs none: its cube-array programs are ESSL 3.20, where they are core ([`header_for`]).
pub const CUBE_ARRAY_EXTENSION: &str = "GL_ARB_texture_cube_map_array";

/// Vertex shader of the shadow pass: position only.
pub fn shadow_vertex(api: Api) -> String {
    let mut s = header(api, false);
    s.push_str("IN vec3 a_pos;\nuniform mat4 u_view_proj;\nvoid main() { gl_Position = u_view_proj * vec4(a_pos, 1.0); }\n");
    s
}

/// Vertex shader of a generated mip level's down-sampling pass: one triangle over the
/// viewport, from gl_VertexID (no attributes).
pub fn average_vertex(api: Api) -> String {
    let mut s = header(api, false);
    s.push_str(
        "void main() {\n  vec2 c = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n\
           gl_Position = vec4(c * 2.0 - 1.0, 0.0, 1.0);\n}\n",
    );
    s
}

/// Fragment shader of a generated mip level (`MipSource::Averaged`): the mean of the 2 × 2
/// depths of the level above (the texture's base level while this level is drawn), written
/// as the fragment's depth, in the order `umbra_ref::shadow_pass::averaged` computes it.
/// GL refuses glGenerateMipmap on a depth format (GL 4.6 §8.14.4: the base level must be
/// colour-renderable), so a program that wants averaged depth mips writes this pass.
pub fn average_fragment(api: Api) -> String {
    let mut s = header(api, true);
    s.push_str(
        "uniform sampler2D u_src;\n\
         void main() {\n  ivec2 last = textureSize(u_src, 0) - 1;\n  ivec2 p = 2 * ivec2(gl_FragCoord.xy);\n\
           float a = texelFetch(u_src, min(p, last), 0).r;\n\
           float b = texelFetch(u_src, min(p + ivec2(1, 0), last), 0).r;\n\
           float c = texelFetch(u_src, min(p + ivec2(0, 1), last), 0).r;\n\
           float d = texelFetch(u_src, min(p + ivec2(1, 1), last), 0).r;\n\
           gl_FragDepth = 0.25 * (a + b + c + d);\n}\n",
    );
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

/// Vertex shader of the lit pass, for the fragment shader of `t` (whose `#version` it
/// shares).
pub fn lit_vertex(api: Api, t: &Technique) -> String {
    let mut s = header_for(api, false, t.cube_array());
    s.push_str(
        "IN vec3 a_pos;\nIN vec3 a_normal;\nIN vec3 a_albedo;\nIN float a_face;\n\
         uniform mat4 u_view_proj;\n\
         OUT vec3 v_pos;\nOUT vec3 v_normal;\nOUT vec3 v_albedo;\nFLAT OUT float v_face;\n\
         void main() {\n  v_pos = a_pos;\n  v_normal = a_normal;\n  v_albedo = a_albedo;\n  v_face = a_face;\n\
           gl_Position = u_view_proj * vec4(a_pos, 1.0);\n}\n",
    );
    s
}

/// Fragment shader of the lit pass: the shared lookup and shading
/// ([`umbra_case::lit_shader`]) in this API's GLSL. `t` is the technique as this API runs it
/// ([`Api::technique`]).
pub fn lit_fragment(api: Api, t: &Technique) -> String {
    debug_assert!(
        api != Api::Gles2 || t.manual(),
        "GLES 2 compares in the shader: pass Api::technique's technique"
    );
    debug_assert!(
        api != Api::Gles2 || t.layer.is_none(),
        "GLES 2 has no array textures: the backend skips several lights in one array"
    );
    let glsl = Glsl {
        api,
        layered: t.flat_array(),
        cube_array: t.cube_array(),
    };
    lit_shader::lit_fragment(&glsl, t)
}

/// GLES 2's cascades, `faces` of them: no array textures in GLSL ES 1.00, so cascade 0 is
/// `u_map` and cascade k a sampler `u_mapk` of its own, chosen by an if-chain (a sampler
/// array may only be indexed by a constant there).
fn layer_samplers(faces: usize) -> String {
    let mut s = String::new();
    for k in 1..faces {
        let _ = writeln!(s, "uniform sampler2D u_map{k};");
    }
    s.push_str("vec4 layer_texel(int f, vec2 uv) {\n");
    for k in 1..faces {
        let _ = writeln!(s, "  if (f == {k}) return texture2D(u_map{k}, uv);");
    }
    s.push_str("  return texture2D(u_map, uv);\n}\n");
    s
}

/// GLSL in one API's flavour, for one technique's map.
struct Glsl {
    api: Api,
    /// The map is a 2D array (cascades, or several spot or directional lights' maps).
    layered: bool,
    /// The map is a cube-map array (several point lights' maps): cube LAYER is the light's.
    cube_array: bool,
}

impl Dialect for Glsl {
    fn declarations(&self, t: &Technique) -> String {
        let es2 = self.api == Api::Gles2;
        let mut s = header_for(self.api, true, self.cube_array);
        if self.cube_array && self.api == Api::Gl33 {
            // Right after #version: a cube-map array is an extension of GL 3.3 (core in GL
            // 4.0); the backend probes it before it runs the case (Caps::cube_map_array).
            let (version, rest) = s.split_once('\n').expect("a #version line");
            s = format!("{version}\n#extension {CUBE_ARRAY_EXTENSION} : require\n{rest}");
        }
        if self.cube_array && self.api == Api::Gles3 {
            // ESSL 3.20 (header_for): core, and without a default precision.
            s.push_str(
                "precision highp samplerCubeArray;\nprecision highp samplerCubeArrayShadow;\n",
            );
        }
        let faces = if t.cube { 6 } else { t.cascades.max(1) };
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
        if t.world_offsets {
            let _ = writeln!(
                s,
                "uniform float u_face_offset[{faces}];\nuniform float u_light_offset;"
            );
        }
        let sampler = match (t.cube, self.layered, t.manual()) {
            // GLES 2's cascades: a 2D texture each (Glsl::layer_samplers).
            (false, true, _) if es2 => "sampler2D",
            (true, _, false) if self.cube_array => "samplerCubeArrayShadow",
            (true, _, true) if self.cube_array => "samplerCubeArray",
            (false, false, false) => "sampler2DShadow",
            (true, _, false) => "samplerCubeShadow",
            (false, true, false) => "sampler2DArrayShadow",
            (false, false, true) => "sampler2D",
            (true, _, true) => "samplerCube",
            (false, true, true) => "sampler2DArray",
        };
        if self.layered || self.cube_array {
            if self.api == Api::Gles3 && self.layered {
                s.push_str(
                    "precision highp sampler2DArray;\nprecision highp sampler2DArrayShadow;\n",
                );
            }
            s.push_str("uniform vec4 u_view_row;\nuniform float u_split[8];\n");
            // The layer of face f is f + LAYER: a cascade's, or a light's among several (the
            // cube LAYER of a cube-map array).
            let _ = writeln!(s, "const int LAYER = {};", t.layer_base());
        }
        let _ = writeln!(s, "uniform {sampler} u_map;");
        if es2 && self.layered {
            s.push_str(&layer_samplers(faces));
        }
        if !es2 {
            s.push_str(
                "layout(location = 0) out vec4 o_color;\nlayout(location = 1) out vec4 o_vis;\n",
            );
        }
        s
    }

    fn constant(&self, name: &str, value: &str) -> String {
        format!("const float {name} = {value};\n")
    }

    fn to_light(&self, directional: bool) -> &'static str {
        if directional {
            "vec3 to_light(vec3 p) { return u_towards; }\n"
        } else {
            "vec3 to_light(vec3 p) { return normalize(u_light_pos - p); }\n"
        }
    }

    /// An if-chain: GLSL ES 1.00 only promises constant indexing in fragments.
    fn face_matrices(&self, faces: usize, offsets: bool) -> String {
        let mut s = String::new();
        let mut accessor = |ty: &str, name: &str, array: &str| {
            let _ = writeln!(s, "{ty} {name}(int f) {{");
            for f in 0..faces {
                let _ = writeln!(s, "  if (f == {f}) return {array}[{f}];");
            }
            let _ = writeln!(s, "  return {array}[0];\n}}");
        };
        accessor("mat4", "light_m", "u_light");
        accessor("mat4", "tex_m", "u_tex");
        if offsets {
            accessor("float", "face_offset", "u_face_offset");
        }
        s
    }

    fn cube_helpers(&self) -> &'static str {
        "int cube_face(vec3 d) {\n  vec3 a = abs(d);\n\
           if (a.x >= a.y && a.x >= a.z) return d.x < 0.0 ? 1 : 0;\n\
           if (a.y >= a.z) return d.y < 0.0 ? 3 : 2;\n  return d.z < 0.0 ? 5 : 4;\n}\n\
         // Direction of the centre of texel (i, j) of face f: the GL cube-map table inverted.\n\
         vec3 texel_dir(int f, float i, float j) {\n\
           float sc = 2.0 * (i + 0.5) / u_size.x - 1.0;\n  float tc = 2.0 * (j + 0.5) / u_size.y - 1.0;\n\
           if (f == 0) return vec3(1.0, -tc, -sc);\n  if (f == 1) return vec3(-1.0, -tc, sc);\n\
           if (f == 2) return vec3(sc, 1.0, tc);\n  if (f == 3) return vec3(sc, -1.0, -tc);\n\
           if (f == 4) return vec3(sc, -tc, 1.0);\n  return vec3(-sc, -tc, -1.0);\n}\n"
    }

    fn depth_decoder(&self) -> &'static str {
        if self.api != Api::Gles2 {
            return "";
        }
        "float unpack_depth(vec4 c) {\n  vec4 k = floor(c * 255.0 + 0.5);\n\
           if (k.x >= 255.0) return 1.0; // the cleared far plane\n\
           return dot(k, vec4(1.0 / 255.0, 1.0 / 65025.0, 1.0 / 16581375.0, 1.0 / 4228250625.0));\n}\n"
    }

    fn fetch(&self, cube: bool, wrap: Outside, wrong_component: bool) -> String {
        let mut s = String::from("float fetch(int f, float i, float j) {\n");
        s.push_str(match wrap {
            Outside::Border => {
                "  if (i < 0.0 || j < 0.0 || i >= u_size.x || j >= u_size.y) return CLEAR;\n"
            }
            Outside::Repeat => "  i = mod(i, u_size.x);\n  j = mod(j, u_size.y);\n",
            Outside::Lit | Outside::ClampToEdge => {
                "  i = clamp(i, 0.0, u_size.x - 1.0);\n  j = clamp(j, 0.0, u_size.y - 1.0);\n"
            }
        });
        // Never `.z`: a core depth read returns (d, 0, 0, 1); GLES 2 unpacks RGBA8.
        let read = match (cube, self.api == Api::Gles2, wrong_component) {
            (_, true, false) if self.layered => {
                "unpack_depth(layer_texel(f, (vec2(i, j) + 0.5) / u_size))"
            }
            (_, true, true) if self.layered => {
                "unpack_depth(layer_texel(f, (vec2(i, j) + 0.5) / u_size).gbar)"
            }
            _ if self.layered => {
                if wrong_component {
                    "texelFetch(u_map, ivec3(int(i), int(j), f + LAYER), 0).g"
                } else {
                    "texelFetch(u_map, ivec3(int(i), int(j), f + LAYER), 0).r"
                }
            }
            (false, false, false) => "texelFetch(u_map, ivec2(int(i), int(j)), 0).r",
            (false, false, true) => "texelFetch(u_map, ivec2(int(i), int(j)), 0).g",
            (false, true, false) => "unpack_depth(texture2D(u_map, (vec2(i, j) + 0.5) / u_size))",
            (false, true, true) => {
                "unpack_depth(texture2D(u_map, (vec2(i, j) + 0.5) / u_size).gbar)"
            }
            (true, false, false) if self.cube_array => {
                "texture(u_map, vec4(texel_dir(f, i, j), float(LAYER))).r"
            }
            (true, false, true) if self.cube_array => {
                "texture(u_map, vec4(texel_dir(f, i, j), float(LAYER))).g"
            }
            (true, false, false) => "texture(u_map, texel_dir(f, i, j)).r",
            (true, false, true) => "texture(u_map, texel_dir(f, i, j)).g",
            (true, true, false) => "unpack_depth(textureCube(u_map, texel_dir(f, i, j)))",
            (true, true, true) => "unpack_depth(textureCube(u_map, texel_dir(f, i, j)).gbar)",
        };
        let _ = writeln!(s, "  return {read};\n}}");
        s
    }

    fn tap(&self, manual: bool, cube: bool, op: CompareOp) -> String {
        let head = "float tap(int f, float i, float j, float r)";
        match (manual, cube) {
            (true, _) => format!(
                "{head} {{ return r {} fetch(f, i, j) ? 1.0 : 0.0; }}\n",
                op.symbol()
            ),
            (false, false) if self.layered => format!(
                "{head} {{ return texture(u_map, vec4((vec2(i, j) + 0.5) / u_size, float(f + LAYER), r)); }}\n"
            ),
            (false, true) if self.cube_array => format!(
                "{head} {{ return texture(u_map, vec4(texel_dir(f, i, j), float(LAYER)), r); }}\n"
            ),
            (false, true) => {
                format!("{head} {{ return texture(u_map, vec4(texel_dir(f, i, j), r)); }}\n")
            }
            (false, false) => format!(
                "{head} {{ return texture(u_map, vec3((vec2(i, j) + 0.5) / u_size, r)); }}\n"
            ),
        }
    }

    fn compare_at(&self, manual: bool) -> String {
        let head = "float compare_at(int f, vec2 uv, float r)";
        match manual {
            true => format!(
                "{head} {{\n  vec2 x = uv * u_size - 0.5;\n  vec2 i0 = floor(x);\n  vec2 a = x - i0;\n  \
                   return (1.0 - a.x) * (1.0 - a.y) * tap(f, i0.x, i0.y, r) + a.x * (1.0 - a.y) * tap(f, i0.x + 1.0, i0.y, r)\n  \
                   + (1.0 - a.x) * a.y * tap(f, i0.x, i0.y + 1.0, r) + a.x * a.y * tap(f, i0.x + 1.0, i0.y + 1.0, r);\n}}\n"
            ),
            false if self.layered => {
                format!("{head} {{ return texture(u_map, vec4(uv, float(f + LAYER), r)); }}\n")
            }
            false => format!("{head} {{ return texture(u_map, vec3(uv, r)); }}\n"),
        }
    }

    fn castano(&self) -> &'static str {
        "  vec2 uv = c.xy * u_size;\n  vec2 base = floor(uv + 0.5);\n  vec2 st = uv + 0.5 - base;\n  \
           vec2 inv = 1.0 / u_size;\n  base = (base - 0.5) * inv;\n  \
           vec3 uw = vec3(4.0 - 3.0 * st.x, 7.0, 1.0 + 3.0 * st.x);\n  \
           vec3 vw = vec3(4.0 - 3.0 * st.y, 7.0, 1.0 + 3.0 * st.y);\n  \
           vec3 uo = vec3((3.0 - 2.0 * st.x) / uw.x - 2.0, (3.0 + st.x) / uw.y, st.x / uw.z + 2.0);\n  \
           vec3 vo = vec3((3.0 - 2.0 * st.y) / vw.x - 2.0, (3.0 + st.y) / vw.y, st.y / vw.z + 2.0);\n  \
           float sum = 0.0;\n  \
           sum += uw.x * vw.x * compare_at(f, base + vec2(uo.x, vo.x) * inv, r);\n  \
           sum += uw.y * vw.x * compare_at(f, base + vec2(uo.y, vo.x) * inv, r);\n  \
           sum += uw.z * vw.x * compare_at(f, base + vec2(uo.z, vo.x) * inv, r);\n  \
           sum += uw.x * vw.y * compare_at(f, base + vec2(uo.x, vo.y) * inv, r);\n  \
           sum += uw.y * vw.y * compare_at(f, base + vec2(uo.y, vo.y) * inv, r);\n  \
           sum += uw.z * vw.y * compare_at(f, base + vec2(uo.z, vo.y) * inv, r);\n  \
           sum += uw.x * vw.z * compare_at(f, base + vec2(uo.x, vo.z) * inv, r);\n  \
           sum += uw.y * vw.z * compare_at(f, base + vec2(uo.y, vo.z) * inv, r);\n  \
           sum += uw.z * vw.z * compare_at(f, base + vec2(uo.z, vo.z) * inv, r);\n  \
           return sum * (1.0 / 144.0);\n"
    }

    fn window(&self, y_down: bool) -> &'static str {
        if y_down {
            "vec2(gl_FragCoord.x, FRAME_HEIGHT - gl_FragCoord.y)"
        } else {
            "gl_FragCoord.xy"
        }
    }

    fn vec2(&self) -> &'static str {
        "vec2"
    }

    fn v_down(&self) -> bool {
        false
    }

    fn local(&self, glsl: &'static str) -> &'static str {
        glsl
    }

    fn uniform(&self, u: Uniform) -> &'static str {
        match u {
            Uniform::MapWidth => "u_size.x",
            Uniform::MapHeight => "u_size.y",
            Uniform::NormalOffset => "u_normal_offset",
            Uniform::SlopeScale => "u_slope_scale",
            Uniform::NdotLScale => "u_ndl_scale",
            Uniform::NdotLMin => "u_ndl_min",
            Uniform::LightPosition => "u_light_pos",
        }
    }

    fn lookup_start(&self, offset: &str) -> String {
        format!("float visibility(vec3 p, vec3 n) {{\n  p = p + n * {offset};\n")
    }

    fn face(&self, cube: bool) -> &'static str {
        if cube {
            "  int f = cube_face(p - u_light_pos);\n"
        } else {
            "  int f = 0;\n"
        }
    }

    fn layer_lookup_start(&self, extra: &str) -> String {
        let mut s = String::from("float lookup(vec3 p, vec3 n, int f) {\n");
        if !extra.is_empty() {
            let _ = writeln!(s, "  p = p{extra};");
        }
        s
    }

    fn world_offsets(&self, f: &str) -> String {
        format!(" + n * face_offset({f}) + u_towards * u_light_offset")
    }

    /// An if-chain on constant indices (GLSL ES's rule for uniform arrays in fragments).
    fn cascaded_visibility(&self, offset: &str, c: &CascadeSelect) -> String {
        let n = c.count;
        let mut s = format!("float visibility(vec3 p, vec3 n) {{\n  p = p + n * {offset};\n");
        s.push_str(if c.by_distance {
            "  float d = length(p - u_eye);\n"
        } else {
            "  float d = dot(u_view_row.xyz, p) + u_view_row.w;\n"
        });
        if c.beyond {
            let _ = writeln!(s, "  if (d > u_split[{n}]) return 1.0;");
        }
        s.push_str("  int f = 0;\n  float lo = u_split[0];\n  float hi = u_split[1];\n");
        for k in 1..n {
            let _ = writeln!(
                s,
                "  if (d > u_split[{k}]) {{ f = {k}; lo = u_split[{k}]; hi = u_split[{}]; }}",
                k + 1
            );
        }
        s.push_str("  float v = lookup(p, n, f);\n");
        if let Some(b) = c.blend_literal() {
            let _ = write!(
                s,
                "  float band = {b} * {};\n  float t = (d - (hi - band)) / band;\n\
                   if (f < {} && t > 0.0) v = mix(v, lookup(p, n, f + 1), min(t, 1.0));\n",
                c.band_of(),
                n - 1
            );
        }
        s.push_str("  return v;\n}\n");
        s
    }

    fn coordinate(&self, c: &Coordinate) -> &'static str {
        use CoordinateStep::{Bias, Divide};
        match (c.bias_matrix, c.left_out) {
            (BiasMatrix::BeforeDivide, Some(Divide)) => {
                "  vec4 t = tex_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(t.xyz, t.w);\n"
            }
            (BiasMatrix::BeforeDivide, Some(Bias)) => {
                "  vec4 t = light_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(t.xyz / t.w, t.w);\n"
            }
            (BiasMatrix::BeforeDivide, None) => {
                "  vec4 t = tex_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(t.xyz / t.w, t.w);\n"
            }
            (BiasMatrix::AfterDivide, Some(Divide)) => {
                "  vec4 l = light_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(0.5 * l.xyz + 0.5, l.w);\n"
            }
            (BiasMatrix::AfterDivide, Some(Bias)) => {
                "  vec4 l = light_m(f) * vec4(p, 1.0);\n  vec4 c = vec4(l.xyz / l.w, l.w);\n"
            }
            (BiasMatrix::AfterDivide, None) => {
                "  vec4 l = light_m(f) * vec4(p, 1.0);\n  vec3 ndc = vec3(l.x / l.w, l.y / l.w, l.z / l.w);\n\
               vec4 c = vec4(0.5 * ndc + 0.5, l.w);\n"
            }
        }
    }

    fn bias_again(&self) -> &'static str {
        "  c.xyz = 0.5 * c.xyz + 0.5;\n"
    }

    fn nudge_u(&self, texels: &str) -> String {
        format!("  c.x += {texels} / u_size.x;\n")
    }

    fn guard(&self) -> &'static str {
        "  if (c.w <= 0.0) return 1.0;\n"
    }

    fn outside_test(&self) -> &'static str {
        "  if (c.x < 0.0 || c.x > 1.0 || c.y < 0.0 || c.y > 1.0) return 1.0;\n"
    }

    /// GL's face images hold rows as the cube-map table addresses them.
    fn cube_rows(&self) -> &'static str {
        ""
    }

    fn bias_start(&self) -> &'static str {
        "  float bias = u_constant;\n"
    }

    fn slope_bias(&self, scale: &str) -> String {
        format!(
            "  float cosine = dot(n, to_light(p));\n  if (cosine > 0.0) bias += clamp({scale} * sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine, 0.0, u_slope_max);\n"
        )
    }

    fn reference(&self) -> &'static str {
        "  float r = c.z - TOWARD_FAR * bias;\n"
    }

    fn sample_cube(&self) -> &'static str {
        if self.cube_array {
            "  return texture(u_map, vec4(p - u_light_pos, float(LAYER)), r);\n"
        } else {
            "  return texture(u_map, vec4(p - u_light_pos, r));\n"
        }
    }

    fn sample_projective(&self) -> &'static str {
        "  return textureProj(u_map, vec4(t.xy, t.w * r, t.w));\n"
    }

    fn sample(&self) -> &'static str {
        if self.layered {
            "  return texture(u_map, vec4(c.xy, float(f + LAYER), r));\n"
        } else {
            "  return texture(u_map, vec3(c.xy, r));\n"
        }
    }

    /// A cascade array has no levels (validation refuses them).
    fn sample_mipmapped(&self) -> &'static str {
        "  float m = texture(u_map, vec3(c.xy, r));\n"
    }

    fn bilinear_start(&self) -> &'static str {
        "  vec2 x = c.xy * u_size - 0.5;\n  vec2 i0 = floor(x);\n  vec2 a = x - i0;\n"
    }

    fn float_of(&self, n: u32) -> String {
        format!("{n}.0")
    }

    fn pcf_sum(&self, n: u32, centre: &str) -> String {
        format!(
            "  float sum = 0.0;\n  float h = {centre};\n\
               for (int dy = 0; dy < {n}; dy++) {{\n    for (int dx = 0; dx < {n}; dx++) {{\n\
                   vec2 uv = c.xy + (vec2(float(dx), float(dy)) - h) / u_size;\n\
                   sum += tap(f, floor(uv.x * u_size.x), floor(uv.y * u_size.y), r);\n    }}\n  }}\n"
        )
    }

    fn pcf_double_centre(&self) -> &'static str {
        "  vec2 uv0 = c.xy + (vec2(0.0) - h) / u_size;\n\
           sum += tap(f, floor(c.x * u_size.x), floor(c.y * u_size.y), r) - tap(f, floor(uv0.x * u_size.x), floor(uv0.y * u_size.y), r);\n"
    }

    fn pcf_mean(&self, n: u32) -> String {
        format!("  return sum / float({n} * {n});\n")
    }

    fn shade_start(&self) -> &'static str {
        "vec3 shade(vec3 albedo, vec3 n, vec3 l, vec3 e, float vis) {\n  float ndl = dot(n, l);\n  float diffuse = max(ndl, 0.0);\n"
    }

    fn dimmed(&self, kept: &str, lit_spec: &str, light: Option<&str>, shading: &Shading) -> String {
        let (ld, ls) = match light {
            Some(l) => (format!(" * {l}"), format!("{l} * ")),
            None => (String::new(), String::new()),
        };
        format!(
            "  float kept = {kept};\n  float spec = 0.0;\n\
               if (ndl > 0.0) {{ vec3 hv = l + e; float len = length(hv); if (len > 0.0) spec = {ks:.9} * pow(max(dot(n, hv / len), 0.0), {sh:.9}); }}\n\
               return ({a:.9} + kept * diffuse{ld}) * albedo + {ls}vec3({lit_spec});\n",
            ks = shading.specular,
            sh = shading.shininess,
            a = shading.ambient
        )
    }

    fn vec3(&self, v: [f32; 3]) -> String {
        format!("vec3({:.9}, {:.9}, {:.9})", v[0], v[1], v[2])
    }

    /// Outputs: colour; visibility in R and face id + 1 in G, B, A (base 256).
    /// gl_FragCoord is read where it is needed: `window` changes nothing here.
    fn main_start(&self, raw_normal: bool, _window: bool) -> String {
        format!(
            "vec4 encode(float vis, float face) {{\n  float id = face + 1.0;\n\
               return vec4(vis, mod(id, 256.0) / 255.0, mod(floor(id / 256.0), 256.0) / 255.0, floor(id / 65536.0) / 255.0);\n}}\n\
             void main() {{\n  vec3 n = normalize(v_normal);\n  float vis = visibility(v_pos, {});\n",
            if raw_normal { "v_normal" } else { "n" }
        )
    }

    fn main_colour(&self) -> &'static str {
        "  vec3 e = normalize(u_eye - v_pos);\n  vec3 col = clamp(shade(v_albedo, n, to_light(v_pos), e, vis), 0.0, 1.0);\n\
           float face = floor(v_face + 0.5);\n"
    }

    fn main_end(&self) -> &'static str {
        if self.api == Api::Gles2 {
            "  gl_FragColor = u_output < 0.5 ? vec4(col, 1.0) : encode(vis, face);\n}\n"
        } else {
            "  o_color = vec4(col, 1.0);\n  o_vis = encode(vis, face);\n}\n"
        }
    }
}
