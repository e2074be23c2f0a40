//! Partial renders: one render split by sample range across processes or machines, and
//! merged into what a single render of all the ranges writes.
//!
//! `lumagraph render --samples START..END` takes only the samples `START..END` of each
//! pixel's sequence (the path tracer's sampler is indexed by sample, so they are exactly
//! the samples a whole render takes there) and writes a [`Partial`]: the range, the graph,
//! scene and overrides it was rendered with, and a [`Checkpoint`] of the render so far
//! (its key hashes graph, scene and settings; its states hold the path tracer's counters
//! and the accumulation's Kahan sums, compensations and second moments). `lumagraph merge`
//! checks that partials belong together ([`arrange`]), merges their states
//! ([`crate::Executor::merge`]: the sums exactly, [`merge_accumulations`]) and runs the
//! graph over the merged history ([`crate::Executor::present`]).
//!
//! The file: a magic line, the format version, the range's first and end sample, the
//! samples per frame, the graph path, the scene path (empty: none), the overrides, then the
//! checkpoint's bytes ([`Checkpoint::to_bytes`]); numbers are little-endian `u64`, texts
//! and the checkpoint are preceded by their length. It is written atomically.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::checkpoint::{Checkpoint, Reader, put};
use crate::error::{RenderError, Result};

/// The file's first bytes.
const MAGIC: &[u8] = b"lumagraph partial\n";
/// Its format version.
const FORMAT: u64 = 1;

/// Rec. 709 luminance weights, as `post/accumulate.wgsl` has them (`m2.a` is of the
/// luminance).
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// A render of one range of sample indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Partial {
    /// The first sample index rendered.
    pub first: u32,
    /// One past the last sample index rendered.
    pub end: u32,
    /// Samples each frame takes (ranges start and end on frames).
    pub samples_per_frame: u32,
    /// The graph file rendered.
    pub graph: PathBuf,
    /// The scene file rendered, if any.
    pub scene: Option<PathBuf>,
    /// The param overrides applied (`node.param=value`).
    pub overrides: Vec<String>,
    /// The render's state at the range's end.
    pub checkpoint: Checkpoint,
}

impl Partial {
    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        for v in [
            FORMAT,
            u64::from(self.first),
            u64::from(self.end),
            u64::from(self.samples_per_frame),
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        put(&mut out, self.graph.to_string_lossy().as_bytes());
        let scene = self
            .scene
            .as_ref()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        put(&mut out, scene.as_bytes());
        out.extend_from_slice(&(self.overrides.len() as u64).to_le_bytes());
        for o in &self.overrides {
            put(&mut out, o.as_bytes());
        }
        put(&mut out, &self.checkpoint.to_bytes());
        out
    }

    /// Parses a file's bytes.
    ///
    /// # Errors
    /// When they are not a partial render of this format, or are cut short.
    pub fn from_bytes(bytes: &[u8]) -> std::result::Result<Self, String> {
        let rest = bytes
            .strip_prefix(MAGIC)
            .ok_or("not a lumagraph partial render")?;
        let mut r = Reader { bytes: rest, at: 0 };
        let short = || "cut short".to_owned();
        let format = r.u64().ok_or_else(short)?;
        if format != FORMAT {
            return Err(format!(
                "partial render format {format}; this lumagraph reads format {FORMAT}"
            ));
        }
        let mut number = |what: &str| {
            let v = r.u64().ok_or_else(short)?;
            u32::try_from(v).map_err(|_| format!("{what} {v} is out of range"))
        };
        let first = number("first sample")?;
        let end = number("end sample")?;
        let samples_per_frame = number("samples per frame")?;
        let graph = PathBuf::from(r.text().ok_or_else(short)?);
        let scene = Some(r.text().ok_or_else(short)?)
            .filter(|s| !s.is_empty())
            .map(PathBuf::from);
        let n = r.u64().ok_or_else(short)?;
        let mut overrides = Vec::new();
        for _ in 0..n {
            overrides.push(r.text().ok_or_else(short)?);
        }
        let checkpoint = Checkpoint::from_bytes(r.field().ok_or_else(short)?)?;
        if r.at != r.bytes.len() {
            return Err(format!("{} bytes after the end", r.bytes.len() - r.at));
        }
        if first >= end || samples_per_frame == 0 {
            return Err(format!(
                "an empty range {first}..{end} ({samples_per_frame} samples per frame)"
            ));
        }
        Ok(Self {
            first,
            end,
            samples_per_frame,
            graph,
            scene,
            overrides,
            checkpoint,
        })
    }

