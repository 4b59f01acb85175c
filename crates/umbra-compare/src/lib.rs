//! umbra's metrics: how wrong a frame is against the exact truth, how far two frames agree,
//! and pictures of both.
//!
//! A pixel is *shadowed* when its visibility is below 0.5 (the threshold every report uses:
//! it splits a PCF result at "more taps shadowed than lit").
//!
//! - [`truth_error`]: classification error against [`umbra_ref::truth::Truth`], split into
//!   false shadow (acne, over-bias shadows) and false light (leaks, peter-panning), overall and
//!   *away from edges*, with every excluded pixel counted by reason.
//! - [`agreement`]: mask agreement of two frames, with an optional shift radius in pixels.
//! - [`heatmap`]: images of both, colour-coded (legend in [`heatmap`]).
//! - [`reference`]: a frame against the reference's legal intervals (the value judge), and
//!   [`consensus`]: where a failing frame broke them, compared across drivers.

pub mod consensus;
pub mod edges;
pub mod heatmap;
pub mod reference;
pub mod ssim;

use serde::Serialize;
use umbra_case::{Frame, LightFrame};
use umbra_ref::truth::{Class, Truth};

/// Visibility below this reads as shadowed.
pub const SHADOWED_BELOW: f32 = 0.5;

/// Whether a visibility value reads as shadowed.
pub fn is_shadowed(v: f32) -> bool {
    v < SHADOWED_BELOW
}

/// The verdict on one pixel against the truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PixelVerdict {
    /// Not judged: the truth sees no surface there.
    Background,
    /// Not judged: the surface faces away from the light.
    FacesAway,
    /// Not judged: outside the light's frustum.
    Outside,
    /// Not judged: the frame's surface differs from the truth's (silhouette, or coverage).
    Silhouette,
    /// Agrees: lit.
    Lit,
    /// Agrees: shadowed.
    Shadowed,
    /// Shadowed in the frame, lit in truth (acne).
    FalseShadow,
    /// Lit in the frame, shadowed in truth (leak, peter-panning).
    FalseLight,
}

/// Counts of judged pixels and errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Pixels judged.
    pub judged: u64,
    /// Frame shadowed, truth lit.
    pub false_shadow: u64,
    /// Frame lit, truth shadowed.
    pub false_light: u64,
}

impl Counts {
    /// False shadow as a share of judged pixels.
    pub fn false_shadow_rate(&self) -> f64 {
        ratio(self.false_shadow, self.judged)
    }

    /// False light as a share of judged pixels.
    pub fn false_light_rate(&self) -> f64 {
        ratio(self.false_light, self.judged)
    }
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

/// Classification error of a frame against the truth.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TruthError {
    /// Over every judged pixel.
    pub all: Counts,
    /// Over judged pixels that are not edge pixels.
    pub away_from_edges: Counts,
    /// Judged pixels that are edge pixels.
    pub edge_pixels: u64,
    /// Excluded: background in the truth.
    pub background: u64,
    /// Excluded: facing away from the light.
    pub faces_away: u64,
    /// Excluded: outside the light's frustum.
    pub outside: u64,
    /// Excluded: silhouette (the frame's surface is not the truth's).
    pub silhouette: u64,
    /// Shadowed area in the truth, in judged pixels.
    pub truth_shadowed: u64,
    /// Shadowed area in the frame, in judged pixels.
    pub frame_shadowed: u64,
    /// Verdict per pixel (not serialised).
    #[serde(skip)]
    pub verdicts: Vec<PixelVerdict>,
}

/// Judges every light of `frame` against its own truth (`truths`, light by light, each light's
/// run's in [`umbra_case::Prepared::lights`]): the counts add up over the lights (a pixel lit
/// by two lights is judged twice, once per light's shadow); the verdicts (pictures) are the
/// first light's. A light the frame has no plane for counts every covered pixel as judged
/// and neither lit nor shadowed correctly (NaN).
pub fn truth_error_lights(frame: &Frame, truths: &[Truth]) -> TruthError {
    let missing = vec![f32::NAN; (frame.width * frame.height) as usize];
    let mut each = truths.iter().enumerate().map(|(k, t)| {
        let light = frame.light(k).unwrap_or(LightFrame {
            visibility: &missing,
            shadow_map: None,
            surface: None,
            width: frame.width,
            height: frame.height,
            visibility_storage: frame.visibility_storage,
        });
        truth_error(light, t)
    });
    let Some(mut e) = each.next() else {
        return TruthError::default();
    };
    for o in each {
        for (a, b) in [
            (&mut e.all, o.all),
            (&mut e.away_from_edges, o.away_from_edges),
        ] {
            a.judged += b.judged;
            a.false_shadow += b.false_shadow;
            a.false_light += b.false_light;
        }
        e.edge_pixels += o.edge_pixels;
        e.background += o.background;
        e.faces_away += o.faces_away;
        e.outside += o.outside;
        e.silhouette += o.silhouette;
        e.truth_shadowed += o.truth_shadowed;
        e.frame_shadowed += o.frame_shadowed;
    }
    e
}

