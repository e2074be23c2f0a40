//! Writing EXR files as Blender's multi-layer EXR and Nuke's Write node do: scan-line parts
//! whose channels are `layer.channel` (the root layer's plain `R G B A`), each channel
//! half, float or uint, one compression for the file, a display window and per part a
//! data window, and the `chromaticities` of the working space (Rec. 709 unless a graph
//! chooses another). A part may carry the header attributes of the part it was read from
//! ([`super::Source`]).
//!
//! Values are exact where they can be: a half read by [`half_to_f32`] and written back by
//! [`f32_to_half`] keeps its bits, NaN payloads and signalling NaNs included; a uint is
//! written back as the whole number it was read as.

use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
use exr::math::Vec2;
use exr::meta::attribute::{Chromaticities as ExrChromaticities, IntegerBounds, Text};
use exr::meta::header::{ImageAttributes, LayerAttributes};
use exr::prelude::WritableImage as _;

use super::{SampleKind, Window};
use crate::color::{Chromaticities, REC709};

/// A compression EXR writers offer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// None.
    None,
    /// Run-length: lossless, fast, weak.
    Rle,
    /// Zip, one scan line a block: lossless.
    Zips,
    /// Zip, 16 scan lines a block: lossless, Blender's and Nuke's default.
    Zip,
    /// Wavelet: lossless, best on noisy renders.
    Piz,
    /// Lossy for floats (24-bit), lossless for halves.
    Pxr24,
}

impl Compression {
    /// The compression called `name` (the names of `MultiLayerOutput`'s `compression`
    /// param).
    pub fn named(name: &str) -> Option<Self> {
        Some(match name {
            "none" => Self::None,
            "rle" => Self::Rle,
            "zips" => Self::Zips,
            "zip" => Self::Zip,
            "piz" => Self::Piz,
            "pxr24" => Self::Pxr24,
            _ => return None,
        })
    }

    fn exr(self) -> exr::compression::Compression {
        use exr::compression::Compression as C;
        match self {
            Self::None => C::Uncompressed,
            Self::Rle => C::RLE,
            Self::Zips => C::ZIP1,
            Self::Zip => C::ZIP16,
            Self::Piz => C::PIZ,
            Self::Pxr24 => C::PXR24,
        }
    }
}

/// One layer to write.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerOut {
    /// Its name (`""`: the root layer, channels named `R`, `G`… alone).
    pub name: String,
    /// Its channels' names within the layer (`R G B A`, `X Y Z`, `Z`, `u v`).
    pub channels: Vec<String>,
    /// The data window's `width × height × channels.len()` values, interleaved, rows
    /// first.
    pub values: Vec<f32>,
    /// Each channel's sample type, in `channels`' order.
    pub samples: Vec<SampleKind>,
}

impl LayerOut {
    /// A channel's full name in the file.
    pub fn full_name(&self, channel: &str) -> String {
        if self.name.is_empty() {
            channel.to_owned()
        } else {
            format!("{}.{channel}", self.name)
        }
    }
}

/// The header attributes a part carries from the part it was read from, beside its
/// name, view and windows ([`super::Source::carried`]); by default none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartAttributes(pub(crate) Option<LayerAttributes>);

/// The header attributes every part of a file shares (pixel aspect ratio, time code and
/// the shared custom ones), carried from a source ([`super::Source::carried`]); by default
/// a pixel aspect ratio of 1 and nothing else.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileAttributes(pub(crate) Option<ImageAttributes>);

/// One part to write.
#[derive(Clone, Debug, PartialEq)]
pub struct PartOut {
    /// Its `name` attribute (a multi-part file names every part).
    pub name: Option<String>,
    /// Its `view` attribute.
    pub view: Option<String>,
    /// Where its pixels are, in the display window's coordinates.
    pub data_window: Window,
    /// Its layers, each with the data window's values.
    pub layers: Vec<LayerOut>,
    /// What it carries from its source.
    pub attributes: PartAttributes,
}

/// A file to write.
#[derive(Clone, Debug, PartialEq)]
pub struct FileOut {
    /// The image's frame.
    pub display_window: Window,
    /// Its parts, in order (one: a single-part file).
    pub parts: Vec<PartOut>,
    /// The compression of every part.
    pub compression: Compression,
    /// What every part's header shares.
    pub attributes: FileAttributes,
    /// The `chromaticities` written: the working space's primaries and white.
    pub chromaticities: Chromaticities,
}

