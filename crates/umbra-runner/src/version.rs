//! Version numbers, read two ways on purpose.
//!
//! A *driver's* version string is whatever the driver chose to print (`4.5 (Core Profile)
//! Mesa 25.0.7-2~bpo12+1`, `26.3.0-devel (git-abc)`): [`parts`] reads it leniently, keeping
//! the numeric components of its upstream part and dropping the rest, because the harness
//! must run on drivers it has never seen.
//!
//! A version a person *wrote and reviewed* (an expectation's `@applies mesa>=22.4`) is read
//! strictly by [`reviewed`]: one grammar, digits and dots, one to three parts, each fitting
//! a `u32`, nothing before or after. Reading it leniently changed its meaning: `22.4x` (or
//! `22..4`, `22.99999999999`) was read as `22`, and on Mesa 22.3.6 an expected failure meant
//! for 22.4 on applied there and turned a regression into `ExpectedFail` without a word.

/// The numeric components of a driver-reported version's upstream part: up to the first
/// non-numeric component, and never past a packaging suffix (`25.0.7-2~bpo12+1` → [25, 0,
/// 7]; `26.3.0-devel (git-abc)` → [26, 3, 0]). For text a person wrote, use [`reviewed`].
pub fn parts(v: &str) -> Vec<u32> {
    v.split(['-', '~', '+', ' '])
        .next()
        .unwrap_or("")
        .split('.')
        .map_while(|p| p.parse().ok())
        .collect()
}

/// The components of a version a person wrote: `MAJOR[.MINOR[.PATCH]]`, decimal digits
/// only, each part fitting a `u32`. Anything else is refused with what was wrong.
pub fn reviewed(v: &str) -> Result<Vec<u32>, String> {
    const GRAMMAR: &str = "a version is MAJOR[.MINOR[.PATCH]] in decimal digits (22, 22.3, 22.3.6)";
    if v.is_empty() {
        return Err(format!("no version number; {GRAMMAR}"));
    }
    let pieces: Vec<&str> = v.split('.').collect();
    if pieces.len() > 3 {
        return Err(format!("{v:?} has {} parts; {GRAMMAR}", pieces.len()));
    }
    pieces
        .iter()
        .map(|p| {
            if p.is_empty() || !p.bytes().all(|b| b.is_ascii_digit()) {
                return Err(format!("{v:?}: {p:?} is not a number; {GRAMMAR}"));
            }
            p.parse::<u32>()
                .map_err(|_| format!("{v:?}: {p} is too large for a version part; {GRAMMAR}"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_driver_version_is_read_leniently() {
        assert_eq!(parts("25.0.7-2~bpo12+1"), [25, 0, 7]);
        assert_eq!(parts("26.3.0-devel (git-abc)"), [26, 3, 0]);
        assert_eq!(parts("22.4x"), [22]);
    }

    #[test]
    fn a_reviewed_version_is_read_strictly() {
        assert_eq!(reviewed("22"), Ok(vec![22]));
        assert_eq!(reviewed("22.3"), Ok(vec![22, 3]));
        assert_eq!(reviewed("22.3.6"), Ok(vec![22, 3, 6]));
        for bad in [
            "",
            "22.4x",
            "22..4",
            "22.99999999999",
            ".4",
            "22.",
            "22.3.6.1",
            "+22",
            "-1",
            "22 ",
            "v22",
            "22.3-rc1",
            "２２",
        ] {
            let e = reviewed(bad).expect_err(bad);
            assert!(e.contains("MAJOR[.MINOR[.PATCH]]"), "{bad:?}: {e}");
        }
    }
}
