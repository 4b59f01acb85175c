//! Golden images through insta: `golden/` is insta's snapshot directory, one binary PNG
//! snapshot per case point and backend, in one folder per backend
//! (`golden/<backend>/<stem>.snap` + `.snap.png`, see [`folder`] and [`stem`]).
//!
//! A result within tolerance of its golden passes without insta (which would compare the
//! golden's own bytes with themselves; its clean-up of the snapshot's pending files is done by
//! name), so an unchanged picture never churns the file. A result outside it hands its new
//! bytes to insta, which records a pending snapshot for `cargo insta review` and fails the
//! run. A missing golden is a change too, on the release the backend's goldens were blessed
//! on; on another, a run with no golden on any release that the judge passes is a new
//! picture (a feature the new release runs that the old one skipped), reported as a changed
//! picture and not failed: the CI on the blessed release still fails a golden that was
//! deleted or never blessed. Under `CI=true` insta is not called at all and
//! nothing under `golden/` is created, changed or deleted (pending files included): a change
//! fails the run and says how to review it locally.
//!
//! Who may write a golden is umbra's decision, not the environment's: workers get insta's
//! environment from [`insta_env`] only (every inherited `INSTA_*` variable is removed and the
//! run says it ignored it), so `INSTA_UPDATE=always` or `INSTA_FORCE_PASS=1` in a shell or a
//! CI file can neither write nor pass a golden. `cargo xtask bless` runs `umbra conformance
//! --bless` (refused under `CI=true`), which alone sets `INSTA_UPDATE=always`, and lists what
//! it wrote.
//!
//! **Goldens across driver releases.** A golden is strict on the Mesa release it was blessed
//! on and lets the judge speak on any other, the way Mesa's trace CI keeps one checksum per
//! device:
//! - `golden/blessed-on.json` records the release each backend's goldens were first blessed
//!   on, and per golden written since on another, that golden's.
//! - `golden/mesa-RELEASE/` holds a release's own pictures, only those that differ from the
//!   golden of the release they were blessed on ([`held`]): a new release records what
//!   differs, not a second copy of everything. Blessing on a release never overwrites another
//!   release's golden.
//! - A bless on a release (`cargo xtask bless --mesa DIR`) confirms there every golden of
//!   another release it compared and found unchanged (`mesa-RELEASE/confirmed.txt`: stem and
//!   hash), so those hold strictly on it too, for as long as they are the goldens it
//!   confirmed ([`confirmed`]).
//! - On a release where its golden is not strict, a picture that differs is judged pixel by
//!   pixel ([`check`]): where every changed pixel is one the judge holds legal on this driver,
//!   it is a changed picture (`changed-legal`), reported with both versions (terminal,
//!   goldens.csv, report.html) and not failed; where some changed pixels are illegal, the
//!   judge's own checks fail the run there (`changed-judged`: the golden adds nothing); only a
//!   change where the judge does not look (alpha, the frame's size) fails the golden
//!   check, with both versions named. So a Mesa developer's CI on main is green when the
//!   driver is right, and every spec-legal change is still visible.
//!
//! Tolerance (the same backend on another day): each 8-bit colour channel may differ by one
//! step (the output's rounding), except on pixels where the judge already allows the shadow
//! answer itself to differ (the reference agreement's legal pixels: ties, texel boundaries,
//! filter freedom, edges, silhouettes, faces away). Anything else is a change to review.

use std::path::Path;

use umbra_case::Frame;

pub use crate::judge::blessings::{
    Held, MANIFEST, Subject, blessed_on, check_confirmed, check_manifest, confirmed, folder,
    has_goldens, held, record_blessed, record_confirmed, release, release_dir, same_release, stem,
};

