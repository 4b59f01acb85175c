//! Named faults a backend can be run with, to prove that the harness catches real mistakes
//! (docs/catalogue.md, "Faults the harness must catch"). A fault is active only when the process
//! has `UMBRA_SELFTEST=1` *and* `UMBRA_FAULT=<name>`: `cargo xtask selftest` sets both in its
//! worker processes, and no other path can turn one on.
//!
//! Two families. The *gross* faults are the classic mistakes of shadow-mapping code, each
//! visible on most of a frame. The *subtle* ones are what a driver gets wrong by less than a
//! texel, less than a depth step, only at exact ties, only in filtered values or only in
//! colour ([`Subtlety`]): a harness that catches only the first family passes most real
//! driver bugs.

mod applies;

/// How small a fault's effect is (for the self-test's report).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Subtlety {
    /// Visible on large parts of a frame.
    Gross,
    /// Changes only compares whose two values are exactly equal.
    ExactTie,
    /// Moves a lookup or the map by less than a texel.
    SubTexel,
    /// Moves a depth by less than a depth step (or a few).
    SubStep,
    /// Changes only filtered (PCF, LINEAR) values.
    Filtered,
    /// Changes only the shaded colour.
    Colour,
    /// Moves a face's content by a symmetry of the square: invisible wherever that content
    /// is symmetric.
    Orientation,
}

impl Subtlety {
    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Subtlety::Gross => "gross",
            Subtlety::ExactTie => "exact tie",
            Subtlety::SubTexel => "sub-texel",
            Subtlety::SubStep => "sub-step",
            Subtlety::Filtered => "filtered values",
            Subtlety::Colour => "colour",
            Subtlety::Orientation => "orientation",
        }
    }
}

/// A wrong orientation of a square image: one of the seven symmetries of the square other
/// than the identity (the dihedral group D4), acting on a face's clip x and y. A cube face drawn
/// with a wrong up vector is rotated; one drawn with the wrong handedness (or stored with its
/// rows or columns reversed, or its axes swapped) is mirrored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Orientation {
    /// A quarter turn (x, y) → (−y, x): the face's up vector is one of its sides.
    Rot90,
    /// A half turn (x, y) → (−x, −y): the face's up vector is reversed.
    Rot180,
    /// Three quarter turns (x, y) → (y, −x).
    Rot270,
    /// Columns reversed (x, y) → (−x, y): the face's handedness is wrong.
    MirrorX,
    /// Rows reversed (x, y) → (x, −y): the other row order.
    MirrorY,
    /// Axes swapped (x, y) → (y, x): the image transposed.
    Transpose,
    /// Axes swapped and reversed (x, y) → (−y, −x).
    AntiTranspose,
}

impl Orientation {
    /// Every wrong orientation.
    pub const ALL: [Orientation; 7] = [
        Orientation::Rot90,
        Orientation::Rot180,
        Orientation::Rot270,
        Orientation::MirrorX,
        Orientation::MirrorY,
        Orientation::Transpose,
        Orientation::AntiTranspose,
    ];

    /// Name for fault names and reports.
    pub fn name(self) -> &'static str {
        match self {
            Orientation::Rot90 => "rot90",
            Orientation::Rot180 => "rot180",
            Orientation::Rot270 => "rot270",
            Orientation::MirrorX => "mirror-x",
            Orientation::MirrorY => "mirror-y",
            Orientation::Transpose => "transpose",
            Orientation::AntiTranspose => "anti-transpose",
        }
    }

    /// The 2 × 2 matrix acting on (x, y), rows first.
    pub fn xy(self) -> [[f32; 2]; 2] {
        match self {
            Orientation::Rot90 => [[0.0, -1.0], [1.0, 0.0]],
            Orientation::Rot180 => [[-1.0, 0.0], [0.0, -1.0]],
            Orientation::Rot270 => [[0.0, 1.0], [-1.0, 0.0]],
            Orientation::MirrorX => [[-1.0, 0.0], [0.0, 1.0]],
            Orientation::MirrorY => [[1.0, 0.0], [0.0, -1.0]],
            Orientation::Transpose => [[0.0, 1.0], [1.0, 0.0]],
            Orientation::AntiTranspose => [[0.0, -1.0], [-1.0, 0.0]],
        }
    }

    /// The matrix put in front of a face's view-projection: it moves clip x and y (and so
    /// the rendered image) and leaves z and w alone.
    pub fn clip(self) -> glam::Mat4 {
        let [[a, b], [c, d]] = self.xy();
        glam::Mat4::from_cols(
            glam::Vec4::new(a, c, 0.0, 0.0),
            glam::Vec4::new(b, d, 0.0, 0.0),
            glam::Vec4::Z,
            glam::Vec4::W,
        )
    }

    /// It reverses the winding (a mirror): the pass's front face is flipped with it, so that
    /// the face's content is moved and no other triangle is culled.
    pub fn mirrors(self) -> bool {
        let [[a, b], [c, d]] = self.xy();
        a * d - b * c < 0.0
    }
}

