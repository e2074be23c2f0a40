//! Scopes of the previewed image, as a colourist reads them: a histogram (per channel and
//! luma, of the displayed 8-bit values) and a luma waveform (for each column of the image,
//! how many of its pixels have each value: the image's brightness seen from the side).

use egui::{Color32, Shape, Stroke, Ui};

use crate::preview::PreviewImage;

/// Which scope the preview panel shows under the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scope {
    /// None.
    #[default]
    Off,
    /// Red, green, blue and luma histograms.
    Histogram,
    /// Luma waveform.
    Waveform,
}

impl Scope {
    /// Every scope, in menu order.
    pub const ALL: [Self; 3] = [Self::Off, Self::Histogram, Self::Waveform];

    /// Menu label.
    pub fn label(self) -> &'static str {
        match self {
            Self::Off => "no scope",
            Self::Histogram => "histogram",
            Self::Waveform => "waveform",
        }
    }
}

/// Rec. 709 luma of 8-bit display values, rounded.
fn luma(p: &[u8]) -> usize {
    let y = 0.2126 * f32::from(p[0]) + 0.7152 * f32::from(p[1]) + 0.0722 * f32::from(p[2]);
    #[expect(clippy::cast_possible_truncation, reason = "0 ≤ y ≤ 255")]
    #[expect(clippy::cast_sign_loss, reason = "0 ≤ y ≤ 255")]
    let v = y.round() as usize;
    v.min(255)
}

/// Counts of each 8-bit value in red, green, blue and luma.
pub fn histogram(image: &PreviewImage) -> [[u32; 256]; 4] {
    let mut h = [[0_u32; 256]; 4];
    for p in image.rgba.chunks_exact(4) {
        for c in 0..3 {
            h[c][usize::from(p[c])] += 1;
        }
        h[3][luma(p)] += 1;
    }
    h
}

/// Rows of the waveform: values are binned in pairs (0–1 at the bottom, 254–255 at the top).
pub const WAVEFORM_ROWS: usize = 128;

/// The luma waveform: `columns` columns across the image, [`WAVEFORM_ROWS`] rows of value
/// (top row brightest), each the count of pixels of that column band with that luma.
/// Row-major, top row first.
pub fn waveform(image: &PreviewImage, columns: usize) -> Vec<u32> {
    let columns = columns.max(1);
    let mut counts = vec![0_u32; columns * WAVEFORM_ROWS];
    let width = image.width.max(1) as usize;
    for (i, p) in image.rgba.chunks_exact(4).enumerate() {
        let col = (i % width) * columns / width;
        let row = WAVEFORM_ROWS - 1 - luma(p) * WAVEFORM_ROWS / 256;
        counts[row * columns + col] += 1;
    }
    counts
}

/// The waveform as a green-on-black image: brightness grows with the log of the count.
fn waveform_image(counts: &[u32], columns: usize) -> egui::ColorImage {
    let max = counts.iter().copied().max().unwrap_or(1).max(1);
    #[expect(clippy::cast_precision_loss, reason = "display")]
    let scale = 1.0 / (1.0 + max as f32).ln();
    let pixels = counts
        .iter()
        .map(|&n| {
            #[expect(clippy::cast_precision_loss, reason = "display")]
            let t = (1.0 + n as f32).ln() * scale;
            #[expect(clippy::cast_possible_truncation, reason = "0 ≤ t ≤ 1")]
            #[expect(clippy::cast_sign_loss, reason = "0 ≤ t ≤ 1")]
            let g = (t.sqrt() * 255.0) as u8;
            Color32::from_rgb(g / 3, g, g / 3)
        })
        .collect();
    egui::ColorImage::new([columns, WAVEFORM_ROWS], pixels)
}

/// What the panel draws a scope from, remade when the image changes.
#[derive(Default)]
pub struct ScopeView {
    /// The scope shown.
    pub scope: Scope,
    made_for: Option<(Scope, u64)>,
    histogram: Option<Box<[[u32; 256]; 4]>>,
    waveform: Option<egui::TextureHandle>,
}

impl std::fmt::Debug for ScopeView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ScopeView")
            .field("scope", &self.scope)
            .finish_non_exhaustive()
    }
}

impl ScopeView {
    /// The histogram last drawn, if any (tests).
    pub fn drawn_histogram(&self) -> Option<&[[u32; 256]; 4]> {
        self.histogram.as_deref()
    }

