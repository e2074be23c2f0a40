//! The transient texture pool.
//!
//! The plan says which logical textures share an allocation ("slots"); the pool turns
//! slots into GPU textures and keeps them across recompiles, so a graph edited in the
//! editor reuses the textures it already has when formats and sizes still match.

use std::collections::HashMap;

use lumagraph_graph::{Extent, Plan, TexFormat};

use crate::context::GpuContext;

/// The wgpu format for a planned texture format.
pub fn wgpu_format(format: TexFormat) -> wgpu::TextureFormat {
    match format {
        TexFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
        TexFormat::Rgba8Unorm => wgpu::TextureFormat::Rgba8Unorm,
        TexFormat::R32Float => wgpu::TextureFormat::R32Float,
    }
}

/// A GPU texture with its default view.
#[derive(Debug)]
pub struct PooledTexture {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its full view.
    pub view: wgpu::TextureView,
    /// Its format.
    pub format: TexFormat,
    /// Its size.
    pub extent: Extent,
}

/// Textures by format and size, reused between plans.
#[derive(Debug, Default)]
pub struct TexturePool {
    free: HashMap<(TexFormat, Extent), Vec<PooledTexture>>,
    created: usize,
}

impl TexturePool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// How many textures the pool has created in all.
    pub fn created(&self) -> usize {
        self.created
    }

    /// One texture per slot of `plan`, taken from the pool or created.
    pub fn acquire(&mut self, ctx: &GpuContext, plan: &Plan) -> Vec<PooledTexture> {
        plan.slots
            .iter()
            .enumerate()
            .map(|(i, slot)| {
                self.free
                    .get_mut(&(slot.format, slot.extent))
                    .and_then(Vec::pop)
                    .unwrap_or_else(|| {
                        self.created += 1;
                        create(ctx, &format!("slot {i}"), slot.format, slot.extent)
                    })
            })
            .collect()
    }

    /// Returns textures to the pool.
    pub fn release(&mut self, textures: Vec<PooledTexture>) {
        for t in textures {
            self.free.entry((t.format, t.extent)).or_default().push(t);
        }
    }
}

/// Creates a texture usable as a storage target, a sampled input, a copy source/target and
/// a render target (every planned format is renderable; the G-buffer rasterizes into them).
pub fn create(ctx: &GpuContext, label: &str, format: TexFormat, extent: Extent) -> PooledTexture {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: extent.width,
            height: extent.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu_format(format),
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    PooledTexture {
        texture,
        view,
        format,
        extent,
    }
}
