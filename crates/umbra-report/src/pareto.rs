//! The sweep's Pareto plot, drawn with plotters: frame time (log x) against error (y), one
//! colour per backend, every point as a small circle and the front joined by a line with
//! larger markers. The same drawing goes to SVG and to an RGB bitmap that `image` encodes as
//! PNG. Text uses the bundled DejaVu Sans Mono (assets/, with its licence), so the PNG does
//! not depend on the machine's fonts.

use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

/// One point of the plot: a backend's measurement of one technique (none: skipped or
/// failed, which still puts the backend in the legend) and whether it is on its front.
#[derive(Clone, Debug)]
pub struct ParetoPoint {
    /// Backend id.
    pub backend: String,
    /// (frame time ms, error % of judged pixels), when measured.
    pub measured: Option<(f64, f64)>,
    /// On the backend's Pareto front.
    pub front: bool,
}

const SIZE: (u32, u32) = (960, 600);
const FONT: &[u8] = include_bytes!("../assets/DejaVuSansMono.ttf");
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Registration fails only for an unreadable font, which include_bytes rules out.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// The plot as SVG text.
pub fn svg(rows: &[ParetoPoint], title: &str) -> Result<String, String> {
    register_font();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, SIZE).into_drawing_area();
        draw(&root, rows, title)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(text)
}

/// The plot as PNG bytes.
pub fn png(rows: &[ParetoPoint], title: &str) -> Result<Vec<u8>, String> {
    register_font();
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, rows, title)?;
        root.present().map_err(|e| e.to_string())?;
    }
    let mut png = Vec::new();
    image::RgbImage::from_raw(SIZE.0, SIZE.1, rgb)
        .ok_or("bitmap size mismatch")?
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(png)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    rows: &[ParetoPoint],
    title: &str,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let points: Vec<(usize, f64, f64)> = rows
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let (ms, error) = r.measured?;
            Some((i, ms.max(1e-3), error))
        })
        .collect();
    let (mut tmin, mut tmax) = (f64::INFINITY, 0.0f64);
    let (mut emin, mut emax) = (f64::INFINITY, 0.0f64);
    for (_, t, e) in &points {
        tmin = tmin.min(*t);
        tmax = tmax.max(*t);
        emax = emax.max(*e);
        if *e > 0.0 {
            emin = emin.min(*e);
        }
    }
    if points.is_empty() {
        (tmin, tmax, emax) = (0.1, 10.0, 1.0);
    }
    // Errors span decades (acne near 50 %, good techniques near 0.01 %), so y is logarithmic
    // too; an error of exactly 0 is drawn on the floor, half the smallest non-zero error.
    let floor = if emin.is_finite() { emin / 2.0 } else { 1e-3 };
    let points: Vec<(usize, f64, f64)> = points
        .into_iter()
        .map(|(i, t, e)| (i, t, e.max(floor)))
        .collect();
    let x = (tmin / 1.5)..(tmax * 1.5);
    let y = (floor / 1.5)..(emax.max(floor) * 1.5);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x.log_scale(), y.log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frame time (shadow + lit pass), ms: median of N after warm-up; log")
        .y_desc(format!(
            "error vs truth, % of judged px (log; 0 drawn at {floor:.2e})"
        ))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    let mut backends: Vec<&str> = rows.iter().map(|r| r.backend.as_str()).collect();
    backends.dedup();
    backends.sort();
    backends.dedup();
    for (k, backend) in backends.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let mine: Vec<&(usize, f64, f64)> = points
            .iter()
            .filter(|(i, _, _)| rows[*i].backend == *backend)
            .collect();
        chart
            .draw_series(
                mine.iter()
                    .map(|(_, t, e)| Circle::new((*t, *e), 3, colour.mix(0.45).filled())),
            )
            .map_err(err)?;
        let mut on: Vec<(f64, f64)> = mine
            .iter()
            .filter(|(i, _, _)| rows[*i].front)
            .map(|(_, t, e)| (*t, *e))
            .collect();
        on.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(on.clone(), colour.stroke_width(2)))
            .map_err(err)?
            .label(format!("{backend} (front)"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(on.iter().map(|p| Circle::new(*p, 5, colour.filled())))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    Ok(())
}
