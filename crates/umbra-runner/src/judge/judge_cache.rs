//! The judging basis of a case point, computed once and shared by every backend's worker:
//! the exact truth (per point) and the reference's judged render ([`umbra_ref::Judged`], per
//! point and *effective* profile, [`umbra_case::Profile::effective_for`], so that backends
//! whose profiles differ only in freedoms the case cannot exercise share one).
//!
//! Both depend on the case point and on the code that computes them, never on the backend's
//! output, so they are content-addressed by both: an entry's file name is a hash of the
//! resolved case point (and the profile), and it lives in a directory named for that code
//! ([`build_id`]: the [`crate::judge::basis_key`] of the sources of umbra-case, umbra-ref and
//! umbra-compare, this file's format, their locked dependencies and the toolchain, computed
//! by the build script). A change to those, committed or not, is a new directory, so nothing
//! computed by other code is ever read; a change anywhere else (the runner, a backend, the
//! report) keeps the directory, so the next commit's CI job reads what the last one computed.
//! The cache
//! outlives the run: a second conformance run, the self-test, a sweep and every step of a
//! Mesa bisection (which keeps umbra fixed and changes only the driver) read what the first
//! computed, so re-running a point costs the backend's frame and the comparison. [`prepare`]
//! removes the directories of other builds, so the cache holds one build's entries.
//!
//! Commands name the build's directory in `UMBRA_JUDGE_CACHE`; the first worker to need an
//! entry computes it under a lock file (`KEY.lock`, naming its process; another worker that
//! needs the entry meanwhile waits for it rather than computing it too, and takes over if
//! that process has died) and writes it there (to a temporary name, then renamed, so a
//! reader never sees half a file); the others read it. Without the variable (`umbra render`,
//! tests) everything is computed in place. The twins' truths are cached the same way (keyed
//! by the twin's point).
//!
//! Nothing read back is trusted: an entry ends with a checksum of everything before it (which
//! includes the key it was made for), keyed with the cache's own secret (`DIR/secret`, 16
//! random bytes, mode 0600: an entry resealed with the published algorithm but without the
//! secret fails), and a truth read back is recomputed at a sample of its
//! pixels ([`SAMPLE`], exact rays, compared bit for bit: the build is the same, so the answer
//! must be). An empty, truncated, damaged or foreign entry, or one that disagrees with the
//! sample, is never used: it is recomputed and rewritten, with a one-line warning naming the
//! file (once per file and process). A cache directory that cannot be written is said once,
//! by [`prepare`]; the run goes on computing every basis where it is needed. The reference
//! backend is judged against the same basis in every run, so damage that narrows or moves an
//! interval shows as the reference failing its own check; damage that only widens one would
//! not (the reference's answer stays inside), which is why the checksum is keyed.
//!
//! Every entry is stored deflated ([`pack`]: `UMBZ1`, the inflated length (u64), then a raw
//! deflate stream at flate2's fastest level; a judged render in two parts, [`pack_parts`]:
//! `UMBZ2`, the count, each part's lengths, then each part's own stream, so that a reader
//! inflates the map's ranges only when it judges a map) and sealed after packing: the file ends with a
//! u64 checksum ([`checksum`]) of every byte before it, so a change to any stored byte is
//! found before anything is inflated. (Sealed inside the deflate stream, a damaged stream
//! could inflate to the very bytes it held: 28 % of the single-bit flips of a packed truth
//! did, measured over 20 secrets. The entry was then right but used without a word, and a
//! test that damages one bit failed at random, the secret's bytes being part of what was
//! deflated.) The judged renders
//! are mostly runs of equal values (background, uniformly lit or shadowed floor, the map's
//! cleared texels), and unpacked the catalogue's entries took 11 GB of one CI job's disk
//! (2,324 judged entries, 6 GB of them the GL profile's map ranges) and filled it; packed
//! they take a tenth. Inflated, formats are little-endian, each starting with a magic, width
//! and height (u32) and a u64 key check (FNV-1a of the resolved case point, and of the
//! profile's name for a judged render):
//! - `truth-KEY.bin` (`UMBT2`): per pixel the class (u8), the edge flag (u8), the face (u32).
//!   The hit points are not kept (the judge does not read them).
//! - `judged-KEY.bin` (`UMBJ6`): the quantum (f32), the reference's RGBA8 colour, its
//!   visibility (f32), whether a surface buffer follows (u8) and its face ids (u32), then per
//!   pixel what is legal: lo, hi (f32), flags (u8), c0, c1 (3 × f32 each) and the colour
//!   tolerance (f32). Its second part: the number of shadow-map texels kept (u32, 0 unless
//!   the profile is desktop GL's, whose backends read their map back) and their (lo, hi)
//!   ranges (f32 each). Inflated, the ranges are most of a desktop GL entry (8 MB for a 1024²
//!   map, against 37 bytes a pixel), and of the backends judged as `gl` only those that read
//!   their map back (GL 3.3's, the reference) are judged by them.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use umbra_case::format::ColorFormat;
use umbra_case::{ClipDepth, Frame, LightRun, Prepared, Profile};
use umbra_ref::truth::{Class, Truth, ground_truth};
use umbra_ref::{Judged, JudgedLight, PixelLegal};

/// The environment variable naming the cache directory.
pub const ENV: &str = "UMBRA_JUDGE_CACHE";

const TRUTH_MAGIC: &[u8; 5] = b"UMBT2";
const JUDGED_MAGIC: &[u8; 5] = b"UMBJ6";

/// How many pixels of a truth read back are recomputed and compared (spread over the frame,
/// the same for every read of an entry): enough that damage to a few per cent of a frame's
/// pixels is found almost surely (1 − 0.97⁶⁴ ≈ 86 % at 3 %, > 99.8 % at 10 %), at the cost of
/// 64 rays and the bounding-volume tree.
pub const SAMPLE: usize = 64;

/// The truth, and the reference's judged render for one profile.
pub struct Basis {
    /// Every light's exact truth, in the case's order.
    pub truths: Vec<Truth>,
    /// The reference's frame and what every pixel allows.
    pub judged: Judged,
}

/// The default cache root of the commands, beside their default output (`target/umbra`).
pub const DEFAULT_ROOT: &str = "target/umbra/cache/judge";

