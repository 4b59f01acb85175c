//! Triangle rasterization, the way the GL and Vulkan specs describe it.
//!
//! - **Clipping** in homogeneous clip space against the near and far planes of the
//!   convention (−w ≤ z or 0 ≤ z, z ≤ w) and a guard band of ±4w in x and y (far outside any
//!   viewport; it only bounds the fixed-point range). Clipped polygons are fanned from their
//!   first vertex; every new vertex carries its weights on the *original* triangle's vertices,
//!   so attributes always interpolate from the original three. A new vertex is interpolated
//!   from the edge's outside corner whichever way the triangle walks it, so two triangles
//!   sharing a clipped edge make the same corner and no crack opens between them. Under
//!   depth clamp the near and far planes give way to w ≥ [`CLAMP_W_MIN`].
//! - **Viewport** from [`Convention::window_xy`]: GL windows are y up, zero-to-one windows
//!   y down; raster row r holds window y in [r, r+1) either way.
//! - **Snapping** to 8 sub-pixel bits (1/256 px, what llvmpipe and lavapipe use; the specs ask
//!   for at least 4). Edge functions are exact `i64`: with the guard band, window coordinates
//!   stay within ±2.5 · 16384 px, so products stay below 2^48.
//! - **Coverage** at pixel centres (x + ½, y + ½). **Tie rule**: a centre exactly on an edge
//!   belongs to the triangle for which, walking the edge counter-clockwise in raster
//!   coordinates, the edge goes towards lower rows (dy < 0), or is horizontal going towards
//!   higher x. The two triangles sharing an edge walk it in opposite directions, so exactly
//!   one owns it: no gaps, no double hits. In a y-down window this is D3D's top-left rule.
//! - **Facing**: front = counter-clockwise in NDC (y up), the GL and wgpu default.
//! - **Interpolation**: window depth linearly in screen space (z/w is affine there); other
//!   attributes perspective-correctly (weights b_i/w_i, normalised), in f64 from the exact
//!   edge values.

// Vertex attributes are parallel arrays indexed by vertex; index loops read as the spec does.
#![allow(clippy::needless_range_loop)]

use glam::{DVec3, Vec4};
use umbra_case::Convention;
use umbra_case::format::Cull;

/// Sub-pixel bits.
pub const SUBPIXEL_BITS: u32 = 8;
const ONE: i64 = 1 << SUBPIXEL_BITS;
const HALF: i64 = ONE / 2;
/// Guard band, in multiples of w.
const GUARD: f32 = 4.0;

/// What lies across one edge of a triangle in one view, for the judge's coverage freedom:
/// snapping (GL and Vulkan promise only 4 sub-pixel bits) may move a boundary of the drawn
/// surface, but not an edge two drawn triangles share (both snap the same shared vertices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeKind {
    /// A diagonal that clipping added inside one source triangle: never a boundary.
    Internal,
    /// A boundary of the drawn surface in this view: a silhouette, a mesh border, a clip line.
    Open,
    /// Shared with another drawn triangle lying on the other side.
    Shared {
        /// That triangle's face id.
        face: u32,
        /// That triangle's index in the geometry.
        tri: u32,
    },
}

/// A triangle ready to scan: snapped, oriented counter-clockwise in raster coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Tri {
    /// Vertex x in 1/256 px.
    pub x: [i64; 3],
    /// Vertex y (raster rows) in 1/256 px.
    pub y: [i64; 3],
    /// Window depth per vertex.
    pub z: [f32; 3],
    /// 1 / clip w per vertex.
    pub inv_w: [f64; 3],
    /// Each vertex as weights on the source triangle's three vertices.
    pub weights: [DVec3; 3],
    /// Twice the signed area in 1/256² px², > 0.
    pub area: i64,
    /// Whether each edge (opposite vertex i) owns the centres that lie exactly on it.
    pub owns: [bool; 3],
    /// Inclusive pixel bounds `[x0, y0, x1, y1]`, inside the viewport (may be empty when
    /// the triangle covers no pixel centre).
    pub bbox: [i32; 4],
    /// The bounds grown by one pixel, inside the viewport: where coverage may legally differ.
    pub near_bbox: [i32; 4],
    /// Per edge (opposite vertex i): what lies across it.
    pub edges: [EdgeKind; 3],
    /// Index of the source triangle.
    pub source: u32,
    /// Whether the source triangle is front-facing.
    pub front: bool,
    /// Judged renders: per corner, how far another implementation's window depth may lie
    /// from ours ([`crate::shadow_pass::depth_error`]); 0 otherwise.
    pub z_err: [f64; 3],
    /// Judged renders: how far, in pixels, another implementation's transform may put any
    /// corner's window x or y beyond ours besides snapping ([`crate::shadow_pass::xy_error`]:
    /// far from the origin, where the clip rows cancel large terms, a vertex lands a
    /// fraction of a pixel off); 0 otherwise.
    pub xy_err: f64,
    /// How far, in pixels, another implementation's snapping may put a corner: [`SNAP_PX`],
    /// or less where a behaviour card read the driver's sub-pixel bits (shadow pass only).
    pub snap: f64,
}

/// A line between two vertices of a clipped polygon, in window coordinates (1/256 px, raster
/// rows): where another clipper's fan may put a diagonal ([`Rasterizer::viewport_chords`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chord {
    /// One end.
    pub from: [i64; 2],
    /// The other end.
    pub to: [i64; 2],
}

