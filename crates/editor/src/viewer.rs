//! The preview's image viewer: zoom and pan down to single pixels, a readout of the linear
//! values under the pointer, display-only exposure, false colour and an OpenColorIO display
//! transform ([`crate::display`]) for HDR ports, and an A/B compare of the live image with a
//! pinned snapshot (a wipe, or side by side).
//!
//! Nothing here changes the graph: exposure, false colour and the display transform apply
//! to what is shown only, and the readout reads the port's linear values as the GPU wrote
//! them.

use egui::{Color32, Pos2, Rect, Sense, TextureHandle, TextureOptions, Ui, Vec2, pos2, vec2};
use lumagraph_graph::PortType;
use lumagraph_render::cpu::Image;

/// How the live image and the pinned snapshot are shown together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Compare {
    /// The live image alone.
    #[default]
    Off,
    /// The live image left of a vertical line, the snapshot right of it.
    Wipe,
    /// Both, side by side with the same zoom and pan: live left, snapshot right.
    SideBySide,
}

/// An image kept to compare against.
#[derive(Debug)]
pub struct Snapshot {
    /// The port it shows.
    pub port: String,
    /// Its linear values.
    pub image: Image,
    /// Its port type.
    pub ty: PortType,
    /// Samples per pixel it had, when progressive.
    pub spp: Option<u64>,
}

/// The values under the pointer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readout {
    /// Pixel column, from the left.
    pub x: u32,
    /// Pixel row, from the top.
    pub y: u32,
    /// The port's value there (linear for HDR ports, display-encoded for LDR ones).
    pub rgba: [f32; 4],
    /// Rec. 709 luminance of `rgba`.
    pub luminance: f32,
    /// Whether it was read from the snapshot (right of the wipe or the right half).
    pub from_snapshot: bool,
}

/// Rec. 709 luminance.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// The value of pixel (`x`, `y`).
pub fn pixel(image: &Image, x: u32, y: u32) -> Option<[f32; 4]> {
    (x < image.width && y < image.height)
        .then(|| image.pixels[(y as usize) * (image.width as usize) + x as usize])
}

/// The false-colour ramp: exposure in stops around middle grey (0.18) from −6 (dark blue)
/// through 0 (grey-green) to +6 and beyond (white), so clipped highlights and crushed
/// shadows stand out.
pub fn false_color(lum: f32) -> [u8; 3] {
    const STOPS: [(f32, [u8; 3]); 7] = [
        (-6.0, [20, 20, 90]),
        (-4.0, [40, 80, 220]),
        (-2.0, [40, 170, 200]),
        (0.0, [120, 160, 120]),
        (2.0, [230, 200, 40]),
        (4.0, [230, 80, 30]),
        (6.0, [255, 255, 255]),
    ];
    let ev = if lum > 0.0 {
        (lum / 0.18).log2()
    } else {
        -100.0
    };
    let i = STOPS.iter().position(|s| ev < s.0).unwrap_or(STOPS.len());
    if i == 0 {
        return STOPS[0].1;
    }
    if i == STOPS.len() {
        return STOPS[i - 1].1;
    }
    let (a, b) = (STOPS[i - 1], STOPS[i]);
    let t = (ev - a.0) / (b.0 - a.0);
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "0..=255"
    )]
    std::array::from_fn(|c| {
        (f32::from(a.1[c]) + t * (f32::from(b.1[c]) - f32::from(a.1[c]))).round() as u8
    })
}

/// What the viewer shows for `image`: as an Output node writes it to a PNG, after scaling
/// HDR values by 2^`exposure`, or the false-colour ramp of their luminance.
pub fn display_rgba(image: &Image, ty: PortType, exposure: f32, false_colour: bool) -> Vec<u8> {
    let hdr = ty != PortType::LdrColor;
    if !hdr || (exposure == 0.0 && !false_colour) {
        return lumagraph_render::image_io::to_rgba8(image, hdr);
    }
    let gain = exposure.exp2();
    if false_colour {
        return image
            .pixels
            .iter()
            .flat_map(|p| {
                let [r, g, b] = false_color(gain * luminance([p[0], p[1], p[2]]));
                [r, g, b, 255]
            })
            .collect();
    }
    let scaled = Image {
        width: image.width,
        height: image.height,
        pixels: image
            .pixels
            .iter()
            .map(|p| [p[0] * gain, p[1] * gain, p[2] * gain, p[3]])
            .collect(),
    };
    lumagraph_render::image_io::to_rgba8(&scaled, true)
}

