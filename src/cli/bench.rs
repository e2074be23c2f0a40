//! `lumagraph bench`: path tracing throughput on the current adapter, with the
//! scene-specialized shader (with its scene data inlined, then read from buffers; with the
//! host intersecting the rays, then the WGSL BVH) and the general (BVH) one side by side.

use std::sync::Arc;
use std::time::Instant;

use super::progressive::counter;
use crate::graph::{Edge, Graph, Node, ParamValue};
use crate::pathtrace::library::compile;
use crate::pathtrace::specialize::{Feature, Features, Intersector, Tracer as _};
use crate::render::{GpuContext, Resources};
use crate::scene::GpuScene;
use anyhow::Result;

/// CPU time used so far by all of this process's threads (on a CPU adapter, the driver's
/// worker threads do the path tracing), from `/proc/self/task/*/schedstat`; `None` where
/// that is not available.
fn cpu_time() -> Option<f64> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    #[expect(clippy::cast_precision_loss, reason = "a duration in seconds")]
    Some(ns as f64 * 1e-9)
}

/// Throughput of one shader.
struct Figures {
    /// Best paths per second of wall time.
    wall: f64,
    /// Best paths per CPU second of the whole process, where known: on a shared machine
    /// this moves less with the other jobs' load than the wall figure.
    cpu: Option<f64>,
    /// The shader's notes.
    how: String,
    /// Host intersection's figures over all runs, where it was used.
    host: Option<HostFigures>,
    /// The shader's features (what the variants to compare with are chosen by).
    features: Option<crate::pathtrace::specialize::Features>,
    /// Rays traced per path (camera, bounce and shadow rays; the node's `rays` counter over
    /// the timed runs), where counted.
    rays_per_path: Option<f64>,
}

/// Where host intersection's time went, summed over the timed runs.
#[derive(Default)]
struct HostFigures {
    frames: u64,
    steps: u64,
    wall_ns: u64,
    wait_ns: u64,
    embree_ns: u64,
    other_ns: u64,
}

/// Best paths/s of `runs` renders of `spp` samples per pixel, with the shader choices of
/// `variant` (its scene is replaced by `scene`).
fn measure(
    ctx: &GpuContext,
    scene: &Arc<GpuScene>,
    variant: Resources,
    spp: u32,
    runs: u32,
) -> Result<Figures> {
    let spf = spp.min(16);
    let graph = Graph {
        nodes: vec![
            Node::new("pathtrace", "PathTrace")
                .with("samples_per_frame", ParamValue::Int(i64::from(spf))),
            Node::new("accumulate", "Accumulate"),
        ],
        edges: vec![Edge::new("pathtrace.color", "accumulate.color")],
        ..Graph::default()
    };
    let plan = compile(&graph, &["accumulate.color".into()], Some(scene))?;
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        ..variant
    };
    let mut exec = crate::pathtrace::library::executor(ctx, plan, &resources)?;
    let features = crate::pathtrace::nodes::pathtrace::features(&exec, "pathtrace").cloned();
    let how = exec
        .notes()
        .into_iter()
        .map(|(_, n)| n)
        .collect::<Vec<_>>()
        .join("; ");
    exec.warm_up()?; // the driver compiles the pipeline at the first dispatch
    let frames = spp.div_ceil(spf);
    let pixels = f64::from(scene.settings.width) * f64::from(scene.settings.height);
    let paths = pixels * f64::from(frames * spf);
    let mut best = 0.0_f64;
    let mut best_cpu: Option<f64> = None;
    let mut host: Option<HostFigures> = None;
    let mut rays = 0u64;
    for _ in 0..runs.max(1) {
        let before = exec.counters()?;
        let cpu_start = cpu_time();
        let start = Instant::now();
        exec.run_frames(frames, false)?;
        let secs = start.elapsed().as_secs_f64();
        let after = exec.counters()?;
        let diff = |name: &str| counter(&after, name).saturating_sub(counter(&before, name));
        rays += diff("rays");
        if after.iter().any(|(_, c)| c.name == "host_steps") {
            let h = host.get_or_insert_with(HostFigures::default);
            h.frames += u64::from(frames);
            h.steps += diff("host_steps");
            h.wall_ns += u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
            h.wait_ns += diff("host_wait_ns");
            h.embree_ns += diff("host_embree_ns");
            h.other_ns += diff("host_other_ns");
        }
        best = best.max(paths / secs);
        if let (Some(a), Some(b)) = (cpu_start, cpu_time()) {
            best_cpu = Some(best_cpu.unwrap_or(0.0).max(paths / (b - a)));
        }
    }
    Ok(Figures {
        wall: best,
        cpu: best_cpu,
        how,
        host,
        features,
        #[expect(clippy::cast_precision_loss, reason = "a ratio")]
        rays_per_path: (rays > 0).then(|| rays as f64 / (paths * f64::from(runs.max(1)))),
    })
}