/// What happened to a run's golden.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Golden {
    /// Within tolerance of the golden.
    Unchanged,
    /// Different (or new) and written by insta (`INSTA_UPDATE=always`, i.e. blessing) into the
    /// golden directory itself.
    Written,
    /// Different from a golden blessed on another Mesa release and written (blessing) as
    /// this release's golden, `mesa-RELEASE/` beside the old one, which stays.
    WrittenForRelease,
    /// Different (or new) and left for review (or refused under CI): a failure.
    Changed,
    /// Different from a golden blessed on another Mesa release (or no golden on any release
    /// yet), and every pixel that differs is one the judge holds legal on this driver: not a
    /// failure, reported as a changed picture with both versions
    /// ([`umbra_report::GoldenChange`]).
    ChangedLegal,
    /// Different from a golden blessed on another Mesa release, and every pixel that differs
    /// is one the judge compared, some of them illegal: the judge's own checks fail the run
    /// there (value, coverage, colour; an expectation may name that failure, as on the
    /// golden's release), so the golden adds no failure of its own; reported with both
    /// versions.
    ChangedJudged,
}

impl Golden {
    /// The word reports use (`RunResult::golden`).
    pub fn word(self, foreign: bool) -> &'static str {
        match self {
            Golden::Unchanged => "unchanged",
            Golden::Written => "written",
            Golden::WrittenForRelease => "written-for-release",
            Golden::Changed if foreign => "changed-other-driver",
            Golden::Changed => "changed",
            Golden::ChangedLegal => "changed-legal",
            Golden::ChangedJudged => "changed-judged",
        }
    }
}

/// Encodes a frame's colour as PNG.
pub fn png(frame: &Frame) -> Vec<u8> {
    let mut out = Vec::new();
    let enc = image::codecs::png::PngEncoder::new(&mut out);
    let _ = image::ImageEncoder::write_image(
        enc,
        &frame.color,
        frame.width,
        frame.height,
        image::ExtendedColorType::Rgba8,
    );
    out
}

/// A golden check's outcome.
pub struct Checked {
    /// What happened to the golden.
    pub golden: Golden,
    /// Why it changed (empty when it did not).
    pub message: String,
    /// SSIM of the frame's colour against the golden's, where there is one.
    pub ssim: Option<f64>,
    /// Whether the frame's colour is the golden's, pixel for pixel (its PNG is the golden's
    /// file).
    pub identical: bool,
    /// The golden that held, and where a pending one would be (the gallery shows both).
    pub held: Held,
    /// For a picture that differs from its golden: how, and between which versions.
    pub change: Option<umbra_report::GoldenChange>,
}

/// How `frame` differs from golden `img` (same size): pixels with a channel more than one
/// step apart, the largest step, how many of those the judge found illegal, and how many it
/// did not compare (the background, whose RGB it holds to the clear colour but whose alpha
/// only the golden sees).
fn difference(
    img: &image::RgbaImage,
    frame: &Frame,
    judged: &[umbra_compare::reference::PixelJudgement],
) -> (u64, u8, u64, u64) {
    use umbra_compare::reference::PixelJudgement;
    let (mut pixels, mut step, mut illegal, mut unjudged) = (0u64, 0u8, 0u64, 0u64);
    for (i, (g, f)) in img
        .as_raw()
        .chunks_exact(4)
        .zip(frame.color.chunks_exact(4))
        .enumerate()
    {
        let d = g
            .iter()
            .zip(f)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        if d <= 1 {
            continue;
        }
        pixels += 1;
        step = step.max(d);
        match judged.get(i) {
            Some(PixelJudgement::Illegal) => illegal += 1,
            None | Some(PixelJudgement::NotCompared) => unjudged += 1,
            Some(_) => {}
        }
    }
    (pixels, step, illegal, unjudged)
}

