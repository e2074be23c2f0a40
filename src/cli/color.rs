//! `lumagraph color [--config C]`: what an OpenColorIO config offers the `ColorSpace` and
//! `DisplayView` nodes: its colour spaces, displays and their views, looks, and the name it
//! gives lumagraph's working space.

use std::path::Path;

use anyhow::Result;
use lumagraph_color::ColorConfig;

/// Prints the config `spec` names (as the nodes' `config` param takes it).
pub(super) fn color(spec: &str) -> Result<()> {
    let config = ColorConfig::load(spec, Path::new("."))?;
    println!("config: {}", config.source);
    println!(
        "working space (scene-linear Rec. 709): {}",
        config.working_space()
    );
    let spaces = config.color_spaces();
    println!("colour spaces ({}):", spaces.len());
    for s in &spaces {
        println!("  {s}");
    }
    let (default_display, default_view) = config.default_display_view();
    let displays = config.displays();
    println!(
        "displays ({}; default {default_display:?}, view {default_view:?}):",
        displays.len()
    );
    for (d, views) in &displays {
        println!("  {d}: {}", views.join(", "));
    }
    let looks = config.looks();
    if looks.is_empty() {
        println!("looks: none");
    } else {
        println!("looks: {}", looks.join(", "));
    }
    Ok(())
}
