//! A lost GPU device is one clear error, never a panic or a hang, and a new device on the
//! same adapter renders again. The test opens a device of its own (it destroys it).

mod common;

use std::sync::Arc;

use lumagraph::pathtrace::library::compile;
use lumagraph::render::{Executor, GpuContext, RenderError, Resources};

fn executor(ctx: &GpuContext, scene: &Arc<lumagraph::scene::GpuScene>) -> Executor {
    let graph = common::progressive_graph(&[]);
    let plan = compile(&graph, &["acc.color".to_owned()], Some(scene)).unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        ..Resources::default()
    };
    lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap()
}

#[test]
fn a_lost_device_is_a_clear_error_and_a_new_one_renders() {
    if common::gpu().is_none() {
        return;
    }
    let ctx = GpuContext::headless_prefer_cpu().unwrap();
    let scene = common::gpu_scene("assets/cornell.ron", Some(16));
    let mut exec = executor(&ctx, &scene);
    exec.run_frame().unwrap();
    ctx.device.destroy();
    let err = exec.run_frame().expect_err("a frame on a destroyed device");
    assert!(
        matches!(&err, RenderError::DeviceLost { reason, .. } if reason.starts_with("destroyed")),
        "{err}"
    );
    assert!(err.to_string().contains("was lost (destroyed"), "{err}");
    let again = ctx.reopen().unwrap();
    assert!(again.lost().is_none());
    executor(&again, &scene).run_frame().unwrap();
}