/// A texture made from `image` as [`display_rgba`] shows it.
fn upload(
    ctx: &egui::Context,
    slot: &mut Option<TextureHandle>,
    name: &str,
    image: &Image,
    rgba: &[u8],
    options: TextureOptions,
) {
    let color = egui::ColorImage::from_rgba_unmultiplied(
        [image.width as usize, image.height as usize],
        rgba,
    );
    match slot {
        Some(t) => t.set(color, options),
        None => *slot = Some(ctx.load_texture(name, color, options)),
    }
}

/// A camera move asked for on the image in camera mode ([`ImageView::camera_mode`]): drag
/// orbits, Shift-drag or middle-drag pans, the wheel dollies.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraGesture {
    /// Degrees about the up axis (positive: the camera goes right around the target).
    pub yaw: f32,
    /// Degrees about the camera's right axis (positive: the camera goes up).
    pub pitch: f32,
    /// Pan to the right and up, in fractions of the distance to the target.
    pub pan: [f32; 2],
    /// Distance to the target multiplied by this (1: no dolly).
    pub dolly: f32,
}

impl CameraGesture {
    /// Degrees of orbit per point dragged.
    pub const DEGREES_PER_POINT: f32 = 0.3;

    /// Whether it moves nothing.
    pub fn is_none(&self) -> bool {
        self.yaw == 0.0 && self.pitch == 0.0 && self.pan == [0.0; 2] && self.dolly == 1.0
    }
}

/// The viewer's state.
#[derive(Default)]
pub struct ImageView {
    /// Drag, Shift-drag and the wheel move the scene's camera instead of the view
    /// ([`ImageView::show`] returns the move).
    pub camera_mode: bool,
    /// Screen points per image pixel; `None`: the image fits the panel's width.
    pub zoom: Option<f32>,
    /// The image point (in pixels) at the middle of the view, when zoomed.
    pub center: Vec2,
    /// Display-only exposure for HDR ports, in stops.
    pub exposure: f32,
    /// Show HDR ports in false colour (see [`false_color`]); over the display transform.
    pub false_colour: bool,
    /// The OpenColorIO display, view and look HDR ports are shown through (off by default).
    pub display: crate::display::DisplayTransform,
    /// How the snapshot is shown.
    pub compare: Compare,
    /// Where the wipe's line is, from 0 (left edge) to 1.
    pub wipe: f32,
    /// The snapshot compared against.
    pub pinned: Option<Snapshot>,
    /// The values under the pointer on the last frame.
    pub hover: Option<Readout>,
    /// Where the image was drawn on the last frame (the left half side by side).
    pub rect: Option<Rect>,
    live: Option<TextureHandle>,
    live_key: Option<(u64, u32, bool, bool, u64)>,
    snap: Option<TextureHandle>,
    snap_key: Option<(u32, bool, bool, u64)>,
}

impl std::fmt::Debug for ImageView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImageView")
            .field("zoom", &self.zoom)
            .field("compare", &self.compare)
            .field("hover", &self.hover)
            .finish_non_exhaustive()
    }
}

impl ImageView {
    /// A viewer fitting the image, the wipe in the middle.
    pub fn new() -> Self {
        Self {
            wipe: 0.5,
            ..Self::default()
        }
    }

    /// Keeps `image` (of port `port`) to compare the live image against.
    pub fn pin(&mut self, port: &str, image: Image, ty: PortType, spp: Option<u64>) {
        self.pinned = Some(Snapshot {
            port: port.to_owned(),
            image,
            ty,
            spp,
        });
        self.snap_key = None;
        if self.compare == Compare::Off {
            self.compare = Compare::Wipe;
        }
    }

