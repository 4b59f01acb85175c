//! The `umbra` command line as types: one [`Command`] enum, one options struct per command,
//! and the flag groups several commands share ([`Selection`], [`Execution`], [`Output`])
//! flattened into each, so a flag is declared, and its help written ([`help`]), once. clap
//! derives from them the parser, the `--help` of every subcommand, the errors (which name the
//! flag and suggest the near miss) and the shell completions (`umbra completions bash`).
//!
//! The structs hold what was typed (a glob, a backend id, a size stay strings here): each
//! command validates what clap cannot, with errors that name the flag and the fix.
//!
//! Exit codes ([`crate::exit::Exit`]): a command line clap refuses exits 125 ("could not
//! run", as every other set-up error), so `git bisect run cargo xtask conformance …` skips
//! instead of marking a commit bad; `--help` and `--version` exit 0.

use clap::{Args, CommandFactory, Parser, Subcommand, ValueEnum};

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

/// Each flag's one line of help, shared by every command that takes the flag.
pub mod help {
    /// `--backend` of a command that runs one backend (render).
    pub const BACKEND_ONE: &str = "the one backend to run (once): ref, gl33|gles3|gles2/llvmpipe|softpipe|zink, wgpu-vk/lavapipe, wgpu-gl/llvmpipe, or a device of this machine (`umbra backends` lists them) [default: ref]";
    /// `--backend`.
    pub const BACKEND: &str = "backend id: ref, gl33|gles3|gles2/llvmpipe|softpipe|zink, wgpu-vk/lavapipe, wgpu-gl/llvmpipe, a device of this machine (gl33/radeonsi, gl33/nvidia, wgpu-vk/radv …: `umbra backends` lists them), and, where a command takes several, the aliases hw (every hardware device) and all (this build's ids and every hardware device) (repeatable; default: this build's ids)";
    /// `--cases`.
    pub const CASES: &str = "directory of case files (*.json) [default: cases]";
    /// `--filter`.
    pub const FILTER: &str =
        "run only case points whose id or run name (backend/case@point) matches [default: *]";
    /// `--expectations`.
    pub const EXPECTATIONS: &str =
        "directory of expectation files (expectations/*.txt) [default: expectations]";
    /// `--golden`.
    pub const GOLDEN: &str =
        "golden image directory, or `none` to skip golden checks [default: golden]";
    /// `--out`.
    pub const OUT: &str = "where to write results (a directory; for reduce, the reduced case file)";
    /// `--shard`.
    pub const SHARD: &str = "run shard I of N (0 ≤ I < N), for CI jobs or machines: every N-th planned run from I, or split by --durations; `umbra merge` puts the shards back together";
    /// `--durations`.
    pub const DURATIONS: &str = "with --shard: split the plan by a previous run's durations (its results.csv), longest runs first to the least loaded shard; prints the predicted imbalance";
    /// `--jobs`.
    pub const JOBS: &str = "worker processes at once [default: available cores]";
    /// `--timeout`.
    pub const TIMEOUT: &str =
        "per-run time limit; a run past it is killed and reported as Timeout [default: 300]";
    /// `--mesa`.
    pub const MESA: &str = "Mesa to run on: an install prefix, a meson build directory, unpacked Debian packages (cargo xtask fetch-mesa), or `system` [env: UMBRA_MESA]";
    /// `--max-memory`.
    pub const MAX_MEMORY: &str = "memory budget per worker, e.g. 4GiB or 512MiB; runs estimated above it are refused and workers above it are stopped [env: UMBRA_MAX_MEMORY; default: half of MemAvailable / jobs]";
    /// `--judge-cache`.
    pub const JUDGE_CACHE: &str = "where the judging basis (truth, reference) is cached, per build of umbra, for the next run [default: OUT/cache/judge, target/umbra/cache/judge for selftest and sweep]";
    /// `--verbose`.
    pub const VERBOSE: &str = "print every run's details, not just the ones that need a look";
    /// `--bless`.
    pub const BLESS: &str = "accept every changed or new golden (what `cargo xtask bless` runs; refused under CI=true); review with `git diff golden/` before committing";
    /// `--point`.
    pub const POINT: &str = "case point id (or glob over the ids) within the case file";
    /// `--fault`.
    pub const FAULT: &str = "inject only this fault (repeatable; default: every fault in Fault::ALL): a named fault, face<0-5>-<orientation> or map-<orientation> (rot90, rot180, rot270, mirror-x, mirror-y, transpose, anti-transpose), or PARAM@E, a parameter off by E (relative, or texels for a shift), e.g. offset-units@-0.05";
    /// `--scene`.
    pub const SCENE: &str = "the case whose scene the technique matrix is measured on";
    /// `--repeat`.
    pub const REPEAT: &str =
        "timed renders per point after one warm-up (median reported) [default: 5]";
    /// `--baseline`.
    pub const BASELINE: &str = "the Mesa build compared against (see --mesa for the forms)";
    /// `--candidate`.
    pub const CANDIDATE: &str = "the Mesa build under test (see --mesa for the forms)";
    /// `--pictures`.
    pub const PICTURES: &str =
        "at most N changed points get baseline | candidate | reference pictures [default: 200]";
    /// `--mesa-src`.
    pub const MESA_SRC: &str = "a Mesa git work tree (clean)";
    /// `--good`.
    pub const GOOD: &str = "a commit known to pass";
    /// `--bad`.
    pub const BAD: &str = "a commit known to fail";
    /// `--work`.
    pub const WORK: &str =
        "working directory for builds, prefixes, logs and steps.csv [default: target/umbra/bisect]";
    /// `--build-script`.
    pub const BUILD_SCRIPT: &str =
        "script run as `SCRIPT SRC PREFIX` instead of meson + ninja to build and install a commit";
    /// `--meson-option`.
    pub const MESON_OPTION: &str = "extra `-Dkey=value` for meson setup (repeatable)";
    /// `--no-check-ends`.
    pub const NO_CHECK_ENDS: &str = "do not test --good and --bad before bisecting";
    /// `--check`.
    pub const CHECK: &str = "keep failing this check while reducing (value, nan, coverage, colour, map, interior, golden, falls-along, memory, render, card (a backend's behaviour card, which no case point fails) and twin:NAME; repeatable) [default: a subset of the failed checks]";
    /// `--src`.
    pub const SRC: &str = "Mesa source tree at the commit to test";
    /// `--explain`.
    pub const EXPLAIN: &str = "print the judged lookup of the pixel at X,Y (top-left origin) step by step: point, face, coordinate, reference value, every tap's stored range";
    /// `--seed`.
    pub const SEED: &str =
        "seed of the generated cases: the same seed gives the same cases everywhere [default: 1]";
    /// `--thresholds`.
    pub const THRESHOLDS: &str = "selftest: instead of the faults, sweep the magnitude of each continuous mistake (polygon offset, shader biases, normal offset, lookup and shadow-pass shifts, filter weights) per backend family and report the smallest error the catalogue catches, and which point catches it";
    /// `umbra selftest MODE`.
    pub const MODE: &str = "faults: inject each known fault into each backend and check that the judge catches it; thresholds: instead of the faults, sweep the magnitude of each continuous mistake (polygon offset, shader biases, normal offset, lookup and shadow-pass shifts, filter weights) per backend family and report the smallest error the catalogue catches, and which point catches it; orientations: instead of the faults on the backends, the face/orientation table: every cube face and the 2D map drawn with each of the seven wrong orientations by the reference, and the catalogue points that catch each; cards: each behaviour-card entry against a fault that moves the choice it measures (the card must name it)";
    /// `--orientations`.
    pub const ORIENTATIONS: &str = "selftest: instead of the faults on the backends, the face/orientation table: every cube face and the 2D map drawn with each of the seven wrong orientations by the reference, and the catalogue points that catch each";
    /// `--json`.
    pub const JSON: &str = "print JSON for scripts instead of text";
    /// `--spec-only`.
    pub const SPEC_ONLY: &str = "judge every run by the specs alone: measure no behaviour card to narrow the judgement. By default each backend's card is measured once, before its runs, and every run is judged twice: against the specs (a failure there is a failure) and against the spec's freedom narrowed to what the card read (check `card`: the driver chose differently in the scene than in the probes); report.json and report.html give the blind area under both";
    /// `--diff` (card).
    pub const CARD_DIFF: &str = "compare two stored cards (card-RELEASE.json files, e.g. golden/gl33_zink/card-mesa-22.3.6.json and …-26.2.6.json) and name every entry that changed, old and new value and the spec, instead of measuring";
    /// `--card` (bisect).
    pub const BISECT_CARD: &str = "bisect a behaviour: a commit is good when every selected backend's card entry KEY has VALUE (e.g. 'offset-unit.depth16.z0.375=4 codes', as `umbra card` or `cargo xtask drivers` names it), instead of when the chosen cases pass";
    /// `--keep` (card).
    pub const CARD_KEEP: &str = "keep each measured card as its backend's baseline for this driver release in golden directory DIR (DIR/<backend>/card-<release>.json), as `cargo xtask bless` does; refused under CI=true";
    /// `--timeout` (card).
    pub const CARD_TIMEOUT: &str = "time limit of one backend's probes, in seconds [default: 300]";
    /// `--ids`.
    pub const IDS: &str = "backends: print only this machine's device ids, one JSON object per line (what --backend hw and all expand to)";
    /// `--case`.
    pub const CASE: &str = "the case file holding the run's point [default: found under --cases]";
    /// `--control`.
    pub const CONTROL: &str =
        "a conforming backend the repro must pass on [default: the run's API on llvmpipe]";
    /// `--repro`.
    pub const REPRO: &str =
        "write the `umbra repro` bundle of the first bad commit's first failed run into DIR";
    /// `--bisect-log`.
    pub const BISECT_LOG: &str =
        "a bisection's log, carried into issue.md with its first bad commit";
    /// `--first-bad`.
    pub const FIRST_BAD: &str =
        "the first bad commit a bisection found (for issue.md's \"regression?\")";
    /// `--emit`.
    pub const EMIT: &str = "internal: write the bundle's program and pictures for an already reduced case (in the driver's process)";
    /// `--count`.
    pub const COUNT: &str =
        "how many cases to generate (case K of a seed is the same in every count) [default: 100]";
}