    /// Writes it to `path` atomically.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn save(&self, path: &Path) -> Result<()> {
        lumagraph_graph::write_atomic(path, &self.to_bytes())
            .map_err(|e| RenderError::image(path, format!("cannot write the partial render: {e}")))
    }

    /// Reads the partial render at `path`.
    ///
    /// # Errors
    /// When it cannot be read or is not a partial render; the error names the file.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| {
            RenderError::image(path, format!("cannot read the partial render: {e}"))
        })?;
        Self::from_bytes(&bytes).map_err(|e| RenderError::image(path, e))
    }

    /// The range as `first..end`.
    pub fn range(&self) -> String {
        format!("{}..{}", self.first, self.end)
    }
}

/// Sorts partial renders (each with the file it came from) by range and checks that they
/// belong together: the same lumagraph version, key (graph, scene, settings), samples per
/// frame, files and overrides, and ranges that do not overlap and, unless `allow_gaps`,
/// leave no gap from sample 0 to the last one.
///
/// # Errors
/// Every problem found, one a line, naming the files and the ranges.
pub fn arrange(
    mut parts: Vec<(PathBuf, Partial)>,
    allow_gaps: bool,
) -> std::result::Result<Vec<(PathBuf, Partial)>, String> {
    let Some((first_path, first)) = parts.first().cloned() else {
        return Err("no partial renders to merge".into());
    };
    parts.sort_by_key(|(_, p)| (p.first, p.end));
    let mut problems = String::new();
    for (path, p) in &parts {
        let c = &p.checkpoint;
        let differs = [
            (c.version != first.checkpoint.version).then(|| {
                format!(
                    "made by lumagraph {}, {} by {}",
                    c.version,
                    first_path.display(),
                    first.checkpoint.version
                )
            }),
            (c.key != first.checkpoint.key).then(|| {
                format!(
                    "renders another graph, scene or settings than {} (key {:016x}, not {:016x})",
                    first_path.display(),
                    c.key,
                    first.checkpoint.key
                )
            }),
            (p.samples_per_frame != first.samples_per_frame).then(|| {
                format!(
                    "takes {} samples per frame, {} {}",
                    p.samples_per_frame,
                    first_path.display(),
                    first.samples_per_frame
                )
            }),
            (p.graph != first.graph || p.scene != first.scene || p.overrides != first.overrides)
                .then(|| {
                    format!(
                        "was rendered from other files or overrides than {}",
                        first_path.display()
                    )
                }),
        ];
        for d in differs.into_iter().flatten() {
            let _ = writeln!(problems, "{} (samples {}): {d}", path.display(), p.range());
        }
    }
    let mut covered = 0;
    let mut last: Option<&(PathBuf, Partial)> = None;
    for part in &parts {
        let (path, p) = part;
        if p.first < covered {
            if let Some((lp, l)) = last {
                let _ = writeln!(
                    problems,
                    "samples {}..{} are in both {} ({}) and {} ({})",
                    p.first,
                    covered.min(p.end),
                    lp.display(),
                    l.range(),
                    path.display(),
                    p.range()
                );
            }
        } else if p.first > covered && !allow_gaps {
            let _ = writeln!(
                problems,
                "samples {covered}..{} are in no partial render (the next is {}, {})",
                p.first,
                path.display(),
                p.range()
            );
        }
        if p.end > covered {
            covered = p.end;
            last = Some(part);
        }
    }
    if problems.is_empty() {
        Ok(parts)
    } else {
        Err(problems.trim_end().to_owned())
    }
}

