//! The writer: what [`exr::assemble`] makes of images and their sources, and files
//! written by [`exr::encode`] read back by the reader: windows, parts, channel types,
//! attributes and values, bit for bit.

use std::path::{Path, PathBuf};

use lumagraph_footage::exr::{
    self, Compression, ImageIn, PartsChoice, SampleKind, Selection, Settings, Source, TypeChoice,
    Want, Window, WindowChoice,
};

fn image<'a>(values: &'a [f32], components: usize, w: usize, h: usize) -> ImageIn<'a> {
    ImageIn {
        port: "color",
        values,
        components,
        width: w,
        height: h,
        name: None,
        channels: None,
        default_name: String::new(),
        default_channels: ["R", "G", "B", "A"].map(str::to_owned).to_vec(),
        sample: TypeChoice::Float,
        source: None,
    }
}

fn settings(window: WindowChoice, parts: PartsChoice) -> Settings {
    Settings {
        window,
        parts,
        compression: Compression::Zip,
        chromaticities: lumagraph_footage::color::REC709,
    }
}

fn write(dir: &Path, name: &str, file: &exr::FileOut) -> PathBuf {
    let (bytes, notes) = exr::encode(file).unwrap();
    assert!(notes.is_empty(), "{notes:?}");
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn auto_crops_to_the_pixels_that_are_not_empty() {
    let mut values = vec![0.0; 4 * 3 * 4];
    values[(4 + 2) * 4 + 3] = 1.0; // pixel (2, 1), alpha
    values[(2 * 4 + 1) * 4] = -0.5; // pixel (1, 2), red
    let (file, notes) = exr::assemble(
        &[image(&values, 4, 4, 3)],
        &settings(WindowChoice::Auto, PartsChoice::Single),
    )
    .unwrap();
    assert!(notes.is_empty(), "{notes:?}");
    let part = &file.parts[0];
    assert_eq!(
        part.data_window,
        Window {
            min: [1, 1],
            max: [2, 2]
        }
    );
    assert_eq!(part.layers[0].values.len(), 2 * 2 * 4);
    assert_eq!(part.layers[0].values[2 * 4], -0.5);
    let empty = vec![0.0; 4 * 3 * 4];
    let (file, notes) = exr::assemble(
        &[image(&empty, 4, 4, 3)],
        &settings(WindowChoice::Auto, PartsChoice::Single),
    )
    .unwrap();
    assert_eq!(file.parts[0].data_window, Window::at([0, 0], [1, 1]));
    assert!(notes[0].contains("empty"), "{notes:?}");
}

#[test]
fn without_a_source_the_display_window_is_written_and_it_says_so() {
    let values = vec![1.0; 2 * 2 * 4];
    let mut one = image(&values, 4, 2, 2);
    one.sample = TypeChoice::Source;
    let (file, notes) =
        exr::assemble(&[one], &settings(WindowChoice::Source, PartsChoice::Single)).unwrap();
    assert_eq!(file.parts[0].data_window, Window::at([0, 0], [2, 2]));
    assert_eq!(file.parts[0].layers[0].samples, vec![SampleKind::Float; 4]);
    assert_eq!(notes.len(), 2, "{notes:?}");
}

#[test]
fn given_channels_must_fit_the_image() {
    let values = vec![1.0; 4];
    let mut one = image(&values, 1, 2, 2);
    one.channels = Some(vec!["u".into(), "v".into()]);
    let e = exr::assemble(
        &[one],
        &settings(WindowChoice::Display, PartsChoice::Single),
    )
    .unwrap_err();
    assert!(e.contains("1 value a pixel"), "{e}");
}

/// Two layers, one part each, re-read as two parts with their names, windows, types
/// and values; a uint channel keeps whole numbers and says what it rounded.
#[test]
fn parts_windows_and_types_are_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (6, 4);
    let colour: Vec<f32> = (0..w * h * 4)
        .map(|i| if i % 7 == 0 { 0.0 } else { i as f32 * 0.25 })
        .collect();
    let mut ids: Vec<f32> = vec![0.0; w * h];
    ids[w + 2] = 16_777_216.0;
    ids[2 * w + 3] = 7.0;
    let mut a = image(&colour, 4, w, h);
    a.sample = TypeChoice::Half;
    let mut b = image(&ids, 1, w, h);
    b.port = "layer1";
    b.name = Some("id".into());
    b.channels = Some(vec!["N".into()]);
    let (mut file, notes) = exr::assemble(
        &[a, b],
        &settings(WindowChoice::Auto, PartsChoice::PerLayer),
    )
    .unwrap();
    assert!(notes.is_empty(), "{notes:?}");
    file.parts[1].layers[0].samples = vec![SampleKind::Uint];
    let path = write(dir.path(), "parts.exr", &file);
    let info = exr::inspect(&path).unwrap();
    let names: Vec<_> = info.parts.iter().map(|p| p.name.clone()).collect();
    assert_eq!(names, [Some("rgba".into()), Some("id".into())]);
    assert_eq!(info.parts[0].display_window, Window::at([0, 0], [w, h]));
    assert_eq!(info.parts[0].data_window, Window::at([0, 0], [w, h]));
    assert_eq!(
        info.parts[1].data_window,
        Window {
            min: [2, 1],
            max: [3, 2]
        }
    );
    assert_eq!(info.parts[0].channels[0].sample, SampleKind::Half);
    assert_eq!(info.parts[1].channels[0].sample, SampleKind::Uint);
    let raw = exr::read_channels(&path, &info, 1, &["id.N".into()]).unwrap();
    assert_eq!(raw[0].bits, [16_777_216, 0, 0, 7]);
    let colour_back = exr::read_layer(&path, &Selection::layer("rgba"), Want::Rgba).unwrap();
    for (x, y) in colour.iter().zip(&colour_back.pixels) {
        assert_eq!(half::f16::from_f32(*x).to_f32(), *y);
    }
    // A float written as uint is rounded, and the writer says so.
    file.parts[1].layers[0].values[0] = 2.5;
    let (_, notes) = exr::encode(&file).unwrap();
    assert!(notes[0].contains("rounded"), "{notes:?}");
}