/// What to run: the backends, the case points, the catalogue and its expectations (conformance, drivers, bisect).
#[derive(Args, Debug, Clone, Default)]
pub struct Selection {
    /// `--cases`: the directory of case files.
    #[arg(long, value_name = "DIR", help = help::CASES)]
    pub cases: Option<String>,
    /// `--filter`: the glob over case points and run names.
    #[arg(long, value_name = "GLOB", help = help::FILTER)]
    pub filter: Option<String>,
    /// `--backend`: backend ids and aliases, as given.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<String>,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS)]
    pub expectations: Option<String>,
}
/// How runs execute: workers, time and memory limits, the Mesa build, the judging cache (conformance, selftest, soak).
#[derive(Args, Debug, Clone, Default)]
pub struct Execution {
    /// `--jobs`: worker processes at once.
    #[arg(long, value_name = "N", help = help::JOBS)]
    pub jobs: Option<String>,
    /// `--timeout`: per-run time limit, in seconds.
    #[arg(long, value_name = "SECS", help = help::TIMEOUT)]
    pub timeout: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<String>,
    /// `--max-memory`: the memory budget per worker.
    #[arg(long, value_name = "SIZE", help = help::MAX_MEMORY)]
    pub max_memory: Option<String>,
    /// `--judge-cache`: where the judging basis is cached.
    #[arg(long, value_name = "DIR", help = help::JUDGE_CACHE)]
    pub judge_cache: Option<String>,
    /// `--spec-only`: no calibrated judging.
    #[arg(long, help = help::SPEC_ONLY)]
    pub spec_only: bool,
}
/// Where results go and how much is printed (conformance, selftest, soak, reduce).
#[derive(Args, Debug, Clone, Default)]
pub struct Output {
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: Option<String>,
    /// `--verbose`: every run's details.
    #[arg(long, help = help::VERBOSE)]
    pub verbose: bool,
}

