//! `umbra repro`'s bundle: what a failing run becomes so that a driver developer who has
//! never heard of umbra can see, run and bisect it.
//!
//! - [`emit`] runs in the driver's process, on the already reduced case: it renders the run
//!   once judged (pictures, failed checks) and once recorded (every GL call, as
//!   [`umbra_gl::record`] writes it), selects the [`probes`] and writes `repro.c`, the
//!   pictures and `facts.json` (what the parent needs for issue.md).
//! - [`issue`] writes `issue.md` (Mesa's bug template) and `README.md` from those facts and
//!   from what the parent measured: `repro`'s exit codes on the driver and on a conforming
//!   one, and the API capture's replays.
//!
//! A repro is only as good as its intervals: the probes are the judge's own numbers at the
//! pixels and texels the judge failed ([`probes`]), so the program cannot pass where umbra
//! fails nor fail where umbra passes (on the same frame), and `umbra repro` runs it on both
//! drivers before it calls the bundle done.

pub mod issue;
pub mod pictures;
pub mod probes;
pub mod state;

use std::path::Path;

use serde::{Deserialize, Serialize};
use umbra_case::{BackendError, Prepared};

use crate::exit::{Error, Exit, Outcome};

/// The spec text each probe kind is held to (the judge's derivation lives in cases/README.md
/// and docs/platform.md; these are the clauses a driver developer looks up).
pub const VALUE_CLAUSE: &str = "GL 4.6 §8.23.1 depth texture comparison with the freedoms of §8.14 (texel selection, LINEAR weights), §14.5 (rasterization's sub-pixel precision) and §14.6.5 (depth offset); Vulkan 1.3 \"Depth Compare Operation\"";
/// The clause of the map's texels.
pub const MAP_CLAUSE: &str = "GL 4.6 §14.6.5 depth offset (o = m·factor + r·units added to each fragment's depth, then clamped to [0, 1] per fragment), §13.8 clipping and the viewport transform, §2.3.5.2 fixed-point depth conversion";

/// Writes the driver-side half of the bundle for the reduced `case_file` on `backend` into
/// `out`. Returns its outcome: [`Exit::Pass`] written, [`Exit::Fail`] nothing to reproduce
/// (said on stderr), an error when it could not run.
pub fn emit(case_file: &Path, backend_id: &str, out: &Path) -> Outcome {
    if umbra_case::fault::Fault::active() == Some(umbra_case::fault::Fault::NoYFlip) {
        return Err(Error::new(
            "the no-y-flip self-test fault acts on umbra's readback, not on its GL calls: a standalone program cannot carry it",
        ));
    }
    // A build with its own C library: this process continues on it (re-executed).
    if let Some(Err(e)) = crate::harness::mesa_build::selected()
        .filter(|_| crate::harness::mesa_build::is_mesa_backed(backend_id))
        .map(crate::harness::mesa_build::MesaBuild::enter)
    {
        return Err(Error::new(format!("{backend_id}: {e}")));
    }
    let mut backend = crate::harness::registry::create(backend_id)
        .map_err(|e| Error::new(format!("{backend_id}: {e}")))?;
    let point = umbra_case::load_file(case_file)
        .map(|mut p| p.remove(0))
        .map_err(|e| Error::new(e.to_string()))?;
    let profile = backend.profile();
    let info = backend.info();
    let judged = match crate::judge::run::run_point(backend.as_mut(), point.clone(), false) {
        crate::judge::run::Outcome::Done(j) => j,
        crate::judge::run::Outcome::Skip(why) => {
            return Err(Error::new(format!(
                "{backend_id} skips the reduced case: {why}"
            )));
        }
        crate::judge::run::Outcome::Error(e) => {
            return Err(Error::new(format!(
                "{backend_id} fails to render the reduced case: {e}"
            )));
        }
    };
    let prepared = Prepared::new(point.clone());
    let crate::judge::judge_cache::Basis { judged: basis, .. } =
        crate::judge::judge_cache::basis(&prepared, profile, true);
    let (frame, program) = match backend.render_recorded(&prepared) {
        Ok(r) => (Some(r.0), Some(r.1)),
        Err(BackendError::Unsupported(why)) => {
            println!("  no repro.c: {why}");
            (None, None)
        }
        Err(e) => return Err(Error::new(format!("the recorded render failed: {e}"))),
    };
    // The recorded frame is the one probed; it must be the judged one, or the driver is not
    // deterministic on this case and the probes would test another frame than umbra judged.
    let frame = frame.unwrap_or_else(|| judged.frame.clone());
    let same = frame.color == judged.frame.color
        && frame.lights.len() == judged.frame.lights.len()
        && frame.lights.iter().zip(&judged.frame.lights).all(|(a, b)| {
            a.visibility
                .iter()
                .map(|v| v.to_bits())
                .eq(b.visibility.iter().map(|v| v.to_bits()))
                && a.surface == b.surface
                && a.shadow_map.as_ref().map(|m| &m.values)
                    == b.shadow_map.as_ref().map(|m| &m.values)
        });
    let (_, pixels) = umbra_compare::reference::judge(&basis, &frame);
    let probes = probes::select(&basis, &frame, &pixels);
    if probes.is_empty() && program.is_some() {
        eprintln!(
            "error: the reduced case passes the value, coverage, colour and map checks on {backend_id} (it fails {}): a standalone program has nothing to probe",
            crate::judge::expectations::signature(&judged.failed)
        );
        return Err(Error::said(Exit::Fail));
    }
    std::fs::create_dir_all(out)
        .map_err(|e| Error::new(format!("cannot create {}: {e}", out.display())))?;
    let profile_name = basis.profile.name();
    let mut wrote_c = false;
    if let Some(program) = program {
        let env: Vec<String> = crate::harness::registry::driver_env(backend_id)
            .unwrap_or_default()
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        let header = issue::c_header(backend_id, &env.join(" "), &info, &probes);
        let source = program(
            &header,
            &probes.c_source(&profile_name, VALUE_CLAUSE, MAP_CLAUSE),
        );
        std::fs::write(out.join("repro.c"), source).map_err(|e| {
            Error::new(format!(
                "cannot write {}: {e}",
                out.join("repro.c").display()
            ))
        })?;
        wrote_c = true;
    }
    let crop = pictures::write(out, &judged, &pixels, &probes).map_err(|e| {
        Error::new(format!(
            "cannot write the pictures into {}: {e}",
            out.display()
        ))
    })?;
    let size = crate::case_size::Size::of(&serde_json::to_value(&point.case).unwrap_or_default())
        .unwrap_or_default();
    let facts = Facts {
        backend: backend_id.to_string(),
        profile: profile_name.to_string(),
        vendor: info.vendor.clone(),
        renderer: info.renderer.clone(),
        version: info.version.clone(),
        extensions: info.extensions.clone(),
        device: info.device.clone(),
        failed: judged.failed.clone(),
        problems: judged.problems.clone(),
        pixels: probes.pixels.len(),
        pixels_total: probes.pixels_total,
        texels: probes.texels.len(),
        texels_total: probes.texels_total,
        frame: probes.frame,
        map: point.case.shadow.size,
        faces: prepared
            .lights
            .iter()
            .map(|l| l.light.views.len())
            .sum::<usize>(),
        cube: Some(prepared.lights.iter().any(|l| l.light.is_cube())),
        triangles: size.triangles,
        crop,
        deterministic: same,
        repro_c: wrote_c,
        probe_lines: probes_text(&probes),
    };
    std::fs::write(
        out.join("facts.json"),
        serde_json::to_string_pretty(&facts).unwrap_or_default(),
    )
    .map_err(|e| Error::new(format!("cannot write facts.json: {e}")))?;
    Ok(Exit::Pass)
}

