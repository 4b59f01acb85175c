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
}

impl Profile {
    /// Desktop OpenGL (3.3 core and later), seamless cube filtering off.
    pub const GL: Profile = Profile {
        spec: Spec::Gl,
        seamless_cube: false,
        packed_depth: false,
    };
    /// OpenGL ES 3.x: seamless cube maps.
    pub const GLES3: Profile = Profile {
        spec: Spec::Gl,
        seamless_cube: true,
        packed_depth: false,
    };
    /// umbra's GLES 2 path: packed depth, manual compare.
    pub const GLES2: Profile = Profile {
        spec: Spec::Gl,
        seamless_cube: false,
        packed_depth: true,
    };
    /// Vulkan.
    pub const VULKAN: Profile = Profile {
        spec: Spec::Vulkan,
        seamless_cube: true,
        packed_depth: false,
    };

    /// A short stable name, for reports and cache keys.
    pub fn name(self) -> &'static str {
        match (self.spec, self.seamless_cube, self.packed_depth) {
            (_, _, true) => "gles2-packed",
            (Spec::Vulkan, true, false) => "vulkan",
            (Spec::Vulkan, false, false) => "vulkan-2d",
            (Spec::Gl, true, false) => "gles3",
            (Spec::Gl, false, false) => "gl",
        }
    }
}

impl Profile {
    /// The profile with every freedom that cannot matter for `case` dropped, so that backends
    /// whose profiles differ only there share one judged render: seamless filtering matters
    /// only for a hardware LINEAR lookup in a cube map, and the LINEAR rule only for a
    /// hardware LINEAR lookup.
    pub fn effective_for(self, case: &crate::format::Case) -> Profile {
        use crate::format::{Compare, Filter, Light};
        let hardware_linear = case.shadow.filter == Filter::Linear
            && case.shadow.compare == Compare::Hardware
            && !self.packed_depth;
        let cube = matches!(case.light, Light::Point(_));
        Profile {
            spec: if hardware_linear { self.spec } else { Spec::Gl },
            seamless_cube: hardware_linear && cube && self.seamless_cube,
            packed_depth: self.packed_depth,
        }
    }
}
