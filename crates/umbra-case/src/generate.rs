//! Generated cases: valid scenes drawn at random from a seed, across the whole case format,
//! for soaking the judge on scenes it was not developed against (`umbra soak`).
//!
//! The catalogue under `cases/` is the set the tolerance model was developed against, so a
//! model that is too tight for some technique can pass all of it and still fail a correct
//! driver on the first scene a user writes. The generator draws what users write: a floor
//! and two to five boxes, spheres and meshes (closed and open) with transforms, one light of
//! each kind, and every field of the technique (format, filter, compare, each bias form alone
//! and combined, cull, bias-matrix order, attachments, outside policy, guard, depth order),
//! the shading models, small sweeps, scene offsets and map sizes. Every draw is a valid case
//! (a test validates thousands), and the same seed gives the same cases on every machine: the
//! generator uses its own integer generator ([`Rng`]) and writes numbers rounded to a few
//! decimals, so the JSON is readable and round-trips exactly.
//!
//! Sizes are kept small (a 200×150 view, maps of 128² to 1024²) so a soak of a thousand cases
//! on every backend takes minutes, not hours: what a soak looks for is a wrong tolerance, and
//! that shows on small frames as well as on large ones.

use std::collections::BTreeMap;

use crate::format::*;
use crate::math::{cos, sin};

/// A small deterministic generator (SplitMix64): the same seed gives the same cases
/// everywhere, with no dependency.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x005E_ED0F_0B5C_u64)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi), rounded to `digits` decimals.
    fn range(&mut self, lo: f64, hi: f64, digits: i32) -> f32 {
        round(lo + (hi - lo) * self.unit(), digits)
    }

    /// Log-uniform in [lo, hi), rounded to 3 significant digits.
    fn log_range(&mut self, lo: f64, hi: f64) -> f32 {
        let x = crate::math::exp(
            crate::math::ln(lo) + (crate::math::ln(hi) - crate::math::ln(lo)) * self.unit(),
        );
        let digits = 2 - crate::math::log10(x).floor() as i32;
        round(x, digits)
    }

    /// A whole number in [lo, hi].
    fn int(&mut self, lo: u32, hi: u32) -> u32 {
        lo + (self.next_u64() % u64::from(hi - lo + 1)) as u32
    }

    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// One of `items`, uniformly.
    fn pick<T: Clone>(&mut self, items: &[T]) -> T {
        items[(self.next_u64() % items.len() as u64) as usize].clone()
    }
}

fn round(x: f64, digits: i32) -> f32 {
    let k = 10f64.powi(digits);
    ((x * k).round() / k) as f32
}

/// The `count` cases of seed `seed`, named `soak-SEED-K`. Case `k` depends only on `seed`
/// and `k`, so a soak of 100 cases is the first 100 of a soak of 1000.
pub fn cases(seed: u64, count: usize) -> Vec<Case> {
    (0..count).map(|k| case(seed, k)).collect()
}

/// Case `k` of seed `seed`.
pub fn case(seed: u64, k: usize) -> Case {
    let mut rng = Rng::new(seed.wrapping_mul(0x1000_0000_01B3) ^ (k as u64).wrapping_mul(0x9E37));
    // Warm the generator so that neighbouring (seed, k) pairs start far apart.
    for _ in 0..4 {
        rng.next_u64();
    }
    let mut g = Gen { rng };
    g.case(format!("soak-{seed}-{k}"))
}

struct Gen {
    rng: Rng,
}

/// The scene's footprint: objects lie within this half-width around the origin.
const SPREAD: f64 = 4.0;

