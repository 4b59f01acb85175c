//! Driver builds as an input, without building Mesa: `--mesa` loads a relocated copy of the
//! system's Mesa and checks what it loaded, refuses a build whose driver does not load or
//! that falls back to the system's libraries; per-driver expectations select by the version
//! the driver reports; and `umbra bisect` finds the first bad commit of a small fake source
//! tree whose build script makes fake builds (one commit does not build: 125, skipped).

mod common;

use common::{scratch, text};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn umbra(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_umbra"));
    c.args(args).current_dir(repo()).env_remove("UMBRA_MESA");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run umbra")
}

const SYSTEM_LIB: &str = "/usr/lib/x86_64-linux-gnu";

/// A prefix holding copies of the system Mesa's EGL vendor library, GBM and swrast driver (and
/// glapi when `with_glapi`), laid out like an install.
fn relocated_mesa(name: &str, with_glapi: bool) -> PathBuf {
    let p = scratch(name);
    let lib = p.join("usr/lib/x86_64-linux-gnu");
    std::fs::create_dir_all(lib.join("dri")).expect("mkdir");
    let copy = |from: &str, to: &Path| {
        std::fs::copy(Path::new(SYSTEM_LIB).join(from), to).unwrap_or_else(|e| {
            panic!("{SYSTEM_LIB}/{from}: {e}; these tests need the system's Mesa (cargo xtask test installs it)")
        });
    };
    copy("libEGL_mesa.so.0", &lib.join("libEGL_mesa.so.0"));
    copy("dri/swrast_dri.so", &lib.join("dri/swrast_dri.so"));
    copy("libgbm.so.1", &lib.join("libgbm.so.1"));
    if with_glapi {
        copy("libglapi.so.0", &lib.join("libglapi.so.0"));
    }
    p
}

fn conformance_on(prefix: &Path, out: &Path) -> Output {
    umbra(
        &[
            "conformance",
            "--mesa",
            prefix.to_str().unwrap_or_default(),
            "--backend",
            "gl33/llvmpipe",
            "--filter",
            "l-occluder",
            "--golden",
            "none",
            "--out",
            out.to_str().unwrap_or_default(),
        ],
        &[],
    )
}

#[test]
fn a_relocated_mesa_loads_from_its_prefix_and_the_report_names_it() {
    let prefix = relocated_mesa("mesa-ok", true);
    let out = scratch("mesa-ok-out");
    let o = conformance_on(&prefix, &out);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let drivers = std::fs::read_to_string(out.join("latest/drivers.txt")).expect("drivers.txt");
    let canonical = std::fs::canonicalize(&prefix).expect("canonical");
    assert!(
        drivers.contains(&format!("Mesa: {}", canonical.display())) && drivers.contains("build: "),
        "{drivers}"
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json")).expect("report.json"),
    )
    .expect("json");
    assert!(report["mesa_build"]["root"].as_str().is_some(), "{report}");
    assert!(
        report["drivers"][0]["mesa"]
            .as_str()
            .is_some_and(|v| v.starts_with(char::is_numeric))
    );
}

#[test]
fn a_build_with_its_own_c_library_runs_its_workers_through_its_loader() {
    // What `cargo xtask fetch-mesa --suite sid` unpacks on an older machine, in miniature:
    // the build's Mesa beside a C library and its dynamic loader (here the system's own,
    // copied, so the test needs no network).
    let prefix = relocated_mesa("mesa-own-libc", true);
    let lib = prefix.join("usr/lib/x86_64-linux-gnu");
    for f in ["libc.so.6", "libm.so.6", "ld-linux-x86-64.so.2"] {
        std::fs::copy(Path::new(SYSTEM_LIB).join(f), lib.join(f))
            .unwrap_or_else(|e| panic!("{SYSTEM_LIB}/{f}: {e}"));
    }
    let out = scratch("mesa-own-libc-out");
    let o = conformance_on(&prefix, &out);
    let t = text(&o);
    // The worker checks that it runs on the build's C library and refuses otherwise, so a
    // pass is a run through the build's loader.
    assert_eq!(o.status.code(), Some(0), "{t}");
    let drivers = std::fs::read_to_string(out.join("latest/drivers.txt")).expect("drivers.txt");
    assert!(drivers.contains("its own C library"), "{drivers}");
}

