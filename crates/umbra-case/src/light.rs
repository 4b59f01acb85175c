//! Light views: the view and projection of each shadow-map face, convention-free until a
//! backend asks for a [`Convention`]. A directional or spot light has one face; a point light
//! has six (+x, −x, +y, −y, +z, −z), each a 90° perspective with the up vectors of the GL cube
//! map table, selected by the major axis of (point − light) with ties going to x, then y.
//!
//! A cascaded directional light (`cascades`) has one face per cascade: each an orthographic
//! view fitted to its slice of the camera's view depths, selected by the receiver's view
//! depth ([`Cascading`]).
//!
//! A fitted directional frustum (`"fit": "scene"`) encloses every vertex of the scene in the
//! light's view space, widened by 0.5 % of its extent on each side in x and y and by 1 % of the
//! depth range (plus 1e-3 m) at near and far, so that no geometry sits exactly on a clip plane
//! or on the map's outermost texel border.

use glam::{DVec3, Mat4, Vec3, Vec4};

use crate::camera::CameraSetup;
use crate::conventions::{Convention, look_at};
use crate::format::{BlendOf, CascadeFit, Cascades, Fit, Light};
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
    /// One face, six for a point light, or one per cascade.
    pub views: Vec<LightView>,
    /// How a cascaded directional light picks its face.
    pub cascading: Option<Cascading>,
}

/// A cascaded light's face selection: the receiver's view depth d (the distance in front of
/// the camera along its view axis, d = −(V·p).z) against the split depths.
#[derive(Clone, Debug, PartialEq)]
pub struct Cascading {
    /// d = `depth_row` · (p, 1): the camera view matrix's third row, negated.
    pub depth_row: Vec4,
    /// s_0 (the camera's near plane) to s_N (the shadow distance); cascade k covers
    /// [s_k, s_{k+1}].
    pub splits: Vec<f32>,
    /// The blend band's share of a cascade's range or far bound (0: none).
    pub blend: f32,
    /// What `blend` is a share of.
    pub blend_of: BlendOf,
    /// Receivers beyond s_N read lit (a shadow distance was given).
    pub lit_beyond: bool,
}

impl Cascading {
    /// The cascade of view depth `d`: the last k ≥ 1 with d > s_k, else 0 (a depth exactly on
    /// a split goes to the nearer cascade; the judge lets either serve it).
    pub fn cascade_of(&self, d: f64) -> usize {
        let n = self.splits.len() - 1;
        (1..n)
            .filter(|&k| d > f64::from(self.splits[k]))
            .max()
            .unwrap_or(0)
    }

    /// The last split, s_N.
    pub fn end(&self) -> f32 {
        self.splits[self.splits.len() - 1]
    }

    /// Whether view depth `d` lies beyond the shadow distance (lit).
    pub fn beyond(&self, d: f32) -> bool {
        self.lit_beyond && d > self.end()
    }

    /// The width of cascade k's blend band in f32 as the lit shaders compute it: b·w with
    /// w = s_{k+1} − s_k (`range`) or w = s_{k+1} (`far`).
    pub fn band(&self, k: usize) -> f32 {
        let (lo, hi) = (self.splits[k], self.splits[k + 1]);
        match self.blend_of {
            BlendOf::Range => self.blend * (hi - lo),
            BlendOf::Far => self.blend * hi,
        }
    }

    /// [`Cascading::band`] in f64.
    pub fn band_f64(&self, k: usize) -> f64 {
        let (lo, hi) = (f64::from(self.splits[k]), f64::from(self.splits[k + 1]));
        let b = f64::from(self.blend);
        match self.blend_of {
            BlendOf::Range => b * (hi - lo),
            BlendOf::Far => b * hi,
        }
    }

    /// The weight of cascade k + 1 at view depth `d` in cascade k's blend band, in f32 as
    /// the lit shaders compute it: t = (d − (s_{k+1} − band)) / band ([`Cascading::band`]),
    /// clamped to 1; `None` outside the band, without a band, or in the last cascade.
    pub fn blend_weight(&self, k: usize, d: f32) -> Option<f32> {
        if self.blend <= 0.0 || k + 2 >= self.splits.len() {
            return None;
        }
        let hi = self.splits[k + 1];
        let band = self.band(k);
        let t = (d - (hi - band)) / band;
        (t > 0.0).then_some(t.min(1.0))
    }

