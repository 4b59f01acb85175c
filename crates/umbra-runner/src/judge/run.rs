//! Rendering and judging one case point on one backend: the frame, the truth, the error, and
//! for every backend but the reference, agreement with the reference.
//!
//! The agreement rule itself lives in `umbra_compare::reference` (one place in code).

use std::time::{Duration, Instant};

use umbra_case::format::{InteriorError, TwinAgree};
use umbra_case::{Backend, Calibration, CasePoint, Frame, Needs, Prepared, Support};
use umbra_compare::TruthError;
use umbra_compare::consensus::{Failed, Fingerprint};
use umbra_compare::reference::RefAgreement;
use umbra_ref::truth::Truth;
use umbra_report::check::Check;
use umbra_report::{FailedCheck, TwinMetric};

use crate::judge::stages::{Stage, time};

/// One judged run.
pub struct Judged {
    /// The run's inputs.
    pub prepared: Prepared,
    /// What the backend rendered.
    pub frame: Frame,
    /// Every light's exact truth, in the case's order.
    pub truths: Vec<Truth>,
    /// The frame's error against it.
    pub error: TruthError,
    /// Agreement with the reference (None for the reference itself).
    pub agreement: Option<RefAgreement>,
    /// Each pixel's judgement (empty for the reference itself).
    pub pixels: Vec<umbra_compare::reference::PixelJudgement>,
    /// SSIM of the colour against the reference's (None for the reference itself).
    pub ssim: Option<f64>,
    /// The reference frame it was judged against (None for the reference itself).
    pub reference: Option<Frame>,
    /// Per pixel: whether the shadow answer may legally differ from the reference's there
    /// (empty for the reference itself, whose goldens are held exactly).
    pub legal: Vec<bool>,
    /// The checks that failed, each with how many pixels (or 1) failed it: the signature an
    /// expectation matches ([`crate::judge::expectations::Expectation`]).
    pub failed: Vec<FailedCheck>,
    /// Time spent judging (truth, reference, error, agreement), twins excluded.
    pub judge_time: Duration,
    /// Time spent rendering and judging the twins.
    pub twins_time: Duration,
    /// The metamorphic twins, each rendered on the same backend and compared.
    pub twins: Vec<TwinMetric>,
    /// Problems with the result (empty = as expected).
    pub problems: Vec<String>,
    /// Where the frame, its map and its twins broke the model (empty when nothing did): what
    /// the consensus diagnosis compares across drivers.
    pub fingerprint: Fingerprint,
    /// The second judgement, against the backend's card (None without a calibration).
    pub card: Option<CardJudged>,
    /// Each twin's frame as judged (see [`Rendered::twins`]), kept with `frame` so that the
    /// run can be judged again under other deviations without rendering anything again.
    pub twin_frames: Vec<Option<(Frame, bool)>>,
}

/// What a run rendered: its frame, and per twin of the point (in
/// [`umbra_case::twin::twins_of`]'s order) the twin's frame and whether it was drawn over
/// the case's own shadow map, where it was rendered. Judging it again under other deviations
/// ([`judge_again`]) judges these same frames: the pictures that failed, not new renders of
/// the same point, which cost a softpipe run seconds and would be the same frames anyway on
/// a deterministic driver.
#[derive(Clone, Default)]
pub struct Rendered {
    /// The run's own frame.
    pub frame: Option<Frame>,
    /// Each twin's frame (shadow maps dropped) and whether its shadow pass was shared.
    pub twins: Vec<Option<(Frame, bool)>>,
}