/// `umbra render`.
#[derive(Args, Debug, Clone, Default)]
pub struct RenderArgs {
    /// The positional argument.
    #[arg(value_name = "CASE.json", help = "the case file")]
    pub positional: String,
    /// `--backend`: the one backend render runs; given twice, refused by clap (a `Vec` here
    /// once took the last without a word).
    #[arg(long, value_name = "ID", help = help::BACKEND_ONE)]
    pub backend: Option<String>,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: Option<String>,
    /// `--point`.
    #[arg(long, value_name = "GLOB", help = help::POINT)]
    pub point: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<String>,
    /// `--max-memory`: the memory budget per worker.
    #[arg(long, value_name = "SIZE", help = help::MAX_MEMORY)]
    pub max_memory: Option<String>,
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
    pub shard: Option<String>,
    /// `--durations`.
    #[arg(long, value_name = "results.csv", help = help::DURATIONS)]
    pub durations: Option<String>,
    /// Execution flags.
    #[command(flatten)]
    pub execution: Execution,
    /// `--golden`.
    #[arg(long, value_name = "DIR|none", help = help::GOLDEN)]
    pub golden: Option<String>,
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
    pub dirs: Vec<String>,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: String,
}

/// `umbra selftest`.
#[derive(Args, Debug, Clone, Default)]
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
    /// `--backend`: backend ids and aliases, as given.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<String>,
    /// `--fault`.
    #[arg(long, value_name = "NAME", help = help::FAULT)]
    pub fault: Vec<String>,
    /// `--cases`: the directory of case files.
    #[arg(long, value_name = "DIR", help = help::CASES)]
    pub cases: Option<String>,
    /// `--orientations`.
    #[arg(long, hide = true, help = help::ORIENTATIONS)]
    pub orientations: bool,
    /// `--thresholds`.
    #[arg(long, hide = true, help = help::THRESHOLDS)]
    pub thresholds: bool,
    /// `--seed`.
    #[arg(long, value_name = "S", help = help::SEED)]
    pub seed: Option<String>,
    /// `--count`.
    #[arg(long, value_name = "N", help = help::COUNT)]
    pub count: Option<String>,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS)]
    pub expectations: Option<String>,
    /// Execution flags.
    #[command(flatten)]
    pub execution: Execution,
}

