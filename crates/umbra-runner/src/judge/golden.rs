//! Golden images through insta: `golden/` is insta's snapshot directory, one binary PNG
//! snapshot per case point and backend (`golden/<stem>.snap` + `.snap.png`, see [`stem`]).
//!
//! A result within tolerance of its golden passes without insta (which would compare the
//! golden's own bytes with themselves; its clean-up of the snapshot's pending files is done by
//! name), so an unchanged picture never churns the file. A result outside it hands its new
//! bytes to insta, which records a pending snapshot for `cargo insta review` and fails the
//! run. A missing golden is a change too. Under `CI=true` insta is not called at all and
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
//! Goldens stay per backend id; `golden/blessed-on.json` records the Mesa version goldens were
//! blessed on (`cargo xtask bless` writes it): per backend, the version its goldens were first
//! blessed on, and per golden written since, that golden's (so one golden blessed on a newer
//! Mesa, for a feature the older one skips, does not relabel the rest). A run on another
//! version (`--mesa`, or a distribution upgrade) compares as always and a difference still
//! fails, but its reason says plainly that the golden was blessed on another version ("blessed
//! on Mesa 22.3.6, this driver is Mesa 25.0.7"), because the likeliest cause is then the
//! driver's change, not umbra's; `cargo xtask drivers` shows the two builds side by side.
//!
//! Tolerance (the same backend on another day): each 8-bit colour channel may differ by one
//! step (the output's rounding), except on pixels where the judge already allows the shadow
//! answer itself to differ (the reference agreement's legal pixels: ties, texel boundaries,
//! filter freedom, edges, silhouettes, faces away). Anything else is a change to review.

use std::path::Path;

use umbra_case::Frame;

/// What happened to a run's golden.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Golden {
    /// Within tolerance of the golden.
    Unchanged,
    /// Different (or new) and written by insta (`INSTA_UPDATE=always`, i.e. blessing).
    Written,
    /// Different (or new) and left for review (or refused under CI): a failure.
    Changed,
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

/// The golden's file stem for run `name`: letters, digits, `-` and `_` only (insta reads the
/// first `.` as the start of the extension), then a 32-bit FNV-1a hash of the full name so
/// that ids differing only in punctuation stay apart.
pub fn stem(name: &str) -> String {
    let plain: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{plain}-{:08x}", umbra_report::names::fnv1a(name))
}

/// Checks `frame` against golden `name` in `dir`; `legal[i]` marks pixels where a shadow
/// difference is legal (empty: none). Returns what happened, a message for a change, and the
/// SSIM of the colour against the golden where one exists.
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
}

