//! The reader against OpenEXR's own, file by file, over the OpenEXR project's sample
//! images (`../shared/assets/openexr-images`, or `LUMAGRAPH_OPENEXR_IMAGES`).
//!
//! `tests/exr/openexr_reference.json` holds what OpenEXR reads of each file (made by
//! `scripts/exr/reference.py` with OpenEXR 3.5.3's Python bindings and libOpenEXR 3.1.5's
//! `RgbaInputFile`): parts, views, windows, compression, chromaticities, channels with a
//! SHA-256 of each channel's samples as stored, RGBA samples as `RgbaInputFile`
//! reconstructs luminance/chroma images, and colour converted to Rec. 709 with the
//! matrices OpenEXR derives. Every file is checked against it; the counts of files read
//! right, refused cleanly and wrong are printed (`--nocapture`) and none may be wrong.
//!
//! Without the images the test fails where `CI` is set and says so elsewhere.

use std::path::{Path, PathBuf};

use lumagraph_footage::exr::{self, Selection, Want};
use lumagraph_footage::yca;
use serde_json::Value;

fn root() -> Option<PathBuf> {
    lumagraph_footage::testing::openexr_images(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/openexr-images"),
    )
}

/// The reference: `tests/exr/openexr_reference.json`, or `LUMAGRAPH_OPENEXR_REFERENCE`
/// (one made by `scripts/exr/reference.py --root` over another folder of images).
fn reference() -> Value {
    let path = std::env::var_os("LUMAGRAPH_OPENEXR_REFERENCE").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/exr/openexr_reference.json"),
        PathBuf::from,
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn sha256(channel: &exr::RawChannel) -> String {
    lumagraph_footage::testing::channel_sha256(channel)
}

fn window(v: &Value) -> [i64; 4] {
    let a: Vec<i64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_i64().unwrap())
        .collect();
    [a[0], a[1], a[2], a[3]]
}

fn ours(w: exr::Window) -> [i64; 4] {
    [w.min[0], w.min[1], w.max[0], w.max[1]].map(i64::from)
}

/// Everything [`exr::inspect`] and [`exr::read_channels`] give for one file against the
/// reference; the first difference in words.
fn check_file(path: &Path, want: &Value) -> Result<(), String> {
    let info = exr::inspect(path).map_err(|e| e.to_string())?;
    let parts = want["parts"].as_array().unwrap();
    if info.parts.len() != parts.len() {
        return Err(format!(
            "{} parts, OpenEXR reads {}",
            info.parts.len(),
            parts.len()
        ));
    }
    for (part, w) in info.parts.iter().zip(parts) {
        let label = part.label();
        let same = |what: &str, a: Value, b: &Value| {
            if a == *b {
                Ok(())
            } else {
                Err(format!("{label}: {what} {a}, OpenEXR {b}"))
            }
        };
        same("name", part.name.clone().into(), &w["name"])?;
        same("view", part.view.clone().into(), &w["view"])?;
        same("type", part.kind.name().into(), &w["type"])?;
        same(
            "compression",
            part.compression.clone().into(),
            &w["compression"],
        )?;
        if ours(part.data_window) != window(&w["data_window"])
            || ours(part.display_window) != window(&w["display_window"])
        {
            return Err(format!(
                "{label}: windows {} / {} differ from OpenEXR's",
                part.data_window, part.display_window
            ));
        }
        match (&part.chromaticities, w["chromaticities"].as_array()) {
            (None, None) => {}
            (Some(c), Some(r))
                if c.to_array()
                    .iter()
                    .zip(r)
                    .all(|(a, b)| (f64::from(*a) - b.as_f64().unwrap()).abs() < 1e-6) => {}
            (c, r) => return Err(format!("{label}: chromaticities {c:?}, OpenEXR {r:?}")),
        }
        let channels = w["channels"].as_array().unwrap();
        if part.channels.len() != channels.len() {
            return Err(format!(
                "{label}: {} channels, OpenEXR {}",
                part.channels.len(),
                channels.len()
            ));
        }
        for (c, r) in part.channels.iter().zip(channels) {
            same("channel", c.name.clone().into(), &r["name"])?;
            same("channel type", c.sample.name().into(), &r["type"])?;
            same("sampling", serde_json::json!(c.sampling), &r["sampling"])?;
        }
        if part.kind.is_deep() {
            let names: Vec<String> = part.channels.iter().map(|c| c.name.clone()).collect();
            match exr::read_channels(path, &info, part.index, &names) {
                Err(e) if e.message.contains("deep") => continue,
                other => return Err(format!("{label}: a deep part read as {other:?}")),
            }
        }
        let names: Vec<String> = part.channels.iter().map(|c| c.name.clone()).collect();
        let raw = exr::read_channels(path, &info, part.index, &names).map_err(|e| e.to_string())?;
        for (c, r) in raw.iter().zip(channels) {
            if r["sha256"].as_str() != Some(sha256(c).as_str()) {
                return Err(format!(
                    "{label}: channel {}'s samples differ from OpenEXR's",
                    c.name
                ));
            }
        }
    }
    Ok(())
}