/// `umbra soak`.
#[derive(Args, Debug, Clone, Default)]
pub struct SoakArgs {
    /// `--seed`.
    #[arg(long, value_name = "S", help = help::SEED)]
    pub seed: Option<String>,
    /// `--count`.
    #[arg(long, value_name = "N", help = help::COUNT)]
    pub count: Option<String>,
    /// `--backend`: backend ids and aliases, as given.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<String>,
    /// `--filter`: the glob over case points and run names.
    #[arg(long, value_name = "GLOB", help = help::FILTER)]
    pub filter: Option<String>,
    /// Execution flags.
    #[command(flatten)]
    pub execution: Execution,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS)]
    pub expectations: Option<String>,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
}

/// `umbra sweep`.
#[derive(Args, Debug, Clone, Default)]
pub struct SweepArgs {
    /// `--scene`.
    #[arg(long, value_name = "CASE.json", help = help::SCENE)]
    pub scene: Option<String>,
    /// `--point`.
    #[arg(long, value_name = "GLOB", help = help::POINT)]
    pub point: Option<String>,
    /// `--backend`: backend ids and aliases, as given.
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<String>,
    /// `--repeat`.
    #[arg(long, value_name = "N", help = help::REPEAT)]
    pub repeat: Option<String>,
    /// `--timeout`: per-run time limit, in seconds.
    #[arg(long, value_name = "SECS", help = help::TIMEOUT)]
    pub timeout: Option<String>,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<String>,
    /// `--max-memory`: the memory budget per worker.
    #[arg(long, value_name = "SIZE", help = help::MAX_MEMORY)]
    pub max_memory: Option<String>,
    /// `--judge-cache`: where the judging basis is cached.
    #[arg(long, value_name = "DIR", help = help::JUDGE_CACHE)]
    pub judge_cache: Option<String>,
}