#[test]
fn a_build_that_falls_back_to_the_system_is_refused_with_the_library_it_loaded() {
    // No libglapi in the prefix: the prefix's libEGL_mesa takes the system's.
    let prefix = relocated_mesa("mesa-fallback", false);
    let out = scratch("mesa-fallback-out");
    let o = conformance_on(&prefix, &out);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("fell back to a Mesa outside the build") && t.contains("libglapi"),
        "{t}"
    );
}

#[test]
fn a_build_whose_driver_does_not_load_is_refused() {
    let p = scratch("mesa-garbage");
    let lib = p.join("usr/lib/x86_64-linux-gnu");
    std::fs::create_dir_all(lib.join("dri")).expect("mkdir");
    std::fs::write(lib.join("libEGL_mesa.so.0"), "not a library").expect("write");
    std::fs::write(lib.join("dri/swrast_dri.so"), "not a library").expect("write");
    let out = scratch("mesa-garbage-out");
    let o = conformance_on(&p, &out);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    // Refused before a worker starts: the loader names the library it cannot load, and why.
    assert!(
        t.contains("cannot be loaded here")
            && t.contains("libEGL_mesa.so.0 cannot be loaded (file too short)"),
        "{t}"
    );
    // A directory with no Mesa at all is refused before anything runs, with the fix.
    let empty = scratch("mesa-empty");
    let o = conformance_on(&empty, &out);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("no Mesa library") && t.contains("fix:"), "{t}");
}

