//! A conformance run's record for `umbra merge` (`shard.json` in the run's directory): what
//! the run was (the build of umbra, digests of the cases, expectations and goldens it read,
//! the Mesa build, the whole plan before sharding and this shard's place in it) and every
//! run's result in full, as it stood before the checks that read several runs at once
//! (`expect.error_falls_along`, the consensus diagnosis), which the merge makes again over
//! every shard's runs, as one unsharded run would. Written with the other reports, before the
//! run is published, so a shard that did not complete leaves none.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};
use umbra_report::{RunResult, TimeBudget};

use crate::judge::falls_along::FallsAlong;

/// The record's file name in a run's directory.
pub const FILE: &str = "shard.json";

/// The record's format; a merge refuses any other.
pub const SCHEMA: u32 = 1;

/// A run's record.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Record {
    /// [`SCHEMA`].
    pub schema: u32,
    /// The build of umbra.
    pub umbra: Build,
    /// What the run read besides the code.
    pub inputs: Inputs,
    /// The Mesa build (`--mesa`), as report.json has it.
    pub mesa_build: serde_json::Value,
    /// drivers.txt's first line, which names it.
    pub mesa_line: String,
    /// The plan before sharding.
    pub plan: PlanRecord,
    /// This run's share of it.
    pub shard: ShardRecord,
    /// The settings that can change a run's status besides the inputs.
    pub settings: Settings,
    /// Where the worker time went, and the wall time.
    pub budget: TimeBudget,
    /// Per backend: drivers.txt's lines and report.json's row.
    pub drivers: Vec<DriverRecord>,
    /// Backends that refused the Mesa build asked for.
    pub refused: Vec<String>,
    /// Runs whose backend was unavailable.
    pub unavailable_runs: usize,
    /// The cases' `expect.error_falls_along` series.
    pub falls_along: Vec<FallsAlong>,
    /// Every run's result, sorted by name, before the checks across runs.
    pub runs: Vec<RunResult>,
    /// The fingerprint of each failing run, by name (what the consensus compares).
    pub fingerprints: BTreeMap<String, umbra_compare::consensus::Fingerprint>,
}

/// The build of umbra a run came from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Build {
    /// The package version.
    pub version: String,
    /// The key of every crate's sources, Cargo.lock, the toolchain, the build profile and
    /// RUSTFLAGS ([`crate::judge::basis_key::workspace_key`]); empty where the build script
    /// could not compute it (a crate built outside its workspace).
    pub key: String,
    /// The compiler and target it was built with.
    pub toolchain: String,
}

impl Build {
    /// This build.
    pub fn this() -> Build {
        Build {
            version: env!("CARGO_PKG_VERSION").into(),
            key: option_env!("UMBRA_BUILD_KEY").unwrap_or("").into(),
            toolchain: option_env!("UMBRA_BASIS_TOOLCHAIN").unwrap_or("").into(),
        }
    }
}

/// A directory the run read, by its contents.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Digest {
    /// The directory as given.
    pub dir: String,
    /// How many files it holds.
    pub files: usize,
    /// 64-bit FNV-1a over each file's path (relative), length and bytes, in path order.
    pub digest: String,
}

impl Digest {
    /// The digest of every file under `dir`.
    pub fn of(dir: &Path) -> Result<Digest, String> {
        Digest::of_files(dir, |_| true)
    }

    /// The digest of the goldens under `dir`: the reviewed snapshots (`*.snap`,
    /// `*.snap.png`) and the blessed-on record. Pending ones (`*.snap.new*`, which a run at a
    /// desk writes where a picture differs) are not goldens, and would make one shard's
    /// digest differ from the next.
    pub fn of_goldens(dir: &Path) -> Result<Digest, String> {
        Digest::of_files(dir, |name| {
            name.ends_with(".snap")
                || name.ends_with(".snap.png")
                || name == crate::judge::golden::MANIFEST
        })
    }

    fn of_files(dir: &Path, keep: fn(&str) -> bool) -> Result<Digest, String> {
        use crate::judge::basis_key::{FNV_START, files_under, hash_files};
        let files: Vec<_> = files_under(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .into_iter()
            .filter(|f| keep(&f.file_name().unwrap_or_default().to_string_lossy()))
            .collect();
        let h = hash_files(FNV_START, dir, &files)?;
        Ok(Digest {
            dir: dir.display().to_string(),
            files: files.len(),
            digest: format!("{h:016x}"),
        })
    }

    /// Whether two digests are of the same contents (wherever the directories were).
    pub fn same(&self, other: &Digest) -> bool {
        self.files == other.files && self.digest == other.digest
    }
}

/// What a run read besides the code.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Inputs {
    /// `--cases`.
    pub cases: Digest,
    /// `--expectations`.
    pub expectations: Digest,
    /// `--golden`, or `None` for `--golden none`.
    pub golden: Option<Digest>,
}

/// The plan before sharding.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlanRecord {
    /// `--filter`.
    pub filter: String,
    /// The backends selected.
    pub backends: Vec<String>,
    /// Every selected run's name, in plan order.
    pub runs: Vec<String>,
}

/// A run's share of its plan.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardRecord {
    /// I of `--shard I/N`.
    pub index: usize,
    /// N (1: unsharded).
    pub count: usize,
    /// How the plan was split ([`crate::shards::balance::By::describe`]).
    pub by: String,
}

/// The settings that can change a run's status: shards merged must agree on them.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Settings {
    /// `--timeout`, s.
    pub timeout_s: u64,
    /// `--bless` (goldens written, not checked).
    pub bless: bool,
}

