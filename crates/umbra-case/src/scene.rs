//! The one tessellation every backend draws.
//!
//! Each primitive becomes triangles, counter-clockwise seen from outside (from the normal side
//! of a plane). Vertices are computed in f64 and rounded once to f32, so the list does not
//! depend on the platform's f32 trig. Vertices on a sphere's seam and poles are shared by
//! index, which keeps it watertight for the truth's ray test. Each triangle carries its object
//! and its *face*: the planar face it belongs to (a box has 6, a plane 1; sphere and mesh
//! triangles are faces of their own, a cylinder's side quads and caps one each). Faces decide silhouettes in the judge and let the truth
//! skip a surface's own plane.

use glam::{DMat3, DMat4, DVec3, Vec3};

use crate::format::{Object, Scene, Transform};

/// The tessellated scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    /// Vertex positions, world space.
    pub positions: Vec<Vec3>,
    /// Shading normals (unit), world space: flat for planes, boxes, meshes; smooth for spheres.
    pub normals: Vec<Vec3>,
    /// Triangles as vertex indices, counter-clockwise from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: its object's index in `scene.objects`.
    pub object: Vec<u32>,
    /// Per triangle: its planar face, numbered across the scene from 0.
    pub face: Vec<u32>,
    /// Per object: albedo, linear RGB.
    pub albedo: Vec<Vec3>,
}

impl Geometry {
    /// Axis-aligned bounds `(min, max)` of every vertex.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }

    /// The three positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Floats per vertex of [`Geometry::interleaved`].
    pub const VERTEX_FLOATS: usize = 10;

    /// The vertex stream every GPU backend draws: one vertex per triangle corner (so per-
    /// triangle data needs no flat-shading provoking-vertex rules), each
    /// `[position xyz, normal xyz, albedo rgb, face id]` as f32 (face ids are exact below
    /// 2^24).
    pub fn interleaved(&self) -> Vec<f32> {
        let mut v = Vec::with_capacity(self.triangles.len() * 3 * Self::VERTEX_FLOATS);
        for (t, tri) in self.triangles.iter().enumerate() {
            let a = self.albedo[self.object[t] as usize];
            for &i in tri {
                let (p, n) = (self.positions[i as usize], self.normals[i as usize]);
                v.extend_from_slice(&[
                    p.x,
                    p.y,
                    p.z,
                    n.x,
                    n.y,
                    n.z,
                    a.x,
                    a.y,
                    a.z,
                    self.face[t] as f32,
                ]);
            }
        }
        v
    }

    /// Number of planar faces.
    pub fn face_count(&self) -> u32 {
        self.face.iter().max().map_or(0, |f| f + 1)
    }
}

/// Tessellates `scene` (which must have passed validation).
pub fn tessellate(scene: &Scene) -> Geometry {
    let mut b = Builder::default();
    for (index, object) in scene.objects.iter().enumerate() {
        b.object = index as u32;
        match object {
            Object::Plane(p) => {
                b.geo.albedo.push(Vec3::from(p.color));
                let m = matrix(&p.transform);
                let n = DVec3::from(p.normal.map(f64::from)).normalize();
                let reference = if n.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
                let t = (reference - n * n.dot(reference)).normalize();
                let v = n.cross(t);
                let (hu, hv) = p.half_extent.pair();
                let c = DVec3::from(p.point.map(f64::from));
                b.quad(&m, c, t * f64::from(hu), v * f64::from(hv), n);
            }
            Object::Box(bx) => {
                b.geo.albedo.push(Vec3::from(bx.color));
                let m = matrix(&bx.transform);
                let c = DVec3::from(bx.center.map(f64::from));
                let h = DVec3::from(bx.size.map(f64::from)) * 0.5;
                for axis in 0..3 {
                    let e = |k: usize| DVec3::AXES[k % 3] * h[k % 3];
                    for sign in [1.0, -1.0] {
                        let n = DVec3::AXES[axis] * sign;
                        let (u, v) = if sign > 0.0 {
                            (e(axis + 1), e(axis + 2))
                        } else {
                            (e(axis + 2), e(axis + 1))
                        };
                        b.quad(&m, c + e(axis) * sign, u, v, n);
                    }
                }
            }
            Object::Sphere(s) => {
                b.geo.albedo.push(Vec3::from(s.color));
                let m = matrix(&s.transform);
                b.sphere(
                    &m,
                    DVec3::from(s.center.map(f64::from)),
                    f64::from(s.radius),
                    s.segments,
                );
            }
            Object::Cylinder(c) => {
                b.geo.albedo.push(Vec3::from(c.color));
                let m = matrix(&c.transform);
                b.cylinder(
                    &m,
                    DVec3::from(c.center.map(f64::from)),
                    f64::from(c.radius),
                    f64::from(c.height),
                    c.segments,
                );
            }
            Object::Mesh(mesh) => {
                b.geo.albedo.push(Vec3::from(mesh.color));
                let m = matrix(&mesh.transform);
                for t in &mesh.triangles {
                    let p = t.map(|i| {
                        m.transform_point3(DVec3::from(mesh.positions[i as usize].map(f64::from)))
                    });
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
                    let base = b.geo.positions.len() as u32;
                    for q in p {
                        b.vertex(q, n);
                    }
                    b.triangle([base, base + 1, base + 2]);
                    b.next_face();
                }
            }
        }
    }
    b.geo
}

