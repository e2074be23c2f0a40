//! The scene's acceleration structure on devices with ray queries
//! (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`): what `pathtrace/intersect/ray_query.wgsl` traces
//! instead of the WGSL BVH. One bottom-level structure holds the triangles' boxes (in the
//! order of `GpuScene::tri_positions`, so a candidate's primitive index is the triangle's),
//! another the analytic shapes'; the top level has one instance of each, untransformed. Every
//! primitive is a box: the shader tests the candidates with the WGSL BVH's own tests, so
//! images agree with the WGSL BVH's.

use lumagraph_scene::GpuScene;
use wgpu::util::DeviceExt as _;

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::shared::{ACCEL_SHAPES, ACCEL_TRIANGLES};

/// The identity as a TLAS instance's 3×4 row-major transform.
const IDENTITY: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// A scene's acceleration structure, built on the device.
#[derive(Debug)]
pub struct SceneAccel {
    /// The top level, bound to the path tracer (`scene_accel`).
    pub tlas: wgpu::Tlas,
    /// The bottom levels the instances refer to (kept alive with the top level).
    _blas: Vec<wgpu::Blas>,
    /// Bytes of the build inputs uploaded (the boxes).
    pub input_bytes: u64,
}

/// Why a scene cannot be traced through ray queries on a device whose acceleration
/// structures hold at most `most` primitives, if it can't.
pub fn unsupported(scene: &GpuScene, most: u32) -> Option<String> {
    let most = u64::from(most);
    let over = |n: usize| n as u64 > most;
    if !scene.instances.is_empty() {
        Some(crate::embree::flat_only("ray queries", scene))
    } else if over(scene.tri_positions.len()) || over(scene.shapes.len()) {
        Some(format!(
            "{} triangles and {} analytic shapes: the device holds at most {most} primitives in one \
             acceleration structure",
            scene.tri_positions.len(),
            scene.shapes.len()
        ))
    } else if scene.tri_positions.is_empty() && scene.shapes.is_empty() {
        Some("nothing to intersect".to_owned())
    } else {
        None
    }
}

impl SceneAccel {
    /// Builds the scene's acceleration structure and waits for the build.
    ///
    /// # Errors
    /// When the device has no ray queries, the scene exceeds its limits ([`unsupported`]),
    /// or the build fails.
    pub fn build(ctx: &GpuContext, scene: &GpuScene) -> Result<Self> {
        let device = &ctx.device;
        if !device
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
        {
            return Err(RenderError::Gpu(format!(
                "{} has no ray queries",
                ctx.info.name
            )));
        }
        if let Some(why) = unsupported(scene, device.limits().max_blas_primitive_count) {
            return Err(RenderError::Gpu(format!("ray queries: {why}")));
        }
        // Every primitive is a box: the device's traversal finds the boxes a ray meets, and
        // the shader tests their primitives exactly as the WGSL BVH's leaves do. (A triangle
        // geometry would let the device test the triangles itself, with its own rounding:
        // watertight where Möller-Trumbore is not, so at shared edges the two disagree, and
        // a ray the device sends to one triangle and the exact test to none goes through.)
        let (tri_boxes, shape_boxes) = crate::intersect::primitive_boxes(scene);
        let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("scene accel"),
            max_instances: 2,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        // One bottom level per kind; its instance's custom data says which.
        let kinds: Vec<(u32, &str, &[[f32; 6]])> = [
            (
                ACCEL_TRIANGLES,
                "scene accel triangles",
                tri_boxes.as_slice(),
            ),
            (ACCEL_SHAPES, "scene accel shapes", shape_boxes.as_slice()),
        ]
        .into_iter()
        .filter(|(_, _, boxes)| !boxes.is_empty())
        .collect();
        let sizes: Vec<wgpu::BlasAABBGeometrySizeDescriptor> = kinds
            .iter()
            .map(|(_, _, boxes)| wgpu::BlasAABBGeometrySizeDescriptor {
                primitive_count: u32::try_from(boxes.len()).unwrap_or(u32::MAX),
                flags: wgpu::AccelerationStructureGeometryFlags::empty(),
            })
            .collect();
        let inputs: Vec<wgpu::Buffer> = kinds
            .iter()
            .map(|(_, label, boxes)| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::cast_slice(boxes),
                    usage: wgpu::BufferUsages::BLAS_INPUT,
                })
            })
            .collect();
        let blas: Vec<wgpu::Blas> = kinds
            .iter()
            .zip(&sizes)
            .map(|((_, label, _), size)| {
                device.create_blas(
                    &wgpu::CreateBlasDescriptor {
                        label: Some(label),
                        flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                        update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                    },
                    wgpu::BlasGeometrySizeDescriptors::AABBs {
                        descriptors: vec![size.clone()],
                    },
                )
            })
            .collect();
        let entries: Vec<wgpu::BlasBuildEntry> = blas
            .iter()
            .zip(&sizes)
            .zip(&inputs)
            .map(|((b, size), aabb_buffer)| wgpu::BlasBuildEntry {
                blas: b,
                geometry: wgpu::BlasGeometries::AabbGeometries(vec![wgpu::BlasAabbGeometry {
                    size,
                    stride: 24,
                    aabb_buffer,
                    primitive_offset: 0,
                }]),
            })
            .collect();
        for (i, (b, (kind, _, _))) in blas.iter().zip(&kinds).enumerate() {
            tlas[i] = Some(wgpu::TlasInstance::new(b, IDENTITY, *kind, 0xFF));
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("scene accel build"),
        });
        encoder.build_acceleration_structures(entries.iter(), std::iter::once(&tlas));
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        let input_bytes = (std::mem::size_of_val(tri_boxes.as_slice())
            + std::mem::size_of_val(shape_boxes.as_slice())) as u64;
        Ok(Self {
            tlas,
            _blas: blas,
            input_bytes,
        })
    }
}
