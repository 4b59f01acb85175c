//! Fake backends that misbehave on purpose, for the runner's own tests: `fake/crash` aborts
//! the process, `fake/sigbus` dies of a real SIGBUS (a mapped file cut short), `fake/hang`
//! never returns, `fake/flaky` aborts its first worker of a run
//! (the first to claim `UMBRA_FAKE_FLAKY_FILE`, else a file named for its parent process) and renders right in every
//! other, `fake/stale` keeps state from one render to the next (right on a worker's first
//! case, every shadow of any later case inverted, as a stale uniform would), `fake/wrong` inverts
//! every shadow, and `fake/mesa` stands in for a Mesa
//! driver build (`--mesa DIR` with a [`MARKER`] file: it reports that
//! file's version, and inverts every shadow when the file says `"fault": "invert"`), so the
//! bisect driver and per-driver expectations are tested without building Mesa; `fake/hog`
//! is a runaway that keeps allocating (64 MiB every 20 ms, up to 16 GiB), for the memory
//! limit. They exist
//! only when the environment has `UMBRA_FAKE_BACKENDS=1`, so no user run can select one by
//! accident.

use std::path::Path;

use umbra_case::{
    Backend, BackendError, BackendId, DriverInfo, Frame, Needs, Prepared, Profile, Support,
};

/// Whether fake backends are enabled in this process.
pub fn enabled() -> bool {
    std::env::var("UMBRA_FAKE_BACKENDS").is_ok_and(|v| v == "1")
}

/// The fake ids.
pub const IDS: [&str; 8] = [
    "fake/crash",
    "fake/sigbus",
    "fake/hang",
    "fake/flaky",
    "fake/wrong",
    MESA,
    "fake/hog",
    "fake/stale",
];

/// The fake that runs on a fake Mesa build.
pub const MESA: &str = "fake/mesa";

/// A marker file that makes a directory a fake Mesa build, for the runner's own tests (only
/// with fake backends enabled): `{"version": "...", "fault": "invert" | "background" | null}`
/// ("background": the background's alpha changed, which only the golden sees).
pub const MARKER: &str = "umbra-fake-mesa.json";

/// The marker of the fake build in `root`, if it is one: (version, fault), or why the marker
/// cannot be read.
pub fn marker(root: &Path) -> Option<Result<(String, Option<String>), String>> {
    let text = std::fs::read_to_string(root.join(MARKER)).ok()?;
    Some(
        serde_json::from_str::<serde_json::Value>(&text)
            .map(|v| {
                (
                    v["version"].as_str().unwrap_or("0.0.0").to_string(),
                    v["fault"].as_str().map(str::to_string),
                )
            })
            .map_err(|_| format!("{MARKER} is not JSON")),
    )
}

/// The fake build this process runs on, if any: `UMBRA_MESA` (set by the orchestrator for
/// every worker on a selected build) names it.
fn fake_build() -> Option<(String, Option<String>)> {
    let root = std::env::var_os("UMBRA_MESA")?;
    marker(Path::new(&root))?.ok()
}

/// A misbehaving backend around the reference.
pub struct Fake {
    id: &'static str,
    calls: u32,
    /// The first case this worker rendered (`fake/stale`: its state is right for it alone).
    first: Option<String>,
}

impl Fake {
    /// The fake `id`, if it is one.
    pub fn new(id: &str) -> Option<Fake> {
        IDS.iter().find(|f| **f == id).map(|f| Fake {
            id: f,
            calls: 0,
            first: None,
        })
    }
}

impl Backend for Fake {
    fn id(&self) -> BackendId {
        BackendId(self.id.into())
    }

    fn info(&self) -> DriverInfo {
        let version = match (self.id, fake_build()) {
            (MESA, Some((v, _))) => format!("Mesa {v} (fake build)"),
            (MESA, None) => "Mesa 0.0.0 (fake, no build given)".into(),
            _ => String::new(),
        };
        DriverInfo {
            vendor: "umbra".into(),
            renderer: format!("{} (test double)", self.id),
            version,
            ..Default::default()
        }
    }

    fn profile(&self) -> Profile {
        Profile::GL
    }

    fn supports(&self, _needs: &Needs) -> Support {
        Support::Supported
    }

