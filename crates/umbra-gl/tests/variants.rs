//! The GL backend on every Mesa driver: variants that must not change the shadows.
//!
//! - `depth_only` vs `with_color` (docs/catalogue.md §3, "AMD needs a colour attachment"): the
//!   colour attachment must not change a single bit of the visibility.
//! - Hardware vs manual compare at NEAREST (docs/catalogue.md §4): the sampler's compare and the
//!   shader's `texelFetch(...).r <= ref` may differ only where the reference's own lookup was a
//!   depth tie (the compared texel within the stored depth's freedom) or at a texel boundary
//!   (hardware texel selection need only be 4 sub-texel bits exact; the shader computes
//!   floor(u·size) in f32). Both are counted and printed.
//!
//! - GLES 2's packed RGBA8 depth vs GLES 3's D24 (docs/catalogue.md §4): within the packing's
//!   precision (see `packed_vs_d24`).
//!
//! Mesa picks its driver when EGL loads, so `variants_on_every_driver` runs this test binary
//! once per driver with the driver's environment, selecting the ignored `variants_worker`.

use std::process::Command;

use umbra_case::format::{Attachments, Compare, Filter};
use umbra_case::{Backend, ClipDepth, Prepared};
use umbra_gl::{Api, Driver, GlBackend};
use umbra_ref::lookup::ambiguity::{COVERAGE, DEPTH_TIE, TEXEL_BOUNDARY};

const WORKER_DRIVER: &str = "UMBRA_TEST_DRIVER";

/// A named change to a case.
type Variant<'a> = (&'a str, &'a dyn Fn(&mut umbra_case::Case));

