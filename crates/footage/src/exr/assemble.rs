//! What to write of images made from layers read from files: the file [`assemble`]
//! builds for [`super::encode`] from display-window images, each with the [`Source`] it
//! was made from (when there is one), and the writer's choices.
//!
//! - **Names.** A layer's name and channels are those its node's params give; else, when
//!   the image is still the shape of its source layer (as many values a pixel), the
//!   source's, as read (`forward.u forward.v`, `depth.Z`, a multi-view part's `right.Y`);
//!   else the node's defaults. A luminance layer (`Y`) is written as `Y` while its image
//!   is grey, else as `R G B`; a luminance/chroma one (`Y RY BY`) as `R G B`.
//! - **Sample types.** Half, float, or each channel as the source stored it.
//! - **Windows.** The display window is the source's when the image is its size, else
//!   the image's at the origin. The data window is the display window, the source's data
//!   window (what lies outside it is dropped; overscan was cropped when read), or the
//!   bounding box of the pixels that are not zero in every channel written (an
//!   auto-crop, as Nuke's Write node makes).
//! - **Parts.** One part for every layer (Blender's multi-layer EXR), or one part a
//!   layer (Nuke's multi-part EXR), named as the source's part or as the layer.
//! - **Attributes.** Each part carries its source part's header attributes that stay true
//!   ([`Source::carried`]); what is left out is named in one note a file.

use super::windows::{WindowChoice, index, union, window_of};
use super::write::{FileOut, LayerOut, PartAttributes, PartOut};
use super::{Compression, LayerKind, SampleKind, Source, Want, Window};
use crate::color::Chromaticities;

/// Which sample type to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TypeChoice {
    /// 16-bit float.
    Half,
    /// 32-bit float.
    Float,
    /// Each channel as the source stored it (float where there is no source).
    Source,
}

impl TypeChoice {
    /// `half`, `float` or `source`.
    pub fn named(name: &str) -> Option<Self> {
        Some(match name {
            "half" => Self::Half,
            "float" => Self::Float,
            "source" => Self::Source,
            _ => return None,
        })
    }
}

/// How the layers are laid out in parts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartsChoice {
    /// Every layer in one part.
    Single,
    /// One part a layer.
    PerLayer,
}

impl PartsChoice {
    /// `single` or `per_layer`.
    pub fn named(name: &str) -> Option<Self> {
        Some(match name {
            "single" => Self::Single,
            "per_layer" => Self::PerLayer,
            _ => return None,
        })
    }
}

/// One image to write as a layer.
#[derive(Clone, Debug)]
pub struct ImageIn<'a> {
    /// What it is called in messages (the node's input port).
    pub port: &'a str,
    /// `width × height × components` values, interleaved, rows first.
    pub values: &'a [f32],
    /// Values a pixel: 4 or 1.
    pub components: usize,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The layer name the node's params give, if they do.
    pub name: Option<String>,
    /// The channel names the node's params give, if they do.
    pub channels: Option<Vec<String>>,
    /// The layer name where neither the params nor a source give one.
    pub default_name: String,
    /// The channel names where neither the params nor a source give them.
    pub default_channels: Vec<String>,
    /// The sample type.
    pub sample: TypeChoice,
    /// The layer it was made from, if it was read from a file.
    pub source: Option<&'a Source>,
}

/// The writer's choices for the whole file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The data window.
    pub window: WindowChoice,
    /// The parts.
    pub parts: PartsChoice,
    /// The compression.
    pub compression: Compression,
    /// The working space's primaries and white, written as `chromaticities`.
    pub chromaticities: Chromaticities,
}

/// A layer resolved: its names, the image's component for each channel, types, window.
struct Resolved<'a> {
    image: &'a ImageIn<'a>,
    name: String,
    channels: Vec<String>,
    components: Vec<usize>,
    samples: Vec<SampleKind>,
    window: Window,
}

/// The file to write of `images` (each the display window's pixels), and what a user
/// should know of it: what was not carried, dropped, or named otherwise.
///
/// # Errors
/// No image, images of different sizes, values that do not fill an image, channel names
/// the image has too few values a pixel for.
pub fn assemble(
    images: &[ImageIn<'_>],
    settings: &Settings,
) -> Result<(FileOut, Vec<String>), String> {
    let first = images.first().ok_or("no image to write")?;
    let (w, h) = (first.width, first.height);
    for image in images {
        if (image.width, image.height) != (w, h) {
            return Err(format!(
                "input {:?} is {}×{}, input {:?} {w}×{h}: the layers of a file are one size",
                image.port, image.width, image.height, first.port
            ));
        }
        if image.components == 0 || image.values.len() != w * h * image.components {
            return Err(format!(
                "input {:?}: {} values for {w}×{h} pixels of {}",
                image.port,
                image.values.len(),
                image.components
            ));
        }
    }
    let mut notes = Vec::new();
    let display = display_window(images, &mut notes);
    let layers = images
        .iter()
        .map(|image| resolve(image, display, settings.window, &mut notes))
        .collect::<Result<Vec<_>, _>>()?;
    let groups: Vec<Vec<&Resolved<'_>>> = match settings.parts {
        PartsChoice::Single => vec![layers.iter().collect()],
        PartsChoice::PerLayer => layers.iter().map(|l| vec![l]).collect(),
    };
    let mut parts = Vec::new();
    let mut dropped: Vec<String> = Vec::new();
    for group in &groups {
        let (part, carried) = part_of(group, display, settings, &parts);
        for d in carried {
            if !dropped.contains(&d) {
                dropped.push(d);
            }
        }
        parts.push(part);
    }
    let file_attributes = first
        .source
        .map(|s| {
            let same_frame = s.part.display_window == display;
            s.carried(same_frame, false, &settings.chromaticities).file
        })
        .unwrap_or_default();
    if !dropped.is_empty() {
        notes.push(format!(
            "not carried from the source: {}",
            dropped.join("; ")
        ));
    }
    Ok((
        FileOut {
            display_window: display,
            parts,
            compression: settings.compression,
            attributes: file_attributes,
            chromaticities: settings.chromaticities,
        },
        notes,
    ))
}