/// The layer `selection` names read through the display window agrees with the raw
/// channels: each display pixel inside the data window is the stored value, 0 outside.
fn check_placement(path: &Path) -> Result<(), String> {
    let info = exr::inspect(path).map_err(|e| e.to_string())?;
    let Ok(layer) = Selection::default().find(&info) else {
        return Ok(());
    };
    if !matches!(layer.kind, exr::LayerKind::Color { .. })
        || info.parts[layer.part]
            .chromaticities
            .is_some_and(|c| !c.is_rec709())
    {
        return Ok(());
    }
    let image =
        exr::read_layer(path, &Selection::default(), Want::Rgba).map_err(|e| e.to_string())?;
    let part = &info.parts[layer.part];
    let raw =
        exr::read_channels(path, &info, layer.part, &layer.channels).map_err(|e| e.to_string())?;
    let (data, display) = (part.data_window, part.display_window);
    if image.width() != display.width() || image.height() != display.height() {
        return Err(format!(
            "read as {}×{}, the display window is {display}",
            image.width(),
            image.height()
        ));
    }
    for y in display.min[1]..=display.max[1] {
        for x in display.min[0]..=display.max[0] {
            let at = ((y - display.min[1]) as usize * display.width()
                + (x - display.min[0]) as usize)
                * 4;
            let got = &image.pixels[at..at + 4];
            let inside =
                x >= data.min[0] && x <= data.max[0] && y >= data.min[1] && y <= data.max[1];
            let want: [f32; 4] = if inside {
                let i = (y - data.min[1]) as usize * data.width() + (x - data.min[0]) as usize;
                let a = if raw.len() > 3 { raw[3].value(i) } else { 1.0 };
                [raw[0].value(i), raw[1].value(i), raw[2].value(i), a]
            } else {
                [0.0; 4]
            };
            if got
                .iter()
                .zip(want)
                .any(|(g, w)| g.to_bits() != w.to_bits() && !(g.is_nan() && w.is_nan()))
            {
                return Err(format!(
                    "display pixel ({x}, {y}) is {got:?}, OpenEXR places {want:?} there"
                ));
            }
        }
    }
    Ok(())
}

/// `RgbaInputFile`'s reconstruction at the reference's sample positions, as halves.
fn check_rgba(path: &Path, want: &Value) -> Result<(), String> {
    let info = exr::inspect(path).map_err(|e| e.to_string())?;
    let layer = Selection::default().find(&info)?;
    let part = &info.parts[layer.part];
    let exr::LayerKind::Luminance { chroma, alpha } = layer.kind else {
        return Err(format!(
            "the default layer is {:?}, not luminance",
            layer.kind
        ));
    };
    let raw =
        exr::read_channels(path, &info, layer.part, &layer.channels).map_err(|e| e.to_string())?;
    let planes: Vec<Vec<f32>> = raw.iter().map(exr::RawChannel::values).collect();
    let input = yca::YcaInput {
        width: part.data_window.width(),
        height: part.data_window.height(),
        origin: (part.data_window.min[0], part.data_window.min[1]),
        y: &planes[0],
        ry: chroma.then(|| planes[1].as_slice()),
        by: chroma.then(|| planes[2].as_slice()),
        a: alpha.then(|| planes[planes.len() - 1].as_slice()),
    };
    let rgba = yca::to_rgba(
        &input,
        yca::luminance_weights(part.chromaticities.map(|c| c.to_array())),
    )
    .map_err(|e| e.to_string())?;
    let mut worst = 0.0_f32;
    for s in want["samples"].as_array().unwrap() {
        let v: Vec<f64> = s
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let (x, y) = (
            v[0] as i32 - part.data_window.min[0],
            v[1] as i32 - part.data_window.min[1],
        );
        let got = rgba[y as usize * part.data_window.width() + x as usize];
        for c in 0..4 {
            let (g, r) = (half::f16::from_f32(got[c]).to_f32(), v[2 + c] as f32);
            worst = worst.max((g - r).abs() / r.abs().max(1e-3));
        }
    }
    // Chroma reconstruction rounds to halves at several steps; a half's step is 2^-10.
    if worst > 2e-3 {
        return Err(format!(
            "RGBA differs from RgbaInputFile's by up to {worst:.2e} (relative)"
        ));
    }
    Ok(())
}