impl Chord {
    /// Whether the centre of pixel (x, y) lies within `delta_px` of this chord's line,
    /// measured as [`Tri::near_internal`] measures a diagonal (inside the convex polygon the
    /// line is the chord).
    pub fn near(&self, x: i32, y: i32, delta_px: f64) -> bool {
        let (px, py) = (i64::from(x) * ONE + HALF, i64::from(y) * ONE + HALF);
        let (dx, dy) = (self.to[0] - self.from[0], self.to[1] - self.from[1]);
        let e = dx * (py - self.from[1]) - dy * (px - self.from[0]);
        near_line(e, dx, dy, delta_px)
    }
}

/// Whether a centre with edge value `e` (of the line along (dx, dy), in 1/256 px) lies within
/// `delta_px` of the line: E = length · distance and length ≤ |dx| + |dy|, so the test is
/// generous by at most √2.
fn near_line(e: i64, dx: i64, dy: i64, delta_px: f64) -> bool {
    (e as f64).abs() <= delta_px * ONE as f64 * (dx.abs() + dy.abs()) as f64
}

/// How far another implementation's vertex window coordinates may lie from ours, per axis, in
/// pixels: GL 4.6 §14.5 and Vulkan "Rasterization" require only 4 sub-pixel bits (and fix no
/// rounding mode, so up to one 1/16 grid step), ours snap to 8 bits (1/512 by rounding), and
/// the f32 window coordinates themselves carry about 1/1024 pixel at 16k. A triangle's own
/// reach adds its corners' transform error ([`Tri::reach`]).
pub const SNAP_PX: f64 = 1.0 / 16.0 + 1.0 / 512.0 + 1.0 / 1024.0;

/// One covered pixel centre: the three edge values (each ≥ 0).
#[derive(Clone, Copy, Debug)]
pub struct Fragment {
    /// Edge function values, edge i opposite vertex i; b_i = e_i / area.
    pub e: [i64; 3],
}

/// The covered pixel centres of one row of a triangle: `len` centres from column `x`.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    /// The row.
    pub y: i32,
    /// The first covered column.
    pub x: i32,
    /// How many centres, ≥ 1.
    pub len: usize,
    /// The edge values at the first centre.
    pub e: [i64; 3],
    /// What one column to the right adds to each edge value.
    pub step: [i64; 3],
}

impl Span {
    /// The span's fragments, left to right.
    pub fn fragments(&self) -> impl Iterator<Item = Fragment> + use<> {
        let (mut e, step) = (self.e, self.step);
        (0..self.len).map(move |_| {
            let f = Fragment { e };
            for i in 0..3 {
                e[i] += step[i];
            }
            f
        })
    }
}

impl Span {
    /// [`Tri::depth`] of `t` at each of the span's fragments, into `out` (cleared first):
    /// the same operations per fragment, with the edge values stepped in f64, where they are
    /// exact (integers below 2⁵³, as the i64 values converted), so that the loop has no
    /// integer conversions and the compiler vectorises it.
    pub fn depths(&self, t: &Tri, out: &mut Vec<f32>) {
        out.clear();
        out.resize(self.len, 0.0);
        let e = self.e.map(|v| v as f64);
        let step = self.step.map(|v| v as f64);
        let a = t.area as f64;
        let z = t.z.map(f64::from);
        for (k, d) in out.iter_mut().enumerate() {
            let kf = k as f64;
            let b = [
                (e[0] + kf * step[0]) / a,
                (e[1] + kf * step[1]) / a,
                (e[2] + kf * step[2]) / a,
            ];
            *d = (b[0] * z[0] + b[1] * z[1] + b[2] * z[2]) as f32;
        }
    }
}

impl Tri {
    /// Screen-space barycentrics at a fragment.
    pub fn screen_bary(&self, f: Fragment) -> [f64; 3] {
        let a = self.area as f64;
        [f.e[0] as f64 / a, f.e[1] as f64 / a, f.e[2] as f64 / a]
    }

    /// The fragment at pixel (x, y): the edge functions at its centre, exactly as [`Tri::scan`]
    /// steps to them (integer arithmetic), so that a pass may keep only which triangle won a
    /// pixel and recompute the rest for the winner alone.
    pub fn fragment_at(&self, x: i32, y: i32) -> Fragment {
        let (px, py) = (i64::from(x) * ONE + HALF, i64::from(y) * ONE + HALF);
        let mut e = [0i64; 3];
        for (i, ei) in e.iter_mut().enumerate() {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let dx = self.x[b] - self.x[a];
            let dy = self.y[b] - self.y[a];
            *ei = dx * (py - self.y[a]) - dy * (px - self.x[a]);
        }
        Fragment { e }
    }

    /// What one column to the right adds to each edge value (exact integers).
    pub fn column_step(&self) -> [i64; 3] {
        std::array::from_fn(|i| {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            -(self.y[b] - self.y[a]) * ONE
        })
    }

    /// Window depth at a fragment (linear in screen space), rounded once to f32.
    pub fn depth(&self, f: Fragment) -> f32 {
        let b = self.screen_bary(f);
        (b[0] * f64::from(self.z[0]) + b[1] * f64::from(self.z[1]) + b[2] * f64::from(self.z[2]))
            as f32
    }

    /// Perspective-correct weights on the source triangle's vertices at a fragment.
    pub fn source_weights(&self, f: Fragment) -> DVec3 {
        let b = self.screen_bary(f);
        let p = [
            b[0] * self.inv_w[0],
            b[1] * self.inv_w[1],
            b[2] * self.inv_w[2],
        ];
        let s = p[0] + p[1] + p[2];
        (self.weights[0] * p[0] + self.weights[1] * p[1] + self.weights[2] * p[2]) / s
    }