/// The display window: the first source's whose size is the images', else the images'
/// at the origin.
fn display_window(images: &[ImageIn<'_>], notes: &mut Vec<String>) -> Window {
    let (w, h) = (images[0].width, images[0].height);
    let mut sources = images.iter().filter_map(|i| i.source);
    if let Some(s) = sources.clone().find(|s| {
        (
            s.part.display_window.width(),
            s.part.display_window.height(),
        ) == (w, h)
    }) {
        return s.part.display_window;
    }
    if let Some(s) = sources.next() {
        notes.push(format!(
            "the image is {w}×{h}, not the display window {} of {}: written at the origin",
            s.part.display_window,
            s.path.display()
        ));
    }
    Window::at([0, 0], [w, h])
}

/// Values a pixel an image read as `want` has.
fn components_of(want: Want) -> usize {
    match want {
        Want::Rgba | Want::Vector => 4,
        Want::Scalar => 1,
    }
}

/// Whether every pixel's first three components are equal (a grey image).
fn is_grey(image: &ImageIn<'_>) -> bool {
    image.components >= 3
        && image
            .values
            .chunks_exact(image.components)
            .all(|p| p[0].to_bits() == p[1].to_bits() && p[1].to_bits() == p[2].to_bits())
}

/// The source's channels for an image of its shape: full names, components, types.
fn source_channels(
    source: &Source,
    image: &ImageIn<'_>,
    notes: &mut Vec<String>,
) -> (Vec<String>, Vec<usize>, Vec<Option<SampleKind>>) {
    let layer = &source.layer;
    let prefixed = |c: &str| {
        let p = source.prefix();
        if p.is_empty() {
            c.to_owned()
        } else {
            format!("{p}.{c}")
        }
    };
    let own = |names: &[String], components: Vec<usize>| {
        let samples = names.iter().map(|n| source.sample(n)).collect();
        (names.to_vec(), components, samples)
    };
    match (source.want, layer.kind) {
        (Want::Scalar, _) => own(&layer.channels[..1], vec![0]),
        (Want::Rgba, LayerKind::Luminance { chroma, alpha }) => {
            let y = source.sample(&layer.channels[0]);
            let a = alpha.then(|| layer.channels[layer.channels.len() - 1].clone());
            if !chroma && is_grey(image) {
                let mut names = vec![layer.channels[0].clone()];
                names.extend(a.clone());
                let components = if alpha { vec![0, 3] } else { vec![0] };
                return own(&names, components);
            }
            notes.push(format!(
                "input {:?}: the {} layer {} is written as R G B{}",
                image.port,
                layer.kind.name(),
                layer.channels.join(" "),
                if chroma {
                    ": its chroma is not subsampled again"
                } else {
                    ": its image is no longer grey"
                }
            ));
            let mut names: Vec<String> = ["R", "G", "B"].iter().map(|c| prefixed(c)).collect();
            let mut samples = vec![y; 3];
            let mut components = vec![0, 1, 2];
            if let Some(a) = a {
                names.push(prefixed("A"));
                samples.push(source.sample(&a));
                components.push(3);
            }
            (names, components, samples)
        }
        _ => {
            let k = layer.channels.len().min(image.components);
            own(&layer.channels[..k], (0..k).collect())
        }
    }
}

/// A layer's names, components, types and window.
fn resolve<'a>(
    image: &'a ImageIn<'a>,
    display: Window,
    choice: WindowChoice,
    notes: &mut Vec<String>,
) -> Result<Resolved<'a>, String> {
    let source = image.source.filter(|s| s.part.display_window == display);
    let fits = source.filter(|s| components_of(s.want) == image.components);
    if let (Some(s), None) = (source, fits) {
        notes.push(format!(
            "input {:?} holds {} values a pixel, the {} layer {} of {} {}: its channels are \
             named as the node names them",
            image.port,
            image.components,
            s.layer.kind.name(),
            s.layer.channels.join(" "),
            s.path.display(),
            components_of(s.want)
        ));
    }
    let from_source = fits.map(|s| source_channels(s, image, notes));
    let split = |full: &str| match full.rsplit_once('.') {
        Some((p, c)) => (p.to_owned(), c.to_owned()),
        None => (String::new(), full.to_owned()),
    };
    let (mut name, channels, components, source_samples) = match (&image.channels, from_source) {
        (Some(given), from) => {
            if given.is_empty() || given.len() > image.components {
                return Err(format!(
                    "input {:?} holds {} value{} a pixel: give it 1 to {} channel names, not \
                     {:?}",
                    image.port,
                    image.components,
                    if image.components == 1 { "" } else { "s" },
                    image.components,
                    given.join(" ")
                ));
            }
            let types = from.map(|(_, _, t)| t).unwrap_or_default();
            let types = (0..given.len())
                .map(|i| types.get(i).copied().flatten())
                .collect();
            let name = fits.map_or_else(|| image.default_name.clone(), Source::prefix);
            (name, given.clone(), (0..given.len()).collect(), types)
        }
        (None, Some((full, components, types))) => {
            let name = full.first().map(|f| split(f).0).unwrap_or_default();
            let channels = full.iter().map(|f| split(f).1).collect();
            (name, channels, components, types)
        }
        (None, None) => {
            let k = image.default_channels.len().min(image.components);
            (
                image.default_name.clone(),
                image.default_channels[..k].to_vec(),
                (0..k).collect(),
                vec![None; k],
            )
        }
    };
    if let Some(given) = &image.name {
        name.clone_from(given);
    }
    let samples = samples_of(image, &source_samples, notes);
    let window = window_of(image, &components, display, source, choice, notes);
    Ok(Resolved {
        image,
        name,
        channels,
        components,
        samples,
        window,
    })
}

