//! Reading a layer into its part's display window.

use std::path::Path;

use exr::image::read::read;
use exr::image::{AnyChannels, FlatSamples};
use exr::prelude::{ReadChannels as _, ReadLayers as _};

use super::{Error, Info, Layer, LayerKind, Part, Result, SampleKind, Selection, Window, inspect};

/// A layer's channels over its part's data window, as stored: one plane per channel at
/// the channel's own resolution (subsampled channels are smaller), row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct RawChannel {
    /// The channel's full name.
    pub name: String,
    /// The type of its samples.
    pub sample: SampleKind,
    /// Its sampling rates across and down.
    pub sampling: [usize; 2],
    /// Samples across.
    pub width: usize,
    /// Samples down.
    pub height: usize,
    /// Each sample's bits: a half's 16 bits, a float's or a uint's 32.
    pub bits: Vec<u32>,
}

impl RawChannel {
    /// Sample `i` as a float (a half exactly, NaN payloads kept; a uint converted, exact
    /// below 2²⁴).
    pub fn value(&self, i: usize) -> f32 {
        let b = self.bits[i];
        match self.sample {
            SampleKind::Half => super::half_to_f32(u16::try_from(b).unwrap_or(0)),
            SampleKind::Float => f32::from_bits(b),
            #[expect(
                clippy::cast_precision_loss,
                reason = "uint channels hold ids and counts; stated in the doc"
            )]
            SampleKind::Uint => b as f32,
        }
    }

    /// Every sample as a float.
    pub fn values(&self) -> Vec<f32> {
        (0..self.bits.len()).map(|i| self.value(i)).collect()
    }
}

/// What a caller wants a layer as: the port it goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Want {
    /// Linear Rec. 709 RGBA: a colour or luminance(/chroma) layer.
    Rgba,
    /// One value: a one-channel layer, or a luminance layer's `Y`.
    Scalar,
    /// Up to four values (missing ones 0): a vector layer.
    Vector,
}

impl Want {
    /// The port name a layer of this want goes to.
    pub fn port(self) -> &'static str {
        match self {
            Self::Rgba => "color",
            Self::Scalar => "scalar",
            Self::Vector => "vector",
        }
    }

    /// The want a layer of `kind` is read as by default.
    pub fn of(kind: LayerKind) -> Self {
        match kind {
            LayerKind::Color { .. } | LayerKind::Luminance { .. } => Self::Rgba,
            LayerKind::Scalar => Self::Scalar,
            LayerKind::Vector => Self::Vector,
        }
    }

    /// Whether a layer of `kind` can be read as this.
    pub fn fits(self, kind: LayerKind) -> bool {
        match self {
            Self::Rgba => matches!(kind, LayerKind::Color { .. } | LayerKind::Luminance { .. }),
            Self::Scalar => matches!(
                kind,
                LayerKind::Scalar | LayerKind::Luminance { chroma: false, .. }
            ),
            Self::Vector => kind == LayerKind::Vector,
        }
    }
}

/// A layer read into its part's display window.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerImage {
    /// The layer.
    pub layer: Layer,
    /// The image's frame: its width and height are the image's.
    pub display_window: Window,
    /// Where the file had pixels (outside it the image is 0).
    pub data_window: Window,
    /// Values per pixel: 4 (RGBA, or a vector's up to four), or 1 (scalar).
    pub channels: usize,
    /// `display_window.width() × height × channels` values, row-major.
    pub pixels: Vec<f32>,
    /// What was done that a user should know: primaries converted, overscan cropped.
    pub notes: Vec<String>,
}

impl LayerImage {
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.display_window.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.display_window.height()
    }
}

/// Reads the layer `selection` names as `want` into its part's display window.
///
/// # Errors
/// What [`inspect`] refuses, a selection that names no layer, a layer that does not fit
/// `want` (the message names the port it fits), a deep part, damaged pixel data.
pub fn read_layer(path: &Path, selection: &Selection, want: Want) -> Result<LayerImage> {
    read_layer_in(path, selection, want, Primaries::Rec709)
}

/// What [`read_layer_in`] does with a colour layer's primaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primaries {
    /// Converted from the file's `chromaticities` to Rec. 709 ([`read_layer`]).
    Rec709,
    /// Kept as stored (luminance/chroma still reconstructed with the file's own
    /// luminance weights): for a colour space the user names, which converts them.
    AsStored,
}

