//! The path tracer's history (its sample counter, counts and adaptive sampling's state):
//! saved in checkpoints, started at a sample for partial renders, merged and presented.

use lumagraph_graph::Pass;

use super::PathTrace;
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::nodes::{History, NodeExec};

impl PathTrace {
    /// Restores adaptive sampling's buffers from what follows the counters in a saved state
    /// (nothing: adaptive sampling was off, or no frame had run).
    fn load_adaptive(&mut self, ctx: &GpuContext, pass: &Pass, rest: &[u8]) -> Result<()> {
        let a = &mut self.adaptive;
        if rest.is_empty() {
            a.clear = true;
            return Ok(());
        }
        let px = usize::try_from(pass.extent.pixels()).unwrap_or(usize::MAX);
        let expected = 8 + 36 * px;
        let size = rest.get(..8).map(|b| {
            [&b[..4], &b[4..]].map(|w| u32::from_le_bytes(w.try_into().unwrap_or_default()))
        });
        if !a.on()
            || rest.len() != expected
            || size != Some([pass.extent.width, pass.extent.height])
        {
            return Err(RenderError::Gpu(format!(
                "a path tracer's adaptive sampling state does not fit: {} bytes for {} \
                 ({expected} expected; is adaptive_error on in both?)",
                rest.len(),
                pass.extent
            )));
        }
        a.fit(ctx, pass.extent);
        ctx.queue.write_buffer(&a.halves, 0, &rest[8..8 + 32 * px]);
        ctx.queue.write_buffer(&a.stopped, 0, &rest[8 + 32 * px..]);
        a.clear = false;
        Ok(())
    }
}

impl History for PathTrace {
    fn save_state(&mut self, ctx: &GpuContext) -> Result<Vec<u8>> {
        // Folds the GPU's counters into the totals first.
        self.counters(ctx)?;
        let mut bytes = Vec::with_capacity(24);
        for v in [u64::from(self.samples), self.dropped, self.rays] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        // Adaptive sampling's state follows: the window size, the halves, the stopped flags.
        let a = &self.adaptive;
        if a.on() && !a.clear && a.extent.pixels() > 0 {
            bytes.extend_from_slice(&a.extent.width.to_le_bytes());
            bytes.extend_from_slice(&a.extent.height.to_le_bytes());
            lumagraph_render::readback::append_buffer(ctx, &a.halves, &mut bytes)?;
            lumagraph_render::readback::append_buffer(ctx, &a.stopped, &mut bytes)?;
        }
        Ok(bytes)
    }
    fn load_state(&mut self, ctx: &GpuContext, pass: &Pass, state: &[u8]) -> Result<()> {
        let word = |i: usize| {
            state
                .get(8 * i..8 * i + 8)
                .and_then(|b| b.try_into().ok())
                .map(u64::from_le_bytes)
        };
        let (Some(samples), Some(dropped), Some(rays)) = (word(0), word(1), word(2)) else {
            return Err(RenderError::Gpu(format!(
                "a path tracer's state is at least 24 bytes, this one {}",
                state.len()
            )));
        };
        self.load_adaptive(ctx, pass, &state[24..])?;
        self.samples = u32::try_from(samples)
            .map_err(|_| RenderError::Gpu(format!("{samples} samples per pixel is too many")))?;
        self.dropped = dropped;
        self.rays = rays;
        Ok(())
    }
    fn start_at_sample(&mut self, first: u32, _frames: u64) {
        self.samples = first;
    }
    fn set_present(&mut self, _ctx: &GpuContext, present: bool) {
        // Presenting re-runs the frame that took the last samples (for outputs read
        // downstream, such as the first-hit AOVs); recording it counts them again.
        if present {
            self.samples = self.samples.saturating_sub(self.samples_per_frame);
        }
    }
    fn merge_states(&mut self, states: &[&[u8]]) -> Result<Vec<u8>> {
        merge_path_tracers(states).map_err(RenderError::Gpu)
    }
}

/// Merges path tracer states (samples, dropped samples, rays, `u64` each): the samples of
/// the last range's end, the counts summed.
///
/// # Errors
/// When a state is not a path tracer's.
fn merge_path_tracers(states: &[&[u8]]) -> std::result::Result<Vec<u8>, String> {
    let mut merged = [0u64; 3];
    for state in states {
        if state.len() != 24 {
            return Err(if state.len() > 24 {
                "adaptive sampling cannot be split into sample ranges: each part would stop \
                 pixels by its own samples (render it whole, or tile it)"
                    .to_owned()
            } else {
                format!(
                    "a path tracer's state is 24 bytes, this one {}",
                    state.len()
                )
            });
        }
        let word =
            |i: usize| u64::from_le_bytes(state[8 * i..8 * i + 8].try_into().unwrap_or_default());
        merged[0] = merged[0].max(word(0));
        merged[1] += word(1);
        merged[2] += word(2);
    }
    Ok(merged.iter().flat_map(|v| v.to_le_bytes()).collect())
}
