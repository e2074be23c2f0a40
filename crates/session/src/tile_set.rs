//! Tiles rendered apart: one tiled render split by tile across processes or machines
//! (`lumagraph render --tile N --tiles I..J`), and assembled by `lumagraph merge` into the
//! files the whole tiled render writes, byte for byte (each tile is rendered exactly as in
//! it; see [`crate::tiled`]).
//!
//! A [`TileSet`] holds, for each `Output` node of the graph, the cores of its tiles
//! `first..end`, with what is needed to check that sets belong together (the render's key,
//! the image, tile and apron sizes) and to write the files (each output's path and
//! format).
//!
//! The file: a magic line, the format version, the key, image width and height, tile
//! side, apron, tiles in all, first and end tile, then per output its node id, path, texel
//! format and port type names and its cores' bytes, tile by tile; numbers are
//! little-endian `u64`, texts and byte blocks are preceded by their length. It is written
//! atomically.

use std::fmt::Write as _;
use std::path::Path;

use lumagraph_graph::tile::{Tile, tiles};
use lumagraph_graph::{Extent, PortType, TexFormat};

use lumagraph_render::checkpoint::{Reader, put};
use lumagraph_render::{RenderError, Result};

/// The file's first bytes.
pub const MAGIC: &[u8] = b"lumagraph tiles\n";
/// Its format version.
const FORMAT: u64 = 1;

/// The texel formats a set may hold, by name.
const FORMATS: [TexFormat; 3] = [
    TexFormat::Rgba32Float,
    TexFormat::Rgba8Unorm,
    TexFormat::R32Float,
];

/// Some tiles of a tiled render: every output's cores.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TileSet {
    /// What was rendered (graph, scene and overrides; [`lumagraph_render::checkpoint::render_key`]).
    pub key: u64,
    /// The whole image.
    pub image: Extent,
    /// The tile side.
    pub tile: u32,
    /// The apron.
    pub apron: u32,
    /// Tiles of the whole render.
    pub count: u32,
    /// The first tile held.
    pub first: u32,
    /// One past the last tile held.
    pub end: u32,
    /// Every output's cores.
    pub outputs: Vec<TileOutput>,
}

/// One output's cores in a [`TileSet`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TileOutput {
    /// The `Output` node's id.
    pub node: String,
    /// Its `path` param (relative to the output folder).
    pub path: String,
    /// Texel format.
    pub format: TexFormat,
    /// What the image holds.
    pub ty: PortType,
    /// The cores of tiles `first..end`, each rows of its core's width.
    pub cores: Vec<Vec<u8>>,
}

impl TileSet {
    /// The tiles of the whole render, as [`tiles`] gives them.
    pub fn tiles(&self) -> Vec<Tile> {
        tiles(self.image.width, self.image.height, self.tile, self.apron)
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        for v in [
            FORMAT,
            self.key,
            u64::from(self.image.width),
            u64::from(self.image.height),
            u64::from(self.tile),
            u64::from(self.apron),
            u64::from(self.count),
            u64::from(self.first),
            u64::from(self.end),
            self.outputs.len() as u64,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for o in &self.outputs {
            put(&mut out, o.node.as_bytes());
            put(&mut out, o.path.as_bytes());
            put(&mut out, o.format.name().as_bytes());
            put(&mut out, o.ty.name().as_bytes());
            for core in &o.cores {
                put(&mut out, core);
            }
        }
        out
    }

    /// Reads a set from its file's bytes.
    ///
    /// # Errors
    /// A message saying what is wrong (not a tile set, another format, damaged).
    pub fn from_bytes(bytes: &[u8]) -> std::result::Result<Self, String> {
        let rest = bytes
            .strip_prefix(MAGIC)
            .ok_or("not a lumagraph tile set")?;
        let damaged = || "damaged (cut short or overwritten)".to_owned();
        let mut r = Reader { bytes: rest, at: 0 };
        let format = r.u64().ok_or_else(damaged)?;
        if format != FORMAT {
            return Err(format!(
                "tile set format {format}; this lumagraph reads {FORMAT}"
            ));
        }
        let key = r.u64().ok_or_else(damaged)?;
        let mut ints = [0_u32; 8];
        for v in &mut ints {
            *v = r
                .u64()
                .and_then(|v| u32::try_from(v).ok())
                .ok_or_else(damaged)?;
        }
        let [width, height, tile, apron, count, first, end, outputs] = ints;
        let image = Extent::new(width, height);
        if first >= end || end > count || tile == 0 || image.pixels() == 0 {
            return Err(format!(
                "tiles {first}..{end} of {count} ({width}×{height}, tile {tile}): not a valid set"
            ));
        }
        let layout = tiles(width, height, tile, apron);
        if layout.len() != count as usize {
            return Err(format!(
                "{count} tiles, but {width}×{height} in tiles of {tile} makes {}",
                layout.len()
            ));
        }
        let mut set = Self {
            key,
            image,
            tile,
            apron,
            count,
            first,
            end,
            outputs: Vec::new(),
        };
        for _ in 0..outputs {
            let node = r.text().ok_or_else(damaged)?;
            let path = r.text().ok_or_else(damaged)?;
            let format_name = r.text().ok_or_else(damaged)?;
            let format = FORMATS
                .into_iter()
                .find(|f| f.name() == format_name)
                .ok_or_else(|| format!("output \"{node}\": unknown texel format {format_name}"))?;
            let ty_name = r.text().ok_or_else(damaged)?;
            let ty = PortType::ALL
                .into_iter()
                .find(|t| t.name() == ty_name)
                .ok_or_else(|| format!("output \"{node}\": unknown image type {ty_name}"))?;
            let mut cores = Vec::new();
            for t in &layout[first as usize..end as usize] {
                let core = r.field().ok_or_else(damaged)?;
                let want =
                    u64::from(t.core.width) * u64::from(t.core.height) * format.bytes_per_pixel();
                if core.len() as u64 != want {
                    return Err(format!(
                        "output \"{node}\": a tile of {} bytes where {want} are expected",
                        core.len()
                    ));
                }
                cores.push(core.to_vec());
            }
            set.outputs.push(TileOutput {
                node,
                path,
                format,
                ty,
                cores,
            });
        }
        if r.at != rest.len() {
            return Err(damaged());
        }
        Ok(set)
    }

    /// Writes the set to `path` atomically.
    ///
    /// # Errors
    /// When it cannot be written; the error names the file.
    pub fn save(&self, path: &Path) -> Result<()> {
        lumagraph_graph::write_atomic(path, &self.to_bytes())
            .map_err(|e| RenderError::image(path, format!("cannot write the tiles: {e}")))
    }

    /// Reads the set at `path`.
    ///
    /// # Errors
    /// When it cannot be read or is not a tile set; the error names the file.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path)
            .map_err(|e| RenderError::image(path, format!("cannot read the tiles: {e}")))?;
        Self::from_bytes(&bytes).map_err(|e| RenderError::image(path, e))
    }

