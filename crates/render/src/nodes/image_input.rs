//! `ImageInput`: an image file (an EXR layer of it), uploaded once, copied into the
//! frame's textures each frame.

use std::path::{Path, PathBuf};

use lumagraph_footage::exr::{Selection, Want};
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

/// What was loaded (path and selection) and a texture per bound port.
struct Loaded {
    path: PathBuf,
    selection: Selection,
    textures: Vec<(&'static str, PooledTexture)>,
}

impl ImageInput {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass, paths: &Resources) -> Result<Self> {
        let mut node = Self {
            paths: paths.clone(),
            loaded: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
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
    selection: &Selection,
    want: Want,
) -> Result<PooledTexture> {
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
    let layer = crate::image_io::load_exr_layer(path, selection, want)?;
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
        if self
            .loaded
            .as_ref()
            .is_some_and(|l| l.path == path && l.selection == selection)
        {
            return Ok(());
        }
        let mut textures = Vec::new();
        for (port, want) in PORTS {
            if pass.output(port).is_some() {
                textures.push((port, load(ctx, &pass.node, &path, &selection, want)?));
            }
        }
        self.loaded = Some(Loaded {
            path,
            selection,
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