/// Checks `frame`'s colour against run `name`'s golden in `dir` (`legal`: the pixels where the
/// judge allows the shadow itself to differ).
pub fn check(dir: &Path, name: &str, frame: &Frame, legal: &[bool]) -> Checked {
    let stem = stem(name);
    let existing = std::fs::read(dir.join(format!("{stem}.snap.png"))).ok();
    let decoded = existing
        .as_deref()
        .and_then(|bytes| image::load_from_memory(bytes).ok())
        .map(|i| i.to_rgba8());
    let identical = decoded.as_ref().is_some_and(|img| {
        img.dimensions() == (frame.width, frame.height) && *img.as_raw() == frame.color
    });
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
    let within = decoded.is_some_and(|img| {
        img.dimensions() == (frame.width, frame.height)
            && img
                .as_raw()
                .chunks_exact(4)
                .zip(frame.color.chunks_exact(4))
                .enumerate()
                .all(|(i, (g, f))| {
                    legal.get(i).copied().unwrap_or(false)
                        || g.iter().zip(f).all(|(a, b)| a.abs_diff(*b) <= 1)
                })
    });
    let ci = under_ci();
    if within && dir.join(format!("{stem}.snap")).is_file() {
        // insta would be handed the golden's own bytes and find them equal: a pass that
        // writes nothing, at the price of reading the snapshot again and listing the whole
        // golden directory (its clean-up of this snapshot's pending files, done here by name;
        // never under CI, which changes nothing under golden/).
        if !ci {
            for pending in [format!("{stem}.snap.new"), format!("{stem}.snap.new.png")] {
                let _ = std::fs::remove_file(dir.join(pending));
            }
        }
        return Checked {
            golden: Golden::Unchanged,
            message: String::new(),
            ssim,
            identical,
        };
    }
    if ci {
        let what = if existing.is_some() {
            "differs from its golden"
        } else {
            "has no golden yet"
        };
        return Checked {
            golden: Golden::Changed,
            message: format!(
                "the colour image {what}; CI=true: nothing written; run `cargo xtask bless` or `cargo insta review` locally and commit the result"
            ),
            ssim,
            identical,
        };
    }
    let bytes = match (&existing, within) {
        (Some(b), true) => b.clone(),
        _ => png(frame),
    };
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(dir);
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.set_description(format!("umbra golden: colour of {name}"));
    let name_ext = format!("{stem}.png");
    // insta reports a mismatch by panicking: keep that panic (and, with RUST_BACKTRACE set,
    // its backtrace) off the output; the run's reason says what happened and how to review
    // it, in one line. The hook is global, and workers render on one thread.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        settings.bind(|| insta::assert_binary_snapshot!(name_ext.as_str(), bytes.clone()));
    }));
    std::panic::set_hook(hook);
    let (golden, message) = match (outcome, within) {
        (Ok(()), true) => (Golden::Unchanged, String::new()),
        (Ok(()), false) => (Golden::Written, format!("golden {stem} written")),
        (Err(_), _) => {
            let what = if existing.is_some() {
                "differs from its golden"
            } else {
                "has no golden yet"
            };
            let how = format!(
                "review it with `cargo insta review` (pending {}/{stem}.snap.new) or accept all with `cargo xtask bless`",
                dir.display()
            );
            (Golden::Changed, format!("the colour image {what}; {how}"))
        }
    };
    Checked {
        golden,
        message,
        ssim,
        identical,
    }
}

/// Whether this process runs under CI (`CI=true` or `CI=1`, as CI systems set it).
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
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

/// The manifest of driver versions the goldens were blessed on, in the golden directory.
pub const MANIFEST: &str = "blessed-on.json";

/// The key of [`MANIFEST`] that holds the checksum of its other entries.
const MANIFEST_SUM: &str = "#fnv1a64";

/// The manifest's entries, if it is there and whole: its checksum (64-bit FNV-1a of the
/// other entries as compact JSON, keys sorted) must match. `Err` says what is wrong.
fn manifest(dir: &Path) -> Result<Option<std::collections::BTreeMap<String, String>>, String> {
    let path = dir.join(MANIFEST);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot be read ({e})")),
    };
    let mut map: std::collections::BTreeMap<String, String> =
        serde_json::from_str(&text).map_err(|e| format!("is not a JSON map of strings ({e})"))?;
    let Some(sum) = map.remove(MANIFEST_SUM) else {
        return Err(format!("has no \"{MANIFEST_SUM}\" entry"));
    };
    let want = manifest_sum(&map);
    if sum != want {
        return Err(format!(
            "fails its checksum (\"{MANIFEST_SUM}\": {sum:?}, its entries give {want:?}): edited by hand or damaged"
        ));
    }
    Ok(Some(map))
}

fn manifest_sum(map: &std::collections::BTreeMap<String, String>) -> String {
    let text = serde_json::to_string(map).unwrap_or_default();
    let h = text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{h:016x}")
}

/// Checks [`MANIFEST`] in `dir` once for a run: `Some(warning)` when it is there but damaged
/// (its versions are then not used: a golden blessed on another driver is judged as any
/// other, without the version note).
pub fn check_manifest(dir: &Path) -> Option<String> {
    manifest(dir).err().map(|why| {
        format!(
            "warning: {} {why}; its driver versions are not used; restore it from git, or rewrite it with `cargo xtask bless`",
            dir.join(MANIFEST).display()
        )
    })
}