/// `umbra drivers`.
#[derive(Args, Debug, Clone, Default)]
pub struct DriversArgs {
    /// `--baseline`.
    #[arg(long, value_name = "PREFIX|system", help = help::BASELINE)]
    pub baseline: String,
    /// `--candidate`.
    #[arg(long, value_name = "PREFIX|system", help = help::CANDIDATE)]
    pub candidate: String,
    /// Selection flags.
    #[command(flatten)]
    pub selection: Selection,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: Option<String>,
    /// `--pictures`.
    #[arg(long, value_name = "N", help = help::PICTURES)]
    pub pictures: Option<String>,
    /// `--jobs`: worker processes at once.
    #[arg(long, value_name = "N", help = help::JOBS)]
    pub jobs: Option<String>,
    /// `--timeout`: per-run time limit, in seconds.
    #[arg(long, value_name = "SECS", help = help::TIMEOUT)]
    pub timeout: Option<String>,
}

/// `umbra bisect`.
#[derive(Args, Debug, Clone, Default)]
pub struct BisectArgs {
    /// `--mesa-src`.
    #[arg(long, value_name = "DIR", help = help::MESA_SRC)]
    pub mesa_src: String,
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
    #[arg(long, value_name = "DIR", help = help::WORK)]
    pub work: Option<String>,
    /// `--build-script`.
    #[arg(long, value_name = "PATH", help = help::BUILD_SCRIPT)]
    pub build_script: Option<String>,
    /// `--meson-option`.
    #[arg(long, value_name = "OPT", help = help::MESON_OPTION)]
    pub meson_option: Vec<String>,
    /// `--no-check-ends`.
    #[arg(long, help = help::NO_CHECK_ENDS)]
    pub no_check_ends: bool,
    /// `--repro`.
    #[arg(long, value_name = "DIR", help = help::REPRO)]
    pub repro: Option<String>,
    /// `--card KEY=VALUE`: bisect a behaviour-card entry instead of case verdicts.
    #[arg(long, value_name = "KEY=VALUE", help = help::BISECT_CARD)]
    pub card: Option<String>,
}

/// `umbra reduce`.
#[derive(Args, Debug, Clone, Default)]
pub struct ReduceArgs {
    /// The positional argument.
    #[arg(value_name = "CASE.json", help = "the case file")]
    pub positional: String,
    /// `--point`.
    #[arg(long, value_name = "GLOB", help = help::POINT)]
    pub point: String,
    /// `--backend`: backend ids and aliases, as given.
    #[arg(long, value_name = "ID", help = help::BACKEND, required = true)]
    pub backend: Vec<String>,
    /// `--check`.
    #[arg(long, value_name = "CHECK", help = help::CHECK)]
    pub check: Vec<String>,
    /// Output flags.
    #[command(flatten)]
    pub output: Output,
    /// `--timeout`: per-run time limit, in seconds.
    #[arg(long, value_name = "SECS", help = help::TIMEOUT)]
    pub timeout: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<String>,
}

