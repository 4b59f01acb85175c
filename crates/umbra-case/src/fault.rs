//! Named faults a backend can be run with, to prove that the harness catches real mistakes
//! (EDGE_CASES.md, "Faults the harness must catch"). A fault is active only when the process
//! has `UMBRA_SELFTEST=1` *and* `UMBRA_FAULT=<name>`: `cargo xtask selftest` sets both in its
//! worker processes, and no other path can turn one on.
//!
//! Two families. The *gross* faults are the classic mistakes of shadow-mapping code, each
//! visible on most of a frame. The *subtle* ones are what a driver gets wrong by less than a
//! texel, less than a depth step, only at exact ties, only in filtered values or only in
//! colour ([`Subtlety`]): a harness that catches only the first family passes most real
//! driver bugs.

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
        }
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
}

impl Fault {
    /// Every fault.
    pub const ALL: [Fault; 26] = [
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
    ];

    /// The fault's name, as `UMBRA_FAULT` takes it.
    pub fn name(self) -> &'static str {
        match self {
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
        }
    }

    /// How small its effect is.
    pub fn subtlety(self) -> Subtlety {
        match self {
            Fault::CompareStrict | Fault::ClampFloat | Fault::NoClamp => Subtlety::ExactTie,
            Fault::QuarterTexel | Fault::ShadowHalfTexel | Fault::NormalOffsetShort => {
                Subtlety::SubTexel
            }
            Fault::OffsetUnitsLow | Fault::SlopeShort => Subtlety::SubStep,
            Fault::PcfOffCentre
            | Fault::PcfDoubleCentre
            | Fault::BilinearCoarse
            | Fault::Vis4Bit => Subtlety::Filtered,
            Fault::ColourGamma | Fault::DimmingOff | Fault::SpecularUnshadowed => Subtlety::Colour,
            _ => Subtlety::Gross,
        }
    }

    /// Parses a name.
    pub fn parse(s: &str) -> Option<Fault> {
        Fault::ALL.into_iter().find(|f| f.name() == s)
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
