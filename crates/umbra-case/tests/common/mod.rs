//! Shared by the convention property tests: a deterministic generator, random light set-ups
//! with points inside their frustum, the exact f64 lookup and the rounding-error model
//! (Higham, "Accuracy and Stability of Numerical Algorithms", §3.1).

#![allow(dead_code)]

use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};
use umbra_case::{Convention, LookupMatrices};

pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        // xorshift64*: deterministic, no dependency.
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// f32 unit roundoff.
pub const U: f64 = 1.0 / (1u64 << 24) as f64;

/// γₙ = n·u/(1 − n·u).
pub fn gamma(n: f64) -> f64 {
    n * U / (1.0 - n * U)
}

pub fn abs_mat(m: DMat4) -> DMat4 {
    DMat4::from_cols(
        m.x_axis.abs(),
        m.y_axis.abs(),
        m.z_axis.abs(),
        m.w_axis.abs(),
    )
}

pub fn look_at_f64(eye: DVec3, target: DVec3, up: DVec3) -> DMat4 {
    let f = (target - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    DMat4::from_cols(
        DVec4::new(s.x, u.x, -f.x, 0.0),
        DVec4::new(s.y, u.y, -f.y, 0.0),
        DVec4::new(s.z, u.z, -f.z, 0.0),
        DVec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

/// A random light: perspective (even set-ups) or orthographic, looking at the ground.
pub struct Setup {
    pub view32: Mat4,
    pub view: DMat4,
    pub perspective: bool,
    pub fov: f64,
    pub aspect: f64,
    pub n: f64,
    pub f: f64,
    pub ortho: [f64; 6],
}

impl Setup {
    pub fn random(rng: &mut Rng, index: usize, size: [u32; 2]) -> Setup {
        let eye = DVec3::new(
            rng.range(-50.0, 50.0),
            rng.range(5.0, 60.0),
            rng.range(-50.0, 50.0),
        );
        let target = DVec3::new(rng.range(-5.0, 5.0), 0.0, rng.range(-5.0, 5.0));
        let view32 = umbra_case::conventions::look_at(eye.as_vec3(), target.as_vec3(), Vec3::Y);
        let view = look_at_f64(
            eye.as_vec3().as_dvec3(),
            target.as_vec3().as_dvec3(),
            DVec3::Y,
        );
        let perspective = index % 2 == 0;
        let (n, f) = if perspective {
            (rng.range(0.05, 2.0), rng.range(30.0, 500.0))
        } else {
            (rng.range(-5.0, 1.0), rng.range(40.0, 300.0))
        };
        let fov = rng.range(0.2, 2.5);
        let aspect = f64::from(size[0]) / f64::from(size[1]);
        let half = rng.range(2.0, 40.0);
        Setup {
            view32,
            view,
            perspective,
            fov,
            aspect,
            n,
            f,
            ortho: [-half * aspect, half * aspect, -half, half, n, f],
        }
    }

    /// The f32 projection in a convention.
    pub fn proj(&self, c: Convention) -> Mat4 {
        if self.perspective {
            c.perspective(
                self.fov as f32,
                self.aspect as f32,
                self.n as f32,
                self.f as f32,
            )
        } else {
            let o = self.ortho.map(|x| x as f32);
            c.orthographic(o[0], o[1], o[2], o[3], o[4], o[5])
        }
    }

    /// A world point (rounded to f32) inside the frustum: exact NDC in [−0.98, 0.98]², depth
    /// in (0.02, 0.98); with its exact GL texture coordinate and window depth.
    pub fn sample(&self, rng: &mut Rng) -> (Vec3, (f64, f64, f64)) {
        let (n, f) = (self.n, self.f);
        let (nx, ny, dz) = (
            rng.range(-0.98, 0.98),
            rng.range(-0.98, 0.98),
            rng.range(0.02, 0.98),
        );
        let z_eye = if self.perspective {
            -(f * n / (f - (f - n) * dz))
        } else {
            -(n + dz * (f - n))
        };
        let o = self.ortho;
        let (ex, ey) = if self.perspective {
            let t = (0.5 * self.fov).tan();
            (nx * -z_eye * t * self.aspect, ny * -z_eye * t)
        } else {
            (
                0.5 * (nx * (o[1] - o[0]) + o[1] + o[0]),
                0.5 * (ny * (o[3] - o[2]) + o[3] + o[2]),
            )
        };
        let world = self.view.inverse() * DVec4::new(ex, ey, z_eye, 1.0);
        let p = world.truncate().as_vec3();
        (p, self.exact(p.as_dvec3()))
    }

    /// Exact (f64) texture coordinate and window depth of `p` in the GL convention (v up);
    /// the zero-to-one convention's v is 1 − v.
    pub fn exact(&self, p: DVec3) -> (f64, f64, f64) {
        let e = self.view * p.extend(1.0);
        let (n, f) = (self.n, self.f);
        if self.perspective {
            let t = (0.5 * self.fov).tan();
            let (x, y) = (e.x / (-e.z * t * self.aspect), e.y / (-e.z * t));
            let d = f / (f - n) + f * n / ((f - n) * e.z);
            (0.5 * x + 0.5, 0.5 * y + 0.5, d)
        } else {
            let [l, r, b, tp, n, f] = self.ortho;
            let x = (2.0 * e.x - (r + l)) / (r - l);
            let y = (2.0 * e.y - (tp + b)) / (tp - b);
            (0.5 * x + 0.5, 0.5 * y + 0.5, (-e.z - n) / (f - n))
        }
    }

    /// The rounding bound of component `comp` (0 u, 1 v, 2 depth) of the lookup of `p`
    /// whose exact value is `value`, for the bias-matrix-before-divide path (see the note in
    /// conventions.rs): γ₈·(|B||P||V|·|p|)_comp/|w| + |value|·γ₈·(…)_w/|w| + 3u·|value| + u.
    pub fn bound(
        &self,
        c: Convention,
        m: &LookupMatrices,
        p: Vec3,
        comp: usize,
        value: f64,
    ) -> f64 {
        let full = abs_mat(c.bias_matrix().as_dmat4())
            * abs_mat(self.proj(c).as_dmat4())
            * abs_mat(self.view32.as_dmat4());
        let pa = p.as_dvec3().abs().extend(1.0);
        let row = full.row(comp).dot(pa);
        let wrow = full.row(3).dot(pa);
        let w = f64::from((m.light * p.extend(1.0)).w).abs();
        gamma(8.0) * (row + value.abs() * wrow) / w + 3.0 * U * value.abs() + U
    }
}
