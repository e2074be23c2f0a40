//! `GBuffer`: a raster pass (vertex + fragment, depth-tested) from the path tracer's camera,
//! writing first-hit albedo, shading normal and distance along the ray.
//!
//! Instanced meshes are drawn once per instance: each mesh's triangles (in its own space)
//! are one range of the vertex buffer, drawn with its instances' transforms from a second,
//! per-instance buffer (`GpuInstance` records, an identity first for everything else).
//!
//! The scene's triangles go to one non-indexed vertex buffer with their corner normals and
//! material color (and, with textures, UV, tangent and material id: the fragment shader
//! applies the base color texture and the normal map as the path tracer does); each analytic shape becomes its kind's hull (`ShapeKind::hull`: a UV
//! sphere circumscribing a sphere, a polygon around a disk), and the fragment shader
//! intersects the shape itself along the pixel-center ray with the path tracer's test
//! (dropping misses, writing the exact normal and depth), so shapes agree with the ray
//! tracer to the pixel.
//! See `shaders/gbuffer/gbuffer.wgsl` for the projection (reversed, infinite depth).
//!
//! Outputs nothing reads are rendered into node-owned stand-ins of the same size, since
//! every attachment of a render pass must have the same size.

use lumagraph_graph::{Extent, Pass, TexFormat};
use lumagraph_scene::{FEATURE_TEXTURES, GpuInstance, GpuScene, TRI_VERTEX_NORMALS};
use wgpu::util::DeviceExt as _;

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::kernel::uniform_buffer;
use lumagraph_render::nodes::{NodeExec, NodeImpl, Recording, Resources, View, boxed};
use lumagraph_render::pool::{PooledTexture, create, wgpu_format};

/// Floats per vertex: position, normal, albedo (3 each), shape (4), uv (both sets: 4),
/// tangent (4), material id (the bits of a `u32`), vertex colour (4, decoded).
const VERTEX_FLOATS: usize = 26;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const PORTS: [(&str, TexFormat); 3] = [
    ("albedo", TexFormat::Rgba32Float),
    ("normal", TexFormat::Rgba32Float),
    ("depth", TexFormat::R32Float),
];

/// The `GBuffer` kind: it owns its depth attachment.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("GBuffer", |ctx, pass, resources| {
    boxed(GBuffer::new(ctx, pass, resources))
})
.owning(|pass| {
    Some((
        4 * pass.extent.pixels(),
        "depth attachment (depth32float)".to_owned(),
    ))
});

pub(crate) struct GBuffer {
    scene: std::sync::Arc<GpuScene>,
    /// The camera rasterized from: the scene's, until [`View::move_camera`](lumagraph_render::nodes::View::move_camera).
    camera_now: lumagraph_scene::GpuCamera,
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    /// The vertex buffer, the per-instance buffer, and the draws over them.
    vertices: Option<(wgpu::Buffer, wgpu::Buffer, Vec<Draw>)>,
    segments: u32,
    /// Depth attachment and stand-ins for unread outputs, at the pass's size.
    targets: Option<(Extent, wgpu::TextureView, [Option<PooledTexture>; 3])>,
    /// The camera uniform, rewritten when the window moves.
    camera: wgpu::Buffer,
    /// Where the pass's image lies in the whole image, and the camera block written for it.
    origin: [u32; 2],
    written: Option<RasterCamera>,
}

