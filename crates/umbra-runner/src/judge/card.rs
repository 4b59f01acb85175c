//! Behaviour cards: what a driver chose wherever the specs leave it a choice, measured by
//! short probe renders ([`crate::judge::card_probes`]), and kept as a reviewed baseline per
//! backend and driver release beside the goldens.
//!
//! The judge grants every freedom the specs allow, so a driver that changes its choice inside
//! them (its polygon-offset unit, its depth rounding, its filter weights) passes every judged
//! run; only a golden notices, as a picture diff with no words. A card says it in words:
//! `depth rounding, D16: to nearest → truncated (inside the spec)`. `umbra card` prints one;
//! conformance measures the live card and fails check `card` when it differs from the one
//! blessed for that release (`golden/<backend>/card-<release>.json`), naming each entry, its
//! old and new value, and whether each lies inside the spec; `cargo xtask drivers` and
//! `bisect` report card changes first, so a bisection can target a behaviour.
//!
//! An entry is compared by its `value`, a classification (`2 codes`, `to nearest`) coarse
//! enough that the probe's resolution ([`Sure`]) cannot flip it on the same driver; the
//! number behind it (`measured`) is shown, not compared.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// How sure a measurement is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sure {
    /// A discrete observation (lit or not, a count).
    Exact,
    /// The measured number is within this much of the true one (in its unit).
    Within(f64),
    /// A classification by the sign of a threshold whose least distance from the
    /// classification's boundary was this much (in codes): the larger, the surer.
    Margin(f64),
    /// The value is a lower bound: the probe resolves no more.
    AtLeast,
    /// Not measured (the entry's `value` says why).
    None,
}

impl Sure {
    /// In words, for the table.
    pub fn words(&self) -> String {
        match self {
            Sure::Exact => "exact".into(),
            Sure::Within(e) => format!("±{e:.3}"),
            Sure::Margin(m) => format!("margin {m:.2} code"),
            Sure::AtLeast => "lower bound".into(),
            Sure::None => "not measured".into(),
        }
    }
}

/// One choice of the driver's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// Stable key (`offset-unit.depth16.z0.375`): what baselines are matched by.
    pub key: String,
    /// What it is, in words.
    pub what: String,
    /// The driver's choice, classified: what a change is.
    pub value: String,
    /// The number behind the value, where there is one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured: Option<f64>,
    /// What the specs allow, and where they say so.
    pub spec: String,
    /// Whether the value lies inside the spec (none: nothing to hold it to, or not measured).
    pub inside: Option<bool>,
    /// How it was measured.
    pub probe: String,
    /// How sure the measurement is.
    pub sure: Sure,
}

impl Entry {
    /// A measured entry.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        key: &str,
        what: &str,
        value: String,
        measured: Option<f64>,
        spec: &str,
        inside: Option<bool>,
        probe: &str,
        sure: Sure,
    ) -> Entry {
        Entry {
            key: key.into(),
            what: what.into(),
            value,
            measured,
            spec: spec.into(),
            inside,
            probe: probe.into(),
            sure,
        }
    }

    /// An entry the probe could not measure, and why.
    pub fn unmeasured(key: &str, what: &str, spec: &str, probe: &str, why: String) -> Entry {
        Entry::new(
            key,
            what,
            format!("not measured: {why}"),
            None,
            spec,
            None,
            probe,
            Sure::None,
        )
    }

    /// The value with where it lies against the spec.
    pub fn value_and_verdict(&self) -> String {
        match self.inside {
            Some(true) => format!("{} (inside the spec)", self.value),
            Some(false) => format!("{} (OUTSIDE the spec)", self.value),
            None => self.value.clone(),
        }
    }
}

/// A backend's card on one driver.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Card {
    /// The backend id.
    pub backend: String,
    /// The driver, as it reports itself (renderer | version).
    pub driver: String,
    /// The release the card is kept for (`mesa-22.3.6`; `umbra` for the reference).
    pub release: String,
    /// What the driver chose.
    pub entries: Vec<Entry>,
    /// Renders the probes took.
    #[serde(default)]
    pub renders: u32,
    /// Seconds the probes took (not compared).
    #[serde(default)]
    pub seconds: f64,
}

/// One difference between two cards.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// The entry's key.
    pub key: String,
    /// Its words, from whichever card has it.
    pub what: String,
    /// The old entry, if the old card had it.
    pub old: Option<Entry>,
    /// The new entry, if the new card has it.
    pub new: Option<Entry>,
}

