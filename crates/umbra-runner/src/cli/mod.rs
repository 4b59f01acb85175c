//! The `umbra` command line as types: one [`Command`] enum, one options struct per command,
//! and the flag groups several commands share ([`Selection`], [`Execution`], [`Output`])
//! flattened into each, so a flag is declared, and its help written ([`help`]), once. clap
//! derives from them the parser, the `--help` of every subcommand, the errors (which name the
//! flag and suggest the near miss) and the shell completions (`umbra completions bash`).
//!
//! Numbers, durations, sizes and shards are typed ([`values`]): clap refuses a bad one the
//! same way for every command, and a default sits on its flag's declaration, from which clap
//! writes the help's `[default: …]`. A glob, a backend id and a Mesa build stay strings
//! here: what only the machine can check is checked when the shared groups are resolved
//! ([`resolve`]) or when the command sets up, with errors that name the flag and the fix.
//!
//! Exit codes ([`crate::exit::Exit`]): a command line clap refuses exits 125 ("could not
//! run", as every other set-up error), so `git bisect run cargo xtask conformance …` skips
//! instead of marking a commit bad; `--help` and `--version` exit 0.

use std::path::PathBuf;

use clap::{Args, CommandFactory, Parser, Subcommand, ValueEnum};

pub use crate::harness::mesa_build::MesaChoice;

/// The whole command line.
#[derive(Parser, Debug)]
#[command(
    name = "umbra",
    about = "A regression and conformance harness for shadow mapping on Mesa's GL and Vulkan drivers",
    version,
    subcommand_required = true,
    arg_required_else_help = true,
    after_help = "Exit codes: 0 as expected, 1 regressions (or a fault unseen, a first bad commit not found), 125 could not run."
)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// Every command `main` dispatches (`umbra deqp`, which speaks dEQP's own flags, is handed its
/// arguments before clap sees them).
#[derive(Subcommand, Debug)]
pub enum Command {
    /// `umbra render`.
    #[command(
        about = "Render one case on one backend and write its pictures (colour, visibility, truth, error heat map, shadow map) and figures (exit 0 every point within the specs, 1 a point fails, 125 could not run: a missing or invalid case, an unknown backend, a --point that matches nothing)"
    )]
    Render(RenderArgs),
    /// `umbra conformance`.
    #[command(
        about = "Run every case point on every backend, judge them, and write results.csv, failures.csv, junit.xml, report.json and report.html (exit 0 as expected, 1 regressions, 125 could not run)"
    )]
    Conformance(ConformanceArgs),
    /// `umbra merge`.
    #[command(
        about = "Merge the results of conformance shards (--shard I/N, on N jobs or machines) into one run: results.csv, failures.csv, junit.xml, report.json and report.html, judged across runs again as one unsharded run; refuses shards of different builds, inputs or overlapping runs, and names a missing shard (exit 0 as expected, 1 regressions, 125 could not merge)"
    )]
    Merge(MergeArgs),
    /// `umbra selftest`.
    #[command(
        about = "Inject each known fault into each backend's shaders and check that the judge catches it (exit 1 when a fault goes unseen); with --seed/--count, the catch rate on generated cases"
    )]
    Selftest(SelftestArgs),
    /// `umbra soak`.
    #[command(
        about = "Generate N valid cases from a seed and run them on every backend with the judge alone: runs, passes, skips, diagnosed deviations and failures by class per backend (exit 1 on any failure)"
    )]
    Soak(SoakArgs),
    /// `umbra sweep`.
    #[command(
        about = "Measure speed against error over a technique matrix per backend: sweep.csv, a Pareto plot (SVG, PNG) and an HTML section (exit 125 when it cannot run: an unknown backend, a missing case or point, a bad value)"
    )]
    Sweep(SweepArgs),
    /// `umbra drivers`.
    #[command(
        about = "Run the catalogue on two Mesa builds and report every changed point: regressions, fixes, changed pictures (exit 1 on a regression)"
    )]
    Drivers(DriversArgs),
    /// `umbra bisect`.
    #[command(
        about = "Find the first Mesa commit that breaks the chosen case points: build, install and test each step with git bisect"
    )]
    Bisect(BisectArgs),
    /// `umbra tier`.
    #[command(
        about = "Choose a pre-merge tier for a time budget from the self-test's catch matrix and recorded durations: every fault × backend pair the catalogue catches by at least one run, then more; prints its expected time and coverage and writes the tier file conformance --tier and selftest --tier run (--random SEED: a random draw of equal time, to compare)"
    )]
    Tier(TierArgs),
    /// `umbra timing`.
    #[command(
        about = "Where a conformance run's worker time went: per kind of run (or per backend), the backends' frames and each stage of judging (truth rays, the judged reference, cache reads, waiting, comparison, card, twins, golden), from its report.json"
    )]
    Timing(TimingArgs),
    /// `umbra reduce`.
    #[command(
        about = "Shrink a failing case point to a minimal case that still fails the same way on the backend, for a bug report"
    )]
    Reduce(ReduceArgs),
    /// `umbra repro`.
    #[command(
        about = "Turn a failing run (backend/case@point, as conformance names it) into a bug report a driver developer can use without umbra: a reduced case, a standalone C program (repro.c) with the judge's intervals as probes, an API capture, issue.md and pictures"
    )]
    Repro(ReproArgs),
    /// `umbra card`.
    #[command(
        about = "Measure each backend's behaviour card: what its driver chose wherever the specs leave a choice (polygon-offset unit and slope term, depth rounding, LINEAR-compare weights, sub-pixel bits, cube seams and face ties, the reference clamp, border compare, LOD scale factor and offset), each with the spec's range, the probe and how sure it is; --diff OLD NEW names what changed between two stored cards (exit 0 measured, 125 could not run)"
    )]
    Card(CardArgs),
    /// `umbra backends`.
    #[command(
        about = "List what this machine can run: every backend id with its driver's strings and how it is reached, every EGL device with the contexts it makes, every wgpu adapter (--json for scripts)"
    )]
    Backends(BackendsArgs),
    /// `umbra worker`.
    #[command(
        about = "One backend's worker process, speaking JSON lines on stdin/stdout (spawned by umbra)",
        hide = true
    )]
    Worker(WorkerArgs),
    /// `umbra bisect-step`.
    #[command(
        about = "One bisection step at the source tree's HEAD: build, install, test (spawned by git bisect run)",
        name = "bisect-step",
        hide = true
    )]
    BisectStep(BisectStepArgs),
    /// `umbra completions`.
    #[command(
        about = "Print a shell completion script (e.g. `umbra completions bash > /etc/bash_completion.d/umbra`)"
    )]
    Completions(CompletionsArgs),
}