/// Checks `frame`'s colour against the golden that holds for `run` in `dir` ([`held`]).
/// `legal`: the pixels where the judge allows the shadow itself to differ (the tolerance on
/// the golden's own release); `judged`: each pixel's judgement (which pixels a change on
/// another release may touch); `judge_passed`: whether the run broke nothing the specs
/// allow (a missing golden on another release is then a new picture, not a failure).
pub fn check(
    dir: &Path,
    run: &Subject,
    frame: &Frame,
    legal: &[bool],
    judged: &[umbra_compare::reference::PixelJudgement],
    judge_passed: bool,
) -> Checked {
    let held = held(dir, run);
    let seen = match Seen::read(&held, frame, legal) {
        Ok(seen) => seen,
        Err(message) => {
            return Checked {
                golden: Golden::Changed,
                message,
                ssim: None,
                identical: false,
                held,
                change: None,
            };
        }
    };
    let stem = stem(run.name);
    let ci = under_ci();
    let snap_of = |d: &Path| d.join(format!("{stem}.snap"));
    let read_dir = held
        .file
        .as_ref()
        .and_then(|f| f.parent())
        .map_or_else(|| held.write_dir.clone(), Path::to_path_buf);
    if seen.within && snap_of(&read_dir).is_file() {
        // insta would be handed the golden's own bytes and find them equal: a pass that
        // writes nothing, at the price of reading the snapshot again and listing the whole
        // golden directory (its clean-up of this snapshot's pending files, done here by name;
        // never under CI, which changes nothing under golden/).
        if !ci {
            for pending in [format!("{stem}.snap.new"), format!("{stem}.snap.new.png")] {
                let _ = std::fs::remove_file(held.write_dir.join(pending));
            }
        }
        return Checked {
            golden: Golden::Unchanged,
            message: String::new(),
            ssim: seen.ssim,
            identical: seen.identical,
            held,
            change: None,
        };
    }
    let change = seen.change(&held, run, frame, judged, judge_passed);
    let (golden, message) = if ci {
        seen.refused_under_ci(&held, run, &change)
    } else {
        seen.handed_to_insta(&held, run, frame, &change)
    };
    Checked {
        golden,
        message,
        ssim: seen.ssim,
        identical: seen.identical,
        held,
        change: Some(change),
    }
}

/// What a golden check saw: the golden's bytes and picture, and how the frame compares.
struct Seen {
    /// The golden file's bytes, where there is one.
    existing: Option<Vec<u8>>,
    /// The golden's picture.
    decoded: Option<image::RgbaImage>,
    /// The golden and the frame are the same size.
    same_size: bool,
    /// Pixel for pixel the golden.
    identical: bool,
    /// SSIM against the golden.
    ssim: Option<f64>,
    /// Within the tolerance: one step per channel, or a pixel the judge holds legal.
    within: bool,
}

impl Seen {
    /// Reads the golden that held and compares `frame` with it; `Err` with the message for a
    /// golden that is there but cannot be decoded (a damaged file, a merge conflict's markers,
    /// a Git LFS pointer): never "differs", never a new picture that a release other than the
    /// golden's would report as legal. Blessing replaces it (as if there were none): what its
    /// message says to do.
    fn read(held: &Held, frame: &Frame, legal: &[bool]) -> Result<Seen, String> {
        let existing = held.file.as_ref().and_then(|f| std::fs::read(f).ok());
        let decoding = existing.as_deref().map(image::load_from_memory);
        let blessing = std::env::var("INSTA_UPDATE").is_ok_and(|v| v == "always");
        if let (Some(Err(e)), Some(file), false) = (&decoding, &held.file, blessing) {
            return Err(format!(
                "the golden {} cannot be decoded as a PNG ({e}): a damaged file; restore it (`git checkout -- {}`), or bless again after review",
                file.display(),
                file.display()
            ));
        }
        let decoded = decoding.and_then(Result::ok).map(|i| i.to_rgba8());
        let same_size = decoded
            .as_ref()
            .is_some_and(|img| img.dimensions() == (frame.width, frame.height));
        let identical = same_size
            && decoded
                .as_ref()
                .is_some_and(|img| *img.as_raw() == frame.color);
        let ssim = decoded.as_ref().and_then(|img| {
            // A frame identical to its golden (the usual regression run) is at SSIM 1 by
            // definition; the windowed computation is most of a golden check's time.
            if identical {
                return Some(1.0);
            }
            let golden = Frame {
                width: img.width(),
                height: img.height(),
                color: img.as_raw().clone(),
                ..frame.clone()
            };
            umbra_compare::ssim(&golden, frame)
        });
        let within = same_size
            && decoded.as_ref().is_some_and(|img| {
                img.as_raw()
                    .chunks_exact(4)
                    .zip(frame.color.chunks_exact(4))
                    .enumerate()
                    .all(|(i, (g, f))| {
                        legal.get(i).copied().unwrap_or(false)
                            || g.iter().zip(f).all(|(a, b)| a.abs_diff(*b) <= 1)
                    })
            });
        Ok(Seen {
            existing,
            decoded,
            same_size,
            identical,
            ssim,
            within,
        })
    }