impl Change {
    /// `depth rounding, D16: to nearest → truncated (both inside the spec)`.
    pub fn line(&self) -> String {
        let v = |e: &Option<Entry>| e.as_ref().map_or("(no entry)".into(), |e| e.value.clone());
        let ins = |e: &Option<Entry>| e.as_ref().and_then(|e| e.inside);
        let verdict = match (ins(&self.old), ins(&self.new)) {
            (Some(true), Some(true)) => " (both inside the spec)".to_string(),
            (Some(a), Some(b)) => format!(
                " (was {}, now {} the spec)",
                if a { "inside" } else { "OUTSIDE" },
                if b { "inside" } else { "OUTSIDE" }
            ),
            (None, Some(b)) | (Some(b), None) if self.old.is_some() && self.new.is_some() => {
                format!(" ({} the spec)", if b { "inside" } else { "OUTSIDE" })
            }
            _ => String::new(),
        };
        format!(
            "{}: {} → {}{verdict}",
            self.what,
            v(&self.old),
            v(&self.new)
        )
    }
}

impl Card {
    /// What changed from `old` to `self`, in `self`'s entry order (then `old`'s dropped ones).
    pub fn changes_since(&self, old: &Card) -> Vec<Change> {
        let find = |c: &Card, k: &str| c.entries.iter().find(|e| e.key == k).cloned();
        let mut out: Vec<Change> = self
            .entries
            .iter()
            .filter_map(|e| {
                let o = find(old, &e.key);
                (o.as_ref().map(|o| &o.value) != Some(&e.value)).then(|| Change {
                    key: e.key.clone(),
                    what: e.what.clone(),
                    old: o,
                    new: Some(e.clone()),
                })
            })
            .collect();
        out.extend(
            old.entries
                .iter()
                .filter(|e| find(self, &e.key).is_none())
                .map(|e| Change {
                    key: e.key.clone(),
                    what: e.what.clone(),
                    old: Some(e.clone()),
                    new: None,
                }),
        );
        out
    }

    /// The card as a table for a terminal.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{}: {}\n  ({} probe renders, {:.1} s; release {})\n",
            self.backend, self.driver, self.renders, self.seconds, self.release
        );
        for e in &self.entries {
            let measured = match e.measured {
                Some(m) if m.fract() == 0.0 => format!("measured {m:.0}, "),
                Some(m) => format!("measured {m:.4}, "),
                None => String::new(),
            };
            s.push_str(&format!(
                "  {}\n      {}   [{measured}{}]\n      spec: {}\n      probe: {}\n",
                e.what,
                e.value_and_verdict(),
                e.sure.words(),
                e.spec,
                e.probe
            ));
        }
        s
    }

    /// Reads a stored card.
    pub fn read(file: &Path) -> Result<Card, String> {
        let text = std::fs::read_to_string(file)
            .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
        serde_json::from_str(&text).map_err(|e| {
            format!(
                "{} is not a behaviour card: {e} (keep the live one with `umbra card --backend ID --keep golden`, or `cargo xtask bless`)",
                file.display()
            )
        })
    }

    /// The card as stored: pretty JSON, the seconds left out (they change every run).
    pub fn stored(&self) -> String {
        let mut c = self.clone();
        c.seconds = 0.0;
        serde_json::to_string_pretty(&c).unwrap_or_default() + "\n"
    }
}

/// The release a card is kept for: `mesa-X.Y.Z` for a Mesa driver, the flattened version
/// string for another, `umbra` for the reference (backend `id`).
pub fn release_of(
    id: &str,
    facts: &crate::judge::expectations::DriverFacts,
    version: &str,
) -> String {
    if id == "ref" {
        return "umbra".into();
    }
    match &facts.mesa {
        Some(m) => format!("mesa-{}", crate::judge::blessings::release(m)),
        None if version.is_empty() => "umbra".into(),
        None => version
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' {
                    c
                } else {
                    '-'
                }
            })
            .collect(),
    }
}

/// Where backend `id`'s card for `release` is kept in golden directory `dir`.
pub fn file(dir: &Path, id: &str, release: &str) -> PathBuf {
    dir.join(crate::judge::blessings::folder(id))
        .join(format!("card-{release}.json"))
}

/// Every card kept for backend `id` in `dir`, by release (sorted by name).
pub fn kept(dir: &Path, id: &str) -> Vec<(String, PathBuf)> {
    let folder = dir.join(crate::judge::blessings::folder(id));
    let mut out: Vec<(String, PathBuf)> = std::fs::read_dir(&folder)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let release = name
                .strip_prefix("card-")?
                .strip_suffix(".json")?
                .to_string();
            Some((release, e.path()))
        })
        .collect();
    out.sort();
    out
}

/// What conformance's `card` check found.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// The live card equals the one kept for this release.
    Unchanged,
    /// It differs: each change.
    Changed(Vec<Change>),
    /// No card is kept for this release: the changes against the nearest release's, if any
    /// is kept (which release), for the report; not a failure (a new release's choices are
    /// reported, and held once a bless keeps them).
    New(Option<(String, Vec<Change>)>),
    /// The kept card cannot be read.
    Unreadable(String),
}