impl GBuffer {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass, resources: &Resources) -> Result<Self> {
        let scene = resources.scene.clone().ok_or_else(|| {
            RenderError::Gpu("GBuffer needs a scene (lumagraph render --scene FILE)".into())
        })?;
        let device = &ctx.device;
        let textured = scene.header.features & FEATURE_TEXTURES != 0;
        let source = lumagraph_render::shader::resolve_with(
            "gbuffer/gbuffer.wgsl",
            &[(
                "gbuffer/options.wgsl",
                format!(
                    "const HAS_TEXTURES: bool = {textured};\nconst HAS_ALPHA: bool = {};\n",
                    scene.header.features & lumagraph_scene::FEATURE_ALPHA != 0
                ),
            )],
        )?;
        let (pipeline, layout) = pipeline(ctx, source)?;
        let camera = uniform_buffer(
            ctx,
            "gbuffer camera",
            bytemuck::bytes_of(&raster_camera(&scene, &scene.camera, [0, 0], pass.extent)),
        );
        // The materials are always read (their emission marks emitters); the textures only
        // with textures: without, a zeroed stand-in.
        let storage = |label: &str, bytes: &[u8], textured: bool| {
            let zeros = [0_u8; 80];
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if textured && !bytes.is_empty() {
                    bytes
                } else {
                    &zeros
                },
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let materials = storage(
            "gbuffer materials",
            bytemuck::cast_slice(&scene.materials),
            true,
        );
        let texture_descs = storage(
            "gbuffer texture descriptors",
            bytemuck::cast_slice(&scene.atlas.descriptors),
            textured,
        );
        if textured {
            crate::scene_gpu::check_limits(&scene, &ctx.device.limits(), &ctx.info.name)?;
        }
        let textures = crate::scene_gpu::atlas_texture(ctx, &scene);
        // The analytic shapes each fragment of their hulls intersects.
        let shapes = storage("gbuffer shapes", bytemuck::cast_slice(&scene.shapes), true);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: camera.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: materials.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: texture_descs.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&textures),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: shapes.as_entire_binding(),
                },
            ],
        });
        let mut node = Self {
            camera_now: scene.camera,
            scene,
            pipeline,
            bind_group,
            vertices: None,
            segments: 0,
            targets: None,
            camera,
            origin: [0, 0],
            written: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

/// The raster pipeline of `source` (the resolved G-buffer shader) and its bind group layout
/// (camera uniform, materials, texture descriptors, the texture atlas, the analytic shapes).
fn pipeline(
    ctx: &GpuContext,
    source: String,
) -> Result<(wgpu::RenderPipeline, wgpu::BindGroupLayout)> {
    let device = &ctx.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("gbuffer"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("gbuffer"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            storage_entry(1),
            storage_entry(2),
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            storage_entry(4),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gbuffer"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let attributes = wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x4,
        4 => Float32x4, 5 => Float32x4, 6 => Uint32, 7 => Float32x4
    ];
    // A `GpuInstance`: its transforms' rows and (root, flags, pad_scale, pad_base).
    let instance_attributes = wgpu::vertex_attr_array![
        8 => Float32x4, 9 => Float32x4, 10 => Float32x4,
        11 => Float32x4, 12 => Float32x4, 13 => Float32x4, 14 => Uint32x4
    ];
    let target = |format| {
        Some(wgpu::ColorTargetState {
            format: wgpu_format(format),
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })
    };
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("gbuffer"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            buffers: &[
                Some(wgpu::VertexBufferLayout {
                    array_stride: (VERTEX_FLOATS * 4) as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                }),
                Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<GpuInstance>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &instance_attributes,
                }),
            ],
        },
        // No culling: the path tracer sees back faces too.
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            targets: &PORTS.map(|(_, f)| target(f)),
        }),
        multiview_mask: None,
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(RenderError::Shader {
            name: "gbuffer/gbuffer.wgsl".into(),
            message: e.to_string(),
        });
    }
    Ok((pipeline, layout))
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

lumagraph_render::param_block! {
    /// The raster camera: the path tracer's pinhole camera, the image size in its spare floats.
    pub(crate) struct RasterCamera in "gbuffer/gbuffer.wgsl" as "RasterCamera" {
        position: [f32; 3],
        tan_half_fov: f32,
        right: [f32; 3],
        aspect: f32,
        up: [f32; 3],
        width: f32,
        forward: [f32; 3],
        height: f32,
        /// The pixels this pass renders: left, top, width and height in the whole image.
        window: [f32; 4],
    }
}

fn raster_camera(
    scene: &GpuScene,
    c: &lumagraph_scene::GpuCamera,
    origin: [u32; 2],
    extent: Extent,
) -> RasterCamera {
    #[expect(clippy::cast_precision_loss, reason = "image sizes are small")]
    let window = [
        origin[0] as f32,
        origin[1] as f32,
        extent.width as f32,
        extent.height as f32,
    ];
    #[expect(clippy::cast_precision_loss, reason = "image sizes are small")]
    let (width, height) = (scene.settings.width as f32, scene.settings.height as f32);
    RasterCamera {
        position: c.position,
        tan_half_fov: c.tan_half_fov,
        right: c.right,
        aspect: c.aspect,
        up: c.up,
        width,
        forward: c.forward,
        height,
        window,
    }
}

fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if l > 0.0 { a.map(|x| x / l) } else { a }
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Texture attributes of a vertex.
#[derive(Clone, Copy)]
struct Tex {
    uv: [f32; 4],
    tangent: [f32; 4],
    material: u32,
    color: [f32; 4],
}

/// One draw: a range of vertices, drawn once per instance of a range of the per-instance
/// buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Draw {
    pub vertices: std::ops::Range<u32>,
    pub instances: std::ops::Range<u32>,
}

/// The per-instance records: the identity (for the scene's own triangles and spheres), then
/// the instances grouped by mesh; and the draws: the scene's own triangles and tessellated
/// spheres once, then each instanced mesh's triangles once per instance of it.
pub(crate) fn draws(scene: &GpuScene, segments: u32) -> (Vec<f32>, Vec<GpuInstance>, Vec<Draw>) {
    let identity = GpuInstance {
        to_world: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        to_object: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        ..GpuInstance::default()
    };
    let own = scene.tri_source.len();
    let mut data = vertices(scene, 0..own, segments.max(1));
    let floats = |d: &Vec<f32>| (d.len() / VERTEX_FLOATS) as u32;
    let mut draws = vec![Draw {
        vertices: 0..floats(&data),
        instances: 0..1,
    }];
    let mut instances = vec![identity];
    for (mesh, &[first, count]) in scene.mesh_triangles.iter().enumerate() {
        let start = floats(&data);
        data.extend(vertices(scene, first as usize..(first + count) as usize, 0));
        let at = instances.len() as u32;
        instances.extend(
            scene
                .instances
                .iter()
                .zip(&scene.instance_mesh)
                .filter(|(_, m)| **m as usize == mesh)
                .map(|(i, _)| *i),
        );
        draws.push(Draw {
            vertices: start..floats(&data),
            instances: at..instances.len() as u32,
        });
    }
    (data, instances, draws)
}

/// The vertex data of the triangles `triangles` (indices in `tri_positions`) and, where
/// `segments` is not 0, every analytic shape's hull, `VERTEX_FLOATS` per vertex.
pub(crate) fn vertices(
    scene: &GpuScene,
    triangles: std::ops::Range<usize>,
    segments: u32,
) -> Vec<f32> {
    let albedo = |m: u32| {
        scene
            .materials
            .get(m as usize)
            .map_or([0.0; 3], |m| m.base_color)
    };
    let mut out = Vec::new();
    let mut push = |p: [f32; 3], n: [f32; 3], a: [f32; 3], s: [f32; 4], tex: Tex| {
        out.extend_from_slice(&p);
        out.extend_from_slice(&n);
        out.extend_from_slice(&a);
        out.extend_from_slice(&s);
        out.extend_from_slice(&tex.uv);
        out.extend_from_slice(&tex.tangent);
        out.push(f32::from_bits(tex.material));
        out.extend_from_slice(&tex.color);
    };
    let no_tex = |material: u32| Tex {
        uv: [0.0; 4],
        tangent: [0.0; 4],
        material,
        color: [1.0; 4],
    };
    for i in triangles {
        let (t, sh) = (&scene.tri_positions[i], &scene.tri_shading[i]);
        let corners = [t.v0, add(t.v0, t.e1), add(t.v0, t.e2)];
        let ng = normalize(cross(t.e1, t.e2));
        let normals = if sh.flags & TRI_VERTEX_NORMALS != 0 {
            [sh.n0, sh.n1, sh.n2]
        } else {
            [sh.n0; 3]
        };
        let a = albedo(sh.material);
        let tc = scene.tri_texcoords.get(i);
        for k in 0..3 {
            let tex = tc.map_or(no_tex(sh.material), |tc| {
                let [t0, t1, t2] = [tc.t0, tc.t1, tc.t2];
                let tan = [t0, t1, t2][k];
                let uv = [[tc.uv01[0], tc.uv01[1]], [tc.uv01[2], tc.uv01[3]], tc.uv2][k];
                let uv1 = [
                    [tc.uv1_01[0], tc.uv1_01[1]],
                    [tc.uv1_01[2], tc.uv1_01[3]],
                    tc.uv1_2,
                ][k];
                Tex {
                    uv: [uv[0], uv[1], uv1[0], uv1[1]],
                    tangent: [tan[0], tan[1], tan[2], t0[3]],
                    material: sh.material,
                    color: lumagraph_scene::vertex_color(tc.colors[k]).to_array(),
                }
            });
            push(corners[k], normals[k], a, [ng[0], ng[1], ng[2], 0.0], tex);
        }
    }
    if segments == 0 {
        return out;
    }
    // Each analytic shape as its kind's hull, which its fragments intersect (the shape's
    // index + 1 in the fourth float of `shape`).
    for (k, s) in scene.shapes.iter().enumerate() {
        let a = albedo(s.material);
        let shape = [0.0, 0.0, 0.0, (k + 1) as f32];
        for tri in lumagraph_scene::shapes::KINDS[s.kind as usize].hull(s, segments) {
            for p in tri {
                push(p.to_array(), [0.0; 3], a, shape, no_tex(s.material));
            }
        }
    }
    out
}

