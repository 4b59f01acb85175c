//! The pictures of a judged run, written where a person or the report will look: the
//! backend's colour and visibility, the reference, the truth, the error heat map and the shadow
//! map (names the report reads back, see `umbra_report::html`), and for every judged run of a
//! conformance run the gallery's set (see `umbra_report::gallery`).

use std::path::Path;

use umbra_compare::heatmap;

/// Writes the images of a judged run into `dir`.
pub fn write_images(
    dir: &Path,
    j: &crate::judge::run::Judged,
) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let f = &j.frame;
    image::save_buffer(
        dir.join("color.png"),
        &f.color,
        f.width,
        f.height,
        image::ColorType::Rgba8,
    )?;
    heatmap::visibility_map(&f.visibility, f.width, f.height)
        .save_png(&dir.join("visibility.png"))?;
    judging_pictures(dir, j, None)?;
    if let Some(m) = &f.shadow_map {
        // Layers stacked top to bottom (cube faces +x, −x, +y, −y, +z, −z).
        heatmap::depth_map(&m.values, m.width, m.height * m.layers)
            .save_png(&dir.join("shadow_map.png"))?;
    }
    Ok(())
}

/// Thumbnails fit in this many pixels on their long side (the gallery's cell).
pub const THUMB: u32 = 96;

/// Writes the gallery pictures of a judged run into `dir`: `thumb.png` (the backend's colour
/// shrunk to [`THUMB`] pixels by a box filter), `color.png`, `error.png` (heat map),
/// `reference.png`, `truth.png`, and the golden and pending golden when `golden` names files
/// that exist (`golden.png`, `pending.png`). The reference and the truth are the same for
/// every backend's run of a point: each distinct picture is encoded once, into `.shared/`
/// beside the runs' directories, and hard-linked into each run's.
pub fn write_gallery(
    dir: &Path,
    j: &crate::judge::run::Judged,
    golden: Option<(&Path, &Path)>,
) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let f = &j.frame;
    let colour = image::RgbaImage::from_raw(f.width, f.height, f.color.clone())
        .ok_or("frame size does not match its colour buffer")?;
    let scale = f64::from(THUMB) / f64::from(f.width.max(f.height).max(1));
    let (tw, th) = if scale < 1.0 {
        (
            ((f64::from(f.width) * scale).round() as u32).max(1),
            ((f64::from(f.height) * scale).round() as u32).max(1),
        )
    } else {
        (f.width, f.height)
    };
    image::imageops::thumbnail(&colour, tw, th).save(dir.join("thumb.png"))?;
    colour.save(dir.join("color.png"))?;
    // The gallery root is the conformance run's own (cleared at its start): its runs share
    // `.shared/` beside their directories.
    judging_pictures(dir, j, dir.parent().map(|p| p.join(".shared")).as_deref())?;
    if let Some((blessed, pending)) = golden {
        for (from, to) in [(blessed, "golden.png"), (pending, "pending.png")] {
            if from.is_file() {
                std::fs::copy(from, dir.join(to))?;
            }
        }
    }
    Ok(())
}

/// `dir/name`: with `shared`, a hard link to `shared/HASH.png`, which is encoded only if no
/// worker has encoded the same pixels yet (through [`crate::atomic_file`], so a reader never
/// sees half a file; where a link cannot be made, a copy); without, the picture itself.
fn png(
    dir: &Path,
    name: &str,
    (rgba, width, height): (&[u8], u32, u32),
    shared: Option<&Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    let save = |path: &Path| {
        image::save_buffer(path, rgba, width, height, image::ColorType::Rgba8)
            .map_err(std::io::Error::other)
    };
    let target = dir.join(name);
    let Some(shared) = shared else {
        return Ok(save(&target)?);
    };
    std::fs::create_dir_all(shared)?;
    let key = umbra_report::names::fnv64(
        width
            .to_le_bytes()
            .into_iter()
            .chain(height.to_le_bytes())
            .chain(rgba.iter().copied()),
    );
    let file = shared.join(format!("{key}.png"));
    if !file.is_file() {
        crate::atomic_file::replace(&file, save)?;
    }
    let _ = std::fs::remove_file(&target);
    if std::fs::hard_link(&file, &target).is_err() {
        std::fs::copy(&file, &target)?;
    }
    Ok(())
}

/// What the judge saw, beside any backend's frame: the truth, the error heat map and the
/// reference's colour. The truth and the reference are the same for every backend's run of a
/// point: with `shared`, each distinct one is encoded once ([`png`]).
fn judging_pictures(
    dir: &Path,
    j: &crate::judge::run::Judged,
    shared: Option<&Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    let truth = heatmap::truth_map(&j.truth);
    png(
        dir,
        "truth.png",
        (&truth.data, truth.width, truth.height),
        shared,
    )?;
    heatmap::truth_error_map(&j.error, &j.truth).save_png(&dir.join("error.png"))?;
    if let Some(r) = &j.reference {
        png(dir, "reference.png", (&r.color, r.width, r.height), shared)?;
    }
    Ok(())
}
