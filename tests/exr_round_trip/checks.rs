//! How a written file is held to its source: names, windows, channels, types, values.

use std::path::Path;

use lumagraph::footage::exr::{self, Layer, LayerKind, Selection, Want, Window};
use serde_json::Value;

/// A channel's samples hashed as the reference hashes them (little-endian, as stored).
pub(crate) fn channel_hash(channel: &exr::RawChannel) -> String {
    lumagraph::footage::testing::channel_sha256(channel)
}

pub(crate) fn window(v: &Value) -> Window {
    let a: Vec<i32> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| i32::try_from(x.as_i64().unwrap()).unwrap())
        .collect();
    Window {
        min: [a[0], a[1]],
        max: [a[2], a[3]],
    }
}

pub(crate) fn intersect(a: Window, b: Window) -> Option<Window> {
    let min = [a.min[0].max(b.min[0]), a.min[1].max(b.min[1])];
    let max = [a.max[0].min(b.max[0]), a.max[1].min(b.max[1])];
    (min[0] <= max[0] && min[1] <= max[1]).then_some(Window { min, max })
}

/// A `(layer, view)` selection that finds `layer` in `info`, if there is one.
pub(crate) fn selection_of(info: &exr::Info, layer: &Layer) -> Option<Selection> {
    let view = layer.view.clone().unwrap_or_default();
    let part = &info.parts[layer.part];
    std::iter::once(String::new())
        .chain(layer.names(part))
        .map(|name| Selection {
            layer: name,
            view: view.clone(),
        })
        .find(|s| s.find(info).as_ref() == Ok(layer))
}

/// How a written layer is held to its source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// Same windows and values: every channel's hash is the reference's.
    Identical,
    /// The source has overscan: the values inside the display window, bit for bit.
    Cropped,
    /// Colour converted to Rec. 709 when read: lumagraph's conversion, rounded.
    Converted,
    /// Luminance/chroma: written as `R G B`, lumagraph's reconstruction, rounded.
    Reconstructed,
}

/// How `layer` of `part` is held to its source, and the channels it is written as.
pub(crate) fn expect(part: &exr::Part, layer: &Layer) -> (Kind, Vec<String>) {
    if let LayerKind::Luminance {
        chroma: true,
        alpha,
    } = layer.kind
    {
        let prefix = layer.channels[0]
            .rsplit_once('.')
            .map(|(p, _)| format!("{p}."))
            .unwrap_or_default();
        let mut names: Vec<String> = ["R", "G", "B"]
            .iter()
            .map(|c| format!("{prefix}{c}"))
            .collect();
        if alpha {
            names.push(format!("{prefix}A"));
        }
        return (Kind::Reconstructed, names);
    }
    let converted = part.chromaticities.is_some_and(|c| !c.is_rec709());
    if Want::of(layer.kind) == Want::Rgba && converted {
        (Kind::Converted, layer.channels.clone())
    } else if part.display_window.contains(&part.data_window) {
        (Kind::Identical, layer.channels.clone())
    } else {
        (Kind::Cropped, layer.channels.clone())
    }
}