impl Gen {
    fn case(&mut self, name: String) -> Case {
        let scene = self.scene();
        let light = self.light();
        let point = matches!(light, Light::Point(_));
        let camera = self.camera();
        let shadow = self.shadow(point);
        let shading = self.shading();
        let mut case = Case {
            about: String::new(),
            name,
            scene,
            camera,
            // The one drawn light (`lights[0]` below, until `more_lights` may add others).
            lights: vec![light],
            shadow,
            shading,
            sweep: BTreeMap::new(),
            expect: Expect::default(),
        };
        if self.rng.chance(0.12) {
            self.sweep(&mut case);
        }
        if self.rng.chance(0.1) {
            let other = match case.shadow.attachments {
                Attachments::DepthOnly => "with_color",
                Attachments::WithColor => "depth_only",
            };
            case.expect.twins.push(Twin {
                name: "attachments".into(),
                set: BTreeMap::from([("shadow.attachments".into(), other.into())]),
                agree: TwinAgree::Identical,
            });
        }
        // Drawn last and only where the technique allows levels, so that every other case of
        // a seed is the one it gave before mipmapped maps existed.
        let s = &case.shadow;
        if !point
            && s.compare == Compare::Hardware
            && !matches!(s.filter, Filter::Pcf(_))
            && !s.filter.shader_taps()
            && s.size.iter().all(|n| n.is_power_of_two())
            && self.rng.chance(0.3)
        {
            case.shadow.mipmaps = Some(Mipmaps {
                levels: self.rng.int(2, 6),
                filter: self.rng.pick(&[MipFilter::Nearest, MipFilter::Linear]),
                source: if self.rng.chance(0.25) {
                    MipSource::Averaged
                } else {
                    MipSource::Rendered
                },
            });
        }
        // Cascades, drawn after everything else for the same reason, on a directional light
        // whose map has no levels.
        self.cascades(&mut case);
        // The light's colour and intensity and the clear colour, drawn last for the same
        // reason: a tinted light in a quarter of the cases (an intensity above 1 in a third
        // of those, where lit colours saturate), a clear colour in a fifth.
        if self.rng.chance(0.25) {
            let color = [
                self.rng.range(0.3, 1.0, 2),
                self.rng.range(0.3, 1.0, 2),
                self.rng.range(0.3, 1.0, 2),
            ];
            let intensity = if self.rng.chance(0.33) {
                self.rng.range(1.0, 3.0, 2)
            } else {
                self.rng.range(0.5, 1.0, 2)
            };
            match &mut case.lights[0] {
                Light::Directional(d) => (d.color, d.intensity) = (color, intensity),
                Light::Spot(l) => (l.color, l.intensity) = (color, intensity),
                Light::Point(l) => (l.color, l.intensity) = (color, intensity),
            }
        }
        if self.rng.chance(0.2) {
            case.camera.clear = [
                self.rng.range(0.0, 1.0, 2),
                self.rng.range(0.0, 1.0, 2),
                self.rng.range(0.0, 1.0, 2),
            ];
        }
        // Lit-pass culling, drawn last too: back faces in a sixth of the cases, front faces
        // in a twentieth (the insides of boxes and spheres show).
        let r = self.rng.unit();
        case.camera.cull = if r < 0.05 {
            Cull::Front
        } else if r < 0.22 {
            Cull::Back
        } else {
            Cull::None
        };
        // The shadow pass's inclusive depth function in a third of the cases, drawn last
        // too (wgpu's example and many engines use LEQUAL).
        if self.rng.chance(0.33) {
            case.shadow.depth_func = Some(match case.shadow.depth_order {
                DepthOrder::Forward => DepthFunc::LessEqual,
                DepthOrder::Reversed => DepthFunc::GreaterEqual,
            });
        }
        // An sRGB colour target in a fifth of the cases, drawn last too.
        if self.rng.chance(0.2) {
            case.camera.color_format = ColorFormat::Srgb8Alpha8;
        }
        self.more_lights(&mut case);
        case.about = about(&case);
        case
    }

    /// Several lights in a seventh of the cases (drawn last too), where the format allows
    /// them: dimmed shading, no sweep (its paths name `light`), no cascades. One or two more
    /// lights of any kind (a point light only on a square map), tinted and dimmer, so that
    /// sums saturate less often; their maps in one 2D array in half the cases that have no
    /// point light and no mip levels.
    fn more_lights(&mut self, case: &mut Case) {
        let cascaded = matches!(&case.lights[0], Light::Directional(d) if d.cascades.is_some());
        if !self.rng.chance(0.15)
            || case.shading.model != ShadingModel::Dimmed
            || !case.sweep.is_empty()
            || cascaded
        {
            return;
        }
        let square = case.shadow.size[0] == case.shadow.size[1];
        let mut lights = vec![case.lights[0].clone()];
        for _ in 0..self.rng.int(1, 2) {
            let mut light = self.light();
            // A point light's cube map needs square faces, has no mip levels and no Castano
            // or Vogel filter.
            let cube_fits =
                square && case.shadow.mipmaps.is_none() && !case.shadow.filter.shader_taps();
            while matches!(light, Light::Point(_)) && !cube_fits {
                light = self.light();
            }
            let color = [
                self.rng.range(0.3, 1.0, 2),
                self.rng.range(0.3, 1.0, 2),
                self.rng.range(0.3, 1.0, 2),
            ];
            let intensity = self.rng.range(0.3, 0.8, 2);
            match &mut light {
                Light::Directional(d) => (d.color, d.intensity) = (color, intensity),
                Light::Spot(l) => (l.color, l.intensity) = (color, intensity),
                Light::Point(l) => (l.color, l.intensity) = (color, intensity),
            }
            lights.push(light);
        }
        let points = lights
            .iter()
            .filter(|l| matches!(l, Light::Point(_)))
            .count();
        if points == 0 && case.shadow.mipmaps.is_none() && self.rng.chance(0.5) {
            case.shadow.placement = Placement::Array;
        } else if points == lights.len() && case.shadow.mipmaps.is_none() && self.rng.chance(0.5) {
            case.shadow.placement = Placement::CubeArray;
        }
        case.lights = lights;
    }

