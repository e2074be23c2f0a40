//! Output: copies its input to a readback buffer in the frame, then writes the file
//! ([`write_image`], also what tiled renders and tile merges write with). An EXR is
//! written as the layer its input was read as, when it was read from one
//! ([`crate::image_io::Sources`]): its names, windows, types and attributes.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use lumagraph_footage::color as footage_color;
use lumagraph_footage::exr::{self as footage, ImageIn, Source, TypeChoice, Want, WindowChoice};
use lumagraph_graph::{Extent, Pass, Plan, PortType, TexFormat, TextureId, write_atomic};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::nodes::{
    FrameIo, HeldImage, NodeExec, NodeImpl, Recording, Resources, Sink, boxed, check_writable,
};

/// The `Output` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("Output", |ctx, pass, resources| {
    boxed(Output::new(ctx, pass, resources))
});

pub(crate) struct Output {
    paths: Resources,
    staged: Option<Staged>,
    /// The ports its input came through, nearest first ([`upstream`]).
    upstream: Vec<(String, &'static str)>,
    /// The notes printed last, so a sequence prints each once.
    said: Vec<String>,
}

/// The output ports an image came through before reaching texture `id`, nearest first:
/// the port that wrote it, then the port that wrote that pass's first input, and so on
/// up to a pass without inputs. A node passes on its first input's source, as Nuke's
/// nodes pass on their first input's metadata.
pub(crate) fn upstream(plan: &Plan, mut id: TextureId) -> Vec<(String, &'static str)> {
    let mut ports = Vec::new();
    for _ in 0..=plan.passes.len() {
        let Some(pass) = plan
            .textures
            .get(id.0)
            .and_then(|t| plan.passes.get(t.first))
        else {
            break;
        };
        let Some((port, _)) = pass.outputs.iter().find(|(_, t)| *t == id) else {
            break;
        };
        ports.push((pass.node.clone(), *port));
        match pass.kind.inputs.iter().find_map(|i| pass.input(i.name)) {
            Some(next) => id = next,
            None => break,
        }
    }
    ports
}

/// The source of the image that came through `ports` ([`upstream`]): the nearest one
/// recorded.
pub(crate) fn source_of(
    resources: &Resources,
    ports: &[(String, &'static str)],
) -> Option<Arc<Source>> {
    ports
        .iter()
        .find_map(|(node, port)| resources.sources.get(node, port))
}

/// The image's values, `components` a pixel (4, or 1 for a one-channel format).
pub(crate) fn values(image: &HeldImage) -> (Vec<f32>, usize) {
    match image.format {
        TexFormat::Rgba32Float => (bytemuck::pod_collect_to_vec(&image.bytes), 4),
        TexFormat::R32Float => (bytemuck::pod_collect_to_vec(&image.bytes), 1),
        TexFormat::Rgba8Unorm => (
            image.bytes.iter().map(|&b| f32::from(b) / 255.0).collect(),
            4,
        ),
    }
}

/// Values a pixel an image read as `want` has.
pub(crate) fn components_of(want: Want) -> usize {
    match want {
        Want::Rgba | Want::Vector => 4,
        Want::Scalar => 1,
    }
}

/// Prints `notes` about the file at `path`, unless they are the ones printed last.
pub(crate) fn say(node: &str, path: &Path, notes: Vec<String>, said: &mut Vec<String>) {
    if notes != *said {
        for note in &notes {
            eprintln!("{node}: {}: {note}", path.display());
        }
        *said = notes;
    }
}

/// The primaries and white of the graph's working space, which EXR files are tagged with.
pub(crate) fn working_chromaticities(resources: &Resources) -> footage_color::Chromaticities {
    footage_color::Chromaticities::from_array(resources.working_space.chromaticities())
}

/// The choice a param of an EXR writer names.
pub(crate) fn choice<T>(pass: &Pass, param: &str, named: fn(&str) -> Option<T>) -> Result<T> {
    let value = pass.params.str(param);
    named(value).ok_or_else(|| RenderError::Gpu(format!("unknown {param} {value:?}")))
}

/// Encodes `file` and writes it atomically; prints the encoder's notes.
pub(crate) fn write_exr(
    node: &str,
    path: &Path,
    file: &footage::FileOut,
    mut notes: Vec<String>,
    said: &mut Vec<String>,
) -> Result<()> {
    let (bytes, more) = footage::encode(file).map_err(|e| RenderError::image(path, e))?;
    notes.extend(more);
    write_atomic(path, &bytes)
        .map_err(|e| RenderError::image(path, format!("cannot write: {e}")))?;
    say(node, path, notes, said);
    Ok(())
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
            upstream: Vec::new(),
            said: Vec::new(),
        };
        node.update(ctx, pass)?;
        Ok(node)
    }

    fn path(&self, pass: &Pass) -> Result<PathBuf> {
        output_path(pass, &self.paths)
    }

    /// Writes `image` as an EXR file: as the layer it was read as, when it was read from
    /// one (its names; windows and types as the params choose; its attributes), else as
    /// RGBA.
    fn write_exr(&mut self, pass: &Pass, path: &Path, image: HeldImage) -> Result<()> {
        let source = source_of(&self.paths, &self.upstream);
        let native = match image.format {
            TexFormat::R32Float => 1,
            TexFormat::Rgba32Float | TexFormat::Rgba8Unorm => 4,
        };
        let extent = image.extent;
        // The image as its source's layer, else as RGBA (a one-channel image as grey);
        // its bytes dropped once converted, so a large image is not held twice.
        let (values, components) = if source
            .as_ref()
            .is_some_and(|s| components_of(s.want) == native)
        {
            values(&image)
        } else {
            let rgba = crate::readback::to_image(&image.bytes, image.format, extent);
            (rgba.pixels.into_iter().flatten().collect(), 4)
        };
        drop(image);
        let input = ImageIn {
            port: "color",
            values: &values,
            components,
            width: extent.width as usize,
            height: extent.height as usize,
            name: None,
            channels: None,
            default_name: String::new(),
            default_channels: ["R", "G", "B", "A"].map(str::to_owned).to_vec(),
            sample: choice(pass, "type", TypeChoice::named)?,
            source: source.as_deref(),
        };
        let settings = footage::Settings {
            window: choice(pass, "data_window", WindowChoice::named)?,
            parts: footage::PartsChoice::Single,
            compression: footage::Compression::Zip,
            chromaticities: working_chromaticities(&self.paths),
        };
        let (file, notes) =
            footage::assemble(&[input], &settings).map_err(|e| RenderError::image(path, e))?;
        write_exr(&pass.node, path, &file, notes, &mut self.said)
    }
}

impl NodeExec for Output {
    fn sink(&mut self) -> Option<&mut dyn Sink> {
        Some(self)
    }

