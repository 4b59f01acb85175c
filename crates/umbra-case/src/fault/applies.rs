//! Where each fault applies, beside the faults: on which backends it means anything (by what
//! the backend's family can do, [`Capabilities`]), which case points exercise it, and which
//! cases were built to see it. The self-test asks these; a new fault is taught here.

use super::{Fault, Param};
use crate::Capabilities;
use crate::format::Case;

impl Fault {
    /// Whether the fault means anything on a backend that can do `b` (its family's
    /// capabilities): a fault of a driver's shaders on a driver's backend, each where the
    /// mistake it makes can happen.
    pub fn applies(self, b: &Capabilities) -> bool {
        if !b.driver {
            return false;
        }
        match self {
            // GL's [-1, 1] depth mapping is wrong only where clip depth is [0, 1].
            Fault::GlDepthRange => b.zero_to_one_depth,
            Fault::WrongComponent | Fault::WrongTextureUnit => b.gl_texture_units,
            // The GLES 2 path has no float depth, and is the only one that clamps in the shader.
            Fault::ClampFloat => !b.gles2_technique,
            Fault::NoClamp => b.gles2_technique,
            // GLES 2 has no mipmapped compare (it skips every mipmapped case).
            Fault::MipBaseOnly | Fault::MipLevelCoarse => !b.gles2_technique,
            // A manual LINEAR filter; wgpu's GL backend has no manual compare.
            Fault::BilinearCoarse
            | Fault::Scaled {
                param: Param::FilterWeights,
                ..
            } => b.manual_compare,
            _ => true,
        }
    }

    /// Whether case `c` exercises the fault on a backend with (`es2`) or without GLES 2's
    /// technique ([`Capabilities::gles2_technique`]) at all: only such points are run for it.
    pub fn exercises(self, c: &Case, es2: bool) -> bool {
        use crate::format::{
            ColorFormat, Compare, DepthFormat, Filter, Light, Outside, Placement, ShadingModel,
        };
        let s = &c.shadow;
        // A light's kind, cascades and colour: the first light's decide, as they always have
        // (a fault's applicability light by light is for its place beside the fault).
        let light = &c.lights[0];
        match self {
            // GLES 2 compares by hand whatever the case says.
            Fault::WrongComponent => s.compare == Compare::Manual || es2,
            Fault::Repeat => s.outside != Outside::Lit,
            Fault::NoGuard => !matches!(light, Light::Directional(_)) && s.guard_behind_light,
            Fault::NoDivide => !matches!(light, Light::Directional(_)),
            Fault::ShadowViewport => s.size != c.camera.size,
            Fault::ClampFloat => {
                s.format == DepthFormat::Depth32f && s.compare == Compare::Hardware
            }
            Fault::NoClamp => s.format.is_fixed() && s.compare == Compare::Hardware,
            Fault::QuarterTexel => !matches!(light, Light::Point(_)),
            Fault::NormalOffsetShort => s.bias.normal_offset != 0.0,
            // A normal short of unit length between the vertices of a curved receiver, read by
            // whatever bias reads the normal.
            Fault::NormalUnnormalized => {
                let curved = c.scene.objects.iter().any(|o| {
                    matches!(
                        o,
                        crate::format::Object::Sphere(_) | crate::format::Object::Cylinder(_)
                    )
                });
                let b = &s.bias;
                curved
                    && (b.normal_offset != 0.0
                        || b.normal_offset_texels != 0.0
                        || b.n_dot_l.is_some()
                        || b.slope.is_some())
            }
            Fault::OffsetUnitsLow => s.bias.polygon_offset[1] != 0.0,
            Fault::SlopeShort => s.bias.slope.is_some(),
            Fault::PcfOffCentre | Fault::PcfDoubleCentre => matches!(s.filter, Filter::Pcf(_)),
            Fault::VogelUnrotated | Fault::NoiseYDown | Fault::VogelNoSqrt => {
                s.filter == Filter::Vogel5
            }
            Fault::BilinearCoarse => {
                s.filter == Filter::Linear && (s.compare == Compare::Manual || es2)
            }
            Fault::Vis4Bit => s.filter != Filter::Nearest,
            Fault::DimmingOff => c.shading.model == ShadingModel::Dimmed && c.shading.dimming > 0.0,
            Fault::SpecularUnshadowed => {
                c.shading.model == ShadingModel::Dimmed && c.shading.specular > 0.0
            }
            Fault::Oriented { face, .. } => face.is_some() == matches!(light, Light::Point(_)),
            Fault::MipBaseOnly | Fault::MipLevelCoarse => s.mipmaps.is_some(),
            Fault::ClampIgnored => s.depth_clamp,
            Fault::ClampForced => !s.depth_clamp,
            Fault::LayerShift | Fault::CascadeByDistance => {
                matches!(light, Light::Directional(d) if d.cascades.as_ref().is_some_and(|k| k.count > 1))
            }
            Fault::BlendIgnored => matches!(light, Light::Directional(d)
                if d.cascades.as_ref().is_some_and(|k| k.count > 1 && k.blend > 0.0)),
            Fault::BandOfRange => matches!(light, Light::Directional(d)
                if d.cascades.as_ref().is_some_and(|k| k.count > 1 && k.blend > 0.0
                    && k.blend_of == crate::format::BlendOf::Far)),
            Fault::WorldOffsetsDropped => {
                s.bias.normal_offset_texels != 0.0 || s.bias.light_offset != 0.0
            }
            Fault::LightColourIgnored => light.radiance() != [1.0; 3],
            Fault::ClearIgnored => c.camera.clear != [0.0; 3],
            Fault::LitCullFlipped => !c.camera.cull.is_none(),
            Fault::DepthFuncSwapped => s.depth_test().inclusive(),
            Fault::SrgbIgnored => c.camera.color_format == ColorFormat::Srgb8Alpha8,
            Fault::LightSwap => c.lights.len() > 1,
            Fault::ArrayLayerZero => c.lights.len() > 1 && s.placement != Placement::Separate,
            Fault::Scaled { param, .. } => {
                let b = &s.bias;
                match param {
                    Param::OffsetUnits => b.polygon_offset[1] != 0.0,
                    Param::OffsetFactor => b.polygon_offset[0] != 0.0,
                    Param::OffsetClamp => {
                        b.polygon_offset_clamp != 0.0 && b.polygon_offset != [0.0, 0.0]
                    }
                    Param::ConstantBias => b.constant != 0.0,
                    Param::SlopeScale | Param::SlopeCap => b.slope.is_some(),
                    Param::NormalOffset => b.normal_offset != 0.0,
                    Param::NdotLScale | Param::NdotLMin => b.n_dot_l.is_some(),
                    Param::LookupU | Param::LookupV => !matches!(light, Light::Point(_)),
                    Param::ShadowShiftU | Param::ShadowShiftV => true,
                    // GLES 2 compares (and so filters) in the shader whatever the case says.
                    Param::FilterWeights => {
                        s.filter == Filter::Linear && (s.compare == Compare::Manual || es2)
                    }
                }
            }
            _ => true,
        }
    }

