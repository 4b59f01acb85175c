//! The golden store's records (`golden/`, see [`crate::judge::golden`] for the check): one
//! folder per backend ([`folder`]: `golden/gl33_llvmpipe/`), each run's golden file name in it
//! ([`stem`]), the manifest of the Mesa releases goldens were blessed
//! on (`blessed-on.json`, checksummed), each release's own pictures (`mesa-RELEASE/`), the
//! confirmations a whole bless leaves (`BACKEND@RELEASE`), and from them which golden holds
//! for a run on a driver and how strictly ([`held`]).
//!
//! A golden is strict on the release it was blessed or confirmed on; on another, the check
//! lets the judge decide every pixel it compared. Blessing on a release never overwrites
//! another release's golden: its differing picture goes to that release's directory, so a
//! new release records what differs, not a second copy of everything.

use std::path::Path;

/// How many characters of a run's name its golden's stem keeps.
pub const STEM_PLAIN: usize = 160;

/// The golden's file stem for run `name`: letters, digits, `-` and `_` only (insta reads the
/// first `.` as the start of the extension), then a 32-bit FNV-1a hash of the full name so
/// that ids differing only in punctuation stay apart.
pub fn stem(name: &str) -> String {
    // At most STEM_PLAIN characters of the name (the hash is of the whole name, so stems
    // stay distinct): `STEM.snap.new.png` then fits in a file name (255 bytes) whatever the
    // length of the case's name and its sweep values.
    let plain = flat(&name.chars().take(STEM_PLAIN).collect::<String>());
    format!("{plain}-{:08x}", umbra_report::names::fnv1a(name))
}

/// `s` with every character other than ASCII letters, digits and `-` made `_`: a file name
/// part on every file system, with no `.` for insta to read as an extension.
fn flat(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The folder of backend `id`'s goldens, in the golden directory and in each release's
/// (`gl33/llvmpipe` → `gl33_llvmpipe`): one per backend, so a backend's goldens are reviewed,
/// blessed and deleted together, and a directory listing stays short.
pub fn folder(id: &str) -> String {
    flat(id)
}

/// The release a driver version belongs to for goldens: its numeric parts (`26.2.6-1` →
/// `26.2.6`), so a distribution's packaging suffix does not matter.
pub fn release(version: &str) -> String {
    crate::version::parts(version)
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(".")
}

/// The directory of release `version`'s goldens inside the golden directory: the pictures
/// that differ on that release from the golden blessed on another (`golden/mesa-26.2.6/`).
pub fn release_dir(dir: &Path, version: &str) -> std::path::PathBuf {
    dir.join(format!("mesa-{}", release(version)))
}

/// The run being checked: which golden and which driver.
pub struct Subject<'a> {
    /// The backend id.
    pub backend: &'a str,
    /// The run name.
    pub name: &'a str,
    /// The Mesa version the driver reports (none: not a Mesa driver, or the reference).
    pub driver: Option<&'a str>,
}

/// Where a run's golden is read and written, and how strictly it holds on this driver.
#[derive(Clone, Debug)]
pub struct Held {
    /// The golden file (`STEM.snap.png`), where one exists on any release.
    pub file: Option<std::path::PathBuf>,
    /// Where a new golden for this driver is written (and insta's pending snapshot): the
    /// golden directory, or the release directory when the golden was blessed on another
    /// release (which never overwrites the other release's golden).
    pub write_dir: std::path::PathBuf,
    /// The release whose own folder `write_dir` is (`mesa-RELEASE/BACKEND`), where it is one:
    /// a golden written there is this release's, beside the other release's.
    pub release: Option<String>,
    /// The Mesa version the golden was blessed on, where known.
    pub blessed_on: Option<String>,
    /// Whether this driver's release is one the golden was blessed or confirmed on
    /// ([`confirmed`]), or either version is unknown: then any difference outside the
    /// tolerance is a change to review. Otherwise the judge decides each changed pixel it
    /// compared ([`crate::judge::golden::check`]).
    pub strict: bool,
}

