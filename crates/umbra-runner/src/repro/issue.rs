//! The bundle's words: the header of `repro.c`, `issue.md` in the shape of Mesa's bug template
//! (`.gitlab/issue_templates/Bug Report.md`: description, system information, regression,
//! steps, screenshots, API captures) and `README.md`, the bundle's index.

use std::fmt::Write as _;

use crate::repro::Facts;
use umbra_case::DriverInfo;

use crate::repro::probes::Probes;

/// One run of the compiled program.
#[derive(Clone, Debug)]
pub struct ProgramRun {
    /// The backend (driver) it ran on.
    pub backend: String,
    /// The environment that chose it, as shell text.
    pub env: String,
    /// Exit code (None: killed or not started).
    pub code: Option<i32>,
    /// stdout and stderr.
    pub output: String,
}

/// A capture's replay on one driver.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The backend it replayed on.
    pub backend: String,
    /// The command, as shell text.
    pub command: String,
    /// What came of it (a snapshot written, or why not).
    pub outcome: String,
}

/// Everything the parent measured, beside the driver-side facts.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The run as conformance names it.
    pub run: String,
    /// Where its point came from.
    pub case_file: String,
    /// The point id.
    pub point: String,
    /// The reducer's summary line (before → after).
    pub reduced: String,
    /// umbra's diagnosis, when an expectation names this run.
    pub diagnosis: Option<String>,
    /// The Mesa build the run used (`--mesa`), described.
    pub mesa_build: Option<String>,
    /// Program runs: the driver's first, then the control.
    pub runs: Vec<ProgramRun>,
    /// Why no program was built or run, when so.
    pub no_program: Option<String>,
    /// The capture file's name and how it was made, or why there is none.
    pub capture: Result<String, String>,
    /// Replays of the capture.
    pub replays: Vec<Replay>,
    /// First bad commit, and the bisection's log (its text) when one was given.
    pub bisect: Option<(String, Option<String>)>,
    /// The command that made this bundle.
    pub command: String,
    /// Whether the program reproduces, in one sentence.
    pub verdict: String,
}

impl Measured {
    /// Nothing measured yet.
    pub fn new(run: String, case_file: String, point: String) -> Measured {
        Measured {
            run,
            case_file,
            point,
            reduced: String::new(),
            diagnosis: None,
            mesa_build: None,
            runs: Vec::new(),
            no_program: None,
            capture: Err("not attempted".into()),
            replays: Vec::new(),
            bisect: None,
            command: String::new(),
            verdict: String::new(),
        }
    }
}

/// The comment at the top of `repro.c`; `env` selects the driver (shell text).
pub fn c_header(backend: &str, env: &str, info: &DriverInfo, probes: &Probes) -> String {
    let what = if probes.texels.is_empty() {
        "the frame"
    } else {
        "the frame and the shadow map"
    };
    format!(
        "/*\n * repro.c: a standalone reproduction of a shadow-mapping conformance failure, written by\n * umbra (`umbra repro`) from the GL calls umbra made on {backend}\n * ({renderer}, {version}).\n *\n * It draws the reduced case's two passes (shadow map, then the lit pass sampling it) with\n * exactly the shaders, state and vertex data umbra sent the driver, reads back {what},\n * and tests {n} probes against the intervals umbra's judge derived from the GL and Vulkan\n * specs (the numbers are below, with the clauses). It needs libEGL only:\n *\n *     cc repro.c -o repro -lEGL -lm\n *     {env} ./repro\n *\n * (GALLIUM_DRIVER=llvmpipe for the conforming comparison.) Exit status, as `git bisect run`\n * reads it: 0 every probe inside, 1 a probe outside (the bug), 125 could not run (no EGL\n * display or context, a GL error, a shader that does not compile).\n */\n",
        renderer = info.renderer,
        version = info.version,
        n = probes.pixels.len() + probes.texels.len(),
    )
}

/// The failed checks as words, with the clause each is held to
/// ([`umbra_report::check::Check::counted`]).
fn violated(facts: &Facts) -> String {
    let parts: Vec<String> = facts
        .failed
        .iter()
        .map(|f| f.check.counted(f.count))
        .collect();
    parts.join("; ")
}

/// `issue.md`.
pub fn issue_md(facts: &Facts, m: &Measured) -> String {
    let mut o = String::new();
    issue_description(&mut o, facts, m);
    issue_system(&mut o, facts, m);
    issue_regression(&mut o, facts, m);
    issue_steps(&mut o, facts, m);
    issue_probes(&mut o, facts, m);
    issue_screenshots(&mut o, facts);
    issue_capture(&mut o, m);
    issue_for_umbra_users(&mut o, facts, m);
    o
}

