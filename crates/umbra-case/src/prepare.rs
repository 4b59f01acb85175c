//! A run ready to render: the case point, its tessellation and its camera and light set-ups.
//! Built once per run and shared by every backend, so that all draw the same triangles.

use std::sync::Arc;

use glam::Vec3;

pub use crate::camera::CameraSetup;
use crate::conventions::look_at;
use crate::light::LightSetup;
use crate::point::CasePoint;
use crate::scene::{Geometry, tessellate};

/// One run's inputs.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The case point, resolved: its `scene.offset` already applied to every position (and
    /// reset to zero). Build variants from the point as written, not from this.
    pub point: CasePoint,
    /// Its triangles.
    pub geometry: Arc<Geometry>,
    /// Its camera.
    pub camera: CameraSetup,
    /// Its light.
    pub light: LightSetup,
}

impl Prepared {
    /// Tessellates and sets up a validated case point. A `scene.offset` is applied here
    /// (`crate::offset`), so every consumer sees the moved, f32-rounded case.
    pub fn new(mut point: CasePoint) -> Self {
        point.case = crate::offset::apply_offset(&point.case);
        let geometry = Arc::new(tessellate(&point.case.scene));
        Self::with_geometry(point, geometry)
    }

    /// Sets up a point whose (offset-free) scene was already tessellated.
    fn with_geometry(point: CasePoint, geometry: Arc<Geometry>) -> Self {
        let c = &point.case.camera;
        let camera = CameraSetup {
            eye: Vec3::from(c.eye),
            view: look_at(Vec3::from(c.eye), Vec3::from(c.target), Vec3::from(c.up)),
            fov_y: c.fov_y_deg.to_radians(),
            near: c.near,
            far: c.far,
            size: c.size,
        };
        let light = LightSetup::new(
            &point.case.light,
            point.case.shadow.size,
            &geometry,
            &camera,
        );
        Prepared {
            point,
            geometry,
            camera,
            light,
        }
    }

    /// The case.
    pub fn case(&self) -> &crate::format::Case {
        &self.point.case
    }
}
