//! The exact ground truth: for each camera pixel, the first surface along the ray through the
//! pixel centre and whether a shadow ray from it reaches the light, in f64, against the same
//! triangles every backend draws; the shadow map plays no part.
//!
//! Each pixel gets a [`Class`]:
//! - `Background`: the ray hits nothing before the far plane.
//! - `FacesAway`: the surface's geometric normal faces away from the light (N·L ≤ 0). The
//!   shadow term does not show there (diffuse and specular are zero), and shadow maps
//!   legitimately differ on such faces, so they are excluded from error and counted.
//! - `Outside`: the point is outside the light's frustum (beyond its bounds, near or far, or a
//!   cascaded light's shadow distance), where the map holds nothing and the case's outside
//!   policy decides; excluded and counted.
//! - `Lit` or `Shadowed`: the answer of the shadow ray (skipping the surface's own planar face,
//!   which cannot shadow itself).
//!
//! **Edge** flag: a shadow map samples the light's view at texel resolution, so within a texel
//! or two of a true shadow boundary no technique can be expected to match a point-exact ray.
//! For each judged pixel the truth also shoots shadow rays from the points of the receiver's
//! tangent plane that the light sees through the texels around it (offsets −r..r texels in the
//! map's grid, r = 1 for NEAREST and LINEAR, 1 + ⌈(N−1)/2⌉ for PCF N). If any answer differs
//! from the centre's, the pixel is an edge pixel: error there is reported separately, and
//! "error away from edges" must be zero for a well-biased technique. Extrapolating along the
//! tangent plane (instead of using neighbouring surface points) keeps slanted receivers from
//! being counted as their own occluders; a convex curved receiver lies behind its tangent plane
//! as seen from the light, so it does not either.

pub mod aliasing;
pub mod bvh;
pub mod ray;

use std::time::{Duration, Instant};

use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;
use umbra_case::format::Filter;
use umbra_case::{Convention, LightKind, LightRun};

use bvh::Bvh;
use ray::Ray;

/// What the truth says about one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Class {
    /// Nothing is hit.
    Background,
    /// The surface faces away from the light.
    FacesAway,
    /// Outside the light's frustum.
    Outside,
    /// Reached by the light.
    Lit,
    /// Blocked from the light.
    Shadowed,
}

/// The truth for every pixel of a run, top row first.
#[derive(Clone, Debug)]
pub struct Truth {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Class per pixel.
    pub class: Vec<Class>,
    /// Per pixel: within the light's texel resolution of a true shadow boundary.
    pub edge: Vec<bool>,
    /// Per pixel: the hit triangle's face + 1, 0 for background.
    pub face: Vec<u32>,
    /// Per pixel: the world point hit (meaningless for background).
    pub point: Vec<DVec3>,
    /// Time taken.
    pub elapsed: Duration,
}

impl Truth {
    /// Whether pixel `i` is judged (lit or shadowed).
    pub fn judged(&self, i: usize) -> bool {
        matches!(self.class[i], Class::Lit | Class::Shadowed)
    }
}

/// The texel radius of the edge test for a filter.
pub fn edge_radius(filter: Filter) -> i32 {
    match filter {
        Filter::Nearest | Filter::Linear => 1,
        Filter::Pcf(n) => 1 + (n as i32 - 1 + 1) / 2,
        // Its nine bilinear taps reach from 3 texels before the point to 2¼ + 1 after it.
        Filter::Castano13 => 4,
        // Its five bilinear taps lie within one texel of the point, each reading one more.
        Filter::Vogel5 => 2,
    }
}

struct Scene<'a> {
    bvh: Bvh,
    face: &'a [u32],
    light: LightKind,
    /// A cascaded light's face selection.
    cascading: Option<umbra_case::light::Cascading>,
    faces: Vec<(DMat4, DMat4)>,
    map: [u32; 2],
    eps: f64,
    radius: i32,
    inv_cam: DMat4,
    size: [u32; 2],
    /// The lit pass's culling (`camera.cull`): camera rays pass through culled faces.
    camera_cull: umbra_case::format::Cull,
}

