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
    // Each light's visibility and map: light 0's as `visibility.png` and `shadow_map.png`,
    // light k's with `-k` before the extension.
    for (k, plane) in f.lights.iter().enumerate() {
        let name = |stem: &str| match k {
            0 => format!("{stem}.png"),
            k => format!("{stem}-{k}.png"),
        };
        heatmap::visibility_map(&plane.visibility, f.width, f.height)
            .save_png(&dir.join(name("visibility")))?;
        if let Some(m) = &plane.shadow_map {
            // Layers stacked top to bottom (cube faces +x, −x, +y, −y, +z, −z).
            heatmap::depth_map(&m.values, m.width, m.height * m.layers)
                .save_png(&dir.join(name("shadow_map")))?;
        }
    }
    judging_pictures(dir, j, None)?;
    Ok(())
}

/// Thumbnails fit in this many pixels on their long side (the gallery's cell).
pub const THUMB: u32 = 96;

/// Writes the gallery pictures of a judged run into `dir`: `thumb.png` (the backend's colour
/// shrunk to [`THUMB`] pixels by a box filter), `color.png`, `error.png` (heat map),
/// `reference.png`, `truth.png`, and the golden and pending golden when `golden` names files
/// that exist (`golden.png`, `pending.png`). The reference and the truth are the same for
/// every backend's run of a point: each distinct picture is encoded once, into `.shared/`
/// beside the runs' directories, and hard-linked into each run's. A colour that is its
/// golden's pixel for pixel (`identical`) is the golden's bytes, not encoded again.
///
/// Nothing here is ever a link to a file outside the report: a golden or a pending snapshot
/// is *copied* into `.shared/` (once per report) and linked from there, so a tool that edits
/// report pictures in place (a PNG optimiser over a CI artifact) cannot change `golden/`.
pub fn write_gallery(
    dir: &Path,
    j: &crate::judge::run::Judged,
    golden: Option<(&Path, &Path)>,
    identical: bool,
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
    let thumb = image::imageops::thumbnail(&colour, tw, th);
    save(&dir.join("thumb.png"), (thumb.as_raw(), tw, th))?;
    // The gallery root is the conformance run's own: its runs share `.shared/` beside their
    // directories.
    let shared = dir.parent().map(|p| p.join(".shared"));
    let blessed = golden.map(|g| g.0).filter(|g| g.is_file());
    match (blessed, &shared) {
        (Some(g), Some(shared)) if identical => {
            link(&copy_into(g, shared)?, &dir.join("color.png"))?;
        }
        _ => save(&dir.join("color.png"), (&f.color, f.width, f.height))?,
    }
    judging_pictures(dir, j, shared.as_deref())?;
    if let Some((blessed, pending)) = golden {
        for (from, to) in [(blessed, "golden.png"), (pending, "pending.png")] {
            if from.is_file() {
                match &shared {
                    Some(shared) => link(&copy_into(from, shared)?, &dir.join(to))?,
                    None => {
                        std::fs::copy(from, dir.join(to))?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Encodes a gallery picture: PNG with the Paeth filter on every row, which compresses these
/// renders within a few per cent of the encoder's default adaptive choice (tried per row
/// with every filter) at well under half its time. Goldens keep the default encoding
/// ([`crate::judge::golden::png`]): their bytes are what insta compares.
fn save(path: &Path, (rgba, width, height): (&[u8], u32, u32)) -> std::io::Result<()> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    image::ImageEncoder::write_image(
        PngEncoder::new_with_quality(file, CompressionType::Fast, FilterType::Paeth),
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(std::io::Error::other)
}

/// A copy of `from` (a golden or a pending snapshot) in the report's `shared` directory,
/// named by its bytes' key, made once per report (through [`crate::atomic_file`], so
/// concurrent workers never see half a file): the file the report's pictures link to.
fn copy_into(from: &Path, shared: &Path) -> std::io::Result<std::path::PathBuf> {
    let bytes = std::fs::read(from)?;
    std::fs::create_dir_all(shared)?;
    let file = shared.join(format!(
        "file-{:016x}.png",
        picture_key(bytes.len() as u32, 0, &bytes)
    ));
    if !file.is_file() {
        crate::atomic_file::write(&file, &bytes)?;
    }
    Ok(file)
}

/// `to` as a hard link to `from`, a file of the report itself (a copy where no link can be
/// made), replacing `to`.
fn link(from: &Path, to: &Path) -> std::io::Result<()> {
    let _ = std::fs::remove_file(to);
    if std::fs::hard_link(from, to).is_err() {
        std::fs::copy(from, to)?;
    }
    Ok(())
}

/// A 64-bit content key of a picture: its size, then its pixels eight bytes at a time, each
/// word mixed in by a multiply and a shift (a content address within one run, not a
/// cryptographic hash; byte-wise FNV cost more than encoding the picture).
fn picture_key(width: u32, height: u32, rgba: &[u8]) -> u64 {
    let mix = |h: u64, w: u64| {
        let h = (h ^ w).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        h ^ (h >> 29)
    };
    let mut h = mix(
        0xcbf2_9ce4_8422_2325,
        u64::from(width) << 32 | u64::from(height),
    );
    let words = rgba.chunks_exact(8);
    let rest = words.remainder();
    for w in words {
        h = mix(h, u64::from_le_bytes(w.try_into().unwrap_or_default()));
    }
    let mut last = [0u8; 8];
    last[..rest.len()].copy_from_slice(rest);
    mix(mix(h, u64::from_le_bytes(last)), rest.len() as u64)
}

/// `dir/name`: with `shared`, a hard link to `shared/KEY.png` ([`picture_key`]), which is
/// encoded only if no worker has encoded the same pixels yet (through
/// [`crate::atomic_file`], so a reader never sees half a file; where a link cannot be made, a
/// copy); without, the picture itself.
fn png(
    dir: &Path,
    name: &str,
    picture: (&[u8], u32, u32),
    shared: Option<&Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    let target = dir.join(name);
    let Some(shared) = shared else {
        return Ok(save(&target, picture)?);
    };
    std::fs::create_dir_all(shared)?;
    let (rgba, width, height) = picture;
    let file = shared.join(format!("{:016x}.png", picture_key(width, height, rgba)));
    if !file.is_file() {
        crate::atomic_file::replace(&file, |path| save(path, picture))?;
    }
    Ok(link(&file, &target)?)
}

/// What the judge saw, beside any backend's frame: the truth, the error heat map and the
/// reference's colour. The truth and the reference are the same for every backend's run of a
/// point, and backends that agree have the same heat map: with `shared`, each distinct
/// picture is encoded once ([`png`]).
fn judging_pictures(
    dir: &Path,
    j: &crate::judge::run::Judged,
    shared: Option<&Path>,
) -> Result<(), Box<dyn std::error::Error>> {
    // The first light's truth, beside the frame's first light's visibility (a picture per
    // light comes with the frame's lights as a list).
    let truth = heatmap::truth_map(&j.truths[0]);
    png(
        dir,
        "truth.png",
        (&truth.data, truth.width, truth.height),
        shared,
    )?;
    let error = heatmap::truth_error_map(&j.error, &j.truths[0]);
    png(
        dir,
        "error.png",
        (&error.data, error.width, error.height),
        shared,
    )?;
    if let Some(r) = &j.reference {
        png(dir, "reference.png", (&r.color, r.width, r.height), shared)?;
    }
    Ok(())
}
