//! umbra's OpenGL backend: GL 3.3 core, GLES 3.0 and GLES 2.0 through EGL, on Mesa's
//! software drivers (llvmpipe, softpipe and zink, chosen by environment on the surfaceless
//! platform: [`parse_id`]) and on any EGL device a machine has, whoever made its driver
//! (`gl33/radeonsi`, `gl33/nvidia`: [`parse_device_id`], [`platform::named_devices`]).
//!
//! - [`platform`]: how EGL reaches the driver, surfaceless or an EGL device.
//! - [`context`]: EGL loaded at run time; a missing library or driver is
//!   [`context::Unavailable`] with the package to install, never a panic.
//! - [`driver`]: one Mesa driver per process, selected by environment before EGL loads.
//! - [`caps`]: what the driver can do, probed once; the only place its differences live.
//! - [`shaders`]: GLSL per API and technique, mirroring the reference's lookup.
//! - [`render`]: both passes, checks after every stage, readback with the one row flip.
//! - [`record`] and [`repro_c`]: a run's GL calls as a standalone C program (`umbra repro`).
//! - [`backend`]: the `Backend` trait, with what each API supports.
//!
//! Conventions come from `umbra_case::conventions` (GL clip range, the case's depth order);
//! no projection is built here.
#![allow(unsafe_code)] // FFI: EGL and GL calls are unsafe by nature; each block says why it holds.

pub mod api;
pub mod backend;
pub mod caps;
pub mod context;
pub mod driver;
pub mod inject;
pub mod platform;
pub mod record;
pub mod render;
pub mod repro_c;
pub mod shaders;

pub use api::Api;
pub use backend::GlBackend;
pub use driver::Driver;

/// Parses a backend id of a Mesa software driver such as `gles3/softpipe`.
pub fn parse_id(id: &str) -> Option<(Api, Driver)> {
    let (api, driver) = id.split_once('/')?;
    Some((Api::parse(api)?, Driver::parse(driver)?))
}

/// Parses a backend id of an EGL device such as `gl33/radeonsi`, `gles3/iris.2` or
/// `gl33/nvidia` (its name from [`platform::named_devices`]): an API, then a name that is
/// not one of the Mesa software drivers' (those are [`parse_id`]'s, chosen by environment).
/// Whether such a device exists is only known by listing the devices.
pub fn parse_device_id(id: &str) -> Option<(Api, &str)> {
    let (api, name) = id.split_once('/')?;
    (umbra_case::BackendId::is_name_part(name) && Driver::parse(name).is_none())
        .then_some((Api::parse(api)?, name))
}

/// Every GL backend id, in report order.
pub fn ids() -> Vec<String> {
    Driver::ALL
        .iter()
        .flat_map(|d| {
            Api::ALL
                .iter()
                .map(move |a| format!("{}/{}", a.name(), d.name()))
        })
        .collect()
}