pub mod help;
pub mod resolve;
pub mod values;

pub use resolve::{Limits, Selected};
pub use values::{BackendName, Bytes, Count, Jobs, Seconds, Shard};

/// What to run: the backends, the case points, the catalogue and its expectations (conformance, drivers, bisect).
#[derive(Args, Debug, Clone)]
pub struct Selection {
    /// `--cases`: the directory of case files.
    #[arg(long, value_name = "DIR", help = help::CASES, default_value = CASES_DIR)]
    pub cases: PathBuf,
    /// `--filter`: the glob over case points and run names.
    #[arg(long, value_name = "GLOB", help = help::FILTER)]
    pub filter: Option<String>,
    /// `--backend`: backend ids and aliases, each checked by clap ([`BackendName`]).
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<BackendName>,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS, default_value = EXPECTATIONS_DIR)]
    pub expectations: PathBuf,
}

/// `--cases`' default: the catalogue, relative to where umbra runs.
pub const CASES_DIR: &str = "cases";
/// `--expectations`' default.
pub const EXPECTATIONS_DIR: &str = "expectations";

impl Default for Selection {
    /// What a command line with no selection flag parses to.
    fn default() -> Selection {
        Selection {
            cases: CASES_DIR.into(),
            filter: None,
            backend: Vec::new(),
            expectations: EXPECTATIONS_DIR.into(),
        }
    }
}
/// How runs execute: workers, time and memory limits, the Mesa build, the judging cache (conformance, selftest, soak).
#[derive(Args, Debug, Clone)]
pub struct Execution {
    /// `--jobs`: worker processes at once (default: the core count, [`Execution::resolve`]).
    #[arg(long, value_name = "N", help = help::JOBS)]
    pub jobs: Option<Jobs>,
    /// `--timeout`: per-run time limit: conformance's and soak's default here, the
    /// self-test's on [`SelftestArgs`].
    #[arg(long, value_name = "SECS", help = help::TIMEOUT, default_value = "300")]
    pub timeout: Seconds,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
    /// `--max-memory`: the memory budget per worker.
    #[arg(long, value_name = "SIZE", help = help::MAX_MEMORY)]
    pub max_memory: Option<Bytes>,
    /// `--judge-cache`: where the judging basis is cached.
    #[arg(long, value_name = "DIR", help = help::JUDGE_CACHE)]
    pub judge_cache: Option<PathBuf>,
    /// `--spec-only`: no calibrated judging.
    #[arg(long, help = help::SPEC_ONLY)]
    pub spec_only: bool,
}
/// Where results go and how much is printed (conformance, selftest, soak, reduce).
#[derive(Args, Debug, Clone, Default)]
pub struct Output {
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: Option<PathBuf>,
    /// `--verbose`: every run's details.
    #[arg(long, help = help::VERBOSE)]
    pub verbose: bool,
}