/// `issue.md`'s title and `### Description`: what was violated, the diagnosis, and how umbra
/// found and reduced it.
fn issue_description(o: &mut String, facts: &Facts, m: &Measured) {
    let renderer = facts.renderer.as_str();
    let _ = writeln!(
        o,
        "# {renderer}: shadow map sampling breaks the spec's bounds: {}\n",
        violated(facts)
    );
    let _ = writeln!(o, "### Description\n");
    let _ = writeln!(
        o,
        "A shadow-mapping program (a depth-only pass into a depth texture, then a lit pass that samples it with depth comparison) gets results on **{renderer}** that no conformant implementation may return: {}. The bounds come from the GL and Vulkan specs (every freedom they give: rounding, sub-pixel precision, texel selection, LINEAR weights, the offset's `r`), computed per pixel by an exact reference; a conforming driver ({}) stays inside them on the same program.\n",
        violated(facts),
        m.runs
            .get(1)
            .map_or("llvmpipe".to_string(), |r| r.backend.clone())
    );
    if let Some(d) = &m.diagnosis {
        let _ = writeln!(o, "Diagnosis so far (from reading Mesa's source): {d}.\n");
    }
    let _ = writeln!(
        o,
        "Found by umbra's conformance run (a shadow-mapping conformance harness judging drivers against the specs' bounds) as `{}` ({} point `{}`), reduced to {} triangles, a {}×{} frame and a {}{}×{} shadow map ({}).\n",
        m.run,
        m.case_file,
        m.point,
        facts.triangles,
        facts.frame[0],
        facts.frame[1],
        match (facts.cube, facts.faces) {
            // Bundles written before cascades carry no "cube": six faces were a cube.
            (Some(true), _) | (None, 6) => "cube ".to_string(),
            (_, 1) => String::new(),
            (_, n) => format!("{n}-cascade "),
        },
        facts.map[0],
        facts.map[1],
        m.reduced
    );
}

/// `issue.md`'s `### System information`: the driver's strings, the Mesa build, the platform.
fn issue_system(o: &mut String, facts: &Facts, m: &Measured) {
    let backend = facts.backend.as_str();
    let renderer = facts.renderer.as_str();
    let _ = writeln!(o, "### System information\n");
    let _ = writeln!(o, "- GL_VENDOR: `{}`", facts.vendor.as_str());
    let _ = writeln!(o, "- GL_RENDERER: `{renderer}`");
    let _ = writeln!(o, "- GL_VERSION: `{}`", facts.version.as_str());
    let exts = facts.extensions.clone();
    if let Some(egl) = exts.iter().find(|e| e.starts_with("EGL ")) {
        let _ = writeln!(o, "- EGL: `{}`", egl.trim_start_matches("EGL "));
    }
    let _ = writeln!(
        o,
        "- Mesa: {}",
        m.mesa_build
            .clone()
            .unwrap_or_else(|| "the system's (see GL_VERSION)".into())
    );
    let device = facts.device.as_str();
    let platform = if device.starts_with("EGL device") {
        format!("{device} (`EGL_PLATFORM_DEVICE_EXT`)")
    } else {
        "EGL surfaceless (`EGL_PLATFORM_SURFACELESS_MESA`)".to_string()
    };
    let _ = writeln!(
        o,
        "- Platform: {platform}, no window system; umbra backend `{backend}`\n"
    );
}

/// `issue.md`'s `### Regression`: the first bad commit, or how to bisect.
fn issue_regression(o: &mut String, facts: &Facts, m: &Measured) {
    let backend = facts.backend.as_str();
    let _ = writeln!(o, "### Regression\n");
    match &m.bisect {
        Some((commit, log)) => {
            let _ = writeln!(
                o,
                "Yes. First bad commit: **{commit}**, found by bisecting a Mesa tree (each commit built, installed into its own prefix and judged); this bundle's program and pictures come from that commit's build."
            );
            if let Some(log) = log {
                let command = log.lines().next().unwrap_or("").trim_start_matches("# ");
                let git_log = log
                    .split_once("# git bisect log")
                    .map_or("", |(_, g)| g)
                    .trim();
                let _ = writeln!(
                    o,
                    "\nTo run the bisection again: `{command}` (or `git bisect replay` the log below). To bisect with the program alone: {}\n\n```\n{git_log}\n```\n\nThe full transcript is `bisect.log`.\n",
                    bisect_hint(m)
                );
            } else {
                let _ = writeln!(o);
            }
        }
        None => {
            let _ = writeln!(
                o,
                "Not bisected. The same program passes on {}. To bisect a Mesa tree with it: {} Or umbra's `cargo xtask bisect --mesa-src DIR --good A --bad B --backend {backend} --repro DIR`, which also writes this bundle for the first bad commit.\n",
                m.runs
                    .get(1)
                    .map_or("llvmpipe".to_string(), |r| r.backend.clone()),
                bisect_hint(m)
            );
        }
    }
}