/// A continuous parameter a driver (or a program) can get wrong by a little: the self-test's
/// `--thresholds` sweep scales each by a relative error (or, for the shifts, moves it by a
/// fraction of a texel) and finds the smallest error the catalogue catches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Param {
    /// Polygon-offset units (`glPolygonOffset`'s second argument, Vulkan's constant factor).
    OffsetUnits,
    /// Polygon-offset factor (the slope term).
    OffsetFactor,
    /// Polygon-offset clamp.
    OffsetClamp,
    /// The shader's constant bias.
    ConstantBias,
    /// The slope bias's scale.
    SlopeScale,
    /// The slope bias's cap.
    SlopeCap,
    /// The normal offset.
    NormalOffset,
    /// The N·L bias's scale.
    NdotLScale,
    /// The N·L bias's least value.
    NdotLMin,
    /// The lookup coordinate along u, in texels.
    LookupU,
    /// The lookup coordinate along v, in texels.
    LookupV,
    /// The shadow pass's image along x, in texels.
    ShadowShiftU,
    /// The shadow pass's image along y, in texels.
    ShadowShiftV,
    /// A manual bilinear filter's weights about ½: a → ½ + (a − ½)(1 + e).
    FilterWeights,
}

impl Param {
    /// Every parameter.
    pub const ALL: [Param; 14] = [
        Param::OffsetUnits,
        Param::OffsetFactor,
        Param::OffsetClamp,
        Param::ConstantBias,
        Param::SlopeScale,
        Param::SlopeCap,
        Param::NormalOffset,
        Param::NdotLScale,
        Param::NdotLMin,
        Param::LookupU,
        Param::LookupV,
        Param::ShadowShiftU,
        Param::ShadowShiftV,
        Param::FilterWeights,
    ];

    /// Name for fault names and reports.
    pub fn name(self) -> &'static str {
        match self {
            Param::OffsetUnits => "offset-units",
            Param::OffsetFactor => "offset-factor",
            Param::OffsetClamp => "offset-clamp",
            Param::ConstantBias => "constant-bias",
            Param::SlopeScale => "slope-scale",
            Param::SlopeCap => "slope-cap",
            Param::NormalOffset => "normal-offset",
            Param::NdotLScale => "ndotl-scale",
            Param::NdotLMin => "ndotl-min",
            Param::LookupU => "lookup-u",
            Param::LookupV => "lookup-v",
            Param::ShadowShiftU => "shadow-shift-u",
            Param::ShadowShiftV => "shadow-shift-v",
            Param::FilterWeights => "filter-weights",
        }
    }

    /// The error is a shift in texels, not a relative error of the parameter.
    pub fn in_texels(self) -> bool {
        matches!(
            self,
            Param::LookupU | Param::LookupV | Param::ShadowShiftU | Param::ShadowShiftV
        )
    }
}

