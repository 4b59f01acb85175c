//! Edge displacement: how far, in pixels, a frame's shadow edges lie from the true ones.
//!
//! Over the judged pixels (truth class lit or shadowed), a pixel is on an edge of a mask when
//! one of its 4-neighbours is judged and has the other answer. Each edge pixel of the frame
//! gets its distance to the nearest true edge pixel (a two-pass 3-4 chamfer transform, within
//! 8 % of Euclidean); the displacement is the mean and the maximum of those distances. Acne
//! shows as a large mean (speckle far from any true edge), aliasing as a mean of a pixel or
//! two, peter-panning as a mean near the detachment width.

use umbra_case::LightFrame;
use umbra_ref::truth::{Class, Truth};

use crate::is_shadowed;

/// Edge displacement of a frame against the truth.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct EdgeDisplacement {
    /// Edge pixels of the frame's mask.
    pub frame_edges: u64,
    /// Edge pixels of the true mask.
    pub true_edges: u64,
    /// Mean distance from a frame edge pixel to the nearest true edge pixel (None when either
    /// mask has no edge).
    pub mean_px: Option<f64>,
    /// Largest such distance.
    pub max_px: Option<f64>,
}

/// Measures `frame`'s shadow edges against `truth`'s (same size).
pub fn edge_displacement(frame: LightFrame, truth: &Truth) -> EdgeDisplacement {
    let (w, h) = (truth.width as usize, truth.height as usize);
    let judged = |i: usize| matches!(truth.class[i], Class::Lit | Class::Shadowed);
    let truly = |i: usize| truth.class[i] == Class::Shadowed;
    let says = |i: usize| is_shadowed(frame.visibility[i]);
    let edges = |answer: &dyn Fn(usize) -> bool| -> Vec<bool> {
        (0..w * h)
            .map(|i| {
                if !judged(i) {
                    return false;
                }
                let (x, y) = (i % w, i / w);
                let mut n = Vec::with_capacity(4);
                if x > 0 {
                    n.push(i - 1);
                }
                if x + 1 < w {
                    n.push(i + 1);
                }
                if y > 0 {
                    n.push(i - w);
                }
                if y + 1 < h {
                    n.push(i + w);
                }
                n.into_iter().any(|j| judged(j) && answer(j) != answer(i))
            })
            .collect()
    };
    let true_edges = edges(&truly);
    let frame_edges = edges(&says);
    let mut out = EdgeDisplacement {
        frame_edges: frame_edges.iter().filter(|e| **e).count() as u64,
        true_edges: true_edges.iter().filter(|e| **e).count() as u64,
        ..Default::default()
    };
    if out.frame_edges == 0 || out.true_edges == 0 {
        return out;
    }
    let dist = chamfer(&true_edges, w, h);
    let (mut sum, mut max) = (0.0f64, 0.0f64);
    for (i, e) in frame_edges.iter().enumerate() {
        if *e {
            let d = f64::from(dist[i]) / 3.0;
            sum += d;
            max = max.max(d);
        }
    }
    out.mean_px = Some(sum / out.frame_edges as f64);
    out.max_px = Some(max);
    out
}

/// 3-4 chamfer distance (in thirds of a pixel) to the nearest `true` cell.
fn chamfer(seeds: &[bool], w: usize, h: usize) -> Vec<u32> {
    const FAR: u32 = u32::MAX / 2;
    let mut d: Vec<u32> = seeds.iter().map(|s| if *s { 0 } else { FAR }).collect();
    let at = |x: usize, y: usize| y * w + x;
    for y in 0..h {
        for x in 0..w {
            let mut v = d[at(x, y)];
            if x > 0 {
                v = v.min(d[at(x - 1, y)] + 3);
            }
            if y > 0 {
                v = v.min(d[at(x, y - 1)] + 3);
                if x > 0 {
                    v = v.min(d[at(x - 1, y - 1)] + 4);
                }
                if x + 1 < w {
                    v = v.min(d[at(x + 1, y - 1)] + 4);
                }
            }
            d[at(x, y)] = v;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let mut v = d[at(x, y)];
            if x + 1 < w {
                v = v.min(d[at(x + 1, y)] + 3);
            }
            if y + 1 < h {
                v = v.min(d[at(x, y + 1)] + 3);
                if x + 1 < w {
                    v = v.min(d[at(x + 1, y + 1)] + 4);
                }
                if x > 0 {
                    v = v.min(d[at(x - 1, y + 1)] + 4);
                }
            }
            d[at(x, y)] = v;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chamfer_is_exact_along_axes_and_close_on_diagonals() {
        let (w, h) = (9, 9);
        let mut seeds = vec![false; w * h];
        seeds[4 * w + 4] = true;
        let d = chamfer(&seeds, w, h);
        assert_eq!(d[4 * w + 8], 12); // 4 px along x: 4 × 3
        assert_eq!(d[0], 16); // 4 diagonal steps: 4 × 4 (exact 4√2·3 ≈ 17)
    }
}
