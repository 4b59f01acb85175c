//! The three GL flavours and what each can do, decided here once.

use umbra_case::Technique;

/// A GL API and version.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Api {
    /// OpenGL 3.3 core profile.
    Gl33,
    /// OpenGL ES 3.0.
    Gles3,
    /// OpenGL ES 2.0.
    Gles2,
}

impl Api {
    /// Every flavour, in report order.
    pub const ALL: [Api; 3] = [Api::Gl33, Api::Gles3, Api::Gles2];

    /// What umbra-gl can do on this API: it makes every GL call itself (texture units, a
    /// shader compare on every API), in GL's [-1, 1] clip depth; GLES 2 forces its own
    /// technique.
    pub fn capabilities(self) -> umbra_case::Capabilities {
        umbra_case::Capabilities {
            driver: true,
            umbra_makes_gl_calls: true,
            gl_texture_units: true,
            zero_to_one_depth: false,
            integer_depth_bias: false,
            manual_compare: true,
            gles2_technique: self == Api::Gles2,
        }
    }

    /// The id prefix: `gl33`, `gles3`, `gles2`.
    pub fn name(self) -> &'static str {
        match self {
            Api::Gl33 => "gl33",
            Api::Gles3 => "gles3",
            Api::Gles2 => "gles2",
        }
    }

    /// Parses an id prefix.
    pub fn parse(s: &str) -> Option<Api> {
        Api::ALL.into_iter().find(|a| a.name() == s)
    }

    /// The context version requested.
    pub fn version(self) -> (i32, i32) {
        match self {
            Api::Gl33 => (3, 3),
            Api::Gles3 => (3, 0),
            Api::Gles2 => (2, 0),
        }
    }

    /// A case's technique as this API runs it: GLES 2 has no shadow samplers, so it always
    /// compares in the shader (a hardware case keeps its semantics there).
    pub fn technique(self, t: Technique) -> Technique {
        if self == Api::Gles2 {
            t.with_manual_compare()
        } else {
            t
        }
    }

    /// Whether this is an ES API.
    pub fn is_es(self) -> bool {
        self != Api::Gl33
    }
}
