//! A bounding-volume hierarchy over the scene's triangles in f64, median split on the widest
//! centroid axis, leaves of up to 4 triangles. Traversal visits children nearest first and
//! prunes by the current hit distance. Box tests are padded by a relative 1e-9 so a ray that
//! grazes a box face still enters it: pruning must never lose a hit the exact test would find.

use glam::DVec3;
use umbra_case::Geometry;
use umbra_case::format::Cull;

use super::ray::Ray;

const LEAF: usize = 4;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle in `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Leaf: triangle count; inner: 0.
    count: u32,
}

/// The hierarchy plus the triangles it indexes.
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    verts: Vec<[DVec3; 3]>,
    face: Vec<u32>,
}

/// A hit: triangle, distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Triangle index.
    pub tri: u32,
    /// Distance along the ray, in units of its direction.
    pub t: f64,
}

impl Bvh {
    /// Builds the hierarchy over `geo`'s triangles.
    pub fn new(geo: &Geometry) -> Self {
        let verts: Vec<[DVec3; 3]> = (0..geo.triangles.len())
            .map(|t| geo.corners(t).map(|p| p.as_dvec3()))
            .collect();
        let mut order: Vec<u32> = (0..verts.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * verts.len() / LEAF + 1);
        nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            start: 0,
            count: 0,
        });
        build(&verts, &mut order, &mut nodes, 0, 0, verts.len());
        // Pad every box once here rather than in every test.
        for n in &mut nodes {
            let pad = (n.hi - n.lo).max_element().max(1.0) * 1e-9;
            (n.lo, n.hi) = (n.lo - pad, n.hi + pad);
        }
        Bvh {
            nodes,
            order,
            verts,
            face: geo.face.clone(),
        }
    }

    /// The corners of triangle `t`.
    pub fn corners(&self, t: u32) -> [DVec3; 3] {
        self.verts[t as usize]
    }

    /// The nearest hit in (t_min, t_max).
    pub fn closest(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
        self.closest_facing(ray, t_min, t_max, Cull::None)
    }

    /// The nearest hit in (t_min, t_max) on a triangle that `cull` keeps: a triangle is
    /// front-facing where its corners run counter-clockwise seen from the ray's origin
    /// (its normal (b − a) × (c − a) points against the ray), as a rasteriser's front face
    /// is; an edge-on triangle (normal ⟂ ray) covers nothing and is culled either way.
    pub fn closest_facing(&self, ray: &Ray, t_min: f64, t_max: f64, cull: Cull) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        self.walk(ray, t_min, &mut limit, &mut |tri, t, limit| {
            if cull != Cull::None {
                let [a, b, c] = self.verts[tri as usize];
                let facing = (b - a).cross(c - a).dot(ray.dir);
                let kept = match cull {
                    Cull::Back => facing < 0.0,
                    Cull::Front => facing > 0.0,
                    Cull::None => true,
                };
                if !kept {
                    return false;
                }
            }
            if t < *limit {
                *limit = t;
                best = Some(Hit { tri, t });
            }
            false
        });
        best
    }

    /// Whether anything but face `skip_face` is hit in (t_min, t_max).
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64, skip_face: u32) -> bool {
        let mut found = false;
        let mut limit = t_max;
        self.walk(ray, t_min, &mut limit, &mut |tri, _, _| {
            if self.face[tri as usize] == skip_face {
                return false;
            }
            found = true;
            true
        });
        found
    }

    /// Visits the leaves' triangles nearest box first. Each child's entry distance is
    /// computed once, when its parent is visited, and kept on the stack: when it is popped,
    /// `enter` with the (possibly lowered) limit would fail exactly when that entry lies
    /// beyond the limit (the entry is already at or before the box's exit), so the check is a
    /// comparison. The stack is a fixed array (depth ≤ 2·log₂ of the triangle count + 2, far
    /// below its size for any scene that fits in memory), so a walk allocates nothing.
    fn walk(
        &self,
        ray: &Ray,
        t_min: f64,
        limit: &mut f64,
        on_hit: &mut dyn FnMut(u32, f64, &mut f64) -> bool,
    ) {
        if self.verts.is_empty() {
            return;
        }
        let root = &self.nodes[0];
        let Some(t_root) = enter(ray, root.lo, root.hi, t_min, *limit) else {
            return;
        };
        let mut stack = [(0usize, 0f64); 128];
        stack[0] = (0, t_root);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let (n, t_entry) = stack[depth];
            if t_entry > *limit {
                continue;
            }
            let node = self.nodes[n];
            if node.count > 0 {
                for &tri in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    let [a, b, c] = self.verts[tri as usize];
                    if let Some(t) = ray.hit(a, b, c, t_min, *limit) {
                        if on_hit(tri, t, limit) {
                            return;
                        }
                    }
                }
            } else {
                let (l, r) = (node.start as usize, node.start as usize + 1);
                let dl = enter(ray, self.nodes[l].lo, self.nodes[l].hi, t_min, *limit);
                let dr = enter(ray, self.nodes[r].lo, self.nodes[r].hi, t_min, *limit);
                let mut push = |node: usize, t: f64| {
                    stack[depth] = (node, t);
                    depth += 1;
                };
                match (dl, dr) {
                    (Some(a), Some(b)) if a <= b => {
                        push(r, b);
                        push(l, a);
                    }
                    (Some(a), Some(b)) => {
                        push(l, a);
                        push(r, b);
                    }
                    (Some(a), None) => push(l, a),
                    (None, Some(b)) => push(r, b),
                    (None, None) => {}
                }
            }
        }
    }
}

/// Entry distance into a (padded) box, if the ray meets it within (t_min, t_max).
fn enter(ray: &Ray, lo: DVec3, hi: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
    let mut t0 = t_min;
    let mut t1 = t_max;
    for k in 0..3 {
        let inv = ray.inv_dir[k];
        let (mut a, mut b) = ((lo[k] - ray.origin[k]) * inv, (hi[k] - ray.origin[k]) * inv);
        if inv.is_infinite() {
            // Parallel to this slab: inside or never.
            if ray.origin[k] < lo[k] || ray.origin[k] > hi[k] {
                return None;
            }
            continue;
        }
        if a > b {
            std::mem::swap(&mut a, &mut b);
        }
        t0 = t0.max(a);
        t1 = t1.min(b);
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}

fn build(
    verts: &[[DVec3; 3]],
    order: &mut [u32],
    nodes: &mut Vec<Node>,
    at: usize,
    start: usize,
    end: usize,
) {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for &t in &order[start..end] {
        for p in verts[t as usize] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let c = centroid(&verts[t as usize]);
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let count = end - start;
    let ext = chi - clo;
    if count <= LEAF || ext.max_element() == 0.0 {
        nodes[at] = Node {
            lo,
            hi,
            start: start as u32,
            count: count as u32,
        };
        return;
    }
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = start + count / 2;
    order[start..end].select_nth_unstable_by(count / 2, |a, b| {
        let (ca, cb) = (
            centroid(&verts[*a as usize])[axis],
            centroid(&verts[*b as usize])[axis],
        );
        ca.total_cmp(&cb).then(a.cmp(b))
    });
    let left = nodes.len();
    nodes.push(Node {
        lo,
        hi,
        start: 0,
        count: 0,
    });
    nodes.push(Node {
        lo,
        hi,
        start: 0,
        count: 0,
    });
    nodes[at] = Node {
        lo,
        hi,
        start: left as u32,
        count: 0,
    };
    build(verts, order, nodes, left, start, mid);
    build(verts, order, nodes, left + 1, mid, end);
}

fn centroid(t: &[DVec3; 3]) -> DVec3 {
    (t[0] + t[1] + t[2]) / 3.0
}
