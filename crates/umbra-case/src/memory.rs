//! What one run of a case needs in memory, estimated from the case before anything renders,
//! so that a case that validates but cannot fit (an 8192² image with a 16384² cube map asks
//! for tens of GiB) is refused with the fields to shrink instead of taking the machine down.
//!
//! The estimate is linear in what a case controls: camera pixels, shadow-map texels (all
//! faces) and triangles, plus a fixed base. Each coefficient covers every buffer that scales
//! with it over a whole judged run: the backend's frame, the reference's frame and map, the
//! truth, the judge's per-pixel intervals and classes, the twins (rendered one after the
//! other), the driver's own copies (GL textures, readbacks, llvmpipe's tiles) and the PNGs.
//! They are measured, not guessed: peak resident memory (`VmHWM`, printed by `umbra render`)
//! of a plane-and-box case on ref, gl33/llvmpipe and wgpu-vk/lavapipe (2 cores, Mesa 22.3.6):
//!
//! | image, map          | ref      | gl33/llvmpipe | wgpu-vk/lavapipe |
//! |---------------------|----------|---------------|------------------|
//! | 256², 32² (base)    | 19 MiB   | 100 MiB       | 104 MiB          |
//! | 256², 2048²         | 270 MiB  | 369 MiB       | 356 MiB          |
//! | 256², 4096²         | 1.0 GiB  | 1.2 GiB       | 1.0 GiB          |
//! | 1024², 512²         | 221 MiB  | 292 MiB       | 302 MiB          |
//! | 2048², 512²         | 824 MiB  | 890 MiB       | 892 MiB          |
//! | 512², 1024² × 6     | 235 MiB  | 338 MiB       | 319 MiB          |
//!
//! that is up to 71 bytes a texel (gl33, 4096²), 201 a pixel (ref, 2048²) and a 104 MiB base;
//! the constants below add about a fifth on each, and summing the parts (the peaks of the map
//! and the judging phases do not add up) adds more. Triangles are not calibrated beyond the
//! catalogue's few thousand. The test `estimate_bounds_measured_peaks` in `umbra-runner`
//! re-measures four of these sizes and two several-light cases on all three backends and
//! fails if a run needs more than its estimate (or, with several lights, less than half of it).

use crate::Case;
use crate::format::Light;

/// Bytes per camera pixel over a judged run (measured; see the module notes).
pub const BYTES_PER_PIXEL: u64 = 240;
/// Bytes per shadow-map texel, all faces (measured; see the module notes).
pub const BYTES_PER_TEXEL: u64 = 80;
/// Bytes per texel of every light's map but the largest, in a case with several lights: what
/// a judged run keeps of each light while the others are judged (the backend's map, the
/// reference's map and its intervals). Measured by `VmHWM` on 256² frames with 1, 2 and 4
/// lights, point lights at 1024² (six faces, a cube array) and spot lights at 2048² (one
/// array), 2 cores, Mesa 22.3.6, `umbra render --backend B`: each light after the first adds
/// 21.0–21.2 bytes a texel on ref, 18.2–21.1 on gl33/llvmpipe and 15.9–21.2 on
/// wgpu-vk/lavapipe (points); 17.5–18, 20.3–21.6 and 11.8–16.5 (spots). 24 covers the most
/// with a tenth to spare (`estimate_bounds_measured_peaks` in umbra-runner re-measures). It
/// was 36 while the judge cloned every light's reference frame to add their colours (ref's
/// four point lights peaked at 730 MiB, now 575). Counting the first light alone once
/// estimated 1, 2 and 4 point lights at the same 641 MiB, and four 4096² spot lights at
/// 1.4 GiB where they peaked at 2.1 GiB.
pub const BYTES_PER_KEPT_TEXEL: u64 = 24;
/// Bytes per drawn triangle (geometry, its f64 copy for the truth, the acceleration grid).
pub const BYTES_PER_TRIANGLE: u64 = 2_000;
/// What a worker holds before any case: the process, the driver, the compiled shaders.
pub const BASE_BYTES: u64 = 160 << 20;