/// A deliberate mistake of the kind real shadow-mapping code (or a driver) makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fault {
    /// The depth compare runs the wrong way (GREATER for LEQUAL).
    CompareFlipped,
    /// The lookup forgets the perspective divide.
    NoDivide,
    /// The w > 0 guard is missing (receivers behind a spot light back-project).
    NoGuard,
    /// The shadow map repeats instead of clamping.
    Repeat,
    /// A manual compare reads the wrong component of a depth texel (`.g`, which is 0 in a
    /// core profile).
    WrongComponent,
    /// The bias matrix is applied twice.
    BiasTwice,
    /// The bias matrix is not applied at all.
    NoBias,
    /// The GL [-1,1] depth range is used on a [0,1] API.
    GlDepthRange,
    /// The readback forgets (or adds) the one row flip.
    NoYFlip,
    /// The shadow pass keeps the camera's viewport instead of the map's.
    ShadowViewport,
    /// The map is bound to texture unit 1 while the sampler uniform says 0.
    WrongTextureUnit,
    /// The compare is strict: LESS for LEQUAL (GREATER for GEQUAL). Differs only where the
    /// reference value equals the stored one.
    CompareStrict,
    /// A float (D32F) format's reference value is clamped to [0,1] as a fixed-point one's is.
    ClampFloat,
    /// The GLES 2 path's emulated hardware compare forgets to clamp the reference value.
    NoClamp,
    /// The lookup coordinate is a quarter texel off along u.
    QuarterTexel,
    /// The shadow pass is shifted by half a texel along x (a projection's texel-centre slip).
    ShadowHalfTexel,
    /// The normal offset is three quarters of what the case asks.
    NormalOffsetShort,
    /// The polygon offset's units are cut to a tenth: r·units below the smallest the specs
    /// allow on every driver umbra runs (Mesa's r is 2/(2ⁿ − 1), zink's 4/(2ⁿ − 1); the
    /// smallest legal is 2⁻ⁿ).
    OffsetUnitsLow,
    /// The slope bias's scale is 0.8 of what the case asks.
    SlopeShort,
    /// The PCF kernel is not centred: offsets k − N/2 instead of k − (N − 1)/2.
    PcfOffCentre,
    /// One PCF corner tap is replaced by the centre tap.
    PcfDoubleCentre,
    /// The shader's bilinear weights are quantised to quarters.
    BilinearCoarse,
    /// The visibility is quantised to 1/16 before it is used and stored.
    Vis4Bit,
    /// The colour is written gamma-encoded (square root) where the case is linear.
    ColourGamma,
    /// The dimmed model keeps no diffuse in shadow (dimming ignored).
    DimmingOff,
    /// The specular term is not shadowed.
    SpecularUnshadowed,
    /// A mipmapped map is sampled from level 0 alone (the sampler ignores the mip filter):
    /// distant receivers read the finest level.
    MipBaseOnly,
    /// A mipmapped map's levels start one too coarse (level 1 read where level 0 is asked,
    /// and so on: an LOD off by one).
    MipLevelCoarse,
    /// The shadow pass clips at the light's near and far planes although the case asks for
    /// depth clamp (a driver that ignores GL_DEPTH_CLAMP or depthClampEnable): a caster
    /// in front of the near plane is cut away.
    ClampIgnored,
    /// The shadow pass clamps depth although the case does not ask for it (a driver whose
    /// clamp state leaks from an earlier draw): casters in front of the near plane are stored
    /// at it.
    ClampForced,
    /// The shadow pass draws each cascade into the next layer of the array (the last into
    /// layer 0): every receiver of a cascaded light is looked up in another slice's map.
    LayerShift,
    /// The lit pass picks the cascade by the receiver's distance from the eye instead of its
    /// view depth (the camera's z): off the view axis the distance is larger, so receivers
    /// near a split are looked up in the next cascade, whose map may not cover them.
    CascadeByDistance,
    /// The lit pass switches cascades hard where the case asks for a blend band (a blend
    /// weight that never leaves 0).
    BlendIgnored,
    /// The lit pass takes the blend band as a share of the cascade's range where the case
    /// asks for a share of its far bound (Unity's and Godot's formula in a port of Bevy's
    /// `blend_of: far`): the band is narrower, so part of it switches hard.
    BandOfRange,
    /// The lit pass leaves out the texel-scaled normal offset and the offset towards the
    /// light (`normal_offset_texels`, `light_offset`: a port that keeps only a world normal
    /// offset and a depth constant): the unbiased receivers shadow themselves.
    WorldOffsetsDropped,
    /// The lit pass shades with a white light of intensity 1 whatever the case's light
    /// colour and intensity (a colour uniform that never reaches the shader).
    LightColourIgnored,
    /// The lit pass clears its colour target to black whatever the case's clear colour (a
    /// clear value dropped on the way to the driver).
    ClearIgnored,
    /// The lit pass culls the other face than the case asks (a front-face winding taken the
    /// wrong way round, as a y-flipped framebuffer does): back faces show, front faces go.
    LitCullFlipped,
    /// The shadow pass applies the mirrored depth function where the case asks for an
    /// inclusive one (a compare-op table with its LEQUAL and GEQUAL entries swapped): the map
    /// keeps the farthest surface instead of the nearest.
    DepthFuncSwapped,
    /// The lit pass's colour target is linear where the case asks for sRGB (desktop GL's
    /// GL_FRAMEBUFFER_SRGB left disabled, the classic; a driver that drops the encoding):
    /// colours are stored unencoded, darker in every mid-tone.
    SrgbIgnored,
    /// With several lights, each light's lit pass reads the next light's map (light k that
    /// of light k + 1, the last the first's): a texture unit or array layer indexed by the
    /// wrong light, the mix-up of two lights' maps.
    LightSwap,
    /// With several lights in one array (2D, or a cube-map array), every light's lit pass
    /// reads layer (cube) 0 (a layer index that never reaches the shader or the sampler's
    /// coordinate).
    ArrayLayerZero,
    /// The lookup takes the interpolated normal as the rasteriser gives it, not renormalised
    /// (the shading still normalises it): the normal offset and the N·L and slope biases
    /// read a normal short of unit length between the vertices of a curved receiver, by
    /// 1 − cos(π/segments) at a quad's middle (7.6 % on an 8-segment cylinder, 5·10⁻⁴ on a
    /// 96-segment sphere).
    NormalUnnormalized,
    /// The Vogel disk is not rotated per pixel (φ = 0: the noise dropped, as a port that
    /// wants a stable picture does): every pixel samples the same five offsets, and a soft
    /// edge turns from grain into a fixed pattern.
    VogelUnrotated,
    /// The Vogel disk's noise reads the window position with y down from the top row, as
    /// WGSL's `@builtin(position)` gives it, instead of GL's gl_FragCoord (a WebGL shader
    /// ported to WebGPU without the flip): each pixel gets another pixel's rotation.
    NoiseYDown,
    /// The Vogel disk's taps lie at (k + ½)/5 of the radius instead of √((k + ½)/5): the
    /// area law forgotten, the taps bunched towards the centre.
    VogelNoSqrt,
    /// State leaks from one case point to the next: the lit pass keeps the texture matrices
    /// of the first case a worker process rendered for every later case (a uniform upload
    /// skipped once a program has one, a stale binding). Each point alone renders right; a
    /// point after another renders with the other's lookup.
    StaleUniform,
    /// One face of the map is drawn with a wrong orientation: cube face `face` (0–5 in the
    /// GL order +x, −x, +y, −y, +z, −z), or the 2D map when `face` is `None`.
    Oriented {
        /// The cube face, or None for a 2D map.
        face: Option<u8>,
        /// The mistake.
        orientation: Orientation,
    },
    /// A continuous parameter off by `ppm` millionths: relative (the parameter × (1 + e)),
    /// or for the shifts `e` texels ([`Param::in_texels`]). Named `PARAM@E`, e.g.
    /// `offset-units@-0.05`; `umbra selftest --thresholds` sweeps them.
    Scaled {
        /// The parameter.
        param: Param,
        /// The error e, in millionths.
        ppm: i32,
    },
}