    /// Perspective-correct weights on the source triangle's vertices at any point (x, y) of
    /// the raster in pixels (inside or outside the triangle: the planes are extended).
    pub fn source_weights_at(&self, x: f64, y: f64) -> DVec3 {
        let (px, py) = (x * ONE as f64, y * ONE as f64);
        let a = self.area as f64;
        let mut b = [0f64; 3];
        for (i, bi) in b.iter_mut().enumerate() {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (
                (self.x[k] - self.x[j]) as f64,
                (self.y[k] - self.y[j]) as f64,
            );
            *bi = (dx * (py - self.y[j] as f64) - dy * (px - self.x[j] as f64)) / a;
        }
        let p = [
            b[0] * self.inv_w[0],
            b[1] * self.inv_w[1],
            b[2] * self.inv_w[2],
        ];
        let s = p[0] + p[1] + p[2];
        (self.weights[0] * p[0] + self.weights[1] * p[1] + self.weights[2] * p[2]) / s
    }

    /// Max of |∂z/∂x| and |∂z/∂y| in window depth per pixel: the polygon-offset slope m
    /// (the approximation the specs allow, and what Mesa computes).
    pub fn max_depth_slope(&self) -> f64 {
        let (dx, dy) = self.depth_slopes();
        dx.abs().max(dy.abs())
    }

    /// (∂z/∂x, ∂z/∂y) of window depth per pixel, from the snapped vertices.
    pub fn depth_slopes(&self) -> (f64, f64) {
        let px = |v: i64| v as f64 / ONE as f64;
        let (x0, y0, z0) = (px(self.x[0]), px(self.y[0]), f64::from(self.z[0]));
        let (x1, y1, z1) = (
            px(self.x[1]) - x0,
            px(self.y[1]) - y0,
            f64::from(self.z[1]) - z0,
        );
        let (x2, y2, z2) = (
            px(self.x[2]) - x0,
            px(self.y[2]) - y0,
            f64::from(self.z[2]) - z0,
        );
        let det = x1 * y2 - x2 * y1;
        ((z1 * y2 - z2 * y1) / det, (x1 * z2 - x2 * z1) / det)
    }

    /// Largest |window z| of the vertices (for the float polygon-offset unit).
    pub fn max_abs_z(&self) -> f32 {
        self.z.iter().fold(0.0f32, |m, z| m.max(z.abs()))
    }

    /// Calls `visit(x, y, fragment)` for every covered pixel centre in rows `rows`, row by
    /// row, left to right ([`Tri::scan_spans`], one centre at a time).
    pub fn scan(&self, rows: std::ops::Range<i32>, mut visit: impl FnMut(i32, i32, Fragment)) {
        self.scan_spans(rows, |span| {
            for (k, f) in span.fragments().enumerate() {
                visit(span.x + k as i32, span.y, f);
            }
        });
    }

    /// Calls `visit(span)` for the covered pixel centres of each row in rows `rows` that has
    /// any, top row first.
    ///
    /// A centre is covered when every edge value is positive, or zero on an edge the triangle
    /// owns ([`Tri::owns`]). Along a row each edge value is affine in x with an integer step,
    /// so the covered centres of a row are one interval, found exactly in integers (a ceiling
    /// or floor division per edge) rather than by testing every centre of the bounds; the
    /// edge values a span steps through are the same integers a per-centre walk computes.
    pub fn scan_spans(&self, rows: std::ops::Range<i32>, mut visit: impl FnMut(Span)) {
        let y_start = self.bbox[1].max(rows.start);
        let y_end = (self.bbox[3] + 1).min(rows.end);
        // Edge i runs from vertex i+1 to vertex i+2: E(p) = dx·(p.y − a.y) − dy·(p.x − a.x).
        let mut step_x = [0i64; 3];
        let mut step_y = [0i64; 3];
        let mut origin = [0i64; 3];
        let px0 = i64::from(self.bbox[0]) * ONE + HALF;
        for i in 0..3 {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let dx = self.x[b] - self.x[a];
            let dy = self.y[b] - self.y[a];
            step_x[i] = -dy * ONE;
            step_y[i] = dx * ONE;
            let py0 = i64::from(y_start) * ONE + HALF;
            origin[i] = dx * (py0 - self.y[a]) - dy * (px0 - self.x[a]);
        }
        // The smallest edge value that counts as inside: 0 on an owned edge, else 1.
        let least = self.owns.map(|owns| i64::from(!owns));
        let last = i64::from(self.bbox[2] - self.bbox[0]);
        for y in y_start..y_end {
            // Columns k (x = bbox[0] + k) with origin + k·step ≥ least for every edge.
            let (mut lo, mut hi) = (0i64, last);
            for i in 0..3 {
                let (e0, s) = (origin[i], step_x[i]);
                let need = least[i] - e0; // k·s ≥ need
                if s > 0 {
                    lo = lo.max(-(-need).div_euclid(s)); // ⌈need / s⌉
                } else if s < 0 {
                    hi = hi.min((-need).div_euclid(-s)); // ⌊need / s⌋ for s < 0
                } else if need > 0 {
                    hi = -1;
                }
            }
            if lo <= hi {
                visit(Span {
                    y,
                    x: self.bbox[0] + lo as i32,
                    len: (hi - lo + 1) as usize,
                    e: std::array::from_fn(|i| origin[i] + lo * step_x[i]),
                    step: step_x,
                });
            }
            for i in 0..3 {
                origin[i] += step_y[i];
            }
        }
    }

    /// The per-centre walk [`Tri::scan`] replaces, kept to test it against.
    #[cfg(test)]
    fn scan_each_centre(
        &self,
        rows: std::ops::Range<i32>,
        mut visit: impl FnMut(i32, i32, Fragment),
    ) {
        let y_start = self.bbox[1].max(rows.start);
        let y_end = (self.bbox[3] + 1).min(rows.end);
        for y in y_start..y_end {
            for x in self.bbox[0]..=self.bbox[2] {
                let f = self.fragment_at(x, y);
                let inside = |i: usize| f.e[i] > 0 || (f.e[i] == 0 && self.owns[i]);
                if inside(0) && inside(1) && inside(2) {
                    visit(x, y, f);
                }
            }
        }
    }
}

