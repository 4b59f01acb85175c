//! The judge's checks, one vocabulary: what a failing run names (`failed: value=12+map=3`),
//! what an expectation bounds (`Fail:value<=12`), what `umbra reduce --check` keeps failing,
//! and what the reports and a repro bundle print. Each check says what it holds a run to and
//! the spec text behind it, so a driver developer reading `failed:` can look it up.
//!
//! A check is written by its name (`value`, `falls-along`, `twin:bias-order`); a name that is
//! not one is refused with the nearest names (`colour` for `color`), never taken as a check
//! nothing emits.

use std::fmt;

/// One check of a run.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Check {
    /// The visibility value at a covered pixel lies outside what the specs allow there.
    Value,
    /// A NaN where a value was due.
    Nan,
    /// A pixel covered where the truth has no surface, or the reverse.
    Coverage,
    /// The colour is not the lit or shadowed shading of a legal value.
    Colour,
    /// A shadow-map texel outside the range of depths the specs allow it.
    Map,
    /// `expect.interior_error`: false shadow or false light away from shadow edges.
    Interior,
    /// The colour image against its reviewed golden.
    Golden,
    /// `expect.error_falls_along`: the error must not grow along the swept path.
    FallsAlong,
    /// The run was refused before rendering: it cannot fit in the memory budget.
    Memory,
    /// The backend failed to render (an API error, an unsupported state).
    Render,
    /// The backend's behaviour card (what its driver chose inside the specs' freedom)
    /// differs from the one kept for its driver release.
    Card,
    /// A metamorphic twin (`twin:NAME`) disagrees with its case beyond what is legal.
    Twin(String),
}

/// Every check but the twins' (one per twin, `twin:NAME`).
pub const FIXED: [Check; 11] = [
    Check::Value,
    Check::Nan,
    Check::Coverage,
    Check::Colour,
    Check::Map,
    Check::Interior,
    Check::Golden,
    Check::FallsAlong,
    Check::Memory,
    Check::Render,
    Check::Card,
];

impl Check {
    /// The check's name, as `failed:`, expectations and `--check` write it.
    pub fn name(&self) -> String {
        match self {
            Check::Twin(t) => format!("twin:{t}"),
            fixed => fixed.fixed_name().to_string(),
        }
    }

