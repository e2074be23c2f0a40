//! A flattened scene on the GPU: one storage buffer per array of
//! [`lumagraph_scene::GpuScene`], bound by the path tracer in the order of its shader.

use lumagraph_scene::GpuScene;
use wgpu::util::DeviceExt as _;

use crate::context::GpuContext;

/// The scene's storage buffers.
#[derive(Debug)]
pub struct SceneBuffers {
    /// BVH nodes, each with its skip links ([`GpuScene::bvh_records`]).
    pub bvh_nodes: wgpu::Buffer,
    /// Triangle intersection data.
    pub tri_positions: wgpu::Buffer,
    /// Triangle shading data.
    pub tri_shading: wgpu::Buffer,
    /// Spheres.
    pub spheres: wgpu::Buffer,
    /// Materials.
    pub materials: wgpu::Buffer,
    /// Emitters.
    pub lights: wgpu::Buffer,
    /// Alias table over the emitters.
    pub light_alias: wgpu::Buffer,
    /// Texture coordinates and tangents per triangle (one zeroed entry without textures).
    pub tri_texcoords: wgpu::Buffer,
    /// Every texture, packed (a zeroed stand-in without textures).
    pub textures: wgpu::Buffer,
    /// Bytes uploaded, for reports.
    pub bytes: u64,
}

fn storage(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    // Bindings may not be empty: a scene without spheres still binds a (zeroed) buffer.
    let mut padded;
    let contents = if bytes.len() < 64 {
        padded = bytes.to_vec();
        padded.resize(64, 0);
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

impl SceneBuffers {
    /// Uploads every array of `scene`.
    pub fn upload(ctx: &GpuContext, scene: &GpuScene) -> Self {
        // A runtime-sized array binding holds at least one element.
        let one = [lumagraph_scene::GpuTriTexcoords::default()];
        let texcoords = if scene.tri_texcoords.is_empty() {
            &one[..]
        } else {
            &scene.tri_texcoords[..]
        };
        let records = scene.bvh_records();
        let parts: [(&str, &[u8]); 9] = [
            ("bvh_nodes", bytemuck::cast_slice(&records)),
            ("tri_positions", bytemuck::cast_slice(&scene.tri_positions)),
            ("tri_shading", bytemuck::cast_slice(&scene.tri_shading)),
            ("spheres", bytemuck::cast_slice(&scene.spheres)),
            ("materials", bytemuck::cast_slice(&scene.materials)),
            ("lights", bytemuck::cast_slice(&scene.lights)),
            ("light_alias", bytemuck::cast_slice(&scene.light_alias)),
            ("tri_texcoords", bytemuck::cast_slice(texcoords)),
            ("textures", bytemuck::cast_slice(&scene.textures)),
        ];
        let bytes = parts.iter().map(|(_, b)| b.len() as u64).sum::<u64>()
            - if scene.tri_texcoords.is_empty() {
                std::mem::size_of_val(&one) as u64
            } else {
                0
            };
        let [b0, b1, b2, b3, b4, b5, b6, b7, b8] = parts.map(|(label, b)| storage(ctx, label, b));
        Self {
            bvh_nodes: b0,
            tri_positions: b1,
            tri_shading: b2,
            spheres: b3,
            materials: b4,
            lights: b5,
            light_alias: b6,
            tri_texcoords: b7,
            textures: b8,
            bytes,
        }
    }
}
