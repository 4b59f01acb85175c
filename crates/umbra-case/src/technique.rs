//! The technique a lit pass implements, described once for every GPU backend.
//!
//! Why it exists: GL and wgpu each generate their lit pass (GLSL, WGSL) from the prepared
//! run. Each used to copy the case into its own key field by field and to decide on its own
//! how a self-test fault bends the lookup, so the two could drift apart without any test
//! noticing. Here [`Technique::new`] reads the run once, and every fault that acts on the lit
//! pass is resolved in this file only, into plain values: a compare operator, a scale, a wrap
//! policy, which filter taps. [`crate::lit_shader`] writes the lookup from them in whichever
//! language, and the renderers set their samplers from the same values.
//!
//! What a backend does differently is an explicit adjustment of the technique, not a second
//! derivation: GLES 2 has no shadow samplers, so GL applies
//! [`Technique::with_manual_compare`] there.
//!
//! The steps mirror `umbra_ref::lookup`: normal offset, cube face, coordinate (bias matrix
//! before or after the divide), w > 0 guard, outside test, bias, the reference's clamp, filter.

use crate::fault::{Fault, Param};
use crate::format::{
    BeyondFar, BiasMatrix, BlendOf, Compare, DepthOrder, Filter, LightVector, Outside, Shading,
};
use crate::light::LightKind;
use crate::prepare::LightRun;

/// Everything that shapes a lit pass's lookup and shading.
#[derive(Clone, Debug, PartialEq)]
pub struct Technique {
    /// A cube map (point light): six faces, the face chosen by direction.
    pub cube: bool,
    /// Parallel rays (directional light): the direction to the light is the same everywhere.
    pub directional: bool,
    /// Cascades (the layers of a 2D array, one chosen per receiver by its view depth), or 0
    /// for a single map.
    pub cascades: usize,
    /// A cascaded light reads lit beyond its shadow distance.
    pub cascade_beyond: bool,
    /// A cascaded light's blend band (0: none).
    pub cascade_blend: f32,
    /// What the band is a share of.
    pub cascade_blend_of: BlendOf,
    /// The lookup point moves by the texel-scaled normal offset and towards the light after
    /// the face is chosen (`shadow.bias.normal_offset_texels`, `light_offset`).
    pub world_offsets: bool,
    /// A light of several whose maps are one array's layers (2D, or a cube-map array's cubes):
    /// the layer (cube) its lit pass reads
    /// (its own, unless a self-test fault mixes them up: [`Fault::map_of_light`]).
    pub layer: Option<usize>,
    /// The case's filter.
    pub filter: Filter,
    /// Who compares: the sampler or the shader (see [`Technique::with_manual_compare`]).
    pub compare: Compare,
    /// The reference is clamped to [0,1]: a hardware compare on a fixed-point format. Kept
    /// when a backend compares in the shader in the sampler's place.
    pub clamp_reference: bool,
    /// The case's outside policy (the lit test; the wrap is [`Technique::texel_wrap`]).
    pub outside: Outside,
    /// The case's w > 0 guard (the lookup's is [`Technique::guards`]).
    pub guard: bool,
    /// Where the bias matrix is applied relative to the perspective divide.
    pub bias_matrix: BiasMatrix,
    /// Depth order.
    pub order: DepthOrder,
    /// A slope bias is present (its scale and cap are uniforms).
    pub slope: bool,
    /// An N·L bias is present (its scale and least value are uniforms).
    pub n_dot_l: bool,
    /// The N·L bias's L is the vector towards the light's position on a directional light
    /// (`light: position`; on spot and point lights that is the light direction already).
    pub n_dot_l_from_position: bool,
    /// The shader reads lit beyond the light's far plane (`beyond_far: lit`).
    pub beyond_far_lit: bool,
    /// The map has mip levels (the sampler picks them: [`Taps::HardwareMipmapped`]).
    pub mipmapped: bool,
    /// The illumination model and its constants (written into the shader).
    pub shading: Shading,
    /// The frame's height in pixels: WGSL's fragment position runs down from the top, and
    /// the Vogel disk's rotation reads GL's window position, up from the bottom.
    pub frame_height: u32,
    /// The light's colour times its intensity (written into the shader where it is not
    /// white: [`Technique::light_colour`]).
    radiance: [f32; 3],
    /// The self-test's fault: read by the methods below and nowhere else.
    fault: Option<Fault>,
}

