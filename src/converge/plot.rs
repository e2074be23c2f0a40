//! The converge plot: log-log relMSE against seconds, drawn with `plotters` into a bitmap and
//! written as PNG.
//!
//! Text needs a TrueType font; plotters' `ab_glyph` backend has none built in, so the first
//! of `LUMAGRAPH_FONT` and a few usual system paths (`DejaVuSans.ttf`, `LiberationSans-Regular.ttf`) is
//! registered. Without any, the plot is not written and the command says why (the CSV and
//! the table are still there).

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Result, anyhow, bail};
use plotters::prelude::*;

use super::Compare;

const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Registers a sans-serif font once; whether one was found.
fn font() -> bool {
    static FOUND: OnceLock<bool> = OnceLock::new();
    *FOUND.get_or_init(|| {
        let env = std::env::var("LUMAGRAPH_FONT").ok();
        env.iter()
            .map(String::as_str)
            .chain(FONT_PATHS.iter().copied())
            .filter_map(|p| std::fs::read(p).ok())
            .any(|bytes| {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
            })
    })
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn draw_err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// Writes the plot of `series` (ours, lines with dots) and `compare` (lines with crosses).
///
/// # Errors
/// When no font is found, drawing fails or the file cannot be written.
pub fn write(
    path: &Path,
    series: &[(String, Vec<(f64, f64)>)],
    compare: Option<&Compare>,
) -> Result<()> {
    if !font() {
        bail!("no TrueType font found for the plot's text (set LUMAGRAPH_FONT=path/to/font.ttf)");
    }
    let (w, h) = (720_u32, 480_u32);
    let mut rgb = vec![0_u8; (w * h * 3) as usize];
    let all: Vec<(f64, f64)> = series
        .iter()
        .chain(compare.into_iter().flatten())
        .flat_map(|(_, p)| p.iter().copied())
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .collect();
    if all.is_empty() {
        bail!("nothing to plot");
    }
    let (x0, x1) = all.iter().fold((f64::MAX, f64::MIN), |(a, b), (x, _)| {
        (a.min(*x), b.max(*x))
    });
    let (y0, y1) = all.iter().fold((f64::MAX, f64::MIN), |(a, b), (_, y)| {
        (a.min(*y), b.max(*y))
    });
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("error against wall time", ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(
                (x0 / 1.5..x1 * 1.5).log_scale(),
                (y0 / 1.5..y1 * 1.5).log_scale(),
            )
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("seconds (render + denoise), log")
            .y_desc("relMSE vs reference, log")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| format!("{v:.2}"))
            .draw()
            .map_err(draw_err)?;
        let ours = series.iter().map(|s| (s, true));
        let theirs = compare.into_iter().flatten().map(|s| (s, false));
        for (i, ((name, pts), is_ours)) in ours.chain(theirs).enumerate() {
            let color = COLORS[i % COLORS.len()];
            let width = if is_ours { 2 } else { 1 };
            chart
                .draw_series(LineSeries::new(
                    pts.iter().copied(),
                    color.stroke_width(width),
                ))
                .map_err(draw_err)?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(width))
                });
            if is_ours {
                chart
                    .draw_series(pts.iter().map(|p| Circle::new(*p, 3, color.filled())))
                    .map_err(draw_err)?;
            } else {
                chart
                    .draw_series(pts.iter().map(|p| Cross::new(*p, 4, color.stroke_width(1))))
                    .map_err(draw_err)?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(draw_err)?;
        root.present().map_err(draw_err)?;
    }
    let rgba: Vec<u8> = rgb
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    crate::render::image_io::write_png(path, w, h, &rgba)?;
    Ok(())
}