fn case(rel: &str) -> umbra_case::CasePoint {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases")
        .join(rel);
    umbra_case::load_file(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(0)
}

/// The drivers' workers run side by side and are read in order: on 2 cores 39 s against 43 s
/// one after another (softpipe's worker alone takes 32 s).
#[test]
fn variants_on_every_driver() {
    let exe = std::env::current_exe().expect("test binary");
    let workers: Vec<_> = Driver::ALL
        .into_iter()
        .map(|driver| {
            let child = Command::new(&exe)
                .args([
                    "--exact",
                    "variants_worker",
                    "--include-ignored",
                    "--nocapture",
                    "--test-threads",
                    "1",
                ])
                .env(WORKER_DRIVER, driver.name())
                .envs(driver.env())
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("start the driver worker");
            (driver, child)
        })
        .collect();
    for (driver, child) in workers {
        let out = child
            .wait_with_output()
            .expect("wait for the driver worker");
        let stdout = String::from_utf8_lossy(&out.stdout);
        println!("--- {} ---\n{stdout}", driver.name());
        assert!(
            out.status.success(),
            "{} worker failed:\n{stdout}\n{}",
            driver.name(),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            stdout.contains("1 passed"),
            "{}: the worker did not run",
            driver.name()
        );
    }
}

#[test]
#[ignore = "driver worker: variants_on_every_driver runs it in a child process with the driver's environment"]
fn variants_worker() {
    let name = std::env::var(WORKER_DRIVER).expect("run by variants_on_every_driver");
    let driver = Driver::parse(&name).expect("a driver name");
    let cases = [
        "basics/square-occluder.json",
        "lights/spot-20deg.json",
        "lights/directional-ortho-10.json",
        "packed-cubes/packed-cubes.json",
    ];
    // Each case as written (biased: ties are rare), and with every bias removed (acne by
    // design: the receivers compare against their own depth, so ties are everywhere).
    let unbiased = |c: &mut umbra_case::Case| c.shadow.bias = Default::default();
    let variants: [Variant; 2] = [("", &|_| {}), ("+no-bias", &unbiased)];
    let mut tie_pixels_seen = 0u64;
    for api in Api::ALL {
        let mut backend = GlBackend::new(api, driver).unwrap_or_else(|e| {
            panic!(
                "{}/{}: {} (`cargo xtask test` installs the Mesa packages)",
                api.name(),
                driver.name(),
                e.0
            )
        });
        for (rel, (tag, vary)) in cases
            .iter()
            .flat_map(|r| variants.iter().map(move |v| (*r, *v)))
        {
            let mut base = case(rel);
            vary(&mut base.case);
            let id = format!("{}/{}{tag}", backend.id(), base.id());
            let render = |b: &mut GlBackend, change: &dyn Fn(&mut umbra_case::Case)| {
                let mut p = base.clone();
                change(&mut p.case);
                let run = Prepared::new(p);
                let frame = b.render(&run).unwrap_or_else(|e| panic!("{id}: {e}"));
                (run, frame)
            };
            let (_, depth_only) = render(&mut backend, &|c| {
                c.shadow.attachments = Attachments::DepthOnly
            });
            let (_, with_color) = render(&mut backend, &|c| {
                c.shadow.attachments = Attachments::WithColor
            });
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&depth_only.lights[0].visibility),
                bits(&with_color.lights[0].visibility),
                "{id}: with_color changed the shadows"
            );
            assert_eq!(
                depth_only.lights[0].surface, with_color.lights[0].surface,
                "{id}: with_color changed the surfaces"
            );

            if rel == cases[0] {
                twin_shares_the_shadow_pass(&mut backend, &base, &id);
            }

            let nearest = |compare: Compare| {
                move |c: &mut umbra_case::Case| {
                    c.shadow.filter = Filter::Nearest;
                    c.shadow.compare = compare;
                }
            };
            let (run, hw) = render(&mut backend, &nearest(Compare::Hardware));
            let (_, manual) = render(&mut backend, &nearest(Compare::Manual));
            let judged =
                umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, backend.profile());
            let ambiguity: Vec<u8> = judged.lights[0].legal.iter().map(|l| l.flags).collect();
            let free = umbra_compare::reference::free_pixels(&judged);
            tie_pixels_seen += ambiguity.iter().filter(|a| **a & DEPTH_TIE != 0).count() as u64;
            let g = umbra_compare::agreement(
                hw.light(0).expect("a light"),
                manual.light(0).expect("a light"),
                0,
            );
            assert_eq!(
                g.coverage_differs, 0,
                "{id}: coverage differs between compare modes"
            );
            let (mut ties, mut boundaries, mut coverage) = (0, 0, 0);
            for (i, differs) in g.disagrees.iter().enumerate() {
                if !differs {
                    continue;
                }
                if !free[i] {
                    panic!(
                        "{id}: hardware and manual compare differ at pixel {i}, where the reference leaves no freedom (flags {:#04x})",
                        ambiguity[i]
                    );
                } else if ambiguity[i] & DEPTH_TIE != 0 {
                    ties += 1;
                } else if ambiguity[i] & TEXEL_BOUNDARY != 0 {
                    boundaries += 1;
                } else if ambiguity[i] & COVERAGE != 0 {
                    // A tap whose texel may hold another surface: its stored range spans both
                    // answers, and the tie is one inside it.
                    coverage += 1;
                } else {
                    panic!(
                        "{id}: hardware and manual compare differ at pixel {i}, which is neither a depth tie, a texel boundary nor a texel of uncertain coverage (flags {:#04x})",
                        ambiguity[i]
                    );
                }
            }
            println!(
                "{id}: with_color bit-identical; hardware vs manual NEAREST: {} of {} px differ ({ties} depth ties, {boundaries} texel boundaries, {coverage} uncertain coverage)",
                g.unexplained(),
                g.compared
            );
        }
    }
    packed_vs_d24(driver, &cases, &variants);
    // The unbiased variants must have produced ties, or the tie classification was not tested.
    assert!(
        tie_pixels_seen > 10_000,
        "only {tie_pixels_seen} reference lookups were depth ties"
    );
}

