//! The results model every writer reads: one [`RunResult`] per run with its [`Status`], the
//! judged [`Metrics`] (with each [`TwinMetric`] and the [`FailedCheck`]s that make its
//! signature), and the [`TimeBudget`] of a whole run. Workers send these as JSON, the
//! orchestrator completes them with expectations, and the writers turn them into files; none of
//! the three needs to know how the others work.

use std::fmt;
use std::time::Duration;

use serde::{Deserialize, Serialize};
use umbra_compare::reference::RefAgreement;

/// The status of one run.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "status", content = "reason")]
pub enum Status {
    /// Rendered and judged as expected.
    Pass,
    /// Rendered and judged wrong, or the backend reported an error.
    Fail,
    /// The worker died during the run.
    Crash,
    /// The run did not finish within the per-run time limit.
    Timeout,
    /// The backend cannot run it; the reason says why.
    Skip(String),
    /// Failed as an expectation says it will.
    ExpectedFail,
    /// Passed although an expectation says it fails: update the baseline.
    UnexpectedPass,
    /// Failed on a worker where another run had gone before it, then passed alone on a fresh
    /// worker: state left by an earlier run (a stale uniform, a stale binding) changed its
    /// answer. A regression, never a flake; the reason names the run that went before.
    OrderDependent,
    /// Failed with evidence of nondeterminism (the worker crashed or hung), then passed on
    /// its rerun on a fresh worker.
    Flake,
}

impl Status {
    /// The name deqp-runner's CSV uses.
    pub fn name(&self) -> &'static str {
        match self {
            Status::Pass => "Pass",
            Status::Fail => "Fail",
            Status::Crash => "Crash",
            Status::Timeout => "Timeout",
            Status::Skip(_) => "Skip",
            Status::ExpectedFail => "ExpectedFail",
            Status::UnexpectedPass => "UnexpectedPass",
            Status::OrderDependent => "OrderDependent",
            Status::Flake => "Flake",
        }
    }

    /// Where the report's gallery puts a run (issue 59): failures first (every regression:
    /// a failure, a crash, a timeout, an unexpected pass, an order-dependent failure), then
    /// flakes, expected failures, skips and passes, the order a driver developer reads in.
    pub fn glance_rank(&self) -> u8 {
        match self {
            Status::Fail
            | Status::Crash
            | Status::Timeout
            | Status::UnexpectedPass
            | Status::OrderDependent => 0,
            Status::Flake => 1,
            Status::ExpectedFail => 2,
            Status::Skip(_) => 3,
            Status::Pass => 4,
        }
    }

    /// The name deqp-runner's parser reads (`RunnerStatus`'s FromStr in deqp-runner 0.24's
    /// `runner_results.rs`), for results.csv and failures.csv, which Mesa's CI tools read:
    /// an unexpected pass is `UnexpectedImprovement(Pass)` since deqp-runner 0.16, and an
    /// order-dependent failure, which deqp-runner has no word for, is a `Fail` (report.json
    /// keeps umbra's name and the reason).
    pub fn deqp_name(&self) -> &'static str {
        match self {
            Status::UnexpectedPass => "UnexpectedImprovement(Pass)",
            Status::OrderDependent => "Fail",
            s => s.name(),
        }
    }

    /// The status a name stands for ([`Status::name`]'s inverse; a skip's reason is not in
    /// its name, so it reads back empty): how a status written to report.json or a CSV is
    /// counted again.
    pub fn of_name(name: &str) -> Option<Status> {
        Some(match name {
            "Pass" => Status::Pass,
            "Fail" => Status::Fail,
            "Crash" => Status::Crash,
            "Timeout" => Status::Timeout,
            "Skip" => Status::Skip(String::new()),
            "ExpectedFail" => Status::ExpectedFail,
            "UnexpectedPass" | "UnexpectedImprovement(Pass)" => Status::UnexpectedPass,
            "OrderDependent" => Status::OrderDependent,
            "Flake" => Status::Flake,
            _ => return None,
        })
    }

    /// Whether the status makes the run a regression (exit code 1).
    pub fn is_regression(&self) -> bool {
        matches!(
            self,
            Status::Fail
                | Status::Crash
                | Status::Timeout
                | Status::UnexpectedPass
                | Status::OrderDependent
        )
    }

    /// Whether the raw outcome is a failure of some kind (worth a rerun).
    pub fn is_failure(&self) -> bool {
        matches!(self, Status::Fail | Status::Crash | Status::Timeout)
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One failed check of a run: its name and how many pixels failed it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FailedCheck {
    /// Which check ([`crate::check::Check`]; written by its name).
    pub check: crate::check::Check,
    /// Pixels that failed it (1 for checks that are not counted in pixels).
    pub count: u64,
}

/// How one metamorphic twin ([`umbra_case::twin`]) compared with its case on one backend.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct TwinMetric {
    /// The twin's name.
    pub name: String,
    /// `identical`, `legal`, `no_worse` or `reported`.
    pub agree: String,
    /// Why the backend could not render the twin (the twin is then not judged).
    #[serde(default)]
    pub skipped: Option<String>,
    /// The comparison with the case's frame, by the reference judge's classes (for
    /// `identical`: every pixel whose visibility value differs at all counts as illegal).
    #[serde(flatten)]
    pub pair: RefAgreement,
    /// The case's false shadow + false light away from edges.
    pub interior_error: u64,
    /// The twin's, against its own truth (for `no_worse` and `reported`).
    pub twin_interior_error: Option<u64>,
    /// The twin's render time, ms (same clock as the case's).
    pub render_ms: f64,
    /// Not rendered: on this backend the twin is the case's own render by construction (it
    /// differs only in settings the backend never reads), so it holds trivially.
    #[serde(default)]
    pub by_construction: bool,
    /// Rendered over the case's own shadow map: the twin's shadow pass is the case's by
    /// construction (it changes only the lit pass), and the backend kept the map
    /// ([`umbra_case::Backend::render_twin`]), so only the lit pass was drawn again.
    #[serde(default)]
    pub shared_shadow_pass: bool,
    /// Whether the relation held.
    pub ok: bool,
}

