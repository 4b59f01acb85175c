//! The pictures of a judged run, written where a person or the report will look: the
//! backend's colour and visibility, the reference, the truth, the error heat map and the shadow
//! map (names the report reads back, see `umbra_report::html`).

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
    heatmap::truth_map(&j.truth).save_png(&dir.join("truth.png"))?;
    heatmap::truth_error_map(&j.error, &j.truth).save_png(&dir.join("error.png"))?;
    if let Some(r) = &j.reference {
        image::save_buffer(
            dir.join("reference.png"),
            &r.color,
            r.width,
            r.height,
            image::ColorType::Rgba8,
        )?;
    }
    if let Some(m) = &f.shadow_map {
        // Layers stacked top to bottom (cube faces +x, −x, +y, −y, +z, −z).
        heatmap::depth_map(&m.values, m.width, m.height * m.layers)
            .save_png(&dir.join("shadow_map.png"))?;
    }
    Ok(())
}