impl Fault {
    /// Every fault the self-test runs by default. [`Fault::Oriented`] has 6 × 7 + 7 forms;
    /// three stand for them here (a wrong handedness on the +x face, the one the
    /// four-fold symmetric point-light cases could not see; a wrong up vector on the −y face;
    /// a transposed 2D map), and `umbra selftest --fault` or `--orientations` runs any.
    pub const ALL: [Fault; 50] = [
        Fault::CompareFlipped,
        Fault::NoDivide,
        Fault::NoGuard,
        Fault::Repeat,
        Fault::WrongComponent,
        Fault::BiasTwice,
        Fault::NoBias,
        Fault::GlDepthRange,
        Fault::NoYFlip,
        Fault::ShadowViewport,
        Fault::WrongTextureUnit,
        Fault::CompareStrict,
        Fault::ClampFloat,
        Fault::NoClamp,
        Fault::QuarterTexel,
        Fault::ShadowHalfTexel,
        Fault::NormalOffsetShort,
        Fault::OffsetUnitsLow,
        Fault::SlopeShort,
        Fault::PcfOffCentre,
        Fault::PcfDoubleCentre,
        Fault::BilinearCoarse,
        Fault::Vis4Bit,
        Fault::ColourGamma,
        Fault::DimmingOff,
        Fault::SpecularUnshadowed,
        Fault::MipBaseOnly,
        Fault::MipLevelCoarse,
        Fault::ClampIgnored,
        Fault::ClampForced,
        Fault::LayerShift,
        Fault::CascadeByDistance,
        Fault::BlendIgnored,
        Fault::BandOfRange,
        Fault::WorldOffsetsDropped,
        Fault::LightColourIgnored,
        Fault::ClearIgnored,
        Fault::LitCullFlipped,
        Fault::DepthFuncSwapped,
        Fault::SrgbIgnored,
        Fault::LightSwap,
        Fault::ArrayLayerZero,
        Fault::StaleUniform,
        Fault::NormalUnnormalized,
        Fault::VogelUnrotated,
        Fault::NoiseYDown,
        Fault::VogelNoSqrt,
        Fault::Oriented {
            face: Some(0),
            orientation: Orientation::MirrorX,
        },
        Fault::Oriented {
            face: Some(3),
            orientation: Orientation::Rot90,
        },
        Fault::Oriented {
            face: None,
            orientation: Orientation::Transpose,
        },
    ];