/// How a triangle covers a pixel centre, given the vertex snapping's reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// Covered whatever the snapping.
    Certain,
    /// Near one edge it shares with the drawn triangle `.0` (its index in the geometry): if
    /// that triangle is near the same edge too (not near one of its own boundaries), exactly
    /// one of the two covers the centre (the shared edge moves as a whole, and the tie rule is
    /// the implementation's).
    Pair(u32),
    /// Near a boundary of the drawn surface, or near a vertex: covered or not.
    Maybe,
}

impl Tri {
    /// Calls `visit(x, y, e, coverage)` for every pixel centre in rows `rows` of the grown
    /// bounds that this triangle covers, or could cover if each vertex moved by up to
    /// `delta_px` pixels along x and y (vertex snapping), with how it covers it
    /// ([`Coverage`]). Internal edges (fan diagonals inside one source triangle) never move:
    /// a centre exactly on one counts as covered by both sides (one plane, one depth).
    pub fn scan_near(
        &self,
        rows: std::ops::Range<i32>,
        delta_px: f64,
        mut visit: impl FnMut(i32, i32, [i64; 3], Coverage),
    ) {
        let [bx0, by0, bx1, by1] = self.near_bbox;
        let y_start = by0.max(rows.start);
        let y_end = (by1 + 1).min(rows.end);
        let mut tol = [0i64; 3];
        for i in 0..3 {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (self.x[b] - self.x[a], self.y[b] - self.y[a]);
            // A vertex moving by δ along x and y moves the edge line by δ·(|dx| + |dy|)/len
            // along its normal; E = len · distance, so E moves by δ·(|dx| + |dy|).
            if self.edges[i] != EdgeKind::Internal {
                tol[i] = (delta_px * ONE as f64 * (dx.abs() + dy.abs()) as f64).ceil() as i64;
            }
        }
        // A fan's apex (a vertex between two internal edges) is a corner of the clipped
        // polygon's outline, whose outline edges are the first and last fan triangles' and so
        // not this one's: within the snapping's reach of it, the centre may lie outside the
        // outline however far it is from this triangle's own open edges (soak-45-430: a
        // ground plane's corner snapped onto a texel centre of a cube face, reported certain
        // by the middle triangle of its fan).
        let reach = (delta_px * ONE as f64).ceil() as i64;
        let apexes: Vec<(i64, i64)> = (0..3)
            .filter(|&k| {
                self.edges[(k + 1) % 3] == EdgeKind::Internal
                    && self.edges[(k + 2) % 3] == EdgeKind::Internal
            })
            .map(|k| (self.x[k], self.y[k]))
            .collect();
        let near_apex = |px: i64, py: i64| {
            apexes
                .iter()
                .any(|&(ax, ay)| (px - ax).abs() <= reach && (py - ay).abs() <= reach)
        };
        for y in y_start..y_end {
            let py = i64::from(y) * ONE + HALF;
            for x in bx0..=bx1 {
                let px = i64::from(x) * ONE + HALF;
                let mut e = [0i64; 3];
                let (mut inside, mut near_open, mut near) = (true, false, 0);
                let mut partner = 0;
                for i in 0..3 {
                    let (a, b) = ((i + 1) % 3, (i + 2) % 3);
                    let (dx, dy) = (self.x[b] - self.x[a], self.y[b] - self.y[a]);
                    e[i] = dx * (py - self.y[a]) - dy * (px - self.x[a]);
                    inside &= e[i] >= -tol[i];
                    if e[i] <= tol[i] && tol[i] > 0 {
                        near += 1;
                        match self.edges[i] {
                            EdgeKind::Shared { tri, .. } => partner = tri,
                            _ => near_open = true,
                        }
                    }
                }
                if inside {
                    // Near a vertex (two edges at once) the triangles around it need not
                    // cover the centre between them (the vertex may lie on a silhouette,
                    // where the fan folds): only near one shared edge alone is a neighbour
                    // sure to cover what this triangle leaves.
                    let c = if near_open || near > 1 || near_apex(px, py) {
                        Coverage::Maybe
                    } else if near == 1 {
                        Coverage::Pair(partner)
                    } else {
                        Coverage::Certain
                    };
                    visit(x, y, e, c);
                }
            }
        }
    }

    /// How far, in pixels, another implementation may place this triangle's corners: the
    /// snapping ([`Tri::snap`]) and the transform ([`Tri::xy_err`]).
    pub fn reach(&self) -> f64 {
        self.snap + self.xy_err
    }

    /// Whether the centre with edge values `e` lies within `delta_px` of a diagonal the
    /// clipper added inside the source triangle ([`EdgeKind::Internal`]).
    pub fn near_internal(&self, e: [i64; 3], delta_px: f64) -> bool {
        (0..3).any(|i| {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (self.x[b] - self.x[a], self.y[b] - self.y[a]);
            self.edges[i] == EdgeKind::Internal && near_line(e[i], dx, dy, delta_px)
        })
    }

    /// Window depth at a centre given its edge values (inside or just outside: the plane is
    /// extended), in f64.
    pub fn depth_at(&self, e: [i64; 3]) -> f64 {
        let a = self.area as f64;
        (0..3).map(|i| e[i] as f64 / a * f64::from(self.z[i])).sum()
    }

    /// Σ|bᵢ|·z_errᵢ at a centre: how far the corners' transform errors ([`Tri::z_err`]) carry
    /// to the plane's value there (a corner the clipper made far away, with a large error,
    /// weighs little where its weight is small).
    pub fn depth_error_at(&self, e: [i64; 3]) -> f64 {
        let a = self.area as f64;
        (0..3)
            .map(|i| (e[i] as f64 / a).abs() * self.z_err[i])
            .sum()
    }

