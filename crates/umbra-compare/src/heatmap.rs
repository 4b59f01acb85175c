//! Pictures of the metrics, as RGBA8 images ready for PNG.
//!
//! Truth-error legend: black background; dark blue-grey faces away from the light; dark purple
//! outside the light's frustum; olive silhouettes; light grey correctly lit; mid grey correctly
//! shadowed (both a little bluer on edge pixels); **red** false shadow away from edges, orange
//! false shadow on an edge; **blue** false light away from edges, light blue false light on an
//! edge.

use std::path::Path;

use umbra_ref::truth::Truth;

use crate::{Agreement, PixelVerdict, TruthError};

/// An RGBA8 image, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgba {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Pixels, 4 bytes each.
    pub data: Vec<u8>,
}

impl Rgba {
    /// Writes the image as PNG.
    pub fn save_png(&self, path: &Path) -> image::ImageResult<()> {
        image::save_buffer(
            path,
            &self.data,
            self.width,
            self.height,
            image::ColorType::Rgba8,
        )
    }
}

/// Colour of a verdict; `edge` tints judged pixels on shadow edges.
pub fn verdict_color(v: PixelVerdict, edge: bool) -> [u8; 4] {
    let rgb = match (v, edge) {
        (PixelVerdict::Background, _) => [0, 0, 0],
        (PixelVerdict::FacesAway, _) => [40, 44, 64],
        (PixelVerdict::Outside, _) => [64, 32, 72],
        (PixelVerdict::Silhouette, _) => [110, 110, 20],
        (PixelVerdict::Lit, false) => [210, 210, 210],
        (PixelVerdict::Lit, true) => [185, 185, 225],
        (PixelVerdict::Shadowed, false) => [95, 95, 95],
        (PixelVerdict::Shadowed, true) => [95, 95, 135],
        (PixelVerdict::FalseShadow, false) => [255, 30, 30],
        (PixelVerdict::FalseShadow, true) => [255, 160, 40],
        (PixelVerdict::FalseLight, false) => [30, 90, 255],
        (PixelVerdict::FalseLight, true) => [110, 200, 255],
    };
    [rgb[0], rgb[1], rgb[2], 255]
}

/// The truth-error heat map.
pub fn truth_error_map(error: &TruthError, truth: &Truth) -> Rgba {
    let data = error
        .verdicts
        .iter()
        .zip(&truth.edge)
        .flat_map(|(v, e)| verdict_color(*v, *e))
        .collect();
    Rgba {
        width: truth.width,
        height: truth.height,
        data,
    }
}

/// The truth itself: white lit, grey shadowed, dark excluded, black background; edge pixels
/// tinted blue.
pub fn truth_map(truth: &Truth) -> Rgba {
    use umbra_ref::truth::Class;
    let data = truth
        .class
        .iter()
        .zip(&truth.edge)
        .flat_map(|(c, e)| {
            let v = match c {
                Class::Background => PixelVerdict::Background,
                Class::FacesAway => PixelVerdict::FacesAway,
                Class::Outside => PixelVerdict::Outside,
                Class::Lit => PixelVerdict::Lit,
                Class::Shadowed => PixelVerdict::Shadowed,
            };
            verdict_color(v, *e)
        })
        .collect();
    Rgba {
        width: truth.width,
        height: truth.height,
        data,
    }
}

/// Visibility as grey levels (NaN background black, otherwise 40 + 215·v so a shadowed surface
/// stays distinguishable from the background).
pub fn visibility_map(visibility: &[f32], width: u32, height: u32) -> Rgba {
    let data = visibility
        .iter()
        .flat_map(|v| {
            if v.is_nan() {
                [0, 0, 0, 255]
            } else {
                let g = (40.0 + 215.0 * v.clamp(0.0, 1.0)).round() as u8;
                [g, g, g, 255]
            }
        })
        .collect();
    Rgba {
        width,
        height,
        data,
    }
}

/// Agreement heat map over frame `a`'s visibility: disagreements in magenta on a dimmed copy.
pub fn agreement_map(g: &Agreement, a_visibility: &[f32], width: u32, height: u32) -> Rgba {
    let mut img = visibility_map(a_visibility, width, height);
    for (px, bad) in img.data.chunks_mut(4).zip(&g.disagrees) {
        if *bad {
            px.copy_from_slice(&[255, 0, 255, 255]);
        } else {
            for c in &mut px[..3] {
                *c /= 2;
            }
        }
    }
    img
}

/// A depth layer as grey levels stretched over its own range (far-plane texels white).
pub fn depth_map(values: &[f32], width: u32, height: u32) -> Rgba {
    let (lo, hi) = values
        .iter()
        .filter(|v| **v < 1.0)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let data = values
        .iter()
        .flat_map(|v| {
            let g = if *v >= 1.0 {
                255
            } else {
                (((v - lo) / span).clamp(0.0, 1.0) * 230.0).round() as u8
            };
            [g, g, g, 255]
        })
        .collect();
    Rgba {
        width,
        height,
        data,
    }
}
