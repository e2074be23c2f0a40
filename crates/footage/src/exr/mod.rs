//! OpenEXR files as compositors read them.
//!
//! [`inspect`] reads a file's headers: its parts (name, view, kind, windows, compression,
//! levels, colour primaries, every attribute) and their channels. [`Layer`]s group a
//! part's channels by name as Nuke and Blender do (`depth.Z`, `forward.u`/`forward.v`,
//! `ViewLayer.Combined.R`…); [`Selection`] finds one by the names users bring (see
//! [`layers`]). [`read_layer`] reads a layer into the part's **display window**: the data
//! window's pixels placed at its offset, transparent black elsewhere, overscan outside the
//! display window cropped (with a note), colour converted from the file's primaries to
//! Rec. 709, and luminance/chroma images reconstructed as OpenEXR's `RgbaInputFile` does.
//!
//! What is not read is said: deep parts are refused naming the part, and everything a
//! file holds is listed by [`inspect`] (`lumagraph info`).
//!
//! Writing: [`assemble`] makes the file to write of display-window images, each with the
//! [`Source`] it was read from (names, windows, sample types, header attributes that stay
//! true, and a note naming what does not), and [`encode`] writes it, one part or several.

mod assemble;
mod layers;
mod read;
mod source;
mod windows;
mod write;

use std::fmt;
use std::path::{Path, PathBuf};

use exr::meta::BlockDescription;
use exr::meta::attribute::{AttributeValue, LevelMode, SampleType};
use exr::meta::header::Header;

pub use assemble::{ImageIn, PartsChoice, Settings, TypeChoice, assemble};
pub use layers::{Layer, LayerKind, Selection};
pub use read::{LayerImage, Primaries, RawChannel, Want, read_channels, read_layer, read_layer_in};
pub use source::{Carried, Source};
pub use windows::WindowChoice;
pub use write::{
    Compression, FileAttributes, FileOut, LayerOut, PartAttributes, PartOut, encode, encode_layers,
    f32_to_half, half_to_f32,
};

use crate::color::Chromaticities;

/// The most pixels a part may have (16384 × 16384): readers allocate a part whole from
/// its header's size, so a corrupt size would otherwise ask for terabytes.
pub const MAX_PIXELS: u64 = 1 << 28;

/// An error reading a footage file: the file and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct Error {
    /// The file.
    pub path: PathBuf,
    /// What is wrong, in words.
    pub message: String,
}

impl Error {
    pub(crate) fn new(path: &Path, message: impl fmt::Display) -> Self {
        Self {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }
}

/// A result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// A pixel rectangle, both corners inclusive, as EXR stores its windows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    /// Left, top corner.
    pub min: [i32; 2],
    /// Right, bottom corner (inclusive).
    pub max: [i32; 2],
}

impl Window {
    /// A window from its position and size.
    pub fn at(position: [i32; 2], size: [usize; 2]) -> Self {
        let end = |p: i32, s: usize| p.saturating_add(i32::try_from(s).unwrap_or(i32::MAX)) - 1;
        Self {
            min: position,
            max: [end(position[0], size[0]), end(position[1], size[1])],
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        usize::try_from(i64::from(self.max[0]) - i64::from(self.min[0]) + 1).unwrap_or(0)
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        usize::try_from(i64::from(self.max[1]) - i64::from(self.min[1]) + 1).unwrap_or(0)
    }

    /// Whether `other` lies wholly inside this window.
    pub fn contains(&self, other: &Self) -> bool {
        other.min[0] >= self.min[0]
            && other.min[1] >= self.min[1]
            && other.max[0] <= self.max[0]
            && other.max[1] <= self.max[1]
    }
}

impl fmt::Display for Window {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "({}, {})–({}, {}), {}×{}",
            self.min[0],
            self.min[1],
            self.max[0],
            self.max[1],
            self.width(),
            self.height()
        )
    }
}

/// How a part stores its pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartKind {
    /// Flat scan lines.
    ScanLines,
    /// Flat tiles (maybe with resolution levels).
    Tiles,
    /// Deep scan lines (any number of samples per pixel).
    DeepScanLines,
    /// Deep tiles.
    DeepTiles,
}

impl PartKind {
    /// The name EXR's `type` attribute gives it.
    pub fn name(self) -> &'static str {
        match self {
            Self::ScanLines => "scanlineimage",
            Self::Tiles => "tiledimage",
            Self::DeepScanLines => "deepscanline",
            Self::DeepTiles => "deeptile",
        }
    }

    /// Whether the part holds deep data.
    pub fn is_deep(self) -> bool {
        matches!(self, Self::DeepScanLines | Self::DeepTiles)
    }
}