/// The system Mesa's hardware drivers in a relocated prefix (hard links where the file system
/// allows, else copies): Debian's packages carry radeonsi, iris and nouveau for GL and RADV
/// and ANV for Vulkan, as a Mesa developer's own build would.
fn relocated_mesa_with_hardware(name: &str) -> PathBuf {
    let p = relocated_mesa(name, true);
    let lib = p.join("usr/lib/x86_64-linux-gnu");
    for f in [
        "dri/radeonsi_dri.so",
        "dri/iris_dri.so",
        "dri/nouveau_dri.so",
        "libvulkan_radeon.so",
        "libvulkan_intel.so",
    ] {
        let from = std::fs::canonicalize(Path::new(SYSTEM_LIB).join(f)).unwrap_or_else(|e| {
            panic!("{SYSTEM_LIB}/{f}: {e}; cargo xtask test installs Debian's Mesa drivers")
        });
        if std::fs::hard_link(&from, lib.join(f)).is_err() {
            std::fs::copy(&from, lib.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
    }
    p
}

/// Whether this machine has a DRM render node (then its driver's ids may run, not skip).
fn has_render_node() -> bool {
    std::fs::read_dir("/sys/class/drm").is_ok_and(|rd| {
        rd.filter_map(Result::ok)
            .any(|e| e.file_name().to_string_lossy().starts_with("renderD"))
    })
}

#[test]
fn a_build_with_hardware_drivers_serves_their_device_ids_and_names_the_missing_device() {
    let prefix = relocated_mesa_with_hardware("mesa-hw");
    let p = prefix.to_str().unwrap_or_default();
    let want = [
        ("gl33/radeonsi", "AMD Radeon"),
        ("gles3/iris", "Intel GPU"),
        ("gles2/nouveau", "NVIDIA GPU"),
        ("wgpu-vk/radv", "AMD Radeon"),
        ("wgpu-vk/anv", "Intel GPU"),
    ];
    // The listing: the build's hardware ids beside the software ones, each with its reason.
    let o = umbra(&["backends", "--mesa", p, "--json"], &[]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let listing: serde_json::Value =
        serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {t}"));
    let backends = listing["backends"].as_array().cloned().unwrap_or_default();
    for (id, device) in want {
        let b = backends
            .iter()
            .find(|b| b["id"] == id)
            .unwrap_or_else(|| panic!("{id} not listed: {t}"));
        assert_eq!(b["aliases"], "hw, all", "{b}");
        if !has_render_node() {
            let why = b["why"].as_str().unwrap_or_default();
            assert!(
                b["available"] == false
                    && why.contains("this machine has no device for")
                    && why.contains(device)
                    && why.contains(
                        &*std::fs::canonicalize(&prefix)
                            .expect("canonical")
                            .to_string_lossy()
                    ),
                "{b}"
            );
        }
    }
    // `hw` takes them; without a device each is a skip that names it, never a run on the
    // system's driver and never an error that stops the others.
    let out = scratch("mesa-hw-out");
    let o = umbra(
        &[
            "conformance",
            "--mesa",
            p,
            "--backend",
            "hw",
            "--filter",
            "l-occluder",
            "--golden",
            "none",
            "--out",
            out.to_str().unwrap_or_default(),
        ],
        &[],
    );
    let t = text(&o);
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("latest/report.json"))
            .unwrap_or_else(|e| panic!("{e}: {t}")),
    )
    .expect("json");
    let runs = report["runs"].as_array().cloned().unwrap_or_default();
    for (id, device) in want {
        let run = runs
            .iter()
            .find(|r| r["backend"] == id)
            .unwrap_or_else(|| panic!("no run of {id}: {t}"));
        if !has_render_node() {
            assert_eq!(run["status"], "Skip", "{run}");
            assert!(
                run["reason"].as_str().is_some_and(|r| r.contains(device)),
                "{run}"
            );
        }
    }
    // Without the build, a device this machine lacks stays an error naming what it has.
    if !has_render_node() {
        let o = umbra(
            &[
                "conformance",
                "--backend",
                "gl33/radeonsi",
                "--filter",
                "l-occluder",
                "--golden",
                "none",
                "--out",
                out.to_str().unwrap_or_default(),
            ],
            &[],
        );
        assert_eq!(o.status.code(), Some(125), "{}", text(&o));
        assert!(
            text(&o).contains("no such device on this machine"),
            "{}",
            text(&o)
        );
    }
}

/// A fake build directory reporting `version`, rendering wrong when `fault`.
fn fake_build(name: &str, version: &str, fault: bool) -> PathBuf {
    fake_build_with(name, version, fault.then_some("invert"))
}

/// A fake build directory reporting `version`, with the fake's `fault` (`invert`: every
/// shadow wrong; `background`: the background's alpha changed, where only a golden looks).
fn fake_build_with(name: &str, version: &str, fault: Option<&str>) -> PathBuf {
    let p = scratch(name);
    let marker = serde_json::json!({"version": version, "fault": fault});
    std::fs::write(p.join("umbra-fake-mesa.json"), marker.to_string()).expect("write");
    p
}

#[test]
fn expectations_apply_to_the_driver_versions_they_name() {
    let exp = scratch("exp-versions");
    std::fs::write(
        exp.join("fake.txt"),
        "@applies mesa>=1.1 mesa<2\nfake/mesa/l-occluder,Fail:value<=100000+interior<=100000+colour<=100000+twin:bias-order<=100000+twin:moved-100m<=100000,inverted shadows in 1.1.x\n",
    )
    .expect("write");
    let run = |build: &Path, out: &str| {
        let out = scratch(out);
        let o = umbra(
            &[
                "conformance",
                "--mesa",
                build.to_str().unwrap_or_default(),
                "--backend",
                "fake/mesa",
                "--filter",
                "l-occluder",
                "--golden",
                "none",
                "--expectations",
                exp.to_str().unwrap_or_default(),
                "--out",
                out.to_str().unwrap_or_default(),
            ],
            &[("UMBRA_FAKE_BACKENDS", "1")],
        );
        let drivers = std::fs::read_to_string(out.join("latest/drivers.txt")).unwrap_or_default();
        (o, drivers)
    };
    // 1.1.3 is covered: an expected failure, and the report lists the file that applied.
    let (o, drivers) = run(&fake_build("fake-113", "1.1.3", true), "exp-113");
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("ExpectedFail"), "{t}");
    assert!(
        drivers.contains("expectations: ") && drivers.contains("fake.txt"),
        "{drivers}"
    );
    // 2.0.0 is past the range the fix closed: the same failure is a regression that names
    // the deviation as come back, and drivers.txt says the line's runs are held to pass.
    let (o, drivers) = run(&fake_build("fake-200", "2.0.0", true), "exp-200");
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("regression: Fail fake/mesa/l-occluder"), "{t}");
    assert!(
        t.contains(
            "a deviation that Mesa 2 fixed matches this failure, inverted shadows in 1.1.x ("
        ) && t.contains("fake.txt:2): it may be back"),
        "{t}"
    );
    assert!(drivers.contains("expectations: none"), "{drivers}");
    assert!(
        drivers.contains("closed before this release (deviations fixed; their runs must pass): ")
            && drivers.contains("fake.txt (1)"),
        "{drivers}"
    );
    // Below the range (1.0.0) the line never applied and nothing is closed.
    let (o, drivers) = run(&fake_build("fake-100", "1.0.0", true), "exp-100");
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        !t.contains("may be back") && !drivers.contains("fake.txt"),
        "{t}"
    );
}

