//! The `umbra` command line, parsed by clap: one table of flags ([`FLAGS`]), each with its
//! help written once (`--mesa` means the same on every command that takes it), and one table of
//! commands ([`COMMANDS`]) naming the flags each takes. From them clap builds the parser, the
//! `--help` of every subcommand, the errors (which name the flag and suggest the near miss)
//! and the shell completions (`umbra completions bash`).
//!
//! A parsed command line becomes an [`Args`] (flag name → values), which the command reads;
//! the commands validate what clap cannot (a glob, a backend id, a size), with errors that
//! name the flag and the fix.
//!
//! Exit codes: a command line clap refuses exits 125 ("could not run", as every other
//! set-up error), so `git bisect run cargo xtask conformance …` skips instead of marking a
//! commit bad; `--help` and `--version` exit 0.

use clap::{Arg, ArgAction, Command};

pub use crate::args::Args;

/// One flag: `--name VALUE` (or a switch when `value` is `None`).
pub struct Flag {
    /// Long name, without dashes; also the key commands read it by.
    pub name: &'static str,
    /// Short form, if any.
    pub short: Option<char>,
    /// The value's placeholder in help (`None`: a switch).
    pub value: Option<&'static str>,
    /// May be given more than once.
    pub repeat: bool,
    /// One line of help.
    pub help: &'static str,
}

const fn valued(name: &'static str, value: &'static str, help: &'static str) -> Flag {
    Flag {
        name,
        short: None,
        value: Some(value),
        repeat: false,
        help,
    }
}

const fn repeated(name: &'static str, value: &'static str, help: &'static str) -> Flag {
    Flag {
        name,
        short: None,
        value: Some(value),
        repeat: true,
        help,
    }
}

const fn switch(name: &'static str, help: &'static str) -> Flag {
    Flag {
        name,
        short: None,
        value: None,
        repeat: false,
        help,
    }
}