/// The type of a channel's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleKind {
    /// 16-bit float.
    Half,
    /// 32-bit float.
    Float,
    /// 32-bit unsigned integer.
    Uint,
}

impl SampleKind {
    /// `half`, `float` or `uint`, as OpenEXR names them.
    pub fn name(self) -> &'static str {
        match self {
            Self::Half => "half",
            Self::Float => "float",
            Self::Uint => "uint",
        }
    }

    fn of(t: SampleType) -> Self {
        match t {
            SampleType::F16 => Self::Half,
            SampleType::F32 => Self::Float,
            SampleType::U32 => Self::Uint,
        }
    }
}

/// One channel of a part.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The full name, layer included (`forward.u`).
    pub name: String,
    /// The type of its samples.
    pub sample: SampleKind,
    /// One sample every `sampling[0]` pixels across and `sampling[1]` down.
    pub sampling: [usize; 2],
}

/// One part of a file (a single-part file has one).
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Its position in the file.
    pub index: usize,
    /// Its `name` attribute (multi-part files name every part).
    pub name: Option<String>,
    /// Its `view` attribute (stereo files: `left`, `right`).
    pub view: Option<String>,
    /// How it stores its pixels.
    pub kind: PartKind,
    /// Where its pixels are.
    pub data_window: Window,
    /// The frame they belong to: the image.
    pub display_window: Window,
    /// Its compression, as OpenEXR names it.
    pub compression: String,
    /// `single`, or the resolution levels of a tiled part (`mipmap`, `ripmap`).
    pub levels: &'static str,
    /// Its colour primaries, when it says.
    pub chromaticities: Option<Chromaticities>,
    /// The views of a single-part multi-view file (`multiView`), default view first.
    pub multi_view: Vec<String>,
    /// Its channels, as stored (sorted by name).
    pub channels: Vec<Channel>,
    /// Every other attribute, name and value in words.
    pub attributes: Vec<(String, String)>,
}

impl Part {
    /// The part's name, or `part N` for an unnamed one, for messages.
    pub fn label(&self) -> String {
        self.name
            .as_ref()
            .map_or_else(|| format!("part {}", self.index), |n| format!("part {n:?}"))
    }
}

/// What [`inspect`] finds in a file.
#[derive(Clone, Debug, PartialEq)]
pub struct Info {
    /// The file.
    pub path: PathBuf,
    /// Its parts, in file order.
    pub parts: Vec<Part>,
}

impl Info {
    /// Every layer of every part, in file order (see [`layers`]).
    pub fn layers(&self) -> Vec<Layer> {
        layers::of(self)
    }

    /// The default view: the first of a `multiView` attribute's views, else the first
    /// part's view, else none.
    pub fn default_view(&self) -> Option<&str> {
        let first = self.parts.first()?;
        first
            .multi_view
            .first()
            .or(first.view.as_ref())
            .map(String::as_str)
    }

    /// Every view the file holds, the default first.
    pub fn views(&self) -> Vec<String> {
        let mut views: Vec<String> = Vec::new();
        for part in &self.parts {
            for v in part.multi_view.iter().chain(part.view.iter()) {
                if !views.contains(v) {
                    views.push(v.clone());
                }
            }
        }
        views
    }
}

/// Reads a file's headers: every part and channel, windows, colour and attributes.
///
/// # Errors
/// A missing or unreadable file, one that is not EXR, a damaged header, or a part larger
/// than [`MAX_PIXELS`].
pub fn inspect(path: &Path) -> Result<Info> {
    let headers = headers(path)?;
    let parts = headers
        .iter()
        .enumerate()
        .map(|(index, h)| part_of(index, h))
        .collect::<Vec<_>>();
    for part in &parts {
        let pixels =
            (part.data_window.width() as u64).saturating_mul(part.data_window.height() as u64);
        let display = (part.display_window.width() as u64)
            .saturating_mul(part.display_window.height() as u64);
        if pixels > MAX_PIXELS || display > MAX_PIXELS {
            return Err(Error::new(
                path,
                format!(
                    "{} is larger than the {MAX_PIXELS} pixels (16384×16384) lumagraph reads \
                     (data window {}, display window {})",
                    part.label(),
                    part.data_window,
                    part.display_window
                ),
            ));
        }
    }
    Ok(Info {
        path: path.to_path_buf(),
        parts,
    })
}

