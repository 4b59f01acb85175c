//! The plain lookup, step by step as a lit-pass shader does it, in f32 (steps 1 to 8 of
//! [`super`]'s list): the value a backend is compared with. Each step's judged interval is
//! computed beside it, in [`super::precision`] and [`super::filters`].

use super::*;

impl Lookup<'_> {
    /// The shadow term at world point `p` with unit normal `n`: 1 lit .. 0 shadowed.
    pub fn visibility(&self, p: Vec3, n: Vec3) -> f32 {
        if let Some(c) = &self.light.cascading {
            return self.cascaded_visibility(c, p, n);
        }
        self.value_of(self.setup(p, n))
    }

    /// The shadow term of a lookup set up (`None`: the tests read lit).
    pub(super) fn value_of(&self, st: Option<Setup>) -> f32 {
        st.map_or(1.0, |st| self.filter_value(&st))
    }

    /// [`Lookup::visibility`] of every point of a run (`out[k]` for point k of `surfaces`), the
    /// same steps with the same operations: on one 2D map without per-point bias terms or
    /// `beyond_far: lit`, the coordinates of the whole run first (a loop the compiler
    /// vectorises: one matrix, no branches), then each point's guard, outside test and
    /// filter; otherwise point by point.
    pub fn visibility_run(
        &self,
        surfaces: &Surfaces,
        out: &mut [f32],
        scratch: &mut Vec<ShadowCoord>,
    ) {
        let s = self.shadow;
        if self.cube()
            || self.light.cascading.is_some()
            || s.bias.slope.is_some()
            || s.bias.n_dot_l.is_some()
            || s.beyond_far == BeyondFar::Lit
        {
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.visibility(surfaces.position(k), surfaces.normal(k));
            }
            return;
        }
        // Step 1 and 3 of every point ([`Lookup::probe`] on the only face).
        let (m, order, conv) = (&self.matrices[0], s.bias_matrix, self.conv);
        scratch.clear();
        scratch.extend((0..out.len()).map(|k| {
            m.coord(
                conv,
                order,
                self.moved(surfaces.position(k), surfaces.normal(k), 0),
            )
        }));
        // Step 6's bias: the slope and N·L terms are exactly 0 without their settings.
        let bias = s.bias.constant + 0.0 + 0.0;
        let away = conv.toward_far() * bias;
        let clamp = s.compare == Compare::Hardware && s.format.is_fixed();
        let (fw, fh) = (s.size[0] as f32, s.size[1] as f32);
        for (o, c) in out.iter_mut().zip(scratch.iter()) {
            let mut reference = c.depth - away;
            *o = if (s.guard_behind_light && c.w <= 0.0) || self.outside_lit(c.u, c.v) {
                1.0
            } else {
                if clamp {
                    reference = reference.clamp(0.0, 1.0);
                }
                match s.filter {
                    // filter_value's NEAREST tap, with the 2D map's own addressing.
                    Filter::Nearest => {
                        let d = self.stored(
                            0,
                            floor_i64(c.u * fw),
                            floor_i64(c.v * fh),
                            Addressing::Wrap,
                        );
                        if conv.compare_lit(reference, d) {
                            1.0
                        } else {
                            0.0
                        }
                    }
                    _ => self.filter_value(&Setup {
                        face: 0,
                        c: *c,
                        reference,
                    }),
                }
            };
        }
    }

    /// Step 1 in the lit shaders' f32 order: the point face `face`'s lookup transforms, `p`
    /// moved by the normal offset (before the face is chosen), then by the face's
    /// texel-scaled normal offset and towards a directional light
    /// (`shadow.bias.normal_offset_texels`, `light_offset`; `umbra_case::lit_shader`'s
    /// `world_offsets`): ((p + n·o) + n·o_f) + l·L.
    pub(super) fn moved(&self, p: Vec3, n: Vec3, face: usize) -> Vec3 {
        let b = &self.shadow.bias;
        let q = p + n * b.normal_offset;
        if b.normal_offset_texels == 0.0 && b.light_offset == 0.0 {
            return q;
        }
        let towards = match self.light.kind {
            LightKind::Directional { towards, .. } => towards,
            LightKind::Spot { .. } | LightKind::Point { .. } => Vec3::ZERO,
        };
        let o_f = self
            .light
            .face_offset(face, b.normal_offset_texels, self.shadow.size);
        q + n * o_f + towards * b.light_offset
    }

    /// The largest distance the offsets of [`Lookup::moved`] move a point, on any face: what
    /// the shader's rounding (or fusing) of those steps is relative to.
    pub(super) fn offsets_reach(&self) -> f32 {
        self.normal_offsets_reach() + self.shadow.bias.light_offset.abs()
    }

    /// The largest distance a point moves along its normal in [`Lookup::moved`], on any
    /// face: `normal_offset` and the face's texel-scaled one (what a turn of the normal
    /// swings the offset point by, per unit of turn).
    pub(super) fn normal_offsets_reach(&self) -> f32 {
        let b = &self.shadow.bias;
        let faces = (0..self.light.views.len())
            .map(|f| {
                self.light
                    .face_offset(f, b.normal_offset_texels, self.shadow.size)
                    .abs()
            })
            .fold(0.0, f32::max);
        b.normal_offset.abs() + faces
    }

    /// The face, the coordinate and the reference value before any clamp, at `p` (before the
    /// normal offset) with normal `n`.
    pub(super) fn probe(&self, p: Vec3, n: Vec3) -> (usize, ShadowCoord, f32) {
        let face = self.light.face_for(p + n * self.shadow.bias.normal_offset);
        let (c, reference) = self.probe_on(p, n, face);
        (face, c, reference)
    }

    /// [`Lookup::probe`] in the projection of face `face`, whichever face the point is on.
    pub(super) fn probe_on(&self, p: Vec3, n: Vec3, face: usize) -> (ShadowCoord, f32) {
        let s = self.shadow;
        let p = self.moved(p, n, face);
        let c = self.matrices[face].coord(self.conv, s.bias_matrix, p);
        let bias = s.bias.constant + self.slope_bias(p, n) + self.n_dot_l_bias(p, n);
        (c, c.depth - self.conv.toward_far() * bias)
    }

    /// Whether the `beyond_far: lit` policy applies to a coordinate of this depth.
    pub(super) fn beyond_far(&self, depth: f32) -> bool {
        self.shadow.beyond_far == BeyondFar::Lit
            && if self.conv.toward_far() > 0.0 {
                depth > 1.0
            } else {
                depth < 0.0
            }
    }

    /// Whether a 2D map's `lit` outside policy applies to (u, v).
    pub(super) fn outside_lit(&self, u: f32, v: f32) -> bool {
        !self.cube()
            && self.shadow.outside == Outside::Lit
            && !((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v))
    }

    /// [`Lookup::setup_on`] on the face `p` (offset along `n`) lies on.
    pub(super) fn setup(&self, p: Vec3, n: Vec3) -> Option<Setup> {
        self.setup_on(p, n, self.probe(p, n).0)
    }

    /// [`Lookup::setup`] in face `face`: where the lookup reads there, the reference clamped
    /// as the compare clamps it; `None` where the guard, the `lit` outside test or
    /// `beyond_far: lit` reads lit.
    pub(super) fn setup_on(&self, p: Vec3, n: Vec3, face: usize) -> Option<Setup> {
        let s = self.shadow;
        let (c, mut reference) = self.probe_on(p, n, face);
        if (s.guard_behind_light && c.w <= 0.0)
            || self.outside_lit(c.u, c.v)
            || self.beyond_far(c.depth)
        {
            return None;
        }
        if s.compare == Compare::Hardware && s.format.is_fixed() {
            reference = reference.clamp(0.0, 1.0);
        }
        Some(Setup { face, c, reference })
    }

    /// The slope bias min(s·sqrt(1 − c²)/c, max) for c = N·L > 0, else 0.
    pub(super) fn slope_bias(&self, p: Vec3, n: Vec3) -> f32 {
        let Some(slope) = self.shadow.bias.slope else {
            return 0.0;
        };
        let c = n.dot(self.light.to_light(p));
        if c > 0.0 {
            (slope.scale * (1.0 - c * c).max(0.0).sqrt() / c).clamp(0.0, slope.max)
        } else {
            0.0
        }
    }

    /// The N·L bias max(s·(1 − c), min) for c = N·L (LearnOpenGL's form; c is not clamped,
    /// so faces away from the light get up to 2s).
    pub(super) fn n_dot_l_bias(&self, p: Vec3, n: Vec3) -> f32 {
        let Some(b) = self.shadow.bias.n_dot_l else {
            return 0.0;
        };
        let c = n.dot(self.light.bias_light_vector(p, b.light));
        (b.scale * (1.0 - c)).max(b.min)
    }

    /// Step 7 and 8: the filter's value at `st`, its taps compared as the shader compares
    /// them, in f32 (the reference's value; [`Lookup::legal_taps`] is its interval).
    pub(super) fn filter_value(&self, st: &Setup) -> f32 {
        let s = self.shadow;
        let [w, h] = s.size;
        let (fw, fh) = (w as f32, h as f32);
        let (u, v) = (st.c.u, st.c.v);
        let addressing = self.tap_addressing();
        let tap = |i: i64, j: i64| -> f32 {
            let d = self.stored(st.face, i, j, addressing);
            if self.conv.compare_lit(st.reference, d) {
                1.0
            } else {
                0.0
            }
        };
        let bilinear = |u: f32, v: f32| -> f32 {
            let (x, y) = (u * fw - 0.5, v * fh - 0.5);
            let (i0, j0) = (floor_f32(x), floor_f32(y));
            let (a, b) = (x - i0, y - j0);
            let (i0, j0) = (i0 as i64, j0 as i64);
            (1.0 - a) * (1.0 - b) * tap(i0, j0)
                + a * (1.0 - b) * tap(i0 + 1, j0)
                + (1.0 - a) * b * tap(i0, j0 + 1)
                + a * b * tap(i0 + 1, j0 + 1)
        };
        match s.filter {
            Filter::Nearest => tap(floor_i64(u * fw), floor_i64(v * fh)),
            Filter::Linear => bilinear(u, v),
            Filter::Castano13 => {
                let mut sum = 0.0;
                for ((wu, wv), (ou, ov)) in castano_taps([u, v], [fw, fh]) {
                    sum += wu * wv * bilinear(ou, ov);
                }
                sum * (1.0 / 144.0)
            }
            Filter::Vogel5 => self.vogel_value(st, bilinear),
            Filter::Pcf(k) => {
                let half = (k as f32 - 1.0) * 0.5;
                let mut sum = 0.0;
                for dy in 0..k {
                    for dx in 0..k {
                        let uu = u + (dx as f32 - half) / fw;
                        let vv = v + (dy as f32 - half) / fh;
                        sum += tap(floor_i64(uu * fw), floor_i64(vv * fh));
                    }
                }
                sum / (k * k) as f32
            }
        }
    }
}
