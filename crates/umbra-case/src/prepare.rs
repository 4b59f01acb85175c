//! A run ready to render: the case point, its tessellation and its camera and light set-ups.
//! Built once per run and shared by every backend, so that all draw the same triangles.

use std::sync::Arc;

pub use crate::camera::CameraSetup;
use crate::light::LightSetup;
use crate::point::CasePoint;
use crate::scene::{Geometry, tessellate};

/// One run's inputs: the case point, its triangles and camera, and every light's own run.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The case point, resolved: its `scene.offset` already applied to every position (and
    /// reset to zero). Build variants from the point as written, not from this.
    pub point: CasePoint,
    /// Its triangles.
    pub geometry: Arc<Geometry>,
    /// Its camera.
    pub camera: CameraSetup,
    /// Every light's run, in the case's order: never empty (one light is a list of one).
    /// Every backend and the reference render a case as these runs, one shadow pass and one
    /// lit pass each, the lit passes' colours added; each run's visibility is judged alone.
    pub lights: Vec<LightRun>,
}

/// One light's run of a case: the case as that light alone lights it
/// ([`crate::format::Case::for_light`]: no ambient term but the first light's), the case's
/// triangles and camera, and the light's set-up.
#[derive(Clone, Debug)]
pub struct LightRun {
    /// The case point with only this light.
    pub point: CasePoint,
    /// The case's triangles (shared by every light's run).
    pub geometry: Arc<Geometry>,
    /// The case's camera.
    pub camera: CameraSetup,
    /// This light's set-up: its views, matrices and cascades.
    pub light: LightSetup,
    /// Which light of how many, and whether their maps are one array's layers.
    pub of_lights: OfLights,
}

/// Which light of a case a run is ([`LightRun::of_lights`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OfLights {
    /// The light's index in the case's `lights`.
    pub light: usize,
    /// How many lights the case has.
    pub lights: usize,
    /// The maps are one array's layers ([`crate::format::Case::maps_share_array`]; the
    /// light's is layer `light`, or its cube in a cube-map array).
    pub array: bool,
}

impl Prepared {
    /// Tessellates and sets up a validated case point. A `scene.offset` is applied here
    /// (`crate::offset`), so every consumer sees the moved, f32-rounded case.
    pub fn new(mut point: CasePoint) -> Self {
        point.case = crate::offset::apply_offset(&point.case);
        let geometry = Arc::new(tessellate(&point.case.scene));
        let camera = CameraSetup::new(&point.case.camera);
        let case = &point.case;
        let array = case.maps_share_array();
        let lights = (0..case.lights.len())
            .map(|k| {
                let point = CasePoint {
                    case: case.for_light(k),
                    ..point.clone()
                };
                LightRun {
                    light: LightSetup::new(&case.lights[k], case.shadow.size, &geometry, &camera),
                    point,
                    geometry: Arc::clone(&geometry),
                    camera,
                    of_lights: OfLights {
                        light: k,
                        lights: case.lights.len(),
                        array,
                    },
                }
            })
            .collect();
        Prepared {
            point,
            geometry,
            camera,
            lights,
        }
    }

    /// The case.
    pub fn case(&self) -> &crate::format::Case {
        &self.point.case
    }
}

impl LightRun {
    /// The case as this light alone lights it.
    pub fn case(&self) -> &crate::format::Case {
        &self.point.case
    }

    /// This light as the case writes it (its colour, intensity and placement).
    pub fn as_written(&self) -> &crate::format::Light {
        // The run's case holds this light alone (`Case::for_light`).
        &self.point.case.lights[0]
    }
}