/// The headers of a file: through the `exr` crate, or for files with subsampled channels
/// (which it refuses) through [`crate::subsampled`].
pub(crate) fn headers(path: &Path) -> Result<Vec<Header>> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => {}
        Ok(_) => {
            return Err(Error::new(
                path,
                "cannot open image: not a regular file (a folder, a device or a pipe)",
            ));
        }
        Err(e) => return Err(Error::new(path, format!("cannot open image: {e}"))),
    }
    match exr::meta::MetaData::read_from_file(path, false) {
        Ok(meta) => Ok(meta.headers.into_vec()),
        Err(e) if e.to_string().contains("subsampling") || e.to_string().contains("deep") => {
            crate::subsampled::read_headers(path)
                .map_err(|e| Error::new(path, format!("not a readable EXR file: {e}")))
        }
        Err(e) => Err(Error::new(path, format!("not a readable EXR file: {e}"))),
    }
}

fn part_of(index: usize, h: &Header) -> Part {
    let own = &h.own_attributes;
    let shared = &h.shared_attributes;
    let view = own.view_name.as_ref().map(ToString::to_string);
    let multi_view = own
        .multi_view_names
        .as_ref()
        .map(|v| v.iter().map(ToString::to_string).collect())
        .unwrap_or_default();
    let kind = match (&h.blocks, h.deep) {
        (BlockDescription::ScanLines, false) => PartKind::ScanLines,
        (BlockDescription::Tiles(_), false) => PartKind::Tiles,
        (BlockDescription::ScanLines, true) => PartKind::DeepScanLines,
        (BlockDescription::Tiles(_), true) => PartKind::DeepTiles,
    };
    let levels = match &h.blocks {
        BlockDescription::Tiles(t) => match t.level_mode {
            LevelMode::Singular => "single",
            LevelMode::MipMap => "mipmap",
            LevelMode::RipMap => "ripmap",
        },
        BlockDescription::ScanLines => "single",
    };
    let bounds = |b: exr::math::Vec2<i32>, s: exr::math::Vec2<usize>| {
        Window::at([b.x(), b.y()], [s.x(), s.y()])
    };
    let display = shared.display_window;
    let chromaticities = shared.chromaticities.map(|c| Chromaticities {
        red: [c.red.x(), c.red.y()],
        green: [c.green.x(), c.green.y()],
        blue: [c.blue.x(), c.blue.y()],
        white: [c.white.x(), c.white.y()],
    });
    Part {
        index,
        name: own.layer_name.as_ref().map(ToString::to_string),
        view,
        kind,
        data_window: bounds(own.layer_position, h.layer_size),
        display_window: bounds(display.position, display.size),
        compression: compression_name(h.compression).to_owned(),
        levels,
        chromaticities,
        multi_view,
        channels: h
            .channels
            .list
            .iter()
            .map(|c| Channel {
                name: c.name.to_string(),
                sample: SampleKind::of(c.sample_type),
                sampling: [c.sampling.x(), c.sampling.y()],
            })
            .collect(),
        attributes: attributes_of(h),
    }
}

fn compression_name(c: exr::compression::Compression) -> &'static str {
    use exr::compression::Compression as C;
    match c {
        C::Uncompressed => "none",
        C::RLE => "rle",
        C::ZIP1 => "zips",
        C::ZIP16 => "zip",
        C::PIZ => "piz",
        C::PXR24 => "pxr24",
        C::B44 => "b44",
        C::B44A => "b44a",
        C::DWAA(_) => "dwaa",
        C::DWAB(_) => "dwab",
        C::HTJ2K32 => "htj2k32",
        C::HTJ2K256 => "htj2k256",
    }
}