/// Judges `frame` against `truth` (same size).
///
/// Silhouettes: where the frame carries face ids, a pixel whose face differs from the truth's
/// (or is covered in one and not the other) is excluded. Without face ids, any pixel whose
/// 8-neighbourhood in the truth shows another face is excluded instead (rasterization and ray
/// differ by less than a pixel, so they can only disagree there).
pub fn truth_error(frame: LightFrame, truth: &Truth) -> TruthError {
    assert_eq!(
        (frame.width, frame.height),
        (truth.width, truth.height),
        "frame and truth sizes differ"
    );
    let (w, h) = (truth.width as usize, truth.height as usize);
    let mut e = TruthError {
        verdicts: Vec::with_capacity(w * h),
        ..Default::default()
    };
    for i in 0..w * h {
        let silhouette = match &frame.surface {
            Some(s) => s[i] != truth.face[i],
            None => {
                frame.covered(i) != (truth.face[i] != 0) || face_changes_near(truth, i % w, i / w)
            }
        };
        let verdict = match truth.class[i] {
            Class::Background if silhouette => PixelVerdict::Silhouette,
            Class::Background => PixelVerdict::Background,
            _ if silhouette => PixelVerdict::Silhouette,
            Class::FacesAway => PixelVerdict::FacesAway,
            Class::Outside => PixelVerdict::Outside,
            Class::Lit | Class::Shadowed => {
                let truly = truth.class[i] == Class::Shadowed;
                let says = is_shadowed(frame.visibility[i]);
                match (says, truly) {
                    (false, false) => PixelVerdict::Lit,
                    (true, true) => PixelVerdict::Shadowed,
                    (true, false) => PixelVerdict::FalseShadow,
                    (false, true) => PixelVerdict::FalseLight,
                }
            }
        };
        match verdict {
            PixelVerdict::Background => e.background += 1,
            PixelVerdict::FacesAway => e.faces_away += 1,
            PixelVerdict::Outside => e.outside += 1,
            PixelVerdict::Silhouette => e.silhouette += 1,
            judged => {
                let edge = truth.edge[i];
                for c in if edge {
                    vec![&mut e.all]
                } else {
                    vec![&mut e.all, &mut e.away_from_edges]
                } {
                    c.judged += 1;
                    c.false_shadow += u64::from(judged == PixelVerdict::FalseShadow);
                    c.false_light += u64::from(judged == PixelVerdict::FalseLight);
                }
                e.edge_pixels += u64::from(edge);
                e.truth_shadowed += u64::from(truth.class[i] == Class::Shadowed);
                e.frame_shadowed += u64::from(matches!(
                    judged,
                    PixelVerdict::Shadowed | PixelVerdict::FalseShadow
                ));
            }
        }
        e.verdicts.push(verdict);
    }
    e
}

fn face_changes_near(truth: &Truth, x: usize, y: usize) -> bool {
    let (w, h) = (truth.width as usize, truth.height as usize);
    let me = truth.face[y * w + x];
    for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
        for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
            if truth.face[ny * w + nx] != me {
                return true;
            }
        }
    }
    false
}

/// Shadow-mask agreement of two frames.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Agreement {
    /// Pixels covered in both frames.
    pub compared: u64,
    /// Of those, the same lit/shadowed answer.
    pub agree: u64,
    /// Shadowed in `a`, lit in `b`, with no such pixel of `b` within the radius.
    pub only_a_shadowed: u64,
    /// Shadowed in `b`, lit in `a`, with no such pixel of `a` within the radius.
    pub only_b_shadowed: u64,
    /// Disagreements that a shift of at most the radius explains.
    pub within_radius: u64,
    /// Covered in exactly one of the frames.
    pub coverage_differs: u64,
    /// Per pixel: whether the pixel is an unexplained disagreement (not serialised).
    #[serde(skip)]
    pub disagrees: Vec<bool>,
}

impl Agreement {
    /// Share of compared pixels with the same answer (1 when nothing is compared).
    pub fn share(&self) -> f64 {
        if self.compared == 0 {
            1.0
        } else {
            self.agree as f64 / self.compared as f64
        }
    }