    fn scene(&mut self) -> Scene {
        let mut objects = vec![self.floor()];
        for _ in 0..self.rng.int(2, 5) {
            let o = match self.rng.int(0, 9) {
                0..=3 => self.cuboid(),
                4..=6 => self.sphere(),
                _ => self.mesh(),
            };
            objects.push(o);
        }
        let offset = if self.rng.chance(0.08) {
            let magnitude = self.rng.pick(&[1e3, 1e4, 3e4]);
            [
                round(magnitude * (0.5 + self.rng.unit()), 1),
                round(magnitude * 0.1 * self.rng.unit(), 1),
                round(-magnitude * self.rng.unit(), 1),
            ]
        } else {
            [0.0; 3]
        };
        Scene { objects, offset }
    }

    fn floor(&mut self) -> Object {
        let tilt = if self.rng.chance(0.2) {
            self.rng.range(-0.25, 0.25, 3)
        } else {
            0.0
        };
        let half = self.rng.range(7.0, 16.0, 1);
        let half_extent = if self.rng.chance(0.3) {
            Extent::Rect([half, self.rng.range(7.0, 16.0, 1)])
        } else {
            Extent::Square(half)
        };
        Object::Plane(Plane {
            point: [0.0, 0.0, 0.0],
            normal: [tilt, 1.0, 0.0],
            half_extent,
            color: self.color(),
            transform: None,
        })
    }

    /// A point above the floor within the scene's footprint, `lift` above its surface.
    fn spot_on_floor(&mut self, lift: f32) -> V3 {
        [
            self.rng.range(-SPREAD, SPREAD, 2),
            lift + if self.rng.chance(0.3) {
                self.rng.range(0.2, 2.5, 2)
            } else {
                0.0
            },
            self.rng.range(-SPREAD, SPREAD, 2),
        ]
    }

    fn cuboid(&mut self) -> Object {
        let size = [
            self.rng.range(0.3, 3.0, 2),
            self.rng.range(0.3, 3.0, 2),
            self.rng.range(0.3, 3.0, 2),
        ];
        let (center, transform) = self.place(size[1] * 0.5);
        Object::Box(BoxShape {
            center,
            size,
            color: self.color(),
            transform,
        })
    }

    fn sphere(&mut self) -> Object {
        let radius = self.rng.range(0.25, 1.5, 2);
        let (center, transform) = self.place(radius);
        Object::Sphere(Sphere {
            center,
            radius,
            segments: self.rng.pick(&[6, 8, 12, 16, 24, 32]),
            color: self.color(),
            transform,
        })
    }

    /// Where an object of half height `half` goes: resting on the floor (or floating above
    /// it) in world coordinates, or built at the origin and placed by a transform.
    fn place(&mut self, half: f32) -> (V3, Option<Transform>) {
        let at = self.spot_on_floor(half);
        if !self.rng.chance(0.5) {
            return (at, None);
        }
        let rotate_deg = self.rng.chance(0.8).then(|| Rotation {
            axis: self.axis(),
            angle: self.rng.range(-180.0, 180.0, 1),
        });
        let scale = match self.rng.int(0, 3) {
            0 => Scale::PerAxis([
                self.rng.range(0.5, 1.5, 2),
                self.rng.range(0.5, 1.5, 2),
                self.rng.range(0.5, 1.5, 2),
            ]),
            1 => Scale::Uniform(self.rng.range(0.5, 1.5, 2)),
            _ => Scale::Uniform(1.0),
        };
        (
            [0.0; 3],
            Some(Transform {
                translate: at,
                rotate_deg,
                scale,
            }),
        )
    }

    fn axis(&mut self) -> V3 {
        loop {
            let a = [
                self.rng.range(-1.0, 1.0, 2),
                self.rng.range(-1.0, 1.0, 2),
                self.rng.range(-1.0, 1.0, 2),
            ];
            if a.iter().map(|x| x * x).sum::<f32>() > 0.05 {
                return a;
            }
        }
    }

