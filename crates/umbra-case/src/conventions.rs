//! Depth and coordinate conventions: the one place where projections, the bias matrix, window
//! mapping and depth compares are defined. No backend builds a projection inline.
//!
//! Two clip conventions exist (docs/platform.md, "Clip space"):
//! - [`ClipDepth::MinusOneToOne`] (OpenGL): −w ≤ z ≤ w, window z = 0.5·z_ndc + 0.5, window y
//!   up (row 0 of a framebuffer or texture is the *bottom*), texture v up.
//! - [`ClipDepth::ZeroToOne`] (Vulkan, wgpu): 0 ≤ z ≤ w, window z = z_ndc, framebuffer y down
//!   (row 0 is the *top*), texture v down.
//!
//! The *bias matrix* maps clip space to texture space ([0,1]² and window depth): GL scales and
//! offsets x, y, z by 0.5; the zero-to-one convention does x the same way, flips y
//! (v = 0.5 − 0.5·y) and leaves z alone. Either may be applied before the perspective divide
//! (`textureProj` of B·P·V·x, the classic texture matrix) or after it; in real arithmetic they
//! agree, in f32 they differ by an ulp or two (docs/catalogue.md §1).
//!
//! Reversed depth multiplies the projection by a z flip (GL: z → −z, zero-to-one: z → w − z),
//! so window depth becomes 1 − depth; clears, compares and bias signs follow from
//! [`Convention::toward_far`]. Matrices are column-major glam `Mat4`, right-handed views
//! looking down −z, written out from the spec formulas rather than taken from a library.

use glam::{Mat4, Vec3, Vec4};

use crate::format::{BiasMatrix, DepthOrder};

/// Clip-space depth range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClipDepth {
    /// OpenGL: −w ≤ z ≤ w, window y up.
    MinusOneToOne,
    /// Vulkan / wgpu / D3D: 0 ≤ z ≤ w, window y down.
    ZeroToOne,
}

/// A clip convention and a depth order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Convention {
    /// Clip-space depth range (and with it the window y direction).
    pub clip: ClipDepth,
    /// Forward or reversed depth.
    pub order: DepthOrder,
}

impl Convention {
    /// OpenGL with forward depth.
    pub const GL: Convention = Convention {
        clip: ClipDepth::MinusOneToOne,
        order: DepthOrder::Forward,
    };
    /// Vulkan / wgpu with forward depth.
    pub const ZERO_TO_ONE: Convention = Convention {
        clip: ClipDepth::ZeroToOne,
        order: DepthOrder::Forward,
    };

    /// The same clip range with `order`.
    pub fn with_order(self, order: DepthOrder) -> Convention {
        Convention { order, ..self }
    }

    /// Whether window (and texture) row 0 is the top of the image.
    pub fn window_y_down(self) -> bool {
        self.clip == ClipDepth::ZeroToOne
    }

    /// +1 for forward depth, −1 for reversed: the sign of "away from the light" in window depth.
    pub fn toward_far(self) -> f32 {
        match self.order {
            DepthOrder::Forward => 1.0,
            DepthOrder::Reversed => -1.0,
        }
    }

    /// The depth a cleared map holds (the far plane).
    pub fn clear_depth(self) -> f32 {
        match self.order {
            DepthOrder::Forward => 1.0,
            DepthOrder::Reversed => 0.0,
        }
    }

    /// Rasterizer depth test (LESS forward, GREATER reversed): whether `incoming` replaces
    /// `stored`.
    pub fn depth_test(self, incoming: f32, stored: f32) -> bool {
        match self.order {
            DepthOrder::Forward => incoming < stored,
            DepthOrder::Reversed => incoming > stored,
        }
    }

    /// Shadow compare (LEQUAL forward, GEQUAL reversed): whether a receiver at `reference` is
    /// lit by a texel holding `texel`.
    pub fn compare_lit(self, reference: f32, texel: f32) -> bool {
        match self.order {
            DepthOrder::Forward => reference <= texel,
            DepthOrder::Reversed => reference >= texel,
        }
    }