/// Every flag of every command.
pub const FLAGS: &[Flag] = &[
    repeated(
        "backend",
        "ID",
        "backend id: ref, gl33|gles3|gles2/llvmpipe|softpipe|zink, wgpu-vk/lavapipe, wgpu-gl/llvmpipe, a device of this machine (gl33/radeonsi, gl33/nvidia, wgpu-vk/radv …: `umbra backends` lists them), and, where a command takes several, the aliases hw (every hardware device) and all (this build's ids and every hardware device) (repeatable; default: this build's ids, `ref` for render)",
    ),
    valued(
        "cases",
        "DIR",
        "directory of case files (*.json) [default: cases]",
    ),
    valued(
        "filter",
        "GLOB",
        "run only case points whose id or run name (backend/case@point) matches [default: *]",
    ),
    valued(
        "expectations",
        "DIR",
        "directory of expectation files (expectations/*.txt) [default: expectations]",
    ),
    valued(
        "golden",
        "DIR|none",
        "golden image directory, or `none` to skip golden checks [default: golden]",
    ),
    Flag {
        name: "out",
        short: Some('o'),
        value: Some("PATH"),
        repeat: false,
        help: "where to write results (a directory; for reduce, the reduced case file)",
    },
    valued(
        "shard",
        "I/N",
        "run shard I of N (0 ≤ I < N), for CI jobs or machines: every N-th planned run from I, or split by --durations; `umbra merge` puts the shards back together",
    ),
    valued(
        "durations",
        "results.csv",
        "with --shard: split the plan by a previous run's durations (its results.csv), longest runs first to the least loaded shard; prints the predicted imbalance",
    ),
    valued(
        "jobs",
        "N",
        "worker processes at once [default: available cores]",
    ),
    valued(
        "timeout",
        "SECS",
        "per-run time limit; a run past it is killed and reported as Timeout [default: 300]",
    ),
    valued(
        "mesa",
        "PREFIX|BUILD_DIR|system",
        "Mesa to run on: an install prefix, a meson build directory, unpacked Debian packages (cargo xtask fetch-mesa), or `system` [env: UMBRA_MESA]",
    ),
    valued(
        "max-memory",
        "SIZE",
        "memory budget per worker, e.g. 4GiB or 512MiB; runs estimated above it are refused and workers above it are stopped [env: UMBRA_MAX_MEMORY; default: half of MemAvailable / jobs]",
    ),
    valued(
        "judge-cache",
        "DIR",
        "where the judging basis (truth, reference) is cached, per build of umbra, for the next run [default: OUT/cache/judge, target/umbra/cache/judge for selftest and sweep]",
    ),
    switch(
        "verbose",
        "print every run's details, not just the ones that need a look",
    ),
    switch(
        "bless",
        "accept every changed or new golden (what `cargo xtask bless` runs; refused under CI=true); review with `git diff golden/` before committing",
    ),
    valued(
        "point",
        "GLOB",
        "case point id (or glob over the ids) within the case file",
    ),
    repeated(
        "fault",
        "NAME",
        "inject only this fault (repeatable; default: every fault in Fault::ALL): a named fault, face<0-5>-<orientation> or map-<orientation> (rot90, rot180, rot270, mirror-x, mirror-y, transpose, anti-transpose), or PARAM@E, a parameter off by E (relative, or texels for a shift), e.g. offset-units@-0.05",
    ),
    valued(
        "scene",
        "CASE.json",
        "the case whose scene the technique matrix is measured on",
    ),
    valued(
        "repeat",
        "N",
        "timed renders per point after one warm-up (median reported) [default: 5]",
    ),
    valued(
        "baseline",
        "PREFIX|system",
        "the Mesa build compared against (see --mesa for the forms)",
    ),
    valued(
        "candidate",
        "PREFIX|system",
        "the Mesa build under test (see --mesa for the forms)",
    ),
    valued(
        "pictures",
        "N",
        "at most N changed points get baseline | candidate | reference pictures [default: 200]",
    ),
    valued("mesa-src", "DIR", "a Mesa git work tree (clean)"),
    valued("good", "REV", "a commit known to pass"),
    valued("bad", "REV", "a commit known to fail"),
    valued(
        "work",
        "DIR",
        "working directory for builds, prefixes, logs and steps.csv [default: target/umbra/bisect]",
    ),
    valued(
        "build-script",
        "PATH",
        "script run as `SCRIPT SRC PREFIX` instead of meson + ninja to build and install a commit",
    ),
    repeated(
        "meson-option",
        "OPT",
        "extra `-Dkey=value` for meson setup (repeatable)",
    ),
    switch(
        "no-check-ends",
        "do not test --good and --bad before bisecting",
    ),
    repeated(
        "check",
        "CHECK",
        "keep failing this check while reducing (value, nan, coverage, colour, map, interior, golden, falls-along, memory, render and twin:NAME; repeatable) [default: a subset of the failed checks]",
    ),
    valued("src", "DIR", "Mesa source tree at the commit to test"),
    valued(
        "explain",
        "X,Y",
        "print the judged lookup of the pixel at X,Y (top-left origin) step by step: point, face, coordinate, reference value, every tap's stored range",
    ),
    valued(
        "seed",
        "S",
        "seed of the generated cases: the same seed gives the same cases everywhere [default: 1]",
    ),
    switch(
        "thresholds",
        "selftest: instead of the faults, sweep the magnitude of each continuous mistake (polygon offset, shader biases, normal offset, lookup and shadow-pass shifts, filter weights) per backend family and report the smallest error the catalogue catches, and which point catches it",
    ),
    switch(
        "orientations",
        "selftest: instead of the faults on the backends, the face/orientation table: every cube face and the 2D map drawn with each of the seven wrong orientations by the reference, and the catalogue points that catch each",
    ),
    switch("json", "print JSON for scripts instead of text"),
    switch(
        "ids",
        "backends: print only this machine's device ids, one JSON object per line (what --backend hw and all expand to)",
    ),
    valued(
        "case",
        "CASE.json",
        "the case file holding the run's point [default: found under --cases]",
    ),
    valued(
        "control",
        "ID",
        "a conforming backend the repro must pass on [default: the run's API on llvmpipe]",
    ),
    valued(
        "repro",
        "DIR",
        "write the `umbra repro` bundle of the first bad commit's first failed run into DIR",
    ),
    valued(
        "bisect-log",
        "FILE",
        "a bisection's log, carried into issue.md with its first bad commit",
    ),
    valued(
        "first-bad",
        "COMMIT",
        "the first bad commit a bisection found (for issue.md's \"regression?\")",
    ),
    switch(
        "emit",
        "internal: write the bundle's program and pictures for an already reduced case (in the driver's process)",
    ),
    valued(
        "count",
        "N",
        "how many cases to generate (case K of a seed is the same in every count) [default: 100]",
    ),
];