    fn fixed_name(&self) -> &'static str {
        match self {
            Check::Value => "value",
            Check::Nan => "nan",
            Check::Coverage => "coverage",
            Check::Colour => "colour",
            Check::Map => "map",
            Check::Interior => "interior",
            Check::Golden => "golden",
            Check::FallsAlong => "falls-along",
            Check::Memory => "memory",
            Check::Render => "render",
            Check::Card => "card",
            Check::Twin(_) => "twin",
        }
    }

    /// What the check holds a run to.
    pub fn about(&self) -> &'static str {
        match self {
            Check::Value => {
                "the visibility value at each covered pixel lies in the interval the specs allow there"
            }
            Check::Nan => "no NaN where a value is due",
            Check::Coverage => "pixels are covered where the truth has a surface, and only there",
            Check::Colour => "the colour is the shading of a legal visibility value",
            Check::Map => "each shadow-map texel holds a depth the specs allow it",
            Check::Interior => {
                "expect.interior_error: no false shadow or light away from shadow edges, as the case says"
            }
            Check::Golden => "the colour image matches its reviewed golden within one 8-bit step",
            Check::FallsAlong => {
                "expect.error_falls_along: the error does not grow along the swept path"
            }
            Check::Memory => "the run fits the worker's memory budget",
            Check::Render => "the backend renders the run without an API error",
            Check::Card => {
                "the driver's choices inside the specs' freedom (its behaviour card: polygon-offset unit and slope, depth rounding, LINEAR weights, sub-pixel bits, reference clamp) are the ones kept for its release (a BACKEND/card row), and each run stays inside the freedom narrowed to what its card's probes read (calibrated judging)"
            }
            Check::Twin(_) => {
                "a metamorphic twin renders what its case renders, within what the specs allow"
            }
        }
    }

    /// The spec text behind the check (umbra's own rule where no spec speaks).
    pub fn clause(&self) -> &'static str {
        match self {
            Check::Value | Check::Nan => {
                "GL 4.6 §8.23.1 depth texture comparison with §8.14 texel selection and filtering, §14.5 rasterization, §14.6.5 depth offset; Vulkan 1.3 \"Depth Compare Operation\""
            }
            Check::Coverage => {
                "GL 4.6 §14.6 polygon rasterization (sample point inside, tie-breaking)"
            }
            Check::Colour => {
                "umbra's shading model (cases/README.md, docs/catalogue.md §17) at 8-bit unorm output, GL 4.6 §2.3.5.2"
            }
            Check::Map => {
                "GL 4.6 §14.6.5 depth offset, §13.8 clipping and the viewport, §2.3.5.2 fixed-point depth conversion"
            }
            Check::Interior => "the case's own expectation (expect.interior_error)",
            Check::Golden => "review: goldens change only through `cargo xtask bless`",
            Check::FallsAlong => "the case's own expectation (expect.error_falls_along)",
            Check::Memory => "umbra's memory budget (--max-memory)",
            Check::Render => "the API's error reporting (glGetError, KHR_debug, wgpu's validation)",
            Check::Card => {
                "review: a driver's card changes only through `cargo xtask bless`; each entry cites the clause whose freedom it measures, and a run is narrowed only inside it (umbra_case::calibration)"
            }
            Check::Twin(_) => {
                "the invariance the twin states (umbra_case::twin), within the spec's freedoms"
            }
        }
    }

    /// `n` failures of this check in words, for a bug report's title and a report's line.
    pub fn counted(&self, n: u64) -> String {
        match self {
            Check::Map => format!(
                "{n} shadow-map texels stored outside the depths GL 4.6 §14.6.5 (polygon offset) allows"
            ),
            Check::Value => format!(
                "{n} pixels' shadow test outside what GL 4.6 §8.23.1 (depth texture comparison) allows"
            ),
            Check::Coverage => {
                format!("{n} pixels show another surface than rasterization (§14.5) allows")
            }
            Check::Colour => {
                format!("{n} pixels' colour is not the shading of their own shadow test")
            }
            Check::Nan => format!("{n} pixels NaN"),
            other => format!("{other} ({n})"),
        }
    }

    /// Reads a check's name; an unknown one is refused with the nearest names.
    pub fn parse(s: &str) -> Result<Check, String> {
        let s = s.trim();
        if let Some(t) = s.strip_prefix("twin:") {
            return if t.is_empty() {
                Err("twin: needs the twin's name (twin:bias-order)".into())
            } else {
                Ok(Check::Twin(t.to_string()))
            };
        }
        if let Some(c) = FIXED.iter().find(|c| c.fixed_name() == s) {
            return Ok(c.clone());
        }
        let mut near: Vec<(usize, &str)> = FIXED
            .iter()
            .map(|c| (crate::names::edits(s, c.fixed_name()), c.fixed_name()))
            .filter(|(d, _)| *d <= 2)
            .collect();
        near.sort();
        let hint = match near.first() {
            Some((_, n)) => format!("; did you mean {n}?"),
            None => String::new(),
        };
        Err(format!(
            "unknown check {s:?}{hint} The checks are {}",
            vocabulary()
        ))
    }
}

/// Every check's name, for help and errors: `value, nan, …, render and twin:NAME`.
pub fn vocabulary() -> String {
    let names: Vec<&str> = FIXED.iter().map(Check::fixed_name).collect();
    format!("{} and twin:NAME", names.join(", "))
}

impl fmt::Display for Check {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl std::str::FromStr for Check {
    type Err = String;
    fn from_str(s: &str) -> Result<Check, String> {
        Check::parse(s)
    }
}

impl serde::Serialize for Check {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Check {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Check, D::Error> {
        let s = String::deserialize(d)?;
        Check::parse(&s).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_near_misses_are_named() {
        for c in FIXED
            .iter()
            .cloned()
            .chain([Check::Twin("bias-order".into())])
        {
            assert_eq!(Check::parse(&c.name()), Ok(c.clone()));
            assert!(!c.about().is_empty() && !c.clause().is_empty());
        }
        let e = Check::parse("color").expect_err("American spelling");
        assert!(e.contains("did you mean colour?"), "{e}");
        let e = Check::parse("falls_along").expect_err("underscore");
        assert!(e.contains("did you mean falls-along?"), "{e}");
        let e = Check::parse("pixels").expect_err("no such check");
        assert!(
            e.contains("nan") && e.contains("twin:NAME") && !e.contains("did you mean"),
            "{e}"
        );
        assert!(Check::parse("twin:").is_err());
        assert_eq!(
            serde_json::to_string(&Check::FallsAlong).expect("json"),
            "\"falls-along\""
        );
    }
}
