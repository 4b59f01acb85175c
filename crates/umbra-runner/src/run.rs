//! Rendering and judging one case point on one backend: the frame, the truth, the error, and
//! for every backend but the reference, agreement with the reference.
//!
//! The agreement rule itself lives in `umbra_compare::reference` (one place in code).

use std::time::{Duration, Instant};

use umbra_case::format::InteriorError;
use umbra_case::{Backend, CasePoint, ClipDepth, Frame, Needs, Prepared, Support};
use umbra_compare::TruthError;
use umbra_compare::reference::RefAgreement;
use umbra_ref::truth::{Truth, ground_truth};

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
    /// SSIM of the colour against the reference's (None for the reference itself).
    pub ssim: Option<f64>,
    /// The reference frame it was judged against (None for the reference itself).
    pub reference: Option<Frame>,
    /// Per pixel: whether a shadow difference from the reference is legal there (empty for
    /// the reference itself, whose goldens are held exactly).
    pub legal: Vec<bool>,
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
    let judged_reference = (backend.id().0 != "ref")
        .then(|| umbra_ref::render_judged(&prepared, ClipDepth::MinusOneToOne));
    let agreement = judged_reference.as_ref().map(|(reference, ambiguity)| {
        umbra_compare::reference::judge(reference, ambiguity, &frame, &truth)
    });
    let ssim = judged_reference
        .as_ref()
        .and_then(|(reference, _)| umbra_compare::ssim(reference, &frame));
    let legal = judged_reference
        .as_ref()
        .map(|(reference, ambiguity)| {
            umbra_compare::reference::legal_pixels(reference, ambiguity, &truth)
        })
        .unwrap_or_default();
    let reference = judged_reference.map(|(r, _)| r);
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
        ssim,
        reference,
        legal,
        judge_time,
        problems,
    }))
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
            "  vs reference: {} of {} px differ (legal: {} ties, {} texel/filter, {} edges, {} unjudged; {} illegal); colour SSIM {:.5}\n",
            a.differ, a.compared, a.legal_tie, a.legal_texel, a.legal_edge, a.legal_unjudged, a.illegal, j.ssim.unwrap_or(f64::NAN)
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
