//! The surface a run of camera pixels shows: for pixels of one row that the same triangle won
//! in the depth test, the perspective-correct weights of each pixel centre, the interpolated
//! position and normal (the varyings), and the unit vector towards the eye.
//!
//! This is [`Tri::source_weights`] followed by the varyings' interpolation, pixel by pixel
//! with the same operations in the same order (so the same bits), written over a run in
//! structure-of-arrays form: the triangle's constants are loaded once, the edge values step by
//! an exact integer per column (as [`Tri::scan_spans`] steps them), and the pixels of the run
//! are independent of each other, so the compiler vectorises the loop and the processor
//! overlaps its divisions and square roots. A pixel alone ([`Tri::source_weights`] and
//! [`interpolate`]) is what the judged render's moved points use; a test holds the two to the
//! same bits.

use glam::{DVec3, Vec3};
use umbra_case::{Geometry, LightKind, LightSetup};

use crate::raster::Tri;

/// One run's surface points, one entry per pixel (structure of arrays).
#[derive(Debug, Default)]
pub struct Surfaces {
    /// World position, per axis.
    pub p: [Vec<f32>; 3],
    /// Unit normal (zero where the interpolated normal vanishes), per axis.
    pub n: [Vec<f32>; 3],
    /// Unit vector towards the eye, per axis.
    pub to_eye: [Vec<f32>; 3],
    /// Unit vector towards the light, per axis ([`LightSetup::to_light`]).
    pub to_light: [Vec<f32>; 3],
}

impl Surfaces {
    /// Pixel `k`'s position.
    pub fn position(&self, k: usize) -> Vec3 {
        Vec3::new(self.p[0][k], self.p[1][k], self.p[2][k])
    }

    /// Pixel `k`'s unit normal.
    pub fn normal(&self, k: usize) -> Vec3 {
        Vec3::new(self.n[0][k], self.n[1][k], self.n[2][k])
    }

    /// Pixel `k`'s unit vector towards the eye.
    pub fn eye_dir(&self, k: usize) -> Vec3 {
        Vec3::new(self.to_eye[0][k], self.to_eye[1][k], self.to_eye[2][k])
    }

    /// Pixel `k`'s unit vector towards the light.
    pub fn light_dir(&self, k: usize) -> Vec3 {
        Vec3::new(
            self.to_light[0][k],
            self.to_light[1][k],
            self.to_light[2][k],
        )
    }

    /// How many pixels the run has.
    pub fn len(&self) -> usize {
        self.p[0].len()
    }

    /// Whether the run is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The surface points of the `len` pixel centres of raster row `y` from column `x0` on,
    /// every one covered by `tri` (set up from source triangle `tri.source` of `geo`), seen
    /// from `eye` and lit by `light`.
    #[allow(clippy::too_many_arguments)]
    pub fn fill(
        &mut self,
        tri: &Tri,
        geo: &Geometry,
        x0: i32,
        y: i32,
        len: usize,
        eye: Vec3,
        light: &LightSetup,
    ) {
        for v in self
            .p
            .iter_mut()
            .chain(&mut self.n)
            .chain(&mut self.to_eye)
            .chain(&mut self.to_light)
        {
            v.clear();
            v.resize(len, 0.0);
        }
        // The edge values at the first centre and their exact step per column: integers below
        // 2⁵³, so e + k·step is exact in f64 and equals the i64 value converted.
        let e = tri.fragment_at(x0, y).e.map(|v| v as f64);
        let step = tri.column_step().map(|v| v as f64);
        let a = tri.area as f64;
        let [q0, q1, q2] = tri.inv_w;
        let [w0, w1, w2] = tri.weights;
        let idx = geo.triangles[tri.source as usize].map(|k| k as usize);
        let [pa, pb, pc] = idx.map(|i| geo.positions[i]);
        let [na, nb, nc] = idx.map(|i| geo.normals[i]);
        let [px, py, pz] = &mut self.p;
        let [nx, ny, nz] = &mut self.n;
        let [ex, ey, ez] = &mut self.to_eye;
        let (px, py, pz) = (&mut px[..len], &mut py[..len], &mut pz[..len]);
        let (nx, ny, nz) = (&mut nx[..len], &mut ny[..len], &mut nz[..len]);
        let (ex, ey, ez) = (&mut ex[..len], &mut ey[..len], &mut ez[..len]);
        for k in 0..len {
            let kf = k as f64;
            // Tri::screen_bary, then Tri::source_weights.
            let b = [
                (e[0] + kf * step[0]) / a,
                (e[1] + kf * step[1]) / a,
                (e[2] + kf * step[2]) / a,
            ];
            let r = [b[0] * q0, b[1] * q1, b[2] * q2];
            let s = r[0] + r[1] + r[2];
            let wt = weighted(w0, w1, w2, r) / s;
            // interpolate: the f32 varyings.
            let (fx, fy, fz) = (wt.x as f32, wt.y as f32, wt.z as f32);
            let p = pa * fx + pb * fy + pc * fz;
            let n = (na * fx + nb * fy + nc * fz).normalize_or_zero();
            let to_eye = (eye - p).normalize_or_zero();
            (px[k], py[k], pz[k]) = (p.x, p.y, p.z);
            (nx[k], ny[k], nz[k]) = (n.x, n.y, n.z);
            (ex[k], ey[k], ez[k]) = (to_eye.x, to_eye.y, to_eye.z);
        }
        let [lx, ly, lz] = &mut self.to_light;
        match light.kind {
            LightKind::Directional { towards, .. } => {
                lx.fill(towards.x);
                ly.fill(towards.y);
                lz.fill(towards.z);
            }
            LightKind::Spot { position } | LightKind::Point { position } => {
                for k in 0..len {
                    // LightSetup::to_light's arithmetic, with the position read from the run.
                    let l = (position - Vec3::new(self.p[0][k], self.p[1][k], self.p[2][k]))
                        .normalize();
                    (lx[k], ly[k], lz[k]) = (l.x, l.y, l.z);
                }
            }
        }
    }
}