/// Colour converted to Rec. 709 as OpenEXR's matrices convert it.
fn check_rec709(path: &Path, want: &Value) -> Result<(), String> {
    let image =
        exr::read_layer(path, &Selection::default(), Want::Rgba).map_err(|e| e.to_string())?;
    let (x0, y0) = (image.display_window.min[0], image.display_window.min[1]);
    let mut worst = 0.0_f64;
    for s in want["samples"].as_array().unwrap() {
        let v: Vec<f64> = s
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let i = ((v[1] as i32 - y0) as usize * image.width() + (v[0] as i32 - x0) as usize) * 4;
        let scale = v[2..5].iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        for c in 0..3 {
            worst = worst.max((f64::from(image.pixels[i + c]) - v[2 + c]).abs() / scale);
        }
    }
    if worst > 1e-5 {
        return Err(format!(
            "converted colour differs from OpenEXR's by up to {worst:.2e}"
        ));
    }
    Ok(())
}

#[test]
fn every_sample_image_reads_as_openexr_reads_it() {
    let Some(root) = root() else { return };
    let reference = reference();
    let (mut right, mut refused, mut wrong) = (0, 0, Vec::new());
    for (name, want) in reference["files"].as_object().unwrap() {
        let path = root.join(name);
        let deep = want["parts"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["type"].as_str().unwrap().starts_with("deep"));
        let mut result = check_file(&path, want);
        if !deep {
            result = result.and_then(|()| check_placement(&path));
        }
        if result.is_ok() && !want["rgba"].is_null() {
            result = check_rgba(&path, &want["rgba"]);
        }
        if result.is_ok() && !want["to_rec709"].is_null() {
            result = check_rec709(&path, &want["to_rec709"]);
        }
        if deep && result.is_ok() {
            // Deep data: listed, refused when read, with the part named.
            match exr::read_layer(&path, &Selection::default(), Want::Rgba) {
                Err(e) if e.message.contains("deep") => refused += 1,
                other => wrong.push(format!(
                    "{name}: deep file read as {:?}",
                    other.map(|i| i.layer)
                )),
            }
            continue;
        }
        match result {
            Ok(()) => right += 1,
            Err(e) => wrong.push(format!("{name}: {e}")),
        }
    }
    let mut damaged = 0;
    for name in reference["damaged"].as_array().unwrap() {
        let path = root.join(name.as_str().unwrap());
        let read =
            std::panic::catch_unwind(|| exr::read_layer(&path, &Selection::default(), Want::Rgba));
        match read {
            Ok(Err(e)) if !e.message.is_empty() => damaged += 1,
            Ok(Err(_)) => wrong.push(format!("{}: refused with an empty message", path.display())),
            Ok(Ok(_)) => wrong.push(format!("{}: a damaged file was read", path.display())),
            Err(_) => wrong.push(format!("{}: panicked", path.display())),
        }
    }
    println!(
        "OpenEXR sample images: {right} read as OpenEXR reads them, {refused} deep refused \
         cleanly, {damaged} damaged refused cleanly, {} wrong",
        wrong.len()
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert_eq!(
        right + refused,
        reference["files"].as_object().unwrap().len()
    );
}

#[test]
fn xyz_primaries_read_as_the_rec709_file_that_shows_the_same_picture() {
    let Some(root) = root() else { return };
    let read =
        |name: &str| exr::read_layer(&root.join(name), &Selection::default(), Want::Rgba).unwrap();
    let (xyz, rec709) = (
        read("Chromaticities/XYZ.exr"),
        read("Chromaticities/Rec709.exr"),
    );
    assert!(
        xyz.notes.iter().any(|n| n.contains("converted")),
        "{:?}",
        xyz.notes
    );
    let info = exr::inspect(&root.join("Chromaticities/XYZ.exr")).unwrap();
    let names = &Selection::default().find(&info).unwrap().channels;
    let raw = exr::read_channels(&root.join("Chromaticities/XYZ.exr"), &info, 0, names).unwrap();
    let mean_rel = |a: &dyn Fn(usize, usize) -> f32| {
        let (mut sum, mut n) = (0.0_f64, 0_u32);
        for i in 0..rec709.pixels.len() / 4 {
            for c in 0..3 {
                let r = rec709.pixels[i * 4 + c];
                if r.abs() > 1e-3 {
                    sum += f64::from((a(i, c) - r).abs() / r.abs());
                    n += 1;
                }
            }
        }
        sum / f64::from(n)
    };
    let converted = mean_rel(&|i, c| xyz.pixels[i * 4 + c]);
    let as_if_709 = mean_rel(&|i, c| raw[c].value(i));
    println!(
        "XYZ.exr against Rec709.exr: mean relative difference {converted:.2e} converted, {as_if_709:.2e} read as Rec. 709"
    );
    assert!(converted < 0.01, "{converted}");
    assert!(as_if_709 > 0.1, "{as_if_709}");
}
