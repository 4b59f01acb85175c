//! Mipmapped maps: the pixel's neighbours, the LOD the reference computes and the LODs a
//! conformant sampler may compute (derivatives, scale factor, precision), the levels each
//! reads, and the judged lookup as the hull of every level within reach.

use super::*;

/// The LOD's precision the judge allows each way ([`Lookup::lod_range`]): 2⁻⁴, Vulkan's
/// least mipmapPrecisionBits and the least dEQP's shadow tests accept.
const LOD_SLACK: f64 = 1.0 / 16.0;

/// A camera pixel's neighbours on the surface it shows, for a mipmapped lookup's
/// derivatives: `.0[j][i]` is the point and unit normal at pixel (x + i − 1, y + j − 1), on
/// the plane of the pixel's own triangle (as a quad's helper invocations extrapolate the
/// varyings). Each neighbour's lookup moves by its own normal's offset, as the shader's does.
#[derive(Clone, Copy, Debug)]
pub struct Neighbours(pub [[(Vec3, Vec3); 3]; 3]);

impl Lookup<'_> {
    /// Whether the map has mip levels: its lookups need the pixel's [`Neighbours`]
    /// ([`Lookup::visibility_mip`], [`Lookup::judged_mip`]).
    pub fn mipmapped(&self) -> bool {
        !self.levels.is_empty()
    }

    /// The level-0 texel coordinates (u·width, v·height) at the nine points of `nb`.
    pub(super) fn footprint(&self, nb: &Neighbours) -> [[DVec2; 3]; 3] {
        let [w, h] = self.shadow.size;
        nb.0.map(|row| {
            row.map(|(q, n)| {
                let c = self.probe_on(q, n, 0).0;
                DVec2::new(f64::from(c.u) * f64::from(w), f64::from(c.v) * f64::from(h))
            })
        })
    }

    /// The LOD the reference's sampler computes: λ = log₂ ρ with the specs' own
    /// ρ = max(|∂(s, t)/∂x|, |∂(s, t)/∂y|) in level-0 texels (GL 4.6 §8.14.1 eq. 8.7,
    /// Vulkan "Scale Factor Operation"), the derivatives as forward differences to the next
    /// pixel of the row and of the column.
    pub fn lod(&self, nb: &Neighbours) -> f64 {
        let t = self.footprint(nb);
        let dx = t[1][2] - t[1][1];
        let dy = t[2][1] - t[1][1];
        umbra_case::math::log2(dx.length().max(dy.length()))
    }

    /// The LODs a conformant sampler may compute at this pixel (a closed interval):
    ///
    /// - **Derivatives.** dFdx may be the difference to either horizontal neighbour in the
    ///   pixel's 2 × 2 quad ("fine"), or one difference shared by the quad, taken in either
    ///   of its rows ("coarse"); likewise dFdy (GLSL 4.60 §8.14.1, SPIR-V DPdx/DPdxFine/
    ///   DPdxCoarse, WGSL dpdx). Here every forward and backward difference of the pixel's
    ///   row and of the rows above and below (columns for y): each component of ∂s/∂x, ∂t/∂x,
    ///   ∂s/∂y, ∂t/∂y at its smallest and largest magnitude over them, independently.
    /// - **Scale factor.** GL lets ρ be any f with max(m_u, m_v) ≤ f ≤ m_u + m_v,
    ///   m_u = max(|∂s/∂x|, |∂s/∂y|), m_v likewise for t (GL 4.6 §8.14.1, the bounds below
    ///   eq. 8.8; GLES 3.2 §8.14.1 the same); Vulkan lets ρ_x be any f_x with
    ///   max(|∂s/∂x|, |∂t/∂x|) ≤ f_x ≤ √2·(|∂s/∂x| + |∂t/∂x|), likewise ρ_y, and ρ = max
    ///   (Vulkan, "Scale Factor Operation"). The lower bounds agree; neither upper bound
    ///   contains the other. The GL profile takes the larger of the two: dEQP's GLES
    ///   verifiers apply Vulkan's √2 rule to GL too since Khronos bug 16179
    ///   (tcu::computeLodBoundsFromDerivates), and zink is GL over a Vulkan sampler.
    /// - **Precision.** Vulkan: "the LOD must be computed with mipmapPrecisionBits of
    ///   accuracy", at least 4 (6 in Roadmap 2022); GL sets none. dEQP's 2D shadow tests
    ///   (es3fTextureShadowTests, vktTextureShadowTests) pass at 6 LOD bits and accept 4 with
    ///   a quality warning: λ ± 2⁻⁴ ([`LOD_SLACK`]), the least any of them accepts.
    /// - A derivative that is not finite (a neighbour at w = 0) leaves λ undefined: every
    ///   level.
    pub fn lod_range(&self, nb: &Neighbours) -> (f64, f64) {
        let t = self.footprint(nb);
        let mut dx = Vec::with_capacity(6);
        let mut dy = Vec::with_capacity(6);
        for (k, row) in t.iter().enumerate() {
            dx.push(row[2] - row[1]);
            dx.push(row[1] - row[0]);
            dy.push(t[2][k] - t[1][k]);
            dy.push(t[1][k] - t[0][k]);
        }
        let span = |v: &[DVec2], pick: fn(DVec2) -> f64| {
            v.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
                let a = pick(*d).abs();
                (lo.min(a), hi.max(a))
            })
        };
        if dx.iter().chain(&dy).any(|d| !d.is_finite()) {
            return (f64::NEG_INFINITY, f64::INFINITY);
        }
        let (sx, tx) = (span(&dx, |d| d.x), span(&dx, |d| d.y));
        let (sy, ty) = (span(&dy, |d| d.x), span(&dy, |d| d.y));
        let lo = sx.0.max(tx.0).max(sy.0).max(ty.0);
        let vulkan = std::f64::consts::SQRT_2 * (sx.1 + tx.1).max(sy.1 + ty.1);
        let hi = match self.profile.spec {
            Spec::Gl => vulkan.max(sx.1.max(sy.1) + tx.1.max(ty.1)),
            Spec::Vulkan => vulkan,
        };
        (
            umbra_case::math::log2(lo) - LOD_SLACK,
            umbra_case::math::log2(hi) + LOD_SLACK,
        )
    }

    /// The level the reference reads for NEAREST between levels at LOD `lod`, or the two it
    /// blends and the second's weight for LINEAR: level 0 (the magnification filter, the
    /// same filter here) for λ ≤ ½ or λ ≤ 0; otherwise GL's d = ⌈λ + ½⌉ − 1 (ties down)
    /// and ⌊λ⌋, ⌊λ⌋ + 1 with weight frac(λ) (GL 4.6 §8.14.3), clamped to the last level.
    pub(super) fn levels_at(&self, lod: f64) -> (usize, usize, f32) {
        let last = self.levels.len() - 1;
        let Some(m) = self.shadow.mipmaps else {
            return (0, 0, 0.0);
        };
        match m.filter {
            MipFilter::Nearest => {
                let d = if lod <= 0.5 {
                    0
                } else {
                    ((lod + 0.5).ceil() - 1.0) as usize
                };
                (d.min(last), d.min(last), 0.0)
            }
            MipFilter::Linear => {
                let lod = lod.max(0.0);
                let d = (lod.floor() as usize).min(last);
                if d == last {
                    (last, last, 0.0)
                } else {
                    (d, d + 1, (lod - lod.floor()) as f32)
                }
            }
        }
    }

    /// Every level a conformant sampler may read for a LOD in [`lo`, `hi`] (first, last).
    pub(super) fn levels_between(&self, (lo, hi): (f64, f64)) -> (usize, usize) {
        let last = self.levels.len() - 1;
        let Some(m) = self.shadow.mipmaps else {
            return (0, 0);
        };
        let (a, b) = match m.filter {
            // Either rounding of a tie (Vulkan allows both; GL prefers down).
            MipFilter::Nearest => (
                ((lo + 0.5).ceil() - 1.0).max(0.0),
                (hi + 0.5).floor().max(0.0),
            ),
            MipFilter::Linear => (lo.max(0.0).floor(), hi.max(0.0).floor() + 1.0),
        };
        ((a as usize).min(last), (b as usize).min(last))
    }

    /// [`Lookup::visibility`] of a mipmapped map at a pixel whose neighbours are `nb`.
    pub fn visibility_mip(&self, p: Vec3, n: Vec3, nb: &Neighbours) -> f32 {
        let (a, b, f) = self.levels_at(self.lod(nb));
        let va = self.levels[a].visibility(p, n);
        if f == 0.0 {
            return va;
        }
        (1.0 - f) * va + f * self.levels[b].visibility(p, n)
    }

    /// [`Lookup::judged`] of a mipmapped map: the hull of every level the LOD's freedom
    /// reaches ([`Lookup::lod_range`]), each judged as a one-level map; a blend of two levels
    /// lies between their intervals.
    pub fn judged_mip(
        &self,
        p: Vec3,
        n: Vec3,
        snap: [Vec3; 2],
        turn: Turn,
        nb: &Neighbours,
    ) -> (f32, Legal) {
        let vis = self.visibility_mip(p, n, nb);
        let range = self.lod_range(nb);
        let (a, b) = self.levels_between(range);
        note(|| {
            format!(
                "mipmapped: LOD {} in [{}, {}], levels {a}..={b}",
                self.lod(nb),
                range.0,
                range.1
            )
        });
        let mut out: Option<Legal> = None;
        for k in a..=b {
            let l = self.levels[k].judged(p, n, snap, turn).1;
            out = Some(out.map_or(l, |o| o.hull(l)));
        }
        let mut l = out.unwrap_or(Legal::LIT);
        if b > a {
            l.flags |= ambiguity::LOD;
        }
        (vis, l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use umbra_case::format::Mipmaps;

    /// A one-point case's run, GL's convention and its judged map, for a [`Lookup`].
    fn gl_run(
        case: &str,
    ) -> (
        umbra_case::LightRun,
        Convention,
        Vec<crate::shadow_pass::DepthLayer>,
    ) {
        let point = umbra_case::load::load_str(case, std::path::Path::new("case.json"))
            .expect("the case")
            .remove(0);
        let run = umbra_case::Prepared::new(point).lights.remove(0);
        let clip = umbra_case::ClipDepth::MinusOneToOne;
        let conv = crate::convention(run.case(), clip);
        let layers = crate::judged_layers(&run, clip, Profile::GL);
        (run, conv, layers)
    }

    /// soak-47-845: at a smooth surface's terminator (N·L ≈ 0) the slope bias is its cap on
    /// one side and nothing on the other (c ≤ 0 reads no bias), and an interpolated normal
    /// is another point's where the camera's snapping moves the surface: lavapipe's lit pass
    /// read c ≤ 0 and no bias where the reference read the cap. The reference's range holds
    /// both ends once the normal's turn reaches c = 0, and only the cap without it.
    #[test]
    fn a_normal_turning_across_the_terminator_frees_the_slope_bias() {
        const CASE: &str = r#"{"name": "terminator", "about": "soak-47-845's bias",
            "scene": {"objects": [{"plane": {"point": [0, 0, 0], "normal": [0, 1, 0], "half_extent": 5}}]},
            "camera": {"eye": [0, 8, 8], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.5, "far": 40, "size": [64, 48]},
            "light": {"directional": {"azimuth_deg": 30, "elevation_deg": 50, "distance": 20, "fit": "scene"}},
            "shadow": {"size": [256, 256], "format": "depth16", "bias": {"constant": 0.000239, "slope": {"scale": 0.000439, "max": 0.018}}}}"#;
        let (run, conv, layers) = gl_run(CASE);
        let lookup = Lookup::new(&run, conv, &layers, Profile::GL);
        let p = Vec3::new(0.3, 0.0, -0.2);
        let l = lookup.light.to_light(p);
        // A unit normal a hair on the lit side of the terminator: c = N·L small and positive.
        let side = l.cross(Vec3::Y).normalize();
        let n = (l.cross(side).normalize() + l * 1e-5).normalize();
        let c = n.dot(l);
        assert!(c > 0.0 && c < 1e-4, "c = {c}");
        let st = lookup.setup(p, n).expect("the point is in the map");
        let depth = f64::from(st.c.depth);
        let unbiased = depth - 0.000239;
        let (_, hi) = lookup.reference_range(p, n, 0.0, &st, 0.0);
        assert!(
            hi < unbiased - 0.017,
            "without a turn: the cap alone, hi {hi}"
        );
        let (lo, hi) = lookup.reference_range(p, n, 1e-3, &st, 0.0);
        assert!(
            lo < unbiased - 0.017 && hi >= unbiased - 1e-6,
            "with a turn: from the cap to none, [{lo}, {hi}] against {unbiased}"
        );
    }

    /// The normal-offset point p + n·o swings by o·Δn when the interpolated normal turns
    /// under the camera's snapping: a point a driver reads shadowed with the turned normal
    /// and lit with its own is sure-lit to the judge without the turn, and may be either
    /// with it.
    #[test]
    fn a_turning_normal_swings_the_normal_offset_point() {
        const CASE: &str = r#"{"name": "swing", "about": "the normal offset's turn",
            "scene": {"objects": [{"plane": {"point": [0, 0, 0], "normal": [0, 1, 0], "half_extent": 6}},
                                  {"box": {"center": [0, 1, 0], "size": [2, 2, 2]}}]},
            "camera": {"eye": [0, 8, 8], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.5, "far": 40, "size": [64, 48]},
            "light": {"directional": {"azimuth_deg": 30, "elevation_deg": 55, "distance": 20, "fit": "scene"}},
            "shadow": {"size": [256, 256], "bias": {"constant": 0.0005, "normal_offset": 0.5}}}"#;
        let (run, conv, layers) = gl_run(CASE);
        let lookup = Lookup::new(&run, conv, &layers, Profile::GL);
        let (n, turned) = (Vec3::Y, (Vec3::Y + Vec3::X * 0.1).normalize());
        let turn = Turn([turned - n, Vec3::ZERO]);
        let still = [Vec3::ZERO; 2];
        let found = (0..2400)
            .map(|i| -6.0 + i as f32 * 0.005)
            .flat_map(|t| [Vec3::new(t, 0.0, 0.0), Vec3::new(0.0, 0.0, t)])
            .find(|&p| {
                lookup.visibility(p, n) == 1.0
                    && lookup.visibility(p, turned) == 0.0
                    && lookup.judged(p, n, still, Turn::NONE).1.lo == 1.0
            });
        let p = found.expect("a point the turn takes into the shadow");
        let (_, l) = lookup.judged(p, n, still, turn);
        assert_eq!(l.lo, 0.0, "at {p}: {l:?}");
        assert_eq!(l.hi, 1.0, "at {p}: {l:?}");
    }

    fn points() -> Vec<umbra_case::CasePoint> {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/mipmaps/rendered.json");
        umbra_case::load_file(&file).expect("the mipmapped case loads")
    }

    /// The LOD's freedom ([`Lookup::lod_range`]) holds every LOD the specs let a sampler
    /// compute: each derivative a forward or backward difference of the pixel's row or of
    /// the next rows (fine or coarse), and each scale factor at the bounds of GL 4.6 §8.14.1
    /// and of Vulkan's "Scale Factor Operation" (the GL profile takes both, as dEQP does);
    /// the coordinates computed here on their own, each neighbour moved by its own normal's
    /// offset (a curved surface under a normal offset); and the reference's own choice of
    /// levels lies among the levels the judge allows.
    #[test]
    fn every_lod_the_specs_allow_lies_in_the_judged_freedom() {
        let mut rand = crate::test_rng::uniform(0x1A0D);
        let mut checked = 0;
        for mut point in points() {
            point.case.shadow.bias.normal_offset = 0.3;
            let run = umbra_case::Prepared::new(point).lights.remove(0);
            let clip = umbra_case::ClipDepth::MinusOneToOne;
            let conv = crate::convention(run.case(), clip);
            let s = &run.case().shadow;
            let m = LookupMatrices::new(conv, run.light.views[0].view_proj(conv));
            let size = glam::DVec2::new(f64::from(s.size[0]), f64::from(s.size[1]));
            let texel = |q: Vec3, n: Vec3| {
                let c = m.coord(conv, s.bias_matrix, q + n * s.bias.normal_offset);
                DVec2::new(f64::from(c.u), f64::from(c.v)) * size
            };
            for profile in [Profile::GL, Profile::VULKAN] {
                let layers = crate::judged_layers(&run, clip, profile);
                let adjacency = crate::adjacency::Adjacency::new(&run.geometry);
                let (shadows, below) =
                    crate::mip_levels(&run, conv, &layers, Some((&adjacency, profile)), None);
                let lookup =
                    Lookup::new(&run, conv, &layers, profile).with_levels(&shadows, &below);
                assert!(lookup.mipmapped());
                for _ in 0..400 {
                    // A ground point, a pixel footprint of a few centimetres to a metre, and
                    // normals that tilt from pixel to pixel (a curved surface).
                    let p = Vec3::new(rand() * 40.0 - 20.0, 0.0, rand() * -50.0 + 10.0);
                    let k = 0.02 + rand();
                    let ex = Vec3::new(rand() - 0.5, 0.0, rand() - 0.5).normalize_or_zero() * k;
                    let ey = Vec3::new(rand() - 0.5, 0.0, rand() - 0.5).normalize_or_zero() * k;
                    let curve = (rand() - 0.5) * 0.2;
                    let tilt = Vec3::new(rand() - 0.5, 0.0, rand() - 0.5) * 0.3;
                    let nb = Neighbours(std::array::from_fn(|j| {
                        std::array::from_fn(|i| {
                            let (a, b) = (i as f32 - 1.0, j as f32 - 1.0);
                            // Perspective bends the footprint from pixel to pixel.
                            let q = p + ex * a * (1.0 + curve * b) + ey * b * (1.0 + curve * a);
                            (q, (Vec3::Y + tilt * (a + 0.5 * b)).normalize())
                        })
                    }));
                    let range = lookup.lod_range(&nb);
                    let t = nb.0.map(|row| row.map(|(q, n)| texel(q, n)));
                    for row in 0..3 {
                        for col in 0..3 {
                            for dx in [t[row][2] - t[row][1], t[row][1] - t[row][0]] {
                                for dy in [t[2][col] - t[1][col], t[1][col] - t[0][col]] {
                                    let (mu, mv) =
                                        (dx.x.abs().max(dy.x.abs()), dx.y.abs().max(dy.y.abs()));
                                    let mut rho = vec![
                                        dx.length().max(dy.length()),
                                        mu.max(mv),
                                        std::f64::consts::SQRT_2
                                            * (dx.x.abs() + dx.y.abs())
                                                .max(dy.x.abs() + dy.y.abs()),
                                    ];
                                    if profile.spec == Spec::Gl {
                                        rho.push(mu + mv);
                                    }
                                    for r in rho {
                                        let lod = umbra_case::math::log2(r);
                                        assert!(
                                            range.0 <= lod && lod <= range.1,
                                            "LOD {lod} outside [{}, {}]",
                                            range.0,
                                            range.1
                                        );
                                        checked += 1;
                                    }
                                }
                            }
                        }
                    }
                    let (a, b, _) = lookup.levels_at(lookup.lod(&nb));
                    let (lo, hi) = lookup.levels_between(range);
                    assert!(lo <= a && b <= hi, "levels {a}, {b} outside {lo}..={hi}");
                }
            }
        }
        assert!(checked > 100_000, "{checked}");
    }

    /// A level of a generated chain holds the mean of the four texels above it, and its
    /// judged range holds the mean of any values within theirs.
    #[test]
    fn an_averaged_level_holds_the_mean_of_the_level_above() {
        let format = umbra_case::format::DepthFormat::Depth24;
        let values = vec![0.25f32, 0.5, 0.75, 1.0, 0.0, 0.0, 0.5, 0.5];
        let prev = crate::shadow_pass::DepthLayer {
            lo: values.iter().map(|v| v - 0.01).collect(),
            hi: values.iter().map(|v| v + 0.01).collect(),
            maybe: vec![false; 8],
            values: values.clone(),
        };
        // A 4 × 2 level: two texels below it.
        let next = crate::shadow_pass::averaged(&prev, [4, 2], format, true);
        assert_eq!(Mipmaps::level_size([4, 2], 1), [2, 1]);
        assert_eq!(next.values.len(), 2);
        assert_eq!(
            next.values[0],
            format.store(0.25 * (0.25 + 0.5 + 0.0 + 0.0))
        );
        assert_eq!(
            next.values[1],
            format.store(0.25 * (0.75 + 1.0 + 0.5 + 0.5))
        );
        for k in 0..2 {
            assert!(next.lo[k] <= next.values[k] - 0.009 && next.values[k] + 0.009 <= next.hi[k]);
        }
    }
}