/// One command: its name, one line of help, its positional argument and its flags (those in
/// `required` must be given).
pub struct Spec {
    /// Subcommand name.
    pub name: &'static str,
    /// One line of help.
    pub about: &'static str,
    /// Positional argument (placeholder, help), required when present.
    pub positional: Option<(&'static str, &'static str)>,
    /// Flags it takes, by name.
    pub flags: &'static [&'static str],
    /// Flags it needs.
    pub required: &'static [&'static str],
    /// Internal (spawned by umbra itself): not listed in help.
    pub hidden: bool,
}

/// Every command.
pub const COMMANDS: &[Spec] = &[
    Spec {
        name: "render",
        about: "Render one case on one backend and write its pictures (colour, visibility, truth, error heat map, shadow map) and figures (exit 0 every point within the specs, 1 a point fails, 125 could not run: a missing or invalid case, an unknown backend, a --point that matches nothing)",
        positional: Some(("CASE.json", "the case file")),
        flags: &["backend", "out", "point", "mesa", "max-memory", "explain"],
        required: &[],
        hidden: false,
    },
    Spec {
        name: "conformance",
        about: "Run every case point on every backend, judge them, and write results.csv, failures.csv, junit.xml, report.json and report.html (exit 0 as expected, 1 regressions, 125 could not run)",
        positional: None,
        flags: &[
            "cases",
            "filter",
            "backend",
            "shard",
            "durations",
            "jobs",
            "timeout",
            "expectations",
            "golden",
            "out",
            "mesa",
            "max-memory",
            "judge-cache",
            "verbose",
            "bless",
        ],
        required: &[],
        hidden: false,
    },
    Spec {
        name: "merge",
        about: "Merge the results of conformance shards (--shard I/N, on N jobs or machines) into one run: results.csv, failures.csv, junit.xml, report.json and report.html, judged across runs again as one unsharded run; refuses shards of different builds, inputs or overlapping runs, and names a missing shard (exit 0 as expected, 1 regressions, 125 could not merge)",
        positional: Some((
            "DIR...",
            "each shard's --out directory (or its runs/ID directory)",
        )),
        flags: &["out"],
        required: &["out"],
        hidden: false,
    },
    Spec {
        name: "selftest",
        about: "Inject each known fault into each backend's shaders and check that the judge catches it (exit 1 when a fault goes unseen); with --seed/--count, the catch rate on generated cases",
        positional: None,
        flags: &[
            "backend",
            "fault",
            "cases",
            "orientations",
            "thresholds",
            "seed",
            "count",
            "out",
            "expectations",
            "timeout",
            "jobs",
            "mesa",
            "max-memory",
            "judge-cache",
            "verbose",
        ],
        required: &[],
        hidden: false,
    },
    Spec {
        name: "soak",
        about: "Generate N valid cases from a seed and run them on every backend with the judge alone: runs, passes, skips, diagnosed deviations and failures by class per backend (exit 1 on any failure)",
        positional: None,
        flags: &[
            "seed",
            "count",
            "backend",
            "filter",
            "jobs",
            "timeout",
            "expectations",
            "out",
            "mesa",
            "max-memory",
            "judge-cache",
            "verbose",
        ],
        required: &[],
        hidden: false,
    },
    Spec {
        name: "sweep",
        about: "Measure speed against error over a technique matrix per backend: sweep.csv, a Pareto plot (SVG, PNG) and an HTML section (exit 125 when it cannot run: an unknown backend, a missing case or point, a bad value)",
        positional: None,
        flags: &[
            "scene",
            "point",
            "backend",
            "repeat",
            "timeout",
            "out",
            "mesa",
            "max-memory",
            "judge-cache",
        ],
        required: &[],
        hidden: false,
    },
    Spec {
        name: "drivers",
        about: "Run the catalogue on two Mesa builds and report every changed point: regressions, fixes, changed pictures (exit 1 on a regression)",
        positional: None,
        flags: &[
            "baseline",
            "candidate",
            "filter",
            "backend",
            "cases",
            "expectations",
            "out",
            "pictures",
            "jobs",
            "timeout",
        ],
        required: &["baseline", "candidate"],
        hidden: false,
    },
    Spec {
        name: "bisect",
        about: "Find the first Mesa commit that breaks the chosen case points: build, install and test each step with git bisect",
        positional: None,
        flags: &[
            "mesa-src",
            "good",
            "bad",
            "filter",
            "backend",
            "work",
            "build-script",
            "meson-option",
            "cases",
            "expectations",
            "no-check-ends",
            "repro",
        ],
        required: &["mesa-src", "good", "bad"],
        hidden: false,
    },
    Spec {
        name: "reduce",
        about: "Shrink a failing case point to a minimal case that still fails the same way on the backend, for a bug report",
        positional: Some(("CASE.json", "the case file")),
        flags: &[
            "point", "backend", "check", "out", "timeout", "mesa", "verbose",
        ],
        required: &["point", "backend"],
        hidden: false,
    },
    Spec {
        name: "repro",
        about: "Turn a failing run (backend/case@point, as conformance names it) into a bug report a driver developer can use without umbra: a reduced case, a standalone C program (repro.c) with the judge's intervals as probes, an API capture, issue.md and pictures",
        positional: Some(("RUN", "the failing run, backend/case@point")),
        flags: &[
            "out",
            "cases",
            "case",
            "control",
            "mesa",
            "timeout",
            "check",
            "bisect-log",
            "first-bad",
            "expectations",
            "backend",
            "emit",
        ],
        required: &["out"],
        hidden: false,
    },
    Spec {
        name: "backends",
        about: "List what this machine can run: every backend id with its driver's strings and how it is reached, every EGL device with the contexts it makes, every wgpu adapter (--json for scripts)",
        positional: None,
        flags: &["json", "ids", "mesa"],
        required: &[],
        hidden: false,
    },
    Spec {
        name: "worker",
        about: "One backend's worker process, speaking JSON lines on stdin/stdout (spawned by umbra)",
        positional: None,
        flags: &["backend"],
        required: &["backend"],
        hidden: true,
    },
    Spec {
        name: "bisect-step",
        about: "One bisection step at the source tree's HEAD: build, install, test (spawned by git bisect run)",
        positional: None,
        flags: &[
            "src",
            "work",
            "filter",
            "build-script",
            "cases",
            "expectations",
            "backend",
        ],
        required: &["src", "work"],
        hidden: true,
    },
];