    /// Every orientation fault: each cube face and the 2D map, each wrong orientation.
    pub fn orientations() -> Vec<Fault> {
        let faces = (0..6).map(Some).chain(std::iter::once(None));
        faces
            .flat_map(|face| {
                Orientation::ALL.map(|orientation| Fault::Oriented { face, orientation })
            })
            .collect()
    }

    /// The fault's name, as `UMBRA_FAULT` takes it.
    pub fn name(self) -> String {
        let name = match self {
            Fault::CompareFlipped => "compare-flipped",
            Fault::NoDivide => "no-divide",
            Fault::NoGuard => "no-guard",
            Fault::Repeat => "repeat",
            Fault::WrongComponent => "wrong-component",
            Fault::BiasTwice => "bias-twice",
            Fault::NoBias => "no-bias",
            Fault::GlDepthRange => "gl-depth-range",
            Fault::NoYFlip => "no-y-flip",
            Fault::ShadowViewport => "shadow-viewport",
            Fault::WrongTextureUnit => "wrong-texture-unit",
            Fault::CompareStrict => "compare-strict",
            Fault::ClampFloat => "clamp-float",
            Fault::NoClamp => "no-clamp",
            Fault::QuarterTexel => "quarter-texel",
            Fault::ShadowHalfTexel => "shadow-half-texel",
            Fault::NormalOffsetShort => "normal-offset-short",
            Fault::OffsetUnitsLow => "offset-units-low",
            Fault::SlopeShort => "slope-short",
            Fault::PcfOffCentre => "pcf-off-centre",
            Fault::PcfDoubleCentre => "pcf-double-centre",
            Fault::BilinearCoarse => "bilinear-coarse",
            Fault::Vis4Bit => "vis-4bit",
            Fault::ColourGamma => "colour-gamma",
            Fault::DimmingOff => "dimming-off",
            Fault::SpecularUnshadowed => "specular-unshadowed",
            Fault::MipBaseOnly => "mip-base-only",
            Fault::MipLevelCoarse => "mip-level-coarse",
            Fault::ClampIgnored => "clamp-ignored",
            Fault::ClampForced => "clamp-forced",
            Fault::LayerShift => "layer-shift",
            Fault::CascadeByDistance => "cascade-by-distance",
            Fault::BlendIgnored => "blend-ignored",
            Fault::BandOfRange => "band-of-range",
            Fault::WorldOffsetsDropped => "world-offsets-dropped",
            Fault::LightColourIgnored => "light-colour-ignored",
            Fault::ClearIgnored => "clear-ignored",
            Fault::LitCullFlipped => "lit-cull-flipped",
            Fault::DepthFuncSwapped => "depth-func-swapped",
            Fault::SrgbIgnored => "srgb-ignored",
            Fault::LightSwap => "light-swap",
            Fault::ArrayLayerZero => "array-layer-zero",
            Fault::StaleUniform => "stale-uniform",
            Fault::NormalUnnormalized => "normal-unnormalized",
            Fault::VogelUnrotated => "vogel-unrotated",
            Fault::NoiseYDown => "noise-y-down",
            Fault::VogelNoSqrt => "vogel-no-sqrt",
            Fault::Oriented { face, orientation } => {
                return match face {
                    Some(f) => format!("face{f}-{}", orientation.name()),
                    None => format!("map-{}", orientation.name()),
                };
            }
            Fault::Scaled { param, ppm } => {
                return format!("{}@{}", param.name(), f64::from(ppm) / 1e6);
            }
        };
        name.to_string()
    }

