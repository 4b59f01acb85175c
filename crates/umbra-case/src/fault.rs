//! Named faults a backend can be run with, to prove that the harness catches real mistakes
//! (EDGE_CASES.md, "Faults the harness must catch"). A fault is active only when the process
//! has `UMBRA_SELFTEST=1` *and* `UMBRA_FAULT=<name>`: `cargo xtask selftest` sets both in its
//! worker processes, and no other path can turn one on.

/// A deliberate mistake of the kind real shadow-mapping code makes.
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
}

impl Fault {
    /// Every fault.
    pub const ALL: [Fault; 11] = [
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