    /// Σ|bᵢ| of the screen-space barycentrics at a centre: 1 inside, a little more just
    /// outside (how far a vertex displacement carries to the plane's value there).
    pub fn weight_norm(&self, e: [i64; 3]) -> f64 {
        let a = self.area as f64;
        e.iter().map(|v| (*v as f64 / a).abs()).sum()
    }

    /// The smallest altitude of the triangle in pixels (how well its depth slopes are
    /// determined by its vertices).
    pub fn min_altitude(&self) -> f64 {
        let len = |i: usize| {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (
                (self.x[b] - self.x[a]) as f64,
                (self.y[b] - self.y[a]) as f64,
            );
            umbra_case::math::hypot(dx, dy)
        };
        let longest = len(0).max(len(1)).max(len(2));
        self.area as f64 / longest / ONE as f64
    }
}

/// Sets up triangles for one viewport.
#[derive(Clone, Copy, Debug)]
pub struct Rasterizer {
    /// The clip and window conventions.
    pub conv: Convention,
    /// Viewport width in pixels.
    pub width: u32,
    /// Viewport height in pixels.
    pub height: u32,
    /// Face culling.
    pub cull: Cull,
    /// Depth clamp (the shadow pass's `shadow.depth_clamp`): no clipping against the near
    /// and far planes, only against w ≥ [`CLAMP_W_MIN`] and the guard band; the fragment's
    /// depth is clamped after its offset, where the depth range's clamp is
    /// (`shadow_pass::depth_test_run`).
    pub depth_clamp: bool,
}

/// The least clip w a depth-clamped triangle keeps (clip w is the distance in front of a
/// perspective light, in scene units): GL and Vulkan clip only at x, y = ±w then, and their
/// guard-band clippers at some small w > 0; what lies nearer the light than this projects
/// outside any viewport unless it is within 4 × this of the light's axis.
pub const CLAMP_W_MIN: f32 = 1e-5;

#[derive(Clone, Copy)]
struct ClipVertex {
    clip: Vec4,
    weights: DVec3,
}

impl Rasterizer {
    /// Clips, projects, snaps and culls source triangle `source` with clip-space corners
    /// `clip`, appending 0 or more scan-ready triangles to `out`. `edges[j]` says what lies
    /// across the source edge from corner j to corner j + 1 ([`EdgeKind::Open`] everywhere
    /// when no judge needs it); edges made by clipping are open, fan diagonals internal.
    pub fn setup(&self, clip: [Vec4; 3], source: u32, edges: [EdgeKind; 3], out: &mut Vec<Tri>) {
        let Some((poly, tags)) = self.clip_polygon(clip, edges, GUARD) else {
            return;
        };
        let n = poly.len();
        for k in 1..n - 1 {
            // Fan triangle (0, k, k+1); its edge opposite corner i runs between the other two.
            let kinds = [
                tags[k],
                if k + 1 == n - 1 {
                    tags[n - 1]
                } else {
                    EdgeKind::Internal
                },
                if k == 1 { tags[0] } else { EdgeKind::Internal },
            ];
            self.setup_clipped([poly[0], poly[k], poly[k + 1]], source, kinds, out);
        }
    }

    /// The source triangle `clip` clipped by the depth planes (or, under depth clamp,
    /// w ≥ [`CLAMP_W_MIN`]) and by x, y = ±`guard`·w, with what lies across each of the
    /// polygon's edges (from vertex i to vertex i + 1); `None` when nothing is left.
    fn clip_polygon(
        &self,
        clip: [Vec4; 3],
        edges: [EdgeKind; 3],
        guard: f32,
    ) -> Option<(Vec<ClipVertex>, Vec<EdgeKind>)> {
        let zmin = self.conv.clip_z_min_over_w();
        // Plane (p, c): p · (x, y, z, w) + c ≥ 0. Depth clamp trades the near and far planes
        // for w ≥ CLAMP_W_MIN.
        let near_far = [
            (Vec4::new(0.0, 0.0, 1.0, -zmin), 0.0),
            (Vec4::new(0.0, 0.0, -1.0, 1.0), 0.0),
        ];
        let clamped = [(Vec4::W, -CLAMP_W_MIN)];
        let depth_planes: &[(Vec4, f32)] = if self.depth_clamp {
            &clamped
        } else {
            &near_far
        };
        let planes = depth_planes.iter().copied().chain([
            (Vec4::new(-1.0, 0.0, 0.0, guard), 0.0),
            (Vec4::new(1.0, 0.0, 0.0, guard), 0.0),
            (Vec4::new(0.0, -1.0, 0.0, guard), 0.0),
            (Vec4::new(0.0, 1.0, 0.0, guard), 0.0),
        ]);
        let mut poly: Vec<ClipVertex> = vec![
            ClipVertex {
                clip: clip[0],
                weights: DVec3::X,
            },
            ClipVertex {
                clip: clip[1],
                weights: DVec3::Y,
            },
            ClipVertex {
                clip: clip[2],
                weights: DVec3::Z,
            },
        ];
        if clip.iter().any(|c| !c.is_finite()) {
            return None;
        }
        // What lies across the polygon's edge from vertex i to vertex i + 1.
        let mut tags = edges.to_vec();
        for (plane, c) in planes {
            let d: Vec<f32> = poly.iter().map(|v| plane.dot(v.clip) + c).collect();
            if d.iter().all(|&x| x >= 0.0) {
                continue;
            }
            let mut next = Vec::with_capacity(poly.len() + 1);
            let mut next_tags = Vec::with_capacity(poly.len() + 1);
            for i in 0..poly.len() {
                let j = (i + 1) % poly.len();
                let (a, b, da, db) = (poly[i], poly[j], d[i], d[j]);
                if da >= 0.0 {
                    next.push(a);
                    next_tags.push(tags[i]);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    // From the outside corner, whichever way this triangle walks the edge: a
                    // neighbour sharing the edge walks it the other way and must make the
                    // same f32 corner, or a crack opens between them that the judge, which
                    // holds a shared edge watertight, calls impossible (found by the soak:
                    // seed 39, case 844, a floor diagonal clipped by the near plane).
                    let (from, to, d_from, d_to) = if da < 0.0 {
                        (a, b, da, db)
                    } else {
                        (b, a, db, da)
                    };
                    let t = d_from / (d_from - d_to);
                    next.push(ClipVertex {
                        clip: from.clip + (to.clip - from.clip) * t,
                        weights: from.weights + (to.weights - from.weights) * f64::from(t),
                    });
                    // Leaving the volume, the next edge runs along the clip plane; entering
                    // it, the rest of the source edge follows.
                    next_tags.push(if da >= 0.0 { EdgeKind::Open } else { tags[i] });
                }
            }
            poly = next;
            tags = next_tags;
            if poly.len() < 3 {
                return None;
            }
        }
        Some((poly, tags))
    }