fn flag(name: &str) -> &'static Flag {
    FLAGS
        .iter()
        .find(|f| f.name == name)
        .unwrap_or_else(|| panic!("cli: command table names unknown flag --{name}"))
}

/// The whole parser: every command, and `completions SHELL`.
pub fn command() -> Command {
    let mut root = Command::new("umbra")
        .about("A regression and conformance harness for shadow mapping on Mesa's GL and Vulkan drivers")
        .version(env!("CARGO_PKG_VERSION"))
        .subcommand_required(true)
        .arg_required_else_help(true)
        .after_help("Exit codes: 0 as expected, 1 regressions (or a fault unseen, a first bad commit not found), 125 could not run.");
    for spec in COMMANDS {
        let mut c = Command::new(spec.name).about(spec.about).hide(spec.hidden);
        if let Some((value, help)) = spec.positional {
            // `NAME...`: one or more.
            let many = value.strip_suffix("...");
            let mut a = Arg::new("positional")
                .value_name(many.unwrap_or(value))
                .help(help)
                .required(true);
            if many.is_some() {
                a = a.num_args(1..).action(ArgAction::Append);
            }
            c = c.arg(a);
        }
        for name in spec.flags {
            let f = flag(name);
            let mut a = Arg::new(f.name).long(f.name).help(f.help);
            if let Some(s) = f.short {
                a = a.short(s);
            }
            a = match (f.value, f.repeat) {
                (None, _) => a.action(ArgAction::SetTrue),
                (Some(v), true) => a.value_name(v).action(ArgAction::Append),
                (Some(v), false) => a.value_name(v).action(ArgAction::Set),
            };
            if spec.required.contains(name) {
                a = a.required(true);
            }
            c = c.arg(a);
        }
        root = root.subcommand(c);
    }
    root.subcommand(
        Command::new("completions")
            .about("Print a shell completion script (e.g. `umbra completions bash > /etc/bash_completion.d/umbra`)")
            .arg(
                Arg::new("shell")
                    .value_name("SHELL")
                    .required(true)
                    .value_parser(clap::value_parser!(clap_complete::Shell)),
            ),
    )
}

