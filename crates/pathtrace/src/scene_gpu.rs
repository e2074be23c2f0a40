//! A flattened scene on the GPU: one storage buffer per array of
//! [`lumagraph_scene::GpuScene`], bound by the path tracer in the order of its shader, and
//! the texture atlas as a 2D array texture.
//!
//! Every part is checked against the device's limits before anything is created: a part
//! that does not fit is one [`RenderError::TooLarge`] naming it (BVH nodes, triangles,
//! textures…), its size and the limit, never a bind-group error from the driver.

use lumagraph_scene::GpuScene;
use wgpu::util::DeviceExt as _;

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};

/// The scene's storage buffers and texture atlas.
#[derive(Debug)]
pub struct SceneBuffers {
    /// BVH nodes, each with its skip links ([`GpuScene::bvh_records`]).
    pub bvh_nodes: wgpu::Buffer,
    /// Triangle intersection data.
    pub tri_positions: wgpu::Buffer,
    /// Triangle shading data.
    pub tri_shading: wgpu::Buffer,
    /// Analytic shapes.
    pub shapes: wgpu::Buffer,
    /// Materials.
    pub materials: wgpu::Buffer,
    /// Emitters.
    pub lights: wgpu::Buffer,
    /// Alias table over the emitters.
    pub light_alias: wgpu::Buffer,
    /// Texture coordinates and tangents per triangle (one zeroed entry without textures).
    pub tri_texcoords: wgpu::Buffer,
    /// Every texture's place in the atlas (a zeroed stand-in without textures).
    pub texture_descs: wgpu::Buffer,
    /// The texture atlas, all its pages (a 1×1 stand-in without textures).
    pub textures: wgpu::TextureView,
    /// Bytes uploaded, for reports.
    pub bytes: u64,
}

