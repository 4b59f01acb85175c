//! A block of map texels' answers to one compare, read once, with prefix counts of each kind
//! of answer, so that any sub-block's one definite answer (if it has one) or the hull of
//! what its texels may answer costs a few reads. Castano's filter asks this of nine taps for
//! every base texel the coordinate may take, and a coordinate uncertain by several texels
//! takes many: with each tap reading its block itself, a frame whose coordinate is uncertain
//! by several texels took minutes.

use std::ops::RangeInclusive;

use super::{Possible, ambiguity};

/// The kinds counted: lit only, shadowed only, either through depth, either through coverage.
const KINDS: usize = 4;

fn kind(p: Possible) -> usize {
    match (p.lit, p.shadow, p.by_coverage) {
        (true, false, _) => 0,
        (false, true, _) => 1,
        (_, _, false) => 2,
        (_, _, true) => 3,
    }
}

pub(super) struct Grid {
    i0: i64,
    j0: i64,
    ni: usize,
    cells: Vec<Possible>,
    /// Per kind, texels of that kind in columns < i and rows < j, at (i − i0) + (j − j0)·(ni + 1).
    counts: [Vec<u32>; KINDS],
}

impl Grid {
    /// The answers of columns `is` × rows `js`.
    pub(super) fn new(
        is: RangeInclusive<i64>,
        js: RangeInclusive<i64>,
        answer: impl Fn(i64, i64) -> Possible,
    ) -> Grid {
        let (i0, j0) = (*is.start(), *js.start());
        let ni = (is.end() - i0 + 1).max(0) as usize;
        let nj = (js.end() - j0 + 1).max(0) as usize;
        let mut cells = Vec::with_capacity(ni * nj);
        for j in js {
            for i in is.clone() {
                cells.push(answer(i, j));
            }
        }
        let stride = ni + 1;
        let mut counts: [Vec<u32>; KINDS] = std::array::from_fn(|_| vec![0; stride * (nj + 1)]);
        for j in 0..nj {
            for i in 0..ni {
                let k = kind(cells[j * ni + i]);
                for (c, table) in counts.iter_mut().enumerate() {
                    let here = u32::from(c == k);
                    table[(j + 1) * stride + i + 1] =
                        here + table[j * stride + i + 1] + table[(j + 1) * stride + i]
                            - table[j * stride + i];
                }
            }
        }
        Grid {
            i0,
            j0,
            ni,
            cells,
            counts,
        }
    }

    /// The answer of texel (i, j), which must lie in the grid.
    pub(super) fn at(&self, i: i64, j: i64) -> Possible {
        self.cells[(j - self.j0) as usize * self.ni + (i - self.i0) as usize]
    }

    /// How many texels of each kind the sub-block `is` × `js` (inside the grid) holds.
    fn count(&self, is: &RangeInclusive<i64>, js: &RangeInclusive<i64>) -> [u32; KINDS] {
        let stride = self.ni + 1;
        let (a, b) = (
            (is.start() - self.i0) as usize,
            (is.end() - self.i0) as usize + 1,
        );
        let (c, d) = (
            (js.start() - self.j0) as usize,
            (js.end() - self.j0) as usize + 1,
        );
        std::array::from_fn(|k| {
            let t = &self.counts[k];
            t[d * stride + b] + t[c * stride + a] - t[c * stride + b] - t[d * stride + a]
        })
    }

    /// The one definite answer every texel of the sub-block gives, if they all give one.
    pub(super) fn sure(
        &self,
        is: &RangeInclusive<i64>,
        js: &RangeInclusive<i64>,
    ) -> Option<Possible> {
        let n = self.count(is, js);
        let total: u32 = n.iter().sum();
        let definite = |lit: bool| Possible {
            lit,
            shadow: !lit,
            by_coverage: false,
        };
        if total > 0 && n[0] == total {
            Some(definite(true))
        } else if total > 0 && n[1] == total {
            Some(definite(false))
        } else {
            None
        }
    }

    /// The least and greatest answer the sub-block's texels may give, and the flags of its
    /// ambiguities: what any convex combination of them (a LINEAR compare under any
    /// weighting, or a shader's bilinear sum) may return.
    pub(super) fn hull(
        &self,
        is: &RangeInclusive<i64>,
        js: &RangeInclusive<i64>,
    ) -> (f64, f64, u8) {
        let [lit, shadow, depth, coverage] = self.count(is, js);
        let lo = if shadow + depth + coverage > 0 {
            0.0
        } else {
            1.0
        };
        let hi = if lit + depth + coverage > 0 { 1.0 } else { 0.0 };
        let mut flags = 0;
        if depth > 0 {
            flags |= ambiguity::DEPTH_TIE;
        }
        if coverage > 0 {
            flags |= ambiguity::COVERAGE;
        }
        if [lit, shadow, depth, coverage]
            .iter()
            .filter(|&&n| n > 0)
            .count()
            > 1
        {
            flags |= ambiguity::FILTER;
        }
        (lo, hi, flags)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sub-block's counted answer against a direct pass over its texels.
    #[test]
    fn sub_blocks_count_as_a_pass_over_them_does() {
        let mut rand = crate::test_rng::uniform(0x6121_d5e5);
        let cells: Vec<Possible> = (0..7 * 5)
            .map(|_| {
                let r = (rand() * 10.0) as u32;
                Possible {
                    lit: r != 0,
                    shadow: r < 3,
                    by_coverage: r == 1,
                }
            })
            .collect();
        let grid = Grid::new(-3..=3, 10..=14, |i, j| {
            cells[((j - 10) * 7 + i + 3) as usize]
        });
        for (a, b) in (-3..=3).flat_map(|a| (a..=3).map(move |b| (a, b))) {
            for (c, d) in (10..=14).flat_map(|c| (c..=14).map(move |d| (c, d))) {
                let texels: Vec<Possible> = (c..=d)
                    .flat_map(|j| (a..=b).map(move |i| (i, j)))
                    .map(|(i, j)| grid.at(i, j))
                    .collect();
                let lo = texels.iter().map(|t| t.min()).fold(1.0, f64::min);
                let hi = texels.iter().map(|t| t.max()).fold(0.0, f64::max);
                let (glo, ghi, flags) = grid.hull(&(a..=b), &(c..=d));
                assert_eq!((glo, ghi), (lo, hi), "block {a}..={b} × {c}..={d}");
                let tie = texels.iter().any(|t| t.lit && t.shadow && !t.by_coverage);
                assert_eq!(flags & ambiguity::DEPTH_TIE != 0, tie);
                let first = texels[0];
                let uniform = texels.iter().all(|t| *t == first);
                let definite = first.lit != first.shadow;
                assert_eq!(
                    grid.sure(&(a..=b), &(c..=d)),
                    (uniform && definite).then_some(first)
                );
            }
        }
    }
}