    /// Whether the file at `path` starts as a tile set does.
    pub fn is_tile_set(path: &Path) -> bool {
        use std::io::Read as _;
        let mut head = [0_u8; MAGIC.len()];
        std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut head))
            .is_ok_and(|()| head == MAGIC)
    }
}

/// One output's whole image, assembled from tile sets.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// The `Output` node's id.
    pub node: String,
    /// Its `path` param.
    pub path: String,
    /// Texel format.
    pub format: TexFormat,
    /// What the image holds.
    pub ty: PortType,
    /// Rows of the whole image's width.
    pub bytes: Vec<u8>,
}

/// Assembles `sets` (with the files they came from) into every output's whole image.
///
/// # Errors
/// Sets that do not belong together (another render, image or tiling; other outputs), and
/// tiles held twice or by none, each named by file and tile range.
pub fn assemble(
    sets: &[(std::path::PathBuf, TileSet)],
) -> std::result::Result<Vec<Assembled>, String> {
    let Some((first_path, first)) = sets.first() else {
        return Err("no tile sets".into());
    };
    let mut problems = String::new();
    for (path, s) in &sets[1..] {
        let same_render = s.key == first.key
            && (s.image, s.tile, s.apron, s.count)
                == (first.image, first.tile, first.apron, first.count);
        // Outputs are in node id order (`render_set`), whatever order the plan ran them in.
        let same_outputs = s.outputs.len() == first.outputs.len()
            && s.outputs.iter().zip(&first.outputs).all(|(a, b)| {
                (&a.node, &a.path, a.format, a.ty) == (&b.node, &b.path, b.format, b.ty)
            });
        if !same_render || !same_outputs {
            let _ = writeln!(
                problems,
                "{} is of another render than {} (another graph, scene, overrides, image size \
                 or tiling)",
                path.display(),
                first_path.display()
            );
        }
    }
    let mut owner: Vec<Option<usize>> = vec![None; first.count as usize];
    for (i, (path, s)) in sets.iter().enumerate() {
        for t in s.first..s.end.min(first.count) {
            match owner[t as usize] {
                Some(j) => {
                    let _ = writeln!(
                        problems,
                        "tile {t} is in both {} (tiles {}..{}) and {} (tiles {}..{})",
                        sets[j].0.display(),
                        sets[j].1.first,
                        sets[j].1.end,
                        path.display(),
                        s.first,
                        s.end
                    );
                }
                None => owner[t as usize] = Some(i),
            }
        }
    }
    let mut t = 0;
    while t < owner.len() {
        if owner[t].is_some() {
            t += 1;
            continue;
        }
        let start = t;
        while t < owner.len() && owner[t].is_none() {
            t += 1;
        }
        let _ = writeln!(problems, "tiles {start}..{t} are in no tile set");
    }
    if !problems.is_empty() {
        return Err(problems.trim_end().to_owned());
    }
    let layout = first.tiles();
    let mut out = Vec::new();
    for (o, output) in first.outputs.iter().enumerate() {
        let bpp = output.format.bytes_per_pixel() as usize;
        let row = first.image.width as usize * bpp;
        let mut bytes = vec![0_u8; first.image.pixels() as usize * bpp];
        for (_, s) in sets {
            for (k, t) in (s.first..s.end).enumerate() {
                let tile = &layout[t as usize];
                let core = &s.outputs[o].cores[k];
                let w = tile.core.width as usize * bpp;
                for y in 0..tile.core.height as usize {
                    let dst = (tile.core.y as usize + y) * row + tile.core.x as usize * bpp;
                    bytes[dst..dst + w].copy_from_slice(&core[y * w..(y + 1) * w]);
                }
            }
        }
        out.push(Assembled {
            node: output.node.clone(),
            path: output.path.clone(),
            format: output.format,
            ty: output.ty,
            bytes,
        });
    }
    Ok(out)
}