    /// Outside the tolerance, or no golden: how the picture changed. On a release the golden
    /// was not blessed on, the judge decides every pixel it compared: a change there is legal
    /// (reported, never failed: the driver's choice inside the spec) or illegal (failed by
    /// its own checks); only a change where it did not look (alpha, a resized
    /// frame) is the golden's to fail.
    fn change(
        &self,
        held: &Held,
        run: &Subject,
        frame: &Frame,
        judged: &[umbra_compare::reference::PixelJudgement],
        judge_passed: bool,
    ) -> umbra_report::GoldenChange {
        let area = u64::from(frame.width) * u64::from(frame.height);
        let (pixels, max_step, illegal, unjudged) = match (&self.decoded, self.same_size) {
            (Some(img), true) => difference(img, frame, judged),
            // A new picture: the judge speaks for every pixel it compared.
            (None, _) => (area, 255, u64::from(!judge_passed), 0),
            (Some(_), false) => (area, 255, 0, area),
        };
        let mut change = umbra_report::GoldenChange {
            blessed_on: held.blessed_on.clone(),
            driver: run.driver.map(str::to_string),
            pixels,
            max_step,
            new: self.decoded.is_none(),
            illegal,
            unjudged,
            strict: held.strict,
            legal: false,
        };
        change.legal = Seen::judged(&change) && illegal == 0;
        change
    }

    /// Whether the judge decides this change (off the golden's release, every changed pixel
    /// one it compared).
    fn judged(change: &umbra_report::GoldenChange) -> bool {
        !change.strict && change.unjudged == 0
    }

    /// What a change the judge decides is reported as.
    fn reported(change: &umbra_report::GoldenChange) -> Golden {
        if change.legal {
            Golden::ChangedLegal
        } else {
            Golden::ChangedJudged
        }
    }

