//! Error against time, live: while the preview accumulates, every `Difference` node's
//! relMSE (and RMSE) against its reference at each frame, with the samples per pixel and
//! the wall time of the frames so far, drawn log-log beside the preview as `lumagraph
//! converge` draws it, and written as the same CSV.
//!
//! A point is recorded for each frame that added samples; a restarted accumulation (a new
//! executor, an edit upstream of it, a moved camera) starts a new curve. An edit that
//! re-runs only what is downstream (a denoiser's param) leaves the samples as they were:
//! the last points then take the new values, so the curve's end is always what the
//! preview shows.

use std::fmt::Write as _;
use std::time::Duration;

use egui::{Color32, Pos2, Rect, Sense, Stroke, Ui, pos2, vec2};

/// One node's error at one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorPoint {
    /// The `Difference` node.
    pub node: String,
    /// Samples per pixel accumulated.
    pub spp: u64,
    /// Wall seconds of the frames of this accumulation so far (record, submit, wait).
    pub seconds: f64,
    /// Its `relmse` measurement.
    pub relmse: f64,
    /// Its `rmse` measurement, where it has one.
    pub rmse: Option<f64>,
}

/// The curves of the current accumulation.
#[derive(Clone, Debug, Default)]
pub struct ErrorCurve {
    /// Every point, in the order recorded.
    pub points: Vec<ErrorPoint>,
    /// Wall seconds of the frames so far.
    seconds: f64,
    /// The samples per pixel of the last point.
    last_spp: Option<u64>,
    /// Draw against samples per pixel rather than seconds.
    pub by_samples: bool,
}

/// The horizontal axis.
fn x_of(p: &ErrorPoint, by_samples: bool) -> f64 {
    if by_samples {
        #[expect(clippy::cast_precision_loss, reason = "plot coordinates")]
        let spp = p.spp as f64;
        spp
    } else {
        p.seconds
    }
}

impl ErrorCurve {
    /// Forgets every point (the accumulation restarted, or the graph changed).
    pub fn clear(&mut self) {
        self.points.clear();
        self.seconds = 0.0;
        self.last_spp = None;
    }