/// Each channel's sample type under the image's choice.
fn samples_of(
    image: &ImageIn<'_>,
    source: &[Option<SampleKind>],
    notes: &mut Vec<String>,
) -> Vec<SampleKind> {
    match image.sample {
        TypeChoice::Half => vec![SampleKind::Half; source.len()],
        TypeChoice::Float => vec![SampleKind::Float; source.len()],
        TypeChoice::Source => {
            if source.iter().any(Option::is_none) {
                notes.push(format!(
                    "input {:?}: type `source`, but {} channel{} no source: written as float",
                    image.port,
                    if source.iter().all(Option::is_none) {
                        "its"
                    } else {
                        "some of its"
                    },
                    if source.len() == 1 { " has" } else { "s have" }
                ));
            }
            source
                .iter()
                .map(|s| s.unwrap_or(SampleKind::Float))
                .collect()
        }
    }
}

/// A layer's values over `window`.
fn crop(layer: &Resolved<'_>, display: Window, window: Window) -> LayerOut {
    let image = layer.image;
    let mut values = Vec::with_capacity(window.width() * window.height() * layer.channels.len());
    for y in window.min[1]..=window.max[1] {
        for x in window.min[0]..=window.max[0] {
            let at = index(display, x, y) * image.components;
            values.extend(layer.components.iter().map(|&c| image.values[at + c]));
        }
    }
    LayerOut {
        name: layer.name.clone(),
        channels: layer.channels.clone(),
        values,
        samples: layer.samples.clone(),
    }
}

/// The part of `group`'s layers, and the names of the attributes its source does not
/// carry.
fn part_of(
    group: &[&Resolved<'_>],
    display: Window,
    settings: &Settings,
    before: &[PartOut],
) -> (PartOut, Vec<String>) {
    let window = group
        .iter()
        .map(|l| l.window)
        .reduce(union)
        .unwrap_or(display);
    let sources: Vec<Option<&Source>> = group.iter().map(|l| l.image.source).collect();
    let first = sources.first().copied().flatten();
    // One source part for every layer: its name, view and multiView stay true.
    let one_part = first.filter(|f| {
        sources
            .iter()
            .all(|s| s.is_some_and(|s| s.path == f.path && s.part.index == f.part.index))
    });
    let mut name = one_part.and_then(|s| s.part.name.clone());
    if settings.parts == PartsChoice::PerLayer {
        let layer = &group[0].name;
        let own = if layer.is_empty() { "rgba" } else { layer };
        let taken = |n: &str| before.iter().any(|p| p.name.as_deref() == Some(n));
        name = match name {
            Some(n) if !taken(&n) => Some(n),
            Some(n) => Some(format!("{n}.{own}")),
            None => Some(own.to_owned()),
        };
    }
    let carried = first
        .map(|s| {
            let same_frame = s.part.display_window == display;
            s.carried(same_frame, one_part.is_some(), &settings.chromaticities)
        })
        .unwrap_or_default();
    let part = PartOut {
        name,
        view: one_part.and_then(|s| s.part.view.clone()),
        data_window: window,
        layers: group.iter().map(|l| crop(l, display, window)).collect(),
        attributes: if first.is_some() {
            carried.part
        } else {
            PartAttributes::default()
        },
    };
    (part, carried.dropped)
}
