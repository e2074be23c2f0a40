//! The lumagraph node editor: build render graphs visually, with a live preview.
//!
//! - [`document`]: the [`lumagraph_graph::Graph`] being edited — the source of truth —
//!   and every edit, checked against the registry and recorded for [`undo`].
//! - [`canvas`]: the egui-snarl view of the graph (pins, menus and labels from the
//!   registry, compile errors and GPU times on the nodes).
//! - [`inspector`]: a widget per param, chosen by the param's type.
//! - [`preview`]: the selected output rendered on the editor's own wgpu device through
//!   the render crate's `Executor`; param edits update nodes in place; what its nodes
//!   measure; [`scope`]: histogram and waveform of the previewed image; [`sequence`]:
//!   the frame control of an image sequence (frame patterns in params).
//! - [`viewer`]: zoom, readout, compare; [`display`]: its OpenColorIO display, view and
//!   look, applied to what is shown only.
//! - [`files`]: open, save (atomic), save as, recent files.
//! - [`app`]: the window tying them together.
//!
//! One wgpu device serves both egui and the renderer: the renderer's
//! [`GpuContext`] wraps the device eframe created.

pub mod app;
pub mod canvas;
pub mod display;
pub mod document;
pub mod error_plot;
pub mod files;
pub mod grouping;
pub mod inspector;
pub mod preview;
pub mod render_job;
pub mod scene_doc;
pub mod scope;
pub mod sequence;
pub mod undo;
pub mod viewer;

use std::path::PathBuf;
use std::sync::Arc;

pub use app::{
    DEFAULT_PREVIEW_MAX, Editor, EditorApp, EditorConfig, EditorScene, Pick, RenderForm, SideTab,
};
use lumagraph_render::GpuContext;

/// What can go wrong in the editor.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EditorError {
    /// The window or its GPU could not be created.
    #[error("cannot open the editor window: {0}")]
    Window(String),
    /// A graph file could not be read or written.
    #[error("{0}")]
    Graph(String),
    /// The recent-files list could not be written.
    #[error("cannot update the recent-files list: {0}")]
    Recent(String),
    /// Save was asked for a graph that has no file yet.
    #[error("the graph has no file yet: use Save as")]
    NoPath,
}

/// The wgpu setup the editor asks eframe for: the adapter from the environment
/// (`WGPU_BACKEND`, `WGPU_POWER_PREF`), with the features and limits the renderer uses
/// (timestamp queries for per-node GPU times).
pub fn wgpu_setup() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor =
        Arc::new(|adapter| GpuContext::device_descriptor(adapter, "lumagraph editor"));
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// Opens the editor window, with `graph` loaded when given and the scene, preview size and
/// node library of `config` (a program with node kinds of its own passes its library
/// there); returns when it closes.
///
/// # Errors
/// When the window or its GPU device cannot be created.
pub fn run(graph: Option<PathBuf>, config: EditorConfig) -> Result<(), EditorError> {
    let options = eframe::NativeOptions {
        renderer: eframe::Renderer::Wgpu,
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1280.0, 760.0])
            .with_title("lumagraph editor"),
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: wgpu_setup(),
            ..Default::default()
        },
        ..Default::default()
    };
    let config = EditorConfig {
        recent_store: config.recent_store.or_else(files::default_recent_path),
        ..config
    };
    eframe::run_native(
        "lumagraph editor",
        options,
        Box::new(move |cc| {
            let rs = cc
                .wgpu_render_state
                .as_ref()
                .ok_or("eframe started without a wgpu device")?;
            let gpu =
                GpuContext::from_parts(rs.adapter.clone(), rs.device.clone(), rs.queue.clone());
            let editor = Editor::new(gpu, graph.as_deref(), &config);
            Ok(Box::new(EditorApp::new(editor)))
        }),
    )
    .map_err(|e| EditorError::Window(e.to_string()))
}
