//! Where a run's harness time goes, stage by stage: the exact truth (computed, or read back
//! and sampled), the reference's judged render (computed, or read back), waiting for another
//! worker that is computing an entry, the per-pixel comparison with the reference, the
//! card's second judgement, the twins (their renders and their judging) and the golden check.
//!
//! Each stage's time is *exclusive*: a stage entered inside another (the judged render a
//! card asks for, a truth a twin needs) pauses the outer one, so the stages of a run add up
//! to its harness time and nothing is counted twice. The clock is per thread (a worker
//! judges on the thread that answers the request; the reference's own rayon threads run
//! inside whichever stage started them). [`take`] hands the run's figures to its metrics
//! (`stages_ms` in report.json), which `umbra timing` sums per run kind.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// One stage of a run's harness time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Shadow rays against the real primitives, computed (a cache miss).
    TruthRays,
    /// A cached truth read back, inflated and checked at its sampled pixels.
    TruthRead,
    /// The reference's judged render, computed: its shadow pass with every texel's legal
    /// range (the map's freedom: rounding, offset, coverage, mip levels).
    JudgedMap,
    /// … its lit pass with every pixel's judged lookup (the legal interval over the lookup
    /// point's region, its ambiguity, its colour's bounds).
    JudgedLookups,
    /// … and the rest of it (the scene's adjacency, the planes turned top row first).
    JudgedRender,
    /// A cached judged render read back and inflated.
    JudgedRead,
    /// Waiting for another worker that holds an entry's lock.
    Wait,
    /// A computed entry packed (deflated), sealed and written for the next worker.
    CacheWrite,
    /// The frame against the truth and against the reference's intervals, SSIM, and the
    /// interior check.
    Compare,
    /// The second judgement, against the backend's card (its own judged render excluded).
    Card,
    /// The twins' own renders.
    TwinRender,
    /// The twins' judging (their truths excluded).
    TwinJudge,
    /// PNG encoding and the golden comparison.
    Golden,
}

impl Stage {
    /// Every stage, in the order reports print them.
    pub const ALL: [Stage; 13] = [
        Stage::TruthRays,
        Stage::TruthRead,
        Stage::JudgedMap,
        Stage::JudgedLookups,
        Stage::JudgedRender,
        Stage::JudgedRead,
        Stage::Wait,
        Stage::CacheWrite,
        Stage::Compare,
        Stage::Card,
        Stage::TwinRender,
        Stage::TwinJudge,
        Stage::Golden,
    ];

    /// The name report.json and `umbra timing` use.
    pub fn name(self) -> &'static str {
        match self {
            Stage::TruthRays => "truth_rays",
            Stage::TruthRead => "truth_read",
            Stage::JudgedMap => "judged_map",
            Stage::JudgedLookups => "judged_lookups",
            Stage::JudgedRender => "judged_render",
            Stage::JudgedRead => "judged_read",
            Stage::Wait => "wait",
            Stage::CacheWrite => "cache_write",
            Stage::Compare => "compare",
            Stage::Card => "card",
            Stage::TwinRender => "twin_render",
            Stage::TwinJudge => "twin_judge",
            Stage::Golden => "golden",
        }
    }
}

#[derive(Default)]
struct Clock {
    /// The stages entered and not left, innermost last, with when each last resumed.
    open: Vec<(Stage, Instant)>,
    /// Exclusive time per stage since the last [`take`].
    spent: BTreeMap<Stage, Duration>,
}

thread_local! {
    static CLOCK: RefCell<Clock> = RefCell::new(Clock::default());
}

/// Runs `f` as `stage`: its time counts to `stage`, less any stage entered inside it.
pub fn time<T>(stage: Stage, f: impl FnOnce() -> T) -> T {
    CLOCK.with(|c| {
        let mut c = c.borrow_mut();
        let now = Instant::now();
        if let Some((outer, since)) = c.open.last().copied() {
            *c.spent.entry(outer).or_default() += now - since;
        }
        c.open.push((stage, now));
    });
    let value = f();
    CLOCK.with(|c| {
        let mut c = c.borrow_mut();
        let now = Instant::now();
        if let Some((inner, since)) = c.open.pop() {
            *c.spent.entry(inner).or_default() += now - since;
        }
        if let Some(outer) = c.open.last_mut() {
            outer.1 = now;
        }
    });
    value
}

