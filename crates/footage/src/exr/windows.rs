//! Data windows: the display window, the source's data window, or the bounding box of
//! the pixels that are not empty (an auto-crop).

use super::assemble::ImageIn;
use super::{Source, Window};

/// Which data window to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowChoice {
    /// The display window: every pixel.
    Display,
    /// The source's data window, as read.
    Source,
    /// The bounding box of the pixels that are not zero in every channel written.
    Auto,
}

impl WindowChoice {
    /// `display`, `source` or `auto`.
    pub fn named(name: &str) -> Option<Self> {
        Some(match name {
            "display" => Self::Display,
            "source" => Self::Source,
            "auto" => Self::Auto,
            _ => return None,
        })
    }
}

/// Whether pixel `i` is zero in every component written.
fn is_empty(image: &ImageIn<'_>, components: &[usize], i: usize) -> bool {
    let p = &image.values[i * image.components..(i + 1) * image.components];
    components.iter().all(|&c| p[c] == 0.0)
}

/// The layer's data window under `choice`.
pub(super) fn window_of(
    image: &ImageIn<'_>,
    components: &[usize],
    display: Window,
    source: Option<&Source>,
    choice: WindowChoice,
    notes: &mut Vec<String>,
) -> Window {
    let one_pixel = Window::at(display.min, [1, 1]);
    match choice {
        WindowChoice::Display => display,
        WindowChoice::Source => {
            let Some(s) = source else {
                notes.push(format!(
                    "input {:?}: data window `source`, but it was not read from a file of \
                     this frame: the display window is written",
                    image.port
                ));
                return display;
            };
            let data = s.part.data_window;
            let window = match intersect(data, display) {
                None => {
                    notes.push(format!(
                        "input {:?}: the data window {data} of {} lies outside the display \
                         window {display}: one empty pixel is written",
                        image.port,
                        s.path.display()
                    ));
                    one_pixel
                }
                Some(window) if window != data => {
                    notes.push(format!(
                        "input {:?}: the data window {data} of {} reaches outside the display \
                         window: its overscan was cropped when read; {window} is written",
                        image.port,
                        s.path.display()
                    ));
                    window
                }
                Some(window) => window,
            };
            let outside = count_outside(image, components, display, window);
            if outside > 0 {
                notes.push(format!(
                    "input {:?}: {outside} pixels outside the data window {window} are not \
                     empty: they are not written",
                    image.port
                ));
            }
            window
        }
        WindowChoice::Auto => bounding_box(image, components, display).unwrap_or_else(|| {
            notes.push(format!(
                "input {:?} is empty: one empty pixel is written",
                image.port
            ));
            one_pixel
        }),
    }
}

fn intersect(a: Window, b: Window) -> Option<Window> {
    let min = [a.min[0].max(b.min[0]), a.min[1].max(b.min[1])];
    let max = [a.max[0].min(b.max[0]), a.max[1].min(b.max[1])];
    (min[0] <= max[0] && min[1] <= max[1]).then_some(Window { min, max })
}

pub(super) fn union(a: Window, b: Window) -> Window {
    Window {
        min: [a.min[0].min(b.min[0]), a.min[1].min(b.min[1])],
        max: [a.max[0].max(b.max[0]), a.max[1].max(b.max[1])],
    }
}

/// The display-window pixel index of absolute position (x, y).
pub(super) fn index(display: Window, x: i32, y: i32) -> usize {
    let dx = usize::try_from(i64::from(x) - i64::from(display.min[0])).unwrap_or(0);
    let dy = usize::try_from(i64::from(y) - i64::from(display.min[1])).unwrap_or(0);
    dy * display.width() + dx
}

/// Pixels outside `window` that are not empty.
fn count_outside(
    image: &ImageIn<'_>,
    components: &[usize],
    display: Window,
    window: Window,
) -> usize {
    let mut n = 0;
    for y in display.min[1]..=display.max[1] {
        for x in display.min[0]..=display.max[0] {
            let inside = x >= window.min[0]
                && x <= window.max[0]
                && y >= window.min[1]
                && y <= window.max[1];
            if !inside && !is_empty(image, components, index(display, x, y)) {
                n += 1;
            }
        }
    }
    n
}

/// The bounding box of the pixels that are not empty, if any.
fn bounding_box(image: &ImageIn<'_>, components: &[usize], display: Window) -> Option<Window> {
    let mut found: Option<Window> = None;
    for y in display.min[1]..=display.max[1] {
        for x in display.min[0]..=display.max[0] {
            if !is_empty(image, components, index(display, x, y)) {
                let here = Window {
                    min: [x, y],
                    max: [x, y],
                };
                found = Some(found.map_or(here, |f| union(f, here)));
            }
        }
    }
    found
}