    /// How small its effect is.
    pub fn subtlety(self) -> Subtlety {
        match self {
            Fault::CompareStrict | Fault::ClampFloat | Fault::NoClamp => Subtlety::ExactTie,
            Fault::QuarterTexel | Fault::ShadowHalfTexel | Fault::NormalOffsetShort => {
                Subtlety::SubTexel
            }
            Fault::OffsetUnitsLow | Fault::SlopeShort | Fault::NormalUnnormalized => {
                Subtlety::SubStep
            }
            Fault::PcfOffCentre
            | Fault::PcfDoubleCentre
            | Fault::BilinearCoarse
            | Fault::VogelUnrotated
            | Fault::NoiseYDown
            | Fault::VogelNoSqrt
            | Fault::Vis4Bit
            | Fault::MipBaseOnly
            | Fault::MipLevelCoarse => Subtlety::Filtered,
            Fault::ColourGamma
            | Fault::DimmingOff
            | Fault::SpecularUnshadowed
            | Fault::LightColourIgnored
            | Fault::SrgbIgnored => Subtlety::Colour,
            Fault::Oriented { .. } => Subtlety::Orientation,
            Fault::Scaled { param, .. } if param.in_texels() => Subtlety::SubTexel,
            Fault::Scaled {
                param: Param::FilterWeights,
                ..
            } => Subtlety::Filtered,
            Fault::Scaled { .. } => Subtlety::SubStep,
            _ => Subtlety::Gross,
        }
    }

    /// Parses a name.
    pub fn parse(s: &str) -> Option<Fault> {
        if let Some((param, e)) = s.split_once('@') {
            let param = Param::ALL.into_iter().find(|p| p.name() == param)?;
            let e: f64 = e
                .parse()
                .ok()
                .filter(|e: &f64| e.is_finite() && e.abs() <= 100.0)?;
            // Held to the nearest millionth; an E that rounds to none is refused (it once
            // became no fault at all, which then read as a fault the judge missed).
            if (e * 1e6).round() == 0.0 {
                return None;
            }
            return Some(Fault::scaled(param, e));
        }
        Fault::ALL
            .into_iter()
            .chain(Fault::orientations())
            .find(|f| f.name() == s)
    }

    /// `param` off by `e` (relative, or texels for a shift), to a millionth.
    pub fn scaled(param: Param, e: f64) -> Fault {
        Fault::Scaled {
            param,
            ppm: (e * 1e6).round() as i32,
        }
    }

    /// The error this fault gives `param`, if it is that parameter's.
    pub fn error_of(self, param: Param) -> Option<f32> {
        match self {
            Fault::Scaled { param: p, ppm } if p == param => Some(ppm as f32 / 1e6),
            _ => None,
        }
    }

    /// Whether a faulted backend's shadow pass clamps depth where the case `asks` it to
    /// (`shadow.depth_clamp`) or not.
    pub fn depth_clamp(fault: Option<Fault>, asks: bool) -> bool {
        match fault {
            Some(Fault::ClampIgnored) => false,
            Some(Fault::ClampForced) => true,
            _ => asks,
        }
    }

    /// The colour a backend under `fault` (if any) clears its lit pass's colour target to:
    /// the case's `camera.clear`, black under ClearIgnored.
    pub fn clear_colour(fault: Option<Fault>, camera: &crate::format::Camera) -> [f32; 3] {
        if fault == Some(Fault::ClearIgnored) {
            [0.0; 3]
        } else {
            camera.clear
        }
    }

    /// The faces a backend under `fault` (if any) culls in its lit pass: the case's
    /// `camera.cull`, the other face under LitCullFlipped.
    pub fn lit_cull(fault: Option<Fault>, camera: &crate::format::Camera) -> crate::format::Cull {
        if fault == Some(Fault::LitCullFlipped) {
            camera.cull.flipped()
        } else {
            camera.cull
        }
    }

    /// The colour target a backend under `fault` (if any) gives its lit pass: the case's
    /// `camera.color_format`, linear RGBA8 under SrgbIgnored.
    pub fn colour_format(
        fault: Option<Fault>,
        camera: &crate::format::Camera,
    ) -> crate::format::ColorFormat {
        if fault == Some(Fault::SrgbIgnored) {
            crate::format::ColorFormat::Rgba8
        } else {
            camera.color_format
        }
    }

    /// The depth test a backend under `fault` (if any) gives its shadow pass: the case's
    /// ([`crate::format::Shadow::depth_test`]), mirrored under DepthFuncSwapped where that is
    /// an inclusive function.
    pub fn depth_func(
        fault: Option<Fault>,
        shadow: &crate::format::Shadow,
    ) -> crate::format::DepthFunc {
        let f = shadow.depth_test();
        if fault == Some(Fault::DepthFuncSwapped) && f.inclusive() {
            f.mirrored()
        } else {
            f
        }
    }