/// How a cascaded light's lit pass picks (and blends) its cascade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeSelect {
    /// Cascades.
    pub count: usize,
    /// By the distance from the eye instead of the view depth (CascadeByDistance).
    pub by_distance: bool,
    /// Lit beyond the last split (a shadow distance).
    pub beyond: bool,
    /// The blend band's share of a cascade's range or far bound (0: none).
    pub blend: f32,
    /// What the band is a share of.
    pub blend_of: BlendOf,
}

impl CascadeSelect {
    /// The blend band's share as a literal, where there is a band.
    pub fn blend_literal(&self) -> Option<String> {
        // Nine decimals, as every float the lit shaders are written with.
        (self.blend > 0.0 && self.count > 1).then(|| format!("{:.9}", self.blend))
    }

    /// What the band's share multiplies, in the shaders' names: the cascade's range
    /// `hi - lo` or its far bound `hi` (`umbra_case::light::Cascading::band`).
    pub fn band_of(&self) -> &'static str {
        match self.blend_of {
            BlendOf::Range => "(hi - lo)",
            BlendOf::Far => "hi",
        }
    }
}

/// A depth compare, `reference OP stored` (true is lit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompareOp {
    /// `<=` (forward depth).
    LessEqual,
    /// `>=` (reversed depth).
    GreaterEqual,
    /// `<`.
    Less,
    /// `>`.
    Greater,
}

impl CompareOp {
    /// The operator as GLSL and WGSL both write it.
    pub fn symbol(self) -> &'static str {
        match self {
            CompareOp::LessEqual => "<=",
            CompareOp::GreaterEqual => ">=",
            CompareOp::Less => "<",
            CompareOp::Greater => ">",
        }
    }
}

/// How the lookup coordinate c = (u, v, depth, w) is computed from the light matrices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coordinate {
    /// Where the bias matrix goes relative to the divide.
    pub bias_matrix: BiasMatrix,
    /// A step left out (the self-test's NoDivide, NoBias).
    pub left_out: Option<CoordinateStep>,
    /// The bias matrix is applied a second time, after the rest.
    pub bias_again: bool,
    /// Texels added to u at the end.
    pub u_nudge_texels: f32,
    /// Texels added to v at the end.
    pub v_nudge_texels: f32,
}

/// A step of the lookup coordinate that a fault can leave out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoordinateStep {
    /// The divide by w.
    Divide,
    /// The bias matrix (NDC to [0,1]).
    Bias,
}

/// How the lookup reads the map once the reference is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Taps {
    /// The sampler compares once, at the direction from the light (cube map).
    HardwareCube,
    /// The sampler compares once at the undivided coordinate and divides itself
    /// (`textureProj`, the classic code's form). A language without it samples
    /// [`Taps::Hardware`].
    HardwareProjective,
    /// The sampler compares (and filters, NEAREST or LINEAR) once at c.
    Hardware,
    /// The sampler compares at c on a mipmapped map, choosing levels by the implicit
    /// derivatives of c: sampled before the guard and the outside tests, so that the
    /// derivatives are taken in uniform control flow (GLSL 4.60 §8.9, WGSL's uniformity
    /// rules for textureSampleCompare), and returned after them.
    HardwareMipmapped,
    /// One tap at texel floor(c · size).
    Nearest,
    /// Four taps with bilinear weights.
    Bilinear {
        /// The weights are quantised to quarters.
        coarse_weights: bool,
        /// The weights are moved about ½ by this many millionths of their distance from it
        /// (the threshold sweep's filter-weights error; 0 = exact).
        weight_gain_ppm: i32,
    },
    /// Castano's filter (Bevy's `castano_thirteen`, named for the 2013 article): nine bilinear compares (the sampler's, or the shader's
    /// four taps where it compares itself) weighted into a 6 × 6-texel tent.
    Castano13,
    /// three.js's PCF: five LINEAR compares on a Vogel disk of one texel, rotated per pixel
    /// by interleaved gradient noise of the window position (`Filter::Vogel5`).
    Vogel5 {
        /// The disk is rotated per pixel (VogelUnrotated drops the noise: φ = 0).
        rotated: bool,
        /// The noise reads the window position with y down from the top row, as WGSL's
        /// `@builtin(position)` gives it, instead of GL's gl_FragCoord (NoiseYDown).
        window_y_down: bool,
        /// Tap k lies at √((k + ½)/5) of the radius; without the root (VogelNoSqrt), at
        /// (k + ½)/5, bunched towards the centre.
        sqrt_radius: bool,
    },
    /// N × N nearest taps around c, averaged.
    Pcf {
        /// N.
        n: u32,
        /// The kernel's offsets are k − N/2 instead of k − (N − 1)/2.
        off_centre: bool,
        /// The first corner's tap is replaced by the centre's.
        double_centre: bool,
    },
}

