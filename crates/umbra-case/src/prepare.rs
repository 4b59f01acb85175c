//! A run ready to render: the case point, its tessellation and its camera and light set-ups.
//! Built once per run and shared by every backend, so that all draw the same triangles.

use std::sync::Arc;

pub use crate::camera::CameraSetup;
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
    /// A light's run of a case with several lights ([`Prepared::for_light`]): which light
    /// of how many, and whether their maps are one 2D array's layers (the light's in layer
    /// `light`). `None` for a case's own run.
    pub of_lights: Option<OfLights>,
}

/// Which light of several a run is ([`Prepared::of_lights`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OfLights {
    /// The light's index in `lights`.
    pub light: usize,
    /// How many lights the case has.
    pub lights: usize,
    /// The maps are one array's layers (`shadow.placement` `array`, or `cube_array`
    /// whose layers are cubes).
    pub array: bool,
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
        let camera = CameraSetup::new(&point.case.camera);
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
            of_lights: None,
        }
    }

    /// The case.
    pub fn case(&self) -> &crate::format::Case {
        &self.point.case
    }

    /// How many lights the case has (`lights`, or the one `light`).
    pub fn light_count(&self) -> usize {
        self.case().all_lights().len()
    }

    /// Light `k`'s run: the case as that light alone lights it ([`crate::format::Case::for_light`]:
    /// no ambient term but the first light's), the same triangles. Every backend and the
    /// reference render a case with several lights as these runs, one lit pass each, the
    /// passes' colours added; each run's visibility is judged as a one-light case's is.
    pub fn for_light(&self, k: usize) -> Prepared {
        let point = CasePoint {
            case: self.point.case.for_light(k),
            ..self.point.clone()
        };
        let lights = self.light_count();
        let array = self.case().shadow.placement != crate::format::Placement::Separate;
        Prepared {
            of_lights: (lights > 1).then_some(OfLights {
                light: k,
                lights,
                array,
            }),
            ..Self::with_geometry(point, Arc::clone(&self.geometry))
        }
    }
}