    /// The case's bias as a faulted backend applies it: units cut to a tenth
    /// (OffsetUnitsLow), or one parameter × (1 + e) ([`Fault::Scaled`]). The shader's own
    /// scale faults (NormalOffsetShort, SlopeShort) are written into the source instead.
    pub fn bias(self, b: &crate::format::Bias) -> crate::format::Bias {
        let mut b = b.clone();
        if self == Fault::OffsetUnitsLow {
            b.polygon_offset[1] *= 0.1;
        }
        let Fault::Scaled { param, .. } = self else {
            return b;
        };
        let k = 1.0 + self.error_of(param).unwrap_or(0.0);
        match param {
            Param::OffsetUnits => b.polygon_offset[1] *= k,
            Param::OffsetFactor => b.polygon_offset[0] *= k,
            Param::OffsetClamp => b.polygon_offset_clamp *= k,
            Param::ConstantBias => b.constant *= k,
            Param::SlopeScale => b.slope.iter_mut().for_each(|s| s.scale *= k),
            Param::SlopeCap => b.slope.iter_mut().for_each(|s| s.max *= k),
            Param::NormalOffset => b.normal_offset *= k,
            Param::NdotLScale => b.n_dot_l.iter_mut().for_each(|n| n.scale *= k),
            Param::NdotLMin => b.n_dot_l.iter_mut().for_each(|n| n.min *= k),
            _ => {}
        }
        b
    }

    /// Texels the shadow pass's image is moved by along x and y (ShadowHalfTexel: ½ along
    /// x; the shadow-shift parameters).
    pub fn shadow_shift_texels(self) -> [f32; 2] {
        match self {
            Fault::ShadowHalfTexel => [0.5, 0.0],
            _ => [
                self.error_of(Param::ShadowShiftU).unwrap_or(0.0),
                self.error_of(Param::ShadowShiftV).unwrap_or(0.0),
            ],
        }
    }

    /// The matrix put in front of face `face`'s view-projection when the shadow pass renders
    /// it (`cube`: the map is a cube map), and whether that matrix mirrors the face; `None`
    /// when this fault leaves the face alone.
    pub fn face_mistake(self, face: usize, cube: bool) -> Option<(glam::Mat4, bool)> {
        match self {
            Fault::Oriented {
                face: f,
                orientation,
            } if f.map(usize::from) == cube.then_some(face) => {
                Some((orientation.clip(), orientation.mirrors()))
            }
            _ => None,
        }
    }

    /// Whose map light `k` of `lights` reads in its lit pass: its own; the next light's under
    /// LightSwap, where that map is of the same kind (`cube(j)`: light j's map is a cube map;
    /// a 2D map cannot be bound where a cube map is sampled, nor the reverse: that is an API
    /// error, not a frame to judge); the first's under ArrayLayerZero where the maps are one
    /// array's layers (`array`).
    pub fn map_of_light(
        fault: Option<Fault>,
        k: usize,
        lights: usize,
        array: bool,
        cube: impl Fn(usize) -> bool,
    ) -> usize {
        match fault {
            Some(Fault::LightSwap) if cube((k + 1) % lights) == cube(k) => (k + 1) % lights,
            Some(Fault::ArrayLayerZero) if array => 0,
            _ => k,
        }
    }

    /// Light `k`'s texture matrices `tex` for case `case`, as a backend under `fault` uploads
    /// them: under [`Fault::StaleUniform`], those the process first uploaded for light `k`
    /// of another case (same count), the stale state an earlier point left; otherwise (and
    /// for the first case, its twins included) as given.
    pub fn stale_texture(fault: Option<Fault>, case: &str, k: usize, tex: &mut [glam::Mat4]) {
        use std::sync::Mutex;
        type Kept = std::collections::BTreeMap<usize, (String, Vec<glam::Mat4>)>;
        static FIRST: Mutex<Kept> = Mutex::new(Kept::new());
        if fault != Some(Fault::StaleUniform) {
            return;
        }
        let Ok(mut first) = FIRST.lock() else {
            return;
        };
        match first.get(&k) {
            Some((name, kept)) if name != case && kept.len() == tex.len() => {
                tex.copy_from_slice(kept);
            }
            Some(_) => {}
            None => {
                first.insert(k, (case.to_string(), tex.to_vec()));
            }
        }
    }

    /// The light view the shadow pass draws into layer `face` of `faces` (`layered`: the
    /// layers of a cascade array): LayerShift draws the next cascade's there.
    pub fn drawn_view(fault: Option<Fault>, face: usize, faces: usize, layered: bool) -> usize {
        match fault {
            Some(Fault::LayerShift) if layered => (face + 1) % faces,
            _ => face,
        }
    }