impl NodeExec for GBuffer {
    fn view(&mut self) -> Option<&mut dyn View> {
        Some(self)
    }

    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let segments = u32::try_from(pass.params.int("sphere_segments")).unwrap_or(48);
        if self.vertices.is_none() || segments != self.segments {
            let (data, instances, draws) = draws(&self.scene, segments);
            u32::try_from(data.len() / VERTEX_FLOATS)
                .map_err(|_| RenderError::Gpu("too many G-buffer vertices".into()))?;
            let instances = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("gbuffer instances"),
                    contents: bytemuck::cast_slice(&instances),
                    usage: wgpu::BufferUsages::VERTEX,
                });
            let buffer = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("gbuffer vertices"),
                    contents: bytemuck::cast_slice(if data.is_empty() {
                        &[0.0_f32; VERTEX_FLOATS]
                    } else {
                        &data
                    }),
                    usage: wgpu::BufferUsages::VERTEX,
                });
            self.vertices = Some((buffer, instances, draws));
            self.segments = segments;
        }
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let extent = pass.extent;
        let camera = raster_camera(&self.scene, &self.camera_now, self.origin, extent);
        if self.written != Some(camera) {
            ctx.queue
                .write_buffer(&self.camera, 0, bytemuck::bytes_of(&camera));
            self.written = Some(camera);
        }
        if self.targets.as_ref().is_none_or(|(e, _, _)| *e != extent) {
            let depth = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("gbuffer depth"),
                size: wgpu::Extent3d {
                    width: extent.width,
                    height: extent.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: DEPTH_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            });
            let view = depth.create_view(&wgpu::TextureViewDescriptor::default());
            let stand_ins = PORTS.map(|(port, format)| {
                pass.output(port)
                    .is_none()
                    .then(|| create(ctx, &format!("unused gbuffer {port}"), format, extent))
            });
            self.targets = Some((extent, view, stand_ins));
        }
        let Some((_, depth, stand_ins)) = &self.targets else {
            return Ok(());
        };
        let views: Vec<&wgpu::TextureView> = PORTS
            .iter()
            .zip(stand_ins)
            .map(
                |((port, _), stand_in)| match (pass.output(port), stand_in) {
                    (Some(t), _) => Ok(&io.texture(t).view),
                    (None, Some(s)) => Ok(&s.view),
                    (None, None) => Err(RenderError::Gpu(format!("no target for {port}"))),
                },
            )
            .collect::<Result<_>>()?;
        let clear = |a: f64| wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: 0.0,
                a,
            }),
            store: wgpu::StoreOp::Store,
        };
        let attachments: Vec<_> = views
            .iter()
            .zip([1.0, 1.0, 0.0])
            .map(|(view, a)| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear(a),
                })
            })
            .collect();
        let timestamp_writes = timer.and_then(|t| t.render_writes(&pass.node));
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&pass.node),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if let Some((buffer, instances, draws)) = &self.vertices {
            rpass.set_pipeline(&self.pipeline);
            rpass.set_bind_group(0, &self.bind_group, &[]);
            rpass.set_vertex_buffer(0, buffer.slice(..));
            rpass.set_vertex_buffer(1, instances.slice(..));
            for d in draws {
                rpass.draw(d.vertices.clone(), d.instances.clone());
            }
        }
        Ok(())
    }
}

impl View for GBuffer {
    fn set_origin(&mut self, origin: [u32; 2]) {
        self.origin = origin;
    }

    fn move_camera(&mut self, camera: &lumagraph_scene::GpuCamera) {
        self.camera_now = *camera;
    }
}