/// One backend's driver, as drivers.txt and report.json describe it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DriverRecord {
    /// The backend id.
    pub backend: String,
    /// Its lines in drivers.txt.
    pub text: String,
    /// Its row in report.json's `drivers`.
    pub row: umbra_report::DriverRow,
}

impl Record {
    /// The planned runs this shard holds, in plan order (a case file that did not load is
    /// reported by every shard, under no plan).
    pub fn own_runs(&self) -> Vec<String> {
        let held: std::collections::BTreeSet<&str> =
            self.runs.iter().map(|r| r.name.as_str()).collect();
        self.plan
            .runs
            .iter()
            .filter(|n| held.contains(n.as_str()))
            .cloned()
            .collect()
    }

    /// Writes the record into the run's directory `dir`, synced (a full disk is an error
    /// here, not a short file later), sealed with the checksum of its own bytes
    /// ([`seal`]).
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let json = serde_json::to_vec(self).map_err(std::io::Error::other)?;
        umbra_report::write_synced(&dir.join(FILE), &seal(&json))
    }

    /// Reads a record; an error names the file and says what is wrong with it. A record
    /// whose checksum does not match its bytes (damaged, or edited by hand: a Fail made a
    /// Pass) is refused, as one from an umbra before checksums is.
    pub fn read(path: &Path) -> Result<Record, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let text =
            unseal(&text).map_err(|e| format!("{}: {e}; run the shard again", path.display()))?;
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
            format!(
                "{}: not JSON ({e}): a damaged or truncated record; run the shard again",
                path.display()
            )
        })?;
        match v["schema"].as_u64() {
            Some(s) if s == u64::from(SCHEMA) => {}
            other => {
                return Err(format!(
                    "{}: record schema {} where this umbra reads {SCHEMA}: merge with the umbra that ran the shards",
                    path.display(),
                    other.map_or("missing".to_string(), |s| s.to_string())
                ));
            }
        }
        serde_json::from_value(v).map_err(|e| {
            format!(
                "{}: not a shard record ({e}); run the shard again",
                path.display()
            )
        })
    }
}

/// What a sealed record starts with; the checksum (16 hex digits) follows, then `","record":`.
const SEAL: &str = "{\"checksum\":\"";
const RECORD: &str = "\",\"record\":";

/// `{"checksum":"H","record":R}`: R is the record's JSON, byte for byte as written, and H the
/// FNV-1a hash of those bytes, so a change to any byte of R (a status, a metric, a name) no
/// longer matches H. An accidental-damage and hand-edit check, not a cryptographic one.
pub fn seal(record: &[u8]) -> Vec<u8> {
    let h = crate::judge::basis_key::fnv(crate::judge::basis_key::FNV_START, record);
    let mut out = format!("{SEAL}{h:016x}{RECORD}").into_bytes();
    out.extend_from_slice(record);
    out.push(b'}');
    out
}

/// The record's JSON inside a sealed file, if its checksum holds.
pub fn unseal(text: &str) -> Result<&str, String> {
    // A newline an artifact store or an editor added after the seal is not damage.
    let body = text
        .trim_end()
        .strip_prefix(SEAL)
        .and_then(|t| Some((t.get(..16)?, t.get(16..)?.strip_prefix(RECORD)?)))
        .and_then(|(h, t)| Some((h, t.strip_suffix('}')?)));
    let Some((h, record)) = body else {
        return Err("not a sealed record (no checksum: damaged, or written by an umbra before records were checksummed)".into());
    };
    let sum = crate::judge::basis_key::fnv(crate::judge::basis_key::FNV_START, record.as_bytes());
    if format!("{sum:016x}") != h {
        return Err(format!(
            "its checksum {h} does not match its contents ({sum:016x}): the record was damaged or edited after the run wrote it"
        ));
    }
    Ok(record)
}

#[cfg(test)]
mod tests {
    /// A record edited after it was written (a Fail made a Pass, keeping valid JSON) fails
    /// its checksum; the untouched record reads back.
    #[test]
    fn an_edited_record_is_refused() {
        let record = br#"{"schema":1,"runs":[{"name":"a","status":"Fail"}]}"#;
        let sealed = String::from_utf8(super::seal(record)).expect("utf-8");
        assert_eq!(super::unseal(&sealed).expect("intact").as_bytes(), record);
        let forged = sealed.replace("\"Fail\"", "\"Pass\"");
        let e = super::unseal(&forged).expect_err("forged");
        assert!(e.contains("does not match its contents"), "{e}");
        let e = super::unseal(std::str::from_utf8(record).expect("utf-8")).expect_err("unsealed");
        assert!(e.contains("not a sealed record"), "{e}");
        assert!(super::unseal(&sealed[..sealed.len() - 1]).is_err());
    }

    use super::*;

    #[test]
    fn a_pending_snapshot_leaves_the_goldens_digest_as_it_was() {
        let dir = std::env::temp_dir().join(format!("umbra-digest-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("ref_a.snap"), "x").expect("write");
        std::fs::write(dir.join("ref_a.snap.png"), "png").expect("write");
        let before = Digest::of_goldens(&dir).expect("digest");
        std::fs::write(dir.join("ref_a.snap.new"), "y").expect("write");
        std::fs::write(dir.join("ref_a.snap.new.png"), "png2").expect("write");
        assert_eq!(Digest::of_goldens(&dir).expect("digest"), before);
        // A golden that changes does change it; every file counts in `of`.
        std::fs::write(dir.join("ref_a.snap.png"), "png3").expect("write");
        assert!(!Digest::of_goldens(&dir).expect("digest").same(&before));
        assert_eq!(Digest::of(&dir).expect("digest").files, 4);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
