//! Fake backends that misbehave on purpose, for the runner's own tests: `fake/crash` aborts
//! the process, `fake/hang` never returns, `fake/flaky` renders wrong on its first call and
//! right afterwards, `fake/wrong` inverts every shadow, and `fake/mesa` stands in for a Mesa
//! driver build (`--mesa DIR` with a [`crate::mesa_build::FAKE_MARKER`] file: it reports that
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
pub const IDS: [&str; 6] = [
    "fake/crash",
    "fake/hang",
    "fake/flaky",
    "fake/wrong",
    MESA,
    "fake/hog",
];

/// The fake that runs on a fake Mesa build.
pub const MESA: &str = "fake/mesa";

/// The fake build's marker file, when this process runs on one: (version, fault).
fn fake_build() -> Option<(String, Option<String>)> {
    let root = std::env::var(crate::mesa_build::ENV).ok()?;
    let text =
        std::fs::read_to_string(Path::new(&root).join(crate::mesa_build::FAKE_MARKER)).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some((
        v["version"].as_str().unwrap_or("0.0.0").to_string(),
        v["fault"].as_str().map(str::to_string),
    ))
}

/// A misbehaving backend around the reference.
pub struct Fake {
    id: &'static str,
    calls: u32,
}

impl Fake {
    /// The fake `id`, if it is one.
    pub fn new(id: &str) -> Option<Fake> {
        IDS.iter()
            .find(|f| **f == id)
            .map(|f| Fake { id: f, calls: 0 })
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
            "fake/crash" => std::process::abort(),
            "fake/hang" => loop {
                std::thread::sleep(std::time::Duration::from_secs(3600));
            },
            "fake/flaky" if self.calls > 1 => {}
            MESA if fake_build().and_then(|b| b.1).as_deref() != Some("invert") => {}
            _ => {
                for v in &mut frame.visibility {
                    if !v.is_nan() {
                        *v = 1.0 - *v;
                    }
                }
                // The picture changes with the shadows (goldens see it too).
                for px in frame.color.chunks_exact_mut(4) {
                    for c in &mut px[..3] {
                        *c = 255 - *c;
                    }
                }
            }
        }
        Ok(frame)
    }
}