/// `umbra repro`.
#[derive(Args, Debug, Clone, Default)]
pub struct ReproArgs {
    /// The positional argument.
    #[arg(value_name = "RUN", help = "the failing run, backend/case@point")]
    pub positional: String,
    /// `--out`: where results go.
    #[arg(short = 'o', long, value_name = "PATH", help = help::OUT)]
    pub out: String,
    /// `--cases`: the directory of case files.
    #[arg(long, value_name = "DIR", help = help::CASES)]
    pub cases: Option<String>,
    /// `--case`.
    #[arg(long, value_name = "CASE.json", help = help::CASE)]
    pub case: Option<String>,
    /// `--control`.
    #[arg(long, value_name = "ID", help = help::CONTROL)]
    pub control: Option<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<String>,
    /// `--timeout`: per-run time limit, in seconds.
    #[arg(long, value_name = "SECS", help = help::TIMEOUT)]
    pub timeout: Option<String>,
    /// `--check`.
    #[arg(long, value_name = "CHECK", help = help::CHECK)]
    pub check: Vec<String>,
    /// `--bisect-log`.
    #[arg(long, value_name = "FILE", help = help::BISECT_LOG)]
    pub bisect_log: Option<String>,
    /// `--first-bad`.
    #[arg(long, value_name = "COMMIT", help = help::FIRST_BAD)]
    pub first_bad: Option<String>,
    /// `--expectations`: the directory of expectation files.
    #[arg(long, value_name = "DIR", help = help::EXPECTATIONS)]
    pub expectations: Option<String>,
    /// `--backend`: the backend of `--emit`'s process (once).
    #[arg(long, value_name = "ID", help = help::BACKEND_ONE)]
    pub backend: Option<String>,
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
    pub mesa: Option<String>,
}