    /// Records the frame that took `wall` and left `spp` samples per pixel, with what the
    /// nodes measured on it (`(node, name, value)`); nothing without a sample count or a
    /// `relmse`.
    pub fn record<'a>(
        &mut self,
        spp: Option<u64>,
        wall: Duration,
        measurements: impl IntoIterator<Item = (&'a str, &'a str, f64)>,
    ) {
        let Some(spp) = spp else {
            self.clear();
            return;
        };
        if self.last_spp.is_some_and(|last| spp < last) {
            self.clear();
        }
        let mut by_node: Vec<(&str, Option<f64>, Option<f64>)> = Vec::new();
        for (node, name, value) in measurements {
            let i = by_node
                .iter()
                .position(|(n, ..)| *n == node)
                .unwrap_or_else(|| {
                    by_node.push((node, None, None));
                    by_node.len() - 1
                });
            match name {
                "relmse" => by_node[i].1 = Some(value),
                "rmse" => by_node[i].2 = Some(value),
                _ => {}
            }
        }
        let same_frame = self.last_spp == Some(spp);
        if !same_frame {
            self.seconds += wall.as_secs_f64();
        }
        for (node, relmse, rmse) in by_node {
            let Some(relmse) = relmse else { continue };
            let point = ErrorPoint {
                node: node.to_owned(),
                spp,
                seconds: self.seconds,
                relmse,
                rmse,
            };
            let last = self.points.iter_mut().rev().find(|p| p.node == node);
            match last {
                Some(last) if same_frame && last.spp == spp => *last = point,
                _ => self.points.push(point),
            }
        }
        self.last_spp = Some(spp);
    }

    /// The nodes with points, in the order first seen.
    pub fn nodes(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for p in &self.points {
            if !out.contains(&p.node.as_str()) {
                out.push(&p.node);
            }
        }
        out
    }

    /// The points as `lumagraph converge` writes `converge.csv` (`ssim` and `gpu_ms` are
    /// left empty: the preview does not measure them).
    pub fn csv(&self) -> String {
        let mut s = String::from("output,spp,seconds,rmse,relmse,ssim,gpu_ms\n");
        for p in &self.points {
            let _ = writeln!(
                s,
                "{},{},{:.6},{},{:.6e},,",
                p.node,
                p.spp,
                p.seconds,
                p.rmse.map_or_else(String::new, |r| format!("{r:.6e}")),
                p.relmse
            );
        }
        s
    }

    /// Draws the curves log-log in a plot `width` points wide, with a legend and the axis
    /// range; returns the plot's rectangle.
    pub fn show(&mut self, ui: &mut Ui, width: f32) -> Rect {
        ui.horizontal(|ui| {
            ui.label("error against");
            ui.selectable_value(&mut self.by_samples, false, "time");
            ui.selectable_value(&mut self.by_samples, true, "samples");
        });
        let height = (width * 0.55).clamp(80.0, 220.0);
        let (rect, _) = ui.allocate_exact_size(vec2(width, height), Sense::hover());
        let painter = ui.painter_at(rect);
        let visuals = ui.visuals();
        painter.rect_filled(rect, 2.0, visuals.extreme_bg_color);
        let pts: Vec<(f64, f64)> = self
            .points
            .iter()
            .map(|p| (x_of(p, self.by_samples), p.relmse))
            .filter(|(x, y)| *x > 0.0 && *y > 0.0)
            .collect();
        let text = visuals.text_color();
        if pts.is_empty() {
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "no error yet: a Difference node measures it",
                egui::FontId::proportional(11.0),
                visuals.weak_text_color(),
            );
            return rect;
        }
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (x, y) in &pts {
            x0 = x0.min(*x);
            x1 = x1.max(*x);
            y0 = y0.min(*y);
            y1 = y1.max(*y);
        }
        // A decade at least on each axis, so one point is not a degenerate range.
        let widen = |a: f64, b: f64| {
            let (la, lb) = (a.log10(), b.log10());
            let mid = 0.5 * (la + lb);
            let half = (0.5 * (lb - la)).max(0.5) * 1.1;
            (mid - half, mid + half)
        };
        let ((lx0, lx1), (ly0, ly1)) = (widen(x0, x1), widen(y0, y1));
        let inner = rect.shrink2(vec2(6.0, 14.0));
        #[expect(clippy::cast_possible_truncation, reason = "screen coordinates")]
        let to_screen = |x: f64, y: f64| -> Pos2 {
            let fx = (x.log10() - lx0) / (lx1 - lx0);
            let fy = (y.log10() - ly0) / (ly1 - ly0);
            pos2(
                inner.left() + fx as f32 * inner.width(),
                inner.bottom() - fy as f32 * inner.height(),
            )
        };
        for (i, node) in self.nodes().iter().enumerate() {
            let color = COLORS[i % COLORS.len()];
            let line: Vec<Pos2> = self
                .points
                .iter()
                .filter(|p| p.node == *node)
                .map(|p| (x_of(p, self.by_samples), p.relmse))
                .filter(|(x, y)| *x > 0.0 && *y > 0.0)
                .map(|(x, y)| to_screen(x, y))
                .collect();
            painter.add(egui::Shape::line(line.clone(), Stroke::new(1.5, color)));
            for p in &line {
                painter.circle_filled(*p, 2.0, color);
            }
            #[expect(clippy::cast_precision_loss, reason = "legend rows")]
            let row = i as f32;
            painter.text(
                rect.right_top() + vec2(-4.0, 2.0 + 12.0 * row),
                egui::Align2::RIGHT_TOP,
                format!("{node} relMSE"),
                egui::FontId::proportional(10.0),
                color,
            );
        }
        let unit = if self.by_samples { "spp" } else { "s" };
        painter.text(
            rect.left_bottom() + vec2(4.0, -2.0),
            egui::Align2::LEFT_BOTTOM,
            format!("{x0:.3} – {x1:.3} {unit} (log);  relMSE {y0:.1e} – {y1:.1e} (log)"),
            egui::FontId::proportional(10.0),
            text,
        );
        rect
    }
}

const COLORS: [Color32; 4] = [
    Color32::from_rgb(31, 119, 180),
    Color32::from_rgb(214, 39, 40),
    Color32::from_rgb(44, 160, 44),
    Color32::from_rgb(148, 103, 189),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn points_follow_frames_restarts_and_reruns() {
        let mut c = ErrorCurve::default();
        c.record(Some(1), ms(100), [("d", "relmse", 0.5), ("d", "rmse", 0.2)]);
        c.record(
            Some(2),
            ms(100),
            [("d", "relmse", 0.25), ("e", "relmse", 0.1)],
        );
        assert_eq!(c.points.len(), 3);
        assert_eq!(c.nodes(), ["d", "e"]);
        assert!((c.points[1].seconds - 0.2).abs() < 1e-9);
        assert_eq!(c.points[0].rmse, Some(0.2));
        // A re-run at the same samples (a post edit): the last point takes the new value.
        c.record(Some(2), ms(5), [("d", "relmse", 0.3)]);
        assert_eq!(c.points.len(), 3);
        assert_eq!(c.points[1].relmse, 0.3);
        assert!((c.points[1].seconds - 0.2).abs() < 1e-9);
        // A restart: a new curve.
        c.record(Some(1), ms(100), [("d", "relmse", 0.6)]);
        assert_eq!(c.points.len(), 1);
        assert!((c.points[0].seconds - 0.1).abs() < 1e-9);
        let csv = c.csv();
        assert_eq!(
            csv,
            "output,spp,seconds,rmse,relmse,ssim,gpu_ms\nd,1,0.100000,,6.000000e-1,,\n"
        );
        // Without a sample count there is no curve.
        c.record(None, ms(1), [("d", "relmse", 0.1)]);
        assert!(c.points.is_empty());
    }
}