/// `umbra render`.
#[derive(Args, Debug, Clone, Default)]
pub struct RenderArgs {
    /// The positional argument.
    #[arg(value_name = "CASE.json", help = "the case file")]
    pub positional: PathBuf,
    /// `--backend`: the one backend render runs; given twice, refused by clap (a `Vec` here
    /// once took the last without a word).
    #[arg(long, value_name = "ID", help = help::BACKEND_ONE)]
    pub backend: Option<BackendName>,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT, default_value = "target/umbra/render")]
    pub out: PathBuf,
    /// `--point`.
    #[arg(long, value_name = "GLOB", help = help::POINT)]
    pub point: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
    /// `--max-memory`: the memory budget per worker.
    #[arg(long, value_name = "SIZE", help = help::MAX_MEMORY)]
    pub max_memory: Option<Bytes>,
    /// `--explain`.
    #[arg(long, value_name = "X,Y", help = help::EXPLAIN)]
    pub explain: Option<String>,
}

/// `umbra conformance`.
#[derive(Args, Debug, Clone, Default)]
pub struct ConformanceArgs {
    /// Selection flags.
    #[command(flatten)]
    pub selection: Selection,
    /// `--shard`.
    #[arg(long, value_name = "I/N", help = help::SHARD)]
    pub shard: Option<Shard>,
    /// `--durations`.
    #[arg(long, value_name = "results.csv", help = help::DURATIONS)]
    pub durations: Option<PathBuf>,
    /// `--tier FILE`: run the tier's runs only (kept in the run directory).
    #[arg(long, value_name = "FILE", help = help::TIER, conflicts_with = "budget")]
    pub tier: Option<PathBuf>,
    /// `--budget DURATION`: choose a tier for the budget from the recorded catches and
    /// durations (`tiers/`), and run it.
    #[arg(long, value_name = "DURATION", help = help::BUDGET)]
    pub budget: Option<String>,
    /// Execution flags.
    #[command(flatten)]
    pub execution: Execution,
    /// `--golden`.
    #[arg(long, value_name = "DIR|none", help = help::GOLDEN, default_value = "golden")]
    pub golden: PathBuf,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
    /// `--bless`.
    #[arg(long, help = help::BLESS)]
    pub bless: bool,
}

/// `umbra merge`.
#[derive(Args, Debug, Clone, Default)]
pub struct MergeArgs {
    /// The positional arguments.
    #[arg(value_name = "DIR", help = "each shard's --out directory (or its runs/ID directory)", required = true, num_args = 1..)]
    pub dirs: Vec<PathBuf>,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: PathBuf,
}