/// Parses `argv` (program name first): the command's name and its arguments, or clap's error
/// (which also carries `--help` and `--version`).
pub fn parse(argv: &[String]) -> Result<(String, Args), clap::Error> {
    let m = command().try_get_matches_from(argv)?;
    let (name, sub) = m.subcommand().ok_or_else(|| {
        command().error(
            clap::error::ErrorKind::MissingSubcommand,
            "no command given",
        )
    })?;
    let mut args = Args::default();
    if name == "completions" {
        if let Some(shell) = sub.get_one::<clap_complete::Shell>("shell") {
            args.positional.push(shell.to_string());
        }
        return Ok((name.to_string(), args));
    }
    let spec = COMMANDS
        .iter()
        .find(|s| s.name == name)
        .ok_or_else(|| command().error(clap::error::ErrorKind::InvalidSubcommand, name))?;
    if spec.positional.is_some() {
        args.positional.extend(
            sub.get_many::<String>("positional")
                .into_iter()
                .flatten()
                .cloned(),
        );
    }
    for f in spec.flags.iter().map(|n| flag(n)) {
        if f.value.is_none() {
            if sub.get_flag(f.name) {
                args.set(f.name, String::new());
            }
        } else {
            for v in sub.get_many::<String>(f.name).into_iter().flatten() {
                args.set(f.name, v.clone());
            }
        }
    }
    Ok((name.to_string(), args))
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

/// Writes the completion script for `shell` to stdout.
pub fn completions(shell: &str) -> i32 {
    match shell.parse::<clap_complete::Shell>() {
        Ok(s) => {
            clap_complete::generate(s, &mut command(), "umbra", &mut std::io::stdout());
            0
        }
        Err(e) => {
            eprintln!("error: completions: {e}");
            125
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_agree_with_clap() {
        command().debug_assert();
        for spec in COMMANDS {
            for name in spec.required {
                assert!(spec.flags.contains(name), "{}: --{name}", spec.name);
            }
        }
    }

    /// `--check`'s help names every check the judge has (it once left out `nan`).
    #[test]
    fn check_help_names_every_check() {
        let help = FLAGS
            .iter()
            .find(|f| f.name == "check")
            .map(|f| f.help)
            .unwrap_or_default();
        for c in umbra_report::check::FIXED {
            assert!(help.contains(&c.name()), "--check's help lacks {c}");
        }
        assert!(help.contains("twin:NAME"));
    }

    #[test]
    fn flags_reach_the_command_by_name() {
        let argv: Vec<String> = ["umbra", "render", "c.json", "-o", "x", "--backend", "ref"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let (name, a) = parse(&argv).expect("parses");
        assert_eq!(name, "render");
        assert_eq!(a.positional, ["c.json"]);
        assert_eq!(a.value("out"), Some("x"));
        assert_eq!(a.values("backend"), ["ref"]);
    }

    #[test]
    fn an_unknown_flag_is_named() {
        let argv: Vec<String> = ["umbra", "conformance", "--filtre", "x"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let e = parse(&argv).expect_err("unknown flag").to_string();
        assert!(e.contains("--filtre") && e.contains("--filter"), "{e}");
    }
}