/// The figures of one judged run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Metrics {
    /// Judged pixels.
    pub judged: u64,
    /// False shadow, all judged pixels.
    pub false_shadow: u64,
    /// False light, all judged pixels.
    pub false_light: u64,
    /// Judged pixels away from edges.
    pub interior_judged: u64,
    /// False shadow away from edges.
    pub interior_false_shadow: u64,
    /// False light away from edges.
    pub interior_false_light: u64,
    /// Edge pixels.
    pub edge_px: u64,
    /// Silhouette pixels.
    pub silhouette: u64,
    /// Pixels facing away from the light.
    pub faces_away: u64,
    /// Pixels outside the light's frustum.
    pub outside: u64,
    /// Agreement with the reference: share of compared pixels with the same answer.
    pub agreement: Option<f64>,
    /// Illegal pixels against the reference (every check).
    pub illegal: Option<u64>,
    /// Every count of the comparison with the reference: compared pixels, each legal class,
    /// blind pixels, checked values and their closest margin, each illegal check.
    #[serde(default)]
    pub reference: Option<umbra_compare::reference::RefAgreement>,
    /// The same comparison under the backend's card (calibrated judging: the spec's freedom
    /// narrowed to what the card's probes read); None where the run was judged by the spec
    /// alone. Its blind area is the run's blind area under the card.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_card: Option<umbra_compare::reference::RefAgreement>,
    /// The effective calibrated profile of that judgement (`gl card(r24=…,slope=max,…)`).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub judged_as_card: String,
    /// The profile the run was judged for (`gl`, `gles3`, `gles2-packed`, `vulkan`).
    #[serde(default)]
    pub profile: String,
    /// The effective profile its legal intervals were computed for (the profile with the
    /// freedoms that cannot matter for the case dropped): runs of one point with the same
    /// `judged_as` were held to the same intervals.
    #[serde(default)]
    pub judged_as: String,
    /// The backend's visibility target (`f32`, `unorm8`).
    #[serde(default)]
    pub visibility_storage: String,
    /// SSIM of the colour against the reference's.
    pub ssim: Option<f64>,
    /// SSIM of the colour against its golden, where one exists.
    pub ssim_golden: Option<f64>,
    /// How the colour differs from its golden, where it does (or where there is none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub golden_change: Option<GoldenChange>,
    /// Shadow pass, ms.
    pub shadow_ms: f64,
    /// Lit pass, ms.
    pub lit_ms: f64,
    /// Whole render, ms.
    pub total_ms: f64,
    /// `gpu` or `cpu-wall`.
    pub clock: String,
    /// The metamorphic twins (the built-in bias-order twin first).
    #[serde(default)]
    pub twins: Vec<TwinMetric>,
    /// Harness time of the run, ms: judging (truth, reference, agreement), the twins (their
    /// renders and judging), and the golden check (PNG encoding and comparison).
    #[serde(default)]
    pub judge_ms: f64,
    /// See `judge_ms`.
    #[serde(default)]
    pub twins_ms: f64,
    /// See `judge_ms`.
    #[serde(default)]
    pub golden_ms: f64,
    /// The kind of run (light count, map shape, placement, filter, mips) that decides what
    /// judging it costs: the rows of `umbra timing`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub kind: String,
    /// The run's harness time stage by stage, ms, each exclusive (truth rays or read, judged
    /// render or read, waiting for another worker's entry, compare, card, twin renders, twin
    /// judging, golden): what `umbra timing` sums.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub stages_ms: std::collections::BTreeMap<String, f64>,
    /// 64-bit FNV-1a of the frame's colour bytes: two builds' frames are the same picture
    /// exactly when these match (`umbra drivers`).
    #[serde(default)]
    pub color_hash: String,
    /// The same over the visibility values' bits.
    #[serde(default)]
    pub visibility_hash: String,
}