/// `translate · rotate · scale` in f64.
pub fn matrix(t: &Option<Transform>) -> DMat4 {
    let Some(t) = t else { return DMat4::IDENTITY };
    let translate = DMat4::from_translation(DVec3::from(t.translate.map(f64::from)));
    let rotate = match &t.rotate_deg {
        Some(r) => DMat4::from_axis_angle(
            DVec3::from(r.axis.map(f64::from)).normalize(),
            f64::from(r.angle).to_radians(),
        ),
        None => DMat4::IDENTITY,
    };
    let scale = DMat4::from_scale(DVec3::from(t.scale.vec().map(f64::from)));
    translate * rotate * scale
}

#[derive(Default)]
struct Builder {
    geo: Geometry,
    object: u32,
    face: u32,
    normal_matrix: Option<DMat3>,
}

impl Builder {
    fn normal_of(&self, m: &DMat4, n: DVec3) -> DVec3 {
        let nm = self
            .normal_matrix
            .unwrap_or_else(|| DMat3::from_mat4(*m).inverse().transpose());
        (nm * n).normalize()
    }

    fn vertex(&mut self, p: DVec3, n: DVec3) -> u32 {
        self.geo.positions.push(p.as_vec3());
        self.geo.normals.push(n.as_vec3().normalize());
        (self.geo.positions.len() - 1) as u32
    }

    fn triangle(&mut self, t: [u32; 3]) {
        self.geo.triangles.push(t);
        self.geo.object.push(self.object);
        self.geo.face.push(self.face);
    }

    fn next_face(&mut self) {
        self.face += 1;
    }

    /// A planar quad centred at `c` spanning ±u, ±v with u × v along `n`, as one face.
    fn quad(&mut self, m: &DMat4, c: DVec3, u: DVec3, v: DVec3, n: DVec3) {
        self.normal_matrix = Some(DMat3::from_mat4(*m).inverse().transpose());
        let wn = self.normal_of(m, n);
        let corners = [c - u - v, c + u - v, c + u + v, c - u + v];
        let base = self.geo.positions.len() as u32;
        for q in corners {
            self.vertex(m.transform_point3(q), wn);
        }
        // A mirroring transform (negative determinant) reverses the winding: restore it.
        let flip = DMat3::from_mat4(*m).determinant() < 0.0;
        let tris = if flip {
            [[0, 2, 1], [0, 3, 2]]
        } else {
            [[0, 1, 2], [0, 2, 3]]
        };
        for t in tris {
            self.triangle(t.map(|k| base + k));
        }
        self.next_face();
        self.normal_matrix = None;
    }

    fn sphere(&mut self, m: &DMat4, c: DVec3, r: f64, segments: u32) {
        let rings = (segments / 2).max(2);
        let nm = DMat3::from_mat4(*m).inverse().transpose();
        let put = |b: &mut Builder, dir: DVec3| {
            let p = m.transform_point3(c + dir * r);
            b.vertex(p, (nm * dir).normalize())
        };
        let top = put(self, DVec3::Y);
        let mut ring_start = Vec::with_capacity(rings as usize);
        for i in 1..rings {
            let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
            ring_start.push(self.geo.positions.len() as u32);
            for j in 0..segments {
                let phi = std::f64::consts::TAU * f64::from(j) / f64::from(segments);
                put(
                    self,
                    DVec3::new(
                        crate::math::sin(theta) * crate::math::sin(phi),
                        crate::math::cos(theta),
                        crate::math::sin(theta) * crate::math::cos(phi),
                    ),
                );
            }
        }
        let bottom = put(self, -DVec3::Y);
        let at = |ring: usize, j: u32| ring_start[ring] + j % segments;
        let mut tris = Vec::new();
        for j in 0..segments {
            tris.push([top, at(0, j), at(0, j + 1)]);
            tris.push([
                bottom,
                at(ring_start.len() - 1, j + 1),
                at(ring_start.len() - 1, j),
            ]);
        }
        for ring in 0..ring_start.len() - 1 {
            for j in 0..segments {
                tris.push([at(ring, j), at(ring + 1, j), at(ring + 1, j + 1)]);
                tris.push([at(ring, j), at(ring + 1, j + 1), at(ring, j + 1)]);
            }
        }
        let centre = m.transform_point3(c);
        for t in tris {
            self.outward(t, centre);
            self.next_face();
        }
    }

