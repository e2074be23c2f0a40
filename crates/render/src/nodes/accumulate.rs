//! Accumulate: progressive running mean with Kahan-compensated sums.
//!
//! The sums are history that outlives a frame, so they live in buffers the node owns, not
//! in the per-frame texture pool. [`NodeExec::reset`] clears them (scene or camera changed).
//!
//! When the `variance` output is read, a third buffer keeps what the variance of the mean
//! is estimated from (the Kahan sums, and so the mean, are computed exactly as without it):
//! the sum and count of the second half of the frames (`variance_estimate: halves`, every
//! other frame), or Welford's second moment over frames (`frames`). Otherwise that buffer
//! and output are 16-byte and 1×1 stand-ins and the shader skips the work.

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{History, NodeExec, NodeImpl, Recording, boxed};
use crate::pool::{PooledTexture, create};

/// The `Accumulate` kind: it owns its history buffers.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("Accumulate", |ctx, pass, _| {
    boxed(Accumulate::new(ctx, pass))
})
.owning(|pass| {
    let buffers = if pass.output("variance").is_some() {
        3
    } else {
        2
    };
    Some((
        buffers * 16 * pass.extent.pixels(),
        format!(
            "{buffers} history buffers of 16 B per pixel (sum, compensation{})",
            if buffers == 3 {
                ", half sum or second moment"
            } else {
                ""
            }
        ),
    ))
});

crate::param_block! {
    /// Accumulate's params: a 1.0 the compiler cannot fold away (it keeps the Kahan
    /// compensation), how to estimate the variance (0: not at all, 1: from the frames'
    /// spread, 2: from two halves), the image size, whether to present the history
    /// without adding to it, and the parity of the render's frame before the first one
    /// added (odd in a partial render that starts at an odd frame).
    pub(crate) struct AccumulateParams in "post/accumulate.wgsl" as "Params" {
        one: f32,
        variance: u32,
        size: [u32; 2],
        present: u32,
        parity: u32,
    }
}

/// `params.variance` when the variance is estimated from two halves of the frames.
const VARIANCE_HALVES: u32 = 2;

/// The shader's `params.variance` for `pass`: 0 when nothing reads the variance.
fn variance_mode(pass: &Pass) -> u32 {
    if pass.output("variance").is_none() {
        0
    } else if pass.params.str("variance_estimate") == "frames" {
        1
    } else {
        VARIANCE_HALVES
    }
}

pub(crate) struct Accumulate {
    kernel: Kernel,
    params: wgpu::Buffer,
    /// Size, sum, compensation and the variance's buffer (a stand-in without `variance`).
    history: Option<(Extent, wgpu::Buffer, wgpu::Buffer, wgpu::Buffer)>,
    clear: bool,
    /// The shader's `params.variance`: 0 (no `variance` output), 1 (frames) or 2 (halves).
    variance: u32,
    /// Write the mean of the history without adding a frame ([`NodeExec::set_present`]).
    present: bool,
    /// 1 when the first frame added is an odd frame of the render (the path tracer's second
    /// Sobol replicate): it then belongs to the second half.
    parity: u32,
    /// Stand-ins for an output nothing reads (color, variance).
    unused: [PooledTexture; 2],
}

/// The shader for variance mode `variance`: the code of the other modes is left out
/// (`post/accumulate_options.wgsl`).
fn kernel(ctx: &GpuContext, variance: u32) -> Result<Kernel> {
    let name = "post/accumulate.wgsl";
    let options = format!("const VARIANCE: u32 = {variance}u;\n");
    let source = crate::shader::resolve_with(name, &[("post/accumulate_options.wgsl", options)])?;
    Kernel::from_source(ctx, name, &source)
}