/// `umbra card`.
#[derive(Args, Debug, Clone, Default)]
pub struct CardArgs {
    /// `--backend`: which backends to measure (default: this build's ids).
    #[arg(long, value_name = "ID", help = help::BACKEND)]
    pub backend: Vec<String>,
    /// `--json`.
    #[arg(long, help = help::JSON)]
    pub json: bool,
    /// `--diff OLD NEW`: compare two stored cards instead of measuring.
    #[arg(long, num_args = 2, value_names = ["OLD", "NEW"], help = help::CARD_DIFF)]
    pub diff: Vec<String>,
    /// `--mesa`: the Mesa to run on.
    #[arg(long, value_name = "PREFIX|BUILD_DIR|system", help = help::MESA)]
    pub mesa: Option<String>,
    /// `--timeout`: the time limit of one backend's probes, in seconds.
    #[arg(long, value_name = "SECONDS", help = help::CARD_TIMEOUT)]
    pub timeout: Option<u64>,
    /// `--keep DIR`: keep each card as the reviewed baseline in golden directory DIR.
    #[arg(long, value_name = "DIR", help = help::CARD_KEEP)]
    pub keep: Option<String>,
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
    pub src: String,
    /// `--work`.
    #[arg(long, value_name = "DIR", help = help::WORK)]
    pub work: String,
    /// Selection flags.
    #[command(flatten)]
    pub selection: Selection,
    /// `--build-script`.
    #[arg(long, value_name = "PATH", help = help::BUILD_SCRIPT)]
    pub build_script: Option<String>,
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

impl Selection {
    /// These flags as a command line, for a child umbra (drivers' and bisection's
    /// conformance runs).
    pub fn argv(&self) -> Vec<String> {
        let mut argv = Vec::new();
        push(&mut argv, "filter", &self.filter);
        push(&mut argv, "cases", &self.cases);
        push(&mut argv, "expectations", &self.expectations);
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

/// `--timeout SECS` of `command`: whole seconds, 1 or more, `default` when not given.
pub fn timeout_secs(
    command: &str,
    value: Option<&str>,
    default: u64,
) -> Result<std::time::Duration, crate::exit::Error> {
    match value.map(str::parse::<u64>).transpose() {
        Ok(Some(0)) => Err(usage_error(
            command,
            format!(
                "--timeout 0: no run can finish in no time; give whole seconds, 1 or more (default {default})"
            ),
        )),
        Ok(t) => Ok(std::time::Duration::from_secs(t.unwrap_or(default))),
        Err(_) => Err(usage_error(
            command,
            format!("--timeout takes whole seconds, 1 or more (default {default})"),
        )),
    }
}

/// `--jobs`, `--timeout` and `--max-memory`, read strictly and the budget selected: one
/// reading for every command that runs workers (selftest once ran `--timeout 10s` silently
/// with its default, and a budget below one run's base counted every fault as caught). A
/// value that is not whole and positive is a usage error of `command`.
pub fn limits(
    command: &str,
    execution: &Execution,
    default_timeout: u64,
) -> Result<(usize, std::time::Duration), crate::exit::Error> {
    let jobs = match execution
        .jobs
        .as_deref()
        .map(str::parse::<usize>)
        .transpose()
    {
        Ok(Some(0)) => {
            return Err(usage_error(
                command,
                "--jobs 0: at least one worker must run; give --jobs 1 or more (default: the core count)",
            ));
        }
        Ok(j) => j.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        Err(_) => {
            return Err(usage_error(command, "--jobs takes a positive number"));
        }
    };
    let timeout = timeout_secs(command, execution.timeout.as_deref(), default_timeout)?;
    crate::harness::memory_limit::check_jobs(jobs).map_err(|e| usage_error(command, e))?;
    match crate::harness::memory_limit::select(execution.max_memory.as_deref(), jobs) {
        Ok(b) if b < umbra_case::memory::BASE_BYTES => Err(usage_error(
            command,
            format!(
                "the memory budget per worker, {}, is below one run's base ({}: a worker with its driver, before any case; umbra_case::memory::BASE_BYTES); give --max-memory 1GiB or more, or fewer --jobs",
                umbra_case::memory::gib(b),
                umbra_case::memory::gib(umbra_case::memory::BASE_BYTES)
            ),
        )),
        Ok(_) => Ok((jobs, timeout)),
        Err(e) => Err(usage_error(command, e)),
    }
}

/// Writes the completion script for `shell` to stdout.
pub fn completions(args: &CompletionsArgs) -> crate::exit::Outcome {
    clap_complete::generate(args.shell, &mut command(), "umbra", &mut std::io::stdout());
    Ok(crate::exit::Exit::Pass)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn argv(words: &[&str]) -> Vec<String> {
        words.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn clap_accepts_the_definitions() {
        command().debug_assert();
    }

    /// `--check`'s help names every check the judge has (it once left out `nan`).
    #[test]
    fn check_help_names_every_check() {
        for c in umbra_report::check::FIXED {
            assert!(help::CHECK.contains(&c.name()), "--check's help lacks {c}");
        }
        assert!(help::CHECK.contains("twin:NAME"));
    }

    #[test]
    fn flags_reach_the_command_typed() {
        let c = parse(&argv(&[
            "umbra",
            "render",
            "c.json",
            "-o",
            "x",
            "--backend",
            "ref",
        ]));
        let Ok(Command::Render(a)) = c else {
            panic!("render parses: {c:?}");
        };
        assert_eq!(a.positional, "c.json");
        assert_eq!(a.out.as_deref(), Some("x"));
        assert_eq!(a.backend.as_deref(), Some("ref"));
    }

    #[test]
    fn shared_groups_are_the_same_flags_everywhere() {
        let c = parse(&argv(&[
            "umbra",
            "soak",
            "--jobs",
            "2",
            "--mesa",
            "system",
            "-o",
            "o",
            "--verbose",
        ]));
        let Ok(Command::Soak(a)) = c else {
            panic!("soak parses: {c:?}");
        };
        assert_eq!(a.execution.jobs.as_deref(), Some("2"));
        assert_eq!(a.execution.mesa.as_deref(), Some("system"));
        assert_eq!(a.output.out.as_deref(), Some("o"));
        assert!(a.output.verbose);
    }

    #[test]
    fn selftest_modes_are_named_or_spelt_as_before() {
        for (words, mode) in [
            (&["umbra", "selftest"][..], SelftestMode::Faults),
            (
                &["umbra", "selftest", "thresholds", "--backend", "ref"][..],
                SelftestMode::Thresholds,
            ),
            (
                &["umbra", "selftest", "--orientations"][..],
                SelftestMode::Orientations,
            ),
        ] {
            let Ok(Command::Selftest(a)) = parse(&argv(words)) else {
                panic!("{words:?} parses");
            };
            assert_eq!(a.mode(), mode, "{words:?}");
        }
    }

    #[test]
    fn an_unknown_flag_is_named() {
        let e = parse(&argv(&["umbra", "conformance", "--filtre", "x"]))
            .expect_err("unknown flag")
            .to_string();
        assert!(e.contains("--filtre") && e.contains("--filter"), "{e}");
    }
}