/// A half's bits as an `f32`, exactly: a NaN keeps its sign, payload and signalling bit
/// (the `half` crate's conversion makes every NaN quiet).
pub fn half_to_f32(bits: u16) -> f32 {
    if bits & 0x7C00 == 0x7C00 && bits & 0x03FF != 0 {
        let sign = u32::from(bits & 0x8000) << 16;
        f32::from_bits(sign | 0x7F80_0000 | (u32::from(bits & 0x03FF) << 13))
    } else {
        half::f16::from_bits(bits).to_f32()
    }
}

/// An `f32` as a half's bits, rounded to the nearest half; a NaN keeps its sign and the
/// top ten bits of its payload, so [`half_to_f32`]'s NaNs come back bit for bit.
pub fn f32_to_half(v: f32) -> u16 {
    if v.is_nan() {
        let b = v.to_bits();
        let sign = u16::try_from((b >> 16) & 0x8000).unwrap_or(0);
        let payload = u16::try_from((b >> 13) & 0x03FF).unwrap_or(0);
        sign | 0x7C00 | if payload == 0 { 0x0200 } else { payload }
    } else {
        half::f16::from_f32(v).to_bits()
    }
}

/// An `f32` as a uint sample: whole numbers in range exactly; others rounded and clamped
/// (NaN as 0), counted in `changed`.
fn to_uint(v: f32, changed: &mut usize) -> u32 {
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "clamped to u32's range first; `as` saturates and maps NaN to 0"
    )]
    let u = v.round().clamp(0.0, 4_294_967_295.0) as u32;
    #[expect(clippy::cast_precision_loss, reason = "compared as f32 on purpose")]
    if u as f32 != v {
        *changed += 1;
    }
    u
}

/// The layers as one single-part EXR file's bytes: `width × height` pixels, the data
/// window the display window, at the origin.
///
/// # Errors
/// As [`encode`].
pub fn encode_layers(
    width: usize,
    height: usize,
    layers: &[LayerOut],
    compression: Compression,
) -> Result<Vec<u8>, String> {
    let window = Window::at([0, 0], [width, height]);
    let file = FileOut {
        display_window: window,
        parts: vec![PartOut {
            name: None,
            view: None,
            data_window: window,
            layers: layers.to_vec(),
            attributes: PartAttributes::default(),
        }],
        compression,
        attributes: FileAttributes::default(),
        chromaticities: REC709,
    };
    encode(&file).map(|(bytes, _)| bytes)
}

/// The channels of one part, each plane's samples in its type; notes uint values
/// rounded.
fn channels_of(
    part: &PartOut,
    notes: &mut Vec<String>,
) -> Result<exr::prelude::SmallVec<[AnyChannel<FlatSamples>; 4]>, String> {
    let pixels = part.data_window.width() * part.data_window.height();
    let mut list: exr::prelude::SmallVec<[AnyChannel<FlatSamples>; 4]> =
        exr::prelude::SmallVec::new();
    let mut names: Vec<String> = Vec::new();
    for layer in &part.layers {
        let n = layer.channels.len();
        if n == 0 || layer.values.len() != pixels * n || layer.samples.len() != n {
            return Err(format!(
                "layer {:?}: {} values and {} sample types for {n} channels of {}×{} pixels",
                layer.name,
                layer.values.len(),
                layer.samples.len(),
                part.data_window.width(),
                part.data_window.height()
            ));
        }
        for (c, channel) in layer.channels.iter().enumerate() {
            let name = layer.full_name(channel);
            if names.contains(&name) {
                return Err(format!(
                    "two channels are named {name:?}: give the layers other names"
                ));
            }
            if Text::new_or_none(name.as_str()).is_none() {
                return Err(format!("the channel name {name:?} is not one EXR can hold"));
            }
            names.push(name.clone());
            let plane = layer.values.iter().skip(c).step_by(n).copied();
            let samples = match layer.samples[c] {
                SampleKind::Half => FlatSamples::F16(
                    plane
                        .map(|v| half::f16::from_bits(f32_to_half(v)))
                        .collect(),
                ),
                SampleKind::Float => FlatSamples::F32(plane.collect()),
                SampleKind::Uint => {
                    let mut changed = 0;
                    let samples = plane.map(|v| to_uint(v, &mut changed)).collect();
                    if changed > 0 {
                        notes.push(format!(
                            "channel {name:?} is uint: {changed} values that were not whole \
                             numbers from 0 to 2^32 − 1 were rounded and clamped"
                        ));
                    }
                    FlatSamples::U32(samples)
                }
            };
            list.push(AnyChannel::new(name.as_str(), samples));
        }
    }
    if list.is_empty() {
        return Err("no layer to write".into());
    }
    Ok(list)
}

