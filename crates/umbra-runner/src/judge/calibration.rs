//! A behaviour card read as the judge's narrowing of the specs' freedom (calibrated judging,
//! docs/cards.md): which of the card's entries the judge can hold a run to, and how wide.
//!
//! Only an entry the card measured, inside the spec (`inside == Some(true)`: GLES 2's packed
//! entries measure umbra's own shader and narrow nothing), with a reading the probe is sure
//! of, narrows anything; each keeps the probe's own uncertainty ([`Sure`]). What the card
//! cannot say (a unit that depends on depth, a slope between the two forms, an unmeasured
//! rounding) leaves the spec's freedom in place. The narrowing itself is applied by the
//! reference ([`umbra_case::calibration`]).

use umbra_case::calibration::{Calibration, Rounding, SlopeForm};

use crate::judge::card::{Card, Entry, Sure};

/// The narrowing `card` supports.
pub fn of_card(card: &Card) -> Calibration {
    let entry = |key: &str| {
        card.entries
            .iter()
            .find(|e| e.key == key && e.inside == Some(true))
    };
    let mut c = Calibration::default();
    for (i, format) in ["depth16", "depth24"].into_iter().enumerate() {
        c.offset_unit[i] = offset_unit(
            entry(&format!("offset-unit.{format}.z0.375")),
            entry(&format!("offset-unit.{format}.z0.75")),
            entry(&format!("offset-unit.{format}.depends-on-depth")),
        );
        c.rounding[i] =
            entry(&format!("depth-rounding.{format}")).and_then(|e| match e.value.as_str() {
                "to nearest" => Some(Rounding::Nearest),
                "truncated (towards 0)" => Some(Rounding::Truncate),
                "up (away from 0)" => Some(Rounding::Up),
                _ => None,
            });
    }
    c.slope = entry("slope-term.diagonal").and_then(|e| match e.value.as_str() {
        "max(|∂z/∂x|, |∂z/∂y|)" => Some(SlopeForm::Max),
        "√(∂z/∂x² + ∂z/∂y²), exact" => Some(SlopeForm::Exact),
        _ => None,
    });
    c.bilinear = entry("linear-compare")
        .is_some_and(|e| e.value.starts_with("bilinear of the compare results"));
    c.cube_seams = entry("cube-seams").and_then(|e| match e.value.as_str() {
        "across faces" => Some(true),
        "per face" => Some(false),
        _ => None,
    });
    c.subpixel_bits = entry("subpixel-bits").and_then(|e| {
        let bits: u8 = e.value.split(' ').next()?.parse().ok()?;
        (4..=24).contains(&bits).then_some(bits)
    });
    c
}

/// The unit r of one fixed-point format, in thousandths of a code, from its two probes: the
/// span of their readings widened by each one's uncertainty; none where the unit depends on
/// depth or either probe is missing.
fn offset_unit(a: Option<&Entry>, b: Option<&Entry>, same: Option<&Entry>) -> Option<(u32, u32)> {
    if same?.value != "no" {
        return None;
    }
    let read = |e: &Entry| match (e.measured, &e.sure) {
        (Some(x), Sure::Within(w)) => Some((x - w, x + w)),
        _ => None,
    };
    let ((a_lo, a_hi), (b_lo, b_hi)) = (read(a?)?, read(b?)?);
    let (lo, hi) = (a_lo.min(b_lo).max(0.0), a_hi.max(b_hi));
    Some(((lo * 1e3).floor() as u32, (hi * 1e3).ceil() as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_card_narrows_to_the_model() {
        // The kept card of `ref` (umbra's model): 1 code, max, to nearest, bilinear, 8 bits.
        let card = crate::judge::card::Card::read(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../golden/ref/card-umbra.json"
        )))
        .expect("the kept reference card");
        let c = of_card(&card);
        for r in c.offset_unit {
            let (lo, hi) = r.expect("a unit for D16 and D24");
            assert!(lo < 1000 && hi > 1000 && hi - lo < 100, "{lo}..{hi}");
        }
        assert_eq!(c.slope, Some(SlopeForm::Max));
        assert_eq!(c.rounding[0], Some(Rounding::Nearest));
        assert!(c.bilinear);
        assert_eq!(c.subpixel_bits, Some(8));
    }

    #[test]
    fn an_entry_outside_the_spec_or_unmeasured_narrows_nothing() {
        let mut card = crate::judge::card::Card::read(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../golden/ref/card-umbra.json"
        )))
        .expect("the kept reference card");
        for e in &mut card.entries {
            e.inside = match e.key.as_str() {
                "offset-unit.depth16.z0.375" | "slope-term.diagonal" => Some(false),
                "subpixel-bits" => None,
                _ => e.inside,
            };
        }
        let c = of_card(&card);
        assert_eq!(c.offset_unit[0], None);
        assert!(c.offset_unit[1].is_some());
        assert_eq!(c.slope, None);
        assert_eq!(c.subpixel_bits, None);
    }
}