    /// Triangle `t`, wound counter-clockwise seen from outside a convex solid whose centre is
    /// `centre`, whatever the winding given and the transform did.
    fn outward(&mut self, mut t: [u32; 3], centre: DVec3) {
        let [a, b, c] = t.map(|i| self.geo.positions[i as usize].as_dvec3());
        if (b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) < 0.0 {
            t.swap(1, 2);
        }
        self.triangle(t);
    }

    /// A capped cylinder along y: `segments` side quads (two triangles each, one planar face
    /// a quad, their vertex normals pointing straight out from the axis: smooth, as an engine
    /// draws one) and two flat caps (a fan each, one face each). The caps' rim vertices are
    /// the side's positions with the cap's normal: the same f32 positions, so the edges are
    /// shared for the truth's watertight test and the judge's adjacency.
    fn cylinder(&mut self, m: &DMat4, c: DVec3, r: f64, h: f64, segments: u32) {
        let nm = DMat3::from_mat4(*m).inverse().transpose();
        let around = |j: u32| {
            let phi = std::f64::consts::TAU * f64::from(j % segments) / f64::from(segments);
            DVec3::new(crate::math::sin(phi), 0.0, crate::math::cos(phi))
        };
        let half = DVec3::Y * (h / 2.0);
        let centre = m.transform_point3(c);
        // The side: normals from the axis.
        let mut low = Vec::with_capacity(segments as usize);
        let mut high = Vec::with_capacity(segments as usize);
        for j in 0..segments {
            let d = around(j);
            low.push(self.vertex(m.transform_point3(c + d * r - half), nm * d));
            high.push(self.vertex(m.transform_point3(c + d * r + half), nm * d));
        }
        for j in 0..segments as usize {
            let k = (j + 1) % segments as usize;
            // A side quad is planar: its two triangles are one face.
            for t in [[low[j], low[k], high[k]], [low[j], high[k], high[j]]] {
                self.outward(t, centre);
            }
            self.next_face();
        }
        // The caps: flat, one face each.
        for side in [-1.0, 1.0] {
            let n = nm * (DVec3::Y * side);
            let hub = self.vertex(m.transform_point3(c + half * side), n);
            let ring: Vec<u32> = (0..segments)
                .map(|j| self.vertex(m.transform_point3(c + around(j) * r + half * side), n))
                .collect();
            for j in 0..segments as usize {
                let k = (j + 1) % segments as usize;
                self.outward([hub, ring[j], ring[k]], centre);
            }
            self.next_face();
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::format::{BoxShape, Extent, Plane, Rotation, Scale, Sphere};

    fn scene(objects: Vec<Object>) -> Scene {
        Scene {
            objects,
            offset: [0.0; 3],
        }
    }

    fn boxed(size: [f32; 3], transform: Option<Transform>) -> Object {
        Object::Box(BoxShape {
            center: [0.0; 3],
            size,
            color: [0.5; 3],
            transform,
        })
    }

    /// Every triangle's winding normal points away from `inside`.
    fn assert_outward(g: &Geometry, inside: Vec3) {
        for t in 0..g.triangles.len() {
            let [a, b, c] = g.corners(t);
            let n = (b - a).cross(c - a);
            assert!(
                n.dot((a + b + c) / 3.0 - inside) > 0.0,
                "triangle {t} faces inward"
            );
            // Shading normals agree with the winding.
            let sn = g.normals[g.triangles[t][0] as usize];
            assert!(
                sn.dot(n) > 0.0,
                "triangle {t}: shading normal against winding"
            );
        }
    }

    #[test]
    fn a_box_has_six_outward_faces_and_its_area() {
        let g = tessellate(&scene(vec![boxed([1.0, 2.0, 3.0], None)]));
        assert_eq!((g.triangles.len(), g.face_count()), (12, 6));
        assert_outward(&g, Vec3::ZERO);
        let area: f32 = (0..12)
            .map(|t| {
                let [a, b, c] = g.corners(t);
                (b - a).cross(c - a).length() / 2.0
            })
            .sum();
        assert!((area - 2.0 * (2.0 + 6.0 + 3.0)).abs() < 1e-5, "{area}");
    }

    #[test]
    fn a_sphere_is_watertight_and_outward() {
        let s = Object::Sphere(Sphere {
            center: [1.0, 2.0, 3.0],
            radius: 2.0,
            segments: 12,
            color: [0.5; 3],
            transform: None,
        });
        let g = tessellate(&scene(vec![s]));
        assert_eq!(
            g.triangles.len(),
            12 * 2 + 12 * 2 * 4,
            "2 caps + 4 bands for 6 rings"
        );
        assert_outward(&g, Vec3::new(1.0, 2.0, 3.0));
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &g.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(
            edges.values().all(|&n| n == 2),
            "every edge is shared by exactly two triangles"
        );
    }

    /// A cylinder as engines draw one: closed (every edge, matched by position as the truth
    /// and the judge's adjacency match it, has exactly two triangles), outward, a face per
    /// side quad and per cap, and side normals straight out from the axis, so that the
    /// interpolated normal at a quad's middle is short by 1 − cos(π/segments).
    #[test]
    fn a_cylinder_is_closed_outward_and_smooth_on_its_side() {
        for segments in [3, 8, 16, 32] {
            let g = tessellate(&scene(vec![Object::Cylinder(crate::format::Cylinder {
                center: [1.0, 2.0, 0.0],
                radius: 0.5,
                height: 2.0,
                segments,
                color: [0.5; 3],
                transform: None,
            })]));
            let n = segments as usize;
            assert_eq!(g.triangles.len(), 2 * n + 2 * n);
            assert_eq!(g.face_count(), segments + 2);
            assert_outward(&g, Vec3::new(1.0, 2.0, 0.0));
            let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let mut edges: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
            for t in 0..g.triangles.len() {
                let c = g.corners(t).map(key);
                for j in 0..3 {
                    let (a, b) = (c[j], c[(j + 1) % 3]);
                    *edges
                        .entry(if a < b { (a, b) } else { (b, a) })
                        .or_default() += 1;
                }
            }
            assert!(edges.values().all(|&k| k == 2), "{segments}: an open edge");
            // Side normals are horizontal and unit; the middle of a quad is short.
            let side = g.triangles[0].map(|i| g.normals[i as usize]);
            for v in side {
                assert!(v.y.abs() < 1e-6 && (v.length() - 1.0).abs() < 1e-6, "{v}");
            }
            let mid = (g.normals[g.triangles[0][0] as usize]
                + g.normals[g.triangles[0][1] as usize])
                / 2.0;
            let short = (1.0 - crate::math::cos(std::f64::consts::PI / f64::from(segments))) as f32;
            assert!(
                (1.0 - mid.length() - short).abs() < 1e-5,
                "{segments}: {}",
                mid.length()
            );
        }
    }

    #[test]
    fn a_plane_is_lit_on_its_normal_side() {
        let p = Object::Plane(Plane {
            point: [0.0, 1.0, 0.0],
            normal: [0.0, 0.0, 2.0],
            half_extent: Extent::Rect([2.0, 1.0]),
            color: [0.5; 3],
            transform: None,
        });
        let g = tessellate(&scene(vec![p]));
        assert_eq!((g.triangles.len(), g.face_count()), (2, 1));
        assert_outward(&g, Vec3::new(0.0, 1.0, -1.0));
        let (lo, hi) = g.bounds();
        // Normal +z is far from ±y, so u is world y projected (half 2) and v = n × u = −x
        // (half 1), as cases/README.md says.
        assert_eq!(
            (lo, hi),
            (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 3.0, 0.0))
        );
    }

    #[test]
    fn transforms_scale_then_rotate_then_translate() {
        let t = Transform {
            translate: [5.0, 0.0, 0.0],
            rotate_deg: Some(Rotation {
                axis: [0.0, 1.0, 0.0],
                angle: 90.0,
            }),
            scale: Scale::PerAxis([2.0, 1.0, 1.0]),
        };
        let g = tessellate(&scene(vec![boxed([1.0, 1.0, 1.0], Some(t))]));
        let (lo, hi) = g.bounds();
        // Scaled to 2 along x, turned so that extent lies along z, then moved to x = 5.
        assert!(
            (lo - Vec3::new(4.5, -0.5, -1.0)).abs().max_element() < 1e-5,
            "{lo}"
        );
        assert!(
            (hi - Vec3::new(5.5, 0.5, 1.0)).abs().max_element() < 1e-5,
            "{hi}"
        );
        assert_outward(&g, Vec3::new(5.0, 0.0, 0.0));
    }

    #[test]
    fn a_mirroring_transform_keeps_faces_outward() {
        let t = Transform {
            translate: [0.0; 3],
            rotate_deg: None,
            scale: Scale::PerAxis([-1.0, 1.0, 1.0]),
        };
        let g = tessellate(&scene(vec![boxed([1.0, 1.0, 1.0], Some(t))]));
        assert_outward(&g, Vec3::ZERO);
    }
}