/// The code that computes the judging basis, as the cache keys it: the sources' key
/// ([`crate::judge::basis_key`], `KEY-src`). Where the build script could not compute one (a
/// crate built outside its workspace), this build of umbra: the linker's GNU build id (a
/// SHA-1 over the linked executable's contents, which Debian's toolchain always writes, read
/// from the note near the file's start), or where there is none, 64-bit FNV-1a over the
/// executable's bytes
/// (about 40 ms for the 77 MB debug binary). Computed once per process that asks.
pub fn build_id() -> &'static str {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        // The sources' key where the build script computed one (16 hex digits, `-src` keeps
        // the `HASH16-…` shape `prepare` recognises).
        if let Some(key) = option_env!("UMBRA_BASIS_KEY").filter(|k| !k.is_empty()) {
            return format!("{key}-src");
        }
        let exe = std::env::current_exe().unwrap_or_default();
        let head = std::fs::File::open(&exe)
            .and_then(|f| {
                let mut head = Vec::with_capacity(1 << 16);
                f.take(1 << 16).read_to_end(&mut head)?;
                Ok(head)
            })
            .unwrap_or_default();
        if let Some(id) = gnu_build_id(&head) {
            let hex: String = id.iter().map(|b| format!("{b:02x}")).collect();
            // The directory name keeps the `HASH16-LEN` shape `prepare` recognises.
            return format!(
                "{}-gnu{}",
                &hex[..16.min(hex.len())],
                &hex[16.min(hex.len())..]
            );
        }
        let bytes = std::fs::read(&exe).unwrap_or_default();
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            h = (h ^ u64::from_le_bytes(word)).wrapping_mul(0x0100_0000_01b3);
        }
        format!("{:016x}-{}", h, bytes.len())
    })
}

/// The descriptor of an ELF `NT_GNU_BUILD_ID` note (name "GNU", type 3) in `bytes`, if one
/// of 16 to 64 bytes is there (8-byte notes, the old MD5-less kind, are not trusted).
fn gnu_build_id(bytes: &[u8]) -> Option<&[u8]> {
    const TAIL: &[u8] = b"\x03\0\0\0GNU\0";
    let at = bytes.windows(TAIL.len()).position(|w| w == TAIL)?;
    let header = at.checked_sub(8)?;
    let word = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().unwrap_or_default());
    let (namesz, descsz) = (word(header), word(header + 4) as usize);
    let start = at + TAIL.len();
    (namesz == 4 && (16..=64).contains(&descsz) && start + descsz <= bytes.len())
        .then(|| &bytes[start..start + descsz])
}

