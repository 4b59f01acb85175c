//! One technique point measured for `umbra sweep`: frame time as the median of N renders after
//! one warm-up render, and the error of one of those frames against the exact truth. The frame
//! time is the shadow pass plus the lit pass, timed by GPU timer queries where the backend has
//! them, else CPU wall (the clock is recorded); the CPU wall of the whole render call, set-up
//! and readback included, is kept beside it.

use std::time::Duration;

use serde::{Deserialize, Serialize};
use umbra_case::{Backend, CasePoint, Clock, Needs, Prepared, Support};

/// What a measured point reports.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Measured {
    /// `gpu` (timer queries) or `cpu-wall`; `mixed` if the renders disagreed.
    pub clock: String,
    /// Timed renders after the warm-up.
    pub samples: u32,
    /// Median shadow pass, ms.
    pub shadow_ms: f64,
    /// Median lit pass, ms.
    pub lit_ms: f64,
    /// Median frame time: shadow pass + lit pass, on `clock`, ms. The sweep's time axis.
    pub frame_ms: f64,
    /// Median CPU wall of the whole `render` call (set-up, both passes, readback), ms.
    pub total_ms: f64,
    /// Judged pixels.
    pub judged: u64,
    /// False shadow (acne), pixels.
    pub false_shadow: u64,
    /// False light (leaks, peter-panning), pixels.
    pub false_light: u64,
    /// Edge displacement against the truth: mean, px.
    pub edge_mean_px: Option<f64>,
    /// Edge displacement against the truth: max, px.
    pub edge_max_px: Option<f64>,
    /// Perspective aliasing at the judged pixels (screen pixels per shadow-map texel, Lloyd
    /// et al.'s measure): the worst pixel's.
    #[serde(default)]
    pub aliasing_max: Option<f64>,
    /// Perspective aliasing: the mean over the judged pixels.
    #[serde(default)]
    pub aliasing_mean: Option<f64>,
    /// The nearest and farthest judged view depths (where the aliasing was measured).
    #[serde(default)]
    pub view_depths: Option<(f64, f64)>,
}

/// Outcome of measuring one point.
pub enum Measurement {
    /// Measured.
    Done(Measured),
    /// The backend cannot run the technique, and why.
    Skip(String),
    /// A render failed.
    Error(String),
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Renders `point` 1 + `repeat` times on `backend` and judges the last frame.
pub fn measure(backend: &mut dyn Backend, point: CasePoint, repeat: u32) -> Measurement {
    if let Support::Unsupported(why) = backend.supports(&Needs::of(&point.case)) {
        return Measurement::Skip(why);
    }
    let prepared = Prepared::new(point);
    // Only the timings are kept, and the last frame: holding every frame would make each
    // render allocate (and fault in) fresh memory, which a backend rendering in the caller's
    // memory (the reference) would pay for in its time.
    let mut timed = Vec::new();
    let mut last = None;
    for k in 0..=repeat.max(1) {
        drop(last.take());
        match backend.render(&prepared) {
            Ok(f) => {
                if k > 0 {
                    timed.push(f.timings);
                }
                last = Some(f);
            }
            Err(e) => return Measurement::Error(e.to_string()),
        }
    }
    let Some(frame) = last else {
        return Measurement::Error("no frame was rendered".into());
    };
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let clocks: Vec<Option<Clock>> = timed.iter().map(|t| t.clock).collect();
    let clock = if clocks.iter().all(|c| *c == Some(Clock::Gpu)) {
        "gpu"
    } else if clocks.iter().all(|c| *c != Some(Clock::Gpu)) {
        "cpu-wall"
    } else {
        "mixed"
    };
    let truths = crate::judge::judge_cache::truths(&prepared);
    let error = crate::judge::judge_cache::truth_error(&frame, &truths);
    // Edges and aliasing: the sweep's one light (its cases have one; of several, the first).
    let (truth, light) = (&truths[0], &prepared.lights[0]);
    let missing = vec![f32::NAN; (frame.width * frame.height) as usize];
    let edges = umbra_compare::edges::edge_displacement(
        umbra_compare::reference::light_of(&frame, 0, &missing),
        truth,
    );
    let aliasing = umbra_ref::truth::aliasing::perspective_aliasing(light, truth);
    Measurement::Done(Measured {
        clock: clock.into(),
        samples: timed.len() as u32,
        shadow_ms: median(timed.iter().map(|t| ms(t.shadow_pass)).collect()),
        lit_ms: median(timed.iter().map(|t| ms(t.lit_pass)).collect()),
        frame_ms: median(
            timed
                .iter()
                .map(|t| ms(t.shadow_pass + t.lit_pass))
                .collect(),
        ),
        total_ms: median(timed.iter().map(|t| ms(t.total)).collect()),
        judged: error.all.judged,
        false_shadow: error.all.false_shadow,
        false_light: error.all.false_light,
        edge_mean_px: edges.mean_px,
        edge_max_px: edges.max_px,
        aliasing_max: aliasing.map(|a| a.max),
        aliasing_mean: aliasing.map(|a| a.mean),
        view_depths: aliasing.map(|a| a.depths),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(super::median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(super::median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