/// Which golden holds for `run` in `dir`: this release's own (`mesa-RELEASE/BACKEND/STEM`),
/// else the golden directory's (`BACKEND/STEM`); strict on the release it was blessed on or
/// confirmed on.
pub fn held(dir: &Path, run: &Subject) -> Held {
    let stem = stem(run.name);
    let folder = folder(run.backend);
    let file_in = |d: &Path| {
        let f = d.join(&folder).join(format!("{stem}.snap.png"));
        f.is_file().then_some(f)
    };
    let Some(driver) = run.driver else {
        return Held {
            file: file_in(dir),
            write_dir: dir.join(&folder),
            release: None,
            blessed_on: None,
            strict: true,
        };
    };
    let own = release_dir(dir, driver);
    if let Some(f) = file_in(&own) {
        return Held {
            file: Some(f),
            write_dir: own.join(&folder),
            release: Some(release(driver)),
            blessed_on: Some(release(driver)),
            strict: true,
        };
    }
    let base = file_in(dir);
    let blessed_on = blessed_on(dir, run.backend, run.name);
    let same = blessed_on
        .as_deref()
        .is_none_or(|b| same_release(b, driver));
    // A golden of another release is never overwritten from this one: this release's
    // differing picture goes beside it. A run with no golden anywhere starts one here.
    let (write_dir, release) = if base.is_some() && !same {
        (own.join(&folder), Some(release(driver)))
    } else {
        (dir.join(&folder), None)
    };
    let strict = same
        || base
            .as_deref()
            .is_some_and(|f| confirmed(dir, &stem, f, driver));
    Held {
        file: base,
        write_dir,
        release,
        blessed_on,
        strict,
    }
}

/// The manifest of driver versions the goldens were blessed on, in the golden directory.
pub const MANIFEST: &str = "blessed-on.json";

/// The key of [`MANIFEST`] that holds the checksum of its other entries.
const MANIFEST_SUM: &str = "#fnv1a64";

