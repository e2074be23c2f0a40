//! `--intersector` and `--schedule`: the path tracer's intersector and schedule asked for on
//! the command line, over what the scene and the adapter decide. Without the option, the
//! environment variables `LUMAGRAPH_BVH` (`wide`, `binary`), `LUMAGRAPH_RAY_QUERY=on` and
//! `LUMAGRAPH_WAVEFRONT` (`on`, `off`) ask for them, as overrides for scripts; the render
//! library itself reads neither. A `PathTrace` node's `intersector` or `schedule` param,
//! when not `auto`, wins over both.

use crate::pathtrace::specialize::{Intersector, Schedule, Tracer as _, Tracing};
use crate::render::Resources;

/// The path tracer's choices on the command line.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub(crate) struct Choice {
    /// The path tracer's intersector: auto (the scene and the adapter decide), inline, host
    /// (Embree), binary or wide (the BVH in WGSL) or rays (the device's ray queries). One
    /// that cannot trace the scene on this adapter is an error naming why
    /// (docs/pathtracer.md has the support matrix). A `PathTrace` node's `intersector` param,
    /// when not `auto`, wins.
    #[arg(long, value_name = "NAME", value_parser = Intersector::from_name)]
    intersector: Option<Intersector>,
    /// The path tracer's schedule: auto, megakernel or wavefront (a `PathTrace` node's
    /// `schedule` param, when not `auto`, wins).
    #[arg(long, value_name = "NAME", value_parser = Schedule::from_name)]
    schedule: Option<Schedule>,
}

impl Choice {
    /// The intersector asked for: the option, else the environment, else `AUTO`.
    pub(crate) fn intersector(self) -> Intersector {
        self.intersector.unwrap_or_else(intersector_from_env)
    }

    /// The schedule asked for: the option, else the environment, else `Auto`.
    pub(crate) fn schedule(self) -> Schedule {
        self.schedule.unwrap_or_else(schedule_from_env)
    }

    /// `resources` with the intersector and schedule asked for.
    pub(crate) fn apply(self, resources: Resources) -> Resources {
        resources.tracing(|t: &mut Tracing| {
            t.intersector = self.intersector();
            t.schedule = self.schedule();
        })
    }
}

/// `LUMAGRAPH_RAY_QUERY=on` the device's ray queries; `LUMAGRAPH_BVH=wide` or `binary` the
/// 8-wide or the binary BVH in WGSL; else `AUTO`.
fn intersector_from_env() -> Intersector {
    if std::env::var("LUMAGRAPH_RAY_QUERY").is_ok_and(|v| v == "on" || v == "1") {
        return Intersector::RAY_QUERIES;
    }
    match std::env::var("LUMAGRAPH_BVH").as_deref() {
        Ok("wide") => Intersector::WIDE_BVH,
        Ok("binary") => Intersector::BINARY_BVH,
        _ => Intersector::AUTO,
    }
}

/// `LUMAGRAPH_WAVEFRONT=on` the wavefront, `off` the megakernel; else `Auto`.
fn schedule_from_env() -> Schedule {
    match std::env::var("LUMAGRAPH_WAVEFRONT").as_deref() {
        Ok("on" | "1") => Schedule::Wavefront,
        Ok("off" | "0") => Schedule::Megakernel,
        _ => Schedule::Auto,
    }
}

/// The shader features of every pass specialized to the scene: the intersector and schedule
/// chosen and why, what is compiled in, and what is left out with why, for the adapter
/// `render` would use (found without opening a device) and the choices asked for.
///
/// # Errors
/// When a pass cannot have the intersector or schedule asked for, with why (after printing
/// what it would compile).
pub(crate) fn print_features(
    plan: &crate::graph::Plan,
    scene: &crate::scene::GpuScene,
    library: &crate::render::NodeLibrary,
    choice: Choice,
) -> anyhow::Result<()> {
    let specialized: Vec<_> = plan
        .passes
        .iter()
        .filter_map(|p| {
            library
                .implementation(&p.kind)
                .and_then(|i| i.features)
                .map(|f| (p, f))
        })
        .collect();
    if specialized.is_empty() {
        return Ok(());
    }
    let traits = match crate::render::GpuContext::default_adapter_traits() {
        Ok((info, traits)) => {
            println!(
                "adapter: {} ({:?}{}); the shader choices below are made for it",
                info.name,
                info.device_type,
                if traits.ray_query_limit.is_some() {
                    ", ray queries"
                } else {
                    ""
                }
            );
            traits
        }
        Err(e) => {
            println!("adapter: none found ({e}); shader choices shown for a CPU one");
            crate::render::AdapterTraits {
                cpu: true,
                ray_query_limit: None,
            }
        }
    };
    let resources = choice.apply(Resources::default());
    let mut refusals = Vec::new();
    for (pass, features) in specialized {
        let choices = features(pass, scene, &resources, traits);
        println!("shader features of {} for this scene:", pass.node);
        for line in &choices.lines {
            println!("{line}");
        }
        if let Some(why) = choices.refusal {
            refusals.push(format!("{}: {why}", pass.node));
        }
    }
    anyhow::ensure!(refusals.is_empty(), "{}", refusals.join("\n"));
    Ok(())
}