    /// The choice of scope and the scope of `image` (`frame` changes with every new image),
    /// `width` points wide.
    pub fn show(&mut self, ui: &mut Ui, image: Option<&PreviewImage>, frame: u64, width: f32) {
        egui::ComboBox::from_label("scope")
            .selected_text(self.scope.label())
            .show_ui(ui, |ui| {
                for s in Scope::ALL {
                    ui.selectable_value(&mut self.scope, s, s.label());
                }
            })
            .response
            .on_hover_text("a scope of the previewed image's displayed values");
        let Some(image) = image else {
            return;
        };
        if self.made_for != Some((self.scope, frame)) {
            self.made_for = Some((self.scope, frame));
            match self.scope {
                Scope::Off => {}
                Scope::Histogram => self.histogram = Some(Box::new(histogram(image))),
                Scope::Waveform => {
                    let columns = (image.width as usize).min(256);
                    let img = waveform_image(&waveform(image, columns), columns);
                    let options = egui::TextureOptions::LINEAR;
                    match &mut self.waveform {
                        Some(t) => t.set(img, options),
                        None => {
                            self.waveform = Some(ui.ctx().load_texture("waveform", img, options));
                        }
                    }
                }
            }
        }
        let size = egui::vec2(width, 96.0);
        match self.scope {
            Scope::Off => {}
            Scope::Histogram => {
                if let Some(h) = &self.histogram {
                    draw_histogram(ui, h, size);
                }
            }
            Scope::Waveform => {
                if let Some(t) = &self.waveform {
                    ui.add(egui::Image::new((t.id(), size)))
                        .on_hover_text("luma waveform: columns of the image left to right, value bottom (0) to top (255)");
                }
            }
        }
    }
}

/// The four histograms over one another, each scaled to its largest count between the
/// extremes (clipped pixels at 0 or 255 would flatten the rest; they are drawn to the top).
fn draw_histogram(ui: &mut Ui, h: &[[u32; 256]; 4], size: egui::Vec2) {
    let (response, painter) = ui.allocate_painter(size, egui::Sense::hover());
    let rect = response.rect;
    painter.rect_filled(rect, 2.0, Color32::from_gray(16));
    let colors = [
        Color32::from_rgb(230, 80, 80),
        Color32::from_rgb(80, 210, 80),
        Color32::from_rgb(90, 120, 240),
        Color32::from_gray(220),
    ];
    for (counts, color) in h.iter().zip(colors) {
        let max = counts[1..255].iter().copied().max().unwrap_or(0).max(1);
        #[expect(clippy::cast_precision_loss, reason = "display")]
        let points: Vec<egui::Pos2> = counts
            .iter()
            .enumerate()
            .map(|(v, &n)| {
                let x = rect.left() + rect.width() * v as f32 / 255.0;
                let t = (n as f32 / max as f32).min(1.0);
                egui::pos2(x, rect.bottom() - t * rect.height())
            })
            .collect();
        painter.add(Shape::line(points, Stroke::new(1.0, color)));
    }
    response.on_hover_text("histogram of the displayed values: red, green, blue and luma (white)");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, pixels: &[[u8; 4]]) -> PreviewImage {
        PreviewImage {
            port: "n.color".into(),
            width,
            height: u32::try_from(pixels.len()).unwrap() / width,
            rgba: pixels.concat(),
        }
    }

    #[test]
    fn histogram_counts_each_channel_and_luma() {
        let img = image(
            2,
            &[
                [255, 0, 0, 255],
                [0, 0, 255, 255],
                [10, 10, 10, 255],
                [255, 255, 255, 255],
            ],
        );
        let h = histogram(&img);
        assert_eq!(h[0][255], 2);
        assert_eq!(h[0][0], 1);
        assert_eq!(h[2][255], 2);
        assert_eq!(h[1][10], 1);
        // Luma: red 54, blue 18, grey 10, white 255.
        assert_eq!([h[3][54], h[3][18], h[3][10], h[3][255]], [1, 1, 1, 1]);
        for c in h {
            assert_eq!(c.iter().sum::<u32>(), 4);
        }
    }

    #[test]
    fn waveform_puts_each_pixel_in_its_column_and_value() {
        // 4×2: a black left half, a white right half, one grey pixel.
        let b = [0, 0, 0, 255];
        let w = [255, 255, 255, 255];
        let g = [128, 128, 128, 255];
        let img = image(4, &[b, b, w, w, b, g, w, w]);
        let wf = waveform(&img, 2);
        let at = |row: usize, col: usize| wf[row * 2 + col];
        assert_eq!(
            at(WAVEFORM_ROWS - 1, 0),
            3,
            "black, bottom row, left column"
        );
        assert_eq!(at(0, 1), 4, "white, top row, right column");
        assert_eq!(at(WAVEFORM_ROWS - 1 - 64, 0), 1, "grey, middle row");
        assert_eq!(wf.iter().sum::<u32>(), 8);
    }
}