/// `umbra selftest`: each run's time limit is 120 s (one point, no twins).
#[derive(Args, Debug, Clone, Default)]
#[command(mut_arg("timeout", |a| a.default_value("120")))]
pub struct SelftestArgs {
    /// `MODE`: faults (the default), thresholds or orientations.
    #[arg(
        value_enum,
        value_name = "MODE",
        default_value_t = SelftestMode::Faults,
        hide_possible_values = true,
        help = help::MODE
    )]
    pub mode: SelftestMode,
    /// `--backend`: backend ids and aliases, each checked by clap.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<BackendName>,
    /// `--fault`.
    #[arg(long, value_name = "NAME", help = help::FAULT)]
    pub fault: Vec<String>,
    /// `--cases`: the directory of case files.
    #[arg(long, value_name = "DIR", help = help::SELFTEST_CASES)]
    pub cases: Option<PathBuf>,
    /// `--orientations`.
    #[arg(long, hide = true, help = help::ORIENTATIONS)]
    pub orientations: bool,
    /// `--thresholds`.
    #[arg(long, hide = true, help = help::THRESHOLDS)]
    pub thresholds: bool,
    /// `--seed`: with `--count`, the self-test runs on generated cases.
    #[arg(long, value_name = "S", help = help::SELFTEST_SEED)]
    pub seed: Option<u64>,
    /// `--count`.
    #[arg(long, value_name = "N", help = help::SELFTEST_COUNT)]
    pub count: Option<Count>,
    /// `--catches FILE`: write the catch matrix (what a tier is chosen from).
    #[arg(long, value_name = "FILE", help = help::CATCHES_OUT)]
    pub catches: Option<PathBuf>,
    /// `--tier FILE`: hunt with the tier's runs only.
    #[arg(long, value_name = "FILE", help = help::TIER_SELFTEST)]
    pub tier: Option<PathBuf>,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS, default_value = EXPECTATIONS_DIR)]
    pub expectations: PathBuf,
    /// Execution flags.
    #[command(flatten)]
    pub execution: Execution,
}

/// `umbra soak`.
#[derive(Args, Debug, Clone)]
pub struct SoakArgs {
    /// `--seed`.
    #[arg(long, value_name = "S", help = help::SEED, default_value_t = 1)]
    pub seed: u64,
    /// `--count`.
    #[arg(long, value_name = "N", help = help::COUNT, default_value = "100")]
    pub count: Count,
    /// `--backend`: backend ids and aliases, each checked by clap.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<BackendName>,
    /// `--filter`: the glob over case points and run names.
    #[arg(long, value_name = "GLOB", help = help::FILTER)]
    pub filter: Option<String>,
    /// Execution flags.
    #[command(flatten)]
    pub execution: Execution,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS, default_value = EXPECTATIONS_DIR)]
    pub expectations: PathBuf,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
}

/// `umbra sweep`.
#[derive(Args, Debug, Clone)]
pub struct SweepArgs {
    /// `--scene`.
    #[arg(long, value_name = "CASE.json", help = help::SCENE)]
    pub scene: Option<PathBuf>,
    /// `--point`.
    #[arg(long, value_name = "GLOB", help = help::POINT)]
    pub point: Option<String>,
    /// `--backend`: backend ids and aliases, each checked by clap.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<BackendName>,
    /// `--repeat`.
    #[arg(long, value_name = "N", help = help::REPEAT, default_value = "5")]
    pub repeat: Count,
    /// `--timeout`: per-run time limit (a point's every technique, timed `--repeat` times).
    #[arg(long, value_name = "SECS", help = help::TIMEOUT, default_value = "600")]
    pub timeout: Seconds,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT, default_value = "target/umbra/sweep")]
    pub out: PathBuf,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
    /// `--max-memory`: the memory budget per worker.
    #[arg(long, value_name = "SIZE", help = help::MAX_MEMORY)]
    pub max_memory: Option<Bytes>,
    /// `--judge-cache`: where the judging basis is cached.
    #[arg(long, value_name = "DIR", help = help::JUDGE_CACHE)]
    pub judge_cache: Option<PathBuf>,
}

/// `umbra drivers`.
#[derive(Args, Debug, Clone, Default)]
pub struct DriversArgs {
    /// `--baseline`.
    #[arg(long, value_name = "PREFIX|system", help = help::BASELINE)]
    pub baseline: MesaChoice,
    /// `--candidate`.
    #[arg(long, value_name = "PREFIX|system", help = help::CANDIDATE)]
    pub candidate: MesaChoice,
    /// Selection flags.
    #[command(flatten)]
    pub selection: Selection,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT, default_value = "target/umbra/drivers")]
    pub out: PathBuf,
    /// `--pictures`.
    #[arg(long, value_name = "N", help = help::PICTURES, default_value_t = 200)]
    pub pictures: usize,
    /// `--jobs`: worker processes at once, handed to each side's conformance run.
    #[arg(long, value_name = "N", help = help::JOBS)]
    pub jobs: Option<Jobs>,
    /// `--timeout`: per-run time limit, handed to each side's conformance run (its default
    /// there).
    #[arg(long, value_name = "SECS", help = help::TIMEOUT_CONFORMANCE)]
    pub timeout: Option<Seconds>,
}

