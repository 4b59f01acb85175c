//! Watertight ray/triangle intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013), in f64.
//!
//! The ray is sheared so it runs along +z through the origin; each triangle edge's 2D edge
//! function is then computed from the *same* sheared vertex coordinates by every triangle that
//! shares the edge, so a ray through a shared edge or vertex hits at least one of them. That
//! is what keeps touching cubes from leaking light along their shared faces. A ray lying in a
//! triangle's plane (det = 0) does not hit it; it hits the neighbours across the edge instead.

use glam::DVec3;

/// A ray with its shear precomputed.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub origin: DVec3,
    /// Direction (need not be unit; t is in its units).
    pub dir: DVec3,
    k: [usize; 3],
    shear: DVec3,
    /// 1 / dir, for box tests.
    pub inv_dir: DVec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let shear = DVec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        Ray {
            origin,
            dir,
            k: [kx, ky, kz],
            shear,
            inv_dir: dir.recip(),
        }
    }

    /// The hit distance t in (t_min, t_max) with triangle (a, b, c), either side.
    pub fn hit(&self, a: DVec3, b: DVec3, c: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        let [kx, ky, kz] = self.k;
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let (a, b, c) = (a - self.origin, b - self.origin, c - self.origin);
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * sz * a[kz] + v * sz * b[kz] + w * sz * c[kz];
        let t = t_scaled / det;
        (t > t_min && t < t_max).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_through_a_shared_edge_or_vertex_hit_one_of_the_triangles() {
        // Two triangles sharing the edge x = 2 (a box face split along a diagonal, and its
        // neighbour): rays exactly through the edge and the vertices must hit.
        let q = [
            DVec3::new(-2.0, 2.0, 0.0),
            DVec3::new(2.0, 2.0, 0.0),
            DVec3::new(2.0, 6.0, 0.0),
            DVec3::new(-2.0, 6.0, 0.0),
        ];
        let r = [
            DVec3::new(2.0, 2.0, 0.0),
            DVec3::new(6.0, 2.0, 0.0),
            DVec3::new(6.0, 6.0, 0.0),
            DVec3::new(2.0, 6.0, 0.0),
        ];
        let tris = [
            [q[0], q[1], q[2]],
            [q[0], q[2], q[3]],
            [r[0], r[1], r[2]],
            [r[0], r[2], r[3]],
        ];
        for y in [2.0, 2.5, 4.0, 5.999, 6.0, 4.0 + 1e-12] {
            for dir in [
                DVec3::new(0.0, 0.0, -1.0),
                DVec3::new(0.3, -0.1, -1.0),
                DVec3::new(-1e-9, 0.0, -1.0),
            ] {
                let origin = DVec3::new(2.0, y, 0.0) - dir * 5.0; // aims exactly at (2, y) on the quads
                let ray = Ray::new(origin, dir);
                let hits = tris
                    .iter()
                    .filter(|t| ray.hit(t[0], t[1], t[2], 0.0, f64::INFINITY).is_some())
                    .count();
                assert!(hits >= 1, "leak at y={y} dir={dir}");
            }
        }
    }

    #[test]
    fn distance_is_exact_for_an_axis_ray() {
        let ray = Ray::new(DVec3::new(0.25, 0.25, 3.0), DVec3::new(0.0, 0.0, -2.0));
        let t = ray.hit(DVec3::ZERO, DVec3::X, DVec3::Y, 0.0, 10.0);
        assert_eq!(t, Some(1.5));
        assert_eq!(ray.hit(DVec3::ZERO, DVec3::X, DVec3::Y, 0.0, 1.0), None);
    }
}
