//! Rendering and judging one case point on one backend: the frame, the truth, the error, and
//! for every backend but the reference, agreement with the reference.
//!
//! Agreement rule (first cut of the tolerance model; the conformance-runner issue refines it):
//! a pixel whose lit/shadowed answer differs from the reference's is *legal* when
//! - the reference's own lookup there was within the specs' freedom
//!   ([`umbra_ref::lookup::ambiguity`]): a depth tie (the compared texel within the stored
//!   depth's freedom: polygon-offset slope form and unit r, ±1 storage step, f32 rounding),
//!   a texel boundary (within 1/16 texel, the minimum sub-texel precision, of a texel that
//!   decides differently), or filter freedom (LINEAR taps disagree: weights are
//!   implementation-defined and NEAREST is allowed; a PCF average within one 8-bit step of
//!   0.5);
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

use std::time::{Duration, Instant};

use umbra_case::format::InteriorError;
use umbra_case::{Backend, CasePoint, ClipDepth, Frame, Needs, Prepared, Support};
use umbra_compare::{Agreement, TruthError};
use umbra_ref::truth::{Class, Truth, ground_truth};

/// Agreement with the reference, with each disagreement classified.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RefAgreement {
    /// Pixels covered in both.
    pub compared: u64,
    /// Pixels whose answer differs.
    pub differ: u64,
    /// Of those, a depth tie in the reference's lookup.
    pub legal_tie: u64,
    /// Of those, a texel boundary or filter freedom in the reference's lookup.
    pub legal_texel: u64,
    /// Of those, on a truth edge (texel and raster freedom).
    pub legal_edge: u64,
    /// Of those, on a silhouette or a surface facing away from the light.
    pub legal_unjudged: u64,
    /// Of those, neither: illegal.
    pub illegal: u64,
}

/// One judged run.
pub struct Judged {
    /// The run's inputs.
    pub prepared: Prepared,
    /// What the backend rendered.
    pub frame: Frame,
    /// The exact truth.
    pub truth: Truth,
    /// The frame's error against it.
    pub error: TruthError,
    /// Agreement with the reference (None for the reference itself).
    pub agreement: Option<RefAgreement>,
    /// Time spent judging (truth, reference, error).
    pub judge_time: Duration,
    /// Problems with the result (empty = as expected).
    pub problems: Vec<String>,
}

/// The outcome of trying to run a point on a backend.
pub enum Outcome {
    /// Rendered and judged.
    Done(Box<Judged>),
    /// The backend cannot run it, and why.
    Skip(String),
    /// The backend failed, and how.
    Error(String),
}

/// Renders `point` on `backend` and judges it against the truth (and the reference).
pub fn run_point(backend: &mut dyn Backend, point: CasePoint) -> Outcome {
    if let Support::Unsupported(why) = backend.supports(&Needs::of(&point.case)) {
        return Outcome::Skip(why);
    }
    let prepared = Prepared::new(point);
    let frame = match backend.render(&prepared) {
        Ok(f) => f,
        Err(e) => return Outcome::Error(e.to_string()),
    };
    if (frame.width, frame.height) != (prepared.camera.size[0], prepared.camera.size[1])
        || frame.visibility.len() != (frame.width * frame.height) as usize
    {
        return Outcome::Error(format!(
            "the backend returned a {}x{} frame for a {:?} camera",
            frame.width, frame.height, prepared.camera.size
        ));
    }
    let start = Instant::now();
    let truth = ground_truth(&prepared);
    let error = umbra_compare::truth_error(&frame, &truth);
    let mut problems = Vec::new();
    let agreement = (backend.id().0 != "ref").then(|| {
        let (reference, ambiguity) = umbra_ref::render_judged(&prepared, ClipDepth::MinusOneToOne);
        let surface = reference.surface.clone().unwrap_or_default();
        classify(
            &umbra_compare::agreement(&reference, &frame, 0),
            &truth,
            &ambiguity,
            &surface,
        )
    });
    if let Some(a) = &agreement {
        if a.illegal > 0 && prepared.case().expect.backends_agree {
            problems.push(format!(
                "{} px disagree with the reference where no spec freedom explains it (of {} compared; legal: {} ties, {} texel/filter, {} edges, {} unjudged)",
                a.illegal, a.compared, a.legal_tie, a.legal_texel, a.legal_edge, a.legal_unjudged
            ));
        }
    }
    let judge_time = start.elapsed();
    let a = error.away_from_edges;
    let (shadow_bad, light_bad) = match prepared.case().expect.interior_error {
        InteriorError::Reported => (false, false),
        InteriorError::Zero => (a.false_shadow > 0, a.false_light > 0),
        InteriorError::NoFalseLight => (false, a.false_light > 0),
        InteriorError::NoFalseShadow => (a.false_shadow > 0, false),
    };
    if shadow_bad || light_bad {
        problems.push(format!(
            "expect.interior_error is {}, but away from shadow edges {} px are falsely shadowed and {} px falsely lit (of {} judged)",
            serde_json::to_string(&prepared.case().expect.interior_error).unwrap_or_default(),
            a.false_shadow,
            a.false_light,
            a.judged
        ));
    }
    Outcome::Done(Box::new(Judged {
        prepared,
        frame,
        truth,
        error,
        agreement,
        judge_time,
        problems,
    }))
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
    use umbra_ref::lookup::ambiguity::{DEPTH_TIE, FILTER, TEXEL_BOUNDARY};
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
        } else if ambiguity[i] & (TEXEL_BOUNDARY | FILTER) != 0 {
            r.legal_texel += 1;
        } else if truth.edge[i] {
            r.legal_edge += 1;
        } else {
            r.illegal += 1;
        }
    }
    r
}

/// A short multi-line summary of a judged run.
pub fn describe(j: &Judged) -> String {
    let e = &j.error;
    let pct = |n: u64, d: u64| {
        if d == 0 {
            0.0
        } else {
            100.0 * n as f64 / d as f64
        }
    };
    let t = &j.frame.timings;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let clock = match t.clock {
        Some(umbra_case::Clock::Gpu) => "gpu timers",
        _ => "cpu wall",
    };
    let mut s = format!(
        "  error vs truth: false shadow {:.4}% ({} px), false light {:.4}% ({} px) of {} judged px\n  \
         away from edges: false shadow {} px, false light {} px of {} px ({} edge px)\n  \
         excluded: silhouette {}, faces away {}, outside light {}, background {}\n",
        pct(e.all.false_shadow, e.all.judged),
        e.all.false_shadow,
        pct(e.all.false_light, e.all.judged),
        e.all.false_light,
        e.all.judged,
        e.away_from_edges.false_shadow,
        e.away_from_edges.false_light,
        e.away_from_edges.judged,
        e.edge_pixels,
        e.silhouette,
        e.faces_away,
        e.outside,
        e.background,
    );
    if let Some(a) = &j.agreement {
        s.push_str(&format!(
            "  vs reference: {} of {} px differ (legal: {} ties, {} texel/filter, {} edges, {} unjudged; {} illegal)\n",
            a.differ, a.compared, a.legal_tie, a.legal_texel, a.legal_edge, a.legal_unjudged, a.illegal
        ));
    }
    s.push_str(&format!(
        "  time: shadow pass {:.2} ms, lit pass {:.2} ms, readback {:.2} ms, total {:.2} ms ({clock}); judging {:.1} ms",
        ms(t.shadow_pass),
        ms(t.lit_pass),
        ms(t.readback),
        ms(t.total),
        ms(j.judge_time),
    ));
    s
}