    fn render(&mut self, run: &Prepared) -> Result<Frame, BackendError> {
        self.calls += 1;
        if self.id == "fake/hog" {
            let mut held: Vec<Vec<u8>> = Vec::new();
            for _ in 0..256 {
                // Touched, so it is resident.
                held.push(vec![1u8; 64 << 20]);
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            return Err(BackendError::Other(format!(
                "fake/hog held {} MiB and was not stopped",
                held.len() * 64
            )));
        }
        let mut frame = umbra_ref::render(run, umbra_case::ClipDepth::MinusOneToOne);
        match self.id {
            "fake/crash" => {
                // What a driver's heap corruption leaves on stderr before the signal, after a
                // line that is not UTF-8 (a driver may write any bytes).
                let _ = std::io::Write::write_all(&mut std::io::stderr(), b"\xff\xfe bytes\n");
                eprintln!(
                    "corrupted size vs. prev_size (fake/crash: the last words of a heap corruption)"
                );
                std::process::abort()
            }
            // A real SIGBUS as a driver meets one: a shared mapping of a file that another
            // hand cut short under it (BUS_ADRERR), for the crash report's test.
            "fake/sigbus" => sigbus(),
            "fake/hang" => loop {
                std::thread::sleep(std::time::Duration::from_secs(3600));
            },
            // Nondeterminism across processes: the first worker of the run to claim the file
            // dies, every later one renders right.
            "fake/flaky" if run.case().name != "card-probe" => {
                // The test names a fresh file (no earlier run's claim can be reused).
                let claim = std::env::var_os("UMBRA_FAKE_FLAKY_FILE").map_or_else(
                    || {
                        std::env::temp_dir().join(format!(
                            "umbra-fake-flaky-{}",
                            std::os::unix::process::parent_id()
                        ))
                    },
                    std::path::PathBuf::from,
                );
                if std::fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(&claim)
                    .is_ok()
                {
                    eprintln!("fake/flaky: this worker dies once");
                    std::process::abort()
                }
            }
            // The state a worker's first case left (a stale uniform) is right for that
            // case, and its twins, alone: every other case point renders wrong.
            "fake/flaky" => {}
            "fake/stale"
                if run.case().name == "card-probe"
                    || self.first.get_or_insert_with(|| run.case().name.clone())
                        == &run.case().name => {}
            // A change only where the judge does not look: the background's alpha (the judge
            // holds the background's RGB to the clear colour since issue 39; alpha is the
            // golden's alone).
            MESA if fake_build().and_then(|b| b.1).as_deref() == Some("background") => {
                for i in 0..(frame.width * frame.height) as usize {
                    if !frame.covered(i) {
                        frame.color[i * 4 + 3] = 128;
                    }
                }
            }
            MESA if fake_build().and_then(|b| b.1).as_deref() != Some("invert") => {}
            _ => {
                for v in frame.lights.iter_mut().flat_map(|p| &mut p.visibility) {
                    if !v.is_nan() {
                        *v = 1.0 - *v;
                    }
                }
                // The picture changes with the shadows (goldens see it too); the background,
                // which has none, stays.
                for i in 0..(frame.width * frame.height) as usize {
                    if frame.covered(i) {
                        for c in &mut frame.color[i * 4..i * 4 + 3] {
                            *c = 255 - *c;
                        }
                    }
                }
            }
        }
        Ok(frame)
    }
}

/// Maps a one-page file, cuts the file to nothing and reads the mapping: the kernel sends
/// SIGBUS (BUS_ADRERR), as it does to a driver whose mapped cache file shrank.
#[allow(unsafe_code)] // mmap(2): the block says why it holds.
fn sigbus() -> ! {
    use std::os::fd::AsRawFd as _;
    let path = std::env::temp_dir().join(format!("umbra-fake-sigbus-{}", std::process::id()));
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(true)
        .open(&path);
    if let Ok(file) = file {
        let _ = file.set_len(4096);
        // SAFETY: a fresh shared mapping of the file's one page, read once below; the
        // process is meant to die of that read.
        unsafe {
            let p = libc::mmap(
                std::ptr::null_mut(),
                4096,
                libc::PROT_READ,
                libc::MAP_SHARED,
                file.as_raw_fd(),
                0,
            );
            let _ = std::fs::remove_file(&path);
            if p != libc::MAP_FAILED {
                let _ = file.set_len(0);
                std::ptr::read_volatile(p.cast::<u8>());
            }
        }
    }
    eprintln!("fake/sigbus: the mapping did not fault");
    std::process::abort()
}
