//! What a backend's behaviour card showed it chose inside the specs' freedom, in the form the
//! judge narrows its intervals by: calibrated judging (docs/cards.md, "Calibrated judging").
//!
//! The spec's judgement grants every choice a conformant implementation may make; a driver
//! makes one, and the card's probes read it. A [`Calibration`] holds the choices the judge can
//! use, each as the *intersection* of the spec's range and the probe's reading with its
//! uncertainty: it only ever narrows, so a run that passes under it passes the spec too, and a
//! run inside the spec but outside its calibration did something in the scene that its driver
//! did not do in the probes (check `card`). Integers only, so a [`crate::Profile`] that carries
//! one stays `Copy + Hash` and keys the judging cache by its name.
//!
//! What is not here is not narrowed: the float unit (the spec fixes it already), a unit that
//! depends on depth, a card reading outside the spec (that is the spec's failure, or a
//! modelled deviation's), the compare reference's precision, cube seams (a desktop GL driver
//! filtering per face where its profile says seamless would be a widening, not a narrowing),
//! and GLES 2's packed path (umbra's own shader, no driver choice).

/// How a fixed-point conversion rounds, as read by the card's probe at a quarter and three
/// quarters of a code: the stored code is ⌊x + t⌋ for some t (x in codes), and each reading
/// bounds t.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Rounding {
    /// ¼ rounds down, ¾ up: t ∈ [¼, ¾].
    Nearest,
    /// Both down: t ∈ [0, ¼].
    Truncate,
    /// Both up: t ∈ [¾, 1].
    Up,
}

impl Rounding {
    /// The range of t the reading allows (the module note of [`Rounding`]).
    pub fn t_range(self) -> (f64, f64) {
        match self {
            Rounding::Nearest => (0.25, 0.75),
            Rounding::Truncate => (0.0, 0.25),
            Rounding::Up => (0.75, 1.0),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Rounding::Nearest => "nearest",
            Rounding::Truncate => "truncate",
            Rounding::Up => "up",
        }
    }

    fn parse(s: &str) -> Option<Rounding> {
        [Rounding::Nearest, Rounding::Truncate, Rounding::Up]
            .into_iter()
            .find(|r| r.name() == s)
    }
}

/// Which of the two slope terms the specs allow the driver computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SlopeForm {
    /// max(|∂z/∂x|, |∂z/∂y|).
    Max,
    /// √(∂z/∂x² + ∂z/∂y²).
    Exact,
}

/// The choices a card pinned down (the module note). `Default` narrows nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Calibration {
    /// The polygon-offset unit r on D16 and D24 (that order), in thousandths of a code
    /// (1/(2ⁿ − 1)): the least and the largest the probes allow.
    pub offset_unit: [Option<(u32, u32)>; 2],
    /// The slope term's form.
    pub slope: Option<SlopeForm>,
    /// How D16 and D24 (that order) round a depth between two codes.
    pub rounding: [Option<Rounding>; 2],
    /// LINEAR with compare filters the compare results bilinearly: a GL driver judged by
    /// Vulkan's rule (bilinear weights of 4 bits or more) instead of GL's any weighting.
    pub bilinear: bool,
    /// How the card saw cube maps filtered at a face edge (true: across faces): the
    /// bilinear reading holds in a cube map only where this is what the profile judges by
    /// (wgpu's GL backend, judged as GLES 3, filters per face on desktop GL).
    pub cube_seams: Option<bool>,
    /// Sub-pixel bits of the shadow pass's vertex snapping (at least the specs' 4).
    pub subpixel_bits: Option<u8>,
}

/// The index of a fixed-point format in [`Calibration`]'s per-format arrays.
pub fn fixed_index(format: crate::format::DepthFormat) -> Option<usize> {
    match format {
        crate::format::DepthFormat::Depth16 => Some(0),
        crate::format::DepthFormat::Depth24 => Some(1),
        _ => None,
    }
}

