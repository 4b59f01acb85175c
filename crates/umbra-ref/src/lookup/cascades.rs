//! Cascaded lights: the lit shaders' cascade choice and blend, and the judged interval over
//! every cascade the offset point's view depth may select, blended over every weight within
//! reach.

use super::*;

impl Lookup<'_> {
    /// [`Lookup::visibility`] of a cascaded light, in the lit shaders' steps and f32
    /// arithmetic: the view depth of the offset point, lit beyond the shadow distance, the
    /// cascade's lookup, blended in the band into the next cascade's as `mix` does,
    /// v·(1 − t) + v'·t.
    pub(super) fn cascaded_visibility(&self, c: &Cascading, p: Vec3, n: Vec3) -> f32 {
        let d = c.depth(p + n * self.shadow.bias.normal_offset);
        if c.beyond(d) {
            return 1.0;
        }
        let f = c.cascade_of(f64::from(d));
        let on = |face: usize| self.value_of(self.setup_on(p, n, face));
        let v = on(f);
        match c.blend_weight(f, d) {
            Some(t) => v * (1.0 - t) + on(f + 1) * t,
            None => v,
        }
    }

    /// [`Lookup::legal_at`] for a cascaded light. Every cascade whose view-depth range lies
    /// within reach of the offset point's view depth d = r · (p, 1) may serve it: the reach
    /// is the region of moves and the shader's arithmetic of d (four terms, γ₄ of their
    /// magnitudes: GLSL's and WGSL's dot products round each product and sum, or fuse them).
    /// A receiver on a split may be looked up in either cascade (both maps cover it). In a
    /// blend band the value is (1 − t)·v + t·v' for the weight t of every depth within reach
    /// (widened by the rounding of t's own arithmetic)
    /// ([`Cascading::blend_range`]), v and v' anywhere in their cascades' intervals; linear in
    /// t, its extremes are at the ends of t's range. Within reach of the shadow distance it
    /// may also read lit, and beyond it does.
    pub(super) fn legal_cascaded(
        &self,
        c: &Cascading,
        p: Vec3,
        n: Vec3,
        moves: &[Vec3],
        turn: f32,
    ) -> Legal {
        let q = p + n * self.shadow.bias.normal_offset;
        let row = c.depth_row.truncate();
        let spread: f64 = moves.iter().map(|m| f64::from(row.dot(*m).abs())).sum();
        let terms = f64::from((row * q).abs().element_sum() + c.depth_row.w.abs());
        // Twice γ₄: the centre d is the reference's own f32 arithmetic, as far from the exact
        // value as the shader's may be on the other side.
        let reach = spread + 2.0 * gamma(4.0) * terms;
        let d = f64::from(c.depth(q));
        let end = f64::from(c.end());
        if c.lit_beyond && d - reach > end {
            note(|| "    beyond the shadow distance: lit".into());
            return Legal::LIT;
        }
        let mut out: Option<Legal> = None;
        for f in c.cascades_near(d, reach) {
            let mut l = self.legal_on(p, n, moves, turn, f);
            // The shader's weight t = (d − (hi − band)) / band rounds in hi − lo, hi − band,
            // d − (…) and the division (2.5 ulp in GLSL and WGSL): within 8u·(hi + band) of
            // depth, which widens t's range beside d's own reach.
            let hi = f64::from(c.splits[f + 1]);
            let band = c.band_f64(f);
            let t_reach = reach + 8.0 * U * (hi.abs() + band);
            if let Some((t0, t1)) = c.blend_range(f, d, t_reach) {
                let next = self.legal_on(p, n, moves, turn, f + 1);
                let at = |t: f64, a: f32, b: f32| (1.0 - t) * f64::from(a) + t * f64::from(b);
                l = legal(
                    at(t0, l.lo, next.lo).min(at(t1, l.lo, next.lo)),
                    at(t0, l.hi, next.hi).max(at(t1, l.hi, next.hi)),
                    l.flags | next.flags,
                );
                note(|| format!("    blended into cascade {} with t in [{t0}, {t1}]", f + 1));
            }
            out = Some(out.map_or(l, |o| o.hull(l)));
        }
        let l = out.unwrap_or(Legal::LIT);
        if c.lit_beyond && d + reach > end {
            l.hull(Legal::LIT)
        } else {
            l
        }
    }
}