    /// A closed tetrahedron or wedge, or an open bent sheet, counter-clockwise from outside.
    fn mesh(&mut self) -> Object {
        let s = self.rng.range(0.5, 2.0, 2);
        let (positions, triangles): (Vec<V3>, Vec<[u32; 3]>) = match self.rng.int(0, 2) {
            0 => {
                // A tetrahedron with a random apex over a triangular base.
                let apex = [
                    self.rng.range(-0.3, 0.3, 2) * s,
                    self.rng.range(0.6, 1.5, 2) * s,
                    self.rng.range(-0.3, 0.3, 2) * s,
                ];
                let p = vec![[-s, 0.0, -s * 0.6], [s, 0.0, -s * 0.6], [0.0, 0.0, s], apex];
                (
                    p.clone(),
                    outward(&p, &[[0, 1, 2], [0, 1, 3], [1, 2, 3], [2, 0, 3]]),
                )
            }
            1 => {
                // A wedge (a ramp): a triangular prism.
                let h = self.rng.range(0.3, 1.5, 2) * s;
                let p = vec![
                    [-s, 0.0, -s],
                    [s, 0.0, -s],
                    [s, 0.0, s],
                    [-s, 0.0, s],
                    [-s, h, s],
                    [s, h, s],
                ];
                let t = [
                    [0, 1, 2],
                    [0, 2, 3],
                    [3, 2, 5],
                    [3, 5, 4],
                    [0, 4, 5],
                    [0, 5, 1],
                    [0, 3, 4],
                    [1, 5, 2],
                ];
                (p.clone(), outward(&p, &t))
            }
            _ => {
                // An open sheet folded along its middle (both sides lit and shadowed).
                let fold = self.rng.range(0.2, 1.2, 2) * s;
                let p = vec![
                    [-s, 0.2, -s],
                    [0.0, fold, -s],
                    [s, 0.2, -s],
                    [-s, 0.2, s],
                    [0.0, fold, s],
                    [s, 0.2, s],
                ];
                (p, vec![[0, 3, 4], [0, 4, 1], [1, 4, 5], [1, 5, 2]])
            }
        };
        let at = self.spot_on_floor(0.0);
        let rotate_deg = self.rng.chance(0.7).then(|| Rotation {
            axis: [0.0, 1.0, 0.0],
            angle: self.rng.range(-180.0, 180.0, 1),
        });
        Object::Mesh(Mesh {
            positions,
            triangles,
            color: self.color(),
            transform: Some(Transform {
                translate: at,
                rotate_deg,
                scale: Scale::Uniform(1.0),
            }),
        })
    }

    fn color(&mut self) -> V3 {
        [
            self.rng.range(0.2, 0.95, 2),
            self.rng.range(0.2, 0.95, 2),
            self.rng.range(0.2, 0.95, 2),
        ]
    }

    fn camera(&mut self) -> Camera {
        let azimuth = self.rng.unit() * std::f64::consts::TAU;
        let elevation = self.rng.range(20.0, 70.0, 1).to_radians() as f64;
        let distance = f64::from(self.rng.range(11.0, 22.0, 1));
        let eye = [
            round(distance * cos(elevation) * sin(azimuth), 2),
            round(distance * sin(elevation), 2),
            round(distance * cos(elevation) * cos(azimuth), 2),
        ];
        let size = if self.rng.chance(0.85) {
            [200, 150]
        } else {
            self.rng.pick(&[[160, 120], [240, 180], [150, 200]])
        };
        Camera {
            eye,
            target: [
                self.rng.range(-1.5, 1.5, 2),
                self.rng.range(0.0, 1.5, 2),
                self.rng.range(-1.5, 1.5, 2),
            ],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: self.rng.range(35.0, 60.0, 0),
            near: self.rng.range(0.3, 1.0, 2),
            far: self.rng.range(60.0, 100.0, 0),
            size,
            clear: [0.0; 3],
            cull: Cull::None,
            color_format: ColorFormat::Rgba8,
        }
    }