/// [`read_layer`], with the colour layer's primaries converted or kept.
///
/// # Errors
/// As [`read_layer`].
pub fn read_layer_in(
    path: &Path,
    selection: &Selection,
    want: Want,
    primaries: Primaries,
) -> Result<LayerImage> {
    let info = inspect(path)?;
    let layer = selection.find(&info).map_err(|e| Error::new(path, e))?;
    let part = &info.parts[layer.part];
    if !want.fits(layer.kind) {
        return Err(Error::new(
            path,
            format!(
                "layer {} is a {} layer ({}): it is read onto the `{}` port, not `{}`",
                layer.label(part),
                layer.kind.name(),
                layer.channels.join(" "),
                Want::of(layer.kind).port(),
                want.port()
            ),
        ));
    }
    if part.kind.is_deep() {
        return Err(Error::new(
            path,
            format!(
                "{} holds deep data ({}): lumagraph reads flat images only; flatten it \
                 first (oiiotool --flatten, or Nuke's DeepToImage)",
                part.label(),
                part.kind.name()
            ),
        ));
    }
    let raw = read_channels(path, &info, layer.part, &layer.channels)?;
    let (mut values, channels) = combine(path, part, &layer, &raw, want)?;
    let mut notes = Vec::new();
    if want == Want::Rgba && primaries == Primaries::Rec709 {
        convert_primaries(path, part, &mut values)?;
    }
    if want == Want::Rgba
        && primaries == Primaries::Rec709
        && let Some(c) = part.chromaticities.filter(|c| !c.is_rec709())
    {
        notes.push(format!(
            "colour converted from the file's primaries (red {:?}, green {:?}, blue {:?}, \
             white {:?}) to Rec. 709",
            c.red, c.green, c.blue, c.white
        ));
    }
    let pixels = place(part, &values, channels, &mut notes);
    Ok(LayerImage {
        layer,
        display_window: part.display_window,
        data_window: part.data_window,
        channels,
        pixels,
        notes,
    })
}

/// Every channel of part `part` named in `names`, as stored, in `names`' order.
///
/// # Errors
/// A deep part, a name the part lacks, damaged pixel data.
pub fn read_channels(
    path: &Path,
    info: &Info,
    part: usize,
    names: &[String],
) -> Result<Vec<RawChannel>> {
    let p = &info.parts[part];
    if p.kind.is_deep() {
        return Err(Error::new(
            path,
            format!(
                "{} holds deep data: lumagraph reads flat images only",
                p.label()
            ),
        ));
    }
    // Scan-line parts through the block reader, which decodes only this part's chunks;
    // tiled parts (and their resolution levels) through the `exr` crate's image reader.
    let all = if p.kind == super::PartKind::ScanLines {
        crate::subsampled::read_part(path, part)
            .map_err(|e| Error::new(path, format!("not a readable EXR file: {e}")))?
            .into_iter()
            .map(|s| RawChannel {
                name: s.name,
                sample: SampleKind::of(s.sample_type),
                sampling: [s.sampling.0, s.sampling.1],
                width: s.width,
                height: s.height,
                bits: s.bits,
            })
            .collect()
    } else {
        read_flat_part(path, part)?
    };
    names
        .iter()
        .map(|n| {
            all.iter()
                .find(|c| c.name == *n)
                .cloned()
                .ok_or_else(|| Error::new(path, format!("{} has no channel {n:?}", p.label())))
        })
        .collect()
}

/// Every channel of a flat part, through the `exr` crate (largest resolution level).
fn read_flat_part(path: &Path, part: usize) -> Result<Vec<RawChannel>> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| Error::new(path, format!("not a readable EXR file: {e}")))?;
    let layer = image
        .layer_data
        .get(part)
        .ok_or_else(|| Error::new(path, format!("the file has no part {part}")))?;
    let AnyChannels { list } = &layer.channel_data;
    Ok(list
        .iter()
        .map(|c| {
            let (sample, bits): (SampleKind, Vec<u32>) = match &c.sample_data {
                FlatSamples::F16(v) => (
                    SampleKind::Half,
                    v.iter().map(|h| u32::from(h.to_bits())).collect(),
                ),
                FlatSamples::F32(v) => (SampleKind::Float, v.iter().map(|f| f.to_bits()).collect()),
                FlatSamples::U32(v) => (SampleKind::Uint, v.clone()),
            };
            RawChannel {
                name: c.name.to_string(),
                sample,
                sampling: [1, 1],
                width: layer.size.width(),
                height: layer.size.height(),
                bits,
            }
        })
        .collect())
}

