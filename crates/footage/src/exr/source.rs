//! What a layer was read from, for a writer to write it back as it was: the file, its part
//! (name, view, windows, channels and their sample types, every attribute), the layer,
//! the port it was read onto, and the part's header attributes as the file holds them.
//! [`Source::carried`] says which of those attributes stay true of an image made from the
//! layer, and names the others.

use std::path::{Path, PathBuf};

use exr::math::Vec2;
use exr::meta::BlockDescription;
use exr::meta::attribute::LineOrder;
use exr::meta::header::{ImageAttributes, LayerAttributes};

use super::write::{FileAttributes, PartAttributes};
use super::{Error, Layer, Part, Result, SampleKind, Want, headers, part_of};
use crate::color::Chromaticities;

/// A layer as it was read from a file.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    /// The file.
    pub path: PathBuf,
    /// Its part, as [`super::inspect`] reads it.
    pub part: Part,
    /// The layer.
    pub layer: Layer,
    /// What it was read as (the port it went to).
    pub want: Want,
    own: LayerAttributes,
    shared: ImageAttributes,
    tiled: Option<&'static str>,
    line_order: LineOrder,
}

/// What [`Source::carried`] gives a writer: the part's and the file's attributes, and the
/// names of those left out, each with why.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Carried {
    /// The part's own attributes.
    pub part: PartAttributes,
    /// The attributes every part shares.
    pub file: FileAttributes,
    /// What is not carried, `name (why)`.
    pub dropped: Vec<String>,
}

impl Source {
    /// The source of `layer` of the file at `path`, read as `want`.
    ///
    /// # Errors
    /// An unreadable header, or a layer whose part the file lacks.
    pub fn of(path: &Path, layer: &Layer, want: Want) -> Result<Self> {
        let headers = headers(path)?;
        let header = headers
            .get(layer.part)
            .ok_or_else(|| Error::new(path, format!("the file has no part {}", layer.part)))?;
        let tiled = match &header.blocks {
            BlockDescription::ScanLines => None,
            BlockDescription::Tiles(t) => Some(match t.level_mode {
                exr::meta::attribute::LevelMode::Singular => "tiles",
                exr::meta::attribute::LevelMode::MipMap => "tiles, mip-map levels",
                exr::meta::attribute::LevelMode::RipMap => "tiles, rip-map levels",
            }),
        };
        Ok(Self {
            path: path.to_path_buf(),
            part: part_of(layer.part, header),
            layer: layer.clone(),
            want,
            own: header.own_attributes.clone(),
            shared: header.shared_attributes.clone(),
            tiled,
            line_order: header.line_order,
        })
    }

    /// The layer's name as its channels spell it (`forward` for `forward.u`, `right` for
    /// a multi-view part's `right.Y`, `""` for root channels).
    pub fn prefix(&self) -> String {
        self.layer
            .channels
            .first()
            .and_then(|c| c.rsplit_once('.'))
            .map_or_else(String::new, |(p, _)| p.to_owned())
    }

    /// The sample type of channel `full` of the part, if it has one of that name.
    pub fn sample(&self, full: &str) -> Option<SampleKind> {
        self.part
            .channels
            .iter()
            .find(|c| c.name == full)
            .map(|c| c.sample)
    }

    /// The attributes to write for an image made from this layer, in a graph whose working
    /// space has the primaries `working`: everything the part's header holds that stays
    /// true of it. Left out, and named in `dropped`: colour primaries other than the
    /// working space's (the colour was converted into it),
    /// the preview (a thumbnail of the file's pixels), tiles and resolution levels (the
    /// writer writes scan lines, full resolution), a decreasing line order; with
    /// `same_frame` unset (the image is not the part's display window), what describes
    /// the frame (`screenWindowCenter`, `screenWindowWidth`, `pixelAspectRatio`,
    /// `xDensity`, `originalDataWindow`); with `multi_view` unset (the part written holds
    /// more than this part's channels), the `multiView` list. Name, view and windows are
    /// the writer's.
    pub fn carried(&self, same_frame: bool, multi_view: bool, working: &Chromaticities) -> Carried {
        let mut dropped = Vec::new();
        let mut own = self.own.clone();
        let mut shared = self.shared.clone();
        if let Some(c) = self.part.chromaticities.filter(|c| !c.is_near(working)) {
            dropped.push(format!(
                "chromaticities (red {:?}, green {:?}, blue {:?}, white {:?}: the working \
                 space's are written, the colour having been converted into it)",
                c.red, c.green, c.blue, c.white
            ));
        }
        if own.preview.take().is_some() {
            dropped.push("preview (a thumbnail of the file's pixels)".into());
        }
        if let Some(tiles) = self.tiled {
            dropped.push(format!("{tiles} (written as scan lines, full resolution)"));
        }
        if self.line_order == LineOrder::Decreasing {
            dropped.push("lineOrder decreasing (written increasing)".into());
        }
        if own.deep_image_state.take().is_some() {
            dropped.push("deepImageState (the image written is flat)".into());
        }
        if !multi_view && own.multi_view_names.take().is_some() {
            dropped.push("multiView (the part written holds other channels too)".into());
        }
        if !same_frame {
            let frame = LayerAttributes::default();
            let mut frame_dropped = Vec::new();
            if own.screen_window_center != frame.screen_window_center {
                frame_dropped.push("screenWindowCenter");
            }
            if own.screen_window_width != frame.screen_window_width {
                frame_dropped.push("screenWindowWidth");
            }
            if (shared.pixel_aspect - 1.0).abs() > f32::EPSILON {
                frame_dropped.push("pixelAspectRatio");
            }
            if own.horizontal_density.take().is_some() {
                frame_dropped.push("xDensity");
            }
            if own.original_data_window.take().is_some() {
                frame_dropped.push("originalDataWindow");
            }
            own.screen_window_center = frame.screen_window_center;
            own.screen_window_width = frame.screen_window_width;
            shared.pixel_aspect = 1.0;
            if !frame_dropped.is_empty() {
                dropped.push(format!(
                    "{} (the image is not the file's display window)",
                    frame_dropped.join(", ")
                ));
            }
        }
        own.layer_name = None;
        own.view_name = None;
        own.layer_position = Vec2(0, 0);
        Carried {
            part: PartAttributes(Some(own)),
            file: FileAttributes(Some(shared)),
            dropped,
        }
    }
}