/// The Mesa version the golden of run `name` on backend `id` was blessed on, if recorded: the
/// golden's own entry (written when that golden was written), else the backend's (the
/// version the backend's goldens were first blessed on). Nothing from a damaged manifest
/// ([`check_manifest`] says so once per run).
pub fn blessed_on(dir: &Path, id: &str, name: &str) -> Option<String> {
    let map = manifest(dir).ok()??;
    map.get(&stem(name)).or(map.get(id)).cloned()
}

/// Records blessings: `(key, version)` where the key is a golden's stem (that golden was
/// written on that version) or a backend id (set only if the backend has no entry yet). Keeps
/// every other entry of a whole manifest; leaves the file untouched when nothing changes.
/// The checksum is written with the entries.
pub fn record_blessed(dir: &Path, entries: &[(String, String)]) -> std::io::Result<()> {
    let path = dir.join(MANIFEST);
    let mut map = manifest(dir).ok().flatten().unwrap_or_default();
    for (key, v) in entries {
        if key.contains('/') {
            map.entry(key.clone()).or_insert_with(|| v.clone());
        } else {
            map.insert(key.clone(), v.clone());
        }
    }
    let sum = manifest_sum(&map);
    map.insert(MANIFEST_SUM.to_string(), sum);
    let text = serde_json::to_string_pretty(&map).unwrap_or_default() + "\n";
    if std::fs::read_to_string(&path).is_ok_and(|t| t == text) {
        return Ok(());
    }
    crate::atomic_file::write(&path, text.as_bytes())
}

/// What a backend without goldens is judged by, in the terminal, drivers.txt and the report.
pub const NONE_FOR_BACKEND: &str =
    "no goldens for this backend: judged by the specs and the reference";

/// Whether backend `id` has goldens in `dir`: the manifest names it (blessing records every
/// backend it wrote for), or a golden of one of its runs is there (the ids are told apart by
/// the name each snapshot records, not by the file stem, whose punctuation is flattened).
/// A device's backend without goldens (a device umbra has never seen) is judged by the specs
/// and the reference alone; `cargo xtask bless --backend ID` starts its goldens. This build's
/// own ids are never asked: a golden of theirs that is missing is a change to review.
pub fn has_goldens(dir: &Path, id: &str) -> bool {
    if manifest(dir)
        .ok()
        .flatten()
        .is_some_and(|m| m.contains_key(id))
    {
        return true;
    }
    let prefix = format!("{}_", stem(id).rsplit_once('-').map_or("", |(p, _)| p));
    let marker = format!("colour of {id}/");
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .any(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with(&prefix)
                && name.ends_with(".snap")
                && std::fs::read_to_string(e.path()).is_ok_and(|t| t.contains(&marker))
        })
}

/// Whether two Mesa versions are the same release for goldens (numeric parts only, so a
/// distribution's packaging suffix does not matter).
pub fn same_release(a: &str, b: &str) -> bool {
    crate::judge::expectations::version_parts(a) == crate::judge::expectations::version_parts(b)
}

#[cfg(test)]
mod manifest_tests {
    use super::*;

    #[test]
    fn the_committed_manifest_is_whole_and_a_damaged_one_is_refused() {
        let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../golden");
        assert_eq!(check_manifest(&golden), None);
        assert!(blessed_on(&golden, "gl33/llvmpipe", "gl33/llvmpipe/x").is_some());
        let dir = std::env::temp_dir().join(format!("umbra-manifest-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        record_blessed(&dir, &[("ref".into(), "1.0".into())]).expect("write");
        assert_eq!(check_manifest(&dir), None);
        assert_eq!(blessed_on(&dir, "ref", "ref/x").as_deref(), Some("1.0"));
        let path = dir.join(MANIFEST);
        let edited = std::fs::read_to_string(&path)
            .expect("manifest")
            .replace("1.0", "9.9");
        std::fs::write(&path, edited).expect("edit");
        assert!(check_manifest(&dir).is_some_and(|w| w.contains("fails its checksum")));
        assert_eq!(blessed_on(&dir, "ref", "ref/x"), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
