//! WGSL for both passes, generated per technique. The lookup mirrors `umbra_ref::lookup` step
//! by step, in the zero-to-one convention: the bias matrix maps v = 0.5 − 0.5·y (texture rows
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

use umbra_case::fault::Fault;
use umbra_case::format::{BiasMatrix, Compare, DepthOrder, Filter, Outside, Shading, ShadingModel};

/// Everything that changes the generated source.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    /// A cube map (point light).
    pub cube: bool,
    /// Directional light.
    pub directional: bool,
    /// Filter.
    pub filter: Filter,
    /// Compare mechanism.
    pub compare: Compare,
    /// The sampler clamps the reference to [0,1] (hardware compare on a fixed-point format).
    pub clamp_reference: bool,
    /// What a lookup outside [0,1]² returns (the sampler's address mode for hardware
    /// compare; the shader's wrap for manual compare).
    pub outside: Outside,
    /// w > 0 guard.
    pub guard: bool,
    /// Bias matrix order.
    pub bias_matrix: BiasMatrix,
    /// Depth order.
    pub order: DepthOrder,
    /// Slope bias present.
    pub slope: bool,
    /// N·L bias present (its scale and min ride in `u.size.zw`).
    pub n_dot_l: bool,
    /// Shading model.
    pub model: ShadingModel,
    /// An injected fault (self-test only).
    pub fault: Option<Fault>,
}

/// The uniform block shared by both passes (std140-compatible layout, 16-byte vectors).
pub const UNIFORMS: &str = "struct U {\n  view_proj: mat4x4<f32>,\n  light: array<mat4x4<f32>, 6>,\n  tex: array<mat4x4<f32>, 6>,\n  light_pos: vec4<f32>,\n  towards: vec4<f32>,\n  eye: vec4<f32>,\n  size: vec4<f32>,\n  bias: vec4<f32>,\n}\n@group(0) @binding(0) var<uniform> u: U;\n";

/// Size of [`UNIFORMS`] in bytes: 13 matrices and 5 vectors.
pub const UNIFORM_SIZE: u64 = 13 * 64 + 5 * 16;

/// The shadow pass: position only; a constant colour for the `with_color` variant.
pub fn shadow(with_color: bool) -> String {
    let mut s = String::from(UNIFORMS);
    s.push_str("@vertex fn vs(@location(0) pos: vec3<f32>) -> @builtin(position) vec4<f32> { return u.view_proj * vec4<f32>(pos, 1.0); }\n");
    if with_color {
        s.push_str("@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(1.0, 0.0, 1.0, 1.0); }\n");
    }
    s
}

