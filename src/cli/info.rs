//! `lumagraph info FILE`: what an image file holds, as compositors need to know it: an
//! EXR's parts, views, layers (and the port each is read onto), channels, windows, colour
//! primaries and every attribute.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use lumagraph_footage::exr::{self, Info, LayerKind, Want};

/// Prints `path`'s description, or with `json` the same as JSON.
pub(super) fn info(path: &Path, json: bool) -> Result<()> {
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        let size = crate::render::image_io::dimensions(path)?;
        println!("{}: {size}, colour (one RGB(A) image)", path.display());
        return Ok(());
    }
    let info = exr::inspect(path)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&to_json(&info))?);
    } else {
        print!("{}", text(&info));
    }
    Ok(())
}

fn kind_words(kind: LayerKind, channels: &[String]) -> String {
    let port = Want::of(kind).port();
    let extra = if matches!(kind, LayerKind::Luminance { chroma: false, .. }) {
        " (or `scalar`: Y)"
    } else {
        ""
    };
    format!("{} {} → `{port}`{extra}", kind.name(), channels.join(" "))
}

/// The description in words.
pub(super) fn text(info: &Info) -> String {
    let mut out = String::new();
    let views = info.views();
    let _ = write!(
        out,
        "{}: {} part{}",
        info.path.display(),
        info.parts.len(),
        if info.parts.len() == 1 { "" } else { "s" }
    );
    if !views.is_empty() {
        let _ = write!(
            out,
            ", views {} (default {})",
            views.join(", "),
            info.default_view().unwrap_or("-")
        );
    }
    out.push('\n');
    let layers = info.layers();
    for part in &info.parts {
        let _ = write!(out, "part {}", part.index);
        if let Some(name) = &part.name {
            let _ = write!(out, " {name:?}");
        }
        if let Some(view) = &part.view {
            let _ = write!(out, " (view {view})");
        }
        let _ = writeln!(
            out,
            ": {}, {} compression, levels {}",
            part.kind.name(),
            part.compression,
            part.levels
        );
        let _ = writeln!(out, "  display window {}", part.display_window);
        let _ = writeln!(out, "  data window    {}", part.data_window);
        match &part.chromaticities {
            Some(c) if !c.is_rec709() => {
                let _ = writeln!(
                    out,
                    "  chromaticities red {:?} green {:?} blue {:?} white {:?}: converted to Rec. 709 when read",
                    c.red, c.green, c.blue, c.white
                );
            }
            Some(_) => {
                let _ = writeln!(out, "  chromaticities Rec. 709");
            }
            None => {
                let _ = writeln!(out, "  chromaticities none (Rec. 709, as OpenEXR assumes)");
            }
        }
        if !part.multi_view.is_empty() {
            let _ = writeln!(out, "  multiView {}", part.multi_view.join(", "));
        }
        let channels: Vec<String> = part
            .channels
            .iter()
            .map(|c| {
                let sampling = if c.sampling == [1, 1] {
                    String::new()
                } else {
                    format!(" (1 in {}×{})", c.sampling[0], c.sampling[1])
                };
                format!("{} {}{sampling}", c.name, c.sample.name())
            })
            .collect();
        let _ = writeln!(out, "  channels {}", channels.join(", "));
        if part.kind.is_deep() {
            let _ = writeln!(
                out,
                "  deep data: not read (lumagraph reads flat images only)"
            );
        } else {
            for layer in layers.iter().filter(|l| l.part == part.index) {
                let name = if layer.name.is_empty() {
                    "(root)"
                } else {
                    &layer.name
                };
                let view = layer
                    .view
                    .as_ref()
                    .filter(|v| part.view.as_ref() != Some(*v))
                    .map(|v| format!(" [view {v}]"))
                    .unwrap_or_default();
                let pick = layer
                    .names(part)
                    .first()
                    .map_or_else(|| "(empty: the default)".to_owned(), |n| format!("{n:?}"));
                let _ = writeln!(
                    out,
                    "  layer {name}{view}: {}; layer: {pick}",
                    kind_words(layer.kind, &layer.channels)
                );
            }
        }
        for (k, v) in &part.attributes {
            let _ = writeln!(out, "  {k} = {v}");
        }
    }
    out
}

fn window_json(w: exr::Window) -> serde_json::Value {
    serde_json::json!([w.min[0], w.min[1], w.max[0], w.max[1]])
}

/// The description as JSON (what `--json` prints).
pub(super) fn to_json(info: &Info) -> serde_json::Value {
    let layers = info.layers();
    let parts: Vec<serde_json::Value> = info
        .parts
        .iter()
        .map(|p| {
            serde_json::json!({
                "index": p.index,
                "name": p.name,
                "view": p.view,
                "type": p.kind.name(),
                "data_window": window_json(p.data_window),
                "display_window": window_json(p.display_window),
                "compression": p.compression,
                "levels": p.levels,
                "chromaticities": p.chromaticities.map(|c| c.to_array()),
                "multi_view": p.multi_view,
                "channels": p.channels.iter().map(|c| serde_json::json!({
                    "name": c.name, "type": c.sample.name(), "sampling": c.sampling,
                })).collect::<Vec<_>>(),
                "layers": layers.iter().filter(|l| l.part == p.index).map(|l| serde_json::json!({
                    "name": l.name, "view": l.view, "kind": l.kind.name(),
                    "channels": l.channels, "port": Want::of(l.kind).port(),
                    "names": l.names(p),
                })).collect::<Vec<_>>(),
                "attributes": p.attributes.iter()
                    .map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone())))
                    .collect::<serde_json::Map<_, _>>(),
            })
        })
        .collect();
    serde_json::json!({
        "path": info.path,
        "views": info.views(),
        "default_view": info.default_view(),
        "parts": parts,
    })
}
