//! Writing several images as the named layers of one EXR file, as Blender's multi-layer
//! EXR and Nuke's Write node do: one scan-line part whose channels are `layer.channel`
//! (the root layer's plain `R G B A`), each layer in half or float, one compression for
//! the part, the display window the image's (data window the same), and the
//! `chromaticities` of the working space, Rec. 709.

use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
use exr::math::Vec2;
use exr::meta::attribute::{Chromaticities as ExrChromaticities, IntegerBounds};
use exr::meta::header::{ImageAttributes, LayerAttributes};
use exr::prelude::WritableImage as _;

use crate::color::REC709;

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
    /// `width × height × channels.len()` values, interleaved, rows first.
    pub values: Vec<f32>,
    /// Written as halves (else 32-bit floats).
    pub half: bool,
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

/// The layers as one EXR file's bytes.
///
/// # Errors
/// Layers of the wrong size, two channels of one name, no channel at all, or what the
/// encoder refuses; the message says which.
pub fn encode_layers(
    width: usize,
    height: usize,
    layers: &[LayerOut],
    compression: Compression,
) -> Result<Vec<u8>, String> {
    let pixels = width * height;
    let mut list: exr::prelude::SmallVec<[AnyChannel<FlatSamples>; 4]> =
        exr::prelude::SmallVec::new();
    let mut names: Vec<String> = Vec::new();
    for layer in layers {
        let n = layer.channels.len();
        if n == 0 || layer.values.len() != pixels * n {
            return Err(format!(
                "layer {:?}: {} values for {n} channels of {width}×{height} pixels",
                layer.name,
                layer.values.len()
            ));
        }
        for (c, channel) in layer.channels.iter().enumerate() {
            let name = layer.full_name(channel);
            if names.contains(&name) {
                return Err(format!(
                    "two channels are named {name:?}: give the layers other names"
                ));
            }
            names.push(name.clone());
            let plane = layer.values.iter().skip(c).step_by(n).copied();
            let samples = if layer.half {
                FlatSamples::F16(plane.map(half::f16::from_f32).collect())
            } else {
                FlatSamples::F32(plane.collect())
            };
            list.push(AnyChannel::new(name.as_str(), samples));
        }
    }
    if list.is_empty() {
        return Err("no layer to write".into());
    }
    let size = Vec2(width, height);
    let mut attributes = ImageAttributes::new(IntegerBounds::from_dimensions(size));
    attributes.chromaticities = Some(ExrChromaticities {
        red: Vec2(REC709.red[0], REC709.red[1]),
        green: Vec2(REC709.green[0], REC709.green[1]),
        blue: Vec2(REC709.blue[0], REC709.blue[1]),
        white: Vec2(REC709.white[0], REC709.white[1]),
    });
    let encoding = Encoding {
        compression: compression.exr(),
        ..Encoding::SMALL_LOSSLESS
    };
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(list),
    );
    let image = Image::from_layers(attributes, vec![layer]);
    let mut out = Vec::new();
    image
        .write()
        .to_buffered(std::io::Cursor::new(&mut out))
        .map_err(|e| format!("cannot encode the EXR file: {e}"))?;
    Ok(out)
}