    /// "differs from its golden" or "has no golden yet".
    fn what(&self) -> &'static str {
        if self.existing.is_some() {
            "differs from its golden"
        } else {
            "has no golden yet"
        }
    }

    /// The versions a change is between, where the golden's is not this driver's.
    fn versions(held: &Held, run: &Subject) -> String {
        match (&held.blessed_on, run.driver) {
            (Some(b), Some(h)) if !held.strict => format!(
                "; this golden was blessed on Mesa {b} and this driver is Mesa {h}: the difference may be the driver's change between them (compare the two with `cargo xtask drivers`, and bless on this version only after review)"
            ),
            _ => String::new(),
        }
    }

    /// Under CI nothing is written: a change the judge decides is what it says; any other
    /// fails and says how to review it locally.
    fn refused_under_ci(
        &self,
        held: &Held,
        run: &Subject,
        change: &umbra_report::GoldenChange,
    ) -> (Golden, String) {
        if Seen::judged(change) {
            return (Seen::reported(change), change.describe());
        }
        (
            Golden::Changed,
            format!(
                "the colour image {}{}; CI=true: nothing written; run `cargo xtask bless` or `cargo insta review` locally and commit the result{}",
                self.what(),
                if change.new {
                    String::new()
                } else {
                    format!(" ({})", change.pixels_phrase())
                },
                Seen::versions(held, run)
            ),
        )
    }

    /// Outside CI the new picture goes to insta (into `held.write_dir`: the backend's folder,
    /// or this release's own where the golden is another release's): written when blessing,
    /// pending for review otherwise; what happened, and the words for it.
    fn handed_to_insta(
        &self,
        held: &Held,
        run: &Subject,
        frame: &Frame,
        change: &umbra_report::GoldenChange,
    ) -> (Golden, String) {
        let stem = stem(run.name);
        let bytes = match (&self.existing, self.within) {
            (Some(b), true) => b.clone(),
            _ => png(frame),
        };
        let outcome = snapshot(&held.write_dir, &stem, run.name, bytes);
        // What insta should have left: the written golden, or the pending snapshot a review
        // reads. Where it is not there (a read-only golden directory, a full disk), the run
        // says the golden could not be written, never that a snapshot it cannot find is
        // pending.
        let left = match (&outcome, self.within) {
            (Ok(()), true) => None,
            (Ok(()), false) => Some(held.write_dir.join(format!("{stem}.snap"))),
            (Err(()), _) => Some(held.write_dir.join(format!("{stem}.snap.new"))),
        };
        let unwritten = left.filter(|f| !f.is_file()).map(|file| {
            format!(
                "its golden could not be written: {} ({}); make the golden directory writable and run again",
                file.display(),
                unwritable(&held.write_dir)
            )
        });
        let (what, versions) = (self.what(), Seen::versions(held, run));
        let judged_change = Seen::judged(change);
        match (outcome, self.within) {
            // A change the judge decides (on a release other than the golden's) stays what the
            // judge says it is; anything else fails, saying the write failed.
            (Err(()), _) if judged_change && unwritten.is_some() => (
                Seen::reported(change),
                format!("{}; {}", change.describe(), unwritten.unwrap_or_default()),
            ),
            _ if unwritten.is_some() => (
                Golden::Changed,
                format!(
                    "the colour image {what}, and {}{versions}",
                    unwritten.unwrap_or_default()
                ),
            ),
            (Ok(()), true) => (Golden::Unchanged, String::new()),
            (Ok(()), false) if held.release.is_some() => (
                Golden::WrittenForRelease,
                format!(
                    "golden {stem} written for Mesa {} in {}",
                    held.release.as_deref().unwrap_or_default(),
                    held.write_dir.display()
                ),
            ),
            (Ok(()), false) => (Golden::Written, format!("golden {stem} written")),
            (Err(()), _) if judged_change => (
                Seen::reported(change),
                format!(
                    "{}; pending as this release's golden: {}/{stem}.snap.new (`cargo insta review` or `cargo xtask bless`)",
                    change.describe(),
                    held.write_dir.display()
                ),
            ),
            (Err(()), _) => {
                let how = format!(
                    "review it with `cargo insta review` (pending {}/{stem}.snap.new) or accept all with `cargo xtask bless`",
                    held.write_dir.display()
                );
                (
                    Golden::Changed,
                    format!("the colour image {what}; {how}{versions}"),
                )
            }
        }
    }
}

/// Hands `bytes` to insta as run `name`'s golden `stem` in `dir`: `Ok` when it matched or was
/// written (blessing), `Err` when insta left a pending snapshot (or failed to). insta reports
/// a mismatch by panicking: that panic (and, with RUST_BACKTRACE set, its backtrace) is kept
/// off the output; the run's reason says what happened and how to review it, in one line. The
/// hook is global, and workers render on one thread.
fn snapshot(dir: &Path, stem: &str, name: &str, bytes: Vec<u8>) -> Result<(), ()> {
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(dir);
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.set_description(format!("umbra golden: colour of {name}"));
    let name_ext = format!("{stem}.png");
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        settings.bind(|| insta::assert_binary_snapshot!(name_ext.as_str(), bytes.clone()));
    }));
    std::panic::set_hook(hook);
    outcome.map_err(|_| ())
}

/// Why nothing could be written in `dir`, as far as a probe file can tell.
fn unwritable(dir: &Path) -> String {
    let probe = dir.join(format!(".umbra-probe-{}", std::process::id()));
    match std::fs::write(&probe, b"") {
        Ok(()) => {
            let _ = std::fs::remove_file(&probe);
            "insta wrote nothing there".into()
        }
        Err(e) => e.to_string(),
    }
}

/// What a backend without goldens is judged by, in the terminal, drivers.txt and the report.
pub const NONE_FOR_BACKEND: &str =
    "no goldens for this backend: judged by the specs and the reference";