    /// Under the edge-holes deviation: the chords (lines between two vertices that are not
    /// neighbours) of the polygon a rasterizer *without* a guard band makes of the source
    /// triangle `clip`, clipped at the viewport (x, y = ±w) and the depth planes. Such a
    /// clipper fans the polygon from a vertex of its own choosing (Mesa's draw module:
    /// `draw_pipe_clip.c`, from the polygon's first vertex after its plane order), so any
    /// chord may be a fan diagonal; umbra's own clipper, with its guard band, puts its
    /// diagonals elsewhere (soak-42-364: softpipe's holes on the viewport's anti-diagonal).
    pub fn viewport_chords(&self, clip: [Vec4; 3]) -> Vec<Chord> {
        let Some((poly, _)) = self.clip_polygon(clip, [EdgeKind::Open; 3], 1.0) else {
            return Vec::new();
        };
        if poly.len() < 4 || poly.iter().any(|v| v.clip.w <= 0.0) {
            return Vec::new();
        }
        let at: Vec<[i64; 2]> = poly.iter().map(|v| self.window_fixed(v.clip)).collect();
        let n = at.len();
        let mut out = Vec::new();
        for i in 0..n {
            // Skip the neighbours and, for vertex 0, the chord to n − 1 (its neighbour too).
            for j in i + 2..n - usize::from(i == 0) {
                out.push(Chord {
                    from: at[i],
                    to: at[j],
                });
            }
        }
        out
    }

    /// A clip-space vertex (w > 0) in window coordinates, snapped to 1/256 px.
    fn window_fixed(&self, c: Vec4) -> [i64; 2] {
        let (wx, wy) = self
            .conv
            .window_xy(c.x / c.w, c.y / c.w, self.width, self.height);
        [wx, wy].map(|w| (f64::from(w) * ONE as f64).round() as i64)
    }

