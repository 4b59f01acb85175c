//! Agreement of a backend's frame with the reference, with every disagreement classified by
//! the spec rule that makes it legal (or not). The conformance judge and the tests use this
//! one function.
//!
//! Rule (first cut of the tolerance model; the conformance-runner issue refines it):
//! a pixel whose lit/shadowed answer differs from the reference's is *legal* when
//! - the reference's own lookup there was within the specs' freedom
//!   ([`umbra_ref::lookup::ambiguity`]): a depth tie (the compared texel within the stored
//!   depth's freedom: polygon-offset slope form and unit r, ±1 storage step, f32 rounding),
//!   a texel boundary (within 1/16 texel, the minimum sub-texel precision, of a texel that
//!   decides differently), or filter freedom (LINEAR taps disagree: weights are
//!   implementation-defined and NEAREST is allowed; a PCF average within one 8-bit step of
//!   0.5), or the position freedom (moving the lookup point by the unspecified accuracy of
//!   varying interpolation, [`umbra_ref::lookup::position_freedom`], changes the answer);
//! - the truth marks it an edge pixel: within the light's texel resolution of a true shadow
//!   boundary, where coverage snapping (sub-pixel precision ≥ 4 bits) and the rasterization
//!   tie rule (none prescribed) of the *shadow pass* are the implementation's; or
//! - the pixel shows no receiver both frames share a lookup for: a silhouette (the surface
//!   itself differs) or a surface facing away from the light (its shadow term is multiplied by
//!   a zero diffuse term, and it compares against its own back side).
//!
//! Pixels outside the light's frustum are *not* exempt: the case's outside policy defines
//! their answer, so they are held to the reference like any other.
//!
//! Any other disagreement is illegal and fails the run.

use serde::{Deserialize, Serialize};
use umbra_case::Frame;
use umbra_ref::truth::{Class, Truth};

use crate::{Agreement, agreement};

/// Agreement with the reference, with each disagreement classified.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RefAgreement {
    /// Pixels covered in both.
    pub compared: u64,
    /// Pixels whose answer differs.
    pub differ: u64,
    /// Of those, a depth tie in the reference's lookup.
    pub legal_tie: u64,
    /// Of those, a texel boundary, filter freedom or position freedom in the reference's
    /// lookup.
    pub legal_texel: u64,
    /// Of those, on a truth edge (texel and raster freedom).
    pub legal_edge: u64,
    /// Of those, on a silhouette or a surface facing away from the light.
    pub legal_unjudged: u64,
    /// Of those, neither: illegal.
    pub illegal: u64,
}

impl RefAgreement {
    /// The legal classes, as every message states them:
    /// `legal: T ties, X texel/filter, E edges, U unjudged`.
    pub fn legal_summary(&self) -> String {
        format!(
            "legal: {} ties, {} texel/filter, {} edges, {} unjudged",
            self.legal_tie, self.legal_texel, self.legal_edge, self.legal_unjudged
        )
    }
}

/// Judges `frame` against the `reference` frame (rendered with
/// `umbra_ref::render_judged`, which gives `ambiguity`) and the `truth`.
pub fn judge(reference: &Frame, ambiguity: &[u8], frame: &Frame, truth: &Truth) -> RefAgreement {
    let surface = reference.surface.clone().unwrap_or_default();
    classify(&agreement(reference, frame, 0), truth, ambiguity, &surface)
}

/// Per pixel: whether a shadow answer may legally differ from the reference's there (the
/// legal classes of [`judge`]).
pub fn legal_pixels(reference: &Frame, ambiguity: &[u8], truth: &Truth) -> Vec<bool> {
    let surface = reference.surface.clone().unwrap_or_default();
    (0..truth.class.len())
        .map(|i| {
            matches!(truth.class[i], Class::Background | Class::FacesAway)
                || truth.face[i] == 0
                || silhouette(truth, &surface, i)
                || ambiguity[i] != 0
                || truth.edge[i]
        })
        .collect()
}

/// Judges the disagreements of two backend frames `a` and `b` with the same rule: where both
/// are within the specs' freedom of the reference, they may differ from each other only there.
pub fn judge_pair(
    a: &Frame,
    b: &Frame,
    reference: &Frame,
    ambiguity: &[u8],
    truth: &Truth,
) -> RefAgreement {
    let surface = reference.surface.clone().unwrap_or_default();
    classify(&agreement(a, b, 0), truth, ambiguity, &surface)
}

fn silhouette(truth: &Truth, reference_surface: &[u32], i: usize) -> bool {
    reference_surface[i] != truth.face[i]
}

fn classify(
    g: &Agreement,
    truth: &Truth,
    ambiguity: &[u8],
    reference_surface: &[u32],
) -> RefAgreement {
    use umbra_ref::lookup::ambiguity::{DEPTH_TIE, FILTER, POSITION, TEXEL_BOUNDARY};
    let mut r = RefAgreement {
        compared: g.compared,
        ..Default::default()
    };
    for (i, differs) in g.disagrees.iter().enumerate() {
        if !differs {
            continue;
        }
        r.differ += 1;
        let exempt =
            matches!(truth.class[i], Class::Background | Class::FacesAway) || truth.face[i] == 0;
        if exempt || silhouette(truth, reference_surface, i) {
            r.legal_unjudged += 1;
        } else if ambiguity[i] & DEPTH_TIE != 0 {
            r.legal_tie += 1;
        } else if ambiguity[i] & (TEXEL_BOUNDARY | FILTER | POSITION) != 0 {
            r.legal_texel += 1;
        } else if truth.edge[i] {
            r.legal_edge += 1;
        } else {
            r.illegal += 1;
        }
    }
    r
}
