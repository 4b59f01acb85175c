//! The sampler's choices on a behaviour card ([`crate::judge::card`]), beside the depth and
//! rasterization probes of [`crate::judge::card_probes`]: where a lookup's specs leave the
//! driver a rule of its own.
//!
//! - **Cube-face ties.** A direction whose two largest components have identical magnitude
//!   lies on the seam of two faces; GL lets the implementation "define the rule to
//!   disambiguate" (GL 4.6 and ES 3.2 §8.13), Vulkan asks for a deterministic rule and
//!   recommends z over y and x, then y over x ("Cube Map Face Selection"). An exact tie is
//!   only reachable through exact arithmetic: the probe's receiver is a quad whose every
//!   vertex has equal components on the two axes, so every interpolated position (the
//!   lookup direction, the light being at the origin) ties exactly, whatever the
//!   interpolator's rounding, which is the same for both components. Only one face holds an
//!   occluder next to the seam: the visibility says which face was read.
//! - **LOD scale factor.** A mipmapped map (`source: rendered`) whose level 0 is all shadow
//!   and whose level 1 is all light (casters of half a texel centred on level 0's texels,
//!   between level 1's centres), seen straight down with NEAREST_MIPMAP_NEAREST: the camera
//!   height at which the centre turns lit is where λ crosses ½. Seen with the screen's axes
//!   along the map's, every scale-factor form gives ρ = the footprint L; rotated by 45°,
//!   ∂s = ∂t = L/√2 and the forms part: exact length L, GL's max(m_u, m_v) L/√2, its
//!   m_u + m_v √2·L, Vulkan's bound √2·(|∂s/∂x| + |∂t/∂x|) 2L. log₂ of the two heights'
//!   ratio names the form (0, +½, −½, −1), and the axis-aligned height alone the LOD's
//!   offset from log₂ L.
//! - **Derivatives.** The same level-0/level-1 map, squeezed 8× along t, seen obliquely
//!   with the screen's x along t: ∂t/∂x dominates ρ and grows row by row with distance. With
//!   fine derivatives each row of a 2 × 2 quad has its own ∂/∂x, so the level's boundary in a
//!   column can fall between a quad's two rows; with coarse ones the quad shares one, and it
//!   falls only between quads. Twelve camera heights move the boundary through the rows.
//! - **Depth clamp.** A slab between a downward orthographic light and its near plane, over
//!   a floor, rendered with `depth_clamp` off and on: without it the slab is clipped and the
//!   floor under it lit; with it the slab is stored at the near plane and shadows the floor.
//!   Both APIs are exact here; the entry reads whether the driver does what it was asked.
//! - **Border.** A D32F floor beyond the light's far plane (reference 4/3, which a float
//!   format does not clamp) and outside the map, sampled with CLAMP_TO_BORDER at depth 1:
//!   compared as a depth, the border shadows it; returned as the lookup's result, it lights it.

use serde_json::{Value, json};
use umbra_case::Frame;

use crate::judge::card::{Entry, Sure};

/// Renders one probe case (given as JSON) on the backend whose card is measured:
/// [`crate::judge::card_probes::Prober`]'s, passed in so that this module does not import
/// that one (which calls it).
pub type Render<'a> = dyn FnMut(&Value) -> Result<Frame, String> + 'a;

