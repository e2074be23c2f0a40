//! Shared helpers for the editor tests: one wgpu device per test binary, used by both the
//! renderer (the editor's preview) and egui's test renderer, as in the real window.
//!
//! GPU tests fail when no adapter is found, unless `LUMAGRAPH_ALLOW_NO_GPU=1` is set.
//! With `CI` set, the adapter must be a CPU one (lavapipe).

#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use egui_kittest::{Harness, SnapshotOptions};
use lumagraph_editor::{Editor, EditorConfig};
use lumagraph_render::GpuContext;

/// Snapshot tolerance, kept in one place: per-pixel YIQ distance threshold and the
/// number of pixels allowed to exceed it (text anti-aliasing may differ across Mesa
/// versions).
pub fn snapshot_options() -> SnapshotOptions {
    SnapshotOptions::new()
        .threshold(0.6)
        .max_failed_pixels(40)
        .output_path(repo_crate().join("tests/snapshots"))
}

/// Window size of the test harness.
pub const SIZE: egui::Vec2 = egui::vec2(1100.0, 620.0);

struct Shared {
    instance: wgpu::Instance,
    ctx: GpuContext,
}

fn shared() -> Option<&'static Shared> {
    static GPU: LazyLock<Option<Shared>> = LazyLock::new(|| {
        let made = pollster::block_on(async {
            let desc = GpuContext::instance_descriptor();
            let backends = desc.backends;
            let instance = wgpu::Instance::new(desc);
            let adapters = instance.enumerate_adapters(backends).await;
            let adapter = adapters
                .iter()
                .find(|a| a.get_info().device_type == wgpu::DeviceType::Cpu)
                .or_else(|| adapters.first())
                .cloned()
                .ok_or_else(|| "no GPU adapter".to_owned())?;
            let ctx = GpuContext::from_adapter(adapter)
                .await
                .map_err(|e| e.to_string())?;
            Ok::<_, String>(Shared { instance, ctx })
        });
        lumagraph_render::for_tests(made, |s: &Shared| &s.ctx)
    });
    GPU.as_ref()
}

/// The shared GPU context, or `None` when there is no GPU and that is allowed.
pub fn gpu() -> Option<GpuContext> {
    shared().map(|s| s.ctx.clone())
}

/// The editor crate's folder.
pub fn repo_crate() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A path under the repository root.
pub fn repo(rel: &str) -> PathBuf {
    repo_crate().join("../..").join(rel)
}

/// An editor on the shared device, with the recent-files list in `recent`.
pub fn editor(graph: Option<&Path>, recent: Option<PathBuf>) -> Option<Editor> {
    with_config(
        graph,
        &EditorConfig {
            recent_store: recent,
            ..EditorConfig::default()
        },
    )
}

/// An editor on the shared device with `config`.
pub fn with_config(graph: Option<&Path>, config: &EditorConfig) -> Option<Editor> {
    let gpu = gpu()?;
    Some(Editor::new(gpu, graph, config))
}

/// A headless harness drawing `editor` with egui's wgpu renderer on the shared device.
pub fn harness(editor: Editor) -> Harness<'static, Editor> {
    harness_sized(editor, SIZE)
}

/// [`harness`] whose frames are `step_dt` seconds apart (a quarter second by default;
/// a double click needs two clicks within 0.3 s).
#[allow(dead_code, reason = "not every test file uses it")]
pub fn harness_stepped(editor: Editor, step_dt: f32) -> Harness<'static, Editor> {
    harness_with(editor, SIZE, step_dt)
}

/// [`harness`] with a window of `size` points.
pub fn harness_sized(editor: Editor, size: egui::Vec2) -> Harness<'static, Editor> {
    harness_with(editor, size, 0.25)
}

fn harness_with(editor: Editor, size: egui::Vec2, step_dt: f32) -> Harness<'static, Editor> {
    let s = shared().expect("a harness needs the GPU");
    let setup = egui_wgpu::WgpuSetup::Existing(egui_wgpu::WgpuSetupExisting {
        instance: s.instance.clone(),
        adapter: s.ctx.adapter.clone(),
        device: s.ctx.device.clone(),
        queue: s.ctx.queue.clone(),
    });
    let mut h = Harness::builder()
        .with_size(size)
        .with_step_dt(step_dt)
        .with_pixels_per_point(1.0)
        .wgpu_setup(setup)
        .build_ui_state(|ui, editor: &mut Editor| editor.ui(ui), editor);
    h.run_ok();
    h
}

/// A click (press, release) at `pos`, with the pointer moved there first.
pub fn click_at(h: &mut Harness<'_, Editor>, pos: egui::Pos2) {
    h.hover_at(pos);
    h.run_ok();
    for pressed in [true, false] {
        h.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    h.run_ok();
}