impl Technique {
    /// The technique of `run`, with the self-test's `fault` (`Fault::active()`, or `None`).
    pub fn new(run: &LightRun, fault: Option<Fault>) -> Self {
        let case = run.case();
        let s = &case.shadow;
        Technique {
            cube: run.light.is_cube(),
            directional: matches!(run.light.kind, LightKind::Directional { .. }),
            cascades: run
                .light
                .cascading
                .as_ref()
                .map_or(0, |_| run.light.views.len()),
            cascade_beyond: run.light.cascading.as_ref().is_some_and(|c| c.lit_beyond),
            cascade_blend: run.light.cascading.as_ref().map_or(0.0, |c| c.blend),
            cascade_blend_of: match fault {
                Some(Fault::BandOfRange) => BlendOf::Range,
                _ => run
                    .light
                    .cascading
                    .as_ref()
                    .map_or(BlendOf::Range, |c| c.blend_of),
            },
            world_offsets: (s.bias.normal_offset_texels != 0.0 || s.bias.light_offset != 0.0)
                && fault != Some(Fault::WorldOffsetsDropped),
            layer: Some(run.of_lights)
                .filter(|o| o.array)
                .map(|o| Fault::map_of_light(fault, o.light, o.lights, true, |_| false)),
            filter: s.filter,
            compare: s.compare,
            clamp_reference: s.compare == Compare::Hardware && s.format.is_fixed(),
            outside: s.outside,
            guard: s.guard_behind_light,
            bias_matrix: s.bias_matrix,
            order: s.depth_order,
            slope: s.bias.slope.is_some(),
            n_dot_l: s.bias.n_dot_l.is_some(),
            n_dot_l_from_position: matches!(run.light.kind, LightKind::Directional { .. })
                && s.bias
                    .n_dot_l
                    .is_some_and(|b| b.light == LightVector::Position),
            beyond_far_lit: s.beyond_far == BeyondFar::Lit,
            mipmapped: s.mipmaps.is_some(),
            shading: case.shading.clone(),
            frame_height: case.camera.size[1],
            radiance: run.as_written().radiance(),
            fault,
        }
    }

    /// The same technique with the compare in the shader, for a backend without shadow
    /// samplers: a hardware case keeps its semantics (the reference is still clamped to [0,1]
    /// for a fixed-point format); only the mechanism changes.
    pub fn with_manual_compare(self) -> Self {
        Technique {
            compare: Compare::Manual,
            ..self
        }
    }

    fn is(&self, fault: Fault) -> bool {
        self.fault == Some(fault)
    }

    /// The threshold sweep's error of `param` (0 without it).
    fn error(&self, param: Param) -> f32 {
        self.fault.and_then(|f| f.error_of(param)).unwrap_or(0.0)
    }

    /// The shader compares (it reads depths itself).
    pub fn manual(&self) -> bool {
        self.compare == Compare::Manual
    }

    /// The compare, in the shader or the sampler: `<=` forward, `>=` reversed
    /// (CompareFlipped turns it round, CompareStrict makes it strict).
    pub fn compare_op(&self) -> CompareOp {
        let forward = self.order == DepthOrder::Forward;
        match (forward, self.fault) {
            (true, Some(Fault::CompareFlipped)) => CompareOp::Greater,
            (false, Some(Fault::CompareFlipped)) => CompareOp::Less,
            (true, Some(Fault::CompareStrict)) => CompareOp::Less,
            (false, Some(Fault::CompareStrict)) => CompareOp::Greater,
            (true, _) => CompareOp::LessEqual,
            (false, _) => CompareOp::GreaterEqual,
        }
    }

    /// How texels outside the map are addressed (a sampler's wrap mode, or the shader's for
    /// texels it fetches itself): the case's policy, clamped to the edge on a cube map
    /// (Repeat repeats everywhere).
    pub fn texel_wrap(&self) -> Outside {
        if self.is(Fault::Repeat) {
            Outside::Repeat
        } else if self.cube {
            Outside::ClampToEdge
        } else {
            self.outside
        }
    }

    /// A fetched depth texel is read from the wrong component (WrongComponent).
    pub fn reads_wrong_component(&self) -> bool {
        self.is(Fault::WrongComponent)
    }

    /// The normal the lookup reads: the interpolated one renormalised (`n`), or as it
    /// arrives under NormalUnnormalized.
    pub fn lookup_normal_raw(&self) -> bool {
        self.is(Fault::NormalUnnormalized)
    }

    /// The share of the case's normal offset applied (NormalOffsetShort: 0.75).
    pub fn normal_offset_scale(&self) -> f32 {
        if self.is(Fault::NormalOffsetShort) {
            0.75
        } else {
            1.0
        }
    }

