//! The path tracer's BSDF (`shaders/pathtrace/bsdf/bsdf.wgsl`) on its own, sampled and evaluated
//! on the GPU for one material and outgoing direction, so tests can check each lobe's
//! sampling against its pdf (chi-square), its weights against `f · cos / pdf` and its
//! reciprocity. The kernel is `shaders/pathtrace/bsdf/bsdf_check.wgsl`.

use glam::Vec3;
use lumagraph_scene::GpuMaterial;

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use lumagraph_render::kernel::{Kernel, storage_buffer, uniform_buffer};
use lumagraph_render::readback::{compute_and_read, groups_1d};

/// One sample of the BSDF, in the shading frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled incident direction (unit).
    pub wi: Vec3,
    /// Solid-angle pdf the path tracer uses for MIS (0 for delta and glass samples).
    pub pdf: f32,
    /// `f · cos / pdf` of the sampling done.
    pub weight: Vec3,
    /// Whether the sample is valid (else the path ends).
    pub valid: bool,
}

/// `eval_bsdf` at one incident direction, and with the directions swapped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfValue {
    /// `f(wo, wi) · cos θi`.
    pub f_cos: Vec3,
    /// Solid-angle pdf of sampling `wi` from `wo`.
    pub pdf: f32,
    /// `f(wi, wo) · cos θo`.
    pub f_cos_swapped: Vec3,
    /// Solid-angle pdf of sampling `wo` from `wi`.
    pub pdf_swapped: f32,
}

/// What one dispatch of the kernel does.
enum Job<'a> {
    /// `count` samples with random numbers from `seed`.
    Sample { count: u32, seed: u32 },
    /// Evaluation at these directions.
    Eval(&'a [[f32; 4]]),
}

/// The BSDF kernel with the GGX albedo tables.
#[derive(Debug)]
pub struct BsdfCheck {
    kernel: Kernel,
    ggx_table: wgpu::Buffer,
    /// The clear coat's normal in the shading frame (unit; +z, the default, where the coat
    /// shares the base's normal), as the path tracer sets it per point shaded.
    pub coat_normal: Vec3,
}

impl BsdfCheck {
    /// Compiles the kernel (every lobe compiled in).
    ///
    /// # Errors
    /// When the shader does not compile.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let kernel = Kernel::new(ctx, "pathtrace/bsdf/bsdf_check.wgsl")?;
        let ggx_table = crate::bsdf_tables::upload(ctx, true);
        Ok(Self {
            kernel,
            ggx_table,
            coat_normal: Vec3::Z,
        })
    }

    fn run(
        &self,
        ctx: &GpuContext,
        material: &GpuMaterial,
        wo: Vec3,
        job: &Job<'_>,
    ) -> Result<Vec<[f32; 4]>> {
        let (mode, seed, dirs, count) = match *job {
            Job::Sample { count, seed } => (0, seed, &[][..], count),
            Job::Eval(dirs) => (1, 0, dirs, u32::try_from(dirs.len()).unwrap_or(u32::MAX)),
        };
        let mut params = [0u32; 12];
        params[..3].copy_from_slice(&wo.to_array().map(f32::to_bits));
        params[3] = count;
        params[4] = mode;
        params[5] = seed;
        params[8..11].copy_from_slice(&self.coat_normal.to_array().map(f32::to_bits));
        let params = uniform_buffer(ctx, "bsdf check params", bytemuck::cast_slice(&params));
        let material = storage_buffer(ctx, "bsdf check material", bytemuck::bytes_of(material));
        let dirs = if dirs.is_empty() {
            &[[0.0; 4]][..]
        } else {
            dirs
        };
        let dirs = storage_buffer(ctx, "bsdf check directions", bytemuck::cast_slice(dirs));
        compute_and_read::<[f32; 4]>(ctx, "bsdf check", 2 * count as usize, |encoder, out| {
            self.kernel
                .pass("bsdf check")
                .uniform(&params)
                .buffer(&material)
                .buffer(&self.ggx_table)
                .buffer(&dirs)
                .buffer(out)
                .dispatch(ctx, encoder, groups_1d(count, 64), None)
        })
    }

    /// `count` samples of `material` seen from `wo` (unit, shading frame), with random
    /// numbers from `seed`.
    ///
    /// # Errors
    /// When the GPU work fails.
    pub fn sample(
        &self,
        ctx: &GpuContext,
        material: &GpuMaterial,
        wo: Vec3,
        count: u32,
        seed: u32,
    ) -> Result<Vec<BsdfSample>> {
        if count == 0 {
            return Ok(Vec::new());
        }
        let raw = self.run(ctx, material, wo, &Job::Sample { count, seed })?;
        Ok(raw
            .chunks_exact(2)
            .map(|p| BsdfSample {
                wi: Vec3::new(p[0][0], p[0][1], p[0][2]),
                pdf: p[0][3],
                weight: Vec3::new(p[1][0], p[1][1], p[1][2]),
                valid: p[1][3] != 0.0,
            })
            .collect())
    }

    /// `eval_bsdf` of `material` from `wo` at every direction of `wis` (and swapped).
    ///
    /// # Errors
    /// When the GPU work fails.
    pub fn eval(
        &self,
        ctx: &GpuContext,
        material: &GpuMaterial,
        wo: Vec3,
        wis: &[Vec3],
    ) -> Result<Vec<BsdfValue>> {
        if wis.is_empty() {
            return Ok(Vec::new());
        }
        let dirs: Vec<[f32; 4]> = wis.iter().map(|d| d.extend(0.0).to_array()).collect();
        let raw = self.run(ctx, material, wo, &Job::Eval(&dirs))?;
        Ok(raw
            .chunks_exact(2)
            .map(|p| BsdfValue {
                f_cos: Vec3::new(p[0][0], p[0][1], p[0][2]),
                pdf: p[0][3],
                f_cos_swapped: Vec3::new(p[1][0], p[1][1], p[1][2]),
                pdf_swapped: p[1][3],
            })
            .collect())
    }
}