impl Accumulate {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let variance = variance_mode(pass);
        let kernel = kernel(ctx, variance)?;
        let block = AccumulateParams {
            one: 1.0,
            variance,
            ..AccumulateParams::default()
        };
        let params = uniform_buffer(ctx, "accumulate params", bytemuck::bytes_of(&block));
        let one = Extent::new(1, 1);
        Ok(Self {
            kernel,
            params,
            history: None,
            clear: true,
            variance,
            present: false,
            parity: 0,
            unused: [
                create(ctx, "unused accumulate color", TexFormat::Rgba32Float, one),
                create(
                    ctx,
                    "unused accumulate variance",
                    TexFormat::Rgba32Float,
                    one,
                ),
            ],
        })
    }
}

impl Accumulate {
    /// New (uncleared) history buffers for `extent`.
    fn make_history(&mut self, ctx: &GpuContext, extent: Extent) {
        let make = |label, size| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let bytes = extent.pixels() * 16;
        self.history = Some((
            extent,
            make("accumulate sum", bytes),
            make("accumulate compensation", bytes),
            make(
                "accumulate second moment",
                if self.variance > 0 { bytes } else { 16 },
            ),
        ));
    }

    /// Writes the params block for `extent` (done with every clear).
    fn write_params(&self, ctx: &GpuContext, extent: Extent) {
        // The image size rides with the params (outputs may be 1×1 stand-ins).
        let block = AccumulateParams {
            one: 1.0,
            variance: self.variance,
            size: [extent.width, extent.height],
            present: u32::from(self.present),
            parity: self.parity,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
    }
}

impl NodeExec for Accumulate {
    fn history(&mut self) -> Option<&mut dyn History> {
        Some(self)
    }

    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        // Another estimate keeps other numbers in the third buffer (and has its own
        // shader): start again.
        let variance = variance_mode(pass);
        if variance != self.variance {
            self.kernel = kernel(ctx, variance)?;
            self.variance = variance;
            self.history = None;
            self.clear = true;
        }
        Ok(())
    }