const FIXED: [&str; 2] = ["16", "24"];

impl Calibration {
    /// Narrows nothing (the `Default`, usable in constants).
    pub const NONE: Calibration = Calibration {
        offset_unit: [None; 2],
        slope: None,
        rounding: [None; 2],
        bilinear: false,
        cube_seams: None,
        subpixel_bits: None,
    };

    /// Whether it narrows nothing.
    pub fn is_empty(&self) -> bool {
        *self == Calibration::NONE
    }

    /// The calibration as a short stable string (`r16=968-1032,slope=max,round16=nearest,
    /// linear=bilinear,subpixel=8`): what a worker's request carries and what a profile's
    /// name shows. Empty for none.
    pub fn encode(&self) -> String {
        let mut parts = Vec::new();
        for (i, r) in self.offset_unit.iter().enumerate() {
            if let Some((lo, hi)) = r {
                parts.push(format!("r{}={lo}-{hi}", FIXED[i]));
            }
        }
        if let Some(s) = self.slope {
            parts.push(format!(
                "slope={}",
                match s {
                    SlopeForm::Max => "max",
                    SlopeForm::Exact => "exact",
                }
            ));
        }
        for (i, r) in self.rounding.iter().enumerate() {
            if let Some(r) = r {
                parts.push(format!("round{}={}", FIXED[i], r.name()));
            }
        }
        if self.bilinear {
            parts.push("linear=bilinear".into());
        }
        if let Some(across) = self.cube_seams {
            parts.push(format!(
                "seams={}",
                if across { "across" } else { "per-face" }
            ));
        }
        if let Some(b) = self.subpixel_bits {
            parts.push(format!("subpixel={b}"));
        }
        parts.join(",")
    }

    /// The calibration [`Calibration::encode`] wrote, or the part that is not one.
    pub fn parse(s: &str) -> Result<Calibration, String> {
        let mut c = Calibration::default();
        for part in s.split(',').filter(|p| !p.is_empty()) {
            let bad = || {
                format!(
                    "{part:?} (want r16=LO-HI, r24=LO-HI, slope=max|exact, round16|round24=nearest|truncate|up, linear=bilinear, seams=across|per-face, subpixel=BITS)"
                )
            };
            let (key, value) = part.split_once('=').ok_or_else(bad)?;
            let fixed = |prefix: &str| {
                key.strip_prefix(prefix)
                    .and_then(|n| FIXED.iter().position(|f| *f == n))
            };
            if let Some(i) = fixed("r") {
                let (lo, hi) = value.split_once('-').ok_or_else(bad)?;
                let (lo, hi) = (
                    lo.parse().map_err(|_| bad())?,
                    hi.parse().map_err(|_| bad())?,
                );
                if lo > hi {
                    return Err(bad());
                }
                c.offset_unit[i] = Some((lo, hi));
            } else if let Some(i) = fixed("round") {
                c.rounding[i] = Some(Rounding::parse(value).ok_or_else(bad)?);
            } else {
                match (key, value) {
                    ("slope", "max") => c.slope = Some(SlopeForm::Max),
                    ("slope", "exact") => c.slope = Some(SlopeForm::Exact),
                    ("linear", "bilinear") => c.bilinear = true,
                    ("seams", "across") => c.cube_seams = Some(true),
                    ("seams", "per-face") => c.cube_seams = Some(false),
                    ("subpixel", b) => {
                        let b: u8 = b.parse().map_err(|_| bad())?;
                        if !(4..=24).contains(&b) {
                            return Err(bad());
                        }
                        c.subpixel_bits = Some(b);
                    }
                    _ => return Err(bad()),
                }
            }
        }
        Ok(c)
    }