/// Every attribute not already a field of [`Part`], named and in words, sorted by name.
fn attributes_of(h: &Header) -> Vec<(String, String)> {
    let own = &h.own_attributes;
    let shared = &h.shared_attributes;
    let mut out: Vec<(String, String)> = Vec::new();
    out.push((
        "pixelAspectRatio".into(),
        format!("{}", shared.pixel_aspect),
    ));
    out.push(("lineOrder".into(), format!("{:?}", h.line_order)));
    out.push((
        "screenWindowCenter".into(),
        format!(
            "({}, {})",
            own.screen_window_center.x(),
            own.screen_window_center.y()
        ),
    ));
    out.push((
        "screenWindowWidth".into(),
        format!("{}", own.screen_window_width),
    ));
    if let Some(tc) = &shared.time_code {
        out.push(("timeCode".into(), format!("{tc:?}")));
    }
    if let BlockDescription::Tiles(t) = &h.blocks {
        out.push((
            "tiles".into(),
            format!(
                "{}×{}, {:?} rounding",
                t.tile_size.x(),
                t.tile_size.y(),
                t.rounding_mode
            ),
        ));
    }
    let optional = optional_attributes(own);
    out.extend(
        optional
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| (k.to_owned(), v))),
    );
    for (name, value) in own.other.iter().chain(shared.other.iter()) {
        let name = name.to_string();
        if name == "view" || name == "multiView" || out.iter().any(|(k, _)| *k == name) {
            continue;
        }
        out.push((name, value_text(value)));
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn value_text(value: &AttributeValue) -> String {
    match value {
        AttributeValue::Text(t) => format!("{:?}", t.to_string()),
        AttributeValue::TextVector(v) => {
            let items: Vec<String> = v.iter().map(|t| format!("{:?}", t.to_string())).collect();
            format!("[{}]", items.join(", "))
        }
        AttributeValue::F32(v) => v.to_string(),
        AttributeValue::F64(v) => v.to_string(),
        AttributeValue::I32(v) => v.to_string(),
        AttributeValue::Preview(p) => format!("preview {}×{}", p.size.x(), p.size.y()),
        other => {
            let mut s = format!("{other:?}");
            if s.len() > 200 {
                s.truncate(200);
                s.push('…');
            }
            s
        }
    }
}

/// The optional attributes the `exr` crate reads into fields, named as in the file.
fn optional_attributes(
    own: &exr::meta::header::LayerAttributes,
) -> Vec<(&'static str, Option<String>)> {
    let text = |v: &Option<exr::meta::attribute::Text>| v.as_ref().map(ToString::to_string);
    let num = |v: Option<f32>| v.map(|v| v.to_string());
    let debug = |v: Option<&dyn fmt::Debug>| v.map(|v| format!("{v:?}"));
    vec![
        ("whiteLuminance", num(own.white_luminance)),
        (
            "adoptedNeutral",
            own.adopted_neutral
                .map(|v| format!("({}, {})", v.x(), v.y())),
        ),
        ("renderingTransform", text(&own.rendering_transform_name)),
        (
            "lookModTransform",
            text(&own.look_modification_transform_name),
        ),
        ("xDensity", num(own.horizontal_density)),
        ("owner", text(&own.owner)),
        ("comments", text(&own.comments)),
        ("capDate", text(&own.capture_date)),
        ("utcOffset", num(own.utc_offset)),
        ("longitude", num(own.longitude)),
        ("latitude", num(own.latitude)),
        ("altitude", num(own.altitude)),
        ("focus", num(own.focus)),
        ("expTime", num(own.exposure)),
        ("aperture", num(own.aperture)),
        ("isoSpeed", num(own.iso_speed)),
        (
            "envmap",
            debug(own.environment_map.as_ref().map(|v| v as &dyn fmt::Debug)),
        ),
        (
            "keyCode",
            debug(own.film_key_code.as_ref().map(|v| v as &dyn fmt::Debug)),
        ),
        ("wrapmodes", text(&own.wrap_mode_name)),
        (
            "framesPerSecond",
            own.frames_per_second.map(|r| format!("{}/{}", r.0, r.1)),
        ),
        (
            "worldToCamera",
            debug(own.world_to_camera.as_ref().map(|v| v as &dyn fmt::Debug)),
        ),
        (
            "worldToNDC",
            debug(
                own.world_to_normalized_device
                    .as_ref()
                    .map(|v| v as &dyn fmt::Debug),
            ),
        ),
        (
            "originalDataWindow",
            own.original_data_window.map(|b| {
                Window::at([b.position.x(), b.position.y()], [b.size.x(), b.size.y()]).to_string()
            }),
        ),
        (
            "preview",
            own.preview
                .as_ref()
                .map(|p| format!("{}×{}", p.size.x(), p.size.y())),
        ),
        ("software", text(&own.software_name)),
        ("clipping planes and field of view", {
            let parts: Vec<String> = [
                ("near", own.near_clip_plane),
                ("far", own.far_clip_plane),
                ("fovX", own.horizontal_field_of_view),
                ("fovY", own.vertical_field_of_view),
            ]
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| format!("{k} {v}")))
            .collect();
            (!parts.is_empty()).then(|| parts.join(", "))
        }),
    ]
}