    fn light(&mut self) -> Light {
        match self.rng.int(0, 2) {
            0 => {
                let ortho = self.rng.chance(0.4).then(|| {
                    let half = self.rng.range(7.0, 16.0, 1);
                    Ortho {
                        left: -half,
                        right: half,
                        bottom: -half,
                        top: half,
                        near: self.rng.range(0.1, 20.0, 1),
                        far: self.rng.range(60.0, 110.0, 0),
                    }
                });
                let fit = ortho.is_none().then_some(Fit::Scene);
                let target = [
                    self.rng.range(-1.0, 1.0, 2),
                    self.rng.range(0.0, 1.0, 2),
                    self.rng.range(-1.0, 1.0, 2),
                ];
                let by_angles = self.rng.chance(0.6);
                let (position, azimuth_deg, elevation_deg) = if by_angles {
                    (
                        None,
                        Some(self.rng.range(-180.0, 180.0, 1)),
                        Some(self.rng.range(15.0, 85.0, 1)),
                    )
                } else {
                    let a = self.rng.unit() * std::f64::consts::TAU;
                    let e = f64::from(self.rng.range(20.0, 80.0, 1)).to_radians();
                    let d = 45.0;
                    (
                        Some([
                            round(d * cos(e) * sin(a), 2),
                            round(d * sin(e), 2),
                            round(d * cos(e) * cos(a), 2),
                        ]),
                        None,
                        None,
                    )
                };
                Light::Directional(Directional {
                    position,
                    azimuth_deg,
                    elevation_deg,
                    distance: 50.0,
                    target,
                    up: [0.0, 1.0, 0.0],
                    ortho,
                    fit,
                    cascades: None,
                    color: [1.0; 3],
                    intensity: 1.0,
                })
            }
            1 => {
                let height = self.rng.range(6.0, 18.0, 1);
                let position = [
                    self.rng.range(-10.0, 10.0, 1),
                    height,
                    self.rng.range(-10.0, 10.0, 1),
                ];
                Light::Spot(Spot {
                    position,
                    target: [
                        self.rng.range(-2.0, 2.0, 2),
                        0.0,
                        self.rng.range(-2.0, 2.0, 2),
                    ],
                    up: [0.0, 1.0, 0.0],
                    fov_y_deg: self.rng.range(25.0, 95.0, 0),
                    near: self.rng.range(0.5, 3.0, 1),
                    far: self.rng.range(30.0, 80.0, 0),
                    color: [1.0; 3],
                    intensity: 1.0,
                })
            }
            _ => Light::Point(Point {
                position: [
                    self.rng.range(-2.0, 2.0, 2),
                    self.rng.range(3.2, 7.0, 2),
                    self.rng.range(-2.0, 2.0, 2),
                ],
                near: self.rng.range(0.05, 0.5, 2),
                far: self.rng.range(20.0, 60.0, 0),
                color: [1.0; 3],
                intensity: 1.0,
            }),
        }
    }

    fn shadow(&mut self, point: bool) -> Shadow {
        let side = |g: &mut Gen| g.rng.pick(&[256, 384, 512, 768, 1024]);
        let size = if point {
            let s = self.rng.pick(&[128, 192, 256, 384, 512]);
            [s, s]
        } else if self.rng.chance(0.7) {
            let s = side(self);
            [s, s]
        } else {
            [side(self), side(self)]
        };
        let filter = match self.rng.int(0, 9) {
            0..=3 => Filter::Nearest,
            4..=6 => Filter::Linear,
            // Bevy's default on its directional and spot maps.
            7 if !point => Filter::Castano13,
            // three.js's PCFShadowMap (r187) on its directional and spot maps.
            8 if !point => Filter::Vogel5,
            _ => Filter::Pcf(self.rng.int(2, 5)),
        };
        Shadow {
            size,
            format: self.rng.pick(&[
                DepthFormat::Unsized,
                DepthFormat::Depth16,
                DepthFormat::Depth24,
                DepthFormat::Depth32f,
            ]),
            filter,
            compare: if self.rng.chance(0.6) {
                Compare::Hardware
            } else {
                Compare::Manual
            },
            bias: self.bias(),
            beyond_far: BeyondFar::Compare,
            cull: self.rng.pick(&[Cull::None, Cull::Back, Cull::Front]),
            bias_matrix: self
                .rng
                .pick(&[BiasMatrix::BeforeDivide, BiasMatrix::AfterDivide]),
            attachments: if self.rng.chance(0.8) {
                Attachments::DepthOnly
            } else {
                Attachments::WithColor
            },
            outside: self.rng.pick(&[
                Outside::Lit,
                Outside::Border,
                Outside::ClampToEdge,
                Outside::Repeat,
            ]),
            guard_behind_light: self.rng.chance(0.8),
            depth_order: if self.rng.chance(0.7) {
                DepthOrder::Forward
            } else {
                DepthOrder::Reversed
            },
            // Drawn last, so that the fields above are what they were before it existed.
            depth_clamp: self.rng.chance(0.15),
            // Drawn at the end of the case (`case`), after every earlier field.
            depth_func: None,
            mipmaps: None,
            placement: Placement::Separate,
        }
    }