fn git(dir: &Path, args: &[&str]) -> String {
    let o = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(["-c", "user.name=umbra", "-c", "user.email=umbra@localhost"])
        .args(args)
        .output()
        .expect("git");
    assert!(o.status.success(), "git {args:?}: {}", text(&o));
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

/// A fake Mesa source tree of `n` commits whose build script copies a fake build marker
/// into the prefix: commit k (1-based) reports version 1.0.k, renders wrong from
/// `fault_from` on, and does not build when k is in `broken`. Returns the commits.
fn fake_tree(src: &Path, n: usize, broken: &[usize], fault_from: usize) -> Vec<String> {
    fake_tree_renaming(src, n, broken, fault_from, n + 1)
}

/// A miniature of Mesa's option files: before the rename, 22.3's words (`swrast`, a boolean
/// glvnd); from it on, 25.x's (`llvmpipe` and `softpipe`, a feature glvnd, no osmesa).
fn fake_options(renamed: bool) -> String {
    let (drivers, glvnd, osmesa) = if renamed {
        ("'llvmpipe', 'softpipe', 'zink'", "type : 'feature'", "")
    } else {
        (
            "'swrast', 'zink'",
            "type : 'boolean', value : false",
            "option('osmesa', type : 'boolean', value : false)\n",
        )
    };
    format!(
        "option('gallium-drivers', type : 'array', choices : [{drivers}])\n\
         option('vulkan-drivers', type : 'array', choices : ['swrast'])\n\
         option('egl', type : 'feature')\noption('gles2', type : 'feature')\n\
         option('llvm', type : 'feature')\noption('glvnd', {glvnd})\n{osmesa}"
    )
}

/// [`fake_tree`], whose option file changes at commit `rename_at` ([`fake_options`]); its
/// build script refuses, as meson does, a gallium driver or an option its tree does not
/// declare.
fn fake_tree_renaming(
    src: &Path,
    n: usize,
    broken: &[usize],
    fault_from: usize,
    rename_at: usize,
) -> Vec<String> {
    git(src, &["init", "-q"]);
    std::fs::write(
        src.join("build.sh"),
        "#!/bin/sh\nset -e\nsrc=\"$1\"; prefix=\"$2\"; shift 2\n\
         for o in \"$@\"; do\n  case \"$o\" in\n\
         -Dgallium-drivers=*) for d in $(echo \"${o#*=}\" | tr , ' '); do grep -q \"'$d'\" \"$src/meson.options\" || { echo \"meson: $d is not a gallium driver here\" >&2; exit 1; }; done ;;\n\
         -D*) n=\"${o#-D}\"; n=\"${n%%=*}\"; case \"$n\" in b_*) ;; *) grep -q \"option('$n'\" \"$src/meson.options\" || { echo \"meson: unknown option $n\" >&2; exit 1; } ;; esac ;;\n\
         esac\ndone\n\
         if [ -f \"$src/BROKEN\" ]; then echo 'build error' >&2; exit 1; fi\nmkdir -p \"$prefix\"\ncp \"$src/fake-mesa.json\" \"$prefix/umbra-fake-mesa.json\"\n",
    )
    .expect("write");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(src.join("build.sh"), std::fs::Permissions::from_mode(0o755))
            .expect("chmod");
    }
    let mut commits = Vec::new();
    for k in 1..=n {
        let marker = serde_json::json!({
            "version": format!("1.0.{k}"),
            "fault": (k >= fault_from).then_some("invert"),
        });
        std::fs::write(src.join("fake-mesa.json"), marker.to_string()).expect("write");
        std::fs::write(src.join("meson.options"), fake_options(k >= rename_at)).expect("write");
        if broken.contains(&k) {
            std::fs::write(src.join("BROKEN"), "").expect("write");
        } else {
            let _ = std::fs::remove_file(src.join("BROKEN"));
        }
        git(src, &["add", "-A"]);
        git(src, &["commit", "-q", "-m", &format!("commit {k}")]);
        commits.push(git(src, &["rev-parse", "HEAD"]));
    }
    commits
}

