//! Checkpoints: where a long render stands, so it can stop and go on later bit for bit.
//!
//! A checkpoint holds the frames run and the history every node keeps across frames (the
//! path tracer's sample count and counters, the accumulation's Kahan sums), with a key
//! naming what was rendered (graph, scene, lumagraph version; see [`render_key`]). Going on
//! from it ([`crate::Executor::restore`]) runs the same frames an uninterrupted render
//! would have run next, so the result is identical.
//!
//! The file: a magic line, the format version, the lumagraph version, the key, the adapter,
//! the frames run, then each node's id and state, every number little-endian. It is written
//! through a temporary file and a rename, so a crash while writing leaves the last one.

use std::path::Path;

use crate::error::{RenderError, Result};

/// The file's first bytes.
const MAGIC: &[u8] = b"lumagraph checkpoint\n";
/// Its format version.
const FORMAT: u32 = 1;

/// Where a render stands.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Checkpoint {
    /// What was rendered ([`render_key`]).
    pub key: u64,
    /// The lumagraph version that wrote it.
    pub version: String,
    /// The adapter it ran on (a render goes on bit for bit only on the same kind).
    pub adapter: String,
    /// Frames run.
    pub frames: u64,
    /// Each node that keeps history: its id and state.
    pub nodes: Vec<(String, Vec<u8>)>,
}

/// A 64-bit FNV-1a hash, stable across builds and platforms.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Adds `bytes`, then their length (so concatenations differ).
    #[must_use]
    pub fn write(mut self, bytes: &[u8]) -> Self {
        for &b in bytes.iter().chain(&(bytes.len() as u64).to_le_bytes()) {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        self
    }

    /// The hash.
    pub fn finish(self) -> u64 {
        self.0
    }
}

/// The key of a render: the lumagraph version, the graph as compiled (`graph_text`, e.g.
/// its RON with overrides applied and without layout) and the scene as flattened
/// (`scene_text`, e.g. a digest of every number the GPU gets). The sample count is
/// not part of it: a render may go on to more samples.
pub fn render_key(graph_text: &str, scene_text: &str) -> u64 {
    Fnv::default()
        .write(env!("CARGO_PKG_VERSION").as_bytes())
        .write(graph_text.as_bytes())
        .write(scene_text.as_bytes())
        .finish()
}

/// Writes `bytes` with their length before them (the field of every lumagraph state file:
/// checkpoints, partial renders, tile sets).
pub fn put(out: &mut Vec<u8>, bytes: &[u8]) {
    out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    out.extend_from_slice(bytes);
}

/// Reads what [`put`] wrote.
#[derive(Debug)]
pub struct Reader<'a> {
    /// The file's bytes.
    pub bytes: &'a [u8],
    /// Where the next read starts.
    pub at: usize,
}

impl<'a> Reader<'a> {
    /// The next `n` bytes (`None` past the end).
    pub fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.bytes.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }

    /// The next little-endian `u64`.
    pub fn u64(&mut self) -> Option<u64> {
        self.take(8)?.try_into().ok().map(u64::from_le_bytes)
    }

    /// The next field [`put`] wrote.
    pub fn field(&mut self) -> Option<&'a [u8]> {
        let n = usize::try_from(self.u64()?).ok()?;
        self.take(n)
    }

    /// The next field, as UTF-8 text.
    pub fn text(&mut self) -> Option<String> {
        String::from_utf8(self.field()?.to_vec()).ok()
    }
}

impl Checkpoint {
    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&FORMAT.to_le_bytes());
        put(&mut out, self.version.as_bytes());
        out.extend_from_slice(&self.key.to_le_bytes());
        put(&mut out, self.adapter.as_bytes());
        out.extend_from_slice(&self.frames.to_le_bytes());
        out.extend_from_slice(&(self.nodes.len() as u64).to_le_bytes());
        for (id, state) in &self.nodes {
            put(&mut out, id.as_bytes());
            put(&mut out, state);
        }
        out
    }

    /// Parses a file's bytes.
    ///
    /// # Errors
    /// When they are not a checkpoint of this format, or are cut short.
    pub fn from_bytes(bytes: &[u8]) -> std::result::Result<Self, String> {
        let rest = bytes
            .strip_prefix(MAGIC)
            .ok_or("not a lumagraph checkpoint")?;
        let format = rest
            .get(..4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
            .ok_or("cut short")?;
        if format != FORMAT {
            return Err(format!(
                "checkpoint format {format}; this lumagraph reads format {FORMAT}"
            ));
        }
        let mut r = Reader {
            bytes: &rest[4..],
            at: 0,
        };
        let short = || "cut short".to_owned();
        let version = r.text().ok_or_else(short)?;
        let key = r.u64().ok_or_else(short)?;
        let adapter = r.text().ok_or_else(short)?;
        let frames = r.u64().ok_or_else(short)?;
        let n = r.u64().ok_or_else(short)?;
        let mut nodes = Vec::new();
        for _ in 0..n {
            let id = r.text().ok_or_else(short)?;
            let state = r.field().ok_or_else(short)?.to_vec();
            nodes.push((id, state));
        }
        if r.at != r.bytes.len() {
            return Err(format!("{} bytes after the end", r.bytes.len() - r.at));
        }
        Ok(Self {
            key,
            version,
            adapter,
            frames,
            nodes,
        })
    }

    /// Writes it to `path` atomically.
    ///
    /// # Errors
    /// When the file cannot be written (an older one at `path` is then kept).
    pub fn save(&self, path: &Path) -> Result<()> {
        lumagraph_graph::write_atomic(path, &self.to_bytes())
            .map_err(|e| RenderError::image(path, format!("cannot write the checkpoint: {e}")))
    }

    /// Reads the checkpoint at `path`.
    ///
    /// # Errors
    /// When it cannot be read or is not a checkpoint; the error names the file.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path)
            .map_err(|e| RenderError::image(path, format!("cannot read the checkpoint: {e}")))?;
        Self::from_bytes(&bytes).map_err(|e| RenderError::image(path, e))
    }

    /// Checks that it belongs to the render with `key`, made by this lumagraph.
    ///
    /// # Errors
    /// Says what differs.
    pub fn check(&self, key: u64) -> std::result::Result<(), String> {
        let ours = env!("CARGO_PKG_VERSION");
        if self.version != ours {
            return Err(format!(
                "made by lumagraph {}, this is {ours}: renders of other versions may differ",
                self.version
            ));
        }
        if self.key != key {
            return Err(
                "made for another graph or scene (or other overrides): the key differs".into(),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_round_trip_and_damage_is_an_error() {
        let c = Checkpoint {
            key: 42,
            version: env!("CARGO_PKG_VERSION").into(),
            adapter: "llvmpipe".into(),
            frames: 7,
            nodes: vec![("pathtrace".into(), vec![1, 2, 3]), ("acc".into(), vec![])],
        };
        let bytes = c.to_bytes();
        assert_eq!(Checkpoint::from_bytes(&bytes).unwrap(), c);
        for n in 0..bytes.len() {
            assert!(Checkpoint::from_bytes(&bytes[..n]).is_err(), "cut at {n}");
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(Checkpoint::from_bytes(&long).is_err());
        assert!(c.check(42).is_ok());
        assert!(c.check(43).unwrap_err().contains("another graph"));
    }

    #[test]
    fn the_key_depends_on_graph_and_scene() {
        assert_ne!(render_key("ab", "c"), render_key("a", "bc"));
        assert_eq!(render_key("a", "b"), render_key("a", "b"));
    }
}