/// The manifest's entries, if it is there and whole: its checksum (64-bit FNV-1a of the
/// other entries as compact JSON, keys sorted) must match. `Err` says what is wrong.
pub(crate) fn manifest(
    dir: &Path,
) -> Result<Option<std::collections::BTreeMap<String, String>>, String> {
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
            "warning: {} {why}; its driver versions are not used; restore it from git (`git checkout -- {}`): a bless records nothing over it",
            dir.join(MANIFEST).display(),
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
/// The checksum is written with the entries. A damaged manifest is left as it is and the
/// bless's entries are refused: rewritten from what could be read, it once kept only the
/// new entries and dropped every other golden's version without a word.
pub fn record_blessed(dir: &Path, entries: &[(String, String)]) -> std::io::Result<()> {
    let path = dir.join(MANIFEST);
    let mut map = manifest(dir)
        .map_err(|why| {
            std::io::Error::other(format!(
                "{} {why}: nothing recorded over it; restore it from git (`git checkout -- {}`) and bless again",
                path.display(),
                path.display()
            ))
        })?
        .unwrap_or_default();
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

/// The file of a release's directory that lists the goldens of other releases a bless on it
/// compared and found unchanged: `STEM HASH` per line (HASH: 64-bit FNV-1a of the golden's
/// PNG bytes then), sorted.
pub const CONFIRMED: &str = "confirmed.txt";

/// 64-bit FNV-1a of a golden's bytes, as [`CONFIRMED`] records it.
fn bytes_hash(bytes: &[u8]) -> String {
    umbra_report::names::fnv64(bytes.iter().copied())
}

/// The confirmations of `version`'s release in `dir` (stem → hash of the golden confirmed),
/// parsed once per process and version of the file (a worker checks hundreds of runs: one
/// `stat` each, not a parse).
fn confirmations(dir: &Path, version: &str) -> std::collections::HashMap<String, String> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    type Parsed = (
        Option<(u64, std::time::SystemTime)>,
        HashMap<String, String>,
    );
    static READ: OnceLock<Mutex<HashMap<std::path::PathBuf, Parsed>>> = OnceLock::new();
    let path = release_dir(dir, version).join(CONFIRMED);
    let stamp = std::fs::metadata(&path)
        .ok()
        .and_then(|m| Some((m.len(), m.modified().ok()?)));
    let read = READ.get_or_init(Mutex::default);
    if let Some((_, m)) = read
        .lock()
        .ok()
        .and_then(|c| c.get(&path).filter(|(s, _)| *s == stamp).cloned())
    {
        return m;
    }
    // A damaged file confirms nothing (conformance refuses to start on one: [`check_confirmed`]).
    let m =
        parse_confirmed(&std::fs::read_to_string(&path).unwrap_or_default()).unwrap_or_default();
    if let Ok(mut c) = read.lock() {
        c.insert(path, (stamp, m.clone()));
    }
    m
}

/// [`CONFIRMED`]'s entries, read strictly: every line `STEM HASH` as [`record_confirmed`]
/// writes it (a golden's stem, one space, 16 lower-case hex digits), no stem twice. `Err`
/// names the line. Read leniently, a merge-conflict marker became an entry, a line without
/// its space was dropped and a duplicate kept its last hash: a golden that lost its
/// confirmation that way was judged leniently on the release without a word.
fn parse_confirmed(text: &str) -> Result<std::collections::HashMap<String, String>, String> {
    let mut out = std::collections::HashMap::new();
    for (n, line) in text.lines().enumerate() {
        let at = |why: &str| format!("line {}: {why} ({line:?})", n + 1);
        let Some((stem, hash)) = line.split_once(' ') else {
            return Err(at("not `STEM HASH`"));
        };
        let stem_ok = !stem.is_empty()
            && stem
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
        if !stem_ok {
            return Err(at("the stem is not a golden's file stem"));
        }
        let hash_ok =
            hash.len() == 16 && hash.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
        if !hash_ok {
            return Err(at("the hash is not 16 lower-case hex digits"));
        }
        if out.insert(stem.to_string(), hash.to_string()).is_some() {
            return Err(at("the stem is listed twice"));
        }
    }
    Ok(out)
}

/// Every release's [`CONFIRMED`] in the golden directory `dir`, read strictly: the first
/// that is damaged, with the fix. Conformance refuses to start on it (exit 125).
pub fn check_confirmed(dir: &Path) -> Result<(), String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    let mut files: Vec<_> = entries
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("mesa-"))
        .map(|e| e.path().join(CONFIRMED))
        .filter(|f| f.exists())
        .collect();
    files.sort();
    for f in files {
        let read = std::fs::read_to_string(&f)
            .map_err(|e| e.to_string())
            .and_then(|t| parse_confirmed(&t).map(drop));
        if let Err(why) = read {
            return Err(format!(
                "{}: {why}; restore it from git (`git checkout -- {}`), or remove it (that release's confirmations are lost: its goldens of other releases are judged leniently there until a bless on it confirms them again)",
                f.display(),
                f.display()
            ));
        }
    }
    Ok(())
}

/// Whether the golden `file` of run `stem` (a golden of another release) was compared on
/// `version`'s release by a bless there and found unchanged, and is still the golden it
/// found: then it holds on that release strictly, as on its own. A golden changed since
/// (blessed again on its release) is lenient there again until a bless on that release
/// compares it anew.
pub fn confirmed(dir: &Path, stem: &str, file: &Path, version: &str) -> bool {
    confirmations(dir, version)
        .get(stem)
        .is_some_and(|want| std::fs::read(file).is_ok_and(|b| bytes_hash(&b) == *want))
}

/// Records that a bless on `version`'s release compared these goldens of other releases and
/// found them unchanged: `(stem, golden file)` each, added to (or renewed in) the release's
/// [`CONFIRMED`], kept sorted. A bless confirms exactly what it compared, filtered or not.
pub fn record_confirmed(
    dir: &Path,
    version: &str,
    goldens: &[(String, std::path::PathBuf)],
) -> std::io::Result<()> {
    if goldens.is_empty() {
        return Ok(());
    }
    let release = release_dir(dir, version);
    let path = release.join(CONFIRMED);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e),
    };
    let mut map: std::collections::BTreeMap<String, String> = parse_confirmed(&text)
        .map_err(|why| {
            std::io::Error::other(format!(
                "{} {why}: nothing recorded over it; restore it from git and bless again",
                path.display()
            ))
        })?
        .into_iter()
        .collect();
    for (stem, file) in goldens {
        map.insert(stem.clone(), bytes_hash(&std::fs::read(file)?));
    }
    let text: String = map.iter().map(|(s, h)| format!("{s} {h}\n")).collect();
    std::fs::create_dir_all(&release)?;
    crate::atomic_file::write(&path, text.as_bytes())
}