/// How a run's picture differs from its golden (outside the golden tolerance of one 8-bit
/// step per channel), and between which driver versions.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoldenChange {
    /// The Mesa version the golden was blessed on, where known.
    pub blessed_on: Option<String>,
    /// The Mesa version of this run's driver, where it is a Mesa driver.
    pub driver: Option<String>,
    /// Pixels with a channel more than one step from the golden's (every pixel of the frame
    /// when there is no golden or its size differs).
    pub pixels: u64,
    /// The largest channel difference, in 8-bit steps.
    pub max_step: u8,
    /// No golden on any release yet.
    pub new: bool,
    /// Of the changed pixels, those the judge found illegal on this driver (the run fails
    /// the judge's own checks there: value, coverage, colour). For a new picture (no golden
    /// anywhere) 1 when the judge failed the run, else 0.
    #[serde(default)]
    pub illegal: u64,
    /// Of the changed pixels, those the judge did not compare (the background): no check but
    /// the golden's speaks for them.
    #[serde(default)]
    pub unjudged: u64,
    /// The golden holds strictly on this driver: blessed (or confirmed) on its release, or
    /// not a Mesa driver. Any change is then a failure to review.
    #[serde(default)]
    pub strict: bool,
    /// The golden was blessed on another release and every pixel that differs is one the
    /// judge holds legal on this driver: reported as a changed picture, not a failure.
    pub legal: bool,
}

impl GoldenChange {
    /// `1234 px differ by up to 9/255`.
    pub fn pixels_phrase(&self) -> String {
        format!("{} px differ by up to {}/255", self.pixels, self.max_step)
    }

    /// One sentence for the terminal and the reports.
    pub fn describe(&self) -> String {
        let v = |x: &Option<String>| x.as_deref().unwrap_or("unknown").to_string();
        let (blessed, driver) = (v(&self.blessed_on), v(&self.driver));
        if self.strict {
            return match self.new {
                true => "no golden yet".to_string(),
                false => format!("differs from its golden: {}", self.pixels_phrase()),
            };
        }
        match (self.new, self.legal) {
            (true, true) => format!(
                "new picture, legal on this driver: no golden on any release yet (the backend's goldens are of Mesa {blessed}, this driver is Mesa {driver}) and every pixel is inside what the specs allow"
            ),
            (true, false) => format!(
                "new picture (no golden on any release yet; this driver is Mesa {driver}) that the judge's own checks fail"
            ),
            (false, true) => format!(
                "picture changed within the spec: {} from the golden blessed on Mesa {blessed}, every one legal on this driver (Mesa {driver})",
                self.pixels_phrase()
            ),
            (false, false) if self.unjudged == 0 => format!(
                "picture changed: {} from the golden blessed on Mesa {blessed}, {} of them where the judge finds this driver's (Mesa {driver}) answer illegal: failed by the judge's own checks there, not by the golden",
                self.pixels_phrase(),
                self.illegal
            ),
            (false, false) => format!(
                "picture changed: {} from the golden blessed on Mesa {blessed} (this driver Mesa {driver}), {} of them where the judge does not look (background)",
                self.pixels_phrase(),
                self.unjudged
            ),
        }
    }
}

