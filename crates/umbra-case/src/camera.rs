//! The camera of a case, set up once: its view, projection and image (the camera pass's,
//! and what a cascaded light splits along its view depth).

use glam::{Mat4, Vec3};

use crate::conventions::{Convention, look_at};

/// The camera of a case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSetup {
    /// Eye position.
    pub eye: Vec3,
    /// World → view.
    pub view: Mat4,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Near plane.
    pub near: f32,
    /// Far plane.
    pub far: f32,
    /// Image `[width, height]`.
    pub size: [u32; 2],
}

impl CameraSetup {
    /// The set-up of a validated case's camera.
    pub fn new(c: &crate::format::Camera) -> Self {
        CameraSetup {
            eye: Vec3::from(c.eye),
            view: look_at(Vec3::from(c.eye), Vec3::from(c.target), Vec3::from(c.up)),
            fov_y: c.fov_y_deg.to_radians(),
            near: c.near,
            far: c.far,
            size: c.size,
        }
    }

    /// P · V under `conv` (the camera pass always uses forward depth).
    pub fn view_proj(&self, conv: Convention) -> Mat4 {
        let conv = conv.with_order(crate::format::DepthOrder::Forward);
        conv.perspective(
            self.fov_y,
            self.size[0] as f32 / self.size[1] as f32,
            self.near,
            self.far,
        ) * self.view
    }
}
