//! `ImageInput`: an image file (an EXR layer of it), uploaded once, copied into the
//! frame's textures each frame.

use std::path::{Path, PathBuf};

use lumagraph_footage::exr::{Primaries, Selection, Want};
use lumagraph_graph::{Extent, Params, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::nodes::{NodeExec, NodeImpl, Recording, Resources, boxed};
use crate::pool::{PooledTexture, create};

/// The `ImageInput` kind: its size is the image file's (an EXR's display window).
pub(crate) const IMPL: NodeImpl = NodeImpl::new("ImageInput", |ctx, pass, resources| {
    boxed(ImageInput::new(ctx, pass, resources))
})
.sized_by(|base_dir, params| {
    source_extent(&base_dir.join(params.str("path")), params).map_err(|e| e.to_string())
});

/// The output ports, each with what it reads a layer as.
const PORTS: [(&str, Want); 3] = [
    ("color", Want::Rgba),
    ("scalar", Want::Scalar),
    ("vector", Want::Vector),
];

fn selection(params: &Params) -> Selection {
    Selection {
        layer: params.str("layer").to_owned(),
        view: params.str("view").to_owned(),
    }
}

fn is_exr(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// The size of the image `params` choose in the file at `path`.
fn source_extent(path: &Path, params: &Params) -> Result<Extent> {
    let selection = selection(params);
    if lumagraph_footage::sequence::has_pattern(&path.to_string_lossy()) && !path.is_file() {
        return Err(RenderError::image(
            path,
            "the path holds a frame number pattern (`####`, `%04d`, `$F4`): render it with \
             `--frames`, which puts each frame's number in",
        ));
    }
    if is_exr(path) {
        crate::image_io::exr_extent(path, &selection)
    } else {
        not_exr_selection(path, &selection)?;
        crate::image_io::dimensions(path)
    }
}

/// A layer or view given for a file that has none is an error, not ignored.
fn not_exr_selection(path: &Path, selection: &Selection) -> Result<()> {
    if selection.layer.is_empty() && selection.view.is_empty() {
        return Ok(());
    }
    Err(RenderError::image(
        path,
        "only EXR files have layers and views: leave `layer` and `view` empty",
    ))
}

pub(crate) struct ImageInput {
    paths: Resources,
    loaded: Option<Loaded>,
}

/// What was loaded (path, selection, colour space) and a texture per bound port.
struct Loaded {
    path: PathBuf,
    selection: Selection,
    colorspace: ColorSource,
    textures: Vec<(&'static str, PooledTexture)>,
}

/// Where the colour of the file comes from: the file itself, or a colour space of an
/// OpenColorIO config.
#[derive(Clone, Debug, PartialEq, Eq)]
struct ColorSource {
    /// The `colorspace` param: empty for the file's own.
    space: String,
    /// The `config` param.
    config: String,
}

impl ColorSource {
    fn of(params: &Params) -> Self {
        Self {
            space: params.str("colorspace").trim().to_owned(),
            config: params.str("config").to_owned(),
        }
    }

    /// Whether the file is read as stored, for OpenColorIO to convert.
    fn named(&self) -> bool {
        !self.space.is_empty()
    }
}

/// The keyword of `colorspace` that lets the config's file rules choose.
const FILE_RULES: &str = "file rules";

impl ImageInput {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass, paths: &Resources) -> Result<Self> {
        let mut node = Self {
            paths: paths.clone(),
            loaded: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }

    /// How the file's colour reaches the graph's working space: whether it is read as
    /// stored (else converted to Rec. 709 by the reader, from an EXR's `chromaticities`
    /// with OpenEXR's matrices, or a PNG's sRGB), and the colour space OpenColorIO then
    /// converts it from (none: it is in the working space already). A named colour space
    /// is read as stored and converted. An EXR tagged with the primaries and white of an
    /// ACES space (ACEScg's AP1, ACES2065-1's AP0) is read as stored and, unless that is
    /// the working space, converted by OpenColorIO (with its chromatic adaptation, as ACES
    /// pipelines convert, so that a file an ACEScg graph writes reads back the same in a
    /// Rec. 709 one). Anything else in a Rec. 709 graph is the reader's Rec. 709; in
    /// another, converted from it.
    fn color_route(
        &self,
        path: &Path,
        selection: &Selection,
        colorspace: &ColorSource,
    ) -> (bool, Option<ColorSource>) {
        use lumagraph_graph::WorkingSpace;
        let working = self.paths.working_space;
        let from = |space: &str| ColorSource {
            space: space.to_owned(),
            config: lumagraph_graph::working_space::CONVERSION_CONFIG.to_owned(),
        };
        if colorspace.named() {
            return (true, Some(colorspace.clone()));
        }
        match aces_tag(path, selection) {
            Some(space) if space == working.ocio_names()[0] => return (true, None),
            Some(space) => return (true, Some(from(space))),
            None => {}
        }
        if working == WorkingSpace::Rec709 {
            return (false, None);
        }
        (false, Some(from(WorkingSpace::Rec709.ocio_names()[0])))
    }

    /// Converts `texture` (the file's colour as stored) from the colour space `source`
    /// names into the working space, on the GPU, once.
    fn convert(
        &self,
        ctx: &GpuContext,
        node: &str,
        path: &Path,
        source: &ColorSource,
        texture: PooledTexture,
    ) -> Result<PooledTexture> {
        let config = super::ocio::config_for(&source.config, &self.paths)
            .map_err(|e| RenderError::image(path, e.0))?;
        let space = if source.space.eq_ignore_ascii_case(FILE_RULES) {
            config.color_space_from_filepath(&path.to_string_lossy())
        } else {
            source.space.clone()
        };
        let processor = config
            .processor(&space, config.working_space())
            .map_err(|e| RenderError::image(path, format!("colorspace: {}", e.0)))?;
        eprintln!(
            "{node}: {}: colour read as {space:?}, converted to {:?} ({})",
            path.display(),
            config.working_space(),
            config.source
        );
        if processor.is_no_op() {
            return Ok(texture);
        }
        let size = texture.texture.size();
        let extent = Extent::new(size.width, size.height);
        let out = create(ctx, node, TexFormat::Rgba32Float, extent);
        let program = super::ocio::Built::new(ctx, node, &processor, "rgba32float")?;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(node) });
        program.encode(
            ctx,
            &mut encoder,
            node,
            (&texture.view, &out.view),
            extent,
            None,
        )?;
        ctx.queue.submit(Some(encoder.finish()));
        Ok(out)
    }
}

/// The primaries and white (an EXR `chromaticities` attribute) of the ACES spaces, with
/// their names in OpenColorIO's CG config.
const ACES_TAGS: [([f32; 8], &str); 2] = [
    (
        [0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767],
        "ACEScg",
    ),
    (
        [0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767],
        "ACES2065-1",
    ),
];

/// The ACES space whose primaries and white the EXR layer's part is tagged with, if any.
fn aces_tag(path: &Path, selection: &Selection) -> Option<&'static str> {
    if !is_exr(path) {
        return None;
    }
    let info = lumagraph_footage::exr::inspect(path).ok()?;
    let layer = selection.find(&info).ok()?;
    let tag = info.parts[layer.part].chromaticities?.to_array();
    ACES_TAGS
        .iter()
        .find(|(c, _)| c.iter().zip(tag).all(|(a, b)| (a - b).abs() < 1e-4))
        .map(|(_, name)| *name)
}