/// `umbra bisect`.
#[derive(Args, Debug, Clone, Default)]
pub struct BisectArgs {
    /// `--mesa-src`.
    #[arg(long, value_name = "DIR", help = help::MESA_SRC)]
    pub mesa_src: PathBuf,
    /// `--good`.
    #[arg(long, value_name = "REV", help = help::GOOD)]
    pub good: String,
    /// `--bad`.
    #[arg(long, value_name = "REV", help = help::BAD)]
    pub bad: String,
    /// Selection flags.
    #[command(flatten)]
    pub selection: Selection,
    /// `--work`.
    #[arg(long, value_name = "DIR", help = help::WORK, default_value = "target/umbra/bisect")]
    pub work: PathBuf,
    /// `--build-script`.
    #[arg(long, value_name = "PATH", help = help::BUILD_SCRIPT)]
    pub build_script: Option<PathBuf>,
    /// `--meson-option`.
    #[arg(long, value_name = "OPT", help = help::MESON_OPTION, allow_hyphen_values = true)]
    pub meson_option: Vec<String>,
    /// `--no-check-ends`.
    #[arg(long, help = help::NO_CHECK_ENDS)]
    pub no_check_ends: bool,
    /// `--configure-only`: derive and check both ends' options (and meson), configure, stop.
    #[arg(long, help = help::CONFIGURE_ONLY)]
    pub configure_only: bool,
    /// `--repro`.
    #[arg(long, value_name = "DIR", help = help::REPRO)]
    pub repro: Option<PathBuf>,
    /// `--card KEY=VALUE`: bisect a behaviour-card entry instead of case verdicts.
    #[arg(long, value_name = "KEY=VALUE", help = help::BISECT_CARD)]
    pub card: Option<String>,
}

/// `umbra tier`.
#[derive(Args, Debug, Clone)]
pub struct TierArgs {
    /// `--budget`: wall time, `90s`, `5m`, `premerge`, `smoke`.
    #[arg(long, value_name = "DURATION", help = help::BUDGET)]
    pub budget: String,
    /// `--catches`: the catch matrix.
    #[arg(long, value_name = "FILE", help = help::CATCHES_IN, default_value = crate::tier::CATCHES)]
    pub catches: PathBuf,
    /// `--durations`: a full run's results.csv.
    #[arg(long, value_name = "results.csv", help = help::TIER_DURATIONS, default_value = crate::tier::DURATIONS)]
    pub durations: PathBuf,
    /// `--jobs`: the worker processes the wall time assumes.
    #[arg(long, value_name = "N", help = help::TIER_JOBS, default_value_t = 2)]
    pub jobs: usize,
    /// `--random SEED`: a random tier of the same expected time.
    #[arg(long, value_name = "SEED", help = help::RANDOM)]
    pub random: Option<u64>,
    /// `--out`: the tier file.
    #[arg(short = 'o', long, value_name = "FILE", help = help::OUT, default_value = "target/umbra/tier.json")]
    pub out: PathBuf,
}

/// `umbra timing`.
#[derive(Args, Debug, Clone)]
pub struct TimingArgs {
    /// The report, or the run directory holding it.
    #[arg(
        value_name = "REPORT",
        help = "a report.json, or a run directory holding one",
        default_value = "target/umbra/latest"
    )]
    pub report: PathBuf,
    /// `--by`: what a row gathers.
    #[arg(long, value_enum, default_value_t = TimingBy::Kind, help = "what a row gathers")]
    pub by: TimingBy,
}

/// `umbra timing --by`.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimingBy {
    /// The kind of run: light count, map shape, placement, filter, mips.
    #[default]
    Kind,
    /// The backend.
    Backend,
}

