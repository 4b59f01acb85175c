//! Fake backends that misbehave on purpose, for the runner's own tests: `fake/crash` aborts
//! the process, `fake/hang` never returns, `fake/flaky` renders wrong on its first call and
//! right afterwards, `fake/wrong` inverts every shadow. They exist only when the environment
//! has `UMBRA_FAKE_BACKENDS=1`, so no user run can select one by accident.

use umbra_case::{
    Backend, BackendError, BackendId, DriverInfo, Frame, Needs, Prepared, Profile, Support,
};

/// Whether fake backends are enabled in this process.
pub fn enabled() -> bool {
    std::env::var("UMBRA_FAKE_BACKENDS").is_ok_and(|v| v == "1")
}

/// The fake ids.
pub const IDS: [&str; 4] = ["fake/crash", "fake/hang", "fake/flaky", "fake/wrong"];

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
        DriverInfo {
            vendor: "umbra".into(),
            renderer: format!("{} (test double)", self.id),
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
        let mut frame = umbra_ref::render(run, umbra_case::ClipDepth::MinusOneToOne);
        match self.id {
            "fake/crash" => std::process::abort(),
            "fake/hang" => loop {
                std::thread::sleep(std::time::Duration::from_secs(3600));
            },
            "fake/flaky" if self.calls > 1 => {}
            _ => {
                for v in &mut frame.visibility {
                    if !v.is_nan() {
                        *v = 1.0 - *v;
                    }
                }
            }
        }
        Ok(frame)
    }
}