/// The directory of this build's entries under `root` (created), after removing the entries
/// of any other build there. Workers get it in [`ENV`].
pub fn prepare(root: &Path) -> PathBuf {
    let root = std::fs::canonicalize(root).unwrap_or_else(|_| root.to_path_buf());
    if let Ok(entries) = std::fs::read_dir(&root) {
        for e in entries.flatten() {
            let name = e.file_name();
            let name = name.to_string_lossy();
            // Only what this module writes: `HASH-LEN` directories, and the entries of the
            // layout before builds had directories (`truth-KEY.bin`, `judged-KEY.bin`).
            let ours = name.len() > 17
                && name.as_bytes()[16] == b'-'
                && name[..16].bytes().all(|b| b.is_ascii_hexdigit());
            let unversioned = (name.starts_with("truth-") || name.starts_with("judged-"))
                && name.ends_with(".bin");
            if ours && name != build_id() {
                let _ = std::fs::remove_dir_all(e.path());
            } else if unversioned {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    let dir = root.join(build_id());
    let probe = std::fs::create_dir_all(&dir)
        .and_then(|()| crate::atomic_file::write(&dir.join("writable"), b"umbra"))
        .and_then(|()| {
            load_secret(&dir)
                .then_some(())
                .ok_or_else(|| std::io::Error::other("its secret cannot be made"))
        });
    if let Err(e) = probe {
        eprintln!(
            "warning: the judging cache {} cannot be written ({e}): every worker computes the truth and the reference itself (same results, slower); give --judge-cache a writable directory",
            dir.display()
        );
    }
    let mut swept = crate::atomic_file::sweep(&dir);
    // Locks of processes that died holding them (killed mid-computation).
    for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.extension().is_some_and(|x| x == "lock")
            && holder_gone(&p)
            && std::fs::remove_file(&p).is_ok()
        {
            swept += 1;
        }
    }
    if swept > 0 {
        eprintln!(
            "note: removed {swept} temporary or lock file(s) of ended processes from the judging cache {}",
            dir.display()
        );
    }
    dir
}

/// Every light's exact truth, in the case's order ([`truth`]).
pub fn truths(prepared: &Prepared) -> Vec<Truth> {
    prepared.lights.iter().map(truth).collect()
}

/// The exact truth of one light's run: from the cache when the process has one, else
/// computed. A case's light shares its entry with the one-light case that is the same run.
pub fn truth(run: &LightRun) -> Truth {
    let dir = std::env::var_os(ENV).map(PathBuf::from);
    cached(
        dir.as_deref(),
        "truth",
        key(&run.point, ""),
        write_truth,
        |bytes, k| read_truth(bytes, k).and_then(|t| sampled(run, t)),
        || ground_truth(run),
    )
}

/// `frame`'s error against the truth: each light's visibility against its own run's truth
/// (`truths`, [`truths`]), [`umbra_compare::truth_error_lights`].
pub fn truth_error(frame: &Frame, truths: &[Truth]) -> umbra_compare::TruthError {
    umbra_compare::truth_error_lights(frame, truths)
}

/// `truth` if it is the exact truth at [`SAMPLE`] pixels spread over the frame, else why not.
fn sampled(prepared: &LightRun, truth: Truth) -> Result<Truth, String> {
    let n = truth.class.len();
    let [w, h] = prepared.camera.size;
    if (truth.width, truth.height) != (w, h) {
        return Err(format!(
            "is {}x{} for a {w}x{h} camera",
            truth.width, truth.height
        ));
    }
    if n == 0 {
        return Ok(truth);
    }
    // A stride coprime to n (Fibonacci hashing keeps the sample spread; odd, and adjusted
    // until coprime) visits SAMPLE distinct pixels when n ≥ SAMPLE.
    let mut stride = ((n as f64 * 0.618_033_988_75) as usize) | 1;
    while gcd(stride, n) != 1 {
        stride += 2;
    }
    let at: Vec<usize> = (0..SAMPLE.min(n))
        .map(|k| (k * stride + n / 2) % n)
        .collect();
    let exact = umbra_ref::truth::truth_at(prepared, &at);
    let wrong: Vec<usize> = at
        .iter()
        .zip(&exact)
        .filter(|(i, e)| (truth.class[**i], truth.edge[**i], truth.face[**i]) != **e)
        .map(|(i, _)| *i)
        .collect();
    match wrong.first() {
        None => Ok(truth),
        Some(&i) => Err(format!(
            "disagrees with the exact truth at {} of {} sampled pixels (first at ({}, {}): stored {:?}, exact {:?})",
            wrong.len(),
            at.len(),
            i as u32 % w,
            i as u32 / w,
            truth.class[i],
            exact[at.iter().position(|a| *a == i).unwrap_or(0)].0
        )),
    }
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// The basis of `prepared` for a backend of `profile`: from the cache when the run has one,
/// else computed. `map`: with the map's ranges (for a frame that carries its shadow map).
pub fn basis(prepared: &Prepared, profile: Profile, map: bool) -> Basis {
    let truths = truths(prepared);
    let judged = judged(prepared, profile, map);
    Basis { truths, judged }
}

/// The reference's judged render of `prepared` for `profile`: each light's run judged on its
/// own ([`judged_light`]), the frame's colour all lights'.
pub fn judged(prepared: &Prepared, profile: Profile, map: bool) -> Judged {
    let each = prepared
        .lights
        .iter()
        .map(|light| judged_light(light, profile, map))
        .collect();
    let case = prepared.case();
    Judged::of_lights(each, profile.effective_for(case), case.camera.color_format)
}

/// One light's judged run for `profile` (its effective profile), cached like [`basis`]'s:
/// each light's run is its own entry, which a case's light shares with the one-light case
/// that is the same run, and the entry format stays one light's. `map`: with the map's
/// ranges where the profile keeps them (read from the cache only when asked for: they are
/// most of a desktop GL entry, and only a frame that carries its shadow map is judged by
/// them); a computed entry has them either way.
pub fn judged_light(prepared: &LightRun, profile: Profile, map: bool) -> Judged {
    let profile = profile.effective_for(prepared.case());
    let dir = std::env::var_os(ENV).map(PathBuf::from);
    cached(
        dir.as_deref(),
        "judged",
        key(&prepared.point, &profile.name()),
        write_judged,
        |bytes, k| read_judged(bytes, k, profile, prepared.case().camera.color_format, map),
        || {
            // A card's narrowing is computed over the specs' judgement of the same light
            // (cached too, and usually computed already for the run's own judgement): only
            // the pixels the specs leave open are judged again
            // ([`umbra_ref::judged_light_within`]).
            let uncalibrated = profile.with_calibration(Default::default());
            let mut j = if uncalibrated == profile {
                umbra_ref::explain_light(prepared, ClipDepth::MinusOneToOne, profile, None).0
            } else {
                let spec = judged_light(prepared, uncalibrated, false);
                match spec.lights.first() {
                    Some(s) => umbra_ref::judged_light_within(
                        prepared,
                        ClipDepth::MinusOneToOne,
                        profile,
                        s,
                    ),
                    None => {
                        umbra_ref::explain_light(prepared, ClipDepth::MinusOneToOne, profile, None)
                            .0
                    }
                }
            };
            // The render's own clock divides its time: the shadow pass with the map's
            // ranges, the lit pass with the judged lookups.
            use crate::judge::stages::{Stage, attribute};
            attribute(Stage::JudgedMap, j.frame.timings.shadow_pass);
            attribute(Stage::JudgedLookups, j.frame.timings.lit_pass);
            // Only the GL 3.3 backends read their shadow map back; keep its ranges for them
            // (under their card's narrowing too).
            if uncalibrated != Profile::GL {
                j.lights.iter_mut().for_each(|l| l.map = Vec::new());
            }
            j
        },
    )
}

/// One cached artefact: read it, or compute it and write it for the next worker. A cache that
/// cannot be written only costs time: the value is still right.
fn cached<T>(
    dir: Option<&Path>,
    kind: &str,
    key: u64,
    writer: fn(&T, u64) -> Vec<u8>,
    reader: impl Fn(&[u8], u64) -> Result<T, String>,
    compute: impl FnOnce() -> T,
) -> T {
    use crate::judge::stages::{Stage, time};
    let (computing, reading) = if kind == "truth" {
        (Stage::TruthRays, Stage::TruthRead)
    } else {
        (Stage::JudgedRender, Stage::JudgedRead)
    };
    let compute = || time(computing, compute);
    // No cache, or one that is not a directory ([`prepare`] said so, once, for the run).
    let Some(dir) = dir.filter(|d| d.is_dir() && load_secret(d)) else {
        return compute();
    };
    let file = dir.join(format!("{kind}-{key:016x}.bin"));
    // A missing entry is a miss; one that is there but cannot be used is said, and missed.
    let read = || match regular_file_bytes(&file) {
        Ok(bytes) => reader(&bytes, key)
            .map_err(|why| warn_once(&file, &format!("{why}; recomputed, not used")))
            .ok(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => {
            warn_once(&file, &format!("cannot be read ({e}); recomputed"));
            None
        }
    };
    if let Some(v) = time(reading, read) {
        return v;
    }
    // Every backend's worker goes through the points in the same order, so two workers miss
    // the same entry at the same moment: one computes it (holding `KEY.lock`, which names its
    // process) and the others wait for the file, unless the holder is gone.
    let lock = dir.join(format!("{kind}-{key:016x}.lock"));
    let _ = std::fs::create_dir_all(dir);
    let held = time(Stage::Wait, || {
        loop {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&lock)
            {
                Ok(mut f) => {
                    let _ = write!(f, "{}", std::process::id());
                    break Ok(true);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    if let Some(v) = read() {
                        break Err(v);
                    }
                    if holder_gone(&lock) {
                        let _ = std::fs::remove_file(&lock);
                        continue;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                // A directory that cannot be written: compute without the cache.
                Err(_) => break Ok(false),
            }
        }
    });
    let held = match held {
        Ok(held) => held,
        Err(v) => return v,
    };
    if held {
        // The holder may have finished between our read and our lock.
        if let Some(v) = time(reading, read) {
            let _ = std::fs::remove_file(&lock);
            return v;
        }
    }
    let value = compute();
    // Without the lock the directory cannot be written at all ([`prepare`] said so); with it,
    // a failed store is news (a disk that filled during the run): said once, and the process
    // stops writing (a full disk made one line an entry, thousands, in a CI log).
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    static STORE_FAILED: AtomicBool = AtomicBool::new(false);
    if !STORE_FAILED.load(Relaxed) {
        let stored = time(Stage::CacheWrite, || {
            store(dir, &file, &writer(&value, key))
        });
        if let Err(e) = stored {
            let first = !STORE_FAILED.swap(true, Relaxed);
            if held && first {
                warn_once(
                    &file,
                    &format!(
                        "cannot be written ({e}): this process writes no more entries (the rest are computed where needed, same results, slower); the next run computes them again"
                    ),
                );
            }
        }
    }
    if held {
        let _ = std::fs::remove_file(&lock);
    }
    value
}

/// Prints `warning: judging cache entry FILE WHAT` on stderr, once per path and process (a
/// worker waiting for an entry reads it many times).
fn warn_once(file: &Path, what: &str) {
    static SAID: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    let Ok(mut said) = SAID.lock() else { return };
    if !said.iter().any(|p| p == file) {
        said.push(file.to_path_buf());
        eprintln!("warning: judging cache entry {} {what}", file.display());
    }
}

/// The checksum that ends every entry: SipHash-2-4 of its bytes keyed with the cache's own
/// secret ([`SECRET`]), so an entry edited and resealed by anyone who has not read that secret
/// fails it. It guards against damage and against edits that recompute a published checksum,
/// not against someone who can read the cache's secret: the cache is trusted as far as its
/// directory is; the truth's sampled recomputation stands behind it for truths.
fn checksum(bytes: &[u8]) -> u64 {
    use std::hash::Hasher as _;
    let (k0, k1) = SECRET.get().copied().unwrap_or_default();
    #[allow(deprecated)] // std's one keyed SipHash; stable, deprecated only for its name.
    let mut h = std::hash::SipHasher::new_with_keys(k0, k1);
    h.write(bytes);
    h.write_usize(bytes.len());
    h.finish()
}

/// The key of this process's cache (read once from `DIR/secret`); unset (zero) where no
/// cache is used, when nothing is read back.
static SECRET: std::sync::OnceLock<(u64, u64)> = std::sync::OnceLock::new();

/// The file holding a cache directory's secret.
const SECRET_FILE: &str = "secret";

/// Reads `dir`'s secret into [`SECRET`], making it first if the directory has none (16 bytes
/// from the kernel's random source, mode 0600, linked into place so that of two workers
/// making it at once one wins and both read the winner's). `false`: no cache can be trusted.
///
/// A secret is trusted only as it was made ([`secret_flaw`]): a regular file, not a link, of
/// 16 bytes, owned by this user, readable by nobody else. Anything else (a world-readable
/// secret lets anyone local reseal a widened entry; one cut short or replaced by a directory
/// disabled the cache on every run) is moved aside with a warning, a new one is made, and the
/// entries the old one sealed are removed, to be computed again.
fn load_secret(dir: &Path) -> bool {
    if SECRET.get().is_some() {
        return true;
    }
    let file = dir.join(SECRET_FILE);
    if let Some(flaw) = secret_flaw(&file) {
        let aside = dir.join(format!("secret.refused-{}", std::process::id()));
        if std::fs::rename(&file, &aside).is_err() {
            return false;
        }
        let removed = remove_entries(dir);
        eprintln!(
            "warning: the judging cache's secret {} {flaw}: not trusted; moved aside to {} and a new one made; its {removed} entries are removed and computed again",
            file.display(),
            aside.display()
        );
    }
    if std::fs::symlink_metadata(&file).is_err() {
        let mut bytes = [0u8; 16];
        let made = std::fs::File::open("/dev/urandom")
            .and_then(|mut r| r.read_exact(&mut bytes))
            .and_then(|()| {
                use std::os::unix::fs::OpenOptionsExt as _;
                let tmp = dir.join(format!(".secret.{}", std::process::id()));
                let mut f = std::fs::OpenOptions::new()
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .mode(0o600)
                    .open(&tmp)?;
                f.write_all(&bytes)?;
                f.sync_all()?;
                let linked = std::fs::hard_link(&tmp, &file);
                let _ = std::fs::remove_file(&tmp);
                match linked {
                    Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => Err(e),
                    _ => Ok(()),
                }
            });
        if made.is_err() {
            return false;
        }
    }
    // Read only what was checked: a regular file, here; never a link's target.
    if secret_flaw(&file).is_some() {
        return false;
    }
    match regular_file_bytes(&file) {
        Ok(b) if b.len() == 16 => {
            let k0 = u64::from_le_bytes(b[..8].try_into().unwrap_or_default());
            let k1 = u64::from_le_bytes(b[8..].try_into().unwrap_or_default());
            let _ = SECRET.set((k0, k1));
            true
        }
        _ => false,
    }
}

/// The bytes of the regular file at `file`. It is opened without blocking and without
/// following a link, and anything but a regular file is refused before a byte is read: a FIFO
/// in an entry's place once blocked the worker until its timeout, and the backend was blamed.
fn regular_file_bytes(file: &Path) -> std::io::Result<Vec<u8>> {
    use std::os::unix::fs::OpenOptionsExt as _;
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
        .open(file)?;
    if !f.metadata()?.is_file() {
        return Err(std::io::Error::other("is not a regular file"));
    }
    let mut bytes = Vec::new();
    f.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// What is wrong with the secret at `file`, if it is there and not as umbra makes one.
fn secret_flaw(file: &Path) -> Option<String> {
    use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};
    let meta = std::fs::symlink_metadata(file).ok()?;
    let me = std::fs::metadata("/proc/self").map(|m| m.uid()).ok();
    if meta.file_type().is_symlink() {
        Some("is a symbolic link".into())
    } else if !meta.is_file() {
        Some("is not a regular file".into())
    } else if meta.len() != 16 {
        Some(format!("is {} bytes, not 16", meta.len()))
    } else if me.is_some_and(|me| me != meta.uid()) {
        Some(format!("is owned by user {}, not this one", meta.uid()))
    } else if meta.permissions().mode() & 0o077 != 0 {
        Some(format!(
            "has mode {:04o}: others can read it, and so reseal an entry (it must be 0600)",
            meta.permissions().mode() & 0o7777
        ))
    } else {
        None
    }
}

/// Removes every entry (`*.bin`) of the cache directory `dir`: how many.
fn remove_entries(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "bin"))
        .filter(|e| std::fs::remove_file(e.path()).is_ok())
        .count()
}

/// `bytes` with its checksum appended.
fn sealed(mut bytes: Vec<u8>) -> Vec<u8> {
    let sum = checksum(&bytes);
    bytes.extend_from_slice(&sum.to_le_bytes());
    bytes
}

/// The body of a sealed entry, or what is wrong with it.
fn unsealed(bytes: &[u8]) -> Result<&[u8], String> {
    if bytes.is_empty() {
        return Err("is empty".into());
    }
    let Some(split) = bytes.len().checked_sub(8) else {
        return Err(format!("is truncated ({} bytes)", bytes.len()));
    };
    let (body, sum) = bytes.split_at(split);
    let sum = u64::from_le_bytes(sum.try_into().unwrap_or_default());
    if checksum(body) == sum {
        Ok(body)
    } else {
        Err(format!(
            "fails its checksum ({} bytes: truncated or damaged)",
            bytes.len()
        ))
    }
}

/// The magic of a packed entry.
const PACKED_MAGIC: &[u8; 5] = b"UMBZ1";

/// The largest inflated entry [`unpack`] accepts: a judged render of a 4096 × 4096 frame
/// with an 8192² map is about 1.3 GiB; a wrong length (the checksum stands before it, so
/// only an entry written by other code under this build's name) must not become an
/// allocation.
const MAX_INFLATED: u64 = 2 << 30;

/// `bytes` deflated behind [`PACKED_MAGIC`] and their length. The fastest level: about a
/// tenth of the size for a few tens of ms an entry, against the hundreds of ms (truth) to
/// seconds (a judged render) that computing one costs.
fn pack(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len() / 8 + 64);
    out.extend_from_slice(PACKED_MAGIC);
    out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    deflate_into(out, bytes)
}

/// `out` followed by `bytes` deflated at the fastest level.
fn deflate_into(out: Vec<u8>, bytes: &[u8]) -> Vec<u8> {
    use flate2::{Compression, write::DeflateEncoder};
    let mut z = DeflateEncoder::new(out, Compression::fast());
    // Writing into a Vec cannot fail.
    let _ = z.write_all(bytes);
    z.finish().unwrap_or_default()
}

/// The magic of an entry packed in parts ([`pack_parts`]).
const PARTS_MAGIC: &[u8; 5] = b"UMBZ2";

/// `parts` each deflated on its own behind [`PARTS_MAGIC`], their count (u32) and each one's
/// inflated and deflated lengths (u64 each): a reader inflates only the parts it needs (a
/// judged entry's map ranges, the larger part of a desktop GL entry, are read only by a
/// backend that reads its map back).
fn pack_parts(parts: &[&[u8]]) -> Vec<u8> {
    let streams: Vec<Vec<u8>> = parts.iter().map(|p| deflate_into(Vec::new(), p)).collect();
    let mut out = Vec::with_capacity(64 + streams.iter().map(Vec::len).sum::<usize>());
    out.extend_from_slice(PARTS_MAGIC);
    out.extend_from_slice(&(parts.len() as u32).to_le_bytes());
    for (part, stream) in parts.iter().zip(&streams) {
        out.extend_from_slice(&(part.len() as u64).to_le_bytes());
        out.extend_from_slice(&(stream.len() as u64).to_le_bytes());
    }
    streams.iter().for_each(|s| out.extend_from_slice(s));
    out
}

/// The first `wanted` parts [`pack_parts`] packed, inflated one after the other, or what is
/// wrong with the entry (its checksum, around it, is checked before this).
fn unpack_parts(bytes: &[u8], wanted: usize) -> Result<Vec<u8>, String> {
    let head = PARTS_MAGIC.len() + 4;
    if bytes.len() < head {
        return Err(format!("is truncated ({} bytes)", bytes.len()));
    }
    if &bytes[..PARTS_MAGIC.len()] != PARTS_MAGIC {
        return Err(format!(
            "is not an entry packed in parts (starts {:?}; an older layout or another file)",
            String::from_utf8_lossy(&bytes[..PARTS_MAGIC.len()])
        ));
    }
    let u64_at = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?))
    };
    let count = u32::from_le_bytes(
        bytes[PARTS_MAGIC.len()..head]
            .try_into()
            .unwrap_or_default(),
    ) as usize;
    if count > 16 || wanted > count {
        return Err(format!(
            "has {count} parts where {wanted} are read (damaged or another layout)"
        ));
    }
    let mut at = head + count * 16;
    let mut lens = Vec::with_capacity(count);
    for k in 0..count {
        let (Some(len), Some(packed)) = (u64_at(head + 16 * k), u64_at(head + 16 * k + 8)) else {
            return Err(format!("is truncated ({} bytes)", bytes.len()));
        };
        lens.push((len, packed));
    }
    let total: u64 = lens.iter().take(wanted).map(|l| l.0).sum();
    if total > MAX_INFLATED {
        return Err(format!(
            "claims {total} bytes inflated, more than any entry (damaged)"
        ));
    }
    let mut out = Vec::with_capacity(total as usize);
    for &(len, packed) in lens.iter().take(wanted) {
        let end = usize::try_from(packed)
            .ok()
            .and_then(|p| at.checked_add(p))
            .filter(|e| *e <= bytes.len())
            .ok_or_else(|| format!("is truncated ({} bytes)", bytes.len()))?;
        inflate_into(&mut out, &bytes[at..end], len)?;
        at = end;
    }
    Ok(out)
}

