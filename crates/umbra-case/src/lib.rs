//! umbra's lowest layer: the case format and everything every backend shares.
//!
//! - [`format`]: the JSON a user writes (serde types; every default documented there and in
//!   `cases/README.md`).
//! - [`validate`] and [`load`]: parsing with errors that name the file, the JSON path and the
//!   fix; sweep expansion into [`point::CasePoint`]s ([`point`]: a point and the JSON paths
//!   into a case, below the loader and the twins).
//! - [`schema`]: the format as a schema that conditions over a case point (`@when`) are
//!   checked against, and the precision their numbers compare at.
//! - [`scene`]: the one tessellation every backend draws.
//! - [`conventions`]: clip ranges, projections, the bias matrix, window mapping, compares. The
//!   only place a projection is built.
//! - [`light`] and [`prepare`]: the light faces and camera of a run, fitted where asked.
//! - [`depth`]: storage per depth format and the polygon-offset unit; [`colour`]: the lit
//!   pass's colour target (linear or sRGB) and the freedom of its encoding.
//! - [`math`]: the transcendental functions, the same on every C library (musl's, in Rust).
//! - [`frame`] and [`backend`]: what a backend returns and the trait it implements.
//! - [`profile`]: what an API lets an implementation do differently (the judge's input), and
//!   the driver deviations diagnosed in Mesa's sources that expectations can name.
//! - [`generate`]: valid cases drawn from a seed across the whole format, for soaking the
//!   judge on scenes it was not developed against (`umbra soak`).
//! - [`technique`] and [`lit_shader`]: the lit pass's technique read from a run once, the
//!   self-test's faults resolved on it, and the lookup's steps written once for any shading
//!   language (GL and wgpu supply only their language).
//!
//! Design decision: the `Backend` trait and `Frame` live here rather than in the runner,
//! because every backend crate implements them and none may depend on the runner (which
//! depends on all of them). This crate depends on no GPU crate.

pub mod backend;
pub mod calibration;
pub mod camera;
pub mod colour;
pub mod conventions;
pub mod depth;
pub mod error;
pub mod fault;
pub mod format;
pub mod frame;
pub mod generate;
pub mod light;
pub mod lit_shader;
pub mod load;
pub mod math;
pub mod memory;
pub mod offset;
pub mod point;
pub mod prepare;
pub mod profile;
pub mod scene;
pub mod schema;
pub mod technique;
pub mod twin;
pub mod validate;

pub use backend::{
    Backend, BackendError, BackendId, Capabilities, DriverInfo, Needs, ReproProgram, Support,
};
pub use calibration::Calibration;
pub use conventions::{ClipDepth, Convention, LookupMatrices, ShadowCoord};
pub use error::{CaseError, CaseErrors};
pub use format::Case;
pub use frame::{Clock, DepthMap, Frame, LightFrame, LightPlane, Timings, VisibilityStorage};
pub use light::{LightKind, LightSetup};
pub use load::{CasePoint, case_files, get_path, load_file, load_str};
pub use prepare::{LightRun, OfLights, Prepared};
pub use profile::{Deviation, Deviations, Profile, Spec};
pub use scene::{Geometry, tessellate};
pub use technique::Technique;