    /// A directional light's cascades (a fifth of those whose map has no levels), with
    /// Bevy's forms in some: drawn after everything else, so that only cascaded cases'
    /// streams move when they change.
    fn cascades(&mut self, case: &mut Case) {
        if let Light::Directional(d) = &mut case.lights[0] {
            if case.shadow.mipmaps.is_none() && self.rng.chance(0.2) {
                let split = self.rng.pick(&[
                    SplitScheme::Uniform,
                    SplitScheme::Logarithmic,
                    SplitScheme::Practical,
                    SplitScheme::Fractions,
                ]);
                let count = self.rng.int(1, 4);
                let at = (split == SplitScheme::Fractions).then(|| {
                    (1..count)
                        .map(|k| {
                            let jitter = self.rng.range(-0.3, 0.3, 2);
                            round((f64::from(k) + f64::from(jitter)) / f64::from(count), 3)
                        })
                        .collect()
                });
                let lambda = (split == SplitScheme::Practical).then(|| self.rng.range(0.0, 1.0, 2));
                let (near, far) = (case.camera.near, case.camera.far);
                let distance = self.rng.chance(0.3).then(|| {
                    round(
                        f64::from(near + (far - near) * self.rng.range(0.3, 0.9, 2)),
                        2,
                    )
                });
                let blend = if self.rng.chance(0.3) {
                    self.rng.range(0.05, 0.3, 2)
                } else {
                    0.0
                };
                let mut c = Cascades {
                    count,
                    split,
                    lambda,
                    at,
                    distance,
                    blend,
                    blend_of: BlendOf::Range,
                    fit: CascadeFit::Box,
                };
                // Bevy's forms, drawn after the rest of the cascade (only cascaded cases'
                // streams move): a band of the far bound where every band stays within half
                // its range, the stable fit, and the world and texel offsets.
                if blend > 0.0 && self.rng.chance(0.5) {
                    let splits = crate::light::cascade_splits(&c, near, far);
                    let fits = splits
                        .windows(2)
                        .take(splits.len().saturating_sub(2))
                        .all(|w| blend * w[1] <= 0.5 * (w[1] - w[0]));
                    if fits {
                        c.blend_of = BlendOf::Far;
                    }
                }
                if self.rng.chance(0.4) {
                    c.fit = CascadeFit::Stable;
                }
                if self.rng.chance(0.3) {
                    case.shadow.bias.normal_offset_texels = self.rng.range(0.5, 3.0, 2);
                    case.shadow.bias.light_offset = self.rng.log_range(1e-3, 5e-2);
                }
                d.cascades = Some(c);
                d.ortho = None;
                d.fit = None;
            }
        }
    }

    /// No bias at all (a quarter of the cases: acne is what a model's ties must hold), or one
    /// to three of the forms, each drawn over the range programs use.
    fn bias(&mut self) -> Bias {
        let mut b = Bias::default();
        if self.rng.chance(0.25) {
            return b;
        }
        let forms = self.rng.int(1, 3);
        for _ in 0..forms {
            match self.rng.int(0, 5) {
                0 => b.constant = self.rng.log_range(1e-5, 5e-3),
                1 | 2 => {
                    let units = if self.rng.chance(0.85) {
                        self.rng.int(0, 8) as f32
                    } else {
                        self.rng.range(0.1, 8.0, 3)
                    };
                    b.polygon_offset = [self.rng.range(0.0, 4.0, 1), units];
                    if self.rng.chance(0.3) {
                        b.polygon_offset_clamp = self.rng.log_range(1e-5, 1e-2);
                    }
                }
                3 => {
                    b.slope = Some(SlopeBias {
                        scale: self.rng.log_range(1e-4, 5e-3),
                        max: self.rng.log_range(1e-3, 2e-2),
                    })
                }
                4 => {
                    b.n_dot_l = Some(NdotLBias {
                        scale: self.rng.log_range(1e-3, 5e-2),
                        min: self.rng.log_range(1e-4, 5e-3),
                        light: LightVector::Direction,
                    })
                }
                _ => b.normal_offset = self.rng.log_range(5e-3, 0.1),
            }
        }
        b
    }

    fn shading(&mut self) -> Shading {
        let mut s = Shading {
            ambient: self.rng.range(0.05, 0.35, 2),
            ..Shading::default()
        };
        if self.rng.chance(0.3) {
            s.model = ShadingModel::Classic;
            s.shadowed_factor = self.rng.range(0.2, 0.7, 2);
        } else {
            s.dimming = self.rng.range(0.2, 0.6, 2);
            s.specular = self.rng.range(0.0, 0.5, 2);
            s.shininess = self.rng.pick(&[4.0, 16.0, 32.0, 64.0]);
        }
        s
    }