/// `issue.md`'s `### Steps to reproduce`: the program's commands and exits, or why there is
/// no program.
fn issue_steps(o: &mut String, facts: &Facts, m: &Measured) {
    let backend = facts.backend.as_str();
    let _ = writeln!(o, "### Steps to reproduce\n");
    if m.runs.is_empty() {
        let _ = writeln!(
            o,
            "No standalone program: {}. With umbra: `umbra render case.json --backend {backend}` (it prints the failing pixels with their intervals); the API capture below replays without it.\n",
            m.no_program.as_deref().unwrap_or("none was built")
        );
    } else {
        let _ = writeln!(o, "```sh\ncc repro.c -o repro -lEGL -lm");
        for r in &m.runs {
            let _ = writeln!(
                o,
                "{} ./repro   # {}: exit {}",
                r.env,
                r.backend,
                r.code.map_or("none".into(), |c| c.to_string())
            );
        }
        let _ = writeln!(o, "```\n");
        let _ = writeln!(
            o,
            "`repro.c` needs only libEGL: it makes the exact GL calls umbra made (shaders, state, vertex data as hex floats), reads back the frame{} and tests each probe against the judge's interval. Exit 0: all inside; 1: a probe outside; 125: could not run.\n",
            if facts.texels > 0 {
                " and the shadow map"
            } else {
                ""
            }
        );
    }
}

/// `issue.md`'s `### Probes`: the probes as umbra read them, and the program's output on
/// each driver.
fn issue_probes(o: &mut String, facts: &Facts, m: &Measured) {
    let backend = facts.backend.as_str();
    let _ = writeln!(o, "### Probes\n");
    let _ = writeln!(
        o,
        "{} of {} failing pixels and {} of {} failing texels are probed. As umbra read them on {backend}:\n",
        facts.pixels, facts.pixels_total, facts.texels, facts.texels_total
    );
    let _ = writeln!(o, "```");
    for l in facts.probe_lines.iter().take(16) {
        let _ = writeln!(o, "{l}");
    }
    if facts.probe_lines.len() > 16 {
        let _ = writeln!(o, "... (all of them in repro.c)");
    }
    let _ = writeln!(o, "```\n");
    for r in &m.runs {
        let _ = writeln!(
            o,
            "`repro` on {} (exit {}):\n\n```\n{}```\n",
            r.backend,
            r.code.map_or("none".into(), |c| c.to_string()),
            tail(&r.output, 14)
        );
    }
}

/// `issue.md`'s `### Screenshots`: the crop's table and where the full-size pictures are.
fn issue_screenshots(o: &mut String, facts: &Facts) {
    let renderer = facts.renderer.as_str();
    let _ = writeln!(o, "### Screenshots\n");
    let c = facts.crop.map(u64::from);
    let _ = writeln!(
        o,
        "The failing area (x {}..{}, y {}..{} of the {}×{} frame), magnified {}×. Expected: umbra's reference for this profile; actual: {renderer}; difference: red = outside the spec's bounds, amber = a legal difference, blue = any answer legal, grey = agrees.\n",
        c[0],
        (c[0] + c[2]).saturating_sub(1),
        c[1],
        (c[1] + c[3]).saturating_sub(1),
        facts.frame[0],
        facts.frame[1],
        c[4]
    );
    let _ = writeln!(
        o,
        "| expected | actual | difference |\n|---|---|---|\n| ![expected](expected.png) | ![actual](actual.png) | ![difference](difference.png) |\n"
    );
    let _ = writeln!(
        o,
        "Full-size pictures (colour, visibility, reference, truth, error map, shadow map) are in `full/`.\n"
    );
}

/// `issue.md`'s `### API capture`: how it was made and its replays, or why there is none.
fn issue_capture(o: &mut String, m: &Measured) {
    let _ = writeln!(o, "### API capture\n");
    match &m.capture {
        Ok(how) => {
            let _ = writeln!(o, "{how}\n");
            for r in &m.replays {
                let _ = writeln!(o, "- {}: `{}`: {}", r.backend, r.command, r.outcome);
            }
            let _ = writeln!(o);
        }
        Err(why) => {
            let _ = writeln!(o, "None: {why}.\n");
        }
    }
}

/// `issue.md`'s last section, `### For umbra users`: the reduced case and the command that
/// made the bundle.
fn issue_for_umbra_users(o: &mut String, facts: &Facts, m: &Measured) {
    let backend = facts.backend.as_str();
    let _ = writeln!(o, "### For umbra users\n");
    let _ = writeln!(
        o,
        "`case.json` is the reduced case: `umbra render case.json --backend {backend}` shows the failure with umbra's pictures and `--explain X,Y` prints the judge's derivation at a pixel. This bundle was made by `{}`.",
        m.command
    );
}