    fn update(&mut self, _ctx: &GpuContext, pass: &Pass) -> Result<()> {
        check_writable(&self.path(pass)?)
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, _) = rec.parts();
        let id = pass
            .input("color")
            .ok_or_else(|| RenderError::Gpu("input \"color\" is not bound".into()))?;
        self.upstream = upstream(io.plan, id);
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

    fn finish(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<Vec<PathBuf>> {
        let Some(image) = self.held_image(ctx)? else {
            return Ok(Vec::new());
        };
        let path = self.path(pass)?;
        let is_exr = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if is_exr {
            self.write_exr(pass, &path, image)?;
        } else if image.ty != PortType::LdrColor
            && self.paths.working_space != lumagraph_graph::WorkingSpace::Rec709
        {
            // A PNG's sRGB encoding is Rec. 709's: linear colour of another working space
            // is converted first.
            let mut linear = crate::readback::to_image(&image.bytes, image.format, image.extent);
            super::ocio::working_to_rec709(self.paths.working_space, &mut linear)?;
            crate::image_io::save(&path, &linear, true)?;
        } else {
            write_image(&path, image.bytes, image.format, image.ty, image.extent)?;
        }
        Ok(vec![path])
    }
}

impl Sink for Output {
    fn held_image(&mut self, ctx: &GpuContext) -> Result<Option<HeldImage>> {
        self.staged.as_ref().map(|s| s.read(ctx)).transpose()
    }
}

/// The file an `Output` node writes of `pass` (its `path` param, relative to `out_dir`).
///
/// # Errors
/// A path that leaves the output folder ([`Resources::output`]).
pub fn output_path(pass: &Pass, resources: &Resources) -> Result<PathBuf> {
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