    fn reset(&mut self) {
        self.clear = true;
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let input = io.input(pass, "color")?;
        let (out, var) = (pass.output("color"), pass.output("variance"));
        if out.is_none() && var.is_none() {
            return Ok(());
        }
        let extent = pass.extent;
        if self.present && (self.clear || self.history.as_ref().is_none_or(|(e, ..)| *e != extent))
        {
            return Err(crate::error::RenderError::Gpu(
                "no accumulated samples to present".into(),
            ));
        }
        let mut clear = std::mem::take(&mut self.clear);
        if self.history.as_ref().is_none_or(|(e, ..)| *e != extent) {
            self.make_history(ctx, extent);
            clear = true;
        }
        let Some((_, sum, comp, m2)) = &self.history else {
            return Ok(());
        };
        if clear {
            encoder.clear_buffer(sum, 0, None);
            encoder.clear_buffer(comp, 0, None);
            encoder.clear_buffer(m2, 0, None);
        }
        if clear {
            self.write_params(ctx, extent);
        }
        let view = |t: Option<lumagraph_graph::TextureId>, i: usize| {
            t.map_or(&self.unused[i].view, |t| &io.texture(t).view)
        };
        let color_view = view(out, 0);
        self.kernel
            .pass(&pass.node)
            .read(&input.view)
            .write(color_view)
            .buffer(sum)
            .buffer(comp)
            .uniform(&self.params)
            .buffer(m2)
            .write(view(var, 1))
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}

impl History for Accumulate {
    fn save_state(&mut self, ctx: &GpuContext) -> Result<Vec<u8>> {
        // Header: width, height, and the size of each buffer; then the buffers. No history
        // yet (or one to be cleared) is an empty state.
        let Some((extent, sum, comp, m2)) = self.history.as_ref().filter(|_| !self.clear) else {
            return Ok(Vec::new());
        };
        let mut out = Vec::new();
        out.extend_from_slice(&extent.width.to_le_bytes());
        out.extend_from_slice(&extent.height.to_le_bytes());
        for b in [sum, comp, m2] {
            out.extend_from_slice(&b.size().to_le_bytes());
        }
        for b in [sum, comp, m2] {
            crate::readback::append_buffer(ctx, b, &mut out)?;
        }
        Ok(out)
    }
    fn load_state(&mut self, ctx: &GpuContext, pass: &Pass, state: &[u8]) -> Result<()> {
        if state.is_empty() {
            self.clear = true;
            return Ok(());
        }
        let bad =
            |why: String| crate::error::RenderError::Gpu(format!("accumulation state: {why}"));
        let (w, h, sections) = sections(state).map_err(bad)?;
        if Extent::new(w, h) != pass.extent {
            return Err(bad(format!("{w}×{h}, but the image is {}", pass.extent)));
        }
        self.make_history(ctx, pass.extent);
        let Some((_, sum, comp, m2)) = &self.history else {
            return Err(bad("no buffers".into()));
        };
        for (b, bytes) in [sum, comp, m2].into_iter().zip(sections) {
            if bytes.len() as u64 != b.size() {
                return Err(bad(format!(
                    "a buffer of {} bytes where {} are expected (variance on or off?)",
                    bytes.len(),
                    b.size()
                )));
            }
            ctx.queue.write_buffer(b, 0, bytes);
        }
        self.write_params(ctx, pass.extent);
        self.clear = false;
        Ok(())
    }
    fn start_at_sample(&mut self, _first: u32, frames: u64) {
        self.parity = u32::from(frames % 2 == 1);
    }
    fn set_present(&mut self, ctx: &GpuContext, present: bool) {
        self.present = present;
        if let Some((extent, ..)) = &self.history {
            self.write_params(ctx, *extent);
        }
    }
    fn merge_states(&mut self, states: &[&[u8]]) -> Result<Vec<u8>> {
        merge_accumulations(states, self.variance == VARIANCE_HALVES)
            .map_err(|e| crate::error::RenderError::Gpu(format!("accumulation state: {e}")))
    }
}

// Merging the states of partial renders (`lumagraph merge`, crate::partial).

/// Rec. 709 luminance weights, as `post/accumulate.wgsl` has them (`m2.a` is of the
/// luminance).
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// The layout [`Accumulate::save_state`] writes, split: width, height, and the bytes of
/// the sum, compensation and second-moment buffers (each preceded by its size in the
/// header). Read by `load_state` and by the merge of partial renders.
fn sections(state: &[u8]) -> std::result::Result<(u32, u32, [&[u8]; 3]), String> {
    let u32_at = |i: usize| {
        state
            .get(i..i + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
    };
    let u64_at = |i: usize| {
        state
            .get(i..i + 8)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes)
    };
    let (Some(width), Some(height)) = (u32_at(0), u32_at(4)) else {
        return Err("truncated".into());
    };
    let mut at: usize = 8 + 3 * 8;
    let mut out: [&[u8]; 3] = [&[]; 3];
    for (i, section) in out.iter_mut().enumerate() {
        let size = u64_at(8 + 8 * i).ok_or("truncated")?;
        let len = usize::try_from(size).map_err(|_| "too large")?;
        *section = state
            .get(at..at.checked_add(len).ok_or("too large")?)
            .ok_or("truncated")?;
        at += len;
    }
    if at != state.len() {
        return Err(format!("{} bytes too many", state.len() - at));
    }
    Ok((width, height, out))
}

/// An accumulation's state (see `Accumulate::save_state`): size, and per pixel the Kahan
/// sum (`rgb`, frames in `a`), its compensation, and the second moment (or a 16-byte
/// stand-in), all `vec4<f32>`.
#[derive(Debug)]
struct Accumulation {
    width: u32,
    height: u32,
    sum: Vec<[f32; 4]>,
    comp: Vec<[f32; 4]>,
    m2: Vec<[f32; 4]>,
}

impl Accumulation {
    fn parse(state: &[u8]) -> std::result::Result<Self, String> {
        if state.is_empty() {
            return Err("a partial render without samples".into());
        }
        let (width, height, sections) = sections(state)?;
        let mut buffers = Vec::new();
        for bytes in sections {
            if bytes.len() % 16 != 0 {
                return Err(format!(
                    "a buffer of {} bytes, not whole pixels",
                    bytes.len()
                ));
            }
            buffers.push(
                bytes
                    .chunks_exact(16)
                    .map(|p| {
                        let mut v = [0f32; 4];
                        for (c, b) in v.iter_mut().zip(p.chunks_exact(4)) {
                            *c = f32::from_le_bytes(b.try_into().unwrap_or_default());
                        }
                        v
                    })
                    .collect::<Vec<_>>(),
            );
        }
        let m2 = buffers.pop().unwrap_or_default();
        let comp = buffers.pop().unwrap_or_default();
        let sum = buffers.pop().unwrap_or_default();
        let pixels = u64::from(width) * u64::from(height);
        if sum.len() as u64 != pixels || comp.len() != sum.len() {
            return Err(format!(
                "{width}×{height} with buffers of {} and {} pixels",
                sum.len(),
                comp.len()
            ));
        }
        Ok(Self {
            width,
            height,
            sum,
            comp,
            m2,
        })
    }

    fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(&self.width.to_le_bytes());
        out.extend_from_slice(&self.height.to_le_bytes());
        for b in [&self.sum, &self.comp, &self.m2] {
            out.extend_from_slice(&(b.len() as u64 * 16).to_le_bytes());
        }
        for b in [&self.sum, &self.comp, &self.m2] {
            for p in b {
                for c in p {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        out
    }
}

/// `a + b` as a sum and its exact rounding error (Knuth's `TwoSum`).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// A sum of `f64` kept as an unevaluated pair (`hi + lo`), exact for the few terms of a
/// merge (the low parts' own rounding is below 2^-100 of the sum).
#[derive(Clone, Copy, Default)]
struct Exact {
    hi: f64,
    lo: f64,
}

impl Exact {
    fn plus(self, x: f64) -> Self {
        let (hi, e) = two_sum(self.hi, x);
        let (hi, lo) = two_sum(hi, self.lo + e);
        Self { hi, lo }
    }

    /// Rounded once to the nearest `f32` (ties to even), looking at both parts.
    fn to_f32(self) -> f32 {
        #[expect(clippy::cast_possible_truncation, reason = "the rounding is the point")]
        let r = self.hi as f32;
        if !r.is_finite() {
            return r;
        }
        // How far the exact value lies from r (hi - r is exact: they share the top bits).
        let d = (self.hi - f64::from(r)) + self.lo;
        let next = if d > 0.0 { r.next_up() } else { r.next_down() };
        let half = (f64::from(next) - f64::from(r)).abs() / 2.0;
        if d.abs() > half || (d.abs() == half && r.to_bits() & 1 == 1) {
            next
        } else {
            r
        }
    }
}

/// Merges accumulation states of disjoint sample ranges into one: per pixel and channel
/// the exact sum of every part's compensated Kahan sum (sum − compensation), rounded once
/// to `f32`, with the rounding error as the new compensation, so the mean is the correctly
/// rounded mean of every frame added; the frame counts summed; the variance's buffer
/// combined: with `halves` (Accumulate's `variance_estimate: halves`) the second halves'
/// sums and counts added (in `f64`, rounded once), otherwise the second moments with the
/// pairwise formula of Chan, Golub and `LeVeque` (in `f64`, rounded once).
///
/// # Errors
/// When a state does not parse or the states are of other sizes.
pub(crate) fn merge_accumulations(
    states: &[&[u8]],
    halves: bool,
) -> std::result::Result<Vec<u8>, String> {
    let parts = states
        .iter()
        .map(|s| Accumulation::parse(s))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let Some(first) = parts.first() else {
        return Err("nothing to merge".into());
    };
    for p in &parts {
        if (p.width, p.height, p.m2.len()) != (first.width, first.height, first.m2.len()) {
            return Err(format!(
                "partial renders of {}×{} and {}×{} pixels (or with and without variance)",
                first.width, first.height, p.width, p.height
            ));
        }
    }
    if let [one] = states {
        // Nothing to add: the state as it is (a merge of one range equals its render).
        return Ok(one.to_vec());
    }
    let variance = first.m2.len() == first.sum.len();
    let mut merged = Accumulation {
        width: first.width,
        height: first.height,
        sum: Vec::with_capacity(first.sum.len()),
        comp: Vec::with_capacity(first.sum.len()),
        m2: first.m2.clone(),
    };
    for i in 0..first.sum.len() {
        let mut sum = [0f32; 4];
        let mut comp = [0f32; 4];
        let mut frames = 0f32;
        for p in &parts {
            frames += p.sum[i][3];
        }
        for c in 0..3 {
            let exact = parts.iter().fold(Exact::default(), |e, p| {
                e.plus(f64::from(p.sum[i][c]))
                    .plus(-f64::from(p.comp[i][c]))
            });
            sum[c] = exact.to_f32();
            // Kahan's invariant: the exact sum is sum − compensation.
            #[expect(clippy::cast_possible_truncation, reason = "f32 state")]
            let residual = ((f64::from(sum[c]) - exact.hi) - exact.lo) as f32;
            comp[c] = residual;
        }
        sum[3] = frames;
        merged.sum.push(sum);
        merged.comp.push(comp);
        if variance {
            merged.m2[i] = if halves {
                half_sums(&parts, i)
            } else {
                chan(&parts, i)
            };
        }
    }
    Ok(merged.to_bytes())
}

/// The sum (rgb) and count (alpha) of every part's second half of frames together.
fn half_sums(parts: &[Accumulation], i: usize) -> [f32; 4] {
    let total: [f64; 4] =
        std::array::from_fn(|c| parts.iter().map(|p| f64::from(p.m2[i][c])).sum());
    #[expect(clippy::cast_possible_truncation, reason = "f32 state")]
    total.map(|v| v as f32)
}

/// The second moment (per channel, and of the luminance) of every part's frames together:
/// `M2 = M2_a + M2_b + δ² n_a n_b / n`, part by part.
fn chan(parts: &[Accumulation], i: usize) -> [f32; 4] {
    let mut n = 0f64;
    let mut mean = [0f64; 3];
    let mut m2 = [0f64; 4];
    for p in parts {
        let nb = f64::from(p.sum[i][3]);
        if nb == 0.0 {
            continue;
        }
        let mb: [f64; 3] =
            std::array::from_fn(|c| (f64::from(p.sum[i][c]) - f64::from(p.comp[i][c])) / nb);
        let total = n + nb;
        let delta: [f64; 3] = std::array::from_fn(|c| mb[c] - mean[c]);
        let w = n * nb / total;
        for c in 0..3 {
            m2[c] += f64::from(p.m2[i][c]) + delta[c] * delta[c] * w;
            mean[c] += delta[c] * nb / total;
        }
        let dl: f64 = (0..3).map(|c| delta[c] * f64::from(LUMA[c])).sum();
        m2[3] += f64::from(p.m2[i][3]) + dl * dl * w;
        n = total;
    }
    #[expect(clippy::cast_possible_truncation, reason = "f32 state")]
    m2.map(|v| v as f32)
}

#[cfg(test)]
mod merge_tests {
    use super::*;

    /// Kahan sums of a sequence in one go and in four parts: the merged sum is the exact
    /// sum rounded once, as is the single one but where the exact sum lies within the
    /// single sum's tiny error of a rounding boundary.
    #[test]
    fn merged_kahan_sums_are_the_exact_sum_rounded_once() {
        let kahan = |xs: &[f32]| {
            let (mut s, mut c) = (0f32, 0f32);
            for &x in xs {
                let y = x - c;
                let t = s + y;
                c = (t - s) - y;
                s = t;
            }
            (s, c)
        };
        let mut state = 12345u64;
        let mut differ = 0;
        let trials = 2000;
        for _ in 0..trials {
            let xs: Vec<f32> = (0..64)
                .map(|_| {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1);
                    #[expect(clippy::cast_precision_loss, reason = "test values")]
                    let u = (state >> 40) as f32 / (1u64 << 24) as f32;
                    u * u * 3.0
                })
                .collect();
            let pixel = |s: f32, c: f32, n: f32| {
                let mut b = Vec::new();
                for v in [1u32, 1] {
                    b.extend_from_slice(&v.to_le_bytes());
                }
                for v in [16u64, 16, 16] {
                    b.extend_from_slice(&v.to_le_bytes());
                }
                for v in [s, s, s, n, c, c, c, 0.0, 0.0, 0.0, 0.0, 0.0] {
                    b.extend_from_slice(&v.to_le_bytes());
                }
                b
            };
            let states: Vec<Vec<u8>> = xs
                .chunks(16)
                .map(|part| {
                    let (s, c) = kahan(part);
                    pixel(s, c, 16.0)
                })
                .collect();
            let refs: Vec<&[u8]> = states.iter().map(Vec::as_slice).collect();
            let merged = Accumulation::parse(&merge_accumulations(&refs, false).unwrap()).unwrap();
            let exact: f64 = xs.iter().map(|&x| f64::from(x)).sum();
            #[expect(clippy::cast_possible_truncation, reason = "rounding once")]
            let rounded = exact as f32;
            let ulps = |a: f32, b: f32| a.to_bits().abs_diff(b.to_bits());
            assert!(
                ulps(merged.sum[0][0], rounded) <= 1,
                "{merged:?} vs {exact}"
            );
            assert_eq!(merged.sum[0][3], 64.0);
            let single = kahan(&xs).0;
            if single != merged.sum[0][0] {
                differ += 1;
                assert!(
                    ulps(single, merged.sum[0][0]) <= 1,
                    "{single} vs {merged:?}"
                );
            }
        }
        eprintln!("{differ} of {trials} merged sums differ from the single one (by 1 ulp)");
        // f32 Kahan loses the low bits of the compensation in `x − c` (about 0.03 ulp of
        // the sum over 64 terms of 1), so a few per cent of sums fall on the other side of a
        // rounding boundary.
        assert!(differ * 10 < trials, "{differ} of {trials} differ");
    }

    #[test]
    fn second_moments_merge_as_one_pass_over_all_frames() {
        let xs = [0.5f32, 2.0, 0.25, 4.0, 1.0, 3.0];
        let welford = |xs: &[f32]| {
            let (mut n, mut mean, mut m2) = (0f64, 0f64, 0f64);
            for &x in xs {
                n += 1.0;
                let d = f64::from(x) - mean;
                mean += d / n;
                m2 += d * (f64::from(x) - mean);
            }
            (mean * n, m2)
        };
        let state = |part: &[f32]| {
            let (s, m2) = welford(part);
            #[expect(clippy::cast_possible_truncation, reason = "f32 state")]
            let (s, m2) = (s as f32, m2 as f32);
            #[expect(clippy::cast_precision_loss, reason = "small counts")]
            let n = part.len() as f32;
            let mut b = Vec::new();
            for v in [1u32, 1] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            for v in [16u64, 16, 16] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            let l = m2 * LUMA.iter().sum::<f32>().powi(2);
            for v in [s, s, s, n, 0.0, 0.0, 0.0, 0.0, m2, m2, m2, l] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b
        };
        let (a, b) = (state(&xs[..2]), state(&xs[2..]));
        let merged = Accumulation::parse(&merge_accumulations(&[&a, &b], false).unwrap()).unwrap();
        let (_, m2) = welford(&xs);
        assert!(
            (f64::from(merged.m2[0][0]) - m2).abs() < 1e-5 * m2,
            "{merged:?}"
        );
        let l = m2 * f64::from(LUMA.iter().sum::<f32>()).powi(2);
        assert!((f64::from(merged.m2[0][3]) - l).abs() < 1e-5 * m2);
        assert_eq!(merged.sum[0][3], 6.0);
    }
}