/// `umbra bisect` over a fake tree, on fake/mesa and the l-occluder case.
fn bisect(src: &Path, good: &str, bad: &str, work: &Path) -> Output {
    bisect_with(src, good, bad, work, &[])
}

fn bisect_with(src: &Path, good: &str, bad: &str, work: &Path, extra: &[&str]) -> Output {
    let no_exp = scratch(&format!(
        "{}-exp",
        work.file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("bisect")
    ));
    umbra(
        &[
            "bisect",
            "--mesa-src",
            src.to_str().unwrap_or_default(),
            "--good",
            good,
            "--bad",
            bad,
            "--build-script",
            src.join("build.sh").to_str().unwrap_or_default(),
            "--backend",
            "fake/mesa",
            "--filter",
            "l-occluder",
            "--work",
            work.to_str().unwrap_or_default(),
            "--expectations",
            no_exp.to_str().unwrap_or_default(),
        ]
        .into_iter()
        .chain(extra.iter().copied())
        .collect::<Vec<_>>(),
        &[("UMBRA_FAKE_BACKENDS", "1")],
    )
}

/// Mesa renamed `-Dgallium-drivers=swrast` (llvmpipe and softpipe) and dropped osmesa between
/// 24.x and 25.0: a bisection across it needs each commit's own options. Commits 1–4 speak
/// 22.3's options, 5–8 25.x's; the fault starts at 6.
#[test]
fn bisect_crosses_a_renamed_option_with_each_commits_own_options() {
    let src = scratch("bisect-rename-src");
    let commits = fake_tree_renaming(&src, 8, &[], 6, 5);
    // First the check a user runs on their tree: both ends' options, then stop.
    let work = scratch("bisect-rename-configure");
    let o = bisect_with(&src, &commits[0], &commits[7], &work, &["--configure-only"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains("-Dgallium-drivers=swrast,zink")
            && t.contains("-Dgallium-drivers=llvmpipe,softpipe,zink")
            && t.contains("osmesa: not an option of this tree, left out")
            && t.contains("--configure-only: both ends configure"),
        "{t}"
    );
    assert!(
        !work.join("steps.csv").exists(),
        "--configure-only built nothing"
    );
    // A fixed option the far side lacks is refused before anything builds, naming the end,
    // the file and the option.
    let o = bisect_with(
        &src,
        &commits[0],
        &commits[7],
        &work,
        &[
            "--configure-only",
            "--meson-option",
            "-Dgallium-drivers=swrast,zink",
        ],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(
        t.contains("--bad")
            && t.contains("meson.options: meson would refuse")
            && t.contains("\"swrast\""),
        "{t}"
    );
    // The bisection: every commit builds with its own options, none is skipped.
    let work = scratch("bisect-rename-work");
    let o = bisect(&src, &commits[0], &commits[7], &work);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains(&format!("first bad commit: {}", commits[5])),
        "{t}"
    );
    let steps = std::fs::read_to_string(work.join("steps.csv")).expect("steps.csv");
    assert!(!steps.contains("skip"), "{steps}");
    // Each built commit's log names its options; the ends (1 and 8) are always built, so
    // both sides of the rename are among them.
    let mut sides = [0, 0];
    for (k, c) in commits.iter().enumerate() {
        let Ok(log) =
            std::fs::read_to_string(work.join("logs").join(format!("{}-build.log", &c[..12])))
        else {
            continue;
        };
        let renamed = k + 1 >= 5;
        let want = if renamed {
            "llvmpipe,softpipe,zink"
        } else {
            "swrast,zink"
        };
        assert!(log.contains(want), "commit {}: {log}", k + 1);
        sides[usize::from(renamed)] += 1;
    }
    assert!(sides[0] >= 1 && sides[1] >= 1, "{sides:?}");
}

#[test]
fn bisect_names_the_first_bad_commit_of_a_fake_tree_and_skips_one_that_does_not_build() {
    let src = scratch("bisect-src");
    // 8 commits; 3 does not build; wrong from 6 on.
    let commits = fake_tree(&src, 8, &[3], 6);
    let work = scratch("bisect-work");
    let o = bisect(&src, &commits[0], &commits[7], &work);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains(&format!("first bad commit: {}", commits[5])),
        "{t}"
    );
    assert!(t.contains("commit 6"), "{t}");
    let steps = std::fs::read_to_string(work.join("steps.csv")).expect("steps.csv");
    assert!(steps.lines().any(|l| l.contains(",bad,")), "{steps}");
    assert!(steps.lines().any(|l| l.contains(",good,")), "{steps}");
    // The tree is left as it was.
    assert_eq!(git(&src, &["rev-parse", "HEAD"]), commits[7]);
}

