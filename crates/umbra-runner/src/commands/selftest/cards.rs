//! `umbra selftest cards`: each behaviour-card entry against a fault that moves the choice
//! it measures. The backend's card is measured clean, then with each fault turned on
//! (`UMBRA_SELFTEST=1 UMBRA_FAULT=name`, as the self-test's workers run); the fault is
//! caught when the faulted card differs from the clean one in the fault's own entry, and the
//! table says which other entries moved with it.
//!
//! The faults, and the entry each must move:
//! - `offset-units@-0.5`: the polygon-offset units halved, as a driver whose r is half of
//!   another's (Mesa 22.3's 2 codes → 26.2's 1 code; inside the spec either way):
//!   `offset-unit.*`;
//! - `offset-factor@0.41421356`: the slope term scaled by √2, the size of the change from
//!   max(|∂z/∂x|, |∂z/∂y|) to the exact √(∂z/∂x² + ∂z/∂y²) on a diagonal (on an axis it is
//!   outside the spec, which the entry says): `slope-term.axis`;
//! - `bilinear-coarse`: a manual LINEAR filter's weights quantised to quarters (the GLES 2
//!   path; GL allows any weighting): `linear-compare`;
//! - `clamp-float`: a D32F reference clamped like a fixed-point one's:
//!   `reference-clamp.depth32f`;
//! - `no-clamp`: the GLES 2 path's emulated compare forgets to clamp its reference:
//!   `reference-clamp.depth16`;
//! - `mip-level-coarse`: a mipmapped map's base level one too coarse (an LOD off by a whole
//!   level, outside the spec: no fault of umbra's moves the LOD by less): `lod-offset`, which
//!   then finds no crossing and says so.
//!
//! Entries with no fault yet, because no umbra-side change can move them (they are the
//! rasterizer's and the sampler's): `slope-term.diagonal` (max against exact needs the
//! driver's own slope), `depth-rounding.*` and `reference-precision.*` (the conversions of
//! the stored depth and of the reference), `subpixel-bits`, `cube-seams`,
//! `offset-unit.*.depends-on-depth`, `cube-face-ties`, `border-compare`, `lod-scale-factor`,
//! `lod-derivatives`.

use std::time::Duration;

use umbra_case::fault::Fault;

use crate::exit::{Error, Exit, Outcome};
use crate::harness::scheduler::Session;
use crate::judge::card::Card;

/// Each card fault, and the key prefix of the entry it must move.
pub const CARD_FAULTS: [(&str, &str); 8] = [
    ("offset-units@-0.5", "offset-unit."),
    ("offset-factor@0.41421356", "slope-term.axis"),
    ("bilinear-coarse", "linear-compare"),
    ("clamp-float", "reference-clamp.depth32f"),
    ("no-clamp", "reference-clamp.depth16"),
    ("mip-level-coarse", "lod-offset"),
    ("clamp-ignored", "depth-clamp"),
    ("clamp-forced", "depth-clamp"),
];

/// The entries no card fault moves yet, and why.
pub const UNFAULTED: [(&str, &str); 10] = [
    (
        "slope-term.diagonal",
        "max against exact is the rasterizer's slope; umbra cannot change it from outside",
    ),
    (
        "depth-rounding.*",
        "the depth conversion is the driver's; umbra cannot change it from outside",
    ),
    (
        "reference-precision.*",
        "the compare's precision is the sampler's; umbra cannot change it from outside",
    ),
    (
        "cube-seams",
        "the cube sampler's edge handling is the driver's (or the API's rule)",
    ),
    (
        "subpixel-bits",
        "vertex snapping is the rasterizer's; umbra cannot change it from outside",
    ),
    (
        "offset-unit.*.depends-on-depth",
        "the unit's dependence on depth is the driver's",
    ),
    (
        "cube-face-ties",
        "the face a tied direction selects is the sampler's; umbra cannot change it from outside",
    ),
    (
        "border-compare",
        "what a border texel feeds the compare is the sampler's; umbra cannot change it from outside",
    ),
    (
        "lod-scale-factor",
        "the scale factor's form is the sampler's; umbra cannot change it from outside",
    ),
    (
        "lod-derivatives",
        "fine or coarse implicit derivatives are the shader compiler's; umbra cannot change them from outside",
    ),
];

/// Whether `fault` can move `backend`'s card: the self-test's rule, except that the
/// LINEAR probe compares in hardware, so a manual filter's fault reaches only the GLES 2
/// technique (which filters in its shader whatever the case says).
fn applies(fault: Fault, backend: &str) -> bool {
    let es2 =
        crate::harness::registry::Descriptor::of(backend).is_some_and(|d| d.gles2_technique());
    super::applies(fault, backend) && (fault != Fault::BilinearCoarse || es2)
}

/// One backend's card with `fault` on (none: clean).
fn card(backend: &str, fault: Option<Fault>, limit: Duration) -> Result<Card, String> {
    let mut env = crate::harness::registry::worker_env(backend);
    if let Some(f) = fault {
        env.extend([
            ("UMBRA_SELFTEST".into(), "1".into()),
            ("UMBRA_FAULT".into(), f.name()),
        ]);
    }
    let mut session = Session::start(backend, &env, limit);
    crate::harness::cards::of_session(&mut session)
}

/// Runs `umbra selftest cards` over `backends`; exit 1 when a fault's entry did not move.
pub fn main(backends: &[String], limit: Duration) -> Outcome {
    let (mut caught, mut pairs, mut missed) = (0, 0, Vec::new());
    println!(
        "selftest cards: each card fault on each backend it applies to; caught = its own entry changed"
    );
    for b in backends {
        if !super::applies(Fault::NoBias, b) {
            continue; // the reference: faults are a driver's.
        }
        let clean = match card(b, None, limit) {
            Ok(c) => c,
            Err(e) => {
                println!("  {b}: no clean card ({e}): skipped");
                continue;
            }
        };
        for (name, entry) in CARD_FAULTS {
            let fault = Fault::parse(name)
                .ok_or_else(|| Error::new(format!("card fault {name} is not a fault")))?;
            if !applies(fault, b) {
                continue;
            }
            pairs += 1;
            let faulted = match card(b, Some(fault), limit) {
                Ok(c) => c,
                Err(e) => {
                    println!("  {b} {name}: no card ({e})");
                    missed.push(format!("{b} {name}"));
                    continue;
                }
            };
            let changes = faulted.changes_since(&clean);
            let own: Vec<String> = changes
                .iter()
                .filter(|c| c.key.starts_with(entry))
                .map(crate::judge::card::Change::line)
                .collect();
            let others = changes.len() - own.len();
            if own.is_empty() {
                println!("  MISSED {b} {name}: {entry} unchanged ({others} other entries moved)");
                missed.push(format!("{b} {name}"));
            } else {
                caught += 1;
                println!(
                    "  caught {b} {name}: {} of its entries ({}){}",
                    own.len(),
                    own[0],
                    if others > 0 {
                        format!("; {others} other entries moved with it")
                    } else {
                        String::new()
                    }
                );
            }
        }
    }
    println!("selftest cards: {caught} of {pairs} fault × backend pairs named by their entry");
    for (entry, why) in UNFAULTED {
        println!("selftest cards: no fault for {entry}: {why}");
    }
    Ok(Exit::pass_if(missed.is_empty() && pairs > 0))
}
