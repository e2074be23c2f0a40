//! Image files: EXR, Radiance HDR, PNG and JPEG in; PNG (8-bit sRGB) and EXR (float RGBA)
//! out. Every write goes to a temporary file that is renamed over the target, so a
//! failed or interrupted write never leaves a truncated image.

use std::io::Cursor;
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};

use lumagraph_footage::exr::{self as footage, LayerImage, Selection, Want};
use lumagraph_graph::{Extent, write_atomic};

use crate::cpu::{Image, srgb_decode, srgb_encode, to_u8};
use crate::error::{RenderError, Result};

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// The file is there and is a regular file (a device or a pipe would be read without end).
fn check_exists(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(_) => Err(RenderError::image(
            path,
            "cannot open image: not a regular file (a folder, a device or a pipe)",
        )),
        Err(e) => Err(RenderError::image(path, format!("cannot open image: {e}"))),
    }
}

/// The size of an image file, read from its header only.
///
/// # Errors
/// When the file is missing, unreadable or not an image of a known format.
pub fn dimensions(path: &Path) -> Result<Extent> {
    check_exists(path)?;
    match extension(path).as_str() {
        "exr" => exr_extent(path, &Selection::default()),
        "hdr" | "png" | "jpg" | "jpeg" => image::image_dimensions(path)
            .map(|(w, h)| Extent::new(w, h))
            .map_err(|e| RenderError::image(path, format!("not a readable image: {e}"))),
        other => Err(RenderError::image(
            path,
            format!("unsupported image extension \".{other}\" (use .exr, .hdr, .png, .jpg)"),
        )),
    }
}

/// Loads an image as linear RGBA floats: EXR and HDR as stored, 8- and 16-bit formats
/// decoded from sRGB.
///
/// # Errors
/// When the file is missing, unreadable, corrupt or of an unknown format.
pub fn load(path: &Path) -> Result<Image> {
    check_exists(path)?;
    match extension(path).as_str() {
        "exr" => load_exr(path),
        "hdr" => {
            let img = image::open(path)
                .map_err(|e| RenderError::image(path, format!("not a readable image: {e}")))?;
            let rgba = img.to_rgba32f();
            Ok(Image {
                width: rgba.width(),
                height: rgba.height(),
                pixels: rgba.pixels().map(|p| p.0).collect(),
            })
        }
        "png" | "jpg" | "jpeg" => {
            let img = image::open(path)
                .map_err(|e| RenderError::image(path, format!("not a readable image: {e}")))?;
            let rgba = img.to_rgba32f();
            Ok(Image {
                width: rgba.width(),
                height: rgba.height(),
                pixels: rgba
                    .pixels()
                    .map(|p| {
                        [
                            srgb_decode(p.0[0]),
                            srgb_decode(p.0[1]),
                            srgb_decode(p.0[2]),
                            p.0[3],
                        ]
                    })
                    .collect(),
            })
        }
        other => Err(RenderError::image(
            path,
            format!("unsupported image extension \".{other}\" (use .exr, .hdr, .png, .jpg)"),
        )),
    }
}

/// The most pixels an EXR part may have (16384 × 16384, the largest image devices hold):
/// readers allocate a part whole from its header's size, so a corrupt size would otherwise
/// ask for terabytes and abort the process.
pub const MAX_EXR_PIXELS: u64 = lumagraph_footage::exr::MAX_PIXELS;

/// The size of an EXR layer's image: its part's display window.
///
/// # Errors
/// What [`lumagraph_footage::exr::inspect`] refuses; a selection that names no layer.
pub fn exr_extent(path: &Path, selection: &Selection) -> Result<Extent> {
    let info = footage::inspect(path).map_err(footage_error)?;
    let layer = selection
        .find(&info)
        .map_err(|e| RenderError::image(path, e))?;
    let window = info.parts[layer.part].display_window;
    Ok(Extent::new(
        u32::try_from(window.width()).unwrap_or(u32::MAX),
        u32::try_from(window.height()).unwrap_or(u32::MAX),
    ))
}

/// Reads an EXR layer as `want` into its display window (see
/// [`lumagraph_footage::exr::read_layer`]).
///
/// # Errors
/// What the reader refuses, with the file named.
pub fn load_exr_layer(path: &Path, selection: &Selection, want: Want) -> Result<LayerImage> {
    footage::read_layer(path, selection, want).map_err(footage_error)
}

/// What each image-file source of a graph read, by node and output port: the layer, its
/// part and header ([`footage::Source`]), recorded when the node loads a file, for the
/// sinks downstream to write it back as it was (`Output`, `MultiLayerOutput`). Shared by
/// the nodes of an executor through [`crate::Resources`].
#[derive(Clone, Debug, Default)]
pub struct Sources(Arc<Mutex<Vec<SourceEntry>>>);

/// A node, one of its output ports, and what the port holds.
type SourceEntry = (String, String, Arc<footage::Source>);

impl Sources {
    fn entries(&self) -> std::sync::MutexGuard<'_, Vec<SourceEntry>> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Records what `node`'s `port` holds: the layer `selection` names of the EXR file at
    /// `path`, read as `want`; nothing for another kind of file (or one whose header
    /// cannot be read, which the load has reported).
    pub fn record(&self, node: &str, port: &str, path: &Path, selection: &Selection, want: Want) {
        let source = extension(path)
            .eq("exr")
            .then(|| {
                let info = footage::inspect(path).ok()?;
                let layer = selection.find(&info).ok()?;
                footage::Source::of(path, &layer, want).ok()
            })
            .flatten();
        let mut entries = self.entries();
        entries.retain(|(n, p, _)| !(n == node && p == port));
        if let Some(source) = source {
            entries.push((node.to_owned(), port.to_owned(), Arc::new(source)));
        }
    }