/// One part of an estimate: the case field that controls it, and its size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    /// The case field to shrink (`camera.size`, `shadow.size`, `scene.objects`).
    pub field: &'static str,
    /// What it is, with the figures (`8192×8192 px`).
    pub what: String,
    /// Bytes.
    pub bytes: u64,
}

/// The memory one run of a case needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Estimate {
    /// The parts, largest first; the fixed base is not among them.
    pub parts: Vec<Part>,
}

impl Estimate {
    /// Bytes in all, base included.
    pub fn total(&self) -> u64 {
        BASE_BYTES + self.parts.iter().map(|p| p.bytes).sum::<u64>()
    }

    /// Why a run does not fit in `budget` bytes, naming the fields to shrink (None if it
    /// fits).
    pub fn refuse(&self, budget: u64) -> Option<String> {
        let total = self.total();
        if total <= budget {
            return None;
        }
        let parts: Vec<String> = self
            .parts
            .iter()
            .filter(|p| p.bytes >= 1 << 20)
            .map(|p| format!("{} {}: {}", p.field, p.what, gib(p.bytes)))
            .collect();
        let shrink: Vec<&str> = self
            .parts
            .iter()
            .filter(|p| p.bytes >= total / 10)
            .map(|p| p.field)
            .collect();
        Some(format!(
            "this run needs about {} ({}; base {}), more than the memory budget of {}; fix: shrink {} (each halving of a side quarters its part), or raise the budget with --max-memory if the machine has the memory",
            gib(total),
            parts.join(", "),
            gib(BASE_BYTES),
            gib(budget),
            shrink.join(" or ")
        ))
    }
}

/// The estimate for one run of `case` with `triangles` drawn triangles.
pub fn estimate(case: &Case, triangles: usize) -> Estimate {
    let [cw, ch] = case.camera.size;
    let [sw, sh] = case.shadow.size;
    // Every light's map: the largest is judged at the full cost a texel, the others kept at
    // theirs ([`BYTES_PER_KEPT_TEXEL`]).
    let lights = &case.lights;
    let Some(largest) = lights.iter().max_by_key(|l| l.map_faces()) else {
        return Estimate { parts: Vec::new() };
    };
    let faces = u64::from(largest.map_faces());
    let other_faces: u64 = lights.iter().map(|l| u64::from(l.map_faces())).sum::<u64>() - faces;
    let pixels = u64::from(cw) * u64::from(ch);
    let face_texels = u64::from(sw) * u64::from(sh);
    let texels = faces * face_texels;
    let mut parts = vec![
        Part {
            field: "shadow.size",
            what: if matches!(largest, Light::Point(_)) {
                format!("{sw}×{sh} × 6 cube faces")
            } else if faces > 1 {
                format!("{sw}×{sh} × {faces} cascades")
            } else {
                format!("{sw}×{sh}")
            },
            bytes: texels.saturating_mul(BYTES_PER_TEXEL),
        },
        Part {
            field: "lights",
            what: format!(
                "{} more lights' maps, {other_faces} faces of {sw}×{sh}",
                lights.len() - 1
            ),
            bytes: (other_faces * face_texels).saturating_mul(BYTES_PER_KEPT_TEXEL),
        },
        Part {
            field: "camera.size",
            what: format!("{cw}×{ch} px"),
            bytes: pixels.saturating_mul(BYTES_PER_PIXEL),
        },
        Part {
            field: "scene.objects",
            what: format!("{triangles} triangles"),
            bytes: (triangles as u64).saturating_mul(BYTES_PER_TRIANGLE),
        },
    ];
    parts.retain(|p| p.bytes > 0 || p.field != "lights");
    parts.sort_by_key(|p| std::cmp::Reverse(p.bytes));
    Estimate { parts }
}

/// Bytes as GiB (or MiB below one GiB), for messages.
pub fn gib(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
    } else {
        format!("{:.0} MiB", bytes as f64 / f64::from(1u32 << 20))
    }
}

