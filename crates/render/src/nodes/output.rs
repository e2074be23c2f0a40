//! Output: copies its input to a readback buffer in the frame, then writes the file
//! ([`write_image`], also what tiled renders and tile merges write with).

use std::path::{Path, PathBuf};

use lumagraph_graph::{Extent, Pass, PortType, TexFormat, TextureId};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::nodes::{
    FrameIo, HeldImage, NodeExec, NodeImpl, Recording, Resources, boxed, check_writable,
};

/// The `Output` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("Output", |ctx, pass, resources| {
    boxed(Output::new(ctx, pass, resources))
});

pub(crate) struct Output {
    paths: Resources,
    staged: Option<Staged>,
}

/// A texture copied into a readback buffer in the frame, to be read after it.
pub(crate) struct Staged {
    buffer: wgpu::Buffer,
    padded_row: u32,
    format: TexFormat,
    ty: PortType,
    extent: Extent,
}

impl Staged {
    /// Records the copy of texture `id` into a buffer (`reuse`'s, when it is the size).
    pub(crate) fn record(
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        io: &FrameIo<'_>,
        id: TextureId,
        label: &str,
        reuse: Option<Self>,
    ) -> Self {
        let desc = &io.plan.textures[id.0];
        let texture = io.texture(id);
        let bpp = u32::try_from(desc.format.bytes_per_pixel()).unwrap_or(16);
        let padded_row =
            (desc.extent.width * bpp).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let size = u64::from(padded_row) * u64::from(desc.extent.height);
        let buffer = match reuse {
            Some(s) if s.buffer.size() == size => s.buffer,
            _ => ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        };
        encoder.copy_texture_to_buffer(
            texture.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: Some(desc.extent.height),
                },
            },
            texture.texture.size(),
        );
        Self {
            buffer,
            padded_row,
            format: desc.format,
            ty: desc.ty,
            extent: desc.extent,
        }
    }

    /// The copied image, once the frame is done.
    pub(crate) fn read(&self, ctx: &GpuContext) -> Result<HeldImage> {
        let row = self.extent.width as usize * self.format.bytes_per_pixel() as usize;
        let size = self.buffer.size();
        let bytes = crate::readback::map_read(ctx, &self.buffer, size, |b| {
            b.chunks_exact(self.padded_row as usize)
                .flat_map(|r| r[..row].to_vec())
                .collect::<Vec<u8>>()
        })?;
        Ok(HeldImage {
            bytes,
            format: self.format,
            ty: self.ty,
            extent: self.extent,
        })
    }
}

impl Output {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass, paths: &Resources) -> Result<Self> {
        let mut node = Self {
            paths: paths.clone(),
            staged: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }

    fn path(&self, pass: &Pass) -> Result<PathBuf> {
        output_path(pass, &self.paths)
    }
}

impl NodeExec for Output {
    fn update(&mut self, _ctx: &GpuContext, pass: &Pass) -> Result<()> {
        check_writable(&self.path(pass)?)
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, _) = rec.parts();
        let id = pass
            .input("color")
            .ok_or_else(|| RenderError::Gpu("input \"color\" is not bound".into()))?;
        self.staged = Some(Staged::record(
            ctx,
            encoder,
            io,
            id,
            &pass.node,
            self.staged.take(),
        ));
        Ok(())
    }

    fn held_image(&mut self, ctx: &GpuContext) -> Result<Option<HeldImage>> {
        self.staged.as_ref().map(|s| s.read(ctx)).transpose()
    }

    fn finish(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<Vec<PathBuf>> {
        let Some(image) = self.held_image(ctx)? else {
            return Ok(Vec::new());
        };
        let path = self.path(pass)?;
        write_image(&path, image.bytes, image.format, image.ty, image.extent)?;
        Ok(vec![path])
    }
}

/// The file an `Output` node writes of `pass` (its `path` param, relative to `out_dir`).
///
/// # Errors
/// A path that leaves the output folder ([`Resources::output`]).
pub(crate) fn output_path(pass: &Pass, resources: &Resources) -> Result<PathBuf> {
    resources.output(pass.params.str("path"))
}

/// Writes an image as an `Output` node does: `bytes` rows of `format` pixels holding a
/// `ty` image; PNG or EXR by the extension. `bytes` is dropped once converted, so a large
/// image is not held twice while it is encoded.
pub fn write_image(
    path: &Path,
    bytes: Vec<u8>,
    format: TexFormat,
    ty: PortType,
    extent: Extent,
) -> Result<()> {
    let is_png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if is_png && format == TexFormat::Rgba8Unorm {
        crate::image_io::write_png(path, extent.width, extent.height, &bytes)
    } else {
        let image = crate::readback::to_image(&bytes, format, extent);
        drop(bytes);
        crate::image_io::save(path, &image, ty != PortType::LdrColor)
    }
}