/// One finished run, as reported (and as a shard's record keeps it for `umbra merge`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunResult {
    /// `backend/case@sweep`.
    pub name: String,
    /// The backend id.
    pub backend: String,
    /// The case point id.
    pub case: String,
    /// The case file.
    pub file: String,
    /// The point's swept values, `(path, value)` in axis order.
    pub values: Vec<(String, serde_json::Value)>,
    /// Final status.
    pub status: Status,
    /// Why (failure problems, skip reason, crash status, expectation reason).
    pub reason: String,
    /// Figures of the judged run, when it was judged.
    pub metrics: Option<Metrics>,
    /// The checks a failing run failed (its signature).
    pub failed: Vec<FailedCheck>,
    /// What became of its golden: `unchanged`, `written`, `written-for-release` (blessed as
    /// this Mesa release's golden beside another release's), `changed`,
    /// `changed-other-driver` (differs from another release's golden where the judge does not
    /// look, the background or the frame's size: failed, with both versions named),
    /// `changed-legal` (differs from another release's golden only where every pixel is legal,
    /// or has no golden on any release and passes: not a failure), or `changed-judged`
    /// (differs from another release's golden where some pixels are illegal: the judge's own
    /// checks fail the run there, the golden adds no failure); `metrics.golden_change` says
    /// how.
    pub golden: Option<String>,
    /// Wall time of the run including retries, seconds.
    pub time_s: f64,
    /// The command that reproduces this run alone.
    pub reproduce: String,
    /// For a failing run: how the other drivers of its profile answered where it failed
    /// (the consensus diagnosis), when any other ran the point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diagnosis: Option<Diagnosis>,
    /// What the worker wrote on stderr during a run that did not pass (a driver's warnings;
    /// before a crash, the C library's or the driver's last words), its last lines: the
    /// run's evidence, in report.json, junit.xml's `<system-err>` and the HTML report.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub stderr: String,
    /// Where the run broke the model (what the diagnosis compares; not reported itself).
    #[serde(skip)]
    pub fingerprint: Option<umbra_compare::consensus::Fingerprint>,
    /// The multi-line description of a judged run (terminal and logs only).
    #[serde(skip)]
    pub details: String,
}

#[cfg(test)]
impl RunResult {
    /// A run named `name` (`backend/case`) with `status` and nothing else: the reporting
    /// tests' starting point, each setting what it looks at.
    pub(crate) fn of_test(name: &str, status: Status) -> RunResult {
        let (backend, case) = name.rsplit_once('/').unwrap_or(("ref", name));
        RunResult {
            name: name.into(),
            backend: backend.into(),
            case: case.into(),
            file: String::new(),
            values: Vec::new(),
            status,
            reason: String::new(),
            metrics: None,
            failed: Vec::new(),
            golden: None,
            time_s: 0.0,
            reproduce: String::new(),
            diagnosis: None,
            stderr: String::new(),
            fingerprint: None,
            details: String::new(),
        }
    }
}

/// The consensus diagnosis of a failing run: whether the other drivers judged against the
/// same legal intervals (the same case point and effective profile) fail the same way at the
/// same pixels. Every correct implementation gives a legal answer, so when every driver of a
/// profile answers alike where the judge says none may, the judge's model is the first
/// suspect; when the others answer legally there, the driver is.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Drivers judged against the same intervals that ran the point, this one included.
    pub drivers: usize,
    /// Of those, how many fail the same way at the same pixels, this one included.
    pub agree: usize,
    /// The other drivers that answer legally at those pixels.
    pub disagree: Vec<String>,
    /// What the terminal and the reports show.
    pub message: String,
}

impl Diagnosis {
    /// Whether every driver of the profile fails alike (at least two of them): umbra's
    /// model, not a driver, is the first suspect.
    pub fn suspect_model(&self) -> bool {
        self.drivers >= 2 && self.agree == self.drivers
    }
}