    /// What the viewer shows of `image` (of type `ty`): through the display transform when
    /// one is chosen, the port is not display-encoded and false colour is off; else as
    /// [`display_rgba`] shows it (linear colour converted to Rec. 709 first in a graph with
    /// another working space).
    pub fn shown_rgba(&mut self, image: &Image, ty: PortType) -> Vec<u8> {
        if ty != PortType::LdrColor
            && !self.false_colour
            && let Some(p) = self.display.processor()
        {
            let t = std::time::Instant::now();
            let rgba = crate::display::encode(image, self.exposure, p);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            self.display.last_cost = Some((ms, image.width, image.height));
            return rgba;
        }
        if ty != PortType::LdrColor
            && self.display.working_space != lumagraph_graph::WorkingSpace::Rec709
        {
            // Shown sRGB-encoded, which is Rec. 709's encoding: another working space's
            // colour is converted first (false colour reads luminance in Rec. 709 too).
            let mut rec709 = image.clone();
            if lumagraph_render::nodes::ocio::working_to_rec709(
                self.display.working_space,
                &mut rec709,
            )
            .is_ok()
            {
                return display_rgba(&rec709, ty, self.exposure, self.false_colour);
            }
        }
        display_rgba(image, ty, self.exposure, self.false_colour)
    }

    /// The screen rectangle of the whole image in a view of `view` (fit: as large as fits,
    /// at most twice its size, centred; or zoomed).
    fn image_rect(&self, view: Rect, size: Vec2) -> Rect {
        match self.zoom {
            None => {
                let z = (view.width() / size.x.max(1.0))
                    .min(view.height() / size.y.max(1.0))
                    .min(2.0);
                Rect::from_center_size(view.center(), size * z)
            }
            Some(z) => Rect::from_min_size(view.center() - self.center * z, size * z),
        }
    }