/// Checks `live` against the cards kept in `dir`.
pub fn check(dir: &Path, live: &Card) -> Verdict {
    let own = file(dir, &live.backend, &live.release);
    if own.exists() {
        return match Card::read(&own) {
            Ok(old) => {
                let ch = live.changes_since(&old);
                if ch.is_empty() {
                    Verdict::Unchanged
                } else {
                    Verdict::Changed(ch)
                }
            }
            Err(e) => Verdict::Unreadable(e),
        };
    }
    let nearest = kept(dir, &live.backend)
        .into_iter()
        .min_by_key(|(r, _)| release_distance(r, &live.release));
    match nearest {
        None => Verdict::New(None),
        Some((r, f)) => match Card::read(&f) {
            Ok(old) => Verdict::New(Some((r, live.changes_since(&old)))),
            Err(e) => Verdict::Unreadable(e),
        },
    }
}

/// How far apart two releases are, for picking the nearest kept card: the differences of
/// their major, minor and patch numbers, weighted by place (10⁶, 10³, 1) and summed.
fn release_distance(a: &str, b: &str) -> u64 {
    let parts = |s: &str| crate::version::parts(s.trim_start_matches("mesa-"));
    let (pa, pb) = (parts(a), parts(b));
    let mut d = 0u64;
    for (i, w) in [1_000_000u64, 1_000, 1].iter().enumerate() {
        let x = i64::from(pa.get(i).copied().unwrap_or(0));
        let y = i64::from(pb.get(i).copied().unwrap_or(0));
        d += x.abs_diff(y) * w;
    }
    d
}

/// Every entry that changed from `old` to `new`, per backend both measured, as
/// `backend: change` lines in `new`'s order; then each backend measured on one side only.
pub fn changes_between(old: &[Card], new: &[Card]) -> Vec<String> {
    let find = |cards: &[Card], b: &str| cards.iter().position(|c| c.backend == b);
    let mut lines: Vec<String> = new
        .iter()
        .filter_map(|n| Some((n, &old[find(old, &n.backend)?])))
        .flat_map(|(n, o)| {
            n.changes_since(o)
                .into_iter()
                .map(move |c| format!("{}: {}", n.backend, c.line()))
        })
        .collect();
    for (cards, other, side) in [(new, old, "the new side"), (old, new, "the old side")] {
        for c in cards.iter().filter(|c| find(other, &c.backend).is_none()) {
            lines.push(format!("{}: measured on {side} only", c.backend));
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(key: &str, value: &str, inside: Option<bool>) -> Entry {
        Entry::new(key, key, value.into(), None, "s", inside, "p", Sure::Exact)
    }

    fn card(entries: Vec<Entry>) -> Card {
        Card {
            backend: "gl33/zink".into(),
            driver: "d".into(),
            release: "mesa-26.2.6".into(),
            entries,
            renders: 0,
            seconds: 0.0,
        }
    }

    #[test]
    fn a_change_names_the_entry_both_values_and_the_spec() {
        let old = card(vec![
            entry("offset-unit.depth16.z0.375", "4 codes", Some(false)),
            entry("same", "x", Some(true)),
            entry("gone", "y", None),
        ]);
        let new = card(vec![
            entry("offset-unit.depth16.z0.375", "2 codes", Some(true)),
            entry("same", "x", Some(true)),
        ]);
        let ch = new.changes_since(&old);
        let lines: Vec<String> = ch.iter().map(Change::line).collect();
        assert_eq!(
            lines,
            [
                "offset-unit.depth16.z0.375: 4 codes → 2 codes (was OUTSIDE, now inside the spec)",
                "gone: y → (no entry)",
            ]
        );
        assert!(new.changes_since(&new).is_empty());
    }

    #[test]
    fn cards_are_kept_per_backend_and_release_and_the_nearest_is_compared() {
        let dir = std::env::temp_dir().join(format!("umbra-card-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let old = card(vec![entry("a", "1", Some(true))]);
        let f = file(&dir, "gl33/zink", "mesa-22.3.6");
        std::fs::create_dir_all(f.parent().expect("a folder")).expect("the folder");
        std::fs::write(&f, old.stored()).expect("the card");
        let mut live = card(vec![entry("a", "2", Some(true))]);
        live.release = "mesa-22.3.6".into();
        assert!(matches!(check(&dir, &live), Verdict::Changed(c) if c.len() == 1));
        live.release = "mesa-26.2.6".into();
        match check(&dir, &live) {
            Verdict::New(Some((r, c))) => {
                assert_eq!(r, "mesa-22.3.6");
                assert_eq!(c.len(), 1);
            }
            v => panic!("{v:?}"),
        }
        live.entries = old.entries.clone();
        live.release = "mesa-22.3.6".into();
        assert_eq!(check(&dir, &live), Verdict::Unchanged);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