#[test]
fn bisect_ends_with_the_repro_bundle_of_the_first_bad_commit() {
    let src = scratch("bisect-repro-src");
    let commits = fake_tree(&src, 4, &[], 3);
    let work = scratch("bisect-repro-work");
    let bundle = scratch("bisect-repro-bundle");
    let _ = std::fs::remove_dir_all(&bundle);
    let o = bisect_with(
        &src,
        &commits[0],
        &commits[3],
        &work,
        &["--repro", bundle.to_str().unwrap_or_default()],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let issue = std::fs::read_to_string(bundle.join("issue.md")).expect("issue.md");
    // The commit named by its full hash, the log carried inline and as a file, and the
    // command that bisects again.
    assert!(
        issue.contains(&format!("First bad commit: **{}**", commits[2])),
        "{issue}"
    );
    assert!(issue.contains("git bisect start"), "{issue}");
    assert!(issue.contains("umbra bisect --mesa-src"), "{issue}");
    assert!(bundle.join("bisect.log").is_file());
    assert!(bundle.join("case.json").is_file());
    // The fake driver records no GL calls: the bundle says so instead of a program.
    assert!(issue.contains("records no GL calls"), "{issue}");
}

#[test]
fn bisect_reports_a_commit_that_does_not_build_as_skipped() {
    // Good 2, bad 4, 3 does not build: git cannot decide between 3 and 4, and says so.
    let src = scratch("bisect-skip-src");
    let commits = fake_tree(&src, 4, &[3], 4);
    let work = scratch("bisect-skip-work");
    let o = bisect(&src, &commits[1], &commits[3], &work);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let steps = std::fs::read_to_string(work.join("steps.csv")).expect("steps.csv");
    assert!(steps.contains("skip (does not build"), "{steps}");
    assert!(t.contains("no single first bad commit"), "{t}");
}

#[test]
fn bisect_refuses_ends_that_do_not_fail_as_claimed() {
    let src = scratch("bisect-ends-src");
    let commits = fake_tree(&src, 4, &[], 2);
    // "Good" already fails.
    let o = bisect(&src, &commits[2], &commits[3], &scratch("bisect-ends-good"));
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("already fail on the good commit"), "{t}");
    // "Bad" passes.
    let o = bisect(&src, &commits[0], &commits[0], &scratch("bisect-ends-bad"));
    let t = text(&o);
    assert_eq!(o.status.code(), Some(125), "{t}");
    assert!(t.contains("pass on the bad commit"), "{t}");
    assert_eq!(git(&src, &["rev-parse", "HEAD"]), commits[3]);
}