/// w0·r0 + w1·r1 + w2·r2, as glam's DVec3 operators evaluate it.
#[inline(always)]
fn weighted(w0: DVec3, w1: DVec3, w2: DVec3, r: [f64; 3]) -> DVec3 {
    w0 * r[0] + w1 * r[1] + w2 * r[2]
}

/// The position and unit normal at weights `wt` on source triangle `t`'s vertices (the
/// varyings, interpolated in f32 from the f64 weights): one pixel of [`Surfaces::fill`].
pub fn interpolate(geo: &Geometry, t: usize, wt: DVec3) -> (Vec3, Vec3) {
    let wt = wt.as_vec3();
    let idx = geo.triangles[t].map(|k| k as usize);
    (
        geo.positions[idx[0]] * wt.x + geo.positions[idx[1]] * wt.y + geo.positions[idx[2]] * wt.z,
        (geo.normals[idx[0]] * wt.x + geo.normals[idx[1]] * wt.y + geo.normals[idx[2]] * wt.z)
            .normalize_or_zero(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{EdgeKind, Rasterizer};
    use glam::Vec4;
    use umbra_case::Convention;
    use umbra_case::format::Cull;

    /// Every pixel of every run equals the pixel computed alone (Tri::source_weights,
    /// interpolate, glam's normalize_or_zero), bit for bit, over random perspective
    /// triangles, clipped ones included, in both conventions.
    #[test]
    fn a_run_is_its_pixels_one_by_one() {
        let mut next = crate::test_rng::uniform(0x2545_f491_4f6c_dd1d);
        let mut checked = 0;
        for conv in [Convention::GL, Convention::ZERO_TO_ONE] {
            let r = Rasterizer {
                conv,
                width: 96,
                height: 64,
                cull: Cull::None,
                depth_clamp: false,
            };
            for _ in 0..300 {
                let positions: Vec<Vec3> = (0..3)
                    .map(|_| Vec3::new(next() * 40.0 - 20.0, next() * 40.0 - 20.0, next() * 9.0))
                    .collect();
                let normals: Vec<Vec3> = (0..3)
                    .map(|_| Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5))
                    .collect();
                let geo = Geometry {
                    positions: positions.clone(),
                    normals,
                    triangles: vec![[0, 1, 2]],
                    ..Geometry::default()
                };
                let clip: [Vec4; 3] = std::array::from_fn(|i| {
                    let p = positions[i];
                    Vec4::new(p.x * 0.1, p.y * 0.1, p.z * 0.2 - 0.3, 0.5 + p.z * 0.3)
                });
                let mut tris = Vec::new();
                r.setup(clip, 0, [EdgeKind::Open; 3], &mut tris);
                let eye = Vec3::new(next() * 9.0, next() * 9.0, 30.0);
                let position = Vec3::new(next() * 9.0, 20.0, next() * 9.0);
                let towards = Vec3::new(next(), 1.0, next()).normalize();
                let lights = [
                    LightKind::Directional { towards, position },
                    LightKind::Spot { position },
                    LightKind::Point { position },
                ]
                .map(|kind| LightSetup {
                    kind,
                    views: Vec::new(),
                    cascading: None,
                });
                let mut s = Surfaces::default();
                for (t, light) in tris.iter().zip(lights.iter().cycle()) {
                    t.scan_spans(0..64, |span| {
                        s.fill(t, &geo, span.x, span.y, span.len, eye, light);
                        for k in 0..span.len {
                            let f = t.fragment_at(span.x + k as i32, span.y);
                            let (p, n) = interpolate(&geo, 0, t.source_weights(f));
                            let e = (eye - p).normalize_or_zero();
                            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                            assert_eq!(bits(s.position(k)), bits(p));
                            assert_eq!(bits(s.normal(k)), bits(n));
                            assert_eq!(bits(s.eye_dir(k)), bits(e));
                            assert_eq!(bits(s.light_dir(k)), bits(light.to_light(p)));
                            checked += 1;
                        }
                    });
                }
            }
        }
        assert!(checked > 20_000, "{checked}");
    }
}