    /// The polygon-offset unit range of `format` narrowed to the calibration's reading:
    /// `spec` (the spec's range, as values) intersected with it; `spec` itself where the
    /// calibration has none for the format or the intersection is empty.
    pub fn offset_unit(&self, format: crate::format::DepthFormat, spec: (f64, f64)) -> (f64, f64) {
        let (Some(i), Some(n)) = (fixed_index(format), format.fixed_bits()) else {
            return spec;
        };
        let Some((lo, hi)) = self.offset_unit[i] else {
            return spec;
        };
        let code = 1.0 / f64::from((1u32 << n) - 1);
        let (lo, hi) = (
            spec.0.max(f64::from(lo) * 1e-3 * code),
            spec.1.min(f64::from(hi) * 1e-3 * code),
        );
        if lo <= hi { (lo, hi) } else { spec }
    }

    /// The rounding of `format`, where the calibration has one.
    pub fn rounding_of(&self, format: crate::format::DepthFormat) -> Option<Rounding> {
        fixed_index(format).and_then(|i| self.rounding[i])
    }

    /// How far, in pixels, a vertex of the shadow pass may lie from the reference's besides
    /// its transform: the driver's grid step (2⁻ᵇ, no rounding mode assumed), the reference's
    /// own 8-bit snapping by rounding (1/512) and f32 window coordinates (1/1024 at 16k);
    /// `spec` (the 4-bit [`crate`]-wide bound) without a reading. A reading of more than 8
    /// bits is used as 8: the probe sees one edge at one place, not every setup's arithmetic.
    pub fn snap_px(&self, spec: f64) -> f64 {
        match self.subpixel_bits {
            Some(b) => {
                let step = 1.0 / f64::from(1u32 << b.min(8));
                (step + 1.0 / 512.0 + 1.0 / 1024.0).min(spec)
            }
            None => spec,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::DepthFormat;

    #[test]
    fn a_calibration_reads_back_what_it_wrote() {
        let c = Calibration {
            offset_unit: [Some((968, 1032)), None],
            slope: Some(SlopeForm::Max),
            rounding: [Some(Rounding::Truncate), Some(Rounding::Nearest)],
            bilinear: true,
            cube_seams: Some(false),
            subpixel_bits: Some(8),
        };
        let s = c.encode();
        assert_eq!(
            s,
            "r16=968-1032,slope=max,round16=truncate,round24=nearest,linear=bilinear,seams=per-face,subpixel=8"
        );
        assert_eq!(Calibration::parse(&s), Ok(c));
        assert_eq!(Calibration::parse(""), Ok(Calibration::default()));
        assert_eq!(Calibration::NONE, Calibration::default());
        for bad in [
            "r16=5",
            "r32=1-2",
            "slope=sum",
            "subpixel=2",
            "r16=9-3",
            "x",
        ] {
            assert!(Calibration::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn it_only_narrows() {
        let spec = DepthFormat::Depth16.offset_unit_range(0.5);
        let mut c = Calibration::default();
        assert_eq!(c.offset_unit(DepthFormat::Depth16, spec), spec);
        c.offset_unit[0] = Some((968, 1032));
        let (lo, hi) = c.offset_unit(DepthFormat::Depth16, spec);
        assert_eq!(lo, spec.0);
        assert!(hi < spec.1 && hi > spec.0);
        // A reading outside the spec (zink's 4 codes on 22.3.6) narrows nothing.
        c.offset_unit[0] = Some((3968, 4032));
        assert_eq!(c.offset_unit(DepthFormat::Depth16, spec), spec);
        assert_eq!(c.offset_unit(DepthFormat::Depth32f, (1.0, 1.0)), (1.0, 1.0));
        let spec_snap = 1.0 / 16.0 + 1.0 / 512.0 + 1.0 / 1024.0;
        assert_eq!(c.snap_px(spec_snap), spec_snap);
        c.subpixel_bits = Some(16);
        assert_eq!(
            c.snap_px(spec_snap),
            1.0 / 256.0 + 1.0 / 512.0 + 1.0 / 1024.0
        );
    }
}
