//! Light views: the view and projection of each shadow-map face, convention-free until a
//! backend asks for a [`Convention`]. A directional or spot light has one face; a point light
//! has six (+x, −x, +y, −y, +z, −z), each a 90° perspective with the up vectors of the GL cube
//! map table, selected by the major axis of (point − light) with ties going to x, then y.
//!
//! A fitted directional frustum (`"fit": "scene"`) encloses every vertex of the scene in the
//! light's view space, widened by 0.5 % of its extent on each side in x and y and by 1 % of the
//! depth range (plus 1e-3 m) at near and far, so that no geometry sits exactly on a clip plane
//! or on the map's outermost texel border.

use glam::{Mat4, Vec3};

use crate::conventions::{Convention, look_at};
use crate::format::{Fit, Light};
use crate::scene::Geometry;

/// The unit direction *towards* a light at `azimuth_deg` (from +z towards +x) and
/// `elevation_deg` (above the x-z plane).
pub fn direction_from_angles(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (a, e) = (
        f64::from(azimuth_deg).to_radians(),
        f64::from(elevation_deg).to_radians(),
    );
    use crate::math::{cos, sin};
    glam::DVec3::new(cos(e) * sin(a), sin(e), cos(e) * cos(a)).as_vec3()
}

/// A projection before a convention is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with a vertical field of view in radians.
    Perspective {
        /// Vertical field of view, radians.
        fov_y: f32,
        /// Width / height.
        aspect: f32,
        /// Near plane.
        near: f32,
        /// Far plane.
        far: f32,
    },
    /// Orthographic bounds in view space.
    Ortho {
        /// `[left, right, bottom, top, near, far]`.
        bounds: [f32; 6],
    },
}

impl Projection {
    /// The projection matrix under `conv`.
    pub fn matrix(&self, conv: Convention) -> Mat4 {
        match *self {
            Projection::Perspective {
                fov_y,
                aspect,
                near,
                far,
            } => conv.perspective(fov_y, aspect, near, far),
            Projection::Ortho {
                bounds: [l, r, b, t, n, f],
            } => conv.orthographic(l, r, b, t, n, f),
        }
    }

    /// Near and far distances.
    pub fn near_far(&self) -> (f32, f32) {
        match *self {
            Projection::Perspective { near, far, .. } => (near, far),
            Projection::Ortho { bounds } => (bounds[4], bounds[5]),
        }
    }
}

/// One face of a shadow map: a view and a projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    /// World → light view.
    pub view: Mat4,
    /// Light view → clip.
    pub projection: Projection,
}

impl LightView {
    /// P · V under `conv`, in f32.
    pub fn view_proj(&self, conv: Convention) -> Mat4 {
        self.projection.matrix(conv) * self.view
    }
}

/// Where the light is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Parallel rays; `towards` is the unit direction from the scene to the light.
    Directional {
        /// Unit vector towards the light.
        towards: Vec3,
        /// The light's eye (its `position`, or the target moved `distance` towards it): only
        /// an N·L bias that asks for the vector to the light's position reads it.
        position: Vec3,
    },
    /// A positional light with one perspective face.
    Spot {
        /// Position.
        position: Vec3,
    },
    /// A positional light with six faces.
    Point {
        /// Position.
        position: Vec3,
    },
}

/// Everything a backend needs about the light.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSetup {
    /// Where the light is.
    pub kind: LightKind,
    /// One face, or six for a point light.
    pub views: Vec<LightView>,
}

/// Cube faces: (direction, up) for +x, −x, +y, −y, +z, −z (the GL cube-map table).
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

impl LightSetup {
    /// The light of a validated case, with a `map_size` map, fitted to `geometry` if asked.
    pub fn new(light: &Light, map_size: [u32; 2], geometry: &Geometry) -> Self {
        let aspect = map_size[0] as f32 / map_size[1] as f32;
        match light {
            Light::Directional(d) => {
                let target = Vec3::from(d.target);
                let (eye, towards) = match d.position {
                    Some(p) => (Vec3::from(p), (Vec3::from(p) - target).normalize()),
                    None => {
                        let towards = direction_from_angles(
                            d.azimuth_deg.unwrap_or(0.0),
                            d.elevation_deg.unwrap_or(90.0),
                        );
                        (target + towards * d.distance, towards)
                    }
                };
                let view = look_at(eye, target, Vec3::from(d.up));
                let bounds = match (&d.ortho, d.fit) {
                    (Some(o), _) => [o.left, o.right, o.bottom, o.top, o.near, o.far],
                    (None, Some(Fit::Scene) | None) => fit_bounds(view, geometry),
                };
                LightSetup {
                    kind: LightKind::Directional {
                        towards,
                        position: eye,
                    },
                    views: vec![LightView {
                        view,
                        projection: Projection::Ortho { bounds },
                    }],
                }
            }
            Light::Spot(s) => {
                let position = Vec3::from(s.position);
                let view = look_at(position, Vec3::from(s.target), Vec3::from(s.up));
                let projection = Projection::Perspective {
                    fov_y: s.fov_y_deg.to_radians(),
                    aspect,
                    near: s.near,
                    far: s.far,
                };
                LightSetup {
                    kind: LightKind::Spot { position },
                    views: vec![LightView { view, projection }],
                }
            }
            Light::Point(p) => {
                let position = Vec3::from(p.position);
                let projection = Projection::Perspective {
                    fov_y: std::f32::consts::FRAC_PI_2,
                    aspect: 1.0,
                    near: p.near,
                    far: p.far,
                };
                let views = CUBE_FACES
                    .iter()
                    .map(|(dir, up)| LightView {
                        view: look_at(position, position + *dir, *up),
                        projection,
                    })
                    .collect();
                LightSetup {
                    kind: LightKind::Point { position },
                    views,
                }
            }
        }
    }

