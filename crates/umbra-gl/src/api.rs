//! The three GL flavours and what each can do, decided here once.

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

    /// Whether this is an ES API.
    pub fn is_es(self) -> bool {
        self != Api::Gl33
    }
}