fn storage(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    // Bindings may not be empty: a scene without shapes still binds a (zeroed) buffer, as
    // large as one of any record (the shader's minimum binding size: a `Light` is 80 bytes,
    // a `Material` 224).
    const SMALLEST: usize = 512;
    let mut padded;
    let contents = if bytes.len() < SMALLEST {
        padded = bytes.to_vec();
        padded.resize(SMALLEST, 0);
        &padded[..]
    } else {
        bytes
    };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// `bytes` in MiB, for messages.
fn mib(bytes: u64) -> String {
    #[expect(clippy::cast_precision_loss, reason = "a size for people")]
    let m = bytes as f64 / (1024.0 * 1024.0);
    format!("{m:.1} MiB")
}

/// Whether every part of `scene` fits `limits`: each storage buffer under the largest
/// binding and buffer, the atlas's pages under the largest 2D texture side and its page
/// count under the array layers.
///
/// # Errors
/// [`RenderError::TooLarge`] naming the first part that does not fit, its size and the
/// limit, and what to do.
pub fn check_limits(scene: &GpuScene, limits: &wgpu::Limits, adapter: &str) -> Result<()> {
    check_parts(scene, limits, adapter, true)
}

/// [`check_limits`], leaving out the binary BVH's records where `binary_bvh` is false (an
/// intersector that does not walk them: the host's, the 8-wide BVH's own buffer, ray
/// queries, inline code).
fn check_parts(
    scene: &GpuScene,
    limits: &wgpu::Limits,
    adapter: &str,
    binary_bvh: bool,
) -> Result<()> {
    let too_large = |what: String, message: String| RenderError::TooLarge {
        what: format!("scene part {what}"),
        adapter: adapter.to_owned(),
        message,
    };
    let records = if binary_bvh {
        scene.bvh_records()
    } else {
        Vec::new()
    };
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    for (what, count, bytes) in [
        (
            "\"BVH nodes\"",
            records.len(),
            std::mem::size_of_val(&records[..]),
        ),
        (
            "\"triangles\" (positions)",
            scene.tri_positions.len(),
            std::mem::size_of_val(&scene.tri_positions[..]),
        ),
        (
            "\"triangles\" (shading data)",
            scene.tri_shading.len(),
            std::mem::size_of_val(&scene.tri_shading[..]),
        ),
        (
            "\"triangles\" (texture coordinates)",
            scene.tri_texcoords.len(),
            std::mem::size_of_val(&scene.tri_texcoords[..]),
        ),
        (
            "\"shapes\"",
            scene.shapes.len(),
            std::mem::size_of_val(&scene.shapes[..]),
        ),
        (
            "\"materials\"",
            scene.materials.len(),
            std::mem::size_of_val(&scene.materials[..]),
        ),
        (
            "\"lights\"",
            scene.lights.len(),
            std::mem::size_of_val(&scene.lights[..]),
        ),
    ] {
        let bytes = bytes as u64;
        if bytes > binding {
            return Err(too_large(
                format!("{what}: {count} records"),
                format!(
                    "{} in one storage buffer, over the adapter's largest storage binding of {} \
                     (max_storage_buffer_binding_size {}, max_buffer_size {}); a smaller scene, or a \
                     device with a larger limit, is needed",
                    mib(bytes),
                    mib(binding),
                    limits.max_storage_buffer_binding_size,
                    limits.max_buffer_size
                ),
            ));
        }
    }
    let atlas = &scene.atlas;
    if atlas.pages > 0 {
        let what = format!(
            "\"textures\": {} textures in {} pages of {}x{} texels ({})",
            atlas.textures,
            atlas.pages,
            atlas.page_size,
            atlas.page_size,
            mib(atlas.bytes())
        );
        if atlas.page_size > limits.max_texture_dimension_2d {
            return Err(too_large(
                what,
                format!(
                    "a page must hold the largest texture whole, and {} texels is over the \
                     adapter's largest 2D texture side of {} (max_texture_dimension_2d); scale the \
                     largest textures down to at most {} texels (`render --fit-textures` halves \
                     them)",
                    atlas.page_size,
                    limits.max_texture_dimension_2d,
                    limits.max_texture_dimension_2d
                ),
            ));
        }
        if atlas.pages > limits.max_texture_array_layers {
            return Err(too_large(
                what,
                format!(
                    "{} pages, over the adapter's {} array layers (max_texture_array_layers); \
                     use fewer or smaller textures (`render --fit-textures` halves the largest \
                     until they fit)",
                    atlas.pages, limits.max_texture_array_layers
                ),
            ));
        }
    }
    Ok(())
}

/// The atlas as a 2D array texture (a 1×1 stand-in without textures).
pub(crate) fn atlas_texture(ctx: &GpuContext, scene: &GpuScene) -> wgpu::TextureView {
    let atlas = &scene.atlas;
    let (side, pages) = if atlas.pages == 0 {
        (1, 1)
    } else {
        (atlas.page_size, atlas.pages)
    };
    let size = wgpu::Extent3d {
        width: side,
        height: side,
        depth_or_array_layers: pages,
    };
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("scene textures"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    if atlas.pages > 0 {
        // One page at a time, so no single copy is larger than a page.
        let page = atlas.page_size as usize * atlas.page_size as usize;
        for p in 0..atlas.pages {
            let texels = &atlas.texels[p as usize * page..(p as usize + 1) * page];
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: 0, y: 0, z: p },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(texels),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * side),
                    rows_per_image: Some(side),
                },
                wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

impl SceneBuffers {
    /// Uploads every array of `scene`, after checking each against the device's limits.
    ///
    /// # Errors
    /// [`RenderError::TooLarge`] where a part does not fit ([`check_limits`]).
    pub fn upload(ctx: &GpuContext, scene: &GpuScene) -> Result<Self> {
        Self::upload_for(ctx, scene, true)
    }

    /// [`SceneBuffers::upload`], with a one-record stand-in for the binary BVH's records
    /// where `binary_bvh` is false (its intersector does not walk them), so a scene whose
    /// binary BVH is over the device's largest binding still renders through the host or
    /// the 8-wide BVH.
    ///
    /// # Errors
    /// As [`SceneBuffers::upload`], the binary BVH left out of the check where it is not
    /// uploaded.
    pub fn upload_for(ctx: &GpuContext, scene: &GpuScene, binary_bvh: bool) -> Result<Self> {
        check_parts(scene, &ctx.device.limits(), &ctx.info.name, binary_bvh)?;
        // A runtime-sized array binding holds at least one element: white, for the general
        // shader, which reads the vertex colour of every triangle.
        let one = [lumagraph_scene::GpuTriTexcoords {
            colors: [lumagraph_scene::VERTEX_WHITE; 3],
            ..Default::default()
        }];
        let texcoords = if scene.tri_texcoords.is_empty() {
            &one[..]
        } else {
            &scene.tri_texcoords[..]
        };
        let records = if binary_bvh {
            scene.bvh_records()
        } else {
            GpuScene::default().bvh_records()
        };
        let parts: [(&str, &[u8]); 9] = [
            ("bvh_nodes", bytemuck::cast_slice(&records)),
            ("tri_positions", bytemuck::cast_slice(&scene.tri_positions)),
            ("tri_shading", bytemuck::cast_slice(&scene.tri_shading)),
            ("shapes", bytemuck::cast_slice(&scene.shapes)),
            ("materials", bytemuck::cast_slice(&scene.materials)),
            ("lights", bytemuck::cast_slice(&scene.lights)),
            ("light_alias", bytemuck::cast_slice(&scene.light_alias)),
            ("tri_texcoords", bytemuck::cast_slice(texcoords)),
            (
                "texture_descs",
                bytemuck::cast_slice(&scene.atlas.descriptors),
            ),
        ];
        let bytes = parts.iter().map(|(_, b)| b.len() as u64).sum::<u64>() + scene.atlas.bytes()
            - if scene.tri_texcoords.is_empty() {
                std::mem::size_of_val(&one) as u64
            } else {
                0
            };
        let [b0, b1, b2, b3, b4, b5, b6, b7, b8] = parts.map(|(label, b)| storage(ctx, label, b));
        Ok(Self {
            bvh_nodes: b0,
            tri_positions: b1,
            tri_shading: b2,
            shapes: b3,
            materials: b4,
            lights: b5,
            light_alias: b6,
            tri_texcoords: b7,
            texture_descs: b8,
            textures: atlas_texture(ctx, scene),
            bytes,
        })
    }
}