    /// The lookup coordinate (NoDivide, NoBias, BiasTwice, QuarterTexel).
    pub fn coordinate(&self) -> Coordinate {
        Coordinate {
            bias_matrix: self.bias_matrix,
            left_out: match self.fault {
                Some(Fault::NoDivide) => Some(CoordinateStep::Divide),
                Some(Fault::NoBias) => Some(CoordinateStep::Bias),
                _ => None,
            },
            bias_again: self.is(Fault::BiasTwice),
            u_nudge_texels: if self.is(Fault::QuarterTexel) {
                0.25
            } else {
                self.error(Param::LookupU)
            },
            v_nudge_texels: self.error(Param::LookupV),
        }
    }

    /// The map is an array: one layer per cascade, or one per light (the lit pass reads
    /// layer `f` + [`Technique::layer_base`], or cube `layer_base` of a cube-map array).
    pub fn layered(&self) -> bool {
        self.cascades > 0 || self.layer.is_some()
    }

    /// The map is a cube-map array (several point lights' cubes, `shadow.placement`
    /// `cube_array`): the lit pass reads cube [`Technique::layer_base`], layer-faces
    /// 6 · base + f.
    pub fn cube_array(&self) -> bool {
        self.cube && self.layer.is_some()
    }

    /// The map is a 2D array: one layer per cascade, or one per spot or directional light.
    pub fn flat_array(&self) -> bool {
        self.layered() && !self.cube
    }

    /// The first layer the lit pass reads: a light's layer among several, 0 for cascades.
    pub fn layer_base(&self) -> usize {
        self.layer.unwrap_or(0)
    }

    /// How the cascade is picked and blended, for a cascaded light (BlendIgnored drops the
    /// band).
    pub fn cascade_select(&self) -> Option<CascadeSelect> {
        (self.cascades > 0).then_some(CascadeSelect {
            count: self.cascades,
            by_distance: self.cascade_by_distance(),
            beyond: self.cascade_beyond,
            blend: if self.is(Fault::BlendIgnored) {
                0.0
            } else {
                self.cascade_blend
            },
            blend_of: self.cascade_blend_of,
        })
    }

    /// The cascade is chosen by the receiver's distance from the eye instead of its view
    /// depth (CascadeByDistance): off the view axis a receiver goes to a farther cascade
    /// than its slice.
    pub fn cascade_by_distance(&self) -> bool {
        self.is(Fault::CascadeByDistance)
    }

    /// The lookup reads lit where w ≤ 0 (NoGuard drops it).
    pub fn guards(&self) -> bool {
        self.guard && !self.is(Fault::NoGuard)
    }

    /// The lookup reads lit outside [0,1]² (the `lit` policy; a cube map has no outside).
    pub fn tests_outside(&self) -> bool {
        !self.cube && self.outside == Outside::Lit
    }

    /// The share of the case's slope-bias scale applied, if there is a slope bias
    /// (SlopeShort: 0.8).
    pub fn slope_scale(&self) -> Option<f32> {
        let scale = if self.is(Fault::SlopeShort) { 0.8 } else { 1.0 };
        self.slope.then_some(scale)
    }

    /// The shader clamps the reference to [0,1]: when it compares in place of a sampler that
    /// would (NoClamp forgets), or, under ClampFloat, where a sampler would not.
    pub fn shader_clamps_reference(&self) -> bool {
        if self.manual() {
            self.clamp_reference && !self.is(Fault::NoClamp)
        } else {
            !self.clamp_reference && self.is(Fault::ClampFloat)
        }
    }

    /// How the map is read (BilinearCoarse, PcfOffCentre, PcfDoubleCentre). The projective
    /// form needs the coordinate untouched, so any fault samples c instead; an array has
    /// no projective compare (GLSL's textureProj takes no layer).
    pub fn taps(&self) -> Taps {
        let sampler_filters =
            !self.manual() && !matches!(self.filter, Filter::Pcf(_)) && !self.filter.shader_taps();
        match self.filter {
            _ if sampler_filters && self.cube => Taps::HardwareCube,
            _ if sampler_filters && self.mipmapped => Taps::HardwareMipmapped,
            _ if sampler_filters
                && self.bias_matrix == BiasMatrix::BeforeDivide
                && self.fault.is_none()
                && !self.layered() =>
            {
                Taps::HardwareProjective
            }
            _ if sampler_filters => Taps::Hardware,
            Filter::Nearest => Taps::Nearest,
            Filter::Linear => Taps::Bilinear {
                coarse_weights: self.is(Fault::BilinearCoarse),
                weight_gain_ppm: match self.fault {
                    Some(Fault::Scaled {
                        param: Param::FilterWeights,
                        ppm,
                    }) => ppm,
                    _ => 0,
                },
            },
            Filter::Castano13 => Taps::Castano13,
            Filter::Vogel5 => Taps::Vogel5 {
                rotated: !self.is(Fault::VogelUnrotated),
                window_y_down: self.is(Fault::NoiseYDown),
                sqrt_radius: !self.is(Fault::VogelNoSqrt),
            },
            Filter::Pcf(n) => Taps::Pcf {
                n,
                off_centre: self.is(Fault::PcfOffCentre),
                double_centre: self.is(Fault::PcfDoubleCentre),
            },
        }
    }