    /// Two points along one axis the case can sweep.
    fn sweep(&mut self, case: &mut Case) {
        let mut axes: Vec<(&str, Vec<serde_json::Value>)> = vec![
            ("shadow.size[0]", vec![256.into(), 512.into()]),
            (
                "scene.offset",
                vec![
                    serde_json::json!([0, 0, 0]),
                    serde_json::json!([1000, 0, -500]),
                ],
            ),
            ("shadow.bias.constant", vec![0.into(), 0.0005.into()]),
        ];
        if let Light::Directional(d) = &case.lights[0] {
            if d.azimuth_deg.is_some() {
                axes.push((
                    "light.directional.azimuth_deg",
                    vec![(-60).into(), 30.into()],
                ));
            }
        }
        if matches!(case.lights[0], Light::Point(_)) {
            // A cube map's faces must stay square.
            axes.retain(|(p, _)| !p.starts_with("shadow.size"));
        }
        let (path, values) = self.rng.pick(&axes);
        case.sweep.insert(
            path.to_string(),
            SweepAxis {
                from: None,
                to: None,
                steps: None,
                scale: SweepScale::Linear,
                values: Some(values),
            },
        );
    }
}

/// The triangles of a closed mesh reordered so that each faces away from the centroid.
fn outward(p: &[V3], tris: &[[u32; 3]]) -> Vec<[u32; 3]> {
    use glam::Vec3;
    let c = p.iter().map(|v| Vec3::from(*v)).sum::<Vec3>() / p.len() as f32;
    tris.iter()
        .map(|&[a, b, d]| {
            let [pa, pb, pd] = [a, b, d].map(|i| Vec3::from(p[i as usize]));
            let n = (pb - pa).cross(pd - pa);
            if n.dot((pa + pb + pd) / 3.0 - c) >= 0.0 {
                [a, b, d]
            } else {
                [a, d, b]
            }
        })
        .collect()
}

/// One sentence saying what the case draws (the `about` every case has).
fn about(c: &Case) -> String {
    // The light drawn first (several lights add their count and placement at the end).
    let light = match c.lights[0] {
        Light::Directional(_) => "directional",
        Light::Spot(_) => "spot",
        Light::Point(_) => "point",
    };
    let s = &c.shadow;
    format!(
        "generated: {} objects, {light} light, {:?} {}x{} map, {:?} filter, {:?} compare, {} bias, cull {:?}, {:?}, outside {:?}, {:?} depth",
        c.scene.objects.len(),
        s.format,
        s.size[0],
        s.size[1],
        s.filter,
        s.compare,
        bias_forms(&s.bias),
        s.cull,
        s.bias_matrix,
        s.outside,
        s.depth_order,
    )
    .to_lowercase()
        + &s.mipmaps.map_or(String::new(), |m| {
            format!(
                ", {} mip levels {:?} between, {:?}",
                m.levels, m.filter, m.source
            )
            .to_lowercase()
        })
        + &match &c.lights[0] {
            Light::Directional(Directional {
                cascades: Some(k), ..
            }) => format!(", {} {:?} cascades", k.count, k.split).to_lowercase(),
            _ => String::new(),
        }
        + &s.depth_func
            .map_or(String::new(), |f| format!(", depth test {}", f.name()))
        + if c.camera.color_format.is_rgba8() {
            ""
        } else {
            ", srgb target"
        }
        + &if c.lights.len() == 1 {
            String::new()
        } else {
            format!(", {} lights, {} maps", c.lights.len(), s.placement.name())
        }
}

/// The bias forms a technique uses, as `constant+polygon_offset` (or `no`).
pub fn bias_forms(b: &Bias) -> String {
    let mut f = Vec::new();
    if b.constant != 0.0 {
        f.push("constant");
    }
    if b.polygon_offset != [0.0, 0.0] {
        f.push("polygon_offset");
    }
    if b.polygon_offset_clamp != 0.0 {
        f.push("clamp");
    }
    if b.slope.is_some() {
        f.push("slope");
    }
    if b.n_dot_l.is_some() {
        f.push("n_dot_l");
    }
    if b.normal_offset != 0.0 {
        f.push("normal_offset");
    }
    if b.normal_offset_texels != 0.0 {
        f.push("normal_offset_texels");
    }
    if b.light_offset != 0.0 {
        f.push("light_offset");
    }
    if f.is_empty() {
        "no".into()
    } else {
        f.join("+")
    }
}

/// Writes the `count` cases of `seed` as `DIR/soak-SEED-K.json`, making `dir` if it is not
/// there. It removes nothing: the caller gives it a directory of its own (a soak's new run
/// directory, the self-test's `umbra_owned::fresh` one), so no other case is run beside
/// them and no file of a user's is touched.
pub fn write_cases(dir: &std::path::Path, seed: u64, count: usize) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for case in cases(seed, count) {
        let text = to_json(&case);
        std::fs::write(dir.join(format!("{}.json", case.name)), text + "\n")?;
    }
    Ok(())
}