/// How to bisect a Mesa tree with the program alone (a meson build directory `build`
/// configured with the drivers; each commit installed into a scratch prefix).
fn bisect_hint(m: &Measured) -> String {
    let driver_env = m.runs.first().map_or(String::new(), |r| {
        r.env
            .split_whitespace()
            .filter(|kv| {
                !kv.starts_with("LD_LIBRARY_PATH=")
                    && !kv.contains("_PATH=")
                    && !kv.contains("FILENAMES=")
                    && !kv.starts_with("VK_")
            })
            .collect::<Vec<_>>()
            .join(" ")
    });
    format!(
        "from the Mesa tree, `git bisect run sh -c 'ninja -C build && rm -rf /tmp/p && meson install -C build --destdir /tmp/p || exit 125; L=/tmp/p/usr/local/lib/x86_64-linux-gnu; LD_LIBRARY_PATH=$L LIBGL_DRIVERS_PATH=$L/dri __EGL_VENDOR_LIBRARY_FILENAMES=/tmp/p/usr/local/share/glvnd/egl_vendor.d/50_mesa.json {driver_env} /path/to/repro'` (adjust the prefix to the build's `--prefix`/`--libdir`; exit 125 skips a commit that cannot run it)."
    )
}

/// The last `n` lines of `text`, ending in a newline.
fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let from = lines.len().saturating_sub(n);
    let mut out = String::new();
    if from > 0 {
        out.push_str("...\n");
    }
    for l in &lines[from..] {
        out.push_str(l);
        out.push('\n');
    }
    out
}

/// `README.md`: what each file is and the commands.
pub fn readme(facts: &Facts, m: &Measured, files: &[(String, u64)]) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "# Repro bundle: `{}`\n\n{}\n\nWritten by `{}`. Start with `issue.md`.\n",
        m.run, m.verdict, m.command
    );
    let _ = writeln!(o, "| file | bytes | what |\n|---|---|---|");
    for (name, bytes) in files {
        let what = match name.as_str() {
            "issue.md" => "the bug report draft (Mesa's template)",
            "repro.c" => "standalone program: EGL + GL, the exact calls, the judge's probes",
            "repro" => "repro.c as compiled here (rebuild it on your machine)",
            "case.json" => "the reduced umbra case",
            "facts.json" => "what umbra measured on the driver (strings, checks, probes)",
            "expected.png" | "actual.png" | "difference.png" => "crop of the failing area",
            "reduce.log" => "the reducer's steps",
            "bisect.log" => "the bisection's log",
            "repro-step.sh" => "a `git bisect run` step building Mesa and running repro",
            n if n.ends_with(".trace") => "apitrace capture (replay with eglretrace)",
            n if n.ends_with(".gfxr") => "GFXReconstruct capture",
            n if n.starts_with("full/") => "full-size picture",
            n if n.starts_with("replay") => "a replay's snapshot",
            n if n.starts_with("state-") => {
                "the GL state at the lit pass's draw, replayed (eglretrace -D)"
            }
            n if n.starts_with("mesa/") => "the Mesa build's loader file the commands name",
            n if n.starts_with("repro-") && n.ends_with(".txt") => "repro's output on a driver",
            _ => "",
        };
        let _ = writeln!(o, "| `{name}` | {bytes} | {what} |");
    }
    let _ = writeln!(
        o,
        "\n## Run the program\n\n```sh\ncc repro.c -o repro -lEGL -lm"
    );
    for r in &m.runs {
        let _ = writeln!(o, "{} ./repro   # {}", r.env, r.backend);
    }
    let _ = writeln!(
        o,
        "```\n\nOn a Mesa build that is not installed, point the loaders at it as well, e.g. `LD_LIBRARY_PATH=$PREFIX/lib/x86_64-linux-gnu LIBGL_DRIVERS_PATH=$PREFIX/lib/x86_64-linux-gnu/dri __EGL_VENDOR_LIBRARY_FILENAMES=$PREFIX/share/glvnd/egl_vendor.d/50_mesa.json`.\n"
    );
    if !m.replays.is_empty() {
        let _ = writeln!(o, "## Replay the capture\n");
        for r in &m.replays {
            let _ = writeln!(o, "- {}: `{}`", r.backend, r.command);
        }
        let _ = writeln!(o);
    }
    let _ = writeln!(
        o,
        "Driver strings: {} / {} / {}.",
        facts.vendor.as_str(),
        facts.renderer.as_str(),
        facts.version.as_str()
    );
    o
}