/// Moves `d` of the innermost open stage's time so far (at most all of it) to `to`: a stage that learns how its
/// time divides (the judged render's own timings) says so without a clock of its own.
pub fn attribute(to: Stage, d: Duration) {
    CLOCK.with(|c| {
        let mut c = c.borrow_mut();
        let now = Instant::now();
        if let Some((open, since)) = c.open.last_mut() {
            let slice = now - *since;
            *since = now;
            let open = *open;
            let spent = c.spent.entry(open).or_default();
            *spent += slice;
            let moved = d.min(*spent);
            *spent -= moved;
            *c.spent.entry(to).or_default() += moved;
        }
    });
}

/// The time of each stage since the last call, in ms (stages never entered left out), and
/// the clock reset for the next run.
pub fn take() -> BTreeMap<String, f64> {
    CLOCK.with(|c| {
        std::mem::take(&mut c.borrow_mut().spent)
            .into_iter()
            .map(|(s, d)| (s.name().to_string(), d.as_secs_f64() * 1e3))
            .collect()
    })
}

/// The kind of run a case point is, for `umbra timing`'s table: what decides how much its
/// judging costs. The light count, each light's map shape (`2d`, `cube`, `cascades`), where
/// several maps live (`array`, `cube_array`), the filter, and a mip chain.
pub fn run_kind(case: &umbra_case::Case) -> String {
    use umbra_case::format::{Filter, Light, Placement};
    let shape = |l: &Light| match l {
        Light::Point(_) => "cube",
        Light::Directional(d) if d.cascades.is_some() => "cascades",
        _ => "2d",
    };
    let mut shapes: Vec<&str> = case.lights.iter().map(shape).collect();
    shapes.dedup();
    let mut kind = match case.lights.len() {
        1 => format!("1 light, {}", shapes.join("+")),
        n => format!("{n} lights, {}", shapes.join("+")),
    };
    if case.lights.len() > 1 {
        match case.shadow.placement {
            Placement::Separate => {}
            Placement::Array => kind += " array",
            Placement::CubeArray => kind += " cube_array",
        }
    }
    kind += match case.shadow.filter {
        Filter::Nearest => ", nearest",
        Filter::Linear => ", linear",
        Filter::Pcf(_) => ", pcf",
        Filter::Castano13 => ", castano",
        Filter::Vogel5 => ", vogel",
    };
    if case.shadow.mipmaps.is_some() {
        kind += ", mips";
    }
    kind
}

#[cfg(test)]
mod tests {
    use super::*;

    fn busy(ms: u64) {
        let end = Instant::now() + Duration::from_millis(ms);
        while Instant::now() < end {}
    }

    #[test]
    fn nested_stages_are_exclusive_and_add_up() {
        take();
        let start = Instant::now();
        time(Stage::Card, || {
            busy(5);
            time(Stage::JudgedRender, || busy(10));
            busy(5);
        });
        let total = start.elapsed().as_secs_f64() * 1e3;
        let t = take();
        assert!(t["judged_render"] >= 10.0, "{t:?}");
        assert!(t["card"] >= 10.0, "{t:?}");
        // Exclusive slices of the same span: never more than it, and all of the busy time.
        let sum: f64 = t.values().sum();
        assert!(sum <= total && sum >= 20.0, "{sum} of {total}: {t:?}");
        assert!(take().is_empty(), "take resets the clock");
    }

    #[test]
    fn attributed_time_moves_out_of_the_open_stage() {
        take();
        time(Stage::JudgedRender, || {
            busy(12);
            attribute(Stage::JudgedMap, Duration::from_millis(4));
            // More than the stage has spent moves only what it has.
            attribute(Stage::JudgedLookups, Duration::from_secs(60));
        });
        let t = take();
        assert!((t["judged_map"] - 4.0).abs() < 1e-9, "{t:?}");
        assert!(
            t["judged_lookups"] >= 8.0 && t["judged_lookups"] < 60_000.0,
            "{t:?}"
        );
        assert!(t["judged_render"] < 1.0, "{t:?}");
    }
}