    /// Disagreements that no shift within the radius explains.
    pub fn unexplained(&self) -> u64 {
        self.only_a_shadowed + self.only_b_shadowed
    }
}

/// Compares the shadow masks of one light in `a` and `b` (same size). A disagreeing pixel is
/// explained by a shift when the other frame gives the same answer somewhere within `radius`
/// pixels (Chebyshev distance); radius 0 counts every disagreement.
pub fn agreement(a: LightFrame, b: LightFrame, radius: u32) -> Agreement {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "frame sizes differ"
    );
    let (w, h) = (a.width as usize, a.height as usize);
    let mask = |f: LightFrame, i: usize| f.covered(i) && is_shadowed(f.visibility[i]);
    let near = |f: LightFrame, x: usize, y: usize, want: bool| {
        let r = radius as usize;
        (y.saturating_sub(r)..=(y + r).min(h - 1)).any(|ny| {
            (x.saturating_sub(r)..=(x + r).min(w - 1))
                .any(|nx| f.covered(ny * w + nx) && mask(f, ny * w + nx) == want)
        })
    };
    let mut g = Agreement {
        disagrees: vec![false; w * h],
        ..Default::default()
    };
    for i in 0..w * h {
        match (a.covered(i), b.covered(i)) {
            (true, true) => {}
            (false, false) => continue,
            _ => {
                g.coverage_differs += 1;
                continue;
            }
        }
        g.compared += 1;
        let (sa, sb) = (mask(a, i), mask(b, i));
        if sa == sb {
            g.agree += 1;
            continue;
        }
        let (x, y) = (i % w, i / w);
        if radius > 0 && near(b, x, y, sa) && near(a, x, y, sb) {
            g.within_radius += 1;
        } else if sa {
            g.only_a_shadowed += 1;
            g.disagrees[i] = true;
        } else {
            g.only_b_shadowed += 1;
            g.disagrees[i] = true;
        }
    }
    g
}

/// SSIM of two frames' shaded colour (image-compare's MSSIMSimple on luma, 8x8 windows, as
/// [`ssim::mssim`] computes it bit for bit):
/// 1.0 means identical. docs/platform.md: a 3-pixel shift of a shadowed scene scores about 0.96,
/// so only values very close to 1 mean "the same picture". Reported, not thresholded here.
pub fn ssim(a: &Frame, b: &Frame) -> Option<f64> {
    let luma = |f: &Frame| {
        let data = f
            .color
            .chunks_exact(4)
            .map(|p| {
                (0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
                    .round() as u8
            })
            .collect::<Vec<u8>>();
        (data.len() == (f.width * f.height) as usize).then_some(data)
    };
    if (a.width, a.height) != (b.width, b.height) {
        return None;
    }
    let (la, lb) = (luma(a)?, luma(b)?);
    ssim::mssim(&la, &lb, a.width as usize, a.height as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use umbra_case::Timings;

    fn frame(vis: Vec<f32>, w: u32) -> Frame {
        let h = vis.len() as u32 / w;
        Frame {
            width: w,
            height: h,
            color: vec![0; vis.len() * 4],
            lights: vec![umbra_case::LightPlane {
                visibility: vis,
                surface: None,
                shadow_map: None,
            }],
            visibility_storage: Default::default(),
            timings: Timings::default(),
        }
    }

    #[test]
    fn agreement_counts_and_explains_shifts() {
        let n = f32::NAN;
        // A one-pixel shift of a shadow edge, and one isolated flipped pixel.
        let a = frame(
            vec![
                0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, n, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
                0.0,
            ],
            6,
        );
        let b = frame(
            vec![
                0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
                1.0, 1.0,
            ],
            6,
        );
        let (a, b) = (a.light(0).expect("a light"), b.light(0).expect("a light"));
        let strict = agreement(a, b, 0);
        assert_eq!((strict.compared, strict.coverage_differs), (17, 1));
        assert_eq!(
            (
                strict.only_a_shadowed,
                strict.only_b_shadowed,
                strict.within_radius
            ),
            (2, 0, 0)
        );
        let shifted = agreement(a, b, 1);
        // Pixel 1 has a shadowed neighbour in b and a lit neighbour in a: a shift explains it.
        // Pixel 17 has no shadowed pixel of b within one pixel: a real disagreement.
        assert_eq!((shifted.within_radius, shifted.only_a_shadowed), (1, 1));
        assert!(shifted.disagrees[17] && !shifted.disagrees[1]);
    }
}