    /// The z flip that reversed depth puts in front of a projection.
    fn order_matrix(self) -> Mat4 {
        match (self.order, self.clip) {
            (DepthOrder::Forward, _) => Mat4::IDENTITY,
            (DepthOrder::Reversed, ClipDepth::MinusOneToOne) => {
                Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0))
            }
            // z' = w − z
            (DepthOrder::Reversed, ClipDepth::ZeroToOne) => Mat4::from_cols(
                Vec4::X,
                Vec4::Y,
                Vec4::new(0.0, 0.0, -1.0, 0.0),
                Vec4::new(0.0, 0.0, 1.0, 1.0),
            ),
        }
    }

    /// Perspective projection (`gluPerspective` for GL; its [0,1] form otherwise).
    pub fn perspective(self, fov_y_rad: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
        let f = 1.0 / crate::math::tanf(0.5 * fov_y_rad);
        let (z, zw) = match self.clip {
            ClipDepth::MinusOneToOne => {
                ((far + near) / (near - far), 2.0 * far * near / (near - far))
            }
            ClipDepth::ZeroToOne => (far / (near - far), far * near / (near - far)),
        };
        let p = Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, z, -1.0),
            Vec4::new(0.0, 0.0, zw, 0.0),
        );
        self.order_matrix() * p
    }

    /// Orthographic projection (`glOrtho` for GL; its [0,1] form otherwise).
    #[allow(clippy::too_many_arguments)]
    pub fn orthographic(
        self,
        left: f32,
        right: f32,
        bottom: f32,
        top: f32,
        near: f32,
        far: f32,
    ) -> Mat4 {
        let (z, zw) = match self.clip {
            ClipDepth::MinusOneToOne => (-2.0 / (far - near), -(far + near) / (far - near)),
            ClipDepth::ZeroToOne => (-1.0 / (far - near), -near / (far - near)),
        };
        let p = Mat4::from_cols(
            Vec4::new(2.0 / (right - left), 0.0, 0.0, 0.0),
            Vec4::new(0.0, 2.0 / (top - bottom), 0.0, 0.0),
            Vec4::new(0.0, 0.0, z, 0.0),
            Vec4::new(
                -(right + left) / (right - left),
                -(top + bottom) / (top - bottom),
                zw,
                1.0,
            ),
        );
        self.order_matrix() * p
    }

    /// Clip space → texture space: (u, v) in [0,1]² with v along texture rows, z = window
    /// depth.
    pub fn bias_matrix(self) -> Mat4 {
        match self.clip {
            ClipDepth::MinusOneToOne => Mat4::from_cols(
                Vec4::new(0.5, 0.0, 0.0, 0.0),
                Vec4::new(0.0, 0.5, 0.0, 0.0),
                Vec4::new(0.0, 0.0, 0.5, 0.0),
                Vec4::new(0.5, 0.5, 0.5, 1.0),
            ),
            ClipDepth::ZeroToOne => Mat4::from_cols(
                Vec4::new(0.5, 0.0, 0.0, 0.0),
                Vec4::new(0.0, -0.5, 0.0, 0.0),
                Vec4::new(0.0, 0.0, 1.0, 0.0),
                Vec4::new(0.5, 0.5, 0.0, 1.0),
            ),
        }
    }

    /// NDC z → window depth (depth range [0, 1]).
    pub fn window_depth(self, ndc_z: f32) -> f32 {
        match self.clip {
            ClipDepth::MinusOneToOne => 0.5 * ndc_z + 0.5,
            ClipDepth::ZeroToOne => ndc_z,
        }
    }

    /// NDC (x, y) → window position in pixels for a `w` × `h` viewport at the origin, in the
    /// convention's own row order.
    pub fn window_xy(self, ndc_x: f32, ndc_y: f32, w: u32, h: u32) -> (f32, f32) {
        let x = (ndc_x + 1.0) * 0.5 * w as f32;
        let y = match self.clip {
            ClipDepth::MinusOneToOne => (ndc_y + 1.0) * 0.5 * h as f32,
            ClipDepth::ZeroToOne => (1.0 - ndc_y) * 0.5 * h as f32,
        };
        (x, y)
    }

    /// What to put in front of a cube face's projection when *rendering* the face so that
    /// its texel rows match cube-map sampling (the GL/Vulkan face table, t = 0 in row 0).
    /// GL's window rows run up with NDC y, which already matches: identity. Zero-to-one
    /// windows run down, so the face is rendered with y flipped (which also reverses the
    /// winding: the pass's front face becomes clockwise). Lookups keep the unflipped face
    /// matrix and read row t = 1 − v of the face.
    pub fn cube_face_render_flip(self) -> Mat4 {
        match self.clip {
            ClipDepth::MinusOneToOne => Mat4::IDENTITY,
            ClipDepth::ZeroToOne => Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)),
        }
    }

    /// Smallest clip z inside the volume, as a multiple of w (−1 or 0).
    pub fn clip_z_min_over_w(self) -> f32 {
        match self.clip {
            ClipDepth::MinusOneToOne => -1.0,
            ClipDepth::ZeroToOne => 0.0,
        }
    }
}