    /// Checks this process's `UMBRA_FAULT` before anything runs: a name no fault has is an
    /// error (else every run would silently run no fault, and a self-test pair would read as
    /// the judge missing it); one without `UMBRA_SELFTEST=1` is said to do nothing.
    pub fn check_env() -> Result<Option<String>, String> {
        // Unset or empty (a CI matrix's blank entry): no fault.
        let Some(name) = std::env::var("UMBRA_FAULT").ok().filter(|n| !n.is_empty()) else {
            return Ok(None);
        };
        if Fault::parse(&name).is_none() {
            let names: Vec<String> = Fault::ALL.iter().map(|f| f.name()).collect();
            return Err(format!(
                "UMBRA_FAULT={name:?} names no fault; the faults are {}, face<0-5>-<orientation>, map-<orientation> and PARAM@E (`umbra selftest --help`); or unset UMBRA_FAULT",
                names.join(", ")
            ));
        }
        if std::env::var("UMBRA_SELFTEST").ok().as_deref() != Some("1") {
            return Ok(Some(format!(
                "UMBRA_FAULT={name} does nothing without UMBRA_SELFTEST=1 (the self-test sets both)"
            )));
        }
        Ok(None)
    }

    /// The active fault of this process, if the self-test turned one on.
    pub fn active() -> Option<Fault> {
        if std::env::var("UMBRA_SELFTEST").ok().as_deref() != Some("1") {
            return None;
        }
        std::env::var("UMBRA_FAULT")
            .ok()
            .and_then(|f| Fault::parse(&f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientations_are_the_seven_other_symmetries_of_the_square() {
        let mut seen = vec![[[1.0, 0.0], [0.0, 1.0]]];
        for o in Orientation::ALL {
            let m = o.xy();
            // A symmetry of the square maps its corner (1, 1) onto a corner.
            let corner = [m[0][0] + m[0][1], m[1][0] + m[1][1]];
            assert!(corner.iter().all(|c| c.abs() == 1.0), "{o:?}");
            assert!(!seen.contains(&m), "{o:?} repeats a symmetry");
            seen.push(m);
            let clip = o.clip() * glam::Vec4::new(0.25, 0.5, 0.3, 1.0);
            assert_eq!((clip.z, clip.w), (0.3, 1.0), "{o:?} moves depth");
        }
        let mirrors = Orientation::ALL.iter().filter(|o| o.mirrors()).count();
        assert_eq!(mirrors, 4);
    }

    #[test]
    fn scaled_faults_parse_and_apply_to_one_parameter() {
        let f = Fault::parse("offset-units@-0.05").expect("a fault");
        assert_eq!(f, Fault::scaled(Param::OffsetUnits, -0.05));
        assert_eq!(Fault::parse(&f.name()), Some(f));
        let b = crate::format::Bias {
            polygon_offset: [2.0, 4.0],
            constant: 0.001,
            ..Default::default()
        };
        let faulted = f.bias(&b);
        assert_eq!(faulted.polygon_offset, [2.0, 3.8]);
        assert_eq!(faulted.constant, 0.001);
        assert_eq!(Fault::OffsetUnitsLow.bias(&b).polygon_offset[1], 0.4);
        assert_eq!(
            Fault::scaled(Param::ShadowShiftV, 0.1).shadow_shift_texels(),
            [0.0, 0.1]
        );
        assert_eq!(Fault::ShadowHalfTexel.shadow_shift_texels(), [0.5, 0.0]);
        assert!(Fault::parse("offset-units@nan").is_none());
        assert!(Fault::parse("no-such@0.1").is_none());
        // To the nearest millionth, never rounded to no fault.
        assert!(Fault::parse("offset-units@0.0000004").is_none());
        assert!(Fault::parse("offset-units@0").is_none());
        assert!(Fault::parse("offset-units@0.000002").is_some());
    }

    #[test]
    fn every_fault_name_parses_back() {
        for f in Fault::ALL.into_iter().chain(Fault::orientations()) {
            assert_eq!(Fault::parse(&f.name()), Some(f), "{}", f.name());
        }
        assert_eq!(Fault::orientations().len(), 49);
        let f = Fault::parse("face3-mirror-x").expect("a fault");
        assert!(f.face_mistake(3, true).is_some_and(|(_, m)| m));
        assert!(f.face_mistake(2, true).is_none());
        assert!(f.face_mistake(0, false).is_none());
        let m = Fault::parse("map-transpose").expect("a fault");
        assert!(m.face_mistake(0, false).is_some());
        assert!(m.face_mistake(0, true).is_none());
    }
}