/// The mean visibility over the covered pixels of `f` within `r` pixels of its centre.
fn centre_lit(f: &Frame, r: u32) -> Option<f64> {
    let (cx, cy) = (f.width / 2, f.height / 2);
    let mut v = Vec::new();
    for y in cy.saturating_sub(r)..(cy + r).min(f.height) {
        for x in cx.saturating_sub(r)..(cx + r).min(f.width) {
            let i = (y * f.width + x) as usize;
            // Every light's (a probe has one).
            for l in f.each_light() {
                if l.covered(i) && l.visibility[i].is_finite() {
                    v.push(f64::from(l.visibility[i]));
                }
            }
        }
    }
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// Which face a cube lookup reads where two axes tie exactly, for the pairs (x, y), (y, z)
/// and (x, z) (positive components): one render each.
pub fn cube_tie(render: &mut Render) -> Entry {
    let key = "cube-face-ties";
    let what = "cube map face at an exact tie of the major axis";
    let spec = "any rule (GL 4.6 and ES 3.2 §8.13: \"the implementation may define the rule\"); Vulkan: deterministic, and recommends z over y and x, then y over x (\"Cube Map Face Selection\")";
    let probe = "a point light's receiver quad whose every vertex has equal components on two axes (an exact tie at every pixel), an occluder beside the seam on the first axis's face only (32², D24, NEAREST): shadowed reads the first face";
    let names = ["x", "y", "z"];
    let mut wins = Vec::new();
    let mut readings = Vec::new();
    for (a, b) in [(0, 1), (1, 2), (0, 2)] {
        let lit = match render(&tie_case(a, b)).map(|f| centre_lit(&f, 4)) {
            Ok(Some(lit)) => lit,
            Ok(None) => {
                let why = "the tie's receiver covered no pixel".to_string();
                return Entry::unmeasured(key, what, spec, probe, why);
            }
            Err(why) => return Entry::unmeasured(key, what, spec, probe, why),
        };
        readings.push(format!("{}/{}: lit {lit:.2}", names[a], names[b]));
        if lit < 0.1 {
            wins.push((a, b));
        } else if lit > 0.9 {
            wins.push((b, a));
        } else {
            let value = format!(
                "mixed: {} and {} each win some pixels of one tie (a rule on more than the axes)",
                names[a], names[b]
            );
            return Entry::new(
                key,
                what,
                value,
                Some(lit),
                spec,
                Some(true),
                &format!("{probe}: {}", readings.join(", ")),
                Sure::Exact,
            );
        }
    }
    // A strict order when the three pairwise winners agree with one ranking.
    let beats = |i: usize| wins.iter().filter(|(w, _)| *w == i).count();
    let mut order: Vec<usize> = vec![0, 1, 2];
    order.sort_by_key(|&i| std::cmp::Reverse(beats(i)));
    let ranked = (0..3).all(|k| beats(order[k]) == 2 - k);
    let value = if ranked {
        format!(
            "{} over {} over {}",
            names[order[0]], names[order[1]], names[order[2]]
        )
    } else {
        wins.iter()
            .map(|(w, l)| format!("{} over {}", names[*w], names[*l]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    Entry::new(
        key,
        what,
        value,
        None,
        spec,
        Some(true),
        &format!("{probe}: {}", readings.join(", ")),
        Sure::Exact,
    )
}

/// The case of one tie probe: world axis `a` and `b` tie; face +a holds the occluder.
fn tie_case(a: usize, b: usize) -> Value {
    let c = 3 - a - b;
    // Local (u, v, w) on world axes (a, b, c).
    let world = |u: f64, v: f64, w: f64| {
        let mut p = [0.0; 3];
        p[a] = u;
        p[b] = v;
        p[c] = w;
        p
    };
    // The receiver: u = v exactly at every vertex, 1.5 to 2.5 out, |w| ≤ 0.4 (so u, v are
    // the major axes). Both windings, so that it faces the camera whichever way round.
    let receiver: Vec<[f64; 3]> = vec![
        world(1.5, 1.5, -0.4),
        world(2.5, 2.5, -0.4),
        world(2.5, 2.5, 0.4),
        world(1.5, 1.5, 0.4),
    ];
    // The occluder on face +a, 1 out: directions v/u from 0.5 to 0.99, past the centres of
    // the face's last texel row or column at 1 − 1/32 and short of the seam at 1 (+b's edge
    // texels, at u/v = 1 − 1/32, see none of it).
    let occluder: Vec<[f64; 3]> = vec![
        world(1.0, 0.5, -0.6),
        world(1.0, 0.99, -0.6),
        world(1.0, 0.99, 0.6),
        world(1.0, 0.5, 0.6),
    ];
    let quad = |q: &[[f64; 3]]| {
        json!({ "mesh": { "positions": q,
            "triangles": [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]] } })
    };
    // The camera on the receiver's +b side (no occluder there), looking at its middle.
    json!({
        "name": "card-probe",
        "about": "a behaviour-card probe (umbra_runner::judge::card_sampler_probes)",
        "scene": { "objects": [quad(&receiver), quad(&occluder)] },
        "camera": { "eye": world(1.2, 2.8, 0.0), "target": world(2.0, 2.0, 0.0),
                    "up": world(0.0, 0.0, 1.0),
                    "fov_y_deg": 30, "near": 0.05, "far": 10, "size": [32, 32] },
        "light": { "point": { "position": [0, 0, 0], "near": 0.05, "far": 10 } },
        "shadow": { "size": [32, 32], "format": "depth24", "filter": "nearest",
                    "bias": { "constant": 0.002 } },
    })
}

/// Map texels per metre of the LOD probe: 32 texels over ±2 m.
const LOD_TEXEL: f64 = 0.125;
/// Camera pixels a side, and the field of view, of the LOD probe: at height h the centre's
/// footprint is L = 2h·tan(fov/2)/size/texel level-0 texels per pixel.
const LOD_SIZE: u32 = 8;
const LOD_FOV_DEG: f64 = 10.0;

/// The LOD probe's footprint in level-0 texels per pixel at camera height `h`.
fn lod_footprint(h: f64) -> f64 {
    2.0 * h * umbra_case::math::tan(LOD_FOV_DEG.to_radians() / 2.0)
        / f64::from(LOD_SIZE)
        / LOD_TEXEL
}

/// Casters 15 m up that make a 2-level map's level 0 all shadow and its level 1 all light: a
/// rectangle of half a texel centred on each level-0 texel (i, j) of `cols` × `rows`, the
/// map's texels `size` (x, z) from its corner `origin`. Every level-0 centre lies under one;
/// no centre of level 1 (on level 0's texel corners) or coarser does.
fn level_zero_casters(
    cols: std::ops::Range<u32>,
    rows: std::ops::Range<u32>,
    origin: [f64; 2],
    size: [f64; 2],
) -> Value {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for i in cols {
        for j in rows.clone() {
            let x0 = origin[0] + (f64::from(i) + 0.25) * size[0];
            let z0 = origin[1] + (f64::from(j) + 0.25) * size[1];
            let (x1, z1) = (x0 + 0.5 * size[0], z0 + 0.5 * size[1]);
            let k = positions.len();
            positions.extend([
                [x0, 15.0, z0],
                [x0, 15.0, z1],
                [x1, 15.0, z1],
                [x1, 15.0, z0],
            ]);
            triangles.extend([[k, k + 1, k + 2], [k, k + 2, k + 3]]);
        }
    }
    json!({ "mesh": { "positions": positions, "triangles": triangles } })
}

/// The LOD probe's case: the camera at height `h` straight down, its screen axes along the
/// map's (`rotated` false) or at 45° to them.
fn lod_case(h: f64, rotated: bool) -> Value {
    // The middle 8 × 8 texels (x and z from −0.5 to 0.5).
    let casters = level_zero_casters(12..20, 12..20, [-2.0, -2.0], [LOD_TEXEL, LOD_TEXEL]);
    let up = if rotated {
        json!([
            std::f64::consts::FRAC_1_SQRT_2,
            0,
            -std::f64::consts::FRAC_1_SQRT_2
        ])
    } else {
        json!([0, 0, -1])
    };
    json!({
        "name": "card-probe",
        "about": "a behaviour-card probe (umbra_runner::judge::card_sampler_probes)",
        "scene": { "objects": [
            { "plane": { "point": [0, 0, 0], "normal": [0, 1, 0], "half_extent": 4 } },
            casters
        ] },
        "camera": { "eye": [0, h, 0], "target": [0, 0, 0], "up": up,
                    "fov_y_deg": LOD_FOV_DEG, "near": 0.05, "far": 50,
                    "size": [LOD_SIZE, LOD_SIZE] },
        "light": { "directional": { "position": [0, 30, 0], "target": [0, 0, 0],
            "up": [0, 0, -1],
            "ortho": { "left": -2, "right": 2, "bottom": -2, "top": 2, "near": 0, "far": 40 } } },
        "shadow": { "size": [32, 32], "format": "depth24", "filter": "nearest",
            "mipmaps": { "levels": 2, "filter": "nearest", "source": "rendered" },
            "bias": { "constant": 0.001 } },
    })
}

/// The camera height in [2, 14] m at which the LOD probe's centre turns from level 0
/// (shadowed) to level 1 (lit), bisected over `steps` renders: middle and half-width.
fn lod_crossing(render: &mut Render, rotated: bool, steps: u32) -> Result<(f64, f64), String> {
    let mut read = |h: f64| -> Result<f64, String> {
        let f = render(&lod_case(h, rotated))?;
        centre_lit(&f, 1).ok_or_else(|| "the floor covered no centre pixel".to_string())
    };
    let (lo, hi) = (2.0, 14.0);
    let (l, h) = (read(lo)?, read(hi)?);
    if !(l < 0.5 && h >= 0.5) {
        return Err(format!(
            "no crossing in the searched range: the centre reads {l:.2} at a footprint of {:.2} texels and {h:.2} at {:.2}",
            lod_footprint(lo),
            lod_footprint(hi)
        ));
    }
    let (mut a, mut b) = (lo, hi);
    for _ in 0..steps {
        let m = 0.5 * (a + b);
        if read(m)? < 0.5 { a = m } else { b = m }
    }
    Ok((0.5 * (a + b), 0.5 * (b - a)))
}

/// The LOD's scale factor (from the rotated and the axis-aligned crossing) and its offset
/// from log₂ of the footprint (from the axis-aligned one): two entries.
pub fn lod(render: &mut Render) -> Vec<Entry> {
    let key = "lod-scale-factor";
    let what = "LOD scale factor ρ of a footprint at 45° to the texel axes";
    let spec = "GL: max(m_u, m_v) ≤ ρ ≤ m_u + m_v (GL 4.6 §8.14.1); Vulkan: max(|∂s/∂x|, |∂t/∂x|) ≤ ρ_x ≤ √2·(|∂s/∂x| + |∂t/∂x|) (\"Scale Factor Operation\"): log₂ of ρ over the exact length from −1 (Vulkan's bound) to +½, ± 2⁻⁴ (the judge takes both)";
    let probe = "a 2-level map (rendered: level 0 all shadow, level 1 all light, NEAREST_MIPMAP_NEAREST) seen straight down, screen axes along and at 45° to the map's: log₂ of the two camera heights at which the centre turns to level 1 (λ = ½)";
    let okey = "lod-offset";
    let owhat = "LOD λ against log₂ of the footprint, screen axes along the texel axes";
    let ospec = "λ = log₂ ρ, within the LOD's precision: 2⁻⁴ (Vulkan mipmapPrecisionBits ≥ 4; GL sets none, dEQP's shadow tests accept 4 bits)";
    let oprobe = "the axis-aligned crossing of the same probe: λ = ½ there, against log₂ of the centre's footprint in level-0 texels";
    let (axis, rotated) = match (
        lod_crossing(render, false, 10),
        lod_crossing(render, true, 10),
    ) {
        (Ok(a), Ok(r)) => (a, r),
        (Err(why), _) | (_, Err(why)) => {
            return vec![
                Entry::unmeasured(key, what, spec, probe, why.clone()),
                Entry::unmeasured(okey, owhat, ospec, oprobe, why),
            ];
        }
    };
    // λ = ½ where ρ = √2: ρ/L there = √2/L(h), and L scales with h.
    let form = umbra_case::math::log2(rotated.0 / axis.0);
    let within = (rotated.1 / rotated.0 + axis.1 / axis.0) / std::f64::consts::LN_2;
    let known = [
        (0.5, "max(m_u, m_v) (GL's lower bound)"),
        (0.0, "the exact length √(∂s² + ∂t²)"),
        (-0.5, "m_u + m_v (GL's upper bound)"),
        (-1.0, "√2·(|∂s/∂x| + |∂t/∂x|) (Vulkan's upper bound)"),
    ];
    let value = known
        .iter()
        .find(|(k, _)| (form - k).abs() <= 0.0625 + within)
        .map(|(_, name)| name.to_string())
        .unwrap_or_else(|| format!("log₂ ρ/|∂| = {form:+.3}, none of the named forms"));
    let inside = (-1.0 - 0.0625 - within..=0.5 + 0.0625 + within).contains(&form);
    // Rounded to the shown digits, and −0 made +0, so that a card reads the same each time.
    let offset =
        (100.0 * (0.5 - umbra_case::math::log2(lod_footprint(axis.0)))).round() / 100.0 + 0.0;
    let owithin = axis.1 / axis.0 / std::f64::consts::LN_2;
    vec![
        Entry::new(
            key,
            what,
            value,
            Some(form),
            spec,
            Some(inside),
            &format!(
                "{probe}: heights {:.3} m and {:.3} m, log₂ ratio {form:+.3}",
                axis.0, rotated.0
            ),
            Sure::Within(within),
        ),
        Entry::new(
            okey,
            owhat,
            format!("{offset:+.2} levels"),
            Some(offset),
            ospec,
            Some(offset.abs() <= 0.0625 + owithin),
            &format!(
                "{oprobe}: {:.3} texels per pixel at λ = ½, log₂ {:.3}",
                lod_footprint(axis.0),
                umbra_case::math::log2(lod_footprint(axis.0))
            ),
            Sure::Within(owithin),
        ),
    ]
}

/// Whether CLAMP_TO_BORDER's border depth is compared with the reference, read on D32F
/// where a reference beyond the far plane stays beyond 1.
pub fn border(render: &mut Render) -> Entry {
    let key = "border-compare";
    let what = "CLAMP_TO_BORDER with a depth compare: the border depth compared, or returned";
    let spec = "compared: a border texel takes the border colour as its depth, then the compare applies (GL 4.6 §8.14.2 and §8.23.1; Vulkan \"Texel Replacement\" before \"Depth Compare Operation\")";
    let probe = "a D32F floor 4/3 beyond the light's far plane and outside its map (border depth 1): shadowed if compared, lit if the border is the result";
    let case = json!({
        "name": "card-probe",
        "about": "a behaviour-card probe (umbra_runner::judge::card_sampler_probes)",
        "scene": { "objects": [
            { "plane": { "point": [0, 0, 0], "normal": [0, 1, 0], "half_extent": 4 } }
        ] },
        "camera": { "eye": [2.5, 1.0, 0], "target": [2.5, 0, 0], "up": [0, 0, -1],
                    "fov_y_deg": 30, "near": 0.05, "far": 10, "size": [32, 32] },
        "light": { "directional": { "position": [0, 4, 0], "target": [0, 0, 0],
            "up": [0, 0, -1],
            "ortho": { "left": -1, "right": 1, "bottom": -1, "top": 1, "near": 0, "far": 3 } } },
        "shadow": { "size": [32, 32], "format": "depth32f", "filter": "nearest",
                    "outside": "border" },
    });
    let lit = match render(&case).map(|f| centre_lit(&f, 16)) {
        Ok(Some(lit)) => lit,
        Ok(None) => {
            let why = "the floor covered no pixel".to_string();
            return Entry::unmeasured(key, what, spec, probe, why);
        }
        Err(why) => return Entry::unmeasured(key, what, spec, probe, why),
    };
    let compared = lit < 0.5;
    Entry::new(
        key,
        what,
        if compared {
            "compared"
        } else {
            "returned as the result"
        }
        .to_string(),
        Some(lit),
        spec,
        Some(compared),
        &format!("{probe}: lit fraction {lit:.3}"),
        Sure::Exact,
    )
}

/// The derivatives probe's case: camera height `h` over the floor, looking along +x at 30°
/// down; the map 32 × 32 texels over x ±2 m and z ±0.25 m.
fn derivatives_case(h: f64) -> Value {
    // x from −1.5 to 1.5, z from −0.09 to 0.09: what the centre columns see.
    let casters = level_zero_casters(4..28, 10..22, [-2.0, -0.25], [LOD_TEXEL, 0.5 / 32.0]);
    let back = h / umbra_case::math::tan(30f64.to_radians());
    json!({
        "name": "card-probe",
        "about": "a behaviour-card probe (umbra_runner::judge::card_sampler_probes)",
        "scene": { "objects": [
            { "plane": { "point": [0, 0, 0], "normal": [0, 1, 0], "half_extent": 4 } },
            casters
        ] },
        "camera": { "eye": [-back, h, 0], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y_deg": 20, "near": 0.05, "far": 50, "size": [32, 32] },
        "light": { "directional": { "position": [0, 30, 0], "target": [0, 0, 0],
            "up": [0, 0, -1],
            "ortho": { "left": -2, "right": 2, "bottom": -0.25, "top": 0.25, "near": 0, "far": 40 } } },
        "shadow": { "size": [32, 32], "format": "depth24", "filter": "nearest",
            "mipmaps": { "levels": 2, "filter": "nearest", "source": "rendered" },
            "bias": { "constant": 0.001 } },
    })
}

/// The rows of frame `f`'s column `x` after which visibility steps from shadowed to lit
/// or back (both neighbours covered and read clearly).
fn level_steps(f: &Frame, x: u32) -> Vec<u32> {
    // Every light's steps (a probe has one).
    f.each_light()
        .flat_map(|l| {
            let at = move |y: u32| {
                let i = (y * f.width + x) as usize;
                (l.covered(i) && l.visibility[i].is_finite()).then(|| l.visibility[i] > 0.5)
            };
            (0..f.height.saturating_sub(1))
                .filter(move |&y| matches!((at(y), at(y + 1)), (Some(a), Some(b)) if a != b))
        })
        .collect()
}

/// Whether ∂/∂x is taken per pixel (fine) or per 2 × 2 quad (coarse) in the lit pass.
pub fn derivatives(render: &mut Render) -> Entry {
    let key = "lod-derivatives";
    let what = "the LOD's derivatives: per pixel (fine) or per 2×2 quad (coarse)";
    let spec = "either: dFdx/dFdy may be fine or coarse (GLSL 4.60 and ES 3.20 §8.14.1; SPIR-V DPdx, WGSL dpdx), the judge takes every difference of the pixel's quad and neighbours";
    let probe = "a 2-level map (level 0 all shadow, level 1 all light) squeezed 8× along t, seen at 30° with the screen's x along t, 12 camera heights: the level boundary's rows in the centre columns, inside a quad (fine) or only between quads (coarse)";
    let (mut inside, mut between) = (0, 0);
    for k in 0..12 {
        let h = 0.6 + 0.05 * f64::from(k);
        let f = match render(&derivatives_case(h)) {
            Ok(f) => f,
            Err(why) => return Entry::unmeasured(key, what, spec, probe, why),
        };
        for x in [f.width / 2 - 1, f.width / 2] {
            for y in level_steps(&f, x) {
                if y % 2 == 0 {
                    inside += 1
                } else {
                    between += 1
                }
            }
        }
    }
    let found = format!("{probe}: {inside} boundaries inside a quad, {between} between quads");
    let value = match (inside, between) {
        (0, 0) => {
            let why = "no level boundary in view at any of the 12 heights".to_string();
            return Entry::unmeasured(key, what, spec, &found, why);
        }
        (0, b) if b >= 6 => "per 2×2 quad (coarse)",
        (i, _) if i >= 2 => "per pixel (fine)",
        _ => "unclear: too few boundaries to tell",
    };
    Entry::new(
        key,
        what,
        value.to_string(),
        Some(f64::from(inside)),
        spec,
        Some(true),
        &found,
        Sure::Exact,
    )
}

/// The depth-clamp probe's case: a slab between a downward orthographic light and its near
/// plane, over a floor the camera sees from below the slab; `clamp` is `shadow.depth_clamp`.
fn clamp_case(clamp: bool) -> Value {
    json!({
        "name": "card-probe",
        "about": "a behaviour-card probe (umbra_runner::judge::card_sampler_probes)",
        "scene": { "objects": [
            { "plane": { "point": [0, 0, 0], "normal": [0, 1, 0], "half_extent": 2 } },
            { "box": { "center": [0, 3.5, 0], "size": [1, 0.2, 1] } }
        ] },
        "camera": { "eye": [0, 2, 0], "target": [0, 0, 0], "up": [0, 0, -1],
                    "fov_y_deg": 30, "near": 0.05, "far": 10, "size": [32, 32] },
        "light": { "directional": { "position": [0, 4, 0], "target": [0, 0, 0],
            "up": [0, 0, -1],
            "ortho": { "left": -2, "right": 2, "bottom": -2, "top": 2, "near": 1, "far": 5 } } },
        "shadow": { "size": [64, 64], "format": "depth24", "filter": "nearest",
                    "depth_clamp": clamp },
    })
}

/// Whether the shadow pass clips at the light's near plane without depth clamp and clamps
/// with it: the floor under a slab in front of the near plane, rendered both ways.
pub fn depth_clamp(render: &mut Render) -> Entry {
    let key = "depth-clamp";
    let what = "a caster in front of the light's near plane, with depth clamp off and on";
    let spec = "off: clipped at the near plane; on: not clipped, its depth clamped to [0, 1] after the offset (GL 4.6 \"Primitive Clipping\" and \"Depth Buffer Test\" with DEPTH_CLAMP; Vulkan depthClampEnable, \"Primitive Clipping\" and \"Depth Clamping and Range Adjustment\")";
    let probe = "a slab 0.4-0.6 m from a downward orthographic light whose near plane is 1 m away, over a D24 floor: the floor under it lit when the slab is clipped, shadowed when it is stored at the near plane";
    let mut lit = [0.0; 2];
    for (k, clamp) in [false, true].into_iter().enumerate() {
        lit[k] = match render(&clamp_case(clamp)).map(|f| centre_lit(&f, 8)) {
            Ok(Some(v)) => v,
            Ok(None) => {
                let why = "the floor covered no pixel".to_string();
                return Entry::unmeasured(key, what, spec, probe, why);
            }
            Err(why) => {
                let why = format!("depth clamp {}: {why}", if clamp { "on" } else { "off" });
                return Entry::unmeasured(key, what, spec, probe, why);
            }
        };
    }
    let word = |v: f64| if v < 0.5 { "clamped" } else { "clipped" };
    let value = format!("off: {}, on: {}", word(lit[0]), word(lit[1]));
    Entry::new(
        key,
        what,
        value,
        Some(lit[1] - lit[0]),
        spec,
        Some(lit[0] >= 0.5 && lit[1] < 0.5),
        &format!(
            "{probe}: lit fraction {:.3} with clamp off, {:.3} on",
            lit[0], lit[1]
        ),
        Sure::Exact,
    )
}