    /// The cases built to see the fault (magnified views, exact ties, the guard's own case): their
    /// points are tried first, so a subtle fault is not left to whichever points a spread over
    /// the catalogue happens to pick.
    pub fn aimed_at(self, c: &Case) -> bool {
        let cases: &[&str] = match self {
            Fault::CompareStrict | Fault::ClampFloat | Fault::NoClamp => {
                &["far-clamp", "beyond-far"]
            }
            Fault::QuarterTexel | Fault::ShadowHalfTexel => {
                &["contact", "filters-magnified", "guard-magnified"]
            }
            Fault::NormalOffsetShort | Fault::OffsetUnitsLow | Fault::SlopeShort => {
                &["bias-forms-magnified", "contact", "grazing"]
            }
            Fault::NormalUnnormalized => &["engine-curved", "bias-forms-curved-magnified"],
            Fault::PcfOffCentre
            | Fault::PcfDoubleCentre
            | Fault::BilinearCoarse
            | Fault::Vis4Bit => &["filters-magnified", "filters"],
            Fault::VogelUnrotated | Fault::NoiseYDown | Fault::VogelNoSqrt => {
                &["filters-magnified", "filters", "three-directional"]
            }
            Fault::NoGuard => &["guard-magnified", "behind-spot", "bias-matrix"],
            Fault::Repeat => &["outside"],
            Fault::ClampIgnored => &["pancake", "near-crossing-clamped"],
            Fault::ClampForced => &["pancake", "near-crossing"],
            Fault::LayerShift | Fault::CascadeByDistance => &["street", "on-split", "blend"],
            Fault::BlendIgnored => &["blend", "bevy-forms"],
            Fault::BandOfRange | Fault::WorldOffsetsDropped => &["bevy-forms"],
            Fault::LightColourIgnored | Fault::ClearIgnored => &["tinted"],
            Fault::LitCullFlipped => &["lit-cull"],
            Fault::DepthFuncSwapped => &["depth-func"],
            Fault::SrgbIgnored => &["srgb"],
            Fault::LightSwap | Fault::ArrayLayerZero => &["two-lights", "two-points"],
            Fault::Oriented { face: Some(_), .. } => &["point-faces"],
            Fault::Scaled { param, .. } if param.in_texels() => {
                &["contact", "filters-magnified", "guard-magnified"]
            }
            Fault::Scaled {
                param: Param::FilterWeights,
                ..
            } => &["filters-magnified", "filters", "outside-filtered"],
            Fault::Scaled { .. } => &[
                "bias-forms-magnified",
                "bias-forms-curved-magnified",
                "offset-magnified",
                "offset-clamp-magnified",
                "offset-boundary",
                "far-boundary",
                "contact",
                "grazing",
            ],
            Fault::Oriented { face: None, .. } => &["l-occluder"],
            _ => &[],
        };
        cases.contains(&c.name.as_str())
    }
}