impl Figures {
    /// Whether the shader compiled `f` in.
    fn on(&self, f: Feature) -> bool {
        self.features.as_ref().is_some_and(|x| x.on(f))
    }

    /// Whether the host traced the rays, in steps.
    fn host_steps(&self) -> bool {
        self.features
            .as_ref()
            .is_some_and(|f| f.kind().host_steps())
    }

    /// The intersector the shader traced with, where it has features.
    fn intersector(&self) -> Option<&'static dyn crate::pathtrace::intersect::IntersectorKind> {
        self.features.as_ref().map(Features::kind)
    }
}

/// One line of the report.
fn print(label: &str, f: &Figures) {
    let cpu = f
        .cpu
        .map(|c| format!(", {:.3} M per CPU second", c / 1e6))
        .unwrap_or_default();
    let rays = f
        .rays_per_path
        .map(|r| format!(", {r:.2} rays/path ({:.1} M rays/s)", f.wall * r / 1e6))
        .unwrap_or_default();
    println!(
        "  {label:<12} {:>8.3} M paths/s{cpu}{rays}   ({})",
        f.wall / 1e6,
        f.how
    );
    if let Some(h) = &f.host {
        #[expect(clippy::cast_precision_loss, reason = "milliseconds")]
        let ms = |ns: u64| ns as f64 * 1e-6 / h.frames.max(1) as f64;
        println!(
            "  {:<12} host thread, per frame of {} steps: {:.0} ms waiting for the kernel, {:.0} ms in Embree, {:.0} ms reading back, listing and recording (of {:.0} ms)",
            "",
            h.steps / h.frames.max(1),
            ms(h.wait_ns),
            ms(h.embree_ns),
            ms(h.other_ns),
            ms(h.wall_ns)
        );
    }
}

/// Runs the benchmark and prints the figures (with `traversal`, [`traversal`]'s).
pub fn run(
    scene: &Arc<GpuScene>,
    spp: u32,
    runs: u32,
    specialized_only: bool,
    traversal: bool,
    choice: super::choice::Choice,
) -> Result<()> {
    // What `--intersector` and `--schedule` (or their environment variables) ask for; the
    // variants compared with it ask for their own.
    let asked = choice.apply(Resources::default());
    if traversal {
        return self::traversal(scene, runs);
    }
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    println!(
        "{}x{}, {} bounces, {spp} spp per run, best of {runs}:",
        scene.settings.width, scene.settings.height, scene.settings.max_bounces
    );
    let special = measure(&ctx, scene, asked.clone(), spp, runs)?;
    print("specialized", &special);
    // Where the specialized shader traces on the device with another intersector than the
    // binary BVH (the 8-wide BVH, ray queries), the binary one beside it (the specialized
    // shader as `--intersector binary` runs it).
    let other_intersector = special
        .intersector()
        .filter(|k| !k.inline() && !k.host_steps() && k.intersector() != Intersector::BINARY_BVH);
    let binary = if let Some(kind) = other_intersector {
        let binary = asked
            .clone()
            .tracing(|t| t.intersector = Intersector::BINARY_BVH);
        let binary = measure(&ctx, scene, binary, spp, runs)?;
        print("binary BVH", &binary);
        println!(
            "  specialized ({}) / binary BVH: {:.2}x",
            kind.describe(),
            special.wall / binary.wall
        );
        Some(binary)
    } else {
        None
    };
    // The wavefront beside the megakernel (or the megakernel beside the wavefront, where
    // the specialized shader is one), where the scene allows it: the specialized shader as
    // `--schedule wavefront` or `megakernel` runs it.
    if !special.host_steps() {
        use crate::pathtrace::specialize::Schedule;
        let front = special.on(Feature::Wavefront);
        let other = asked.clone().tracing(|t| {
            t.schedule = if front {
                Schedule::Megakernel
            } else {
                Schedule::Wavefront
            };
        });
        // The wavefront cannot take every scene: then there is nothing to compare.
        let other = match measure(&ctx, scene, other, spp, runs) {
            Ok(other) => Some(other),
            Err(e) => {
                println!("  (no other schedule: {e})");
                None
            }
        };
        if let Some(other) = other.filter(|o| o.on(Feature::Wavefront) != front) {
            let (mega, wave) = if front {
                print("megakernel", &other);
                (&other, &special)
            } else {
                print("wavefront", &other);
                (&special, &other)
            };
            println!("  megakernel / wavefront: {:.2}x", mega.wall / wave.wall);
        }
    }
    if specialized_only {
        return Ok(());
    }
    let wgsl = if special.host_steps() {
        let wgsl = Resources::default().tracing(|t| t.intersector = Intersector::WIDE_BVH);
        let wgsl = measure(&ctx, scene, wgsl, spp, runs)?;
        print("WGSL BVH", &wgsl);
        Some(wgsl)
    } else {
        None
    };
    let buffers = if special.on(Feature::InlineData) {
        let buffers = Resources::default().tracing(|t| t.scene_data_in_buffers = true);
        let buffers = measure(&ctx, scene, buffers, spp, runs)?;
        print("buffers", &buffers);
        Some(buffers)
    } else {
        None
    };
    let general = Resources::default().tracing(|t| t.general_shaders = true);
    let general = measure(&ctx, scene, general, spp, runs)?;
    print("general", &general);
    if binary.is_some() {
        // The general shader walks the binary BVH.
        println!(
            "  (the general shader traverses the binary BVH; specialized / general below is \
             both changes together)"
        );
    }
    if let Some(wgsl) = wgsl {
        println!(
            "  specialized (host intersection) / WGSL BVH: {:.2}x",
            special.wall / wgsl.wall
        );
    }
    if let Some(buffers) = buffers {
        println!(
            "  specialized / buffers: {:.2}x",
            special.wall / buffers.wall
        );
    }
    println!(
        "  specialized / general: {:.2}x",
        special.wall / general.wall
    );
    Ok(())
}