/// What [`pack`] packed, or what is wrong with it (the file's checksum, around it, is
/// checked before this).
fn unpack(bytes: &[u8]) -> Result<Vec<u8>, String> {
    if bytes.is_empty() {
        return Err("is empty".into());
    }
    let head = PACKED_MAGIC.len() + 8;
    if bytes.len() < head {
        return Err(format!("is truncated ({} bytes)", bytes.len()));
    }
    if &bytes[..PACKED_MAGIC.len()] != PACKED_MAGIC {
        return Err(format!(
            "is not a packed entry (starts {:?}; an older layout or another file)",
            String::from_utf8_lossy(&bytes[..PACKED_MAGIC.len()])
        ));
    }
    let len = u64::from_le_bytes(
        bytes[PACKED_MAGIC.len()..head]
            .try_into()
            .unwrap_or_default(),
    );
    if len > MAX_INFLATED {
        return Err(format!(
            "claims {len} bytes inflated, more than any entry (damaged)"
        ));
    }
    let mut out = Vec::with_capacity(len.min(64 << 20) as usize);
    inflate_into(&mut out, &bytes[head..], len)?;
    Ok(out)
}

/// `stream` inflated onto the end of `out`, which must give exactly `len` bytes (the
/// header's word: more or fewer is a damaged entry).
fn inflate_into(out: &mut Vec<u8>, stream: &[u8], len: u64) -> Result<(), String> {
    let before = out.len() as u64;
    flate2::read::DeflateDecoder::new(stream)
        .take(len + 1)
        .read_to_end(out)
        .map_err(|e| format!("cannot be inflated ({e}: truncated or damaged)"))?;
    let got = out.len() as u64 - before;
    if got != len {
        return Err(format!(
            "inflates to {got} bytes, not the {len} its header says (truncated or damaged)"
        ));
    }
    Ok(())
}

