//! The path tracer's sampler on the GPU (`shaders/pathtrace/integrator/sampler.wgsl`), evaluated for a
//! list of queries so tests can hold it against the `sobol_burley` crate and check the
//! stratification of the points a pixel gets.

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use lumagraph_render::kernel::{Kernel, storage_buffer, uniform_buffer};
use lumagraph_render::readback::{compute_and_read, groups_1d};

/// What a query asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerQuery {
    /// `sobol_owen(index, dimension, seed)`: one Owen-scrambled Sobol value (`index < 2^16`,
    /// `dimension < 4`); the point's second coordinate is 0.
    Sobol {
        /// Sample index.
        index: u32,
        /// Dimension.
        dimension: u32,
        /// Sequence seed.
        seed: u32,
    },
    /// The 2D point of dimension pair `pair` of sample `sample` in pixel `pixel` under the
    /// render seed `seed`, as the path tracer's Sobol sampler draws it (one replicate).
    Pixel {
        /// Pixel index (`y * width + x`).
        pixel: u32,
        /// Sample index within the pixel's sequence.
        sample: u32,
        /// The scene's seed.
        seed: u32,
        /// Dimension pair (0 pixel position, 1 lens, 2 light point, 3 BSDF direction).
        pair: u32,
    },
}

/// The sampler kernel.
#[derive(Debug)]
pub struct SamplerCheck {
    kernel: Kernel,
}

impl SamplerCheck {
    /// Compiles the kernel.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let kernel = Kernel::new(ctx, "pathtrace/integrator/sampler_points.wgsl")?;
        Ok(Self { kernel })
    }

    /// The points of `queries`, which must all be of one kind.
    ///
    /// # Errors
    /// When the GPU work fails.
    ///
    /// # Panics
    /// When the queries mix kinds.
    pub fn points(&self, ctx: &GpuContext, queries: &[SamplerQuery]) -> Result<Vec<[f32; 2]>> {
        let Some(first) = queries.first() else {
            return Ok(Vec::new());
        };
        let mode = u32::from(matches!(first, SamplerQuery::Pixel { .. }));
        let words: Vec<[u32; 4]> = queries
            .iter()
            .map(|q| match *q {
                SamplerQuery::Sobol {
                    index,
                    dimension,
                    seed,
                } => {
                    assert_eq!(mode, 0, "queries of one kind only");
                    [index, dimension, seed, 0]
                }
                SamplerQuery::Pixel {
                    pixel,
                    sample,
                    seed,
                    pair,
                } => {
                    assert_eq!(mode, 1, "queries of one kind only");
                    [pixel, sample, seed, pair]
                }
            })
            .collect();
        let count = u32::try_from(queries.len()).unwrap_or(u32::MAX);
        let params = uniform_buffer(
            ctx,
            "sampler params",
            bytemuck::bytes_of(&[count, mode, 0, 0]),
        );
        let input = storage_buffer(ctx, "sampler queries", bytemuck::cast_slice(&words));
        compute_and_read::<[f32; 2]>(ctx, "sampler points", queries.len(), |encoder, output| {
            self.kernel
                .pass("sampler")
                .uniform(&params)
                .buffer(&input)
                .buffer(output)
                .dispatch(ctx, encoder, groups_1d(count, 64), None)
        })
    }
}
