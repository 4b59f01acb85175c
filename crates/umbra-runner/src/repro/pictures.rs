//! The bundle's pictures: umbra's full-size set (`full/`, as `umbra render` writes it) and
//! expected | actual | difference cropped to the failing pixels and magnified, for issue.md.

use std::path::Path;

use umbra_compare::reference::PixelJudgement;

use crate::repro::probes::Probes;

/// Pixels of context kept around the failing area.
const MARGIN: u32 = 3;
/// The long side of a magnified crop, at most.
const TARGET: u32 = 384;

/// Writes `full/` and `expected.png`, `actual.png`, `difference.png`; returns the crop
/// `[x, y, w, h, scale]`.
pub fn write(
    dir: &Path,
    j: &crate::judge::run::Judged,
    pixels: &[PixelJudgement],
    probes: &Probes,
) -> Result<[u32; 5], Box<dyn std::error::Error>> {
    crate::judge::pictures::write_images(&dir.join("full"), j)?;
    let f = &j.frame;
    let (w, h) = (f.width, f.height);
    let bad: Vec<(u32, u32)> = pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| **p == PixelJudgement::Illegal)
        .map(|(i, _)| (i as u32 % w, i as u32 / w))
        .collect();
    // Texel failures alone: the whole frame (the map picture is in full/).
    let (x0, y0, x1, y1) = if bad.is_empty() || probes.pixels.is_empty() {
        (0, 0, w - 1, h - 1)
    } else {
        let xs = bad.iter().map(|p| p.0);
        let ys = bad.iter().map(|p| p.1);
        (
            xs.clone().min().unwrap_or(0).saturating_sub(MARGIN),
            ys.clone().min().unwrap_or(0).saturating_sub(MARGIN),
            (xs.max().unwrap_or(0) + MARGIN).min(w - 1),
            (ys.max().unwrap_or(0) + MARGIN).min(h - 1),
        )
    };
    let (cw, ch) = (x1 - x0 + 1, y1 - y0 + 1);
    let scale = (TARGET / cw.max(ch)).clamp(1, 16);
    let crop = |rgba: &dyn Fn(u32, u32) -> [u8; 4]| {
        image::RgbaImage::from_fn(cw * scale, ch * scale, |x, y| {
            image::Rgba(rgba(x0 + x / scale, y0 + y / scale))
        })
    };
    let px = |c: &[u8], x: u32, y: u32| {
        let i = ((y * w + x) * 4) as usize;
        [c[i], c[i + 1], c[i + 2], 255]
    };
    crop(&|x, y| px(&f.color, x, y)).save(dir.join("actual.png"))?;
    if let Some(r) = &j.reference {
        crop(&|x, y| px(&r.color, x, y)).save(dir.join("expected.png"))?;
    }
    crop(&|x, y| match pixels[(y * w + x) as usize] {
        PixelJudgement::Illegal => [255, 40, 40, 255],
        PixelJudgement::LegalDifference => [230, 170, 40, 255],
        PixelJudgement::Blind => [90, 90, 140, 255],
        PixelJudgement::Agrees => {
            let [r, g, b, _] = px(&f.color, x, y);
            let l = ((u32::from(r) + u32::from(g) + u32::from(b)) / 6) as u8;
            [l, l, l, 255]
        }
        PixelJudgement::NotCompared => [0, 0, 0, 255],
    })
    .save(dir.join("difference.png"))?;
    Ok([x0, y0, cw, ch, scale])
}