/// `umbra reduce`.
#[derive(Args, Debug, Clone)]
pub struct ReduceArgs {
    /// The positional argument.
    #[arg(value_name = "CASE.json", help = "the case file")]
    pub positional: PathBuf,
    /// `--point`.
    #[arg(long, value_name = "GLOB", help = help::POINT)]
    pub point: String,
    /// `--backend`: backend ids and aliases, each checked by clap.
    #[arg(long, value_name = "ID", help = help::BACKEND, required = true)]
    pub backend: Vec<BackendName>,
    /// `--check`.
    #[arg(long, value_name = "CHECK", help = help::CHECK)]
    pub check: Vec<String>,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
    /// `--timeout`: per-run time limit (one candidate).
    #[arg(long, value_name = "SECS", help = help::TIMEOUT, default_value = "120")]
    pub timeout: Seconds,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
}

/// `umbra repro`.
#[derive(Args, Debug, Clone)]
pub struct ReproArgs {
    /// The positional argument.
    #[arg(value_name = "RUN", help = "the failing run, backend/case@point")]
    pub positional: String,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: PathBuf,
    /// `--cases`: the directory of case files.
    #[arg(long, value_name = "DIR", help = help::CASES, default_value = CASES_DIR)]
    pub cases: PathBuf,
    /// `--case`.
    #[arg(long, value_name = "CASE.json", help = help::CASE)]
    pub case: Option<PathBuf>,
    /// `--control`.
    #[arg(long, value_name = "ID", help = help::CONTROL)]
    pub control: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
    /// `--timeout`: per-run time limit of the reduction's candidates.
    #[arg(long, value_name = "SECS", help = help::TIMEOUT, default_value = "120")]
    pub timeout: Seconds,
    /// `--check`.
    #[arg(long, value_name = "CHECK", help = help::CHECK)]
    pub check: Vec<String>,
    /// `--bisect-log`.
    #[arg(long, value_name = "FILE", help = help::BISECT_LOG)]
    pub bisect_log: Option<PathBuf>,
    /// `--first-bad`.
    #[arg(long, value_name = "COMMIT", help = help::FIRST_BAD)]
    pub first_bad: Option<String>,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS, default_value = EXPECTATIONS_DIR)]
    pub expectations: PathBuf,
    /// `--backend`: the backend of `--emit`'s process (once).
    #[arg(long, value_name = "ID", help = help::BACKEND_ONE)]
    pub backend: Option<BackendName>,
    /// `--emit`.
    #[arg(long, help = help::EMIT)]
    pub emit: bool,
}

/// `umbra backends`.
#[derive(Args, Debug, Clone, Default)]
pub struct BackendsArgs {
    /// `--json`.
    #[arg(long, help = help::JSON)]
    pub json: bool,
    /// `--ids`.
    #[arg(long, help = help::IDS)]
    pub ids: bool,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
}

/// `umbra card`.
#[derive(Args, Debug, Clone)]
pub struct CardArgs {
    /// `--backend`: which backends to measure (default: this build's ids).
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<BackendName>,
    /// `--json`.
    #[arg(long, help = help::JSON)]
    pub json: bool,
    /// `--diff OLD NEW`: compare two stored cards instead of measuring.
    #[arg(long, num_args = 2, value_names = ["OLD", "NEW"], help = help::CARD_DIFF)]
    pub diff: Vec<PathBuf>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<MesaChoice>,
    /// `--timeout`: the time limit of one backend's probes (they take 0.1 to 2 s on this
    /// machine's software drivers; a slow hardware driver's shader compiles may take far
    /// longer).
    #[arg(long, value_name = "SECS", help = help::CARD_TIMEOUT, default_value = "300")]
    pub timeout: Seconds,
    /// `--keep DIR`: keep each card as the reviewed baseline in golden directory DIR.
    #[arg(long, value_name = "DIR", help = help::CARD_KEEP)]
    pub keep: Option<PathBuf>,
}

/// `umbra worker`.
#[derive(Args, Debug, Clone, Default)]
pub struct WorkerArgs {
    /// `--backend`: the one backend this worker hosts.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: String,
}