    /// The blend weights of cascade k + 1 that view depths within `reach` of `d` give, as
    /// an interval (0 where some lie outside the band), or `None` where none lies in it.
    pub fn blend_range(&self, k: usize, d: f64, reach: f64) -> Option<(f64, f64)> {
        if self.blend <= 0.0 || k + 2 >= self.splits.len() {
            return None;
        }
        let hi = f64::from(self.splits[k + 1]);
        let band = self.band_f64(k);
        let t = |x: f64| ((x - (hi - band)) / band).clamp(0.0, 1.0);
        let (a, b) = (t(d - reach), t(d + reach));
        (b > 0.0).then_some((a, b))
    }

    /// The view depth of `p` in f32, as the lit shaders compute it.
    pub fn depth(&self, p: Vec3) -> f32 {
        self.depth_row.truncate().dot(p) + self.depth_row.w
    }

    /// The view depth of `p`, exact but for f64 rounding.
    pub fn depth_f64(&self, p: DVec3) -> f64 {
        self.depth_row.truncate().as_dvec3().dot(p) + f64::from(self.depth_row.w)
    }

    /// The lit shaders' cascade uniforms: the depth row, then s_0 … s_7 (zero past s_N;
    /// s_N is at most s_6).
    pub fn uniforms(&self) -> [[f32; 4]; 3] {
        let mut split = [0.0f32; 8];
        for (k, s) in self.splits.iter().take(8).enumerate() {
            split[k] = *s;
        }
        [
            self.depth_row.to_array(),
            [split[0], split[1], split[2], split[3]],
            [split[4], split[5], split[6], split[7]],
        ]
    }

    /// Every cascade whose range lies within `reach` of view depth `d`.
    pub fn cascades_near(&self, d: f64, reach: f64) -> Vec<usize> {
        let n = self.splits.len() - 1;
        (0..n)
            .filter(|&k| {
                let (lo, hi) = (f64::from(self.splits[k]), f64::from(self.splits[k + 1]));
                (k == 0 || d >= lo - reach) && (k + 1 == n || d <= hi + reach)
            })
            .collect()
    }
}