    /// The dimmed model keeps its share of diffuse in shadow (DimmingOff keeps none).
    pub fn keeps_diffuse_in_shadow(&self) -> bool {
        !self.is(Fault::DimmingOff)
    }

    /// What the diffuse and specular terms are multiplied by: the light's colour times its
    /// intensity, or `None` for a white light of intensity 1 (the shader then has no factor
    /// at all, as before lights had colours). LightColourIgnored drops it.
    pub fn light_colour(&self) -> Option<[f32; 3]> {
        (self.radiance != [1.0; 3] && !self.is(Fault::LightColourIgnored)).then_some(self.radiance)
    }

    /// The specular term is shadowed (SpecularUnshadowed forgets).
    pub fn shadows_specular(&self) -> bool {
        !self.is(Fault::SpecularUnshadowed)
    }

    /// The visibility is rounded to this many steps before it is used (Vis4Bit: 16).
    pub fn visibility_steps(&self) -> Option<u32> {
        self.is(Fault::Vis4Bit).then_some(16)
    }

    /// The colour is written gamma-encoded (ColourGamma).
    pub fn encodes_gamma(&self) -> bool {
        self.is(Fault::ColourGamma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::DepthFormat;

    fn spot(edit: impl FnOnce(&mut crate::format::Shadow)) -> LightRun {
        let text = r#"{ "name": "t", "about": "a technique",
            "scene": { "objects": [ { "plane": { "point": [0, 0, 0], "half_extent": 4 } } ] },
            "camera": { "eye": [0, 5, 5], "target": [0, 0, 0], "size": [8, 8] },
            "light": { "spot": { "position": [2, 6, 0], "target": [0, 0, 0], "fov_y_deg": 60, "near": 1, "far": 20 } } }"#;
        let mut point = crate::load_str(text, std::path::Path::new("t.json"))
            .expect("a valid case")
            .remove(0);
        edit(&mut point.case.shadow);
        crate::Prepared::new(point).lights.remove(0)
    }

    #[test]
    fn a_manual_compare_in_the_samplers_place_keeps_the_clamp() {
        let run = spot(|s| s.format = DepthFormat::Depth16);
        let hardware = Technique::new(&run, None);
        assert!(hardware.clamp_reference && !hardware.shader_clamps_reference());
        assert!(
            hardware
                .clone()
                .with_manual_compare()
                .shader_clamps_reference()
        );
        let forgetful = Technique::new(&run, Some(Fault::NoClamp)).with_manual_compare();
        assert!(!forgetful.shader_clamps_reference());
        let float = spot(|s| s.format = DepthFormat::Depth32f);
        assert!(!Technique::new(&float, None).shader_clamps_reference());
        assert!(Technique::new(&float, Some(Fault::ClampFloat)).shader_clamps_reference());
    }

    #[test]
    fn faults_resolve_into_the_lookups_values() {
        let run = spot(|s| s.depth_order = DepthOrder::Reversed);
        let op = |f| Technique::new(&run, f).compare_op();
        assert_eq!(op(None), CompareOp::GreaterEqual);
        assert_eq!(op(Some(Fault::CompareFlipped)), CompareOp::Less);
        assert_eq!(op(Some(Fault::CompareStrict)), CompareOp::Greater);
        let run = spot(|_| {});
        assert_eq!(Technique::new(&run, None).taps(), Taps::HardwareProjective);
        // Any fault samples the (possibly faulted) coordinate rather than textureProj's.
        assert_eq!(
            Technique::new(&run, Some(Fault::ColourGamma)).taps(),
            Taps::Hardware
        );
        let t = Technique::new(&run, Some(Fault::NoDivide));
        assert_eq!(t.coordinate().left_out, Some(CoordinateStep::Divide));
        assert_eq!(
            Technique::new(&run, Some(Fault::Repeat)).texel_wrap(),
            Outside::Repeat
        );
    }
}