/// Computes the truth of `run`.
pub fn ground_truth(run: &LightRun) -> Truth {
    let start = Instant::now();
    let [w, h] = run.camera.size;
    let scene = Scene::new(run);
    let pixels: Vec<(Class, bool, u32, DVec3)> = (0..w * h)
        .into_par_iter()
        .map(|i| scene.camera_pixel(i))
        .collect();
    let mut truth = Truth {
        width: w,
        height: h,
        class: Vec::with_capacity(pixels.len()),
        edge: Vec::with_capacity(pixels.len()),
        face: Vec::with_capacity(pixels.len()),
        point: Vec::with_capacity(pixels.len()),
        elapsed: Duration::ZERO,
    };
    for (c, e, f, p) in pixels {
        truth.class.push(c);
        truth.edge.push(e);
        truth.face.push(f);
        truth.point.push(p);
    }
    truth.elapsed = start.elapsed();
    truth
}

/// The truth of `run` at the pixels `at` (row-major indices), each exactly what
/// [`ground_truth`] computes there: class, edge flag and face. A stored truth is checked
/// against a sample of its pixels this way (the judging cache's sanity check) at the cost of
/// those pixels' rays, not the frame's.
pub fn truth_at(run: &LightRun, at: &[usize]) -> Vec<(Class, bool, u32)> {
    let scene = Scene::new(run);
    at.iter()
        .map(|&i| {
            let (c, e, f, _) = scene.camera_pixel(i as u32);
            (c, e, f)
        })
        .collect()
}

impl<'a> Scene<'a> {
    fn new(run: &'a LightRun) -> Scene<'a> {
        let case = run.case();
        let geo = &run.geometry;
        let conv = Convention::ZERO_TO_ONE;
        let (lo, hi) = geo.bounds();
        let extent = f64::from((hi - lo).max_element()).max(1e-6);
        let faces = run
            .light
            .views
            .iter()
            .map(|v| {
                let m = to_f64(v.view_proj(conv));
                (m, m.inverse())
            })
            .collect();
        Scene {
            bvh: Bvh::new(geo),
            face: &geo.face,
            light: run.light.kind,
            cascading: run.light.cascading.clone(),
            faces,
            map: case.shadow.size,
            eps: extent * 1e-9,
            radius: edge_radius(case.shadow.filter),
            inv_cam: to_f64(run.camera.view_proj(conv)).inverse(),
            size: run.camera.size,
            camera_cull: case.camera.cull,
        }
    }

    /// The truth at camera pixel `i` (row-major), through the pixel's centre.
    fn camera_pixel(&self, i: u32) -> (Class, bool, u32, DVec3) {
        self.pixel(&camera_ray(self.inv_cam, self.size, i))
    }
}

/// The ray through the centre of camera pixel `i` (row-major), from the near plane (t = 0)
/// to the far plane (t = 1).
fn camera_ray(inv_cam: DMat4, [w, h]: [u32; 2], i: u32) -> Ray {
    let (x, y) = (i % w, i / w);
    let ndc_x = (f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0;
    let ndc_y = 1.0 - (f64::from(y) + 0.5) / f64::from(h) * 2.0;
    let near = project(inv_cam, DVec3::new(ndc_x, ndc_y, 0.0));
    let far = project(inv_cam, DVec3::new(ndc_x, ndc_y, 1.0));
    Ray::new(near, far - near)
}

/// The world point each camera pixel's centre ray hits first (`None`: background), found as
/// the truth finds it but without its shadow rays: for measures that need where the pixels
/// land when the truth came from the judge cache, which keeps no hit points.
pub fn camera_hits(run: &LightRun) -> Vec<Option<DVec3>> {
    let bvh = Bvh::new(&run.geometry);
    let inv_cam = to_f64(run.camera.view_proj(Convention::ZERO_TO_ONE)).inverse();
    let [w, h] = run.camera.size;
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let ray = camera_ray(inv_cam, run.camera.size, i);
            bvh.closest_facing(&ray, 0.0, 1.0 + 1e-12, run.case().camera.cull)
                .map(|hit| ray.origin + ray.dir * hit.t)
        })
        .collect()
}

