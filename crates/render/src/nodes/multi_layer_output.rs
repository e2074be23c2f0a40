//! `MultiLayerOutput`: several images written as the named layers of one EXR file, in
//! one part or one part a layer (`lumagraph_footage::exr::assemble`), each copied to a
//! readback buffer in the frame like `Output`'s one. An input read from an EXR file is
//! written as the layer it was read as, unless the params name it otherwise.

use std::path::PathBuf;

use lumagraph_footage::exr::{
    self as footage, Compression, ImageIn, PartsChoice, TypeChoice, WindowChoice,
};
use lumagraph_graph::registry::output::{LAYER_INPUTS, LAYER_PARAMS, default_layer};
use lumagraph_graph::{Pass, PortType};

use crate::context::GpuContext;
use crate::error::Result;
use crate::nodes::output::{
    Staged, choice, source_of, upstream, values, working_chromaticities, write_exr,
};
use crate::nodes::{NodeExec, NodeImpl, Recording, Resources, boxed, check_writable};

/// The `MultiLayerOutput` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("MultiLayerOutput", |_, pass, resources| {
    boxed(MultiLayerOutput::new(pass, resources))
});

/// An input: its port, what the frame copied of it, and the ports it came through.
type StagedInput = (&'static str, Staged, Vec<(String, &'static str)>);

pub(crate) struct MultiLayerOutput {
    paths: Resources,
    /// Per bound input: its port, what the frame copied of it, where it came from.
    staged: Vec<StagedInput>,
    /// The notes printed last, so a sequence prints each once.
    said: Vec<String>,
}

impl MultiLayerOutput {
    fn new(pass: &Pass, paths: &Resources) -> Result<Self> {
        check_writable(&paths.output(pass.params.str("path"))?)?;
        Ok(Self {
            paths: paths.clone(),
            staged: Vec::new(),
            said: Vec::new(),
        })
    }
}

/// What the params of the layer on `port` say of an image of `ty`: the name and channels
/// they give (`None` where left empty), the defaults, and the sample type.
struct Spec {
    name: Option<String>,
    channels: Option<Vec<String>>,
    default_name: String,
    default_channels: Vec<String>,
    sample: TypeChoice,
}

fn layer_spec(pass: &Pass, port: &str, ty: PortType) -> Result<Spec> {
    let split = |s: &str| s.split_whitespace().map(str::to_owned).collect::<Vec<_>>();
    let given = |s: &str| (!s.trim().is_empty()).then(|| s.to_owned());
    if port == "color" {
        let channels = if ty == PortType::Scalar || ty == PortType::Depth {
            default_layer(ty, 0).1
        } else {
            "R G B A"
        };
        return Ok(Spec {
            name: given(pass.params.str("color_name")),
            channels: None,
            default_name: String::new(),
            default_channels: split(channels),
            sample: choice(pass, "color_type", TypeChoice::named)?,
        });
    }
    let i = LAYER_INPUTS.iter().position(|p| *p == port).unwrap_or(0);
    let [name, channels, kind] = LAYER_PARAMS[i];
    let (default_name, default_channels) = default_layer(ty, i + 1);
    Ok(Spec {
        name: given(pass.params.str(name)),
        channels: given(pass.params.str(channels)).map(|c| split(&c)),
        default_name,
        default_channels: split(default_channels),
        sample: choice(pass, kind, TypeChoice::named)?,
    })
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
                .position(|(p, _, _)| *p == port)
                .map(|i| old.swap_remove(i).1);
            self.staged.push((
                port,
                Staged::record(ctx, encoder, io, id, &pass.node, reuse),
                upstream(io.plan, id),
            ));
        }
        Ok(())
    }

    fn finish(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<Vec<PathBuf>> {
        if self.staged.is_empty() {
            return Ok(Vec::new());
        }
        let path = self.paths.output(pass.params.str("path"))?;
        let mut read = Vec::new();
        for (port, staged, ports) in &self.staged {
            let image = staged.read(ctx)?;
            let spec = layer_spec(pass, port, image.ty)?;
            let (all, components) = values(&image);
            read.push((
                *port,
                spec,
                all,
                components,
                image.extent,
                source_of(&self.paths, ports),
            ));
        }
        let images: Vec<ImageIn<'_>> = read
            .iter()
            .map(|(port, spec, all, components, extent, source)| ImageIn {
                port,
                values: all,
                components: *components,
                width: extent.width as usize,
                height: extent.height as usize,
                name: spec.name.clone(),
                channels: spec.channels.clone(),
                default_name: spec.default_name.clone(),
                default_channels: spec.default_channels.clone(),
                sample: spec.sample,
                source: source.as_deref(),
            })
            .collect();
        let settings = footage::Settings {
            window: choice(pass, "data_window", WindowChoice::named)?,
            parts: choice(pass, "parts", PartsChoice::named)?,
            compression: choice(pass, "compression", Compression::named)?,
            chromaticities: working_chromaticities(&self.paths),
        };
        let (file, notes) = footage::assemble(&images, &settings)
            .map_err(|e| crate::error::RenderError::image(&path, e))?;
        write_exr(&pass.node, &path, &file, notes, &mut self.said)?;
        Ok(vec![path])
    }
}

#[cfg(test)]
mod tests {
    use lumagraph_footage::exr::{Compression, PartsChoice, TypeChoice, WindowChoice};
    use lumagraph_graph::registry::output::{DATA_WINDOWS, EXR_COMPRESSIONS, PARTS, SAMPLE_TYPES};

    #[test]
    fn every_choice_the_nodes_offer_is_one_the_writer_takes() {
        for (name, _) in EXR_COMPRESSIONS {
            assert!(Compression::named(name).is_some(), "{name}");
        }
        for (name, _) in DATA_WINDOWS {
            assert!(WindowChoice::named(name).is_some(), "{name}");
        }
        for (name, _) in PARTS {
            assert!(PartsChoice::named(name).is_some(), "{name}");
        }
        for (name, _) in SAMPLE_TYPES {
            assert!(TypeChoice::named(name).is_some(), "{name}");
        }
    }
}