/// Whether this process runs under CI: `CI` set to anything but empty, `0`, `false`, `no` or
/// `off` (any case). CI systems set `true`, `1` or `True` (AppVeyor); reading only `true` and
/// `1` let `CI=True` bless goldens in CI.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        !matches!(
            v.to_ascii_lowercase().as_str(),
            "" | "0" | "false" | "no" | "off"
        )
    })
}

/// The insta variables this process inherited ([`controls_insta`], `NAME=VALUE`): each is
/// removed from every worker's environment and named in a note by the runner.
pub fn inherited_insta() -> Vec<String> {
    std::env::vars_os()
        .filter_map(|(k, v)| {
            let k = k.into_string().ok()?;
            controls_insta(&k).then(|| format!("{k}={}", v.to_string_lossy()))
        })
        .collect()
}

/// Whether an environment variable steers insta (every `INSTA_*` but
/// `INSTA_WORKSPACE_ROOT`, which only saves insta a `cargo metadata` call per worker: the
/// workspace's `.cargo/config.toml` sets it, and it neither writes nor passes a golden;
/// insta's settings from its config file are all overridden by [`insta_env`]).
pub fn controls_insta(name: &str) -> bool {
    name.starts_with("INSTA_") && name != "INSTA_WORKSPACE_ROOT"
}

