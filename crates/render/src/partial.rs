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
//! ([`crate::Executor::merge`]: each node merges its own states, the accumulation's sums
//! exactly) and runs the
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
}
