//! What an API lets a conformant implementation do differently, as far as umbra's judge needs
//! to know: the [`Profile`] a backend declares, from which the reference computes the legal
//! answers of that backend's frames.
//!
//! Three things differ between the paths umbra drives, and nothing else does:
//! - **LINEAR with compare** ([`Spec`]). OpenGL (3.3 core §3.8.16, ES 3.0 §3.8.16) says the
//!   result "may be computed by comparing more than one depth texture value … the details are
//!   implementation-dependent, but r should be a value in [0, 1] proportional to the number
//!   of comparison passes": any convex combination of the 2x2 taps' results, NEAREST
//!   included. Vulkan (1.3 "Texel Filtering", "Depth Compare Operation") filters the compare
//!   results with the bilinear weights, quantised to `subTexelPrecisionBits` (at least 4).
//! - **Cube seams**. Desktop GL filters each face on its own unless
//!   `TEXTURE_CUBE_MAP_SEAMLESS` is enabled (umbra leaves it off, the GL default); GLES 3.0
//!   (§3.8.9) and Vulkan always filter across faces.
//! - **Packed depth** (umbra's GLES 2 path). The shadow pass writes depth, offset by umbra's
//!   own shader, into RGBA8 and the lit pass unpacks and compares it in the shader: the stored
//!   value has the packing's precision instead of the format's codes, the polygon offset is
//!   the application's formula (no r or m freedom), and the camera's depth buffer is 24-bit.
//!
//! These are spec clauses and apply to every driver, one umbra has never seen included. The
//! [`Deviation`]s are Mesa observations: no profile grants them, only an expectation naming a
//! backend or renderer does. README.md ("Any driver a machine has") tables every freedom the
//! judge grants with its source.

use crate::calibration::Calibration;

/// The specification whose freedoms a backend's sampler has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Spec {
    /// OpenGL and OpenGL ES: LINEAR compare is any weighting of the 2x2 results.
    #[default]
    Gl,
    /// Vulkan: LINEAR compare is bilinear with 4-bit (or finer) weights.
    Vulkan,
}

/// How a backend's frames may legally differ from the reference's (see the module note).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Profile {
    /// The sampler's specification.
    pub spec: Spec,
    /// Cube maps are filtered across faces.
    pub seamless_cube: bool,
    /// The GLES 2 path: depth packed into RGBA8 and compared in the shader.
    pub packed_depth: bool,
    /// Known driver deviations the intervals also allow: never set for a backend's own
    /// profile, only to judge a run again under the expectations that name them
    /// (`Deviation:NAME` in expectations/*.txt), so that the deviations explain exactly what
    /// they explain and anything else still fails.
    pub deviations: Deviations,
    /// The spec's freedom narrowed to what the backend's card read (calibrated judging,
    /// [`crate::calibration`]): never set for a backend's own profile, only for the run's
    /// second judgement.
    pub calibration: Calibration,
}

/// A set of [`Deviation`]s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Deviations(u8);

impl Deviations {
    /// No deviation.
    pub const NONE: Deviations = Deviations(0);

    /// Whether `d` is in the set.
    pub fn has(self, d: Deviation) -> bool {
        self.0 & (1 << d as u8) != 0
    }

