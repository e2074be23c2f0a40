//! A processor as a WGSL compute shader: OpenColorIO's generated function (`ocio` lowers
//! its GPU program to WGSL; LUTs are textures read with `textureLoad`, interpolated in the
//! shader, so no sampler and no filterable float textures are needed), wrapped in an entry
//! point that converts an image texture into a storage texture pixel by pixel.
//!
//! All bindings are in group 0, numbered from 0 without a gap: OpenColorIO's uniform
//! buffer (when the program has uniforms) at 0, its LUT textures from 1, then the input
//! image and the output image. Without uniforms, the input image takes binding 0.

use ocio::GpuLanguage;
use ocio::gpu::wgsl::WgslTextureFormat;
use ocio::gpu::{GpuShaderCreator as _, GpuShaderDesc};

use crate::{Error, Processor, Result};

/// A LUT texture of a [`GpuProgram`]: its size, format and texels.
#[derive(Clone, Debug, PartialEq)]
pub struct LutTexture {
    /// 2 or 3.
    pub dimensions: u32,
    /// Width, height and depth in texels (depth 1 for a 2D texture).
    pub size: [u32; 3],
    /// One float a texel (`R32Float`), else four (`Rgba32Float`).
    pub single_channel: bool,
    /// The texels, little-endian floats, rows of `size[0]`, `size[1]` rows a slice.
    pub bytes: Vec<u8>,
    /// Bytes in a row.
    pub bytes_per_row: u32,
}

/// What a binding of a [`GpuProgram`] is, in binding order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// OpenColorIO's uniform buffer.
    Uniforms,
    /// LUT texture `i` of [`GpuProgram::luts`].
    Lut(usize),
    /// The image read (`texture_2d<f32>`).
    Input,
    /// The image written (a storage texture).
    Output,
}

/// A processor as a compute shader and its resources.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuProgram {
    /// The whole module: OpenColorIO's function, the bindings, the entry point `main`
    /// (workgroups of 8 × 8 pixels).
    pub wgsl: String,
    /// The bindings, 0 first.
    pub slots: Vec<Slot>,
    /// The uniform buffer's contents, when the program has uniforms.
    pub uniforms: Option<Vec<u8>>,
    /// The LUT textures.
    pub luts: Vec<LutTexture>,
}

impl Processor {
    /// The conversion as a compute shader from an image to a storage texture of format
    /// `output` (a WGSL storage format: `rgba32float`, `rgba8unorm`).
    ///
    /// # Errors
    /// What OpenColorIO's GPU path cannot do exactly (it never makes an approximate
    /// shader): the message says which conversion.
    pub fn gpu_program(&self, output: &str) -> Result<GpuProgram> {
        let err = |e: ocio::Error| Error(format!("{} on the GPU: {e}", self.description));
        let gpu = self.processor.default_gpu_processor().map_err(err)?;
        let mut desc = GpuShaderDesc::new();
        desc.set_language(GpuLanguage::Wgsl);
        desc.set_allow_texture_1d(false);
        desc.set_function_name("ocio_main");
        desc.set_resource_prefix("ocio");
        gpu.extract_gpu_shader_info(&mut desc).map_err(err)?;
        let bindings = desc.wgsl_bindings().cloned().ok_or_else(|| {
            Error(format!(
                "{}: OpenColorIO gave no WGSL bindings",
                self.description
            ))
        })?;
        let mut slots = Vec::new();
        let uniforms = match bindings.uniform_binding {
            Some(_) => {
                slots.push(Slot::Uniforms);
                Some(bindings.uniform_buffer(&desc).map_err(err)?)
            }
            None => None,
        };
        let first_free = if uniforms.is_some() { 1 } else { 0 };
        let input = if uniforms.is_some() {
            1 + u32::try_from(bindings.textures.len()).unwrap_or(0)
        } else {
            first_free
        };
        if uniforms.is_none() {
            slots.push(Slot::Input);
        }
        let mut textures: Vec<&ocio::gpu::wgsl::WgslTextureBinding> =
            bindings.textures.iter().collect();
        textures.sort_by_key(|t| t.binding);
        let mut luts = Vec::new();
        for (i, t) in textures.iter().enumerate() {
            let values = (0..desc.num_textures())
                .filter_map(|j| desc.texture(j).ok())
                .chain((0..desc.num_3d_textures()).filter_map(|j| desc.texture_3d(j).ok()))
                .find(|g| g.texture_name == t.texture_name)
                .map(|g| g.values.clone())
                .ok_or_else(|| {
                    Error(format!(
                        "{}: no values for LUT {}",
                        self.description, t.texture_name
                    ))
                })?;
            luts.push(LutTexture {
                dimensions: t.dimensions,
                size: [t.width, t.height, t.depth],
                single_channel: t.format == WgslTextureFormat::R32Float,
                bytes: t.texel_data(&values).map_err(err)?,
                bytes_per_row: t.bytes_per_row(),
            });
            slots.push(Slot::Lut(i));
        }
        let output_binding = if uniforms.is_some() {
            slots.push(Slot::Input);
            input + 1
        } else {
            1 + u32::try_from(luts.len()).unwrap_or(0)
        };
        slots.push(Slot::Output);
        let wgsl = format!(
            "{ocio}\n\
             @group(0) @binding({input}) var lumagraph_input: texture_2d<f32>;\n\
             @group(0) @binding({output_binding}) var lumagraph_output: texture_storage_2d<{output}, write>;\n\
             \n\
             @compute @workgroup_size(8, 8)\n\
             fn main(@builtin(global_invocation_id) id: vec3u) {{\n\
             \x20   let size = textureDimensions(lumagraph_input);\n\
             \x20   if (id.x >= size.x || id.y >= size.y) {{ return; }}\n\
             \x20   let c = textureLoad(lumagraph_input, vec2i(id.xy), 0);\n\
             \x20   textureStore(lumagraph_output, vec2i(id.xy), ocio_main(c));\n\
             }}\n",
            ocio = desc.shader_text()
        );
        Ok(GpuProgram {
            wgsl,
            slots,
            uniforms,
            luts,
        })
    }
}