#[test]
fn a_golden_holds_on_its_release_and_lets_the_judge_speak_on_another() {
    let golden = scratch("golden-versions");
    a_bless_records_its_release_and_the_same_picture_passes_on_another(&golden);
    off_its_release_the_judge_speaks_and_the_golden_only_where_it_does_not_look(&golden);
    a_bless_on_another_release_writes_its_picture_beside_the_old_golden(&golden);
    a_bless_where_the_picture_is_the_same_confirms_the_golden(&golden);
}

/// A conformance run of `fake/mesa` on `l-occluder` with the fake `build`, against the
/// goldens in `golden` (blessing them when `bless`), into the scratch directory `out`: its
/// output and that directory.
fn golden_versions_run(golden: &Path, build: &Path, out: &str, bless: bool) -> (Output, PathBuf) {
    let mut env = vec![("UMBRA_FAKE_BACKENDS", "1")];
    // Blessing is refused under CI (and this test may run under CI=true).
    env.push(("CI", if bless { "false" } else { "true" }));
    let out = scratch(out);
    let mut args = vec![
        "conformance",
        "--mesa",
        build.to_str().unwrap_or_default(),
        "--backend",
        "fake/mesa",
        "--filter",
        "l-occluder",
        "--golden",
        golden.to_str().unwrap_or_default(),
        "--out",
        out.to_str().unwrap_or_default(),
    ];
    if bless {
        args.push("--bless");
    }
    (umbra(&args, &env), out)
}

/// Blessing on 1.0.0 records the release in the manifest; the same picture on 1.0.7 passes.
fn a_bless_records_its_release_and_the_same_picture_passes_on_another(golden: &Path) {
    let (o, _) = golden_versions_run(
        golden,
        &fake_build("golden-100", "1.0.0", false),
        "golden-bless",
        true,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let manifest =
        std::fs::read_to_string(golden.join("blessed-on.json")).expect("blessed-on.json");
    assert!(
        manifest.contains("\"fake/mesa\"") && manifest.contains("1.0.0"),
        "{manifest}"
    );
    // The same picture on 1.0.7 passes: the golden guards the picture, not the version.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build("golden-107", "1.0.7", false),
        "golden-same",
        false,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

/// On 2.0.0, wrong shadows fail by the judge's own checks with the change reported, and a
/// change where the judge does not look (the background's alpha) fails the golden check; on 1.0.0 it
/// fails plainly.
fn off_its_release_the_judge_speaks_and_the_golden_only_where_it_does_not_look(golden: &Path) {
    // Wrong shadows on 2.0.0 fail by the judge's own checks; the changed picture is reported
    // with both versions, and the golden adds no failure of its own.
    let (o, out) = golden_versions_run(
        golden,
        &fake_build("golden-200", "2.0.0", true),
        "golden-other",
        false,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("where the judge finds pixels illegal") && !t.contains("golden=1"),
        "{t}"
    );
    let csv = std::fs::read_to_string(out.join("latest").join("goldens.csv")).expect("csv");
    assert!(
        csv.contains("fake/mesa/l-occluder,Fail,changed-judged,1.0.0,2.0.0,"),
        "{csv}"
    );
    // A change where the judge does not look (the background's alpha) fails the golden check on
    // 2.0.0, naming both versions.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build_with("golden-200-bg", "2.0.0", Some("background")),
        "golden-background",
        false,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("blessed on Mesa 1.0.0")
            && t.contains("this driver is Mesa 2.0.0")
            && t.contains("golden=1"),
        "{t}"
    );
    // On the release it was blessed on, the same background change fails too, plainly.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build_with("golden-100-bg", "1.0.0", Some("background")),
        "golden-background-same",
        false,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("golden=1") && !t.contains("this driver is Mesa"),
        "{t}"
    );
}

