//! Tiled renders: an image larger than the device holds, rendered window by window through
//! one executor and assembled on the host.
//!
//! The plan is compiled at the window's size ([`lumagraph_render::NodeLibrary::compile_window`]); each
//! tile moves the window ([`Executor::set_origin`]), renders every frame, and its sinks' images
//! (held, not written: [`Executor::hold_sinks`]) have their cores copied into whole-image
//! canvases, written once at the end as the sinks would have. Only sinks that write one
//! image file ([`InputDef::image_file`], `Output`) can be merged so; a plan with another sink
//! is refused. The tile geometry and the apron are [`lumagraph_graph::tile`]'s: a plan whose
//! nodes all read within a bounded distance gives cores equal to the whole image's pixels.

use std::path::PathBuf;

use lumagraph_graph::registry::InputDef;
use lumagraph_graph::tile::{Tile, Untileable};
use lumagraph_graph::{Extent, Plan, TexFormat, TextureId};

use lumagraph_render::Executor;
use lumagraph_render::Resources;
use lumagraph_render::{GpuContext, human_bytes};
use lumagraph_render::{RenderError, Result};

/// Images, buffers and node memory above this are rendered in tiles unless asked otherwise.
pub const MEMORY_BUDGET: u64 = 4 << 30;

/// The largest tile side chosen automatically.
const LARGEST_TILE: u32 = 4096;

/// Why and how a render is tiled.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tiling {
    /// The tile side (cores), in pixels.
    pub tile: u32,
    /// Pixels rendered around each core ([`lumagraph_graph::tile::apron`]).
    pub apron: u32,
    /// The window every tile renders.
    pub window: Extent,
    /// The tiles, row by row.
    pub tiles: Vec<Tile>,
    /// Why it is tiled (for the log).
    pub why: String,
}

/// Whether the whole-image `plan` (its images and the nodes' own memory, `bytes`) is
/// rendered in tiles on `ctx`, and how: `forced` is `--tile` (0: never; a side: that one);
/// otherwise when an image is larger than the device holds or `bytes` passes
/// [`MEMORY_BUDGET`], with the largest power-of-two tile side that fits both.
///
/// # Errors
/// A plan that must be tiled but cannot (the node that needs the whole image, or a sink
/// that writes no single image file), or that cannot be tiled small enough.
pub fn plan_tiling(
    ctx: &GpuContext,
    plan: &Plan,
    image: Extent,
    bytes: u64,
    forced: Option<u32>,
) -> Result<Option<Tiling>> {
    let limits = ctx.device.limits();
    let max_side = limits.max_texture_dimension_2d;
    let max_buffer = history_limit(&limits);
    let fits = |w: u32, h: u32, bytes: u64| {
        beyond_limits(&limits, Extent::new(w, h)).is_none() && bytes <= MEMORY_BUDGET
    };
    // Without tiles, an image wider than the device's textures is refused by the executor,
    // naming the node; a history buffer larger than it binds, here.
    if forced == Some(0)
        && image.width.max(image.height) <= max_side
        && let Some(limit) = beyond_limits(&limits, image)
    {
        return Err(RenderError::TooLarge {
            what: format!(
                "{}×{} render without tiles (--tile 0)",
                image.width, image.height
            ),
            adapter: ctx.info.name.clone(),
            message: format!("{limit}; leave out --tile, or give a tile side"),
        });
    }
    let why = match forced {
        Some(0) => return Ok(None),
        Some(side) => format!("--tile {side}"),
        None if fits(image.width, image.height, bytes) => return Ok(None),
        None => format!(
            "{}×{} needs {} of images and buffers on {} (budget {}, largest image {max_side}², \
             largest buffer {})",
            image.width,
            image.height,
            human_bytes(bytes),
            ctx.info.name,
            human_bytes(MEMORY_BUDGET),
            human_bytes(max_buffer)
        ),
    };
    let apron = lumagraph_graph::tile::apron(plan).map_err(|e| untileable(&e, &why))?;
    image_sinks(plan).map_err(|e| untileable(&e, &why))?;
    let per_pixel = bytes.div_ceil(image.pixels().max(1));
    let window = |tile: u32| {
        Extent::new(
            lumagraph_graph::tile::window(image.width, tile, apron),
            lumagraph_graph::tile::window(image.height, tile, apron),
        )
    };
    let tile = match forced {
        Some(side) => {
            check_forced(&limits, side, window).map_err(|message| RenderError::TooLarge {
                what: format!("{}×{} render in tiles of {side}", image.width, image.height),
                adapter: ctx.info.name.clone(),
                message,
            })?;
            side
        }
        None => {
            let mut tile = LARGEST_TILE;
            loop {
                let w = window(tile);
                if fits(w.width, w.height, per_pixel * w.pixels()) {
                    break tile;
                }
                if tile <= 64 {
                    return Err(RenderError::TooLarge {
                        what: format!("{}×{} render", image.width, image.height),
                        adapter: ctx.info.name.clone(),
                        message: format!(
                            "even 64-pixel tiles with their {apron}-pixel apron do not fit \
                             ({why})"
                        ),
                    });
                }
                tile /= 2;
            }
        }
    };
    let tiles = lumagraph_graph::tile::tiles(image.width, image.height, tile, apron);
    Ok(Some(Tiling {
        tile,
        apron,
        window: window(tile),
        tiles,
        why,
    }))
}