impl Scene<'_> {
    fn pixel(&self, camera_ray: &Ray) -> (Class, bool, u32, DVec3) {
        // t in (0, 1]: from the near plane to the far plane.
        let Some(hit) = self
            .bvh
            .closest_facing(camera_ray, 0.0, 1.0 + 1e-12, self.camera_cull)
        else {
            return (Class::Background, false, 0, DVec3::ZERO);
        };
        let p = camera_ray.origin + camera_ray.dir * hit.t;
        let face = self.face[hit.tri as usize];
        let [a, b, c] = self.bvh.corners(hit.tri);
        let n = (b - a).cross(c - a).normalize();
        let to_light = self.to_light(p);
        if n.dot(to_light) <= 0.0 {
            return (Class::FacesAway, false, face + 1, p);
        }
        // Beyond a cascaded light's shadow distance the map holds nothing: lit by policy.
        if let Some(c) = &self.cascading {
            if c.lit_beyond && c.depth_f64(p) > f64::from(c.end()) {
                return (Class::Outside, false, face + 1, p);
            }
        }
        let light_face = self.face_for(p);
        let (m, inv) = self.faces[light_face];
        let clip = m * p.extend(1.0);
        let inside = clip.w > 0.0
            && clip.x.abs() <= clip.w
            && clip.y.abs() <= clip.w
            && clip.z >= 0.0
            && clip.z <= clip.w;
        if !inside {
            return (Class::Outside, false, face + 1, p);
        }
        let shadowed = self.blocked(p, face);
        let class = if shadowed {
            Class::Shadowed
        } else {
            Class::Lit
        };
        let ndc = clip.truncate() / clip.w;
        let edge = self.near_boundary(p, n, face, ndc, inv, shadowed);
        (class, edge, face + 1, p)
    }

    fn to_light(&self, p: DVec3) -> DVec3 {
        match self.light {
            LightKind::Directional { towards, .. } => towards.as_dvec3().normalize(),
            LightKind::Spot { position } | LightKind::Point { position } => {
                (position.as_dvec3() - p).normalize()
            }
        }
    }

    /// The face of `p`, exactly: the cube face, or the cascade of its exact view depth.
    fn face_for(&self, p: DVec3) -> usize {
        match (self.light, &self.cascading) {
            (LightKind::Point { position }, _) => {
                umbra_case::light::cube_face(p - position.as_dvec3())
            }
            (_, Some(c)) => c.cascade_of(c.depth_f64(p)),
            _ => 0,
        }
    }

    /// Whether the segment from `p` to the light crosses anything but face `own`.
    fn blocked(&self, p: DVec3, own: u32) -> bool {
        let (dir, t_max) = match self.light {
            LightKind::Directional { towards, .. } => {
                (towards.as_dvec3().normalize(), f64::INFINITY)
            }
            LightKind::Spot { position } | LightKind::Point { position } => {
                let d = position.as_dvec3() - p;
                let len = d.length();
                (d / len, len)
            }
        };
        self.bvh.occluded(&Ray::new(p, dir), self.eps, t_max, own)
    }

    fn near_boundary(
        &self,
        p: DVec3,
        n: DVec3,
        own: u32,
        ndc: DVec3,
        inv: DMat4,
        centre: bool,
    ) -> bool {
        let r = self.radius;
        let (sx, sy) = (2.0 / f64::from(self.map[0]), 2.0 / f64::from(self.map[1]));
        for dy in -r..=r {
            for dx in -r..=r {
                if dx == 0 && dy == 0 {
                    continue;
                }
                let q = project(
                    inv,
                    DVec3::new(
                        ndc.x + f64::from(dx) * sx,
                        ndc.y + f64::from(dy) * sy,
                        ndc.z,
                    ),
                );
                let d = match self.light {
                    LightKind::Directional { towards, .. } => towards.as_dvec3(),
                    LightKind::Spot { position } | LightKind::Point { position } => {
                        q - position.as_dvec3()
                    }
                };
                let dn = d.dot(n);
                if dn.abs() < 1e-12 * d.length() {
                    return true; // the light grazes the receiver: every texel is a boundary
                }
                let on_plane = q + d * ((p - q).dot(n) / dn);
                if self.blocked(on_plane, own) != centre {
                    return true;
                }
            }
        }
        false
    }
}

fn project(m: DMat4, p: DVec3) -> DVec3 {
    let q: DVec4 = m * p.extend(1.0);
    q.truncate() / q.w
}

fn to_f64(m: glam::Mat4) -> DMat4 {
    m.as_dmat4()
}