/// The written part `b` of the file at `out` against `layers` of part `a` of the source:
/// names, windows, channels, types and values as each layer's kind holds them.
pub(crate) fn check_part(
    (src, info, reference): (&Path, &exr::Info, &Value),
    (out, back, b): (&Path, &exr::Info, usize),
    layers: &[(&Layer, &Selection)],
) -> Result<Vec<Kind>, String> {
    let a = &info.parts[layers[0].0.part];
    let r = &reference["parts"][a.index];
    let w = &back.parts[b];
    let label = w.label();
    if (&w.name, &w.view) != (&a.name, &a.view) {
        return Err(format!(
            "{label}: name and view {:?} {:?}, the source's {:?} {:?}",
            w.name, w.view, a.name, a.view
        ));
    }
    let display = window(&r["display_window"]);
    let data = intersect(window(&r["data_window"]), display)
        .unwrap_or_else(|| Window::at(display.min, [1, 1]));
    if (w.display_window, w.data_window) != (display, data) {
        return Err(format!(
            "{label}: windows {} / {}, expected {display} / {data}",
            w.display_window, w.data_window
        ));
    }
    let mut kinds = Vec::new();
    let mut names = Vec::new();
    for (layer, _) in layers {
        let (kind, channels) = expect(a, layer);
        kinds.push(kind);
        names.extend(channels);
    }
    names.sort();
    let written: Vec<String> = w.channels.iter().map(|c| c.name.clone()).collect();
    if written != names {
        return Err(format!("{label}: channels {written:?}, expected {names:?}"));
    }
    let source_channels = r["channels"].as_array().unwrap();
    let find = |n: &str| source_channels.iter().find(|rc| rc["name"] == n);
    for c in &w.channels {
        // R G B of a luminance/chroma layer have the type of its `Y`.
        let rc = find(&c.name)
            .or_else(|| find(&layers[0].0.channels[0]))
            .ok_or_else(|| format!("{label}: no source channel for {}", c.name))?;
        if rc["type"] != c.sample.name() {
            return Err(format!(
                "{label}: channel {} is {}, the source's {}",
                c.name,
                c.sample.name(),
                rc["type"]
            ));
        }
    }
    for ((layer, selection), kind) in layers.iter().zip(&kinds) {
        check_values((src, info, r), (out, back, b), layer, selection, *kind)
            .map_err(|e| format!("{label}: layer {:?}: {e}", layer.name))?;
    }
    Ok(kinds)
}

/// A written layer's values against its source's, as its kind holds them.
pub(crate) fn check_values(
    (src, info, r): (&Path, &exr::Info, &Value),
    (out, back, b): (&Path, &exr::Info, usize),
    layer: &Layer,
    selection: &Selection,
    kind: Kind,
) -> Result<(), String> {
    let e = |e: exr::Error| e.to_string();
    match kind {
        Kind::Identical => {
            let raw = exr::read_channels(out, back, b, &layer.channels).map_err(e)?;
            for c in &raw {
                let rc = r["channels"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .find(|rc| rc["name"] == c.name.as_str())
                    .unwrap();
                if rc["sha256"].as_str() != Some(channel_hash(c).as_str()) {
                    return Err(format!(
                        "channel {}'s samples differ from OpenEXR's",
                        c.name
                    ));
                }
            }
        }
        Kind::Cropped => {
            let part = &info.parts[layer.part];
            let data = part.data_window;
            let window = back.parts[b].data_window;
            let theirs = exr::read_channels(src, info, layer.part, &layer.channels).map_err(e)?;
            let ours = exr::read_channels(out, back, b, &layer.channels).map_err(e)?;
            for (t, o) in theirs.iter().zip(&ours) {
                let mut i = 0;
                for y in window.min[1]..=window.max[1] {
                    for x in window.min[0]..=window.max[0] {
                        let inside = x >= data.min[0]
                            && x <= data.max[0]
                            && y >= data.min[1]
                            && y <= data.max[1];
                        let want = if inside {
                            let at = (y - data.min[1]) as usize * data.width()
                                + (x - data.min[0]) as usize;
                            t.bits[at]
                        } else {
                            0
                        };
                        if o.bits[i] != want {
                            return Err(format!("channel {} differs at ({x}, {y})", o.name));
                        }
                        i += 1;
                    }
                }
            }
        }
        Kind::Converted | Kind::Reconstructed => {
            let want = exr::read_layer(src, selection, Want::Rgba).map_err(e)?;
            let back_selection = Selection {
                layer: String::new(),
                view: selection.view.clone(),
            };
            let got = exr::read_layer(out, &back_selection, Want::Rgba).map_err(e)?;
            let alpha = !matches!(
                layer.kind,
                LayerKind::Color { alpha: false } | LayerKind::Luminance { alpha: false, .. }
            );
            for (i, (g, w)) in got.pixels.iter().zip(&want.pixels).enumerate() {
                let w = exr::half_to_f32(exr::f32_to_half(*w));
                let same = g.to_bits() == w.to_bits() || (g.is_nan() && w.is_nan());
                if !same && (alpha || i % 4 != 3) {
                    return Err(format!(
                        "value {i}: {g}, lumagraph's reader {w} (as a half)"
                    ));
                }
            }
        }
    }
    Ok(())
}
