//! Loading the scene for the command line: flattened for the GPU, its textures fitted to
//! the device, with each stage's time and the peak memory printed.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};

use super::progressive;
use crate::render::GpuContext;
use crate::scene::{GpuScene, Scene};

/// The process's peak resident memory in bytes (Linux: `VmHWM` of `/proc/self/status`);
/// `None` elsewhere.
pub(super) fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// A scene loaded and flattened for the GPU.
pub(super) struct LoadedScene {
    pub(super) scene: Scene,
    pub(super) gpu: Arc<GpuScene>,
}

pub(super) fn load_scene(path: Option<&Path>) -> Result<Option<LoadedScene>> {
    let Some(path) = path else { return Ok(None) };
    let start = Instant::now();
    let stage = progressive::Stage::start(format!("loading {} (meshes, textures)", path.display()));
    let scene = Scene::load(path)?;
    drop(stage);
    for w in scene.report.lines() {
        println!("scene warning: {w}");
    }
    let built = Instant::now();
    let stage = progressive::Stage::start("GPU layout (BVH, triangles, lights, texture atlas)");
    let (gpu, bvh_time) = GpuScene::build_timed(&scene)?;
    drop(stage);
    let layout = built.elapsed();
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let instanced = if gpu.instances.is_empty() {
        String::new()
    } else {
        format!(
            " (of which {} stored once for {} instances of {} meshes, placing {} triangles)",
            gpu.tri_positions.len() - gpu.tri_source.len(),
            gpu.instances.len(),
            scene.instanced.len(),
            gpu.instanced_triangles
        )
    };
    println!(
        "scene {}: {} triangles{instanced}, {} analytic shapes, {} lights, {} textures, {} BVH nodes, \
         {:.1} MiB of geometry ({:.0} ms)",
        path.display(),
        gpu.tri_positions.len(),
        gpu.shapes.len(),
        gpu.lights.len(),
        scene.textures.len(),
        gpu.bvh_nodes.len(),
        gpu.geometry_bytes() as f64 / f64::from(1 << 20),
        ms(start.elapsed())
    );
    let d = scene.stats.decode;
    let textures = if d.images > 0 {
        format!(
            " (of which decoding {} images, {:.1} MiB of texels, on {} thread{}: {:.0} ms)",
            d.images,
            d.bytes as f64 / f64::from(1 << 20),
            d.threads,
            if d.threads == 1 { "" } else { "s" },
            ms(d.time)
        )
    } else {
        String::new()
    };
    let atlas = &gpu.atlas;
    let atlas_note = if atlas.pages > 0 {
        let mib = |b: u64| b as f64 / f64::from(1 << 20);
        format!(
            ", texture atlas {:.0} ms: {} pages of {}x{} texels, {:.1} MiB{}",
            ms(gpu.atlas_time),
            atlas.pages,
            atlas.page_size,
            atlas.page_size,
            mib(atlas.bytes()),
            if gpu.texture_srgb.is_some() {
                format!(" (of which mip levels {:.1} MiB)", mib(atlas.mip_bytes))
            } else {
                " (no mip levels: texture_mips false)".to_owned()
            }
        )
    } else {
        String::new()
    };
    println!(
        "  loading {:.0} ms{textures}; GPU layout {:.0} ms (of which BVH {:.0} ms{atlas_note}){}",
        ms(scene.stats.total),
        ms(layout),
        ms(bvh_time),
        peak_memory().map_or_else(String::new, |m| format!(
            "; peak memory so far {:.2} GiB",
            m as f64 / f64::from(1 << 30)
        ))
    );
    Ok(Some(LoadedScene {
        scene,
        gpu: Arc::new(gpu),
    }))
}