/// What the driver's process measured, for the parent's issue.md and README.md: written by
/// [`emit`] as `facts.json` in the bundle, read back by `umbra repro` through [`Facts::read`]
/// (one type on both sides of the process boundary).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Facts {
    /// The backend id.
    pub backend: String,
    /// The judge's profile for it.
    pub profile: String,
    /// GL_VENDOR (or the adapter's vendor).
    pub vendor: String,
    /// GL_RENDERER.
    pub renderer: String,
    /// GL_VERSION.
    pub version: String,
    /// The extensions the driver lists.
    pub extensions: Vec<String>,
    /// The EGL device or adapter, where one was chosen.
    pub device: String,
    /// The checks the reduced case fails on the driver.
    pub failed: Vec<umbra_report::FailedCheck>,
    /// What the judge could not judge.
    pub problems: Vec<String>,
    /// Pixel probes written into repro.c, of `pixels_total` illegal pixels.
    pub pixels: usize,
    /// Illegal pixels in the frame.
    pub pixels_total: usize,
    /// Texel probes written into repro.c, of `texels_total` illegal texels.
    pub texels: usize,
    /// Illegal texels in the shadow maps.
    pub texels_total: usize,
    /// The frame's width and height.
    pub frame: [u32; 2],
    /// The shadow map's width and height.
    pub map: [u32; 2],
    /// Shadow map faces over every light (6 for a cube, one per cascade).
    #[serde(default = "one")]
    pub faces: usize,
    /// Whether a light's map is a cube (none in bundles written before cascades).
    #[serde(default)]
    pub cube: Option<bool>,
    /// Triangles of the reduced case.
    pub triangles: usize,
    /// The failing area's crop: x, y, width, height, magnification.
    pub crop: [u32; 5],
    /// Whether the recorded render equals the judged one.
    pub deterministic: bool,
    /// Whether repro.c was written (a GL backend).
    pub repro_c: bool,
    /// The probes as issue.md lists them.
    pub probe_lines: Vec<String>,
}

fn one() -> usize {
    1
}

impl Facts {
    /// `facts.json` in `dir`, or an error naming the file and the field that does not read.
    pub fn read(dir: &Path) -> Result<Facts, String> {
        let file = dir.join("facts.json");
        let text = std::fs::read_to_string(&file)
            .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
        let de = &mut serde_json::Deserializer::from_str(&text);
        serde_path_to_error::deserialize(de)
            .map_err(|e| format!("{}: {} at {}", file.display(), e.inner(), e.path()))
    }
}

/// The probes as umbra saw them on the driver's run, one line each (issue.md's table).
fn probes_text(p: &probes::Probes) -> Vec<String> {
    let mut lines = Vec::new();
    for q in &p.pixels {
        let got = if q.got.0.is_nan() {
            "no surface".to_string()
        } else {
            format!("{:.4} (surface {})", q.got.0, q.got.1)
        };
        lines.push(format!(
            "pixel ({}, {}): visibility {got}; allowed [{:.4}, {:.4}] ± {:.4} on surface {}",
            q.x, q.y, q.lo, q.hi, p.eps, q.surface
        ));
    }
    for t in &p.texels {
        lines.push(format!(
            "texel ({}, {}) of face {}: depth {:.9}; allowed [{:.9}, {:.9}]",
            t.x, t.y, t.layer, t.got, t.lo, t.hi
        ));
    }
    lines
}