/// insta's whole environment in a worker: review snapshots (`.snap.new`) normally, write
/// goldens only when `bless`, nothing under CI (where insta is not called anyway); never
/// force a pass or an update; its own summary off (the run's reason says it).
pub fn insta_env(bless: bool) -> Vec<(String, String)> {
    let update = if under_ci() {
        "no"
    } else if bless {
        "always"
    } else {
        "new"
    };
    [
        ("INSTA_UPDATE", update),
        ("INSTA_FORCE_PASS", "0"),
        ("INSTA_FORCE_UPDATE", "0"),
        ("INSTA_OUTPUT", "none"),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect()
}

#[cfg(test)]
mod release_tests {
    use super::*;
    use umbra_compare::reference::PixelJudgement;

    fn frame(color: [u8; 4]) -> Frame {
        Frame {
            width: 4,
            height: 2,
            color: color.repeat(8),
            lights: vec![umbra_case::LightPlane {
                visibility: vec![1.0; 8],
                surface: None,
                shadow_map: None,
            }],
            visibility_storage: Default::default(),
            timings: Default::default(),
        }
    }

    /// A golden directory holding one golden of `gl33/llvmpipe/x`, blessed on Mesa 22.3.6.
    fn golden_dir(tag: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("umbra-golden-release-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let backend = dir.join(folder("gl33/llvmpipe"));
        std::fs::create_dir_all(&backend).expect("dir");
        let stem = stem("gl33/llvmpipe/x");
        std::fs::write(
            backend.join(format!("{stem}.snap")),
            "---\nsource: umbra\n---\n",
        )
        .expect("snap");
        std::fs::write(
            backend.join(format!("{stem}.snap.png")),
            png(&frame([10, 10, 10, 255])),
        )
        .expect("png");
        record_blessed(&dir, &[("gl33/llvmpipe".into(), "22.3.6".into())]).expect("manifest");
        dir
    }

    fn run(driver: &str) -> Subject<'_> {
        Subject {
            backend: "gl33/llvmpipe",
            name: "gl33/llvmpipe/x",
            driver: Some(driver),
        }
    }

    /// The judge's verdict on each pixel: pixel 0 as `first`, the rest legal.
    fn judged(first: PixelJudgement) -> Vec<PixelJudgement> {
        let mut j = vec![PixelJudgement::Agrees; 8];
        j[0] = first;
        j
    }

    #[test]
    fn a_change_on_another_release_is_reported_when_the_judge_holds_it_legal() {
        let dir = golden_dir("legal");
        let changed = frame([30, 10, 10, 255]);
        let legal = judged(PixelJudgement::LegalDifference);
        // On the release it was blessed on, the golden is strict.
        let same = check(&dir, &run("22.3.6-1"), &changed, &[], &legal, true);
        assert_eq!(same.golden, Golden::Changed);
        // On another, a change the judge holds legal everywhere is reported, not failed.
        let other = check(&dir, &run("26.2.6-1"), &changed, &[], &legal, true);
        assert_eq!(other.golden, Golden::ChangedLegal, "{}", other.message);
        let c = other.change.expect("the change is described");
        assert_eq!((c.pixels, c.max_step, c.legal), (8, 20, true));
        assert_eq!(c.blessed_on.as_deref(), Some("22.3.6"));
        assert!(c.describe().contains("22.3.6") && c.describe().contains("26.2.6-1"));
        // Where the judge found the changed pixel illegal, its own checks fail the run.
        let illegal = check(
            &dir,
            &run("26.2.6-1"),
            &changed,
            &[],
            &judged(PixelJudgement::Illegal),
            false,
        );
        assert_eq!(illegal.golden, Golden::ChangedJudged);
        // A change where the judge does not look (the background) is the golden's to fail.
        let background = check(
            &dir,
            &run("26.2.6-1"),
            &changed,
            &[],
            &judged(PixelJudgement::NotCompared),
            true,
        );
        assert_eq!(background.golden, Golden::Changed);
        assert!(background.message.contains("blessed on Mesa 22.3.6"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_release_golden_and_a_confirmation_hold_strictly_on_their_release() {
        let dir = golden_dir("strict");
        let stem = stem("gl33/llvmpipe/x");
        let new = frame([30, 10, 10, 255]);
        let legal = judged(PixelJudgement::LegalDifference);
        // This release's own golden: read from mesa-26.2.6/, strict, and the base untouched.
        let own = release_dir(&dir, "26.2.6-1").join(folder("gl33/llvmpipe"));
        std::fs::create_dir_all(&own).expect("release dir");
        std::fs::write(own.join(format!("{stem}.snap")), "---\n---\n").expect("snap");
        std::fs::write(own.join(format!("{stem}.snap.png")), png(&new)).expect("png");
        let held_there = held(&dir, &run("26.2.6-2"));
        assert!(held_there.strict && held_there.write_dir == own);
        assert_eq!(
            check(&dir, &run("26.2.6-2"), &new, &[], &legal, true).golden,
            Golden::Unchanged
        );
        let other = frame([60, 10, 10, 255]);
        assert_eq!(
            check(&dir, &run("26.2.6-2"), &other, &[], &legal, true).golden,
            Golden::Changed
        );
        // Another release without a golden of its own: lenient, and never writes the base.
        let lenient = held(&dir, &run("26.1.6"));
        assert!(!lenient.strict);
        assert_eq!(
            lenient.write_dir,
            release_dir(&dir, "26.1.6").join("gl33_llvmpipe")
        );
        // A bless on 26.1.6 that compared the golden and found it unchanged confirms it
        // there: strict from then on, until the golden changes.
        let base = dir.join("gl33_llvmpipe").join(format!("{stem}.snap.png"));
        record_confirmed(&dir, "26.1.6", &[(stem.clone(), base.clone())]).expect("confirm");
        let text = std::fs::read_to_string(release_dir(&dir, "26.1.6").join("confirmed.txt"))
            .expect("confirmed.txt");
        assert!(text.starts_with(&format!("{stem} ")), "{text}");
        assert!(confirmed(&dir, &stem, &base, "26.1.6-1"));
        assert!(held(&dir, &run("26.1.6-1")).strict);
        std::fs::write(&base, png(&other)).expect("png");
        assert!(
            !confirmed(&dir, &stem, &base, "26.1.6-1"),
            "a changed golden no longer matches its confirmation"
        );
        assert!(!held(&dir, &run("26.1.6-1")).strict);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn releases_ignore_packaging() {
        assert_eq!(release("26.2.6-1"), "26.2.6");
        assert_eq!(release("25.0.7-2~bpo12+1"), "25.0.7");
        assert!(release_dir(Path::new("golden"), "26.2.6-1").ends_with("mesa-26.2.6"));
    }
}