/// Whether backend `id` has goldens in `dir`: the manifest names it (blessing records every
/// backend it wrote for), or a golden of one of its runs is there (its folder's snapshots are told apart by
/// the name each records, not by the folder's name, whose punctuation is flattened).
/// A device's backend without goldens (a device umbra has never seen) is judged by the specs
/// and the reference alone; `cargo xtask bless --backend ID` starts its goldens. This build's
/// own ids are never asked: a golden of theirs that is missing is a change to review (on the
/// release their goldens were blessed on; see [`crate::judge::golden`] for another).
pub fn has_goldens(dir: &Path, id: &str) -> bool {
    if manifest(dir)
        .ok()
        .flatten()
        .is_some_and(|m| m.contains_key(id))
    {
        return true;
    }
    let marker = format!("colour of {id}/");
    std::fs::read_dir(dir.join(folder(id)))
        .into_iter()
        .flatten()
        .flatten()
        .any(|e| {
            e.file_name().to_string_lossy().ends_with(".snap")
                && std::fs::read_to_string(e.path()).is_ok_and(|t| t.contains(&marker))
        })
}

/// Whether two Mesa versions are the same release for goldens (numeric parts only, so a
/// distribution's packaging suffix does not matter).
pub fn same_release(a: &str, b: &str) -> bool {
    release(a) == release(b)
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
        // A bless over it records nothing and leaves it as it was.
        let damaged = std::fs::read_to_string(&path).expect("manifest");
        let e =
            record_blessed(&dir, &[("gl33/llvmpipe".into(), "2.0".into())]).expect_err("refused");
        assert!(e.to_string().contains("restore it from git"), "{e}");
        assert_eq!(std::fs::read_to_string(&path).expect("manifest"), damaged);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// confirmed.txt is read strictly: the committed files pass; a conflict marker, a line
    /// without its hash, a bad hash and a stem listed twice are each refused with their line,
    /// by conformance's check and by a bless, which then leaves the file as it was.
    #[test]
    fn a_damaged_confirmation_file_is_refused_with_its_line() {
        let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../golden");
        assert_eq!(check_confirmed(&golden), Ok(()));
        let ok = "a_b-12345678 0123456789abcdef\nc-9abcdef0 fedcba9876543210\n";
        assert_eq!(parse_confirmed(ok).map(|m| m.len()), Ok(2));
        for (text, why) in [
            ("<<<<<<< HEAD\n", "line 1: the stem"),
            ("a-12345678\n", "line 1: not `STEM HASH`"),
            ("a-12345678 0123\n", "line 1: the hash"),
            ("a-12345678  0123456789abcdef\n", "line 1: the hash"),
            (
                "a-12345678 0123456789abcdef\na-12345678 0123456789abcdee\n",
                "line 2: the stem is listed twice",
            ),
        ] {
            let e = parse_confirmed(text).expect_err(text);
            assert!(e.starts_with(why), "{text:?}: {e}");
        }
        let dir = std::env::temp_dir().join(format!("umbra-confirmed-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let release = dir.join("mesa-26.2.6");
        std::fs::create_dir_all(&release).expect("dir");
        let file = release.join(CONFIRMED);
        std::fs::write(&file, "a-12345678\n").expect("write");
        let e = check_confirmed(&dir).expect_err("damaged");
        assert!(
            e.contains("confirmed.txt: line 1") && e.contains("restore it from git"),
            "{e}"
        );
        let golden = dir.join("g.png");
        std::fs::write(&golden, b"png").expect("golden");
        assert!(record_confirmed(&dir, "26.2.6", &[("b-12345678".into(), golden)]).is_err());
        assert_eq!(
            std::fs::read_to_string(&file).expect("file"),
            "a-12345678\n"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