/// The JSON text of a generated case, as a user would write it (defaults included).
pub fn to_json(case: &Case) -> String {
    serde_json::to_string_pretty(case).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every generated case is valid, survives a round trip through its JSON, and the
    /// draws cover every value of every technique field.
    #[test]
    fn generated_cases_are_valid_and_cover_the_format() {
        let mut seen = std::collections::BTreeSet::new();
        for seed in [1u64, 2, 77] {
            for case in cases(seed, 400) {
                let text = to_json(&case);
                let file = std::path::Path::new("generated.json");
                let points = crate::load_str(&text, file)
                    .unwrap_or_else(|e| panic!("{} does not validate: {e}\n{text}", case.name));
                assert!(!points.is_empty());
                let back: Case = serde_json::from_str(&text).expect("round trip");
                assert_eq!(back, case, "{} changes through its JSON", case.name);
                let s = &case.shadow;
                seen.insert(format!("format {:?}", s.format));
                seen.insert(format!(
                    "filter {}",
                    match s.filter {
                        Filter::Pcf(_) => "pcf".into(),
                        f => format!("{f:?}"),
                    }
                ));
                seen.insert(format!("compare {:?}", s.compare));
                seen.insert(format!("cull {:?}", s.cull));
                seen.insert(format!("order {:?}", s.bias_matrix));
                seen.insert(format!("attachments {:?}", s.attachments));
                seen.insert(format!("outside {:?}", s.outside));
                seen.insert(format!("guard {}", s.guard_behind_light));
                seen.insert(format!("depth {:?}", s.depth_order));
                seen.insert(format!("clamp {}", s.depth_clamp));
                for form in bias_forms(&s.bias).split('+') {
                    seen.insert(format!("bias {form}"));
                }
                for light in &case.lights {
                    if let Light::Directional(d) = light {
                        if let Some(c) = &d.cascades {
                            seen.insert(format!("cascades {:?}", c.split));
                            if c.blend > 0.0 {
                                seen.insert("cascade blend".into());
                            }
                            if c.distance.is_some() {
                                seen.insert("cascade distance".into());
                            }
                            if c.blend_of == BlendOf::Far {
                                seen.insert("cascade band of the far bound".into());
                            }
                            if c.fit == CascadeFit::Stable {
                                seen.insert("cascade stable fit".into());
                            }
                        }
                    }
                    seen.insert(format!(
                        "light {}",
                        match light {
                            Light::Directional(_) => "directional",
                            Light::Spot(_) => "spot",
                            Light::Point(_) => "point",
                        }
                    ));
                    seen.insert(format!("shading {:?}", case.shading.model));
                    let radiance = light.radiance();
                    if radiance != [1.0; 3] {
                        seen.insert("tinted light".into());
                    }
                    if radiance.iter().any(|x| *x > 1.0) {
                        seen.insert("light above 1".into());
                    }
                }
                if case.camera.clear != [0.0; 3] {
                    seen.insert("clear colour".into());
                }
                seen.insert(format!("lit cull {:?}", case.camera.cull));
                seen.insert(format!(
                    "depth func inclusive {}",
                    case.shadow.depth_test().inclusive()
                ));
                seen.insert(format!("colour target {:?}", case.camera.color_format));
                for o in &case.scene.objects {
                    seen.insert(
                        match o {
                            Object::Plane(_) => "plane",
                            Object::Box(_) => "box",
                            Object::Sphere(_) => "sphere",
                            Object::Cylinder(_) => "cylinder",
                            Object::Mesh(_) => "mesh",
                        }
                        .to_string(),
                    );
                }
                if !case.sweep.is_empty() {
                    seen.insert("sweep".into());
                }
                if case.scene.offset != [0.0; 3] {
                    seen.insert("offset".into());
                }
            }
        }
        // 4 formats, 5 filters (Castano's and the Vogel disk among them), 2 compares, 3 culls, 2 orders, 2 attachments, 4 outside,
        // 2 guards, 2 depth orders, 2 depth clamps, 9 bias entries, 4 split schemes, a
        // cascade blend, distance, band of the far bound and stable fit, 3 lights, 2 shadings, a tinted light, one above 1, a
        // clear colour, 3 lit-pass culls, strict and inclusive depth functions, 2 colour
        // targets, 4 objects, sweep, offset.
        assert_eq!(
            seen.len(),
            4 + 5 + 2 + 3 + 2 + 2 + 4 + 2 + 2 + 2 + 9 + 4 + 4 + 3 + 2 + 3 + 3 + 2 + 2 + 4 + 2,
            "{seen:?}"
        );
    }

    /// The same seed and index give the same case; another index another one.
    #[test]
    fn generation_is_deterministic() {
        assert_eq!(case(5, 3), case(5, 3));
        assert_eq!(cases(5, 10)[7], case(5, 7));
        assert_ne!(case(5, 3).shadow, case(5, 4).shadow);
    }
}
