//! Where a tap's texel is read from (the 2D map's wrap policy, a cube face's clamp, the
//! direction of a texel beyond a cube face's edge, a seamless sampler's neighbouring face)
//! and what a compare against it may answer, the stored value's conversion included.

use super::*;

/// Where a tap's texel comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Addressing {
    /// The map's wrap policy (2D maps).
    Wrap,
    /// Indices clamped to the cube face (the sampler's per-face addressing, manual fetches).
    ClampToFace,
    /// The direction of the texel's centre (hardware PCF taps on a cube).
    Direction,
}

/// A texel: (layer, index) or the border's clear value.
pub(super) enum Texel {
    At(usize, usize),
    Clear,
}

impl Lookup<'_> {
    /// How the lookup's taps address a cube map: the sampler itself for hardware NEAREST and
    /// LINEAR (clamped to the face in the value; seams are the judged interval's business),
    /// the texel centre's direction for hardware PCF taps, clamped indices for manual fetches;
    /// a 2D map's taps take its wrap policy.
    pub(super) fn tap_addressing(&self) -> Addressing {
        if !self.cube() {
            return Addressing::Wrap;
        }
        match (self.hardware(), self.shadow.filter) {
            (true, Filter::Pcf(_)) => Addressing::Direction,
            _ => Addressing::ClampToFace,
        }
    }

    /// The stored value at texel (i, j) of `face` under `addressing` and the wrap policy.
    #[inline]
    pub(super) fn stored(&self, face: usize, i: i64, j: i64, addressing: Addressing) -> f32 {
        match self.texel(face, i, j, addressing) {
            Texel::At(f, k) => self.layers[f].values[k],
            Texel::Clear => self.shadow.format.store(self.conv.clear_depth()),
        }
    }

    /// Where texel (i, j) of `face` is read from under `addressing` and the wrap policy.
    #[inline]
    pub(super) fn texel(&self, face: usize, i: i64, j: i64, addressing: Addressing) -> Texel {
        let [w, h] = self.shadow.size;
        let (wi, hi) = (i64::from(w), i64::from(h));
        let inside = |i: i64, j: i64| (0..wi).contains(&i) && (0..hi).contains(&j);
        let at = |f: usize, i: i64, j: i64| Texel::At(f, (j * wi + i) as usize);
        match addressing {
            Addressing::ClampToFace => at(face, i.clamp(0, wi - 1), j.clamp(0, hi - 1)),
            Addressing::Direction => {
                if inside(i, j) {
                    return at(face, i, j);
                }
                // The shader's texel_dir of a virtual texel beyond the edge, in f32 as it is
                // computed there; the sampler picks the face of that direction.
                let d = umbra_case::light::cube_texel_dir(
                    face,
                    i as f64,
                    self.table_row(j as f64),
                    f64::from(w),
                );
                let d32 = d.as_vec3().as_dvec3();
                let (f, sc, tc) = umbra_case::light::cube_face_coords(d32);
                let ii = (((sc + 1.0) * 0.5 * f64::from(w)).floor() as i64).clamp(0, wi - 1);
                let jj = self.layer_row((tc + 1.0) * 0.5 * f64::from(h)).floor() as i64;
                at(f, ii, jj.clamp(0, hi - 1))
            }
            Addressing::Wrap => {
                let (i, j) = match self.shadow.outside {
                    Outside::Border => {
                        if !inside(i, j) {
                            return Texel::Clear;
                        }
                        (i, j)
                    }
                    Outside::Lit | Outside::ClampToEdge => (i.clamp(0, wi - 1), j.clamp(0, hi - 1)),
                    Outside::Repeat => (i.rem_euclid(wi), j.rem_euclid(hi)),
                };
                at(face, i, j)
            }
        }
    }

    /// One LINEAR tap of the sampler: within the map (or its wrap), or on a cube, within the
    /// face, across a seam (seamless profiles: the neighbouring face's texel; per-face
    /// filtering: clamped), or, on a seamless profile, None at a corner where both
    /// coordinates leave the face.
    pub(super) fn linear_tap(
        &self,
        face: usize,
        i: i64,
        j: i64,
        r: (f64, f64),
    ) -> Option<Possible> {
        if !self.cube() {
            return Some(self.possible(face, i, j, r, Addressing::Wrap));
        }
        let [w, h] = self.shadow.size;
        let (out_i, out_j) = (
            !(0..i64::from(w)).contains(&i),
            !(0..i64::from(h)).contains(&j),
        );
        if !self.profile.seamless_cube || !(out_i || out_j) {
            return Some(self.possible(face, i, j, r, Addressing::ClampToFace));
        }
        if out_i && out_j {
            return None;
        }
        // The texel across the edge: the direction of the point on the edge at this texel's
        // position along it, nudged over the edge.
        let size = f64::from(w);
        let (ci, cj) = (
            if out_i {
                if i < 0 {
                    -0.5 - 1e-9 * size
                } else {
                    size - 0.5 + 1e-9 * size
                }
            } else {
                i as f64
            },
            if out_j {
                if j < 0 {
                    -0.5 - 1e-9 * size
                } else {
                    size - 0.5 + 1e-9 * size
                }
            } else {
                j as f64
            },
        );
        let d = umbra_case::light::cube_texel_dir(face, ci, self.table_row(cj), size);
        let (f, sc, tc) = umbra_case::light::cube_face_coords(d);
        let ii = (((sc + 1.0) * 0.5 * size).floor() as i64).clamp(0, i64::from(w) - 1);
        let jj = self.layer_row((tc + 1.0) * 0.5 * f64::from(h)).floor() as i64;
        Some(self.possible(
            f,
            ii,
            jj.clamp(0, i64::from(h) - 1),
            r,
            Addressing::ClampToFace,
        ))
    }

    /// The cube-map table's row (t counted as GL's face images count it, the rows of the GL
    /// convention's raster) of raster row `j` of a layer; in a convention whose window y runs
    /// down the layer's rows run the other way.
    pub(super) fn table_row(&self, j: f64) -> f64 {
        if self.conv.window_y_down() {
            f64::from(self.shadow.size[1]) - 1.0 - j
        } else {
            j
        }
    }

    /// The layer's row coordinate (in texels from its first row, continuous) of a cube-map
    /// table coordinate `y`: [`Lookup::table_row`]'s inverse for positions.
    pub(super) fn layer_row(&self, y: f64) -> f64 {
        if self.conv.window_y_down() {
            f64::from(self.shadow.size[1]) - y
        } else {
            y
        }
    }

    /// What a compare of reference range `r` against texel (i, j) may answer.
    pub(super) fn possible(
        &self,
        face: usize,
        i: i64,
        j: i64,
        r: (f64, f64),
        addressing: Addressing,
    ) -> Possible {
        let (d_lo, d_hi, by_coverage) = match self.texel(face, i, j, addressing) {
            Texel::At(..) if addressing == Addressing::Direction && !self.on_face(i, j) => {
                // Beyond the face: the sampler may read any texel the direction allows.
                let mut range = (f64::INFINITY, f64::NEG_INFINITY, false);
                for (f, k) in self.direction_texels(face, i, j) {
                    let l = &self.layers[f];
                    let (lo, hi) = self.conversion_range(l.lo[k], l.hi[k]);
                    range = (range.0.min(lo), range.1.max(hi), range.2 || l.maybe[k]);
                }
                range
            }
            Texel::Clear => {
                let c = f64::from(self.shadow.format.store(self.conv.clear_depth()));
                (c, c, false)
            }
            Texel::At(f, k) => {
                let l = &self.layers[f];
                let (lo, hi) = self.conversion_range(l.lo[k], l.hi[k]);
                (lo, hi, l.maybe[k])
            }
        };
        let forward = self.conv.toward_far() > 0.0;
        // Forward: lit iff reference ≤ stored; reversed: lit iff reference ≥ stored.
        let (lit, shadow) = if forward {
            (r.0 <= d_hi, r.1 > d_lo)
        } else {
            (r.1 >= d_lo, r.0 < d_hi)
        };
        note(|| {
            format!(
                "      tap ({i}, {j}) of face {face} ({addressing:?}): stored in [{d_lo}, {d_hi}]{}: lit {lit}, shadowed {shadow}",
                if by_coverage {
                    " (through coverage)"
                } else {
                    ""
                }
            )
        });
        Possible {
            lit,
            shadow,
            by_coverage: lit && shadow && by_coverage,
        }
    }

    /// A texel's stored range as the compare sees it. A fixed-point code reaches the compare
    /// as code/(2ⁿ − 1) converted to f32: one ULP either way for that conversion, except for
    /// the codes of 0 and 1, which convert exactly (GL 4.6 §2.3.5.1, Vulkan "Fixed-Point Data
    /// Conversions"): a cleared texel is exactly the clear value.
    pub(super) fn conversion_range(&self, lo: f32, hi: f32) -> (f64, f64) {
        let (lo, hi) = (f64::from(lo), f64::from(hi));
        if self.shadow.format.is_fixed() && !self.profile.packed_depth {
            let widen = |x: f64, dir: f64| {
                if x == 0.0 || x == 1.0 {
                    x
                } else {
                    x + dir * ulp(x)
                }
            };
            (widen(lo, -1.0), widen(hi, 1.0))
        } else {
            (lo, hi)
        }
    }

    /// Whether (i, j) is a texel of a face (not beyond its edges).
    pub(super) fn on_face(&self, i: i64, j: i64) -> bool {
        let [w, h] = self.shadow.size;
        (0..i64::from(w)).contains(&i) && (0..i64::from(h)).contains(&j)
    }

    /// The texels (face, index) a cube sampler may read for the direction of the centre of
    /// virtual texel (i, j) beyond face `face`'s edge, the direction hardware PCF taps look up
    /// (`texel_dir` in the shaders): every face whose axis may be the major one (GL 4.6 and
    /// ES 3.2 §8.13: "If two or more coordinates have the identical magnitude, the
    /// implementation may define the rule to disambiguate"; beyond a corner two components
    /// tie exactly, and the shader's f32 direction, a few roundings off ours, can tip a
    /// near-tie either way), and on each, every texel within the sampler's 4 sub-texel bits
    /// of the projected coordinate, clamped to the face.
    pub(super) fn direction_texels(&self, face: usize, i: i64, j: i64) -> Vec<(usize, usize)> {
        let [w, h] = self.shadow.size;
        let (fw, fh) = (f64::from(w), f64::from(h));
        let d = umbra_case::light::cube_texel_dir(face, i as f64, self.table_row(j as f64), fw);
        let a = d.abs();
        let major = a.max_element();
        // texel_dir's f32 arithmetic (a division and two sums, GLSL 4.60 §4.7.1) and ours.
        let slack = 8.0 * U * major;
        let mut out = Vec::new();
        for axis in 0..3 {
            if a[axis] < major - slack {
                continue;
            }
            let f = 2 * axis + usize::from(d[axis] < 0.0);
            let (sc, tc) = umbra_case::light::cube_coords_on(d, f);
            let (x, y) = ((sc + 1.0) * 0.5 * fw, self.layer_row((tc + 1.0) * 0.5 * fh));
            let (ex, ey) = (SUBTEXEL + slack * fw, SUBTEXEL + slack * fh);
            for ii in span(x, ex) {
                for jj in span(y, ey) {
                    let (ii, jj) = (ii.clamp(0, i64::from(w) - 1), jj.clamp(0, i64::from(h) - 1));
                    let k = (jj * i64::from(w) + ii) as usize;
                    if !out.contains(&(f, k)) {
                        out.push((f, k));
                    }
                }
            }
        }
        out
    }
}
