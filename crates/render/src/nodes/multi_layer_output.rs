//! `MultiLayerOutput`: several images written as the named layers of one EXR file
//! (`lumagraph_footage::exr::encode_layers`), each copied to a readback buffer in the
//! frame like `Output`'s one.

use std::path::PathBuf;

use lumagraph_footage::exr::{Compression, LayerOut, encode_layers};
use lumagraph_graph::registry::output::{LAYER_INPUTS, LAYER_PARAMS, default_layer};
use lumagraph_graph::{Pass, PortType, TexFormat, write_atomic};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::nodes::output::Staged;
use crate::nodes::{HeldImage, NodeExec, NodeImpl, Recording, Resources, boxed, check_writable};

/// The `MultiLayerOutput` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("MultiLayerOutput", |_, pass, resources| {
    boxed(MultiLayerOutput::new(pass, resources))
});

pub(crate) struct MultiLayerOutput {
    paths: Resources,
    /// Per bound input: its port and what the frame copied of it.
    staged: Vec<(&'static str, Staged)>,
}

impl MultiLayerOutput {
    fn new(pass: &Pass, paths: &Resources) -> Result<Self> {
        check_writable(&paths.output(pass.params.str("path"))?)?;
        Ok(Self {
            paths: paths.clone(),
            staged: Vec::new(),
        })
    }
}

/// The name, channels and sample type of the layer on `port` holding an image of `ty`.
fn layer_spec(pass: &Pass, port: &str, ty: PortType) -> (String, Vec<String>, bool) {
    let split = |s: &str| s.split_whitespace().map(str::to_owned).collect::<Vec<_>>();
    if port == "color" {
        let channels = if ty == PortType::Scalar || ty == PortType::Depth {
            default_layer(ty, 0).1
        } else {
            "R G B A"
        };
        return (
            pass.params.str("color_name").to_owned(),
            split(channels),
            pass.params.str("color_type") == "half",
        );
    }
    let i = LAYER_INPUTS.iter().position(|p| *p == port).unwrap_or(0);
    let [name, channels, kind] = LAYER_PARAMS[i];
    let (default_name, default_channels) = default_layer(ty, i + 1);
    let name = match pass.params.str(name) {
        "" => default_name,
        given => given.to_owned(),
    };
    let channels = match pass.params.str(channels).trim() {
        "" => split(default_channels),
        given => split(given),
    };
    (name, channels, pass.params.str(kind) == "half")
}

/// The image's values, `components` a pixel (4, or 1 for a one-channel format).
fn values(image: &HeldImage) -> (Vec<f32>, usize) {
    match image.format {
        TexFormat::Rgba32Float => (bytemuck::pod_collect_to_vec(&image.bytes), 4),
        TexFormat::R32Float => (bytemuck::pod_collect_to_vec(&image.bytes), 1),
        TexFormat::Rgba8Unorm => (
            image.bytes.iter().map(|&b| f32::from(b) / 255.0).collect(),
            4,
        ),
    }
}

impl NodeExec for MultiLayerOutput {
    fn update(&mut self, _ctx: &GpuContext, pass: &Pass) -> Result<()> {
        check_writable(&self.paths.output(pass.params.str("path"))?)
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, _) = rec.parts();
        let mut old = std::mem::take(&mut self.staged);
        for port in std::iter::once("color").chain(LAYER_INPUTS) {
            let Some(id) = pass.input(port) else {
                continue;
            };
            let reuse = old
                .iter()
                .position(|(p, _)| *p == port)
                .map(|i| old.swap_remove(i).1);
            self.staged.push((
                port,
                Staged::record(ctx, encoder, io, id, &pass.node, reuse),
            ));
        }
        Ok(())
    }

    fn finish(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<Vec<PathBuf>> {
        if self.staged.is_empty() {
            return Ok(Vec::new());
        }
        let path = self.paths.output(pass.params.str("path"))?;
        let mut layers = Vec::new();
        let mut size = None;
        for (port, staged) in &self.staged {
            let image = staged.read(ctx)?;
            let (name, channels, half) = layer_spec(pass, port, image.ty);
            let (all, components) = values(&image);
            if channels.is_empty() || channels.len() > components {
                return Err(RenderError::Gpu(format!(
                    "input {port:?} holds {components} value{} a pixel: give it 1 to \
                     {components} channel names, not {:?}",
                    if components == 1 { "" } else { "s" },
                    channels.join(" ")
                )));
            }
            let k = channels.len();
            let values = all
                .chunks_exact(components)
                .flat_map(|p| p[..k].iter().copied())
                .collect();
            size = Some(image.extent);
            layers.push(LayerOut {
                name,
                channels,
                values,
                half,
            });
        }
        let Some(extent) = size else {
            return Ok(Vec::new());
        };
        let compression = Compression::named(pass.params.str("compression"))
            .ok_or_else(|| RenderError::Gpu("unknown compression".into()))?;
        let bytes = encode_layers(
            extent.width as usize,
            extent.height as usize,
            &layers,
            compression,
        )
        .map_err(|e| RenderError::image(&path, e))?;
        write_atomic(&path, &bytes)
            .map_err(|e| RenderError::image(&path, format!("cannot write: {e}")))?;
        Ok(vec![path])
    }
}

#[cfg(test)]
mod tests {
    use lumagraph_footage::exr::Compression;
    use lumagraph_graph::registry::output::EXR_COMPRESSIONS;

    #[test]
    fn every_compression_the_node_offers_is_one_the_writer_takes() {
        for (name, _) in EXR_COMPRESSIONS {
            assert!(Compression::named(name).is_some(), "{name}");
        }
    }
}