/// Blessing on 2.0.0 writes that release's picture beside the old golden (in the release's
/// folder of the backend), which then holds strictly on 2.0.0 and leaves 1.0.0's alone.
fn a_bless_on_another_release_writes_its_picture_beside_the_old_golden(golden: &Path) {
    // Blessing on 2.0.0 writes that release's picture beside the old golden, which stays,
    // and then holds strictly on 2.0.0.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build_with("golden-200-bless", "2.0.0", Some("background")),
        "golden-bless-200",
        true,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let release = golden.join("mesa-2.0.0");
    // The release's pictures are in its folder of the backend (`fake/mesa` → `fake_mesa`).
    let release_pictures = release.join(umbra_runner::judge::golden::folder("fake/mesa"));
    let pictures: Vec<String> = std::fs::read_dir(&release_pictures)
        .expect("golden/mesa-2.0.0/fake_mesa")
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .collect();
    assert!(
        pictures.iter().any(|p| p.ends_with(".snap.png")),
        "{pictures:?}"
    );
    // The picture differed, so it was written, not confirmed.
    assert!(!release.join("confirmed.txt").exists());
    let (o, _) = golden_versions_run(
        golden,
        &fake_build_with("golden-200-bg-again", "2.0.0", Some("background")),
        "golden-background-again",
        false,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // 1.0.0's golden is untouched: its own picture still passes there.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build("golden-100-again", "1.0.0", false),
        "golden-same-again",
        false,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // And the unchanged picture on 2.0.0, strict there now, fails against 2.0.0's own.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build("golden-200-plain", "2.0.0", false),
        "golden-200-plain-out",
        false,
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

/// A bless on 3.0.0 where the picture is 1.0.0's writes nothing and confirms the golden,
/// which then holds strictly on 3.0.0.
fn a_bless_where_the_picture_is_the_same_confirms_the_golden(golden: &Path) {
    // A bless on 3.0.0, where the picture is 1.0.0's, writes nothing and confirms the golden
    // it compared there: from then on it holds strictly on 3.0.0, so the background change
    // fails plainly, as on 1.0.0.
    let (o, _) = golden_versions_run(
        golden,
        &fake_build("golden-300", "3.0.0", false),
        "golden-300-bless",
        true,
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let confirmed = std::fs::read_to_string(golden.join("mesa-3.0.0/confirmed.txt"))
        .expect("mesa-3.0.0/confirmed.txt");
    assert_eq!(confirmed.lines().count(), 1, "{confirmed}");
    assert!(
        !golden
            .join("mesa-3.0.0/fake_mesa/fake_mesa_l-occluder-70d5e49c.snap.png")
            .exists(),
        "nothing differed on 3.0.0"
    );
    let (o, _) = golden_versions_run(
        golden,
        &fake_build_with("golden-300-bg", "3.0.0", Some("background")),
        "golden-300-bg-out",
        false,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("golden=1") && !t.contains("this driver is Mesa"),
        "{t}"
    );
}

#[test]
fn the_drivers_page_offers_a_bug_report_for_each_regression() {
    // Two fake builds: 1.0.1 right, 1.0.2 with the inverted compare.
    let build = |name: &str, marker: serde_json::Value| {
        let p = scratch(name);
        std::fs::write(p.join("umbra-fake-mesa.json"), marker.to_string()).expect("write");
        p
    };
    let good = build("ab-good", serde_json::json!({"version": "1.0.1"}));
    let bad = build(
        "ab-bad",
        serde_json::json!({"version": "1.0.2", "fault": "invert"}),
    );
    let out = scratch("ab-out");
    let no_exp = scratch("ab-exp");
    let o = umbra(
        &[
            "drivers",
            "--baseline",
            good.to_str().unwrap_or_default(),
            "--candidate",
            bad.to_str().unwrap_or_default(),
            "--backend",
            "fake/mesa",
            "--filter",
            "l-occluder",
            "--expectations",
            no_exp.to_str().unwrap_or_default(),
            "--out",
            out.to_str().unwrap_or_default(),
        ],
        &[("UMBRA_FAKE_BACKENDS", "1")],
    );
    let t = text(&o);
    // Each side's closing line, as its report.json counts it.
    assert!(
        t.contains("): conformance: 1 passed, 0 failed, 0 skipped")
            && t.contains("): conformance: 0 passed, 1 failed, 0 skipped"),
        "{t}"
    );
    let html = std::fs::read_to_string(out.join("report.html")).expect("report.html");
    assert!(
        html.contains(&format!(
            "bug report: <code>cargo run --bin umbra -- repro fake/mesa/l-occluder -o target/umbra/repro/fake_mesa_l-occluder --mesa={}</code>",
            bad.display()
        )),
        "{t}\n{html}"
    );
}