/// `umbra bisect-step`.
#[derive(Args, Debug, Clone, Default)]
pub struct BisectStepArgs {
    /// `--src`.
    #[arg(long, value_name = "DIR", help = help::SRC)]
    pub src: PathBuf,
    /// `--work`.
    #[arg(long, value_name = "DIR", help = help::WORK)]
    pub work: PathBuf,
    /// Selection flags.
    #[command(flatten)]
    pub selection: Selection,
    /// `--build-script`.
    #[arg(long, value_name = "PATH", help = help::BUILD_SCRIPT)]
    pub build_script: Option<PathBuf>,
    /// `--meson-option`: the user's own, after the derived ones.
    #[arg(long, value_name = "OPT", help = help::MESON_OPTION, allow_hyphen_values = true)]
    pub meson_option: Vec<String>,
    /// `--card KEY=VALUE`.
    #[arg(long, value_name = "KEY=VALUE", help = help::BISECT_CARD)]
    pub card: Option<String>,
}

/// `umbra completions`.
#[derive(Args, Debug, Clone)]
pub struct CompletionsArgs {
    /// The shell to write the script for (its possible values are the help).
    #[arg(value_name = "SHELL", help = None)]
    pub shell: clap_complete::Shell,
}
/// `--name value` for each value given, as a child umbra takes them back.
fn push(argv: &mut Vec<String>, name: &str, values: impl IntoIterator<Item = impl AsRef<str>>) {
    for v in values {
        argv.push(format!("--{name}"));
        argv.push(v.as_ref().to_string());
    }
}

impl Default for Execution {
    /// What a command line without these flags gives conformance.
    fn default() -> Execution {
        Execution {
            jobs: None,
            timeout: Seconds(300),
            mesa: None,
            max_memory: None,
            judge_cache: None,
            spec_only: false,
        }
    }
}

impl Selection {
    /// These flags as a command line, for a child umbra (drivers' and bisection's
    /// conformance runs).
    pub fn argv(&self) -> Vec<String> {
        let mut argv = Vec::new();
        push(&mut argv, "filter", &self.filter);
        push(&mut argv, "cases", [self.cases.to_string_lossy()]);
        push(
            &mut argv,
            "expectations",
            [self.expectations.to_string_lossy()],
        );
        push(&mut argv, "backend", &self.backend);
        argv
    }
}

/// `umbra selftest [MODE]`: which of the self-test's questions to ask.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SelftestMode {
    /// Inject each known fault into each backend and check that the judge catches it.
    #[default]
    Faults,
    /// The smallest error of each continuous mistake each backend's judge catches.
    Thresholds,
    /// The face/orientation table, drawn by the reference.
    Orientations,
    /// Each behaviour-card entry against a fault that moves its choice.
    Cards,
}

impl SelftestArgs {
    /// The mode asked for: the positional `MODE`, or the older spellings `--thresholds` and
    /// `--orientations` (kept so that scripts written for them still work).
    pub fn mode(&self) -> SelftestMode {
        match (self.mode, self.thresholds, self.orientations) {
            (SelftestMode::Faults, true, _) => SelftestMode::Thresholds,
            (SelftestMode::Faults, _, true) => SelftestMode::Orientations,
            (m, _, _) => m,
        }
    }
}

/// The parser as clap builds it (for completions and usage lines).
pub fn command() -> clap::Command {
    Cli::command()
}

/// Parses `argv` (program name first) into a [`Command`], or clap's error (which also carries
/// `--help` and `--version`).
pub fn parse(argv: &[String]) -> Result<Command, clap::Error> {
    Cli::try_parse_from(argv).map(|c| c.command)
}

/// The usage line of a command, as clap renders it (for the commands' own errors).
pub fn usage(name: &str) -> String {
    let mut root = command();
    root.build();
    root.find_subcommand_mut(name)
        .map(|c| c.render_usage().to_string())
        .unwrap_or_default()
        .trim_start_matches("Usage: ")
        .to_string()
}

/// A command-line mistake clap could not see (a glob, a size, a backend id): the message,
/// then `command`'s usage line (exit 125).
pub fn usage_error(command: &str, message: impl std::fmt::Display) -> crate::exit::Error {
    crate::exit::Error::new(format!("{message}\nusage: {}", usage(command)))
}

/// Writes the completion script for `shell` to stdout.
pub fn completions(args: &CompletionsArgs) -> crate::exit::Outcome {
    clap_complete::generate(args.shell, &mut command(), "umbra", &mut std::io::stdout());
    Ok(crate::exit::Exit::Pass)
}

#[cfg(test)]
mod tests;