/// A run judged against its backend's card: the spec's freedom narrowed to what the card's
/// probes read (calibrated judging, [`umbra_case::calibration`]).
pub struct CardJudged {
    /// The effective calibrated profile's name (what the intervals were computed for).
    pub judged_as: String,
    /// The comparison with the reference under the narrowed freedom: its blind area is the
    /// run's blind area under the card.
    pub agreement: RefAgreement,
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

/// Renders `point` on `backend` and judges it against the truth (and the reference), with its
/// metamorphic twins when `twins` is set.
pub fn run_point(backend: &mut dyn Backend, point: CasePoint, twins: bool) -> Outcome {
    run_point_as(
        backend,
        point,
        twins,
        umbra_case::Deviations::NONE,
        Calibration::default(),
    )
}

/// [`run_point`], judged with `deviations` allowed besides the backend's profile (what the
/// expectations that name modelled deviations ask for, `Deviation:NAME`), and judged a second
/// time against `calibration` (the backend's card) when it narrows anything.
pub fn run_point_as(
    backend: &mut dyn Backend,
    point: CasePoint,
    twins: bool,
    deviations: umbra_case::Deviations,
    calibration: Calibration,
) -> Outcome {
    run_point_over(
        backend,
        point,
        twins,
        deviations,
        calibration,
        Rendered::default(),
    )
}

/// A run that was judged (`judged`, by [`run_point_as`]) judged again, its same frames (its
/// own and its twins'), with `deviations` allowed and no card: its failed checks are what
/// those deviations do not explain. Nothing is rendered again.
pub fn judge_again(
    backend: &mut dyn Backend,
    point: CasePoint,
    twins: bool,
    deviations: umbra_case::Deviations,
    judged: &Judged,
) -> Outcome {
    run_point_over(
        backend,
        point,
        twins,
        deviations,
        Calibration::default(),
        Rendered {
            frame: Some(judged.frame.clone()),
            twins: judged.twin_frames.clone(),
        },
    )
}

/// [`run_point_as`] over what `given` holds already rendered (nothing: everything is
/// rendered).
fn run_point_over(
    backend: &mut dyn Backend,
    point: CasePoint,
    twins: bool,
    deviations: umbra_case::Deviations,
    calibration: Calibration,
    given: Rendered,
) -> Outcome {
    let profile = backend.profile().with_deviations(deviations);
    if let Support::Unsupported(why) = backend.supports(&Needs::of(&point.case)) {
        return Outcome::Skip(why);
    }
    // Twins are built from the point as written: Prepared applies `scene.offset`, after
    // which a twin that sets the offset would no longer move anything.
    let as_written = point.clone();
    let prepared = Prepared::new(point);
    let frame = match given.frame {
        Some(f) => f,
        None => match rendered(backend, &prepared) {
            Ok(f) => f,
            Err(o) => return o,
        },
    };
    let start = Instant::now();
    // The truth, and the reference's judged render for this backend's profile (which also
    // judges the twins, so even the reference needs it): computed once per point and profile
    // in a conformance run.
    let crate::judge::judge_cache::Basis { truths, judged } =
        crate::judge::judge_cache::basis(&prepared, profile, carries_map(&frame));
    let error = time(Stage::Compare, || {
        crate::judge::judge_cache::truth_error(&frame, &truths)
    });
    let mut problems = Vec::new();
    let mut failed = Vec::new();
    let is_ref = backend.id().0 == "ref";
    // The reference too is judged against its own judged render: its value at every pixel
    // must lie in its own interval, and its map in its own ranges. Anything else is a bug in
    // umbra's model, caught on every case in every conformance run.
    let (agreement, pixels) = {
        let (a, px) = time(Stage::Compare, || {
            umbra_compare::reference::judge(&judged, &frame)
        });
        if is_ref && (a.illegal > 0 || a.illegal_map > 0) {
            problems.push(format!(
                "umbra's reference is not legal under its own model here ({}; {} map texels): a bug in umbra's tolerance model, not in a driver",
                a.illegal_summary(),
                a.illegal_map
            ));
            failed.push(FailedCheck {
                check: Check::Value,
                count: a.illegal.max(a.illegal_map),
            });
        }
        (Some(a), px)
    };
    let (ssim, legal) = time(Stage::Compare, || {
        if is_ref {
            (None, Vec::new())
        } else {
            (
                umbra_compare::ssim(&judged.frame, &frame),
                umbra_compare::reference::free_pixels(&judged),
            )
        }
    });
    let twins_start = Instant::now();
    let mut twin_frames = given.twins;
    let (twins, twin_failures): (Vec<TwinMetric>, Vec<(String, Failed)>) = if twins {
        time(Stage::TwinJudge, || {
            run_twins(
                backend,
                &as_written,
                &prepared,
                (&frame, &error, &judged),
                &mut twin_frames,
            )
        })
        .into_iter()
        .map(|(m, f)| {
            let name = m.name.clone();
            (m, (name, f))
        })
        .unzip()
    } else {
        (Vec::new(), Vec::new())
    };
    let fingerprint = time(Stage::Compare, || Fingerprint {
        profile: judged.profile.name(),
        frame: umbra_compare::reference::frame_failures(&frame, &pixels),
        map: umbra_compare::reference::map_failures(&judged, &frame),
        twins: twin_failures
            .into_iter()
            .filter(|(_, f)| f.total > 0)
            .collect(),
    });
    let twins_time = twins_start.elapsed();
    twins_failed(&twins, &mut failed, &mut problems);
    let reference = (!is_ref).then_some(judged.frame);
    if let Some(a) = agreement.as_ref().filter(|_| !is_ref) {
        if (a.illegal > 0 || a.illegal_map > 0) && prepared.case().expect.backends_agree {
            illegal_failed(a, &mut failed, &mut problems);
        }
    }
    let spec_legal = agreement
        .as_ref()
        .is_some_and(|a| a.illegal == 0 && a.illegal_map == 0);
    let card = (!calibration.is_empty()).then(|| {
        let c = time(Stage::Card, || {
            judged_by_card(&prepared, &frame, profile.with_calibration(calibration))
        });
        if spec_legal && prepared.case().expect.backends_agree {
            card_failed(&c, is_ref, &mut failed, &mut problems);
        }
        c
    });
    let judge_time = start.elapsed().saturating_sub(twins_time);
    time(Stage::Compare, || {
        interior_failed(&prepared, &error, &mut failed, &mut problems)
    });
    Outcome::Done(Box::new(Judged {
        prepared,
        frame,
        truths,
        error,
        agreement,
        pixels,
        ssim,
        reference,
        legal,
        failed,
        judge_time,
        twins_time,
        twins,
        problems,
        fingerprint,
        card,
        twin_frames,
    }))
}

/// `frame` judged against the reference's render for `profile`, a calibrated profile.
fn judged_by_card(prepared: &Prepared, frame: &Frame, profile: umbra_case::Profile) -> CardJudged {
    let judged = crate::judge::judge_cache::judged(prepared, profile, carries_map(frame));
    let (agreement, _) = umbra_compare::reference::judge(&judged, frame);
    CardJudged {
        judged_as: judged.profile.name(),
        agreement,
    }
}

/// Whether `frame` carries a shadow map, which the judge then holds to the map's ranges.
fn carries_map(frame: &Frame) -> bool {
    frame.lights.iter().any(|p| p.shadow_map.is_some())
}

/// A run legal under the spec but not under its card: a failed `card` check and its line.
/// Counted only where the spec's judgement passed (a spec failure says more, and keeps the
/// signature an expectation names).
fn card_failed(
    c: &CardJudged,
    is_ref: bool,
    failed: &mut Vec<FailedCheck>,
    problems: &mut Vec<String>,
) {
    let a = &c.agreement;
    if a.illegal == 0 && a.illegal_map == 0 {
        return;
    }
    problems.push(if is_ref {
        format!(
            "umbra's reference is outside its own card's narrowing of the spec ({}; {} map texels; judged as {}): a bug in the calibration, not in a driver",
            a.illegal_summary(),
            a.illegal_map,
            c.judged_as
        )
    } else {
        format!(
            "inside the spec but outside its own card ({}; {} map texels; judged as {}): the driver chose differently in this scene than in its card's probes",
            a.illegal_summary(),
            a.illegal_map,
            c.judged_as
        )
    });
    failed.push(FailedCheck {
        check: Check::Card,
        count: a.illegal.max(a.illegal_map),
    });
}

/// The backend's frame of `prepared`, or the outcome that ends the run: a skip (a backend
/// that finds out only while rendering that it cannot run the case says so the same way,
/// never a failure), an error, or a frame of the wrong size.
fn rendered(backend: &mut dyn Backend, prepared: &Prepared) -> Result<Frame, Outcome> {
    let frame = match backend.render(prepared) {
        Ok(f) => f,
        Err(umbra_case::BackendError::Unsupported(why)) => return Err(Outcome::Skip(why)),
        Err(e) => return Err(Outcome::Error(e.to_string())),
    };
    if (frame.width, frame.height) != (prepared.camera.size[0], prepared.camera.size[1])
        || frame
            .lights
            .iter()
            .any(|p| p.visibility.len() != (frame.width * frame.height) as usize)
    {
        return Err(Outcome::Error(format!(
            "the backend returned a {}x{} frame for a {:?} camera",
            frame.width, frame.height, prepared.camera.size
        )));
    }
    Ok(frame)
}

/// Each twin that disagreed: a failed `twin:NAME` check and its line.
fn twins_failed(twins: &[TwinMetric], failed: &mut Vec<FailedCheck>, problems: &mut Vec<String>) {
    for t in twins.iter().filter(|t| !t.ok) {
        failed.push(FailedCheck {
            check: Check::Twin(t.name.clone()),
            count: t.pair.illegal.max(1),
        });
        problems.push(format!(
            "twin {} ({}): {} px differ, {} illegal ({}; {}); interior error {} vs the twin's {}",
            t.name,
            t.agree,
            t.pair.differ,
            t.pair.illegal,
            t.pair.illegal_summary(),
            t.pair.legal_summary(),
            t.interior_error,
            t.twin_interior_error
                .map(|e| e.to_string())
                .unwrap_or("-".into())
        ));
    }
}

/// A frame or map outside what the specs allow: each check it broke, and its line.
fn illegal_failed(a: &RefAgreement, failed: &mut Vec<FailedCheck>, problems: &mut Vec<String>) {
    for (check, count) in [
        (Check::Value, a.illegal_value),
        (Check::Nan, a.illegal_nan),
        (Check::Coverage, a.illegal_coverage),
        (Check::Colour, a.illegal_colour),
        (Check::Map, a.illegal_map),
    ] {
        if count > 0 {
            failed.push(FailedCheck { check, count });
        }
    }
    problems.push(format!(
        "{} px and {} map texels break what the specs allow ({}) of {} px and {} texels compared; {}",
        a.illegal,
        a.illegal_map,
        a.illegal_summary(),
        a.compared,
        a.map_checked,
        a.legal_summary()
    ));
}

/// The case's `expect.interior_error` against the error away from shadow edges: the
/// `interior` check and its line where it does not hold.
fn interior_failed(
    prepared: &Prepared,
    error: &TruthError,
    failed: &mut Vec<FailedCheck>,
    problems: &mut Vec<String>,
) {
    let a = error.away_from_edges;
    let (shadow_bad, light_bad) = match prepared.case().expect.interior_error {
        InteriorError::Reported => (false, false),
        InteriorError::Zero => (a.false_shadow > 0, a.false_light > 0),
        InteriorError::NoFalseLight => (false, a.false_light > 0),
        InteriorError::NoFalseShadow => (a.false_shadow > 0, false),
    };
    if shadow_bad || light_bad {
        failed.push(FailedCheck {
            check: Check::Interior,
            count: a.false_shadow * u64::from(shadow_bad) + a.false_light * u64::from(light_bad),
        });
        problems.push(format!(
            "expect.interior_error is {}, but away from shadow edges {} px are falsely shadowed and {} px falsely lit (of {} judged)",
            serde_json::to_string(&prepared.case().expect.interior_error).unwrap_or_default(),
            a.false_shadow,
            a.false_light,
            a.judged
        ));
    }
}

/// Renders every twin of the run on the same backend and compares it with `frame` (`legal`
/// twins: the twin's frame is judged against the case's own judged render, as a backend's
/// frame is, since the twin's change must not matter). `frames`: per twin, its frame where
/// one was rendered already (judged again, [`judge_again`]); each twin rendered here is kept
/// there.
fn run_twins(
    backend: &mut dyn Backend,
    as_written: &CasePoint,
    prepared: &Prepared,
    (frame, error, judged): (&Frame, &TruthError, &umbra_ref::Judged),
    frames: &mut Vec<Option<(Frame, bool)>>,
) -> Vec<(TwinMetric, Failed)> {
    let interior = |e: &TruthError| e.away_from_edges.false_shadow + e.away_from_edges.false_light;
    let plans = umbra_case::twin::twins_of(as_written);
    frames.resize(plans.len(), None);
    plans
        .into_iter()
        .zip(frames.iter_mut())
        .map(|(plan, kept)| {
            let mut m = TwinMetric {
                name: plan.name.clone(),
                agree: serde_json::to_value(plan.agree)
                    .ok()
                    .and_then(|v| v.as_str().map(String::from))
                    .unwrap_or_default(),
                interior_error: interior(error),
                ok: true,
                ..Default::default()
            };
            let point = match plan.point {
                Ok(p) => p,
                Err(e) => {
                    m.ok = false;
                    m.skipped = Some(format!("cannot build the twin: {e}"));
                    return (m, Failed::default());
                }
            };
            if let Support::Unsupported(why) = backend.supports(&Needs::of(&point.case)) {
                m.skipped = Some(why);
                return (m, Failed::default());
            }
            if backend.renders_identically(&as_written.case, &point.case) {
                // The same render twice: its frame would be the case's own, bit for bit.
                m.by_construction = true;
                m.twin_interior_error = Some(m.interior_error);
                m.pair = RefAgreement {
                    compared: error.all.judged,
                    ..Default::default()
                };
                return (m, Failed::default());
            }
            let twin_prepared = Prepared::new(point);
            let mut render = || match kept.clone() {
                Some(given) => Ok(given),
                None => time(Stage::TwinRender, || {
                    backend.render_twin(&twin_prepared, prepared)
                }),
            };
            let twin = match render() {
                // A twin may change the shadow pass on purpose (another frustum, a moved
                // scene): only its frame is held to the case, not its map.
                Ok((mut f, shared)) => {
                    m.shared_shadow_pass = shared;
                    // Every light's map (only the first light's was dropped once).
                    f.lights.iter_mut().for_each(|p| p.shadow_map = None);
                    *kept = Some((f.clone(), shared));
                    f
                }
                Err(e) => {
                    m.ok = false;
                    m.skipped = Some(format!("the twin failed to render: {e}"));
                    return (m, Failed::default());
                }
            };
            m.render_ms = twin.timings.total.as_secs_f64() * 1e3;
            if (twin.width, twin.height) != (frame.width, frame.height) {
                m.ok = false;
                m.skipped = Some("the twin's frame has another size".into());
                return (m, Failed::default());
            }
            if matches!(plan.agree, TwinAgree::NoWorse | TwinAgree::Reported) {
                // Cached like the case's own: the same twin on every backend is one truth.
                let twin_truths = crate::judge::judge_cache::truths(&twin_prepared);
                m.twin_interior_error = Some(interior(&crate::judge::judge_cache::truth_error(
                    &twin,
                    &twin_truths,
                )));
            }
            let (pair, px) = umbra_compare::reference::judge(judged, &twin);
            m.pair = pair;
            let mut failed = umbra_compare::reference::frame_failures(&twin, &px);
            match plan.agree {
                TwinAgree::Identical => {
                    // Bit-identical visibility wherever either frame covers a surface.
                    failed = Failed::default();
                    let n = (frame.width * frame.height) as usize;
                    for i in (0..n).filter(|&i| frame.covered(i) || twin.covered(i)) {
                        // The first light (of every light's planes) whose value differs.
                        let differs =
                            frame.lights.iter().zip(&twin.lights).find(|(a, b)| {
                                a.visibility[i].to_bits() != b.visibility[i].to_bits()
                            });
                        if let Some((_, b)) = differs {
                            failed.push(i, umbra_compare::is_shadowed(b.visibility[i]));
                        }
                    }
                    let differ = failed.total;
                    m.pair = RefAgreement {
                        compared: m.pair.compared,
                        differ,
                        illegal: differ,
                        ..Default::default()
                    };
                    m.ok = differ == 0;
                }
                // A case that disowns the reference's tolerance model (backends_agree false)
                // cannot hold its twins to it either: they are reported.
                TwinAgree::Legal => {
                    m.ok = m.pair.illegal == 0 || !prepared.case().expect.backends_agree;
                }
                TwinAgree::NoWorse => m.ok = m.twin_interior_error <= Some(m.interior_error),
                TwinAgree::Reported => {}
            }
            if m.ok {
                failed = Failed::default();
            }
            (m, failed)
        })
        .collect()
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
            "  vs reference: {} of {} px give another answer ({}); {} illegal{}\n  \
             check strength: {} px blind ({:.3}%), {} values held to an interval (closest margin {}), {} colours checked; colour SSIM {:.5}\n",
            a.differ,
            a.compared,
            a.legal_summary(),
            a.illegal,
            if a.illegal > 0 { format!(" ({})", a.illegal_summary()) } else { String::new() },
            a.blind,
            100.0 * a.blind_share(),
            a.value_checked,
            a.value_margin.map_or("-".into(), |m| format!("{m:.4}")),
            a.colour_checked,
            j.ssim.unwrap_or(f64::NAN)
        ));
    }
    for t in &j.twins {
        match &t.skipped {
            Some(why) => s.push_str(&format!("  twin {} ({}): not run: {why}\n", t.name, t.agree)),
            None => s.push_str(&format!(
                "  twin {} ({}): {} px differ ({}; {} illegal); interior error {} vs {}; {:.2} ms; {}\n",
                t.name,
                t.agree,
                t.pair.differ,
                t.pair.legal_summary(),
                t.pair.illegal,
                t.interior_error,
                t.twin_interior_error.map(|e| e.to_string()).unwrap_or("-".into()),
                t.render_ms,
                if t.ok { "ok" } else { "FAILED" }
            )),
        }
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
