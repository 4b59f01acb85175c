//! Where a failing run broke the model, and whether other drivers broke it the same way: the
//! consensus diagnosis.
//!
//! Every backend of one effective profile ([`umbra_case::Profile::effective_for`]) is judged
//! against the same legal intervals for a case point. A correct implementation answers
//! legally everywhere, so when *every* driver judged against those intervals answers alike
//! where the judge says no answer like that is legal, the first suspect is umbra's model (a
//! tolerance too tight for what the specs allow), not nine drivers at once; when the other
//! drivers answer legally there, the failing driver is the suspect. This cannot prove either
//! (two drivers can share a bug: zink runs on lavapipe, which shares llvmpipe's rasterizer),
//! and it does not change a run's status: it tells a user where to look first.
//!
//! A failing run leaves a [`Fingerprint`]: per check, the pixels (or map texels) it failed,
//! each with the side it erred to (shadowed or lit; above or below the texel's range). The
//! conformance run compares each failing run's fingerprint with the other runs of the same
//! point and profile ([`agree`]).

use serde::{Deserialize, Serialize};

/// The most entries a fingerprint keeps per check (the first ones in pixel order): enough to
/// tell drivers apart, small enough to send for every failing run.
pub const LIMIT: usize = 4096;

/// One check's failed pixels: each `index · 2 + side`, ascending, at most [`LIMIT`], and how
/// many failed in all.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Failed {
    /// `index · 2 + side` (side 1: shadowed, or stored above the range), ascending.
    pub entries: Vec<u32>,
    /// How many failed in all (entries holds the first [`LIMIT`]).
    pub total: u64,
}

impl Failed {
    /// Adds pixel `index` failed toward `side`, in ascending index order.
    pub fn push(&mut self, index: usize, side: bool) {
        self.total += 1;
        if self.entries.len() < LIMIT {
            self.entries.push((index as u32) << 1 | u32::from(side));
        }
    }

    fn contains(&self, e: u32) -> bool {
        self.entries.binary_search(&e).is_ok()
    }
}

/// Where one run failed, check by check; what consensus compares.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// The effective profile the run was judged for: runs compare only within one.
    pub profile: String,
    /// The frame's illegal pixels (value, NaN, coverage, colour), side = shadowed.
    pub frame: Failed,
    /// The shadow map's illegal texels, side = above the range; `None` where the backend
    /// does not read its map back.
    pub map: Option<Failed>,
    /// Each judged twin's illegal pixels, by twin name.
    pub twins: Vec<(String, Failed)>,
}

impl Fingerprint {
    /// Whether nothing failed.
    pub fn is_empty(&self) -> bool {
        self.frame.total == 0
            && self.map.as_ref().is_none_or(|m| m.total == 0)
            && self.twins.iter().all(|(_, f)| f.total == 0)
    }
}

/// How another run of the same point and profile answered where `a` failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// It fails the same way at most (at least half) of those pixels.
    Same,
    /// It answers legally at most of them.
    Legal,
    /// It checked none of what `a` failed (another check set, a twin it did not render).
    NotComparable,
}

/// How `b` (`None`: a run that passed every check `a` failed) answered where `a` failed.
/// Only what both checked counts: a map check against a backend that does not read its map
/// back, or a twin it did not render, is left out.
pub fn agree(
    a: &Fingerprint,
    b: Option<&Fingerprint>,
    b_checks_map: bool,
    b_twins: &[&str],
) -> Answer {
    let empty = Failed::default();
    let mut pairs: Vec<(&Failed, &Failed)> = vec![(&a.frame, b.map_or(&empty, |b| &b.frame))];
    if let Some(am) = &a.map {
        if b_checks_map {
            pairs.push((am, b.and_then(|b| b.map.as_ref()).unwrap_or(&empty)));
        }
    }
    for (name, af) in &a.twins {
        if b_twins.contains(&name.as_str()) {
            let bf = b
                .and_then(|b| b.twins.iter().find(|(n, _)| n == name).map(|(_, f)| f))
                .unwrap_or(&empty);
            pairs.push((af, bf));
        }
    }
    let (mut compared, mut same) = (0usize, 0usize);
    for (af, bf) in pairs {
        compared += af.entries.len();
        same += af.entries.iter().filter(|&&e| bf.contains(e)).count();
    }
    if compared == 0 {
        Answer::NotComparable
    } else if 2 * same >= compared {
        Answer::Same
    } else {
        Answer::Legal
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn failed(entries: &[(usize, bool)]) -> Failed {
        let mut f = Failed::default();
        for &(i, s) in entries {
            f.push(i, s);
        }
        f
    }

    #[test]
    fn the_same_pixels_on_the_same_side_agree() {
        let a = Fingerprint {
            profile: "gl".into(),
            frame: failed(&[(3, true), (9, true), (20, false)]),
            ..Default::default()
        };
        let same = Fingerprint {
            frame: failed(&[(3, true), (9, true), (11, true)]),
            ..a.clone()
        };
        // The same pixels on the other side: another answer, not this one.
        let flipped = Fingerprint {
            frame: failed(&[(3, false), (9, false), (20, true)]),
            ..a.clone()
        };
        assert_eq!(agree(&a, Some(&same), false, &[]), Answer::Same);
        assert_eq!(agree(&a, Some(&flipped), false, &[]), Answer::Legal);
        assert_eq!(agree(&a, None, false, &[]), Answer::Legal);
    }

    #[test]
    fn only_what_both_checked_counts() {
        let a = Fingerprint {
            profile: "gl".into(),
            map: Some(failed(&[(5, true), (6, true)])),
            twins: vec![("attachments".into(), failed(&[(1, true)]))],
            ..Default::default()
        };
        // A backend that reads no map back and did not render the twin cannot say.
        assert_eq!(agree(&a, None, false, &[]), Answer::NotComparable);
        assert_eq!(agree(&a, None, true, &[]), Answer::Legal);
        let b = Fingerprint {
            twins: vec![("attachments".into(), failed(&[(1, true)]))],
            ..a.clone()
        };
        assert_eq!(agree(&a, Some(&b), false, &["attachments"]), Answer::Same);
    }
}