/// The lit pass.
pub fn lit(k: &Key, shading: &Shading) -> String {
    let manual = k.compare == Compare::Manual;
    let mut s = String::from(UNIFORMS);
    let texture = match (k.cube, manual) {
        (false, _) => "texture_depth_2d",
        (true, false) => "texture_depth_cube",
        (true, true) => "texture_depth_2d_array",
    };
    let _ = writeln!(s, "@group(0) @binding(1) var map: {texture};");
    if !manual {
        s.push_str("@group(0) @binding(2) var samp: sampler_comparison;\n");
    }
    s.push_str(
        "struct VOut {\n  @builtin(position) clip: vec4<f32>,\n  @location(0) pos: vec3<f32>,\n  @location(1) normal: vec3<f32>,\n\
           @location(2) albedo: vec3<f32>,\n  @location(3) @interpolate(flat) face: f32,\n}\n\
         @vertex fn vs(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) albedo: vec3<f32>, @location(3) face: f32) -> VOut {\n\
           var o: VOut;\n  o.clip = u.view_proj * vec4<f32>(pos, 1.0);\n  o.pos = pos;\n  o.normal = normal;\n  o.albedo = albedo;\n  o.face = face;\n  return o;\n}\n",
    );
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
        "const TOWARD_FAR: f32 = {far};\nconst CLEAR: f32 = {clear};"
    );
    if k.directional {
        s.push_str("fn to_light(p: vec3<f32>) -> vec3<f32> { return u.towards.xyz; }\n");
    } else {
        s.push_str(
            "fn to_light(p: vec3<f32>) -> vec3<f32> { return normalize(u.light_pos.xyz - p); }\n",
        );
    }
    if k.cube {
        s.push_str(
            "fn cube_face(d: vec3<f32>) -> i32 {\n  let a = abs(d);\n\
               if (a.x >= a.y && a.x >= a.z) { return select(0, 1, d.x < 0.0); }\n\
               if (a.y >= a.z) { return select(2, 3, d.y < 0.0); }\n  return select(4, 5, d.z < 0.0);\n}\n\
             fn texel_dir(f: i32, i: f32, j: f32) -> vec3<f32> {\n\
               let sc = 2.0 * (i + 0.5) / u.size.x - 1.0;\n  let tc = 2.0 * (j + 0.5) / u.size.y - 1.0;\n\
               if (f == 0) { return vec3<f32>(1.0, -tc, -sc); }\n  if (f == 1) { return vec3<f32>(-1.0, -tc, sc); }\n\
               if (f == 2) { return vec3<f32>(sc, 1.0, tc); }\n  if (f == 3) { return vec3<f32>(sc, -1.0, -tc); }\n\
               if (f == 4) { return vec3<f32>(sc, -tc, 1.0); }\n  return vec3<f32>(-sc, -tc, -1.0);\n}\n",
        );
    }
    if manual {
        let outside = if k.fault == Some(Fault::Repeat) {
            Outside::Repeat
        } else if k.cube {
            Outside::ClampToEdge
        } else {
            k.outside
        };
        s.push_str(
            "fn fetch(f: i32, i_in: f32, j_in: f32) -> f32 {\n  var i = i_in;\n  var j = j_in;\n",
        );
        match outside {
            Outside::Border => s.push_str("  if (i < 0.0 || j < 0.0 || i >= u.size.x || j >= u.size.y) { return CLEAR; }\n"),
            Outside::Repeat => s.push_str("  i = i - u.size.x * floor(i / u.size.x);\n  j = j - u.size.y * floor(j / u.size.y);\n"),
            Outside::Lit | Outside::ClampToEdge => s.push_str("  i = clamp(i, 0.0, u.size.x - 1.0);\n  j = clamp(j, 0.0, u.size.y - 1.0);\n"),
        }
        if k.cube {
            s.push_str("  return textureLoad(map, vec2<i32>(i32(i), i32(j)), f, 0);\n}\n");
        } else {
            s.push_str("  return textureLoad(map, vec2<i32>(i32(i), i32(j)), 0);\n}\n");
        }
        let _ = writeln!(
            s,
            "fn tap(f: i32, i: f32, j: f32, r: f32) -> f32 {{ return select(0.0, 1.0, r {cmp} fetch(f, i, j)); }}"
        );
    } else if k.cube {
        s.push_str("fn tap(f: i32, i: f32, j: f32, r: f32) -> f32 { return textureSampleCompareLevel(map, samp, texel_dir(f, i, j), r); }\n");
    } else {
        s.push_str("fn tap(f: i32, i: f32, j: f32, r: f32) -> f32 { return textureSampleCompareLevel(map, samp, (vec2<f32>(i, j) + 0.5) / u.size.xy, r); }\n");
    }
    if k.fault == Some(Fault::NormalOffsetShort) {
        s.push_str("fn visibility(p_in: vec3<f32>, n: vec3<f32>) -> f32 {\n  let p = p_in + n * (0.75 * u.bias.w);\n");
    } else {
        s.push_str(
            "fn visibility(p_in: vec3<f32>, n: vec3<f32>) -> f32 {\n  let p = p_in + n * u.bias.w;\n",
        );
    }
    if k.cube {
        s.push_str("  let f = cube_face(p - u.light_pos.xyz);\n");
    } else {
        s.push_str("  let f = 0;\n");
    }
    match (k.bias_matrix, k.fault) {
        (BiasMatrix::BeforeDivide, Some(Fault::NoDivide)) => s.push_str("  let t = u.tex[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(t.xyz, t.w);\n"),
        (BiasMatrix::BeforeDivide, Some(Fault::NoBias)) => s.push_str("  let t = u.light[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(t.xyz / t.w, t.w);\n"),
        (BiasMatrix::BeforeDivide, _) => s.push_str("  let t = u.tex[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(t.xyz / t.w, t.w);\n"),
        (BiasMatrix::AfterDivide, Some(Fault::NoDivide)) => s.push_str(
            "  let l = u.light[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(0.5 * l.x + 0.5, 0.5 - 0.5 * l.y, l.z, l.w);\n",
        ),
        (BiasMatrix::AfterDivide, Some(Fault::NoBias)) => s.push_str("  let l = u.light[f] * vec4<f32>(p, 1.0);\n  var c = vec4<f32>(l.xyz / l.w, l.w);\n"),
        (BiasMatrix::AfterDivide, _) => s.push_str(
            "  let l = u.light[f] * vec4<f32>(p, 1.0);\n  let ndc = l.xyz / l.w;\n\
               var c = vec4<f32>(0.5 * ndc.x + 0.5, 0.5 - 0.5 * ndc.y, ndc.z, l.w);\n",
        ),
    }
    if k.fault == Some(Fault::BiasTwice) {
        s.push_str("  c = vec4<f32>(0.5 * c.x + 0.5, 0.5 - 0.5 * c.y, c.z, c.w);\n");
    }
    if k.fault == Some(Fault::QuarterTexel) {
        s.push_str("  c.x = c.x + 0.25 / u.size.x;\n");
    }
    if k.guard && k.fault != Some(Fault::NoGuard) {
        s.push_str("  if (c.w <= 0.0) { return 1.0; }\n");
    }
    if !k.cube && k.outside == Outside::Lit {
        s.push_str("  if (c.x < 0.0 || c.x > 1.0 || c.y < 0.0 || c.y > 1.0) { return 1.0; }\n");
    }
    if k.cube {
        s.push_str("  c.y = 1.0 - c.y; // face rows run with the cube table's t\n");
    }
    s.push_str("  var bias = u.bias.x;\n");
    if k.slope {
        // tan(acos(c)) in its algebraic form (umbra_ref::lookup, step 6).
        let scale = if k.fault == Some(Fault::SlopeShort) {
            "0.8 * u.bias.y"
        } else {
            "u.bias.y"
        };
        let _ = writeln!(
            s,
            "  let cosine = dot(n, to_light(p));\n  if (cosine > 0.0) {{ bias += clamp({scale} * sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine, 0.0, u.bias.z); }}"
        );
    }
    if k.n_dot_l {
        // LearnOpenGL's max(s·(1 − N·L), min), N·L unclamped (umbra_ref::lookup, step 6).
        s.push_str("  bias += max(u.size.z * (1.0 - dot(n, to_light(p))), u.size.w);\n");
    }
    s.push_str("  var r = c.z - TOWARD_FAR * bias;\n");
    if !manual && !k.clamp_reference && k.fault == Some(Fault::ClampFloat) {
        s.push_str("  r = clamp(r, 0.0, 1.0);\n"); // a float format clamped like a fixed one
    }
    let hw_direct = !manual && !matches!(k.filter, Filter::Pcf(_));
    match k.filter {
        _ if hw_direct && k.cube => {
            s.push_str("  return textureSampleCompareLevel(map, samp, p - u.light_pos.xyz, r);\n")
        }
        _ if hw_direct => s.push_str("  return textureSampleCompareLevel(map, samp, c.xy, r);\n"),
        Filter::Nearest => {
            s.push_str("  return tap(f, floor(c.x * u.size.x), floor(c.y * u.size.y), r);\n")
        }
        Filter::Linear => {
            s.push_str(
                "  let x = c.xy * u.size.xy - 0.5;\n  let i0 = floor(x);\n  var a = x - i0;\n",
            );
            if k.fault == Some(Fault::BilinearCoarse) {
                s.push_str("  a = floor(a * 4.0) / 4.0;\n");
            }
            s.push_str(
                "  return (1.0 - a.x) * (1.0 - a.y) * tap(f, i0.x, i0.y, r) + a.x * (1.0 - a.y) * tap(f, i0.x + 1.0, i0.y, r)\n\
                    + (1.0 - a.x) * a.y * tap(f, i0.x, i0.y + 1.0, r) + a.x * a.y * tap(f, i0.x + 1.0, i0.y + 1.0, r);\n",
            );
        }
        Filter::Pcf(n) => {
            let centre = if k.fault == Some(Fault::PcfOffCentre) {
                format!("f32({n}) * 0.5")
            } else {
                format!("(f32({n}) - 1.0) * 0.5")
            };
            let _ = writeln!(
                s,
                "  var sum = 0.0;\n  let h = {centre};\n\
                   for (var dy = 0; dy < {n}; dy++) {{\n    for (var dx = 0; dx < {n}; dx++) {{\n\
                       let uv = c.xy + (vec2<f32>(f32(dx), f32(dy)) - h) / u.size.xy;\n\
                       sum += tap(f, floor(uv.x * u.size.x), floor(uv.y * u.size.y), r);\n    }}\n  }}"
            );
            if k.fault == Some(Fault::PcfDoubleCentre) {
                s.push_str(
                    "  let uv0 = c.xy + (vec2<f32>(0.0) - h) / u.size.xy;\n\
                       sum += tap(f, floor(c.x * u.size.x), floor(c.y * u.size.y), r) - tap(f, floor(uv0.x * u.size.x), floor(uv0.y * u.size.y), r);\n",
                );
            }
            let _ = writeln!(s, "  return sum / f32({n} * {n});");
        }
    }
    s.push_str("}\n");
    let _ = writeln!(
        s,
        "fn shade(albedo: vec3<f32>, n: vec3<f32>, l: vec3<f32>, e: vec3<f32>, vis: f32) -> vec3<f32> {{\n  let ndl = dot(n, l);\n  let diffuse = max(ndl, 0.0);"
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
                "  let kept = {kept};\n  var spec = 0.0;\n\
                   if (ndl > 0.0) {{ let hv = l + e; let len = length(hv); if (len > 0.0) {{ spec = {ks:.9} * pow(max(dot(n, hv / len), 0.0), {sh:.9}); }} }}\n\
                   return ({a:.9} + kept * diffuse) * albedo + vec3<f32>({lit_spec});",
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
    s.push_str(
        "struct FOut {\n  @location(0) color: vec4<f32>,\n  @location(1) vis: vec4<f32>,\n  @location(2) face: u32,\n}\n\
         @fragment fn fs(v: VOut) -> FOut {\n  let n = normalize(v.normal);\n  var vis = visibility(v.pos, n);\n",
    );
    if k.fault == Some(Fault::Vis4Bit) {
        s.push_str("  vis = floor(vis * 16.0 + 0.5) / 16.0;\n");
    }
    s.push_str(
        "  let e = normalize(u.eye.xyz - v.pos);\n  var o: FOut;\n\
           var col = clamp(shade(v.albedo, n, to_light(v.pos), e, vis), vec3<f32>(0.0), vec3<f32>(1.0));\n",
    );
    if k.fault == Some(Fault::ColourGamma) {
        s.push_str("  col = sqrt(col);\n");
    }
    s.push_str(
        "  o.color = vec4<f32>(col, 1.0);\n\
           o.vis = vec4<f32>(vis, 0.0, 0.0, 1.0);\n  o.face = u32(floor(v.face + 0.5)) + 1u;\n  return o;\n}\n",
    );
    s
}