/// A light-space lookup coordinate: texture (u, v), window depth, and the clip w it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowCoord {
    /// Texture u in [0,1] inside the map.
    pub u: f32,
    /// Texture v in [0,1] inside the map (along texture rows).
    pub v: f32,
    /// Window depth of the receiver, the compare's reference value.
    pub depth: f32,
    /// Clip w (≤ 0 behind a perspective light).
    pub w: f32,
}

/// The matrices a lookup uses: `light` = P·V (clip), `texture` = B·P·V, both f32 as a program
/// would upload them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookupMatrices {
    /// Light clip from world.
    pub light: Mat4,
    /// Texture space from world, bias matrix included (computed once, in f32).
    pub texture: Mat4,
}

impl LookupMatrices {
    /// For a light with view-projection `light` under `conv`.
    pub fn new(conv: Convention, light: Mat4) -> Self {
        LookupMatrices {
            light,
            texture: conv.bias_matrix() * light,
        }
    }

    /// The lookup coordinate of world point `p`, in f32, in the order `order` says.
    #[inline]
    pub fn coord(&self, conv: Convention, order: BiasMatrix, p: Vec3) -> ShadowCoord {
        let p4 = p.extend(1.0);
        match order {
            BiasMatrix::BeforeDivide => {
                let t = self.texture * p4;
                ShadowCoord {
                    u: t.x / t.w,
                    v: t.y / t.w,
                    depth: t.z / t.w,
                    w: t.w,
                }
            }
            BiasMatrix::AfterDivide => {
                let c = self.light * p4;
                let ndc = Vec3::new(c.x / c.w, c.y / c.w, c.z / c.w);
                let t = conv.bias_matrix() * ndc.extend(1.0);
                ShadowCoord {
                    u: t.x,
                    v: t.y,
                    depth: t.z,
                    w: c.w,
                }
            }
        }
    }
}

/// A right-handed view matrix looking from `eye` at `target` (`gluLookAt`).
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let f = (target - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reversed_depth_is_one_minus_forward() {
        for clip in [ClipDepth::MinusOneToOne, ClipDepth::ZeroToOne] {
            let fwd = Convention {
                clip,
                order: DepthOrder::Forward,
            };
            let rev = fwd.with_order(DepthOrder::Reversed);
            for z_eye in [-0.5f32, -1.0, -7.0, -99.0] {
                let p = Vec4::new(0.0, 0.0, z_eye, 1.0);
                let d = |c: Convention| {
                    let q = c.perspective(1.0, 1.0, 0.5, 100.0) * p;
                    c.window_depth(q.z / q.w)
                };
                assert!((d(fwd) + d(rev) - 1.0).abs() < 1e-6, "{clip:?} z={z_eye}");
            }
        }
    }

    #[test]
    fn near_and_far_map_to_the_ends_of_the_depth_range() {
        for conv in [Convention::GL, Convention::ZERO_TO_ONE] {
            let p = conv.perspective(1.0, 1.5, 2.0, 50.0);
            let o = conv.orthographic(-1.0, 1.0, -1.0, 1.0, 2.0, 50.0);
            for m in [p, o] {
                let depth = |z: f32| {
                    let q = m * Vec4::new(0.3, -0.2, -z, 1.0);
                    conv.window_depth(q.z / q.w)
                };
                assert!(
                    depth(2.0).abs() < 1e-6 && (depth(50.0) - 1.0).abs() < 1e-6,
                    "{conv:?}"
                );
            }
        }
    }

    #[test]
    fn look_at_puts_the_target_on_the_negative_z_axis() {
        let v = look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, -2.0, 3.0), Vec3::Y);
        let t = v.transform_point3(Vec3::new(4.0, -2.0, 3.0));
        assert!(
            t.x.abs() < 1e-6 && t.y.abs() < 1e-6 && (t.z + 5.0).abs() < 1e-5,
            "{t}"
        );
    }
}
