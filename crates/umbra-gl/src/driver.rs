//! Mesa drivers and the environment that selects them. Mesa reads `GALLIUM_DRIVER` (and
//! `LIBGL_ALWAYS_SOFTWARE`) when EGL loads a driver, so one process hosts one driver: the
//! runner starts a process per driver with [`Driver::env`] set.

/// A Mesa driver reachable on a machine without a GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Driver {
    /// Gallium's LLVM rasterizer (Mesa's default software driver).
    Llvmpipe,
    /// Gallium's reference rasterizer.
    Softpipe,
    /// GL on Vulkan (here on lavapipe).
    Zink,
}

impl Driver {
    /// Every driver, in report order.
    pub const ALL: [Driver; 3] = [Driver::Llvmpipe, Driver::Softpipe, Driver::Zink];

    /// The id suffix.
    pub fn name(self) -> &'static str {
        match self {
            Driver::Llvmpipe => "llvmpipe",
            Driver::Softpipe => "softpipe",
            Driver::Zink => "zink",
        }
    }

    /// Parses an id suffix.
    pub fn parse(s: &str) -> Option<Driver> {
        Driver::ALL.into_iter().find(|d| d.name() == s)
    }

    /// The environment that selects the driver (zink alone fails without
    /// LIBGL_ALWAYS_SOFTWARE=1 on this Mesa; docs/platform.md).
    pub fn env(self) -> Vec<(&'static str, &'static str)> {
        match self {
            Driver::Llvmpipe => vec![("GALLIUM_DRIVER", "llvmpipe")],
            Driver::Softpipe => vec![("GALLIUM_DRIVER", "softpipe")],
            // NODEVICE_SELECT: the Vulkan device-select layer only complains about DISPLAY.
            Driver::Zink => vec![
                ("LIBGL_ALWAYS_SOFTWARE", "1"),
                ("GALLIUM_DRIVER", "zink"),
                ("NODEVICE_SELECT", "1"),
            ],
        }
    }

    /// The environment as shell text.
    pub fn env_text(self) -> String {
        self.env()
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Whether this process's environment selects the driver (llvmpipe is also the default).
    pub fn is_selected(self) -> bool {
        let gallium = std::env::var("GALLIUM_DRIVER").ok();
        match self {
            Driver::Llvmpipe => gallium.as_deref().is_none_or(|g| g == "llvmpipe"),
            _ => self
                .env()
                .iter()
                .all(|(k, v)| std::env::var(k).ok().as_deref() == Some(v)),
        }
    }

    /// Whether GL_RENDERER names this driver.
    pub fn matches_renderer(self, renderer: &str) -> bool {
        match self {
            Driver::Llvmpipe => renderer.starts_with("llvmpipe"),
            Driver::Softpipe => renderer.starts_with("softpipe"),
            Driver::Zink => renderer.starts_with("zink"),
        }
    }
}