fn bounds(w: Window) -> IntegerBounds {
    IntegerBounds::new(Vec2(w.min[0], w.min[1]), Vec2(w.width(), w.height()))
}

/// The file's bytes, and what a user should know of them (uint values rounded).
///
/// # Errors
/// No part or an empty window, layers of the wrong size, two channels or parts of one
/// name, a multi-part file with an unnamed part, or what the encoder refuses; the message
/// says which.
pub fn encode(file: &FileOut) -> Result<(Vec<u8>, Vec<String>), String> {
    if file.parts.is_empty() {
        return Err("no part to write".into());
    }
    if file.display_window.width() == 0 || file.display_window.height() == 0 {
        return Err(format!(
            "the display window {} is empty",
            file.display_window
        ));
    }
    let mut notes = Vec::new();
    let mut layers = Vec::new();
    let mut part_names: Vec<&str> = Vec::new();
    for part in &file.parts {
        let window = part.data_window;
        if window.width() == 0 || window.height() == 0 {
            return Err(format!("the data window {window} is empty"));
        }
        match &part.name {
            Some(name) if part_names.contains(&name.as_str()) => {
                return Err(format!("two parts are named {name:?}"));
            }
            Some(name) => part_names.push(name),
            None if file.parts.len() > 1 => {
                return Err("every part of a multi-part file needs a name".into());
            }
            None => {}
        }
        let channels = channels_of(part, &mut notes)?;
        let mut attributes = part.attributes.0.clone().unwrap_or_default();
        attributes.layer_name = part.name.as_deref().and_then(Text::new_or_none);
        attributes.view_name = part.view.as_deref().and_then(Text::new_or_none);
        attributes.layer_position = Vec2(window.min[0], window.min[1]);
        let encoding = Encoding {
            compression: file.compression.exr(),
            ..Encoding::SMALL_LOSSLESS
        };
        layers.push(Layer::new(
            Vec2(window.width(), window.height()),
            attributes,
            encoding,
            AnyChannels::sort(channels),
        ));
    }
    let mut attributes = file
        .attributes
        .0
        .clone()
        .unwrap_or_else(|| ImageAttributes::new(bounds(file.display_window)));
    attributes.display_window = bounds(file.display_window);
    let c = file.chromaticities;
    attributes.chromaticities = Some(ExrChromaticities {
        red: Vec2(c.red[0], c.red[1]),
        green: Vec2(c.green[0], c.green[1]),
        blue: Vec2(c.blue[0], c.blue[1]),
        white: Vec2(c.white[0], c.white[1]),
    });
    let image = Image::from_layers(attributes, layers);
    let mut out = Vec::new();
    image
        .write()
        .to_buffered(std::io::Cursor::new(&mut out))
        .map_err(|e| format!("cannot encode the EXR file: {e}"))?;
    Ok((out, notes))
}

#[cfg(test)]
mod tests {
    use super::{f32_to_half, half_to_f32};

    #[test]
    fn every_half_comes_back_bit_for_bit() {
        for bits in 0..=u16::MAX {
            assert_eq!(f32_to_half(half_to_f32(bits)), bits, "{bits:#06x}");
        }
    }

    #[test]
    fn floats_round_to_the_nearest_half() {
        assert_eq!(f32_to_half(1.0), 0x3C00);
        assert_eq!(f32_to_half(65520.0), 0x7C00);
        assert_eq!(f32_to_half(-0.0), 0x8000);
        assert!(half_to_f32(f32_to_half(f32::NAN)).is_nan());
    }
}