    /// The face a world point is looked up in (0 unless this is a point light).
    pub fn face_for(&self, p: Vec3) -> usize {
        match self.kind {
            LightKind::Point { position } => cube_face((p - position).as_dvec3()),
            _ => 0,
        }
    }

    /// Unit vector from `p` towards the light.
    pub fn to_light(&self, p: Vec3) -> Vec3 {
        match self.kind {
            LightKind::Directional { towards, .. } => towards,
            LightKind::Spot { position } | LightKind::Point { position } => {
                (position - p).normalize()
            }
        }
    }

    /// The light's position: a directional light's eye, a spot or point light's position.
    pub fn position(&self) -> Vec3 {
        match self.kind {
            LightKind::Directional { position, .. }
            | LightKind::Spot { position }
            | LightKind::Point { position } => position,
        }
    }

    /// The light vector of an N·L bias at `p`: [`LightSetup::to_light`], or with
    /// [`LightVector::Position`] the unit vector towards [`LightSetup::position`].
    pub fn bias_light_vector(&self, p: Vec3, which: crate::format::LightVector) -> Vec3 {
        match which {
            crate::format::LightVector::Direction => self.to_light(p),
            crate::format::LightVector::Position => (self.position() - p).normalize(),
        }
    }
}

/// The cube face (+x, −x, +y, −y, +z, −z = 0..5) of direction `d`: its major axis, ties going
/// to x, then y.
pub fn cube_face(d: glam::DVec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        usize::from(d.x < 0.0)
    } else if a.y >= a.z {
        2 + usize::from(d.y < 0.0)
    } else {
        4 + usize::from(d.z < 0.0)
    }
}

/// The direction of the centre of texel (i, j) of cube face `f` (`size` texels a side), the GL
/// cube-map face table inverted: s_c = 2(i + ½)/size − 1, t_c likewise, and for +x the
/// direction (1, −t_c, −s_c), −x (−1, −t_c, s_c), +y (s_c, 1, t_c), −y (s_c, −1, −t_c),
/// +z (s_c, −t_c, 1), −z (−s_c, −t_c, −1). Indices outside the face give the direction of a
/// virtual texel beyond its edge (which lands on the neighbouring face): the shaders reach
/// cube texels this way, so the reference does too.
pub fn cube_texel_dir(f: usize, i: f64, j: f64, size: f64) -> glam::DVec3 {
    let sc = 2.0 * (i + 0.5) / size - 1.0;
    let tc = 2.0 * (j + 0.5) / size - 1.0;
    match f {
        0 => glam::DVec3::new(1.0, -tc, -sc),
        1 => glam::DVec3::new(-1.0, -tc, sc),
        2 => glam::DVec3::new(sc, 1.0, tc),
        3 => glam::DVec3::new(sc, -1.0, -tc),
        4 => glam::DVec3::new(sc, -tc, 1.0),
        _ => glam::DVec3::new(-sc, -tc, -1.0),
    }
}

/// The cube face and the (s_c, t_c) ∈ [−1, 1]² face coordinates of direction `d`, by the
/// same table as [`cube_texel_dir`] (major axis from [`cube_face`]).
pub fn cube_face_coords(d: glam::DVec3) -> (usize, f64, f64) {
    let f = cube_face(d);
    let (sc, tc) = cube_coords_on(d, f);
    (f, sc, tc)
}

/// The (s_c, t_c) face coordinates of direction `d` on face `f` (the table of
/// [`cube_face_coords`], whichever axis is major: for a face chosen where the major axis is a
/// tie, which the specs leave to the implementation).
pub fn cube_coords_on(d: glam::DVec3, f: usize) -> (f64, f64) {
    let a = d.abs();
    match f {
        0 => (-d.z / a.x, -d.y / a.x),
        1 => (d.z / a.x, -d.y / a.x),
        2 => (d.x / a.y, d.z / a.y),
        3 => (d.x / a.y, -d.z / a.y),
        4 => (d.x / a.z, -d.y / a.z),
        _ => (-d.x / a.z, -d.y / a.z),
    }
}

fn fit_bounds(view: Mat4, geometry: &Geometry) -> [f32; 6] {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in &geometry.positions {
        let q = view.transform_point3(*p);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let ext = (hi - lo).max(Vec3::splat(1e-3));
    let (mx, my, mz) = (0.005 * ext.x, 0.005 * ext.y, 0.01 * ext.z + 1e-3);
    // View space looks down −z: near = −max z, far = −min z.
    [
        lo.x - mx,
        hi.x + mx,
        lo.y - my,
        hi.y + my,
        -hi.z - mz,
        -lo.z + mz,
    ]
}
