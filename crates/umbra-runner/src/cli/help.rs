//! Each flag's one line of help, shared by every command that takes the flag. A default is
//! not written here: clap writes `[default: …]` from the flag's declaration (`cli/mod.rs`),
//! so the help cannot say another default than the command uses.

/// `--backend` of a command that runs one backend (render).
pub const BACKEND_ONE: &str = "the one backend to run (once): ref, gl33|gles3|gles2/llvmpipe|softpipe|zink, wgpu-vk/lavapipe, wgpu-gl/llvmpipe, or a device of this machine (`umbra backends` lists them) [default: ref]";
/// `--backend`.
pub const BACKEND: &str = "backend id: ref, gl33|gles3|gles2/llvmpipe|softpipe|zink, wgpu-vk/lavapipe, wgpu-gl/llvmpipe, a device of this machine (gl33/radeonsi, gl33/nvidia, wgpu-vk/radv …: `umbra backends` lists them), and, where a command takes several, the aliases hw (every hardware device) and all (this build's ids and every hardware device) (repeatable; default: this build's ids)";
/// `--cases`.
pub const CASES: &str = "directory of case files (*.json)";
/// `--cases` (selftest, where it is one of two ways to choose the cases).
pub const SELFTEST_CASES: &str =
    "directory of case files (*.json); not with --seed/--count [default: cases]";
/// `--filter`.
pub const FILTER: &str =
    "run only case points whose id or run name (backend/case@point) matches [default: *]";
/// `--expectations`.
pub const EXPECTATIONS: &str = "directory of expectation files (expectations/*.txt)";
/// `--golden`.
pub const GOLDEN: &str = "golden image directory, or `none` to skip golden checks";
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
    "per-run time limit in seconds; a run past it is killed and reported as Timeout";
/// `--timeout` handed to a conformance run (drivers' sides).
pub const TIMEOUT_CONFORMANCE: &str = "per-run time limit in seconds of each side's conformance run; a run past it is killed and reported as Timeout [default: conformance's]";
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
pub const REPEAT: &str = "timed renders per point after one warm-up (median reported)";
/// `--baseline`.
pub const BASELINE: &str = "the Mesa build compared against (see --mesa for the forms)";
/// `--candidate`.
pub const CANDIDATE: &str = "the Mesa build under test (see --mesa for the forms)";
/// `--pictures`.
pub const PICTURES: &str = "at most N changed points get baseline | candidate | reference pictures";
/// `--mesa-src`.
pub const MESA_SRC: &str = "a Mesa git work tree (clean)";
/// `--good`.
pub const GOOD: &str = "a commit known to pass";
/// `--bad`.
pub const BAD: &str = "a commit known to fail";
/// `--work`.
pub const WORK: &str = "working directory for builds, prefixes, logs and steps.csv";
/// `--build-script`.
pub const BUILD_SCRIPT: &str = "script run as `SCRIPT SRC PREFIX OPTIONS...` (the commit's derived meson options) instead of meson + ninja to build and install a commit";
/// `--meson-option`.
pub const MESON_OPTION: &str = "extra `-Dkey=value` for meson setup, after the options derived from each commit's meson.options, and checked against them (repeatable)";
/// `--configure-only`.
pub const CONFIGURE_ONLY: &str = "derive the meson options of --good and --bad from their meson.options, check them and the meson version (bringing a newer meson with pip when the tree asks), configure, and stop: run it first on your tree";
/// `--no-check-ends`.
pub const NO_CHECK_ENDS: &str = "do not test --good and --bad before bisecting";
/// `--check`.
pub const CHECK: &str = "keep failing this check while reducing (value, nan, coverage, colour, map, interior, golden, falls-along, memory, render, card (a backend's behaviour card, which no case point fails) and twin:NAME; repeatable) [default: a subset of the failed checks]";
/// `--src`.
pub const SRC: &str = "Mesa source tree at the commit to test";
/// `--explain`.
pub const EXPLAIN: &str = "print the judged lookup of the pixel at X,Y (top-left origin) step by step: point, face, coordinate, reference value, every tap's stored range";
/// `--seed`.
pub const SEED: &str = "seed of the generated cases: the same seed gives the same cases everywhere";
/// `--seed` of the self-test.
pub const SELFTEST_SEED: &str = "run the faults on generated cases of this seed instead of the catalogue (1 when only --count is given)";
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
pub const CARD_TIMEOUT: &str = "time limit of one backend's probes, in seconds";
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
pub const BISECT_LOG: &str = "a bisection's log, carried into issue.md with its first bad commit";
/// `--first-bad`.
pub const FIRST_BAD: &str =
    "the first bad commit a bisection found (for issue.md's \"regression?\")";
/// `--emit`.
pub const EMIT: &str = "internal: write the bundle's program and pictures for an already reduced case (in the driver's process)";
/// `--count`.
pub const COUNT: &str = "how many cases to generate (case K of a seed is the same in every count)";
/// `--count` of the self-test.
pub const SELFTEST_COUNT: &str = "run the faults on this many generated cases instead of the catalogue (20 when only --seed is given)";
/// `selftest --catches`.
pub const CATCHES_OUT: &str = "write the catch matrix (each fault × backend pair and the case points that caught it) to FILE: what `umbra tier` chooses from";
/// `selftest --tier`.
pub const TIER_SELFTEST: &str =
    "hunt each fault with the tier's runs only, every one of them run: what the tier catches";
/// `conformance --tier`.
pub const TIER: &str = "run only the runs of this tier file (`umbra tier` writes one); the file is kept in the run directory";
/// `conformance --budget`, `tier --budget`.
pub const BUDGET: &str = "choose the runs for this much wall time (90s, 5m, premerge = 5m, smoke = 1m) by what they catch: every fault × backend pair the catalogue catches first, then more catches per pair (from tiers/catches.json and tiers/durations.csv)";
/// `tier --catches`.
pub const CATCHES_IN: &str =
    "the self-test's catch matrix (`umbra selftest --catches FILE` writes one)";
/// `tier --durations`.
pub const TIER_DURATIONS: &str = "a full conformance run's results.csv: each run's duration";
/// `tier --jobs`.
pub const TIER_JOBS: &str =
    "the worker processes the expected wall time assumes (the CI machine kind has 2 cores)";
/// `tier --random`.
pub const RANDOM: &str = "draw a random tier of the same expected time with this seed instead (deqp-runner's --fraction, sized to the budget's choice): the comparison";