/// Where a conformance run's time went, summed over its runs (worker time, not wall).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct TimeBudget {
    /// Wall time of the whole run, s.
    pub wall_s: f64,
    /// Σ per-run time measured by the parent (request to answer, retries included), s.
    pub runs_s: f64,
    /// Σ the backends' own frame time (both passes and readback), s.
    pub render_s: f64,
    /// Σ the metamorphic twins (their renders and comparisons), s.
    pub twins_s: f64,
    /// Σ judging: truth, reference with its ambiguity, error, agreement, s.
    pub judge_s: f64,
    /// Σ golden checks: PNG encoding and comparison, s.
    pub golden_s: f64,
    /// Σ worker start-up (spawn to hello), context creation included, s.
    pub worker_start_s: f64,
    /// Of that, context or device creation, s.
    pub context_s: f64,
    /// The rest of the per-run time: case loading, tessellation, protocol, retries, s.
    pub other_s: f64,
}

impl TimeBudget {
    /// Sums the budget of `results`.
    /// `worker_start` and `context` are the orchestrator's sums over every worker it started.
    pub fn of(
        results: &[RunResult],
        wall: Duration,
        worker_start: Duration,
        context: Duration,
    ) -> TimeBudget {
        let mut b = TimeBudget {
            wall_s: wall.as_secs_f64(),
            worker_start_s: worker_start.as_secs_f64(),
            context_s: context.as_secs_f64(),
            ..Default::default()
        };
        for r in results {
            b.runs_s += r.time_s;
            if let Some(m) = &r.metrics {
                b.render_s += m.total_ms / 1e3;
                b.twins_s += m.twins_ms / 1e3;
                b.judge_s += m.judge_ms / 1e3;
                b.golden_s += m.golden_ms / 1e3;
            }
        }
        b.other_s = (b.runs_s - b.render_s - b.twins_s - b.judge_s - b.golden_s).max(0.0);
        b
    }

    /// The budget of shards run side by side: every sum added up, the wall time the slowest
    /// shard's.
    pub fn merged(parts: &[TimeBudget]) -> TimeBudget {
        let mut b = TimeBudget::default();
        for p in parts {
            b.wall_s = b.wall_s.max(p.wall_s);
            b.runs_s += p.runs_s;
            b.render_s += p.render_s;
            b.twins_s += p.twins_s;
            b.judge_s += p.judge_s;
            b.golden_s += p.golden_s;
            b.worker_start_s += p.worker_start_s;
            b.context_s += p.context_s;
            b.other_s += p.other_s;
        }
        b
    }

    /// Worker start, context creation, judging and PNG encoding, as a share of all worker time.
    pub fn overhead_share(&self) -> f64 {
        let total = self.runs_s + self.worker_start_s;
        if total == 0.0 {
            0.0
        } else {
            (self.worker_start_s + self.judge_s + self.golden_s) / total
        }
    }

    /// One line for the terminal and the report.
    pub fn line(&self) -> String {
        let total = (self.runs_s + self.worker_start_s).max(1e-9);
        let pct = |x: f64| 100.0 * x / total;
        format!(
            "time: {:.1} s of worker time in {:.1} s wall: rendering {:.1} s ({:.0}%), twins {:.1} s ({:.0}%), judging {:.1} s ({:.0}%), goldens/PNG {:.1} s ({:.0}%), worker start {:.1} s ({:.0}%, context creation {:.1} s), other {:.1} s ({:.0}%); harness overhead (start, context, judging, PNG) {:.0}%",
            total,
            self.wall_s,
            self.render_s,
            pct(self.render_s),
            self.twins_s,
            pct(self.twins_s),
            self.judge_s,
            pct(self.judge_s),
            self.golden_s,
            pct(self.golden_s),
            self.worker_start_s,
            pct(self.worker_start_s),
            self.context_s,
            self.other_s,
            pct(self.other_s),
            100.0 * self.overhead_share()
        )
    }
}

/// How many runs ended in each status, in one line (the terminal summary and report.html).
pub fn breakdown(results: &[RunResult]) -> String {
    let count = |n: &str| results.iter().filter(|r| r.status.name() == n).count();
    format!(
        "pass {}, expected fail {}, flake {}, skip {}; fail {}, order-dependent {}, crash {}, timeout {}, unexpected pass {}",
        count("Pass"),
        count("ExpectedFail"),
        count("Flake"),
        count("Skip"),
        count("Fail"),
        count("OrderDependent"),
        count("Crash"),
        count("Timeout"),
        count("UnexpectedPass"),
    )
}
