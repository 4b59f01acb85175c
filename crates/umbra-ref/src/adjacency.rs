//! Which triangle edges are shared, per view: the input of the judge's coverage freedom.
//!
//! GL and Vulkan snap vertices to a sub-pixel grid of at least 4 bits, so another
//! implementation's triangles may cover pixel centres up to 1/16 pixel beyond ours. That moves
//! the *boundary* of what is drawn, but not an edge between two drawn triangles: both snap the
//! same shared vertices (the same positions through the same matrix give the same window
//! coordinates, GL 4.6 "Invariance", Vulkan "Invariance"), so the edge moves as a whole and
//! every centre near it stays covered by one of the two. An edge is *shared* in a view when
//! another drawn (not culled, not degenerate) triangle has the same two corner positions and
//! lies on the other side of it on screen; every other edge is *open*.
//!
//! Positions are matched bitwise: the tessellation writes each shared vertex once per
//! triangle corner, from the same f32 value.

use std::collections::HashMap;

use glam::{DVec2, Mat4, Vec3};
use umbra_case::Geometry;
use umbra_case::format::Cull;

use crate::raster::EdgeKind;

/// For every triangle and local edge j (corner j → j + 1): the other triangles with the same
/// edge, each as (triangle, its corner opposite the edge).
pub struct Adjacency {
    neighbours: Vec<[Vec<(u32, u32)>; 3]>,
}

type Key = ([u32; 3], [u32; 3]);

fn bits(p: Vec3) -> [u32; 3] {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

impl Adjacency {
    /// Builds the edge table of `geo`.
    pub fn new(geo: &Geometry) -> Adjacency {
        let mut by_edge: HashMap<Key, Vec<(u32, u32)>> = HashMap::new();
        for (t, tri) in geo.triangles.iter().enumerate() {
            for j in 0..3 {
                let (a, b) = (
                    bits(geo.positions[tri[j] as usize]),
                    bits(geo.positions[tri[(j + 1) % 3] as usize]),
                );
                let key = if a <= b { (a, b) } else { (b, a) };
                by_edge
                    .entry(key)
                    .or_default()
                    .push((t as u32, tri[(j + 2) % 3]));
            }
        }
        let neighbours = geo
            .triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                std::array::from_fn(|j| {
                    let (a, b) = (
                        bits(geo.positions[tri[j] as usize]),
                        bits(geo.positions[tri[(j + 1) % 3] as usize]),
                    );
                    let key = if a <= b { (a, b) } else { (b, a) };
                    by_edge
                        .get(&key)
                        .map(|v| {
                            v.iter()
                                .filter(|(other, _)| *other as usize != t)
                                .copied()
                                .collect()
                        })
                        .unwrap_or_default()
                })
            })
            .collect();
        Adjacency { neighbours }
    }

    /// What lies across each edge of each triangle in the view `view_proj` with culling
    /// `cull` (front = counter-clockwise in NDC, y up). Edges whose corners are not all in
    /// front of the eye (w ≤ 0) are open: clipping decides there.
    pub fn edge_kinds(&self, geo: &Geometry, view_proj: Mat4, cull: Cull) -> Vec<[EdgeKind; 3]> {
        let ndc: Vec<Option<DVec2>> = geo
            .positions
            .iter()
            .map(|p| {
                let c = view_proj * p.extend(1.0);
                (c.w > 0.0).then(|| DVec2::new(f64::from(c.x / c.w), f64::from(c.y / c.w)))
            })
            .collect();
        let cross = |a: DVec2, b: DVec2, o: DVec2| (b - a).perp_dot(o - a);
        let drawn = |t: usize| -> bool {
            let [a, b, c] = geo.triangles[t].map(|i| ndc[i as usize]);
            let (Some(a), Some(b), Some(c)) = (a, b, c) else {
                return true; // partly behind the eye: clipped, kept
            };
            let area = cross(a, b, c);
            area != 0.0
                && match cull {
                    Cull::None => true,
                    Cull::Back => area > 0.0,
                    Cull::Front => area < 0.0,
                }
        };
        geo.triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                std::array::from_fn(|j| {
                    let (a, b, o) = (
                        ndc[tri[j] as usize],
                        ndc[tri[(j + 1) % 3] as usize],
                        ndc[tri[(j + 2) % 3] as usize],
                    );
                    let (Some(a), Some(b), Some(o)) = (a, b, o) else {
                        return EdgeKind::Open;
                    };
                    let mine = cross(a, b, o);
                    self.neighbours[t][j]
                        .iter()
                        .find(|(other, opposite)| {
                            ndc[*opposite as usize].is_some_and(|q| cross(a, b, q) * mine < 0.0)
                                && drawn(*other as usize)
                        })
                        .map_or(EdgeKind::Open, |(other, _)| EdgeKind::Shared {
                            face: geo.face[*other as usize],
                            tri: *other,
                        })
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use umbra_case::format::{Extent, Object, Plane, Scene};

    #[test]
    fn a_quad_s_diagonal_is_shared_and_its_border_open() {
        let geo = umbra_case::tessellate(&Scene {
            objects: vec![Object::Plane(Plane {
                point: [0.0; 3],
                normal: [0.0, 0.0, 1.0],
                half_extent: Extent::Square(1.0),
                color: [0.8; 3],
                transform: None,
            })],
            offset: [0.0; 3],
        });
        let adj = Adjacency::new(&geo);
        let kinds = adj.edge_kinds(&geo, Mat4::IDENTITY, Cull::None);
        let shared: usize = kinds
            .iter()
            .flatten()
            .filter(|k| matches!(k, EdgeKind::Shared { .. }))
            .count();
        let open = kinds
            .iter()
            .flatten()
            .filter(|k| **k == EdgeKind::Open)
            .count();
        assert_eq!((shared, open), (2, 4), "{kinds:?}");
        // Seen edge-on, nothing is shared: both triangles are degenerate.
        let edge_on = Mat4::from_cols(glam::Vec4::X, glam::Vec4::Z, glam::Vec4::Y, glam::Vec4::W);
        let kinds = adj.edge_kinds(&geo, edge_on, Cull::None);
        assert!(kinds.iter().flatten().all(|k| *k == EdgeKind::Open));
    }
}
