//! `ImageInput`: an image file, uploaded once, copied into the frame's texture each frame.

use std::path::PathBuf;

use lumagraph_graph::{Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::Result;
use crate::nodes::{NodeExec, NodeImpl, Recording, Resources, boxed};
use crate::pool::{PooledTexture, create};

/// The `ImageInput` kind: its size is the image file's.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("ImageInput", |ctx, pass, resources| {
    boxed(ImageInput::new(ctx, pass, resources))
})
.sized_by(|base_dir, params| {
    crate::image_io::dimensions(&base_dir.join(params.str("path"))).map_err(|e| e.to_string())
});

pub(crate) struct ImageInput {
    paths: Resources,
    loaded: Option<(PathBuf, PooledTexture)>,
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
    let extent = lumagraph_graph::Extent::new(image.width, image.height);
    let texture = create(ctx, label, TexFormat::Rgba32Float, extent);
    ctx.queue.write_texture(
        texture.texture.as_image_copy(),
        bytemuck::cast_slice(&image.pixels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(image.width * 16),
            rows_per_image: Some(image.height),
        },
        texture.texture.size(),
    );
    texture
}

impl NodeExec for ImageInput {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let path = self.paths.input(pass.params.str("path"));
        if self.loaded.as_ref().is_some_and(|(p, _)| *p == path) {
            return Ok(());
        }
        let image = crate::image_io::load(&path)?;
        let texture = upload(ctx, &pass.node, &image);
        self.loaded = Some((path, texture));
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (_, encoder, io, _) = rec.parts();
        let (Some(out), Some((_, src))) = (pass.output("color"), &self.loaded) else {
            return Ok(());
        };
        let dst = io.texture(out);
        let size = src.texture.size();
        if dst.texture.size() != size {
            return Err(crate::error::RenderError::Gpu(format!(
                "the image changed size since the graph was compiled ({}x{} now): recompile",
                size.width, size.height
            )));
        }
        encoder.copy_texture_to_texture(
            src.texture.as_image_copy(),
            dst.texture.as_image_copy(),
            size,
        );
        Ok(())
    }
}