    /// The pixel under screen point `p` for an image of `size` drawn in `rect`.
    fn pixel_at(rect: Rect, size: Vec2, p: Pos2) -> Option<(u32, u32)> {
        let u = (p - rect.min) / rect.size() * size;
        #[expect(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "checked"
        )]
        (u.x >= 0.0 && u.y >= 0.0 && u.x < size.x && u.y < size.y)
            .then_some((u.x as u32, u.y as u32))
    }

    /// Zooms by `factor` keeping the image point under `at` in place.
    fn zoom_about(&mut self, view: Rect, size: Vec2, at: Pos2, factor: f32) {
        let rect = self.image_rect(view, size);
        let z = rect.width() / size.x.max(1.0);
        let under = (at - rect.min) / z;
        let new_z = (z * factor).clamp(0.05, 64.0);
        self.zoom = Some(new_z);
        self.center = under - (at - view.center()) / new_z;
    }

    /// Wheel zooms about the pointer, drag pans.
    fn pan_and_zoom(&mut self, ui: &Ui, response: &egui::Response, view: Rect, size: Vec2) {
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0
                && let Some(p) = response.hover_pos()
            {
                self.zoom_about(view, size, p, (scroll / 200.0).exp());
            }
        }
        if response.dragged() {
            let delta = response.drag_delta();
            if self.zoom.is_none() {
                let rect = self.image_rect(view, size);
                self.zoom = Some(rect.width() / size.x.max(1.0));
                self.center = (view.center() - rect.min) / self.zoom.unwrap_or(1.0);
            }
            if let Some(z) = self.zoom {
                self.center -= delta / z;
            }
        }
    }

    /// Draws the live image (`live`, its port type and a frame counter that changes with
    /// it) and, when comparing, the snapshot; handles zoom (wheel), pan (drag), fit
    /// (double-click) and the readout. `height` is the view's height. In camera mode, drag
    /// and wheel are returned as a camera move instead.
    pub fn show(
        &mut self,
        ui: &mut Ui,
        live: &Image,
        ty: PortType,
        frame: u64,
        height: f32,
    ) -> Option<CameraGesture> {
        let size = vec2(live.width as f32, live.height as f32);
        let (view, response) =
            ui.allocate_exact_size(vec2(ui.available_width(), height), Sense::click_and_drag());
        let options = if self.zoom.is_some_and(|z| z >= 2.0) {
            TextureOptions::NEAREST
        } else {
            TextureOptions::LINEAR
        };
        let nearest = options == TextureOptions::NEAREST;
        let shown = self.display.key();
        let key = (
            frame,
            self.exposure.to_bits(),
            self.false_colour,
            nearest,
            shown,
        );
        if self.live_key != Some(key) || self.live.is_none() {
            let rgba = self.shown_rgba(live, ty);
            upload(
                ui.ctx(),
                &mut self.live,
                "viewer-live",
                live,
                &rgba,
                options,
            );
            self.live_key = Some(key);
        }
        if let Some(s) = self.pinned.take() {
            let key = (self.exposure.to_bits(), self.false_colour, nearest, shown);
            if self.snap_key != Some(key) || self.snap.is_none() {
                let rgba = self.shown_rgba(&s.image, s.ty);
                upload(
                    ui.ctx(),
                    &mut self.snap,
                    "viewer-snapshot",
                    &s.image,
                    &rgba,
                    options,
                );
                self.snap_key = Some(key);
            }
            self.pinned = Some(s);
        }

        // Input.
        if response.double_clicked() {
            self.zoom = None;
        }
        let gesture = if self.camera_mode {
            camera_gesture(ui, &response, view)
        } else {
            self.pan_and_zoom(ui, &response, view, size);
            None
        };

        // Drawing.
        let painter = ui.painter_at(view);
        painter.rect_filled(view, 0.0, Color32::from_gray(16));
        let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
        let side = self.compare == Compare::SideBySide && self.pinned.is_some();
        let halves = if side {
            let (l, r) = view.split_left_right_at_fraction(0.5);
            [l, r]
        } else {
            [view, view]
        };
        let rect = self.image_rect(halves[0], size);
        self.rect = Some(rect);
        if let Some(t) = &self.live {
            ui.painter_at(halves[0])
                .image(t.id(), rect, uv, Color32::WHITE);
        }
        let mut wipe_x = None;
        if let (Some(t), Some(_)) = (&self.snap, &self.pinned) {
            match self.compare {
                Compare::Off => {}
                Compare::Wipe => {
                    let x = view.left() + self.wipe * view.width();
                    let right = Rect::from_min_max(pos2(x, view.top()), view.max);
                    ui.painter_at(right).image(t.id(), rect, uv, Color32::WHITE);
                    painter.vline(x, view.y_range(), (1.0, Color32::WHITE));
                    wipe_x = Some(x);
                }
                Compare::SideBySide => {
                    let r2 = self.image_rect(halves[1], size);
                    ui.painter_at(halves[1])
                        .image(t.id(), r2, uv, Color32::WHITE);
                    painter.vline(halves[1].left(), view.y_range(), (1.0, Color32::GRAY));
                }
            }
        }

        // Readout.
        self.hover = response.hover_pos().and_then(|p| {
            let (in_snapshot, rect) = if side && halves[1].contains(p) {
                (true, self.image_rect(halves[1], size))
            } else {
                (wipe_x.is_some_and(|x| p.x >= x), rect)
            };
            let (x, y) = Self::pixel_at(rect, size, p)?;
            let image = match (&self.pinned, in_snapshot) {
                (Some(s), true) => &s.image,
                _ => live,
            };
            let rgba = pixel(image, x, y)?;
            Some(Readout {
                x,
                y,
                rgba,
                luminance: luminance([rgba[0], rgba[1], rgba[2]]),
                from_snapshot: in_snapshot && self.pinned.is_some(),
            })
        });
        gesture
    }
}

/// The camera move of this frame's drag and wheel on `view` (see [`CameraGesture`]).
fn camera_gesture(ui: &Ui, response: &egui::Response, view: Rect) -> Option<CameraGesture> {
    let mut g = CameraGesture {
        dolly: 1.0,
        ..CameraGesture::default()
    };
    let (shift, middle) = ui.input(|i| {
        (
            i.modifiers.shift,
            i.pointer.button_down(egui::PointerButton::Middle),
        )
    });
    if response.dragged() {
        let d = response.drag_delta();
        if shift || middle || response.dragged_by(egui::PointerButton::Middle) {
            // The scene follows the pointer: the camera moves the other way.
            g.pan = [-d.x / view.width().max(1.0), d.y / view.height().max(1.0)];
        } else {
            g.yaw = -d.x * CameraGesture::DEGREES_PER_POINT;
            g.pitch = d.y * CameraGesture::DEGREES_PER_POINT;
        }
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            g.dolly = (-scroll / 200.0).exp();
        }
    }
    (!g.is_none()).then_some(g)
}