/// The split depths s_0 = `near` … s_N = f of `c`, f its shadow distance or the camera's
/// `far`: s_k = λ·n·(f/n)^(k/N) + (1 − λ)·(n + (f − n)·k/N), or n + a_k·(f − n) for
/// explicit fractions, in f64, the ends exact.
pub fn cascade_splits(c: &Cascades, near: f32, far: f32) -> Vec<f32> {
    let far = c.distance.unwrap_or(far);
    let (n, f, count) = (f64::from(near), f64::from(far), c.count.max(1));
    let lambda = f64::from(c.weight());
    (0..=count)
        .map(|k| {
            if k == 0 {
                return near;
            }
            if k == count {
                return far;
            }
            if let Some(a) = c.at.as_ref().and_then(|at| at.get(k as usize - 1)) {
                return (n + f64::from(*a) * (f - n)) as f32;
            }
            let x = f64::from(k) / f64::from(count);
            let log = n * crate::math::pow(f / n, x);
            let uni = n + (f - n) * x;
            (lambda * log + (1.0 - lambda) * uni) as f32
        })
        .collect()
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
    /// Per face, the world distance `shadow.bias.normal_offset_texels` moves the lookup point
    /// along the normal: that many times the world width of one texel of the face's
    /// orthographic map, (right − left) / width, in f32 (Bevy's `shadow_normal_bias ×
    /// texel_size`, which it multiplies in that order); 0 for a perspective face (the field
    /// is refused with spot and point lights).
    pub fn face_offsets(&self, texels: f32, map_size: [u32; 2]) -> Vec<f32> {
        (0..self.views.len())
            .map(|f| self.face_offset(f, texels, map_size))
            .collect()
    }

    /// [`LightSetup::face_offsets`] of face `face`.
    pub fn face_offset(&self, face: usize, texels: f32, map_size: [u32; 2]) -> f32 {
        match self.views[face].projection {
            Projection::Ortho { bounds } => texels * ((bounds[1] - bounds[0]) / map_size[0] as f32),
            Projection::Perspective { .. } => 0.0,
        }
    }

    /// The light of a validated case, with a `map_size` map, fitted to `geometry` if asked
    /// (and, for cascades, to the slices of `camera`'s view).
    pub fn new(
        light: &Light,
        map_size: [u32; 2],
        geometry: &Geometry,
        camera: &CameraSetup,
    ) -> Self {
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
                let kind = LightKind::Directional {
                    towards,
                    position: eye,
                };
                if let Some(c) = &d.cascades {
                    return cascaded(kind, view, c, geometry, camera, map_size);
                }
                let bounds = match (&d.ortho, d.fit) {
                    (Some(o), _) => [o.left, o.right, o.bottom, o.top, o.near, o.far],
                    (None, Some(Fit::Scene) | None) => fit_bounds(view, geometry),
                };
                LightSetup {
                    kind,
                    views: vec![LightView {
                        view,
                        projection: Projection::Ortho { bounds },
                    }],
                    cascading: None,
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
                    cascading: None,
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
                    cascading: None,
                }
            }
        }
    }

    /// The face a world point is looked up in: a point light's cube face, a cascaded
    /// light's cascade (by the f32 view depth), else 0.
    pub fn face_for(&self, p: Vec3) -> usize {
        match (self.kind, &self.cascading) {
            (LightKind::Point { position }, _) => cube_face((p - position).as_dvec3()),
            (_, Some(c)) => c.cascade_of(f64::from(c.depth(p))),
            _ => 0,
        }
    }

    /// A cube map (point light): faces chosen by direction.
    pub fn is_cube(&self) -> bool {
        matches!(self.kind, LightKind::Point { .. })
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

/// A cascaded directional light: one orthographic face per slice of the camera's view
/// depths (a slice after a blend band starts where the band does), fitted as `c.fit` says
/// ([`CascadeFit`]): the box of the slice's corners in x and y (widened by 0.5 % of their
/// extent a side) and the scene in depth (every caster of the slice's receivers is drawn),
/// or the stable square of [`stable_bounds`].
fn cascaded(
    kind: LightKind,
    view: Mat4,
    c: &Cascades,
    geometry: &Geometry,
    camera: &CameraSetup,
    map_size: [u32; 2],
) -> LightSetup {
    let splits = cascade_splits(c, camera.near, camera.far);
    let scene = fit_bounds(view, geometry);
    let to_light = view.as_dmat4() * camera.view.as_dmat4().inverse();
    let tan_y = crate::math::tan(0.5 * f64::from(camera.fov_y));
    let tan_x = tan_y * f64::from(camera.size[0]) / f64::from(camera.size[1]);
    let cascading = Cascading {
        depth_row: -camera.view.row(2),
        splits: splits.clone(),
        blend: c.blend,
        blend_of: c.blend_of,
        lit_beyond: c.distance.is_some(),
    };
    // With a blend band, cascade k + 1 is fitted from where cascade k's band starts (as
    // Bevy's cascade overlap does), so that the band's receivers lie in both maps.
    let starts: Vec<f64> = (0..splits.len() - 1)
        .map(|k| match k {
            0 => f64::from(splits[0]),
            _ => f64::from(splits[k]) - cascading.band_f64(k - 1),
        })
        .collect();
    let views = splits
        .windows(2)
        .zip(&starts)
        .map(|(s, start)| {
            // The slice's corners in camera view space, near then far, each as Bevy orders
            // them: bottom-right, top-right, top-left, bottom-left.
            let corners: Vec<DVec3> = [*start, f64::from(s[1])]
                .iter()
                .flat_map(|&d| {
                    [(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)]
                        .map(|(a, b)| DVec3::new(a * tan_x * d, b * tan_y * d, -d))
                })
                .collect();
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for q in &corners {
                let q = to_light.transform_point3(*q);
                lo = lo.min(q);
                hi = hi.max(q);
            }
            let bounds = match c.fit {
                CascadeFit::Box => {
                    let m = 0.005 * (hi - lo);
                    [
                        (lo.x - m.x) as f32,
                        (hi.x + m.x) as f32,
                        (lo.y - m.y) as f32,
                        (hi.y + m.y) as f32,
                        scene[4],
                        scene[5],
                    ]
                }
                CascadeFit::Stable => stable_bounds(&corners, lo, hi, map_size),
            };
            LightView {
                view,
                projection: Projection::Ortho { bounds },
            }
        })
        .collect();
    LightSetup {
        kind,
        views,
        cascading: Some(cascading),
    }
}

/// Bevy's stable cascade (`calculate_cascade` in bevy_pbr's `light/mod.rs`): the square's
/// side is the longer of the body diagonal (near bottom-right to far top-left) and the far
/// plane's diagonal of the slice's `corners`, rounded up to a whole unit; one texel is that
/// over the map's size; the centre of the corners' light-view box `lo`..`hi` is floored to a
/// whole texel; in depth the bounds are the corners' own (light view looks down −z: near =
/// −max z, far = −min z). Bevy rounds in f32 where this does in f64: the side differs only
/// where a diagonal lies within an f32 rounding of a whole unit.
fn stable_bounds(corners: &[DVec3], lo: DVec3, hi: DVec3, map_size: [u32; 2]) -> [f32; 6] {
    let side = (corners[0] - corners[6])
        .length()
        .max((corners[4] - corners[6]).length())
        .ceil();
    let texel = [side / f64::from(map_size[0]), side / f64::from(map_size[1])];
    let cx = (0.5 * (lo.x + hi.x) / texel[0]).floor() * texel[0];
    let cy = (0.5 * (lo.y + hi.y) / texel[1]).floor() * texel[1];
    let half = 0.5 * side;
    [
        (cx - half) as f32,
        (cx + half) as f32,
        (cy - half) as f32,
        (cy + half) as f32,
        -hi.z as f32,
        -lo.z as f32,
    ]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::SplitScheme;

    fn splits(split: SplitScheme, lambda: Option<f32>) -> Vec<f32> {
        let c = Cascades {
            count: 4,
            split,
            lambda,
            at: None,
            distance: None,
            blend: 0.0,
            blend_of: Default::default(),
            fit: Default::default(),
        };
        cascade_splits(&c, 1.0, 16.0)
    }

    /// Uniform splits are equal ranges, logarithmic ones equal ratios, and the practical
    /// scheme their blend by λ; the ends are the camera's planes exactly.
    #[test]
    fn the_split_schemes_are_zhangs() {
        assert_eq!(
            splits(SplitScheme::Uniform, None),
            [1.0, 4.75, 8.5, 12.25, 16.0]
        );
        assert_eq!(
            splits(SplitScheme::Logarithmic, None),
            [1.0, 2.0, 4.0, 8.0, 16.0]
        );
        let c = Cascades {
            count: 4,
            split: SplitScheme::Fractions,
            lambda: None,
            at: Some(vec![0.1, 0.2, 0.5]),
            distance: Some(11.0),
            blend: 0.0,
            blend_of: Default::default(),
            fit: Default::default(),
        };
        assert_eq!(cascade_splits(&c, 1.0, 16.0), [1.0, 2.0, 3.0, 6.0, 11.0]);
        let p = splits(SplitScheme::Practical, Some(0.5));
        for (k, want) in [1.0, 3.375, 6.25, 10.125, 16.0].iter().enumerate() {
            assert!((p[k] - want).abs() < 1e-5, "{p:?}");
        }
    }

    /// A depth on a split goes to the nearer cascade; the judge's reach admits both.
    #[test]
    fn a_depth_on_a_split_is_the_nearer_cascade_and_near_it_either() {
        let c = Cascading {
            depth_row: Vec4::new(0.0, 0.0, -1.0, 0.0),
            splits: vec![1.0, 2.0, 4.0],
            blend: 0.25,
            blend_of: BlendOf::Range,
            lit_beyond: true,
        };
        // The band is the last quarter of [1, 2]: from 1.75.
        assert_eq!(c.blend_weight(0, 1.5), None);
        assert_eq!(c.blend_weight(0, 1.875), Some(0.5));
        assert_eq!(c.blend_weight(1, 3.9), None, "the last cascade has no band");
        assert_eq!(c.blend_range(0, 1.875, 0.125), Some((0.0, 1.0)));
        assert!(c.beyond(4.001) && !c.beyond(4.0));
        assert_eq!(c.cascade_of(2.0), 0);
        assert_eq!(c.cascade_of(2.000_001), 1);
        assert_eq!(c.cascades_near(2.0, 1e-6), [0, 1]);
        assert_eq!(c.cascades_near(3.0, 1e-6), [1]);
        assert_eq!(c.cascades_near(0.5, 0.0), [0]);
        assert_eq!(c.cascades_near(9.0, 0.0), [1]);
        assert_eq!(c.depth(Vec3::new(5.0, 1.0, -3.0)), 3.0);
    }

    /// Bevy's band is a share of the far bound: 0.2 of cascade 0's far bound 10 starts it
    /// at 8, whatever the near bound.
    #[test]
    fn a_band_of_the_far_bound_is_that_share_of_it() {
        let c = Cascading {
            depth_row: Vec4::new(0.0, 0.0, -1.0, 0.0),
            splits: vec![0.1, 10.0, 24.0, 60.0],
            blend: 0.25,
            blend_of: BlendOf::Far,
            lit_beyond: true,
        };
        assert_eq!(c.band(0), 2.5);
        assert_eq!(c.band(1), 6.0);
        assert_eq!(c.blend_weight(0, 7.5), None);
        assert_eq!(c.blend_weight(0, 8.75), Some(0.5));
        assert_eq!(c.blend_range(1, 21.0, 0.0), Some((0.5, 0.5)));
    }

    /// The stable fit is a square of a whole number of units, centred on a whole texel, and
    /// its side is the same for a camera turned about its eye (the slice's diagonals do not
    /// depend on where the camera looks).
    #[test]
    fn the_stable_fit_is_a_whole_square_on_a_whole_texel() {
        use crate::format::{CascadeFit, Case};
        let sides = |target: &str| {
            let case: Case = serde_json::from_str(&format!(
                r#"{{"name": "t", "about": "t", "scene": {{"objects": [{{"plane": {{"point": [0, 0, 0], "half_extent": 50}}}}]}},
                "camera": {{"eye": [0, 2, 4], "target": {target}, "fov_y_deg": 45, "near": 0.1, "far": 200, "size": [240, 160]}},
                "light": {{"directional": {{"azimuth_deg": 30, "elevation_deg": 35, "distance": 300,
                  "cascades": {{"count": 3, "split": "logarithmic", "distance": 100, "blend": 0.2, "blend_of": "far", "fit": "stable"}}}}}},
                "shadow": {{"size": [1024, 1024]}}}}"#
            ))
            .expect("a case");
            let Light::Directional(d) = &case.lights[0] else {
                panic!("directional");
            };
            assert_eq!(d.cascades.as_ref().map(|c| c.fit), Some(CascadeFit::Stable));
            let camera = CameraSetup::new(&case.camera);
            let geometry = crate::scene::tessellate(&case.scene);
            let light = LightSetup::new(&case.lights[0], case.shadow.size, &geometry, &camera);
            let mut sides = Vec::new();
            for v in &light.views {
                let Projection::Ortho { bounds } = v.projection else {
                    panic!("ortho");
                };
                let side = bounds[1] - bounds[0];
                assert_eq!(side, side.round(), "a whole number of units: {bounds:?}");
                assert_eq!(bounds[3] - bounds[2], side, "a square: {bounds:?}");
                let texel = side / 1024.0;
                let centre = 0.5 * (bounds[0] + bounds[1]);
                assert_eq!(centre / texel, (centre / texel).round(), "on a whole texel");
                sides.push(side);
            }
            sides
        };
        let ahead = sides("[0, 1, -40]");
        assert!(ahead.windows(2).all(|w| w[0] < w[1]), "{ahead:?}");
        assert_eq!(sides("[25, -3, -30]"), ahead, "turned, the same squares");
    }
}