/// Whether the process named in `lock` has ended (killed on a timeout, crashed): its entry
/// will never come. A lock without a process id is stale once it is 5 s old (its holder died
/// between creating it and writing the id); younger, it is being written.
fn holder_gone(lock: &Path) -> bool {
    match std::fs::read_to_string(lock)
        .ok()
        .and_then(|t| t.trim().parse::<u32>().ok())
    {
        Some(pid) => !crate::atomic_file::process_alive(pid),
        None => std::fs::metadata(lock)
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > Duration::from_secs(5)),
    }
}

fn store(dir: &Path, file: &Path, bytes: &[u8]) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    crate::atomic_file::write(file, bytes)
}

/// 64-bit FNV-1a of the resolved case point and `tag` (everything an entry depends on).
fn key(point: &umbra_case::CasePoint, tag: &str) -> u64 {
    let text = serde_json::to_string(&point.case).unwrap_or_default() + tag;
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn class_code(c: Class) -> u8 {
    match c {
        Class::Background => 0,
        Class::FacesAway => 1,
        Class::Outside => 2,
        Class::Lit => 3,
        Class::Shadowed => 4,
    }
}

fn class_of(b: u8) -> Option<Class> {
    Some(match b {
        0 => Class::Background,
        1 => Class::FacesAway,
        2 => Class::Outside,
        3 => Class::Lit,
        4 => Class::Shadowed,
        _ => return None,
    })
}

fn header(out: &mut Vec<u8>, magic: &[u8; 5], w: u32, h: u32, key: u64) {
    out.extend_from_slice(magic);
    out.extend_from_slice(&w.to_le_bytes());
    out.extend_from_slice(&h.to_le_bytes());
    out.extend_from_slice(&key.to_le_bytes());
}

fn put_f32s(out: &mut Vec<u8>, v: &[f32]) {
    v.iter()
        .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
}

fn write_truth(t: &Truth, key: u64) -> Vec<u8> {
    let n = t.class.len();
    let mut out = Vec::with_capacity(32 + n * 6);
    header(&mut out, TRUTH_MAGIC, t.width, t.height, key);
    out.extend(t.class.iter().map(|c| class_code(*c)));
    out.extend(t.edge.iter().map(|e| u8::from(*e)));
    t.face
        .iter()
        .for_each(|f| out.extend_from_slice(&f.to_le_bytes()));
    sealed(pack(&out))
}

fn read_truth(bytes: &[u8], key: u64) -> Result<Truth, String> {
    let inflated = unpack(unsealed(bytes)?)?;
    let mut r = Reader {
        bytes: &inflated,
        at: 0,
    };
    let dims = r.header(TRUTH_MAGIC, key)?;
    parse_truth(r, dims)
        .ok_or_else(|| "has a valid checksum but not the truth's layout".to_string())
}

fn parse_truth(mut r: Reader, (width, height, n): (u32, u32, usize)) -> Option<Truth> {
    let class = r
        .take(n)?
        .iter()
        .map(|b| class_of(*b))
        .collect::<Option<Vec<_>>>()?;
    let edge = r.take(n)?.iter().map(|b| *b != 0).collect();
    let face = r.u32s(n)?;
    r.done()?;
    Some(Truth {
        width,
        height,
        class,
        edge,
        face,
        point: Vec::new(),
        elapsed: Duration::ZERO,
    })
}

fn write_judged(j: &Judged, key: u64) -> Vec<u8> {
    let f = &j.frame;
    let n = (f.width * f.height) as usize;
    let mut out = Vec::with_capacity(32 + n * 50);
    header(&mut out, JUDGED_MAGIC, f.width, f.height, key);
    out.extend_from_slice(&f.color);
    // Each light's plane and judged run (an entry is one light's run: one of each).
    out.extend_from_slice(&(j.lights.len() as u32).to_le_bytes());
    for (plane, light) in f.lights.iter().zip(&j.lights) {
        out.extend_from_slice(&light.quantum.to_le_bytes());
        put_f32s(&mut out, &plane.visibility);
        match &plane.surface {
            Some(s) => {
                out.push(1);
                s.iter()
                    .for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
            }
            None => out.push(0),
        }
        for l in &light.legal {
            put_f32s(&mut out, &[l.lo, l.hi]);
            out.push(l.flags);
            put_f32s(&mut out, &l.c0);
            put_f32s(&mut out, &l.c1);
            put_f32s(&mut out, &[l.ctol]);
        }
    }
    // The map's ranges, each light's, in a part of their own ([`pack_parts`]).
    let mut maps = Vec::new();
    for light in &j.lights {
        maps.extend_from_slice(&(light.map.len() as u32).to_le_bytes());
        for (lo, hi) in &light.map {
            put_f32s(&mut maps, &[*lo, *hi]);
        }
    }
    sealed(pack_parts(&[&out, &maps]))
}

/// A judged entry; `profile` and `color_format` are the key's case's (not stored). Without
/// `map`, the map's ranges are not inflated (the entry's lights have none).
fn read_judged(
    bytes: &[u8],
    key: u64,
    profile: Profile,
    color_format: ColorFormat,
    map: bool,
) -> Result<Judged, String> {
    let inflated = unpack_parts(unsealed(bytes)?, if map { 2 } else { 1 })?;
    let mut r = Reader {
        bytes: &inflated,
        at: 0,
    };
    let dims = r.header(JUDGED_MAGIC, key)?;
    parse_judged(r, dims, profile, color_format, map)
        .ok_or_else(|| "has a valid checksum but not the judged render's layout".to_string())
}

fn parse_judged(
    mut r: Reader,
    (width, height, n): (u32, u32, usize),
    profile: Profile,
    color_format: ColorFormat,
    map: bool,
) -> Option<Judged> {
    let color = r.take(n * 4)?.to_vec();
    let count = r.u32()? as usize;
    let mut planes = Vec::new();
    let mut lights = Vec::new();
    for _ in 0..count {
        let (plane, light) = parse_light(&mut r, n, profile)?;
        planes.push(plane);
        lights.push(light);
    }
    if map {
        let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        for light in &mut lights {
            let texels = r.u32()? as usize;
            light.map = r
                .take(texels.checked_mul(8)?)?
                .chunks_exact(8)
                .map(|b| (f(&b[..4]), f(&b[4..])))
                .collect();
        }
    }
    r.done()?;
    Some(Judged {
        frame: Frame {
            width,
            height,
            color,
            lights: planes,
            visibility_storage: Default::default(),
            timings: Default::default(),
        },
        lights,
        profile,
        color_format,
    })
}

/// One light's plane and judged run in a judged entry ([`write_judged`]).
fn parse_light(
    r: &mut Reader,
    n: usize,
    profile: Profile,
) -> Option<(umbra_case::LightPlane, JudgedLight)> {
    let quantum = r.f32()?;
    let visibility = r.u32s(n)?.into_iter().map(f32::from_bits).collect();
    let surface = match r.take(1)?[0] {
        1 => Some(r.u32s(n)?),
        _ => None,
    };
    // Per pixel: lo, hi, flags, c0, c1, ctol (37 bytes), decoded from fixed offsets.
    const LEGAL: usize = 4 + 4 + 1 + 12 + 12 + 4;
    let f = |b: &[u8], at: usize| f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    let legal = r
        .take(n.checked_mul(LEGAL)?)?
        .chunks_exact(LEGAL)
        .map(|b| PixelLegal {
            lo: f(b, 0),
            hi: f(b, 4),
            flags: b[8],
            c0: [f(b, 9), f(b, 13), f(b, 17)],
            c1: [f(b, 21), f(b, 25), f(b, 29)],
            ctol: f(b, 33),
        })
        .collect();
    let plane = umbra_case::LightPlane {
        visibility,
        surface,
        shadow_map: None,
    };
    let light = JudgedLight {
        legal,
        quantum,
        profile,
        map: Vec::new(),
    };
    Some((plane, light))
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.bytes.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        self.u32().map(f32::from_bits)
    }
    /// `n` little-endian u32 in one pass (what most of an entry is).
    fn u32s(&mut self, n: usize) -> Option<Vec<u32>> {
        Some(
            self.take(n.checked_mul(4)?)?
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        )
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// Magic, size and key, in that order: the size and the pixel count, or why the entry
    /// is not one of `magic` made for `key`.
    fn header(&mut self, magic: &[u8; 5], key: u64) -> Result<(u32, u32, usize), String> {
        let found = self.take(5).unwrap_or_default();
        if found != magic {
            return Err(format!(
                "is not a {} entry (starts {:?})",
                String::from_utf8_lossy(magic),
                String::from_utf8_lossy(found)
            ));
        }
        let short = || "is too short for its header".to_string();
        let (w, h) = (self.u32().ok_or_else(short)?, self.u32().ok_or_else(short)?);
        let made_for = self.u64().ok_or_else(short)?;
        if made_for != key {
            return Err(format!(
                "was made for another case point (key {made_for:016x}, not {key:016x})"
            ));
        }
        let n = (w as usize)
            .checked_mul(h as usize)
            .ok_or_else(|| format!("claims an impossible size {w}x{h}"))?;
        Ok((w, h, n))
    }
    fn done(&self) -> Option<()> {
        (self.at == self.bytes.len()).then_some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Settles this process's [`SECRET`] before a test seals anything: it is set once, by the
    /// first cache directory opened, and a test that sealed with the unset (zero) key while a
    /// sibling test opened a directory would read its own entry back as damaged.
    fn settled_secret() {
        // One directory for every test process (its secret made once, by whichever wins the
        // link), so that nothing is left behind per run.
        let dir = std::env::temp_dir().join("umbra-test-secret");
        std::fs::create_dir_all(&dir).expect("dir");
        assert!(load_secret(&dir));
    }

    #[test]
    fn a_locked_entry_is_waited_for_and_a_dead_holder_is_taken_over() {
        let dir = std::env::temp_dir().join(format!("umbra-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let write = |v: &u32, _k: u64| v.to_le_bytes().to_vec();
        let read = |b: &[u8], _k: u64| {
            b.try_into()
                .map(u32::from_le_bytes)
                .map_err(|_| "not 4 bytes".to_string())
        };
        // Held by a live process (this one): the waiter reads what the holder writes.
        std::fs::write(
            dir.join("t-0000000000000001.lock"),
            std::process::id().to_string(),
        )
        .expect("lock");
        let dir2 = dir.clone();
        let holder = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            std::fs::write(dir2.join("t-0000000000000001.bin"), 7u32.to_le_bytes()).expect("entry");
        });
        let got = cached(Some(&dir), "t", 1, write, read, || 99u32);
        holder.join().expect("holder");
        assert_eq!(
            got, 7,
            "the waiter must read the holder's entry, not compute its own"
        );
        // Held by a process that is gone: taken over and computed.
        std::fs::write(dir.join("t-0000000000000002.lock"), "4194303999").expect("lock");
        assert_eq!(cached(Some(&dir), "t", 2, write, read, || 5u32), 5);
        assert!(!dir.join("t-0000000000000002.lock").exists());
        assert_eq!(
            std::fs::read(dir.join("t-0000000000000002.bin")).expect("entry"),
            5u32.to_le_bytes()
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_written_basis_reads_back_identical() {
        settled_secret();
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/basics/square-occluder.json");
        let point = umbra_case::load_file(&file).expect("case").remove(0);
        let prepared = Prepared::new(point).lights.remove(0);
        let profile = Profile::GLES2;
        let truth = ground_truth(&prepared);
        let judged = umbra_ref::explain_light(&prepared, ClipDepth::MinusOneToOne, profile, None).0;
        let (kt, kj) = (
            key(&prepared.point, ""),
            key(&prepared.point, &profile.name()),
        );
        assert_ne!(
            kj,
            key(&prepared.point, &Profile::GL.name()),
            "the profile is part of the key"
        );
        let back = read_truth(&write_truth(&truth, kt), kt).expect("truth");
        assert_eq!(
            (back.class, back.edge, back.face),
            (truth.class.clone(), truth.edge.clone(), truth.face.clone())
        );
        let bytes = write_judged(&judged, kj);
        // What packing is for: a judged render is mostly runs of equal values.
        let inflated = unpack_parts(unsealed(&bytes).expect("sealed"), 2)
            .expect("packed")
            .len();
        assert!(
            bytes.len() * 4 < inflated,
            "packed {} bytes of {inflated}",
            bytes.len()
        );
        let back = read_judged(&bytes, kj, profile, ColorFormat::Rgba8, true).expect("judged");
        let lit = read_judged(&bytes, kj, profile, ColorFormat::Rgba8, false).expect("judged");
        assert!(lit.lights.iter().all(|l| l.map.is_empty()));
        assert_eq!(lit.lights[0].legal, judged.lights[0].legal);
        assert_eq!(back.frame.color, judged.frame.color);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(back.lights.len(), judged.lights.len());
        assert_eq!(back.frame.lights.len(), judged.frame.lights.len());
        for (b, j) in back.frame.lights.iter().zip(&judged.frame.lights) {
            assert_eq!(bits(&b.visibility), bits(&j.visibility));
            assert_eq!(b.surface, j.surface);
        }
        for (b, j) in back.lights.iter().zip(&judged.lights) {
            assert_eq!(b.legal, j.legal);
            assert_eq!(b.quantum.to_bits(), j.quantum.to_bits());
            assert_eq!(b.map, j.map);
        }
        // Another key (another case or profile) is refused, and so is a truncated file.
        for map in [true, false] {
            assert!(read_judged(&bytes, kj ^ 1, profile, ColorFormat::Rgba8, map).is_err());
            let cut = &bytes[..bytes.len() - 1];
            assert!(read_judged(cut, kj, profile, ColorFormat::Rgba8, map).is_err());
        }
        assert!(read_truth(&write_truth(&truth, kt)[1..], kt).is_err());
    }

    /// Every way an entry can be damaged is refused with its reason, and the basis computed
    /// through a damaged cache is the clean one, bit for bit.
    #[test]
    fn a_damaged_entry_is_refused_and_recomputed_identical() {
        settled_secret();
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/basics/square-occluder.json");
        let prepared = Prepared::new(umbra_case::load_file(&file).expect("case").remove(0))
            .lights
            .remove(0);
        let clean = ground_truth(&prepared);
        let kt = key(&prepared.point, "");
        let good = write_truth(&clean, kt);
        let mut flipped = good.clone();
        flipped[40] ^= 0x04;
        let raw = unpack(unsealed(&good).expect("sealed")).expect("packed");
        for (bytes, why) in [
            (Vec::new(), "is empty"),
            (good[..good.len() / 2].to_vec(), "damaged"),
            (flipped, "fails its checksum"),
            (good[..6].to_vec(), "truncated"),
            (raw.clone(), "fails its checksum"),
            (sealed(raw), "not a packed entry"),
        ] {
            let err = read_truth(&bytes, kt).err().unwrap_or_default();
            assert!(err.contains(why), "{why}: {err}");
        }
        // Every single-bit change of the stored bytes is refused, wherever it falls: in the
        // deflate stream's Huffman header too, where some flips inflate to the same bytes
        // (the entry still right, but the damage unsaid; the checksum used to be inside).
        for bit in 0..good.len() * 8 {
            let mut b = good.clone();
            b[bit / 8] ^= 1 << (bit % 8);
            assert!(
                read_truth(&b, kt).is_err_and(|e| e.contains("fails its checksum")),
                "bit {bit} of {} bytes",
                good.len()
            );
        }
        // Damage that keeps a valid checksum (a hostile edit): every pixel "outside the
        // light", which once judged nothing and passed. The sample recomputes the truth.
        let mut outside = clean.clone();
        outside
            .class
            .iter_mut()
            .filter(|c| matches!(c, Class::Lit | Class::Shadowed))
            .for_each(|c| *c = Class::Outside);
        let forged = write_truth(&outside, kt);
        let read = read_truth(&forged, kt).expect("well formed");
        let err = sampled(&prepared, read).err().unwrap_or_default();
        assert!(err.contains("disagrees with the exact truth"), "{err}");
        assert!(sampled(&prepared, read_truth(&good, kt).expect("good")).is_ok());
        // Through the cache: each damaged entry is replaced by the clean one.
        let dir = std::env::temp_dir().join(format!("umbra-damaged-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let entry = dir.join(format!("truth-{kt:016x}.bin"));
        for damaged in [Vec::new(), good[..100].to_vec(), forged] {
            std::fs::write(&entry, &damaged).expect("damage");
            let got = cached(
                Some(&dir),
                "truth",
                kt,
                write_truth,
                |b, k| read_truth(b, k).and_then(|t| sampled(&prepared, t)),
                || ground_truth(&prepared),
            );
            assert_eq!(
                (&got.class, &got.edge, &got.face),
                (&clean.class, &clean.edge, &clean.face)
            );
            assert_eq!(std::fs::read(&entry).expect("rewritten"), good);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// An entry edited and resealed with the checksum's published algorithm but without the
    /// cache's secret (issue 36: a judged entry with widened intervals and a valid FNV
    /// checksum was used) fails its checksum.
    #[test]
    fn an_entry_resealed_without_the_cache_secret_is_refused() {
        settled_secret();
        let body = b"UMBJ5 an entry whose intervals were widened".to_vec();
        assert!(unsealed(&sealed(body.clone())).is_ok());
        let mut forged = body.clone();
        let unkeyed = {
            use std::hash::Hasher as _;
            #[allow(deprecated)]
            let mut h = std::hash::SipHasher::new_with_keys(0, 0);
            h.write(&body);
            h.write_usize(body.len());
            h.finish()
        };
        forged.extend_from_slice(&unkeyed.to_le_bytes());
        assert!(unsealed(&forged).is_err_and(|e| e.contains("checksum")));
    }

    #[test]
    fn a_build_keeps_its_own_entries_and_drops_other_builds() {
        let root = std::env::temp_dir().join(format!("umbra-judge-cache-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let other = root.join("0123456789abcdef-42");
        let unrelated = root.join("notes");
        for d in [&other, &unrelated] {
            std::fs::create_dir_all(d).expect("dir");
        }
        let unversioned = root.join("truth-0123.bin");
        std::fs::write(&unversioned, b"x").expect("old entry");
        let mine = prepare(&root);
        assert!(mine.ends_with(build_id()) && mine.is_dir());
        // Built in its workspace, the key is the sources' (basis_key), not the executable's.
        assert!(build_id().ends_with("-src"), "{}", build_id());
        assert!(!other.exists(), "another build's entries are removed");
        assert!(unrelated.exists(), "nothing else is touched");
        assert!(
            !unversioned.exists(),
            "entries of the unversioned layout are removed"
        );
        std::fs::write(mine.join("truth-1.bin"), b"x").expect("entry");
        assert_eq!(prepare(&root), mine);
        assert!(
            mine.join("truth-1.bin").exists(),
            "this build's entries survive"
        );
        let _ = std::fs::remove_dir_all(&root);
    }
}
