//! `umbra selftest orientations` (or `--orientations`): the face/orientation table.
//!
//! A cube face (or a 2D map) drawn with a wrong orientation (a wrong up vector turns it, a
//! wrong handedness or row order mirrors it, swapped axes transpose it: the seven symmetries
//! of the square other than the identity, [`Orientation`]) stores the right depths in the
//! wrong texels. Where the face's content is symmetric under that mistake the map is the same
//! and no judge can see it: point-cube and cube-seams are four-fold symmetric about the light,
//! so a quarter turn of their side faces passed. This table asks the catalogue, for each of
//! the 6 × 7 cube-face mistakes and the 7 mistakes of a 2D map, which points see it: the
//! reference renders the point with the mistake ([`umbra_ref::render_with_fault`]) and its
//! frame is judged against the point's intervals for the GL profile, exactly as a backend's
//! would be. A mistake no point sees is a blind spot of the catalogue, and fails.
//!
//! The reference draws the mistake as the backends' `Oriented` self-test fault does (the same
//! matrix in front of the face's view-projection, the front face flipped with a mirror), so
//! the table says what the catalogue can see; `cargo xtask selftest` shows that the backends'
//! judge sees it too for the three mistakes it runs by default.

use std::collections::BTreeMap;

use umbra_case::fault::{Fault, Orientation};
use umbra_case::{CasePoint, ClipDepth, Prepared, Profile};

use crate::exit::{Exit, Outcome};

/// What one mistake did on the catalogue.
#[derive(Clone, Debug, Default)]
pub struct Cell {
    /// Points that use the face (point lights for cube faces, the others for the 2D map).
    pub tried: usize,
    /// Points whose faulted frame has illegal pixels, each with their count and the map's
    /// illegal texels.
    pub caught: Vec<(String, u64, u64)>,
}

impl Cell {
    /// The point that shows it most, with its illegal pixels.
    pub fn best(&self) -> Option<&(String, u64, u64)> {
        self.caught.iter().max_by_key(|c| c.1)
    }
}

/// The cases built to show a face's orientation: tried first.
const AIMED: [&str; 2] = ["point-faces", "l-occluder"];

/// Judges every orientation fault on `points`; with `enough`, a mistake stops at that many
/// catching points (aimed cases first), otherwise every point using the face is run.
pub fn table(points: &[CasePoint], enough: Option<usize>) -> Vec<(Fault, Cell)> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| !AIMED.contains(&points[i].case.name.as_str()));
    let mut bases: BTreeMap<usize, (Prepared, umbra_ref::Judged)> = BTreeMap::new();
    let mut rows = Vec::new();
    for fault in Fault::orientations() {
        let Fault::Oriented { face, .. } = fault else {
            continue;
        };
        let mut cell = Cell::default();
        for &i in &order {
            let point = &points[i];
            let cube = matches!(point.case.lights[0], umbra_case::format::Light::Point(_));
            if cube != face.is_some() {
                continue;
            }
            if enough.is_some_and(|n| cell.caught.len() >= n) {
                break;
            }
            let (run, basis) = bases.entry(i).or_insert_with(|| {
                let run = Prepared::new(point.clone());
                let basis = umbra_ref::render_judged(&run, ClipDepth::MinusOneToOne, Profile::GL);
                (run, basis)
            });
            cell.tried += 1;
            let frame = umbra_ref::render_with_fault(run, ClipDepth::MinusOneToOne, fault);
            let (agreement, _) = umbra_compare::reference::judge(basis, &frame);
            if agreement.illegal > 0 {
                cell.caught
                    .push((point.id(), agreement.illegal, agreement.illegal_map));
            }
        }
        rows.push((fault, cell));
    }
    rows
}

/// The table as text: one row per face, one column per orientation, each cell "caught/tried
/// max-illegal-px"; then the best point of each row.
pub fn render(rows: &[(Fault, Cell)]) -> String {
    let mut out = String::from(
        "face/orientation table: catalogue points whose frame shows illegal pixels when the \
         reference draws the face wrong / points that use the face (most illegal px)\n",
    );
    out.push_str(&format!("{:<6}", "face"));
    for o in Orientation::ALL {
        out.push_str(&format!(" {:>18}", o.name()));
    }
    out.push('\n');
    const FACES: [&str; 7] = ["+x", "-x", "+y", "-y", "+z", "-z", "2D"];
    for (k, label) in FACES.iter().enumerate() {
        let face = (k < 6).then_some(k as u8);
        out.push_str(&format!("{label:<6}"));
        let mut best: Option<(String, u64, &str)> = None;
        for o in Orientation::ALL {
            let cell = rows.iter().find_map(|(f, c)| {
                (*f == Fault::Oriented {
                    face,
                    orientation: o,
                })
                .then_some(c)
            });
            let text = match cell {
                Some(c) => {
                    let most = c.best().map_or(0, |b| b.1);
                    if let Some(b) = c.best()
                        && best.as_ref().is_none_or(|x| b.1 > x.1)
                    {
                        best = Some((b.0.clone(), b.1, o.name()));
                    }
                    format!("{}/{} ({most} px)", c.caught.len(), c.tried)
                }
                None => "-".into(),
            };
            out.push_str(&format!(" {text:>18}"));
        }
        if let Some((id, n, o)) = best {
            out.push_str(&format!("   most: {id}, {o}, {n} px"));
        }
        out.push('\n');
    }
    out
}

/// The command: the table over the self-test's points (`--cases`, loaded and checked by
/// `selftest::setup`); it fails when a mistake goes unseen.
pub fn main(points: &[CasePoint]) -> Outcome {
    let start = std::time::Instant::now();
    let rows = table(points, None);
    print!("{}", render(&rows));
    let blind: Vec<String> = rows
        .iter()
        .filter(|(_, c)| c.caught.is_empty())
        .map(|(f, c)| format!("{} ({} points use the face)", f.name(), c.tried))
        .collect();
    println!(
        "orientations: {} of {} mistakes seen by the catalogue in {:.1} s",
        rows.len() - blind.len(),
        rows.len(),
        start.elapsed().as_secs_f64()
    );
    for b in &blind {
        println!("  blind: {b}");
    }
    Ok(Exit::pass_if(blind.is_empty()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every face of a cube map and the 2D map, drawn with each wrong orientation, is seen by
    /// at least one catalogue point's judge (the aimed cases are tried first, so this stops
    /// early when they do their job).
    #[test]
    fn the_catalogue_sees_every_wrong_face_orientation() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases");
        let points: Vec<CasePoint> = umbra_case::case_files(&root)
            .expect("cases/")
            .iter()
            .flat_map(|f| umbra_case::load_file(f).expect("a valid case"))
            .collect();
        let rows = table(&points, Some(1));
        assert_eq!(rows.len(), 49);
        let blind: Vec<String> = rows
            .iter()
            .filter(|(_, c)| c.caught.is_empty())
            .map(|(f, _)| f.name())
            .collect();
        assert!(
            blind.is_empty(),
            "no catalogue point sees {blind:?}:\n{}",
            render(&rows)
        );
    }
}