/// An 8-bit or HDR image as stored, without decoding sRGB (a named colour space does).
fn load_as_stored(path: &Path) -> Result<crate::cpu::Image> {
    if !path.is_file() {
        return crate::image_io::load(path);
    }
    let img = image::open(path)
        .map_err(|e| RenderError::image(path, format!("not a readable image: {e}")))?;
    let rgba = img.to_rgba32f();
    Ok(crate::cpu::Image {
        width: rgba.width(),
        height: rgba.height(),
        pixels: rgba.pixels().map(|p| p.0).collect(),
    })
}

/// Uploads an image into a new RGBA32F texture.
pub(crate) fn upload(ctx: &GpuContext, label: &str, image: &crate::cpu::Image) -> PooledTexture {
    upload_floats(
        ctx,
        label,
        TexFormat::Rgba32Float,
        Extent::new(image.width, image.height),
        bytemuck::cast_slice(&image.pixels),
    )
}

/// Uploads `values` (4 floats a pixel for RGBA32F, 1 for R32F) into a new texture.
fn upload_floats(
    ctx: &GpuContext,
    label: &str,
    format: TexFormat,
    extent: Extent,
    values: &[f32],
) -> PooledTexture {
    let texture = create(ctx, label, format, extent);
    let bytes_per_pixel = u32::try_from(format.bytes_per_pixel()).unwrap_or(16);
    ctx.queue.write_texture(
        texture.texture.as_image_copy(),
        bytemuck::cast_slice(values),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(extent.width * bytes_per_pixel),
            rows_per_image: Some(extent.height),
        },
        texture.texture.size(),
    );
    texture
}