/// A ray of `raycast` through the centre of pixel (x, y), as the path tracer's pinhole
/// camera makes it.
fn pixel_ray(scene: &GpuScene, x: u32, y: u32) -> crate::pathtrace::raycast::RayQuery {
    use glam::Vec3;
    let c = &scene.camera;
    #[expect(clippy::cast_precision_loss, reason = "pixel coordinates")]
    let (u, v) = (
        (x as f32 + 0.5) / scene.settings.width as f32,
        (y as f32 + 0.5) / scene.settings.height as f32,
    );
    let dir = Vec3::from(c.forward)
        + (2.0 * u - 1.0) * c.tan_half_fov * c.aspect * Vec3::from(c.right)
        - (2.0 * v - 1.0) * c.tan_half_fov * Vec3::from(c.up);
    crate::pathtrace::raycast::RayQuery {
        origin: c.position,
        t_max: f32::MAX,
        dir: dir.normalize().to_array(),
        pad: 0,
    }
}

/// A diffuse ray from where `ray` hits (`hit`): cosine-distributed about the surface's
/// normal on the ray's side, from a point pushed off the surface by a little of its
/// coordinates' magnitude; `None` on a miss.
fn diffuse_ray(
    scene: &GpuScene,
    ray: &crate::pathtrace::raycast::RayQuery,
    hit: &crate::scene::Hit,
    i: u32,
) -> Option<crate::pathtrace::raycast::RayQuery> {
    use glam::Vec3;
    if hit.prim == crate::scene::NO_HIT {
        return None;
    }
    let (o, d) = (Vec3::from(ray.origin), Vec3::from(ray.dir));
    let p = o + d * hit.t;
    let n = if hit.prim & crate::scene::PRIM_SHAPE != 0 {
        let s = scene
            .shapes
            .get((hit.prim & !crate::scene::PRIM_SHAPE) as usize)?;
        crate::scene::shapes::KINDS[s.kind as usize].normal(s, p)
    } else {
        let t = scene.tri_positions.get(hit.prim as usize)?;
        Vec3::from(t.e1).cross(Vec3::from(t.e2)).normalize_or_zero()
    };
    let n = if n.dot(d) > 0.0 { -n } else { n };
    // Two uniform numbers from the index (a hash: the same rays every run).
    let h = |k: u32| {
        let mut x = i.wrapping_mul(0x9E37_79B9) ^ k.wrapping_mul(0x85EB_CA6B);
        x ^= x >> 16;
        x = x.wrapping_mul(0x7FEB_352D);
        x ^= x >> 15;
        x = x.wrapping_mul(0x846C_A68B);
        x ^= x >> 16;
        #[expect(clippy::cast_precision_loss, reason = "24 bits")]
        let f = (x >> 8) as f32 / (1u32 << 24) as f32;
        f
    };
    let (r, phi) = (h(1).sqrt(), std::f32::consts::TAU * h(2));
    let (b1, b2) = n.any_orthonormal_pair();
    let dir = b1 * (r * phi.cos()) + b2 * (r * phi.sin()) + n * (1.0 - r * r).max(0.0).sqrt();
    let origin = p + n * (1e-4 * p.abs().max_element().max(1.0));
    Some(crate::pathtrace::raycast::RayQuery {
        origin: origin.to_array(),
        t_max: f32::MAX,
        dir: dir.to_array(),
        pad: 0,
    })
}