/// Bytes a pixel of a node's own history takes (`Accumulate`'s sums: 16 B a pixel each).
const HISTORY_BYTES: u64 = 16;

/// The largest buffer of node history the device binds.
fn history_limit(limits: &lumagraph_render::wgpu::Limits) -> u64 {
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

/// Which of the device's hard limits an image (or a tile's window) of `extent` passes, in
/// words naming the limit; `None` where it fits.
fn beyond_limits(limits: &lumagraph_render::wgpu::Limits, extent: Extent) -> Option<String> {
    let (w, h) = (extent.width, extent.height);
    let max_side = limits.max_texture_dimension_2d;
    let max_buffer = history_limit(limits);
    if w > max_side || h > max_side {
        return Some(format!(
            "a {w}×{h} image passes the adapter's largest 2D texture side, {max_side} \
             (max_texture_dimension_2d)"
        ));
    }
    let history = u64::from(w) * u64::from(h) * HISTORY_BYTES;
    (history > max_buffer).then(|| {
        format!(
            "{w}×{h} pixels of {HISTORY_BYTES}-byte history take {}, more than the largest \
             buffer the adapter binds, {} (max_storage_buffer_binding_size)",
            human_bytes(history),
            human_bytes(max_buffer)
        )
    })
}

/// Whether tiles of `side` (`window` gives a tile's window, apron included) fit the device's
/// hard limits; else why, with the largest power-of-two side that fits.
fn check_forced(
    limits: &lumagraph_render::wgpu::Limits,
    side: u32,
    window: impl Fn(u32) -> Extent,
) -> std::result::Result<(), String> {
    let Some(limit) = beyond_limits(limits, window(side)) else {
        return Ok(());
    };
    let w = window(side);
    let largest = std::iter::successors(Some(side.next_power_of_two() / 2), |t| {
        (*t > 1).then_some(t / 2)
    })
    .find(|&t| beyond_limits(limits, window(t)).is_none());
    Err(match largest {
        Some(t) => format!(
            "a tile's {}×{} window: {limit}; --tile {t} fits (or leave out --tile)",
            w.width, w.height
        ),
        None => format!("a tile's {}×{} window: {limit}", w.width, w.height),
    })
}

fn untileable(e: &Untileable, why: &str) -> RenderError {
    RenderError::Gpu(format!(
        "this render must be tiled ({why}), but {e}; render it smaller, or without that node"
    ))
}

/// The sinks of `plan` with the texture each writes as its one image file
/// ([`InputDef::image_file`]), as `(pass index, texture)`; a sink whose marked input is
/// left unconnected writes nothing and is left out.
///
/// # Errors
/// The first sink that writes no single image file (`MultiLayerOutput` writes several
/// images into one): a tiled render has nothing to paste its tiles into; any sink of a
/// graph whose working space is not Rec. 709 (the pasted image is written as Rec. 709).
fn image_sinks(plan: &Plan) -> std::result::Result<Vec<(usize, TextureId)>, Untileable> {
    let mut sinks = Vec::new();
    for (p, pass) in plan.passes.iter().enumerate() {
        if !pass.kind.sink {
            continue;
        }
        let Some(port): Option<&InputDef> = pass.kind.image_file_input() else {
            return Err(Untileable {
                node: pass.node.clone(),
                kind: pass.kind.name.to_owned(),
                reason: "it does not write one image file for the tiles to be pasted into \
                         (Output does)"
                    .to_owned(),
            });
        };
        if plan.working_space != lumagraph_graph::WorkingSpace::Rec709 {
            // The pasted image is written as a Rec. 709 file (chromaticities, a PNG's
            // encoding): refused rather than tagged wrongly.
            return Err(Untileable {
                node: pass.node.clone(),
                kind: pass.kind.name.to_owned(),
                reason: format!(
                    "a tiled render writes its image as Rec. 709, and this graph's working \
                     space is {}",
                    plan.working_space
                ),
            });
        }
        if let Some(texture) = pass.input(port.name) {
            sinks.push((p, texture));
        }
    }
    Ok(sinks)
}

/// One sink's whole-image canvas.
struct Canvas {
    node: String,
    /// The node's `path` param, and the file it names.
    param: String,
    path: PathBuf,
    bytes: Vec<u8>,
    image: Option<lumagraph_render::nodes::HeldImage>,
}

/// How a tiled render ended.
#[derive(Debug)]
pub enum Ended {
    /// Every tile rendered and the files written.
    Written(Vec<PathBuf>),
    /// Stopped by `progress` after the tiles of the set (none before the first finished):
    /// they can be saved, the rest rendered with `--tiles`, and both merged.
    Stopped(Option<crate::tile_set::TileSet>),
}

/// Renders `tiling`'s tiles through `exec` (compiled at `tiling.window`), each to
/// `frames` frames, and writes every sink's assembled image; `progress(tile index, frames
/// done, frames)` is called as [`Executor::render`] calls its own, and `false` stops the
/// render (`Ok(None)`, nothing written).
///
/// # Errors
/// A sink that writes no single image file ([`InputDef::image_file`]), memory for the
/// canvases, a failing node or file.
pub fn render(
    exec: &mut Executor,
    tiling: &Tiling,
    whole: Extent,
    resources: &Resources,
    (frames, key): (u32, u64),
    mut progress: impl FnMut(usize, u32, u32) -> bool,
) -> Result<Ended> {
    exec.hold_sinks(true);
    let mut canvases: Vec<(usize, Canvas, lumagraph_graph::TexFormat)> = Vec::new();
    let plan = exec.plan();
    for (p, texture) in image_sinks(plan).map_err(|e| RenderError::Gpu(e.to_string()))? {
        let pass = &plan.passes[p];
        let format = plan.textures[texture.0].format;
        canvases.push((
            p,
            Canvas {
                node: pass.node.clone(),
                param: pass.params.str("path").to_owned(),
                path: lumagraph_render::nodes::output::output_path(pass, resources)
                    .map_err(|e| e.in_node(&pass.node))?,
                bytes: Vec::new(),
                image: None,
            },
            format,
        ));
    }
    allocate(&mut canvases, whole)?;
    let all = 0..tiling.tiles.len();
    let mut finished = 0;
    let done = render_tiles(exec, tiling, all, frames, &mut progress, |i, tile, held| {
        for (p, image) in held {
            if let Some((_, canvas, _)) = canvases.iter_mut().find(|(q, ..)| *q == p) {
                paste(canvas, &image, tile, whole)?;
            }
        }
        finished = i + 1;
        Ok(())
    })?;
    if !done {
        return Ok(Ended::Stopped(finished_set(
            &canvases, tiling, whole, finished, key,
        )));
    }
    let mut written = Vec::new();
    for (_, canvas, _) in canvases {
        let Some(held) = canvas.image else { continue };
        lumagraph_render::write_output(&canvas.path, canvas.bytes, held.format, held.ty, whole)
            .map_err(|e| e.in_node(&canvas.node))?;
        written.push(canvas.path);
    }
    Ok(Ended::Written(written))
}

/// The first `finished` tiles of a stopped render, out of its canvases, as a tile set.
fn finished_set(
    canvases: &[(usize, Canvas, lumagraph_graph::TexFormat)],
    tiling: &Tiling,
    whole: Extent,
    finished: usize,
    key: u64,
) -> Option<crate::tile_set::TileSet> {
    if finished == 0 {
        return None;
    }
    let mut outputs: Vec<crate::tile_set::TileOutput> = canvases
        .iter()
        .filter_map(|(_, canvas, format)| {
            let image = canvas.image.as_ref()?;
            let bpp = format.bytes_per_pixel() as usize;
            let row = whole.width as usize * bpp;
            let cores = tiling.tiles[..finished]
                .iter()
                .map(|t| {
                    let w = t.core.width as usize * bpp;
                    let mut core = Vec::with_capacity(w * t.core.height as usize);
                    for y in t.core.y as usize..(t.core.y + t.core.height) as usize {
                        let at = y * row + t.core.x as usize * bpp;
                        core.extend_from_slice(&canvas.bytes[at..at + w]);
                    }
                    core
                })
                .collect();
            Some(crate::tile_set::TileOutput {
                node: canvas.node.clone(),
                path: canvas.param.clone(),
                format: *format,
                ty: image.ty,
                cores,
            })
        })
        .collect();
    outputs.sort_by(|a, b| a.node.cmp(&b.node));
    Some(crate::tile_set::TileSet {
        key,
        image: whole,
        tile: tiling.tile,
        apron: tiling.apron,
        count: u32::try_from(tiling.tiles.len()).unwrap_or(u32::MAX),
        first: 0,
        end: u32::try_from(finished).unwrap_or(u32::MAX),
        outputs,
    })
}

/// Renders tiles `range` of `tiling` through `exec` (compiled at `tiling.window`), each to
/// `frames` frames, handing each tile's held sink images, as `(pass index, image)`, to
/// `take`; returns `false` when `progress` stopped it.
///
/// # Errors
/// A failing node, or what `take` returns.
pub fn render_tiles(
    exec: &mut Executor,
    tiling: &Tiling,
    range: std::ops::Range<usize>,
    frames: u32,
    mut progress: impl FnMut(usize, u32, u32) -> bool,
    mut take: impl FnMut(usize, &Tile, Vec<(usize, lumagraph_render::nodes::HeldImage)>) -> Result<()>,
) -> Result<bool> {
    exec.hold_sinks(true);
    for i in range {
        let tile = &tiling.tiles[i];
        exec.set_origin([tile.window.x, tile.window.y]);
        exec.restart();
        if exec
            .render(frames, |_, done, total| progress(i, done, total))?
            .is_none()
        {
            return Ok(false);
        }
        take(i, tile, exec.held_images()?)?;
    }
    Ok(true)
}

/// Renders tiles `first..end` of `tiling` (see [`render_tiles`]) into a
/// [`crate::tile_set::TileSet`] of every image sink's cores (`Output`'s), for `key` (the
/// render's; [`lumagraph_render::checkpoint::render_key`]) and a whole image of `whole`; `None` when
/// `progress` stopped it.
///
/// # Errors
/// A sink that writes no single image file ([`InputDef::image_file`]), a range outside the
/// tiles, a failing node.
pub fn render_set(
    exec: &mut Executor,
    tiling: &Tiling,
    whole: Extent,
    (first, end): (u32, u32),
    frames: u32,
    key: u64,
    progress: impl FnMut(usize, u32, u32) -> bool,
) -> Result<Option<crate::tile_set::TileSet>> {
    let count = u32::try_from(tiling.tiles.len()).unwrap_or(u32::MAX);
    if first >= end || end > count {
        return Err(RenderError::Gpu(format!(
            "tiles {first}..{end}: this render has tiles 0..{count}"
        )));
    }
    let mut outputs = Vec::new();
    let mut passes = Vec::new();
    let plan = exec.plan();
    for (p, input) in image_sinks(plan).map_err(|e| RenderError::Gpu(e.to_string()))? {
        let pass = &plan.passes[p];
        let desc = &plan.textures[input.0];
        passes.push(p);
        outputs.push(crate::tile_set::TileOutput {
            node: pass.node.clone(),
            path: pass.params.str("path").to_owned(),
            format: desc.format,
            ty: desc.ty,
            cores: Vec::new(),
        });
    }
    let done = render_tiles(
        exec,
        tiling,
        first as usize..end as usize,
        frames,
        progress,
        |_, tile, held| {
            for (p, image) in held {
                if let Some(o) = passes.iter().position(|&q| q == p) {
                    outputs[o].cores.push(core_of(&image, tile));
                }
            }
            Ok(())
        },
    )?;
    // By node id, so sets of one render list their outputs alike.
    outputs.sort_by(|a, b| a.node.cmp(&b.node));
    Ok(done.then_some(crate::tile_set::TileSet {
        key,
        image: whole,
        tile: tiling.tile,
        apron: tiling.apron,
        count,
        first,
        end,
        outputs,
    }))
}

/// The core of `tile` out of its window's image.
fn core_of(held: &lumagraph_render::nodes::HeldImage, tile: &Tile) -> Vec<u8> {
    let bpp = held.format.bytes_per_pixel() as usize;
    let (cx, cy) = tile.core_in_window();
    let window_row = held.extent.width as usize * bpp;
    let core_row = tile.core.width as usize * bpp;
    let mut out = Vec::with_capacity(core_row * tile.core.height as usize);
    for y in 0..tile.core.height as usize {
        let src = (cy as usize + y) * window_row + cx as usize * bpp;
        out.extend_from_slice(&held.bytes[src..src + core_row]);
    }
    out
}

/// The whole-image canvases, allocated before the first tile so a render the host cannot
/// hold stops at once: checked against the memory the system says is available (Linux),
/// then reserved.
fn allocate(canvases: &mut [(usize, Canvas, TexFormat)], image: Extent) -> Result<()> {
    let held: u64 = canvases
        .iter()
        .map(|(_, _, f)| image.pixels() * f.bytes_per_pixel())
        .sum();
    // Writing an EXR converts one image to RGBA floats and encodes it (at most as large).
    let writing = if canvases.iter().any(|(_, _, f)| *f != TexFormat::Rgba8Unorm) {
        2 * 16 * image.pixels()
    } else {
        0
    };
    let need = held + writing;
    let count = canvases.len();
    let too_large = |message: String| RenderError::TooLarge {
        what: format!(
            "the {count} images this render writes ({}×{}: {}, and {} more while one is written)",
            image.width,
            image.height,
            human_bytes(held),
            human_bytes(writing)
        ),
        adapter: "this machine".into(),
        message,
    };
    if let Some(available) = available_memory()
        && need > available
    {
        return Err(too_large(format!(
            "{} of memory is available; render smaller, or write fewer outputs",
            human_bytes(available)
        )));
    }
    for (_, canvas, format) in canvases.iter_mut() {
        let len = usize::try_from(image.pixels() * format.bytes_per_pixel())
            .map_err(|_| too_large("more than this machine addresses".into()))?;
        canvas.bytes.try_reserve_exact(len).map_err(|_| {
            too_large(format!(
                "{} of memory could not be had",
                human_bytes(len as u64)
            ))
        })?;
        canvas.bytes.resize(len, 0);
    }
    Ok(())
}

/// Memory the system says is available (`MemAvailable` in `/proc/meminfo`), where it says.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Copies the core of `tile` from its window's image `held` into the whole image.
fn paste(
    canvas: &mut Canvas,
    held: &lumagraph_render::nodes::HeldImage,
    tile: &Tile,
    image: Extent,
) -> Result<()> {
    let bpp = held.format.bytes_per_pixel() as usize;
    if canvas.image.is_none() {
        canvas.image = Some(lumagraph_render::nodes::HeldImage {
            bytes: Vec::new(),
            format: held.format,
            ty: held.ty,
            extent: image,
        });
    }
    if canvas.bytes.len() != image.pixels() as usize * bpp {
        return Err(RenderError::Gpu(format!(
            "node \"{}\": a {} image of {} where {} were planned",
            canvas.node,
            held.format.name(),
            held.extent,
            human_bytes(canvas.bytes.len() as u64)
        )));
    }
    let (cx, cy) = tile.core_in_window();
    let window_row = held.extent.width as usize * bpp;
    let image_row = image.width as usize * bpp;
    let core_row = tile.core.width as usize * bpp;
    for y in 0..tile.core.height as usize {
        let src = (cy as usize + y) * window_row + cx as usize * bpp;
        let dst = (tile.core.y as usize + y) * image_row + tile.core.x as usize * bpp;
        canvas.bytes[dst..dst + core_row].copy_from_slice(&held.bytes[src..src + core_row]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use lumagraph_graph::{CompileOptions, Edge, Extent, Graph, Node, ParamValue, Plan, Registry};

    fn plan(sink: &str) -> Plan {
        let mut g = Graph::new();
        g.nodes
            .push(Node::new("in", "ImageInput").with("path", ParamValue::Str("in.exr".into())));
        g.nodes.push(Node::new("out", sink));
        g.edges.push(Edge::new("in.color", "out.color"));
        let options = CompileOptions {
            source_extent: &|_, _| Ok(Extent::new(8, 8)),
            keep: &[],
        };
        lumagraph_graph::compile(&g, &Registry::with_builtins(), &options).unwrap()
    }

    /// A tile side given with `--tile` renders where its window fits the device's hard limits
    /// and is otherwise refused naming the limit and a side that fits: on lavapipe's limits
    /// (128 MiB bound buffers, 16384² textures) a 16384² render takes 2048 but not 4096.
    #[test]
    fn forced_tiles_beyond_the_limits_are_refused_naming_them() {
        let limits = lumagraph_render::wgpu::Limits {
            max_storage_buffer_binding_size: 128 << 20,
            max_texture_dimension_2d: 16384,
            ..lumagraph_render::wgpu::Limits::default()
        };
        let window = |t: u32| {
            Extent::new(
                lumagraph_graph::tile::window(16384, t, 1),
                lumagraph_graph::tile::window(16384, t, 1),
            )
        };
        assert_eq!(super::check_forced(&limits, 2048, window), Ok(()));
        for side in [4096, 8192, 16384] {
            let why = super::check_forced(&limits, side, window).unwrap_err();
            assert!(why.contains("max_storage_buffer_binding_size"), "{why}");
            assert!(
                why.ends_with("--tile 2048 fits (or leave out --tile)"),
                "{why}"
            );
        }
        let why = super::beyond_limits(&limits, Extent::new(20000, 8)).unwrap();
        assert!(why.contains("(max_texture_dimension_2d)"), "{why}");
        assert_eq!(super::beyond_limits(&limits, Extent::new(2050, 2050)), None);
    }

    /// `Output` writes its `color` as one file, which a tiled render pastes its tiles
    /// into; `MultiLayerOutput` writes several images into one file and is refused, by
    /// the kinds' declarations, not their names.
    #[test]
    fn only_sinks_that_write_one_image_file_run_tile_by_tile() {
        let output = plan("Output");
        let color = output.passes[1].input("color").unwrap();
        assert_eq!(super::image_sinks(&output), Ok(vec![(1, color)]));
        let refused = super::image_sinks(&plan("MultiLayerOutput")).unwrap_err();
        assert_eq!(
            refused.to_string(),
            "node \"out\" (MultiLayerOutput) cannot run tile by tile: it does not write one \
             image file for the tiles to be pasted into (Output does)"
        );
        // A graph in ACEScg: its image would be written as Rec. 709.
        let mut aces = plan("Output");
        aces.working_space = lumagraph_graph::WorkingSpace::AcesCg;
        let refused = super::image_sinks(&aces).unwrap_err().to_string();
        assert!(refused.contains("ACEScg"), "{refused}");
    }
}