/// The layer's values over the data window: RGBA (in the file's primaries), one scalar, or
/// a vector padded to four.
fn combine(
    path: &Path,
    part: &Part,
    layer: &Layer,
    raw: &[RawChannel],
    want: Want,
) -> Result<(Vec<f32>, usize)> {
    let n = part.data_window.width() * part.data_window.height();
    if let Some(bad) = raw
        .iter()
        .find(|c| c.sampling == [1, 1] && c.bits.len() != n)
    {
        return Err(Error::new(
            path,
            format!(
                "channel {:?} holds {} samples, not the data window's {n}",
                bad.name,
                bad.bits.len()
            ),
        ));
    }
    match (want, layer.kind) {
        (Want::Scalar, _) => Ok((raw[0].values(), 1)),
        (Want::Vector, _) => {
            let planes: Vec<Vec<f32>> = raw.iter().map(RawChannel::values).collect();
            let mut out = vec![0.0; n * 4];
            for (c, plane) in planes.iter().enumerate().take(4) {
                for (i, v) in plane.iter().enumerate() {
                    out[i * 4 + c] = *v;
                }
            }
            Ok((out, 4))
        }
        (Want::Rgba, LayerKind::Color { alpha }) => {
            let planes: Vec<Vec<f32>> = raw.iter().map(RawChannel::values).collect();
            let mut out = vec![0.0; n * 4];
            for i in 0..n {
                let a = if alpha { planes[3][i] } else { 1.0 };
                out[i * 4..i * 4 + 4].copy_from_slice(&[
                    planes[0][i],
                    planes[1][i],
                    planes[2][i],
                    a,
                ]);
            }
            Ok((out, 4))
        }
        (Want::Rgba, LayerKind::Luminance { chroma, alpha }) => {
            let y = raw[0].values();
            let (ry, by) = if chroma {
                (Some(raw[1].values()), Some(raw[2].values()))
            } else {
                (None, None)
            };
            let a = alpha.then(|| raw[raw.len() - 1].values());
            let weights = crate::yca::luminance_weights(part.chromaticities.map(|c| c.to_array()));
            let input = crate::yca::YcaInput {
                width: part.data_window.width(),
                height: part.data_window.height(),
                origin: (part.data_window.min[0], part.data_window.min[1]),
                y: &y,
                ry: ry.as_deref(),
                by: by.as_deref(),
                a: a.as_deref(),
            };
            let out: Vec<f32> = crate::yca::to_rgba(&input, weights)
                .map_err(|e| Error::new(path, format!("{}: {e}", part.label())))?
                .into_iter()
                .flatten()
                .collect();
            Ok((out, 4))
        }
        (Want::Rgba, _) => Err(Error::new(path, "a scalar or vector layer is not colour")),
    }
}

/// Converts RGBA in `part`'s primaries to Rec. 709, in place.
fn convert_primaries(path: &Path, part: &Part, rgba: &mut [f32]) -> Result<()> {
    let Some(c) = part.chromaticities.filter(|c| !c.is_rec709()) else {
        return Ok(());
    };
    let m = c.to_rec709();
    if !crate::color::is_finite(&m) {
        return Err(Error::new(
            path,
            format!(
                "{}'s chromaticities {:?} span no colour space: its colour cannot be converted",
                part.label(),
                c.to_array()
            ),
        ));
    }
    for p in rgba.chunks_exact_mut(4) {
        let v = crate::color::mul_vec(&m, [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]);
        #[expect(
            clippy::cast_possible_truncation,
            reason = "colour is f32; the matrix is applied in f64"
        )]
        p[..3].copy_from_slice(&v.map(|x| x as f32));
    }
    Ok(())
}

/// Places data-window values into the display window (0 outside the data window); notes
/// overscan cropped.
fn place(part: &Part, values: &[f32], channels: usize, notes: &mut Vec<String>) -> Vec<f32> {
    let (data, display) = (part.data_window, part.display_window);
    let (w, h) = (display.width(), display.height());
    let mut out = vec![0.0; w * h * channels];
    if !display.contains(&data) {
        notes.push(format!(
            "the data window {data} reaches outside the display window {display}: the \
             pixels outside the display window are cropped"
        ));
    }
    let x0 = data.min[0].max(display.min[0]);
    let x1 = data.max[0].min(display.max[0]);
    let y0 = data.min[1].max(display.min[1]);
    let y1 = data.max[1].min(display.max[1]);
    if x0 > x1 || y0 > y1 {
        notes.push(format!(
            "the data window {data} lies wholly outside the display window {display}: the \
             image is empty"
        ));
        return out;
    }
    let dw = data.width();
    let idx = |v: i32, o: i32| usize::try_from(i64::from(v) - i64::from(o)).unwrap_or(0);
    let run = idx(x1, x0) + 1;
    for y in y0..=y1 {
        let src = (idx(y, data.min[1]) * dw + idx(x0, data.min[0])) * channels;
        let dst = (idx(y, display.min[1]) * w + idx(x0, display.min[0])) * channels;
        out[dst..dst + run * channels].copy_from_slice(&values[src..src + run * channels]);
    }
    out
}
