//! The judging basis of a case point, the exact truth and the reference's judged frame with
//! its lookup ambiguity, computed once per point and shared by every backend's worker.
//!
//! Both depend on the case point only, never on the backend, yet each backend's worker used
//! to recompute them: twelve times per point, two thirds of a conformance run's worker time.
//! A conformance run now names a cache directory in `UMBRA_JUDGE_CACHE` (it empties it first,
//! so nothing survives a rebuild); the first worker to judge a point writes the basis there
//! (to a temporary name, then renamed, so a reader never sees half a file) and the others
//! read it. Without the variable (`umbra render`, tests, the self-test) the basis is computed
//! in place, as before.
//!
//! Format, little-endian: `UMBJ1`, width and height (u32), a u64 key check, then per pixel
//! the truth's class (u8), edge flag (u8) and face (u32), the reference's RGBA8 colour, its
//! visibility (f32), whether a surface buffer follows (u8) and its face ids (u32), and the
//! ambiguity flags (u8). The truth's hit points are not kept (the judge does not read them).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use umbra_case::{ClipDepth, Frame, Prepared};
use umbra_ref::truth::{Class, Truth, ground_truth};

/// The environment variable naming the cache directory.
pub const ENV: &str = "UMBRA_JUDGE_CACHE";

const MAGIC: &[u8; 5] = b"UMBJ1";

/// The truth, and the reference frame with its ambiguity flags.
pub struct Basis {
    /// The exact truth.
    pub truth: Truth,
    /// The reference's frame and, per pixel, [`umbra_ref::lookup::ambiguity`] flags.
    pub judged: (Frame, Vec<u8>),
}

/// The basis of `prepared`: from the cache when the run has one, else computed.
pub fn basis(prepared: &Prepared) -> Basis {
    let Some(dir) = std::env::var_os(ENV).map(PathBuf::from) else {
        return compute(prepared);
    };
    let key = key(prepared);
    let file = dir.join(format!("{key:016x}.bin"));
    if let Some(b) = read(&file, key) {
        return b;
    }
    let b = compute(prepared);
    // A cache that cannot be written only costs time: the basis is still right.
    let _ = write(&dir, &file, key, &b);
    b
}

fn compute(prepared: &Prepared) -> Basis {
    Basis {
        truth: ground_truth(prepared),
        judged: umbra_ref::render_judged(prepared, ClipDepth::MinusOneToOne),
    }
}

/// 64-bit FNV-1a of the resolved case point (everything the basis depends on).
fn key(prepared: &Prepared) -> u64 {
    let text = serde_json::to_string(&prepared.point.case).unwrap_or_default();
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

fn write(dir: &Path, file: &Path, key: u64, b: &Basis) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let (frame, ambiguity) = &b.judged;
    let t = &b.truth;
    let n = (t.width * t.height) as usize;
    let mut out = Vec::with_capacity(32 + n * 20);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&t.width.to_le_bytes());
    out.extend_from_slice(&t.height.to_le_bytes());
    out.extend_from_slice(&key.to_le_bytes());
    out.extend(t.class.iter().map(|c| class_code(*c)));
    out.extend(t.edge.iter().map(|e| u8::from(*e)));
    t.face
        .iter()
        .for_each(|f| out.extend_from_slice(&f.to_le_bytes()));
    out.extend_from_slice(&frame.color);
    frame
        .visibility
        .iter()
        .for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
    match &frame.surface {
        Some(s) => {
            out.push(1);
            s.iter()
                .for_each(|f| out.extend_from_slice(&f.to_le_bytes()));
        }
        None => out.push(0),
    }
    out.extend_from_slice(ambiguity);
    let tmp = dir.join(format!(".{key:016x}.{}.tmp", std::process::id()));
    std::fs::File::create(&tmp)?.write_all(&out)?;
    std::fs::rename(&tmp, file)
}

fn read(file: &Path, key: u64) -> Option<Basis> {
    let mut bytes = Vec::new();
    std::fs::File::open(file)
        .ok()?
        .read_to_end(&mut bytes)
        .ok()?;
    let mut r = Reader {
        bytes: &bytes,
        at: 0,
    };
    if r.take(5)? != MAGIC {
        return None;
    }
    let (width, height) = (r.u32()?, r.u32()?);
    if r.u64()? != key {
        return None;
    }
    let n = (width as usize).checked_mul(height as usize)?;
    let class = r
        .take(n)?
        .iter()
        .map(|b| class_of(*b))
        .collect::<Option<Vec<_>>>()?;
    let edge = r.take(n)?.iter().map(|b| *b != 0).collect();
    let face = (0..n).map(|_| r.u32()).collect::<Option<Vec<_>>>()?;
    let color = r.take(n * 4)?.to_vec();
    let visibility = (0..n)
        .map(|_| r.u32().map(f32::from_bits))
        .collect::<Option<Vec<_>>>()?;
    let surface = match r.take(1)?[0] {
        1 => Some((0..n).map(|_| r.u32()).collect::<Option<Vec<_>>>()?),
        _ => None,
    };
    let ambiguity = r.take(n)?.to_vec();
    if r.at != bytes.len() {
        return None;
    }
    Some(Basis {
        truth: Truth {
            width,
            height,
            class,
            edge,
            face,
            point: Vec::new(),
            elapsed: Duration::ZERO,
        },
        judged: (
            Frame {
                width,
                height,
                color,
                visibility,
                surface,
                shadow_map: None,
                timings: Default::default(),
            },
            ambiguity,
        ),
    })
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
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_basis_reads_back_identical() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/basics/square-occluder.json");
        let point = umbra_case::load_file(&file).expect("case").remove(0);
        let prepared = Prepared::new(point);
        let b = compute(&prepared);
        let dir = std::env::temp_dir().join(format!("umbra-judge-cache-{}", std::process::id()));
        let k = key(&prepared);
        let path = dir.join("x.bin");
        write(&dir, &path, k, &b).expect("write");
        let back = read(&path, k).expect("read");
        assert_eq!(back.truth.class, b.truth.class);
        assert_eq!(back.truth.edge, b.truth.edge);
        assert_eq!(back.truth.face, b.truth.face);
        assert_eq!(back.judged.0.color, b.judged.0.color);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&back.judged.0.visibility),
            bits(&b.judged.0.visibility)
        );
        assert_eq!(back.judged.0.surface, b.judged.0.surface);
        assert_eq!(back.judged.1, b.judged.1);
        // Another key (another case) is refused, and so is a truncated file.
        assert!(read(&path, k ^ 1).is_none());
        let bytes = std::fs::read(&path).expect("bytes");
        std::fs::write(&path, &bytes[..bytes.len() - 1]).expect("truncate");
        assert!(read(&path, k).is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