fn images() -> Option<PathBuf> {
    lumagraph_footage::testing::openexr_images(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/openexr-images"),
    )
}

/// A layer read and written back with its source (data window and types `source`), on
/// the CPU: the same part name, view, windows, channels, types, attributes and bits.
#[test]
fn sample_files_written_back_with_their_source_are_the_same() {
    let Some(root) = images() else { return };
    let dir = tempfile::tempdir().unwrap();
    for (name, layer, view) in [
        ("TestImages/AllHalfValues.exr", "", ""),
        ("DisplayWindow/t08.exr", "", ""),
        ("DisplayWindow/t16.exr", "", ""),
        ("MultiResolution/ColorCodedLevels.exr", "", ""),
        ("TestImages/WideFloatRange.exr", "G", ""),
        ("MultiView/Fog.exr", "", "right"),
        ("Beachball/multipart.0001.exr", "whitebarmask", "left"),
    ] {
        let path = root.join(name);
        let selection = Selection {
            layer: layer.into(),
            view: view.into(),
        };
        let info = exr::inspect(&path).unwrap();
        let found = selection.find(&info).unwrap();
        let want = Want::of(found.kind);
        let read = exr::read_layer(&path, &selection, want).unwrap();
        let source = Source::of(&path, &read.layer, want).unwrap();
        let mut one = image(&read.pixels, read.channels, read.width(), read.height());
        one.sample = TypeChoice::Source;
        one.source = Some(&source);
        let (file, notes) =
            exr::assemble(&[one], &settings(WindowChoice::Source, PartsChoice::Single)).unwrap();
        let out = write(dir.path(), "back.exr", &file);
        let back = exr::inspect(&out).unwrap();
        let (a, b) = (&info.parts[found.part], &back.parts[0]);
        assert_eq!(
            (&a.name, &a.view, a.display_window, a.data_window),
            (&b.name, &b.view, b.display_window, b.data_window),
            "{name}"
        );
        let written: Vec<&str> = b.channels.iter().map(|c| c.name.as_str()).collect();
        let mut want_names: Vec<&str> = found.channels.iter().map(String::as_str).collect();
        want_names.sort_unstable();
        assert_eq!(written, want_names, "{name}");
        for (x, y) in b.channels.iter().zip(&want_names) {
            assert_eq!(Some(x.sample), source.sample(y), "{name}: {y}");
        }
        let raw_a = exr::read_channels(&path, &info, found.part, &found.channels).unwrap();
        let raw_b = exr::read_channels(&out, &back, 0, &found.channels).unwrap();
        for (x, y) in raw_a.iter().zip(&raw_b) {
            assert!(x.bits == y.bits, "{name}: channel {} differs", x.name);
        }
        let kept = |p: &exr::Part| -> Vec<(String, String)> {
            p.attributes
                .iter()
                .filter(|(k, _)| !["preview", "tiles"].contains(&k.as_str()))
                .cloned()
                .collect()
        };
        assert_eq!(kept(a), kept(b), "{name}");
        let expect_note = a.attributes.iter().any(|(k, _)| k == "tiles");
        assert_eq!(!notes.is_empty(), expect_note, "{name}: {notes:?}");
    }
}