/// Parses a size such as `512MiB`, `4GiB`, `2G`, `1500M` or `4096B` (a bare number has no
/// unit and is refused).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let n: f64 = num
        .parse()
        .map_err(|_| format!("{text:?} is not a size; write e.g. 512MiB or 4GiB"))?;
    let scale: u64 = match unit.trim().to_ascii_lowercase().as_str() {
        // A bare number was once bytes: `--max-memory 4` then meant 4 bytes, not 4 GiB.
        "" => {
            return Err(format!(
                "{text:?} has no unit; write e.g. 512MiB or 4GiB (B for bytes)"
            ));
        }
        "b" => 1,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        other => {
            return Err(format!(
                "{text:?}: unknown unit {other:?}; write e.g. 512MiB or 4GiB"
            ));
        }
    };
    Ok((n * scale as f64) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(text: &str) -> Case {
        let points = crate::load_str(text, std::path::Path::new("t.json")).expect("loads");
        points.into_iter().next().expect("a point").case
    }

    #[test]
    fn a_huge_point_light_case_is_refused_naming_the_map_first() {
        let c = case(
            r#"{"name": "huge", "about": "t", "scene": {"objects": [{"plane": {"point": [0,0,0], "half_extent": 5}}]},
                "camera": {"eye": [0,5,5], "target": [0,0,0], "fov_y_deg": 50, "near": 0.5, "far": 30, "size": [8192, 8192]},
                "light": {"point": {"position": [0,3,0], "near": 0.1, "far": 40}},
                "shadow": {"size": [16384, 16384]}}"#,
        );
        let e = estimate(&c, 2);
        assert_eq!(e.parts[0].field, "shadow.size");
        let why = e.refuse(8 << 30).expect("refused");
        assert!(
            why.contains("shrink shadow.size or camera.size") && why.contains("6 cube faces"),
            "{why}"
        );
        // A catalogue-sized case fits in a small budget.
        let small = case(
            r#"{"name": "small", "about": "t", "scene": {"objects": [{"plane": {"point": [0,0,0], "half_extent": 5}}]},
                "camera": {"eye": [0,5,5], "target": [0,0,0], "fov_y_deg": 50, "near": 0.5, "far": 30, "size": [200, 150]},
                "light": {"spot": {"position": [1,3,0], "target": [0,0,0], "fov_y_deg": 60, "near": 1, "far": 20}},
                "shadow": {"size": [512, 512]}}"#,
        );
        assert_eq!(estimate(&small, 2).refuse(1 << 30), None);
    }

    /// Integrity round three: the estimate read the first light alone, so 1, 2 and 4 point
    /// lights all estimated 641 MiB. Every light's map counts now.
    #[test]
    fn every_lights_map_counts() {
        let lights = |n: usize| {
            let one = r#"{"point": {"position": [0,3,0], "near": 0.1, "far": 40}}"#;
            let list = vec![one; n].join(",");
            let light = if n == 1 {
                format!(r#""light": {one}"#)
            } else {
                format!(r#""lights": [{list}]"#)
            };
            case(&format!(
                r#"{{"name": "l", "about": "t", "scene": {{"objects": [{{"plane": {{"point": [0,0,0], "half_extent": 5}}}}]}},
                "camera": {{"eye": [0,5,5], "target": [0,0,0], "fov_y_deg": 50, "near": 0.5, "far": 30, "size": [256, 256]}},
                {light}, "shading": {{"model": "dimmed"}},
                "shadow": {{"size": [1024, 1024]}}}}"#
            ))
        };
        let [one, two, four] = [1, 2, 4].map(|n| estimate(&lights(n), 2).total());
        let kept = 6 * 1024 * 1024 * BYTES_PER_KEPT_TEXEL;
        assert_eq!(two - one, kept);
        assert_eq!(four - one, 3 * kept);
        let why = estimate(&lights(4), 2).refuse(1 << 30).expect("refused");
        assert!(
            why.contains("lights 3 more lights' maps, 18 faces of 1024×1024"),
            "{why}"
        );
    }

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_size("4G"), Ok(4 << 30));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert!(parse_size("lots").is_err());
        assert!(parse_size("4").is_err_and(|e| e.contains("no unit")));
        assert_eq!(parse_size("4096B"), Ok(4096));
        assert!(parse_size("4 parsecs").is_err());
    }
}