/// Merges path tracer states (samples, dropped samples, rays, `u64` each): the samples of
/// the last range's end, the counts summed.
///
/// # Errors
/// When a state is not a path tracer's.
pub fn merge_path_tracers(states: &[&[u8]]) -> std::result::Result<Vec<u8>, String> {
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
        let mut buffers = Vec::new();
        for i in 0..3 {
            let size = u64_at(8 + 8 * i).ok_or("truncated")?;
            let len = usize::try_from(size).map_err(|_| "too large")?;
            let bytes = state
                .get(at..at.checked_add(len).ok_or("too large")?)
                .ok_or("truncated")?;
            if len % 16 != 0 {
                return Err(format!("a buffer of {len} bytes, not whole pixels"));
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
            at += len;
        }
        if at != state.len() {
            return Err(format!("{} bytes too many", state.len() - at));
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
pub fn merge_accumulations(states: &[&[u8]], halves: bool) -> std::result::Result<Vec<u8>, String> {
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
mod tests {
    use super::*;

    fn partial(first: u32, end: u32, key: u64) -> Partial {
        Partial {
            first,
            end,
            samples_per_frame: 2,
            graph: "graphs/pathtrace.ron".into(),
            scene: Some("assets/cornell.ron".into()),
            overrides: vec!["pathtrace.samples_per_frame=2".into()],
            checkpoint: Checkpoint {
                key,
                version: env!("CARGO_PKG_VERSION").into(),
                adapter: "llvmpipe".into(),
                frames: u64::from(end / 2),
                nodes: vec![("pathtrace".into(), vec![0; 24])],
            },
        }
    }

    #[test]
    fn bytes_round_trip_and_damage_is_an_error() {
        let p = partial(4, 8, 7);
        let bytes = p.to_bytes();
        assert_eq!(Partial::from_bytes(&bytes).unwrap(), p);
        for n in 0..bytes.len() {
            assert!(Partial::from_bytes(&bytes[..n]).is_err(), "cut at {n}");
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(Partial::from_bytes(&long).is_err());
        let mut q = p.clone();
        q.scene = None;
        assert_eq!(Partial::from_bytes(&q.to_bytes()).unwrap(), q);
    }

    #[test]
    fn ranges_that_overlap_or_leave_gaps_are_named() {
        let named = |ranges: &[(u32, u32, u64)]| {
            ranges
                .iter()
                .enumerate()
                .map(|(i, &(a, b, k))| (PathBuf::from(format!("p{i}")), partial(a, b, k)))
                .collect::<Vec<_>>()
        };
        let ok = arrange(named(&[(4, 8, 1), (0, 4, 1), (8, 10, 1)]), false).unwrap();
        let order: Vec<_> = ok.iter().map(|(_, p)| p.first).collect();
        assert_eq!(order, [0, 4, 8]);
        let e = arrange(named(&[(0, 4, 1), (2, 8, 1)]), false).unwrap_err();
        assert!(
            e.contains("samples 2..4 are in both p0 (0..4) and p1 (2..8)"),
            "{e}"
        );
        let e = arrange(named(&[(0, 4, 1), (6, 8, 1)]), false).unwrap_err();
        assert!(e.contains("samples 4..6 are in no partial render"), "{e}");
        assert!(arrange(named(&[(0, 4, 1), (6, 8, 1)]), true).is_ok());
        let e = arrange(named(&[(2, 4, 1)]), false).unwrap_err();
        assert!(e.contains("samples 0..2 are in no partial"), "{e}");
        let e = arrange(named(&[(0, 4, 1), (4, 8, 2)]), false).unwrap_err();
        assert!(
            e.contains("p1 (samples 4..8): renders another graph"),
            "{e}"
        );
    }

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