/// The bias-order twin drawn over the case's kept shadow map ([`Backend::render_twin`]) is the
/// twin rendered from scratch, bit for bit, and says it shared; a twin whose shadow pass
/// differs (here: a colour attachment beside the depth) is rendered afresh.
fn twin_shares_the_shadow_pass(backend: &mut GlBackend, base: &umbra_case::CasePoint, id: &str) {
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let run = Prepared::new(base.clone());
    let order = umbra_case::twin::twins_of(base)
        .remove(0)
        .point
        .expect("bias-order twin");
    let twin = Prepared::new(order);
    let fresh = backend
        .render(&twin)
        .unwrap_or_else(|e| panic!("{id}: {e}"));
    backend.render(&run).unwrap_or_else(|e| panic!("{id}: {e}"));
    let (shared, yes) = backend
        .render_twin(&twin, &run)
        .unwrap_or_else(|e| panic!("{id}: {e}"));
    assert!(
        yes,
        "{id}: the bias-order twin did not share the shadow pass"
    );
    assert_eq!(shared.color, fresh.color, "{id}: shared twin's colour");
    assert_eq!(
        bits(&shared.lights[0].visibility),
        bits(&fresh.lights[0].visibility),
        "{id}: shared twin's visibility"
    );
    let mut other = base.clone();
    other.case.shadow.attachments = match other.case.shadow.attachments {
        Attachments::DepthOnly => Attachments::WithColor,
        Attachments::WithColor => Attachments::DepthOnly,
    };
    let (_, yes) = backend
        .render_twin(&Prepared::new(other), &run)
        .unwrap_or_else(|e| panic!("{id}: {e}"));
    assert!(
        !yes,
        "{id}: a twin with another shadow pass shared the case's"
    );
}

/// docs/catalogue.md §4 on one driver: GLES 2's depth packed into RGBA8 (compared by hand) against
/// GLES 3's D24 depth texture (hardware compare), NEAREST, same case, same driver.
///
/// Precision of the packing (crates/umbra-gl/src/shaders.rs, `pack_depth`): four base-255
/// digits, each stored as (k + ¼)/255 and recovered exactly, truncating the rest; the first
/// multiply d·255 rounds in f32, later digits only add u/255, u/255², … So
/// |unpack(pack(d)) − d| ≤ u·d·(1 + 1/254) + 255⁻⁴ ≈ 1.004 f32 ulps of d, at most about one D24
/// step (2⁻²⁴) below 1: inside the ±1 storage step the reference's depth tie allows. The two
/// may therefore differ only where the reference's lookup is ambiguous (the same judge as
/// backend vs reference), and the test counts those pixels.
fn packed_vs_d24(driver: Driver, cases: &[&str], variants: &[Variant]) {
    let open = |api: Api| {
        GlBackend::new(api, driver)
            .unwrap_or_else(|e| panic!("{}/{}: {}", api.name(), driver.name(), e.0))
    };
    let (mut gles2, mut gles3) = (open(Api::Gles2), open(Api::Gles3));
    for rel in cases {
        for (tag, vary) in variants {
            let mut p = case(rel);
            vary(&mut p.case);
            p.case.shadow.format = umbra_case::format::DepthFormat::Depth24;
            p.case.shadow.filter = Filter::Nearest;
            p.case.shadow.compare = Compare::Hardware;
            let id = format!("{}/{}{tag}", driver.name(), p.id());
            let run = Prepared::new(p);
            let packed = gles2.render(&run).unwrap_or_else(|e| panic!("{id}: {e}"));
            let d24 = gles3.render(&run).unwrap_or_else(|e| panic!("{id}: {e}"));
            let j2 = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, gles2.profile());
            let j3 = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, gles3.profile());
            let r = umbra_compare::reference::judge_pair(&packed, &j2, &d24, &j3);
            println!(
                "{id}: GLES 2 packed RGBA8 vs GLES 3 D24: {} of {} px differ ({}; {} illegal)",
                r.differ,
                r.compared,
                r.legal_summary(),
                r.illegal
            );
            assert_eq!(
                r.illegal, 0,
                "{id}: packed depth and D24 differ beyond the packing's precision"
            );
        }
    }
}

#[test]
fn a_driver_this_process_did_not_load_is_unavailable_with_the_environment_to_set() {
    // This process was not started with softpipe's environment (the variants test starts its
    // own children for that), so asking for softpipe here must say how to get it.
    if std::env::var("GALLIUM_DRIVER").is_ok() {
        return; // inside a driver worker: not this test's situation
    }
    let Err(e) = GlBackend::new(Api::Gl33, Driver::Softpipe) else {
        panic!("softpipe cannot load in an llvmpipe process")
    };
    assert!(e.0.contains("GALLIUM_DRIVER=softpipe"), "{}", e.0);
}