/// `lumagraph bench --traversal`: closest-hit queries alone, through the binary and the
/// 8-wide BVH. Primary rays: one through each pixel centre; diffuse rays: one from each
/// primary hit. Each set is cast in one submission of several dispatches (enough for about
/// a quarter of a second), best of `runs`; prints M rays/s and the rays that hit.
pub fn traversal(scene: &Arc<GpuScene>, runs: u32) -> Result<()> {
    use crate::pathtrace::intersect::wide_bvh::{WideBvh, upload};
    use crate::pathtrace::raycast::Raycaster;
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    let buffers = crate::pathtrace::SceneBuffers::upload(&ctx, scene)?;
    let start = Instant::now();
    let wide = WideBvh::build(scene).map_err(anyhow::Error::msg)?;
    println!(
        "8-wide BVH: {} nodes, {} deep, built in {:.1} ms; binary BVH: {} nodes",
        wide.nodes,
        wide.depth,
        start.elapsed().as_secs_f64() * 1e3,
        scene.bvh_nodes.len()
    );
    let wide_nodes = upload(&ctx, &wide)?;
    let (w, h) = (scene.settings.width, scene.settings.height);
    let primary: Vec<_> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| pixel_ray(scene, x, y))
        .collect();
    let binary = Raycaster::new(&ctx)?;
    let hits = binary.cast(&ctx, &buffers, &primary)?;
    let diffuse: Vec<_> = primary
        .iter()
        .zip(&hits)
        .zip(0u32..)
        .filter_map(|((r, hit), i)| diffuse_ray(scene, r, hit, i))
        .collect();
    let diffuse_hits = binary
        .cast(&ctx, &buffers, &diffuse)?
        .iter()
        .filter(|h| h.prim != crate::scene::NO_HIT)
        .count();
    println!(
        "{w}x{h}: {} primary rays ({} hit), {} diffuse rays ({diffuse_hits} hit); best of {runs}:",
        primary.len(),
        diffuse.len(),
        diffuse.len()
    );
    let wide_kernel = Raycaster::wide(&ctx)?;
    let mut figures = Vec::new();
    for (name, kernel, nodes) in [
        ("binary BVH", &binary, &buffers.bvh_nodes),
        ("8-wide BVH", &wide_kernel, &wide_nodes),
    ] {
        let mut line = Vec::new();
        for (kind, rays) in [("primary", &primary), ("diffuse", &diffuse)] {
            if rays.is_empty() {
                continue;
            }
            // One dispatch to size the runs (and compile the pipeline).
            let once = kernel.time(&ctx, &buffers, nodes, rays, 1)?.as_secs_f64();
            #[expect(clippy::cast_possible_truncation, reason = "clamped to 1..=64")]
            #[expect(clippy::cast_sign_loss, reason = "clamped to 1..=64")]
            let repeats = (0.25 / once.max(1e-6)).clamp(1.0, 64.0) as u32;
            let mut best = 0.0f64;
            for _ in 0..runs.max(1) {
                let secs = kernel
                    .time(&ctx, &buffers, nodes, rays, repeats)?
                    .as_secs_f64();
                #[expect(clippy::cast_precision_loss, reason = "a rate")]
                let rate = rays.len() as f64 * f64::from(repeats) / secs;
                best = best.max(rate);
            }
            line.push(format!("{kind} {:.1} M rays/s", best / 1e6));
            figures.push(best);
        }
        println!("  {name:<11} {}", line.join(", "));
    }
    if let [bp, bd, wp, wd] = figures[..] {
        println!(
            "  8-wide / binary: primary {:.2}x, diffuse {:.2}x",
            wp / bp,
            wd / bd
        );
    }
    Ok(())
}