/// `render --fit-textures` and `--texture-memory`: the scene's texture atlas against the
/// device's largest 2D texture and array layers and the memory budget. Over them, the
/// largest images are halved until they fit, each named in a warning, where `fit` asks;
/// else a budget exceeded is an error here, and the device's limits are checked with the
/// rest of the scene when it is uploaded (`scene_gpu::check_limits`).
pub(super) fn fit_textures(
    loaded: &mut LoadedScene,
    ctx: &GpuContext,
    args: TextureArgs,
) -> Result<()> {
    use crate::scene::texture::AtlasLimits;
    let (fit, budget_mib) = (args.fit_textures, args.texture_memory);
    let l = ctx.device.limits();
    let limits = AtlasLimits {
        max_side: l.max_texture_dimension_2d,
        max_pages: l.max_texture_array_layers,
        max_bytes: budget_mib.map(|m| m.saturating_mul(1 << 20)),
    };
    let atlas = &loaded.gpu.atlas;
    if limits.hold(atlas.page_size, atlas.pages) {
        return Ok(());
    }
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    let what = format!(
        "scene textures: {} textures in {} pages of {}x{} texels ({:.1} MiB)",
        loaded.scene.textures.len(),
        atlas.pages,
        atlas.page_size,
        atlas.page_size,
        mib(atlas.bytes())
    );
    if !fit {
        if let Some(budget) = budget_mib
            && atlas.bytes() > budget.saturating_mul(1 << 20)
        {
            anyhow::bail!(
                "{what}: over the texture memory budget of {budget} MiB (--texture-memory); \
                 pass --fit-textures to halve the largest textures until they fit"
            );
        }
        return Ok(());
    }
    let gpu = Arc::get_mut(&mut loaded.gpu).context("the scene is already in use")?;
    let Some(notes) = gpu.fit_textures(&loaded.scene.textures, limits) else {
        anyhow::bail!(
            "{what}: no downscaling fits them in {} pages of at most {}x{} texels{} on {}",
            limits.max_pages,
            limits.max_side,
            limits.max_side,
            budget_mib.map_or_else(String::new, |b| format!(" and {b} MiB")),
            ctx.info.name
        );
    };
    for n in &notes {
        println!(
            "scene warning: texture {} downscaled from {}x{} to {}x{} (--fit-textures)",
            n.name, n.from.0, n.from.1, n.to.0, n.to.1
        );
    }
    let atlas = &gpu.atlas;
    println!(
        "  {what}, over what fits ({} pages of at most {}x{}{} on {}): now {} pages of {}x{} ({:.1} MiB), {} images downscaled",
        limits.max_pages,
        limits.max_side,
        limits.max_side,
        budget_mib.map_or_else(String::new, |b| format!(", {b} MiB in all")),
        ctx.info.name,
        atlas.pages,
        atlas.page_size,
        atlas.page_size,
        mib(atlas.bytes()),
        notes.len()
    );
    Ok(())
}

pub(super) fn uses_scene(plan: &crate::graph::Plan) -> bool {
    plan.passes.iter().any(|p| p.kind.renders_scene)
}

/// The pass the render's samples come from (it has `samples_per_frame`), if any.
pub(super) fn progressive_source(plan: &crate::graph::Plan) -> Option<&crate::graph::Pass> {
    plan.passes
        .iter()
        .find(|p| p.params.has(crate::graph::registry::SAMPLES_PER_FRAME))
}

/// How a render fits the scene's textures to the device (`render`'s options).
#[derive(clap::Args, Clone, Copy, Debug)]
pub(super) struct TextureArgs {
    /// Where the scene's textures exceed what the device holds (its largest 2D texture,
    /// its array layers) or `--texture-memory`, halve the largest until they fit, with a
    /// warning naming each (by default such a scene is refused with an error).
    #[arg(long)]
    pub(super) fit_textures: bool,
    /// The most memory the scene's textures may take, in MiB (all atlas pages; by default
    /// what the device holds).
    #[arg(long, value_name = "MIB")]
    pub(super) texture_memory: Option<u64>,
}