/// Reads the file as `want` and uploads it; prints what the reader notes.
fn load(
    ctx: &GpuContext,
    node: &str,
    path: &Path,
    (selection, as_stored): (&Selection, bool),
    want: Want,
) -> Result<PooledTexture> {
    if !is_exr(path) && as_stored {
        not_exr_selection(path, selection)?;
        return Ok(upload(ctx, node, &load_as_stored(path)?));
    }
    if !is_exr(path) {
        not_exr_selection(path, selection)?;
        if want != Want::Rgba {
            return Err(RenderError::image(
                path,
                format!(
                    "a PNG, JPEG or HDR image is colour: read it on `color`, not `{}`",
                    want.port()
                ),
            ));
        }
        return Ok(upload(ctx, node, &crate::image_io::load(path)?));
    }
    let primaries = if as_stored {
        Primaries::AsStored
    } else {
        Primaries::Rec709
    };
    let layer = lumagraph_footage::exr::read_layer_in(path, selection, want, primaries)
        .map_err(|e| RenderError::image(&e.path, e.message))?;
    for note in &layer.notes {
        eprintln!("{node}: {}: {note}", path.display());
    }
    let extent = Extent::new(
        u32::try_from(layer.width()).unwrap_or(0),
        u32::try_from(layer.height()).unwrap_or(0),
    );
    let format = if layer.channels == 1 {
        TexFormat::R32Float
    } else {
        TexFormat::Rgba32Float
    };
    Ok(upload_floats(ctx, node, format, extent, &layer.pixels))
}

impl NodeExec for ImageInput {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let path = self.paths.input(pass.params.str("path"));
        let selection = selection(&pass.params);
        let colorspace = ColorSource::of(&pass.params);
        if self.loaded.as_ref().is_some_and(|l| {
            l.path == path && l.selection == selection && l.colorspace == colorspace
        }) {
            return Ok(());
        }
        let mut textures = Vec::new();
        for (port, want) in PORTS {
            if pass.output(port).is_some() {
                let (as_stored, conversion) = if want == Want::Rgba {
                    self.color_route(&path, &selection, &colorspace)
                } else {
                    (false, None)
                };
                let mut texture = load(ctx, &pass.node, &path, (&selection, as_stored), want)?;
                if let Some(from) = &conversion {
                    texture = self.convert(ctx, &pass.node, &path, from, texture)?;
                }
                // What the port holds, for the sinks that write it back.
                let sources = &self.paths.sources;
                sources.record(&pass.node, port, &path, &selection, want);
                textures.push((port, texture));
            }
        }
        self.loaded = Some(Loaded {
            path,
            selection,
            colorspace,
            textures,
        });
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (_, encoder, io, _) = rec.parts();
        let Some(loaded) = &self.loaded else {
            return Ok(());
        };
        for (port, src) in &loaded.textures {
            let Some(out) = pass.output(port) else {
                continue;
            };
            let dst = io.texture(out);
            let size = src.texture.size();
            if dst.texture.size() != size {
                return Err(RenderError::Gpu(format!(
                    "the image changed size since the graph was compiled ({}x{} now): recompile",
                    size.width, size.height
                )));
            }
            encoder.copy_texture_to_texture(
                src.texture.as_image_copy(),
                dst.texture.as_image_copy(),
                size,
            );
        }
        Ok(())
    }
}