    fn setup_clipped(
        &self,
        v: [ClipVertex; 3],
        source: u32,
        mut edges: [EdgeKind; 3],
        out: &mut Vec<Tri>,
    ) {
        let mut x = [0i64; 3];
        let mut y = [0i64; 3];
        let mut z = [0f32; 3];
        let mut inv_w = [0f64; 3];
        for i in 0..3 {
            let c = v[i].clip;
            if c.w <= 0.0 {
                return;
            }
            [x[i], y[i]] = self.window_fixed(c);
            z[i] = self.conv.window_depth(c.z / c.w);
            inv_w[i] = 1.0 / f64::from(c.w);
        }
        let area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        if area == 0 {
            return;
        }
        let front = (area > 0) != self.conv.window_y_down();
        match self.cull {
            Cull::Back if !front => return,
            Cull::Front if front => return,
            _ => {}
        }
        let mut weights = [v[0].weights, v[1].weights, v[2].weights];
        let mut area = area;
        if area < 0 {
            x.swap(1, 2);
            y.swap(1, 2);
            z.swap(1, 2);
            inv_w.swap(1, 2);
            weights.swap(1, 2);
            // The edge opposite corner 0 is the same; those opposite 1 and 2 trade places.
            edges.swap(1, 2);
            area = -area;
        }
        let mut owns = [false; 3];
        for i in 0..3 {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (x[b] - x[a], y[b] - y[a]);
            owns[i] = dy < 0 || (dy == 0 && dx > 0);
        }
        let lo = |v: i64| (v - HALF + ONE - 1).div_euclid(ONE);
        let hi = |v: i64| (v - HALF).div_euclid(ONE);
        let (w_max, h_max) = (i64::from(self.width) - 1, i64::from(self.height) - 1);
        let (min_x, max_x) = (*x.iter().min().unwrap_or(&0), *x.iter().max().unwrap_or(&0));
        let (min_y, max_y) = (*y.iter().min().unwrap_or(&0), *y.iter().max().unwrap_or(&0));
        let near = [
            (lo(min_x) - 1).max(0),
            (lo(min_y) - 1).max(0),
            (hi(max_x) + 1).min(w_max),
            (hi(max_y) + 1).min(h_max),
        ];
        if near[0] > near[2] || near[1] > near[3] {
            return;
        }
        let bbox = [
            lo(min_x).max(0),
            lo(min_y).max(0),
            hi(max_x).min(w_max),
            hi(max_y).min(h_max),
        ];
        out.push(Tri {
            x,
            y,
            z,
            inv_w,
            weights,
            area,
            owns,
            bbox: bbox.map(|v| v as i32),
            near_bbox: near.map(|v| v as i32),
            edges,
            source,
            front,
            z_err: [0.0; 3],
            xy_err: 0.0,
            snap: SNAP_PX,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(r: &Rasterizer, pts: [[f32; 2]; 3]) -> Vec<Tri> {
        let mut out = Vec::new();
        let clip = pts.map(|p| Vec4::new(p[0], p[1], 0.0, 1.0));
        r.setup(clip, 0, [EdgeKind::Open; 3], &mut out);
        out
    }

    fn coverage(r: &Rasterizer, tris: &[Tri]) -> Vec<u32> {
        let mut hits = vec![0u32; (r.width * r.height) as usize];
        for t in tris {
            t.scan(0..r.height as i32, |x, y, _| {
                hits[(y as u32 * r.width + x as u32) as usize] += 1
            });
        }
        hits
    }

    #[test]
    fn shared_edges_cover_each_pixel_exactly_once() {
        // A fan of triangles around a centre that sits exactly on a pixel centre, with edges
        // through many pixel centres: every pixel inside the square is hit exactly once.
        for conv in [Convention::GL, Convention::ZERO_TO_ONE] {
            let r = Rasterizer {
                conv,
                width: 16,
                height: 16,
                cull: Cull::None,
                depth_clamp: false,
            };
            // NDC of pixel centre (8.5, 8.5) in a 16-wide viewport: (8.5/8 − 1).
            let c = [8.5 / 8.0 - 1.0, 8.5 / 8.0 - 1.0];
            let ring = [
                [-1.0, -1.0],
                [1.0, -1.0],
                [1.0, 1.0],
                [-1.0, 1.0],
                [-1.0, 0.0],
            ];
            let mut tris = Vec::new();
            for i in 0..ring.len() {
                tris.extend(tri(&r, [c, ring[i], ring[(i + 1) % ring.len()]]));
            }
            // Plus a diagonal split of the same square, drawn separately.
            let hits = coverage(&r, &tris);
            assert!(hits.iter().all(|&h| h == 1), "{conv:?}: {hits:?}");
            let diag = [
                tri(&r, [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0]]),
                tri(&r, [[-1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]),
            ]
            .concat();
            assert!(
                coverage(&r, &diag).iter().all(|&h| h == 1),
                "{conv:?} diagonal"
            );
        }
    }

    #[test]
    fn a_shared_edge_the_near_plane_clips_makes_one_corner_in_both_triangles() {
        // Quads split along a diagonal whose far corner lies behind the near plane: each
        // triangle clips the diagonal walking it its own way, and both must make the same
        // snapped corner there, or a crack opens between them. 500 quads, so that the two
        // walks' f32 roundings would differ somewhere if they could.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        for conv in [Convention::GL, Convention::ZERO_TO_ONE] {
            let r = Rasterizer {
                conv,
                width: 997,
                height: 991,
                cull: Cull::None,
                depth_clamp: false,
            };
            let zmin = conv.clip_z_min_over_w();
            for _ in 0..500 {
                let behind_depth = next();
                let mut corner = |x: f32, y: f32, z: f32| {
                    let w = 0.5 + 3.0 * next();
                    Vec4::new(x * w, y * w, z * w, w)
                };
                let behind = zmin - 0.1 - behind_depth;
                let q = [
                    corner(-0.9, -0.9, 0.4),
                    corner(0.9, -0.95, 0.3),
                    corner(0.93, 0.9, behind),
                    corner(-0.95, 0.91, 0.2),
                ];
                let corners = |src: [usize; 3]| {
                    let mut out = Vec::new();
                    r.setup(src.map(|i| q[i]), 0, [EdgeKind::Open; 3], &mut out);
                    out.iter()
                        .flat_map(|t| (0..3).map(move |k| (t.x[k], t.y[k])))
                        .collect::<std::collections::HashSet<_>>()
                };
                let (a, b) = (corners([0, 1, 2]), corners([0, 2, 3]));
                // Corner 0 and the diagonal's clipped end.
                assert_eq!(a.intersection(&b).count(), 2, "{conv:?}: {q:?}");
            }
        }
    }

    #[test]
    fn the_span_scan_visits_what_the_per_centre_walk_visits() {
        // Random triangles, some far outside the viewport, some thin, some on pixel centres:
        // the same fragments, with the same edge values, in the same order.
        for conv in [Convention::GL, Convention::ZERO_TO_ONE] {
            let r = Rasterizer {
                conv,
                width: 64,
                height: 48,
                cull: Cull::None,
                depth_clamp: false,
            };
            let mut next = crate::test_rng::uniform(0x9e37_79b9_7f4a_7c15);
            let mut fragments = 0;
            for k in 0..4000 {
                let spread = [1.1, 3.0, 0.2][k % 3];
                let snap = |v: f32| {
                    if k % 5 == 0 {
                        (v * 16.0).round() / 16.0
                    } else {
                        v
                    }
                };
                let pts: [[f32; 2]; 3] = std::array::from_fn(|_| {
                    [
                        snap((next() * 2.0 - 1.0) * spread),
                        snap((next() * 2.0 - 1.0) * spread),
                    ]
                });
                for t in tri(&r, pts) {
                    let (mut a, mut b) = (Vec::new(), Vec::new());
                    t.scan(0..48, |x, y, f| a.push((x, y, f.e)));
                    t.scan_each_centre(0..48, |x, y, f| b.push((x, y, f.e)));
                    assert_eq!(a, b, "{conv:?} {pts:?}");
                    // And band by band, as the passes call it.
                    let mut c = Vec::new();
                    for band in (0..48).step_by(8) {
                        t.scan(band..band + 8, |x, y, f| c.push((x, y, f.e)));
                    }
                    assert_eq!(a, c);
                    fragments += a.len();
                }
            }
            assert!(fragments > 100_000, "{fragments}");
        }
    }

    #[test]
    fn facing_and_culling_follow_ndc_winding() {
        for conv in [Convention::GL, Convention::ZERO_TO_ONE] {
            let ccw = [[-0.5, -0.5], [0.5, -0.5], [0.0, 0.5]];
            let cw = [ccw[0], ccw[2], ccw[1]];
            let back = Rasterizer {
                conv,
                width: 8,
                height: 8,
                cull: Cull::Back,
                depth_clamp: false,
            };
            assert_eq!(tri(&back, ccw).len(), 1, "{conv:?}");
            assert!(tri(&back, cw).is_empty(), "{conv:?}");
            let front = Rasterizer {
                cull: Cull::Front,
                ..back
            };
            assert!(tri(&front, ccw).is_empty(), "{conv:?}");
            let none = Rasterizer {
                cull: Cull::None,
                ..back
            };
            assert!(
                !tri(&none, cw)[0].front,
                "{conv:?}: clockwise is a back face"
            );
        }
    }

    #[test]
    fn gl_rows_count_from_the_bottom_and_zero_to_one_rows_from_the_top() {
        let upper = [[-1.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let gl = Rasterizer {
            conv: Convention::GL,
            width: 4,
            height: 4,
            cull: Cull::None,
            depth_clamp: false,
        };
        let zo = Rasterizer {
            conv: Convention::ZERO_TO_ONE,
            ..gl
        };
        assert!(tri(&gl, upper)[0].bbox[1] >= 2);
        assert!(tri(&zo, upper)[0].bbox[3] <= 1);
    }

    #[test]
    fn near_plane_clipping_keeps_the_part_in_front() {
        let r = Rasterizer {
            conv: Convention::ZERO_TO_ONE,
            width: 8,
            height: 8,
            cull: Cull::None,
            depth_clamp: false,
        };
        let mut out = Vec::new();
        let clip = [
            Vec4::new(-1.0, -1.0, -1.0, 1.0),
            Vec4::new(1.0, -1.0, 0.5, 1.0),
            Vec4::new(0.0, 1.0, 0.5, 1.0),
        ];
        r.setup(clip, 7, [EdgeKind::Open; 3], &mut out);
        assert!(!out.is_empty());
        for t in &out {
            assert!(t.z.iter().all(|z| (-1e-6..=1.0).contains(z)), "{:?}", t.z);
            assert_eq!(t.source, 7);
        }
    }

    /// A triangle clipped at both the near and the far plane is a pentagon, fanned from one
    /// corner: the middle triangle's apex lies between two internal edges and is a corner of
    /// the outline, so no centre within the snapping's reach of it is certain (soak-45-430).
    #[test]
    fn a_fan_apex_is_an_outline_corner() {
        let r = Rasterizer {
            conv: Convention::GL,
            width: 64,
            height: 64,
            cull: Cull::None,
            depth_clamp: false,
        };
        let clip = [
            Vec4::new(-0.8, -0.8, -3.0, 1.0),
            Vec4::new(0.8, -0.8, 3.0, 1.0),
            Vec4::new(0.0, 0.8, 0.0, 1.0),
        ];
        let mut out = Vec::new();
        r.setup(clip, 0, [EdgeKind::Open; 3], &mut out);
        assert_eq!(out.len(), 3, "a pentagon's fan");
        let middle = out
            .iter()
            .find(|t| t.edges[1] == EdgeKind::Internal && t.edges[2] == EdgeKind::Internal)
            .expect("the middle triangle has two internal edges at its apex");
        let (ax, ay) = (middle.x[0], middle.y[0]);
        let mut near = 0;
        middle.scan_near(0..64, 1.0, |x, y, _, coverage| {
            let (px, py) = (i64::from(x) * ONE + HALF, i64::from(y) * ONE + HALF);
            if (px - ax).abs() <= ONE && (py - ay).abs() <= ONE {
                near += 1;
                assert_eq!(coverage, Coverage::Maybe, "({x}, {y}) beside the apex");
            }
        });
        assert!(near > 0, "no centre beside the apex was checked");
    }

    /// A triangle over the whole viewport is, clipped at the viewport, its square: the chords
    /// a clipper without a guard band may fan along are both diagonals, whichever corner it
    /// starts from (soak-42-364: softpipe's holes on the anti-diagonal), and a centre off
    /// them is on none.
    #[test]
    fn a_viewport_covering_triangle_has_both_diagonals_as_chords() {
        let r = Rasterizer {
            conv: Convention::GL,
            width: 8,
            height: 8,
            cull: Cull::None,
            depth_clamp: false,
        };
        let clip = [[-5.0, -1.0], [5.0, -1.0], [0.0, 9.0]].map(|p| Vec4::new(p[0], p[1], 0.0, 1.0));
        let chords = r.viewport_chords(clip);
        assert_eq!(chords.len(), 2, "{chords:?}");
        let on = |x: i32, y: i32| chords.iter().filter(|c| c.near(x, y, 1.0 / 64.0)).count();
        for k in 0..8 {
            assert_eq!(on(k, k), 1, "main diagonal at {k}");
            assert_eq!(on(k, 7 - k), 1, "anti-diagonal at {k}");
        }
        assert_eq!(on(0, 3), 0);
        // Inside the viewport nothing is clipped: a triangle has no chord.
        let small =
            [[-0.5, -0.5], [0.5, -0.5], [0.0, 0.5]].map(|p| Vec4::new(p[0], p[1], 0.0, 1.0));
        assert!(r.viewport_chords(small).is_empty());
    }
}