    /// The set with `d` added.
    pub fn with(self, d: Deviation) -> Deviations {
        Deviations(self.0 | (1 << d as u8))
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Its deviations, in [`Deviation::ALL`]'s order.
    pub fn iter(self) -> impl Iterator<Item = Deviation> {
        Deviation::ALL.into_iter().filter(move |d| self.has(*d))
    }

    /// The names joined by `+` (what a request carries), empty for none.
    pub fn names(self) -> String {
        self.iter()
            .map(Deviation::name)
            .collect::<Vec<_>>()
            .join("+")
    }

    /// The set named by `names` (`a+b`), or the name that is not a deviation.
    pub fn parse(names: &str) -> Result<Deviations, String> {
        names
            .split('+')
            .filter(|n| !n.is_empty())
            .try_fold(Deviations::NONE, |set, n| {
                Deviation::parse(n)
                    .map(|d| set.with(d))
                    .ok_or_else(|| n.to_string())
            })
    }
}

impl FromIterator<Deviation> for Deviations {
    fn from_iter<I: IntoIterator<Item = Deviation>>(iter: I) -> Deviations {
        iter.into_iter().fold(Deviations::NONE, Deviations::with)
    }
}

/// A driver deviation from the specs that is diagnosed in the driver's source and modelled:
/// an expectation names it (`Deviation:NAME`), and a run it applies to is judged again with
/// the deviation's freedom added. The run is the expected failure only when that judgement
/// passes every check, whatever the case; a known deviation is then recognised on cases
/// nobody wrote an expectation for by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Deviation {
    /// The polygon-offset unit r up to 4/(2ⁿ − 1) on a fixed-point depth format, beyond the
    /// specs' r ≤ 2·2⁻ⁿ (GL 4.6 §14.6.5 leaves r to the implementation but Vulkan's
    /// "Depth Bias" bounds it, and umbra holds GL drivers to the same): zink multiplies GL's
    /// units by 2 for Vulkan's depthBiasConstantFactor (zink_state.c:602-603, with
    /// offset_units_unscaled false) and lavapipe's rasterizer multiplies the factor by 2·mrd
    /// again (lp_state_setup.c:793), so zink on lavapipe offsets by 4/(2ⁿ − 1) per unit.
    OffsetUnitX4,
    /// The polygon offset added per vertex and each vertex's depth clamped to [0, 1] before
    /// interpolation, where GL adds it per fragment and clamps per fragment (GL 4.6 §14.6.5,
    /// §13.6): a triangle with a vertex whose offset depth leaves [0, 1] (one the far plane
    /// clipped, in the first place) loses part of its offset inside, down to none at that
    /// vertex. softpipe does this (draw_pipe_offset.c:119-121, SATURATE(z + offset) per
    /// vertex).
    OffsetVertexClamp,
    /// 16-bit depth written by stepping: the first quad of a batch of up to 16 quads in a row
    /// gets its depths converted (truncated) on their own, every later quad the first quad's
    /// plus dx times a per-pixel step that is itself truncated to a whole code, so the dropped
    /// fraction of |∂z/∂x|·65535 accumulates across the batch: up to 30 pixels × that
    /// fraction, the depth lagging behind its slope. softpipe's Z16 fast path does this
    /// (sp_quad_depth_test_tmp.h: `depth_step = (ushort)(dzdx * scale)`, used from
    /// sp_quad_depth_test.c's choose_depth_test when depth test and write are on and no query
    /// is active; a GL_TIME_ELAPSED query counts, which is why umbra's GL 3.3 path, timing
    /// its passes, never meets it).
    Z16SpanStep,
    /// Holes on edges: a sample point on (within float rounding of) an edge two triangles
    /// share, or a diagonal the clipper's fan adds inside one, may be covered by neither (GL
    /// 4.6 §14.6.1 and Vulkan "Polygon Rasterization" want exactly one). softpipe walks spans
    /// in float, each triangle evaluating the shared edge in its own sequence and truncating
    /// it (sp_setup.c, subtriangle: `left = (int)(sx + y*dxdy)`), and clips every triangle
    /// that crosses the viewport into a fan (no guard band), so a centre exactly on such an
    /// edge can fall out of both. The fan starts at a vertex of the clipper's choosing, so
    /// the model frees every chord of the viewport-clipped polygon
    /// (`umbra_ref::raster::Rasterizer::viewport_chords`; soak-42-364).
    EdgeHoles,
    /// Seamless cube LINEAR reading the wrong texels across a face edge: any answer for a
    /// footprint that crosses an edge. softpipe's img_filter_cube_linear keeps pointers into
    /// its texture tile cache while fetching the next taps, and a later fetch can evict the
    /// tile an earlier pointer reads (sp_tex_sample.c:1778-1798, sp_tex_tile_cache.c:191-196).
    CubeSeamTaps,
}

impl Deviation {
    /// Every deviation, for parsing and messages.
    pub const ALL: [Deviation; 5] = [
        Deviation::OffsetUnitX4,
        Deviation::OffsetVertexClamp,
        Deviation::Z16SpanStep,
        Deviation::EdgeHoles,
        Deviation::CubeSeamTaps,
    ];

    /// The name expectations use.
    pub fn name(self) -> &'static str {
        match self {
            Deviation::OffsetUnitX4 => "offset-unit-x4",
            Deviation::OffsetVertexClamp => "offset-vertex-clamp",
            Deviation::Z16SpanStep => "z16-span-step",
            Deviation::EdgeHoles => "edge-holes",
            Deviation::CubeSeamTaps => "cube-seam-taps",
        }
    }

    /// The deviation named `s`.
    pub fn parse(s: &str) -> Option<Deviation> {
        Deviation::ALL.into_iter().find(|d| d.name() == s)
    }
}

impl Profile {
    /// Desktop OpenGL (3.3 core and later), seamless cube filtering off.
    pub const GL: Profile = Profile {
        spec: Spec::Gl,
        seamless_cube: false,
        packed_depth: false,
        deviations: Deviations::NONE,
        calibration: Calibration::NONE,
    };
    /// OpenGL ES 3.x: seamless cube maps.
    pub const GLES3: Profile = Profile {
        spec: Spec::Gl,
        seamless_cube: true,
        packed_depth: false,
        deviations: Deviations::NONE,
        calibration: Calibration::NONE,
    };
    /// umbra's GLES 2 path: packed depth, manual compare.
    pub const GLES2: Profile = Profile {
        spec: Spec::Gl,
        seamless_cube: false,
        packed_depth: true,
        deviations: Deviations::NONE,
        calibration: Calibration::NONE,
    };
    /// Vulkan.
    pub const VULKAN: Profile = Profile {
        spec: Spec::Vulkan,
        seamless_cube: true,
        packed_depth: false,
        deviations: Deviations::NONE,
        calibration: Calibration::NONE,
    };