    /// What `node`'s `port` holds, if it was read from an EXR file.
    pub fn get(&self, node: &str, port: &str) -> Option<Arc<footage::Source>> {
        self.entries()
            .iter()
            .find(|(n, p, _)| n == node && p == port)
            .map(|(_, _, s)| Arc::clone(s))
    }
}

fn footage_error(e: footage::Error) -> RenderError {
    RenderError::image(&e.path, e.message)
}

fn load_exr(path: &Path) -> Result<Image> {
    let layer = load_exr_layer(path, &Selection::default(), Want::Rgba)?;
    Ok(Image {
        width: u32::try_from(layer.width()).unwrap_or(0),
        height: u32::try_from(layer.height()).unwrap_or(0),
        pixels: layer
            .pixels
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect(),
    })
}

/// Encodes 8-bit RGBA rows as PNG bytes.
///
/// # Errors
/// When encoding fails.
pub fn encode_png(width: u32, height: u32, rgba8: &[u8]) -> Result<Vec<u8>> {
    if rgba8.len() as u64 != u64::from(width) * u64::from(height) * 4 {
        return Err(RenderError::image(
            Path::new("<png>"),
            format!(
                "{} bytes do not make a {width}x{height} RGBA image",
                rgba8.len()
            ),
        ));
    }
    let mut out = Vec::new();
    image::write_buffer_with_format(
        &mut Cursor::new(&mut out),
        rgba8,
        width,
        height,
        image::ExtendedColorType::Rgba8,
        image::ImageFormat::Png,
    )
    .map_err(|e| RenderError::image(Path::new("<png>"), e))?;
    Ok(out)
}

/// Encodes an image as EXR bytes: 32-bit float RGBA, or half floats when `half` is set;
/// ZIP-compressed, its `chromaticities` Rec. 709 (the one EXR writer,
/// [`lumagraph_footage::exr::encode_layers`], with the image as the root layer).
///
/// # Errors
/// When encoding fails.
pub fn encode_exr(image: &Image, half: bool) -> Result<Vec<u8>> {
    let layer = footage::LayerOut {
        name: String::new(),
        channels: ["R", "G", "B", "A"].map(str::to_owned).to_vec(),
        values: image.pixels.iter().flatten().copied().collect(),
        samples: vec![
            if half {
                footage::SampleKind::Half
            } else {
                footage::SampleKind::Float
            };
            4
        ],
    };
    footage::encode_layers(
        image.width as usize,
        image.height as usize,
        &[layer],
        footage::Compression::Zip,
    )
    .map_err(|e| RenderError::image(Path::new("<exr>"), e))
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, bytes).map_err(|e| RenderError::image(path, format!("cannot write: {e}")))
}

/// Writes 8-bit RGBA (already display-encoded) as a PNG file, atomically.
///
/// # Errors
/// When the file cannot be written.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<()> {
    write(path, &encode_png(width, height, rgba8)?)
}

/// 8-bit RGBA texels as a PNG stores them: color sRGB-encoded first when `linear` is set,
/// then every channel clipped to [0, 1] and rounded; alpha as it is.
pub fn to_rgba8(image: &Image, linear: bool) -> Vec<u8> {
    let encode = |x: f32| if linear { srgb_encode(x) } else { x };
    image
        .pixels
        .iter()
        .flat_map(|p| {
            [
                to_u8(encode(p[0])),
                to_u8(encode(p[1])),
                to_u8(encode(p[2])),
                to_u8(p[3]),
            ]
        })
        .collect()
}

/// Writes an image to a file chosen by extension, atomically: `.exr` as 32-bit float RGBA
/// as it is; `.png` as 8-bit, sRGB-encoding the values first when `linear` is set.
///
/// # Errors
/// When the extension is unknown or the file cannot be written.
pub fn save(path: &Path, image: &Image, linear: bool) -> Result<()> {
    match extension(path).as_str() {
        "exr" => write(path, &encode_exr(image, false)?),
        "png" => write_png(path, image.width, image.height, &to_rgba8(image, linear)),
        other => Err(RenderError::image(
            path,
            format!("unsupported output extension \".{other}\" (use .png or .exr)"),
        )),
    }
}

/// The HDR test chart shipped as `assets/test_chart.exr`, 512×256, generated so the
/// project owns it:
/// - rows 0–63: a neutral ramp from 2^-10 to 2^6, exponential in x;
/// - rows 64–127: a fully saturated hue sweep at luminance-independent value 1;
/// - rows 128–191: the same hue sweep fading from 2^-4 (left) to 2^4 (right);
/// - rows 192–255: 17 patches, −8 to +8 EV around 0.18 grey.
pub fn test_chart() -> Image {
    let (w, h) = (512_u32, 256_u32);
    let mut img = Image::filled(w, h, [0.0, 0.0, 0.0, 1.0]);
    #[expect(clippy::cast_precision_loss, reason = "small integers")]
    for y in 0..h {
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            let rgb = match y / 64 {
                0 => [(u * 16.0 - 10.0).exp2(); 3],
                1 => hue(u),
                2 => hue(u).map(|c| c * (u * 8.0 - 4.0).exp2()),
                _ => {
                    let patch = (u * 17.0).floor().min(16.0);
                    [0.18 * (patch - 8.0).exp2(); 3]
                }
            };
            img.pixels[(y * w + x) as usize] = [rgb[0], rgb[1], rgb[2], 1.0];
        }
    }
    img
}

fn hue(u: f32) -> [f32; 3] {
    let f = |n: f32| {
        let k = (n + u * 6.0) % 6.0;
        1.0 - (k.min(4.0 - k).clamp(0.0, 1.0))
    };
    [f(5.0), f(3.0), f(1.0)]
}