    /// Whether a clear of an sRGB colour target may store the clear colour unencoded: GL
    /// 3.3's §4.2.3 (to 4.1) lists no sRGB conversion among what Clear applies, GL 4.2 added
    /// it (§17.4.3 in 4.6), so a GL 3.3 core program may get either; GLES 2's EXT_sRGB does
    /// not say. GLES 3.0 (§4.2.3) and Vulkan ("Clear Values": linear, encoded) always encode.
    /// The GL and GLES 2 profiles, not GLES 3 (the one `Spec::Gl` profile with seamless cube
    /// maps) nor Vulkan.
    pub fn srgb_clear_may_be_unencoded(self) -> bool {
        self.spec == Spec::Gl && !self.seamless_cube
    }

    /// A short stable name, for reports and cache keys (`gl`, `gles3`, `vulkan`, …, with
    /// `+DEVIATION` when a deviation is allowed and ` card(…)` with a calibration).
    pub fn name(self) -> String {
        let api = match (self.spec, self.seamless_cube, self.packed_depth) {
            (_, _, true) => "gles2-packed",
            (Spec::Vulkan, true, false) => "vulkan",
            (Spec::Vulkan, false, false) => "vulkan-2d",
            (Spec::Gl, true, false) => "gles3",
            (Spec::Gl, false, false) => "gl",
        };
        let mut name = api.to_string();
        if !self.deviations.is_empty() {
            name = format!("{name}+{}", self.deviations.names());
        }
        if !self.calibration.is_empty() {
            name = format!("{name} card({})", self.calibration.encode());
        }
        name
    }

    /// This profile narrowed by the calibration `c`.
    pub fn with_calibration(self, c: Calibration) -> Profile {
        Profile {
            calibration: c,
            ..self
        }
    }

    /// This profile with the deviations `d` allowed as well.
    pub fn with_deviations(self, d: Deviations) -> Profile {
        Profile {
            deviations: d,
            ..self
        }
    }
}

impl Profile {
    /// The profile with every freedom that cannot matter for `case` dropped, so that backends
    /// whose profiles differ only there share one judged render: seamless filtering matters
    /// only for a hardware LINEAR lookup in a cube map, and the LINEAR rule only for a
    /// hardware LINEAR lookup; of a calibration, the offset unit and rounding of the map's
    /// format only, the slope form only with a slope factor, the rounding only without a
    /// polygon offset (what the card's probe reads), nothing of the offset or the rounding on
    /// the packed path (umbra's own shader), and the bilinear reading only where GL's LINEAR
    /// rule would apply (in a cube map, only with the seams the profile judges by).
    pub fn effective_for(self, case: &crate::format::Case) -> Profile {
        use crate::format::{Compare, Light};
        let hardware_linear = case.shadow.filter.sampler_linear()
            && case.shadow.compare == Compare::Hardware
            && !self.packed_depth;
        // A light's run has one light; a case of several is judged light by light, and
        // named here by whether any of its maps is a cube.
        let cube = case.lights.iter().any(|l| matches!(l, Light::Point(_)));
        let spec = if hardware_linear { self.spec } else { Spec::Gl };
        let c = self.calibration;
        let own =
            crate::calibration::fixed_index(case.shadow.format).filter(|_| !self.packed_depth);
        let keep = |i: usize| own == Some(i);
        let [factor, units] = case.shadow.bias.polygon_offset;
        // The bilinear reading in a cube map only where the card saw the seams the profile
        // judges by.
        let bilinear = c.bilinear
            && hardware_linear
            && spec == Spec::Gl
            && (!cube || c.cube_seams == Some(self.seamless_cube));
        let calibration = Calibration {
            offset_unit: [0, 1].map(|i| c.offset_unit[i].filter(|_| keep(i) && units != 0.0)),
            slope: c.slope.filter(|_| factor != 0.0 && !self.packed_depth),
            // The card reads the rounding of a depth without an offset; lavapipe rounds an
            // offset depth otherwise (found on offset-clamp-magnified, D16).
            rounding: [0, 1]
                .map(|i| c.rounding[i].filter(|_| keep(i) && factor == 0.0 && units == 0.0)),
            bilinear,
            cube_seams: c.cube_seams.filter(|_| bilinear && cube),
            subpixel_bits: c.subpixel_bits,
        };
        Profile {
            spec,
            seamless_cube: hardware_linear && cube && self.seamless_cube,
            packed_depth: self.packed_depth,
            deviations: self.deviations,
            calibration,
        }
    }
}
