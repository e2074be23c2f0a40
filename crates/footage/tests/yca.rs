//! Luminance/chroma EXR files: reading subsampled channels ([`subsampled`]) and
//! reconstructing RGBA ([`yca`]), checked against the `OpenEXR` test images in the shared
//! assets and against values `OpenEXR` itself produced.
//!
//! The expected pixels below were measured with `OpenEXR` 3.1.5 (Debian's `libopenexr-dev`):
//! a throwaway C++ program opened each file with `Imf::RgbaInputFile`, read the whole
//! data window into an `Imf::Rgba` frame buffer and printed the half bits of a few pixels.
//! On the same files, and on 240 more written by `OpenEXR`'s `RgbaOutputFile` in every
//! compression (none, RLE, ZIPS, ZIP, PIZ, PXR24, B44, B44A, DWAA, DWAB), with shifted
//! and cropped data windows, with and without chroma and alpha, every value of every
//! pixel matched bit for bit, and so did the raw `Y`/`RY`/`BY`/`A` planes as
//! `Imf::InputFile` reads them.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use exr::prelude::{AnyChannels, FlatSamples, ReadChannels, ReadLayers};
use half::f16;
use lumagraph_footage::subsampled::{self, Error, Samples};
use lumagraph_footage::yca::{self, YcaInput};

/// The `OpenEXR` test images; fails when they are missing unless
/// `LUMAGRAPH_ALLOW_NO_SHARED=1`, in which case the calling test returns early.
fn assets() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/openexr-images");
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var("LUMAGRAPH_ALLOW_NO_SHARED").is_ok_and(|v| v == "1"),
        "the OpenEXR test images are missing: expected {}; set LUMAGRAPH_ALLOW_NO_SHARED=1 to skip the tests that need them",
        dir.display()
    );
    None
}

fn channel<'a>(samples: &'a [Samples], name: &str) -> Option<&'a Samples> {
    samples.iter().find(|s| s.name == name)
}

fn floats(s: &Samples) -> Vec<f32> {
    s.bits
        .iter()
        .map(|&b| f16::from_bits(b as u16).to_f32())
        .collect()
}

/// `to_rgba` on a part read with [`subsampled::read_part`], with the file's primaries.
fn rgba_of(path: &Path) -> (usize, Vec<[f32; 4]>) {
    let header = &subsampled::read_headers(path).unwrap()[0];
    let samples = subsampled::read_part(path, 0).unwrap();
    let plane = |name| channel(&samples, name).map(floats);
    let (y, ry, by, a) = (plane("Y").unwrap(), plane("RY"), plane("BY"), plane("A"));
    let c = header.shared_attributes.chromaticities;
    let weights = yca::luminance_weights(c.map(|c| {
        [
            c.red.0, c.red.1, c.green.0, c.green.1, c.blue.0, c.blue.1, c.white.0, c.white.1,
        ]
    }));
    let window = header.data_window();
    let input = YcaInput {
        width: window.size.0,
        height: window.size.1,
        origin: (window.position.0, window.position.1),
        y: &y,
        ry: ry.as_deref(),
        by: by.as_deref(),
        a: a.as_deref(),
    };
    (window.size.0, yca::to_rgba(&input, weights).unwrap())
}

/// Checks pixels `(x, y, [r, g, b, a] half bits)` measured with `OpenEXR`.
fn check_pixels(
    file: &str,
    width: usize,
    rgba: &[[f32; 4]],
    expected: &[(usize, usize, [u16; 4])],
) {
    for &(x, y, bits) in expected {
        let got = rgba[y * width + x].map(|v| f16::from_f32(v).to_bits());
        assert_eq!(
            got, bits,
            "{file}: pixel ({x}, {y}) differs from OpenEXR's RgbaInputFile"
        );
    }
}

#[test]
fn luminance_chroma_files_read_with_their_subsampling() {
    let Some(dir) = assets() else { return };
    for (file, (width, height), compression) in [
        ("LuminanceChroma/Flowers.exr", (784, 734), "B44"),
        ("Chromaticities/XYZ_YC.exr", (610, 406), "PIZ"),
        ("Chromaticities/Rec709_YC.exr", (610, 406), "PIZ"),
    ] {
        let samples = subsampled::read_part(&dir.join(file), 0)
            .unwrap_or_else(|e| panic!("{file} ({compression}): {e}"));
        let names: Vec<&str> = samples.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names[names.len() - 3..], ["BY", "RY", "Y"], "{file}");
        for s in &samples {
            let (sx, sy) = if s.name.ends_with('Y') && s.name != "Y" {
                (2, 2)
            } else {
                (1, 1)
            };
            assert_eq!(s.sampling, (sx, sy), "{file} {}", s.name);
            assert_eq!(
                (s.width, s.height),
                (width / sx, height / sy),
                "{file} {}",
                s.name
            );
            assert_eq!(s.bits.len(), s.width * s.height, "{file} {}", s.name);
        }
    }
}

#[test]
fn subsampled_reader_matches_the_exr_crate_where_it_reads() {
    let Some(dir) = assets() else { return };
    let mut compared = 0;
    for folder in [
        "TestImages",
        "Chromaticities",
        "DisplayWindow",
        "Beachball",
        "MultiView",
        "LuminanceChroma",
    ] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join(folder))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.retain(|p| p.extension().is_some_and(|e| e == "exr"));
        files.sort();
        for path in files {
            let Ok(image) = exr::prelude::read()
                .no_deep_data()
                .largest_resolution_level()
                .all_channels()
                .all_layers()
                .all_attributes()
                .from_file(&path)
            else {
                continue; // subsampled: the crate refuses it
            };
            for (part, layer) in image.layer_data.iter().enumerate() {
                let mine = match subsampled::read_part(&path, part) {
                    Ok(mine) => mine,
                    Err(Error::Unsupported { .. }) => continue, // tiled
                    Err(e) => panic!("{}: part {part}: {e}", path.display()),
                };
                let AnyChannels { list } = &layer.channel_data;
                assert_eq!(mine.len(), list.len(), "{}", path.display());
                for (m, theirs) in mine.iter().zip(list) {
                    let bits: Vec<u32> = match &theirs.sample_data {
                        FlatSamples::F16(v) => v.iter().map(|h| u32::from(h.to_bits())).collect(),
                        FlatSamples::F32(v) => v.iter().map(|f| f.to_bits()).collect(),
                        FlatSamples::U32(v) => v.clone(),
                    };
                    assert_eq!(m.name, theirs.name.to_string(), "{}", path.display());
                    assert!(
                        m.bits == bits,
                        "{} part {part} channel {}: samples differ",
                        path.display(),
                        m.name
                    );
                }
                compared += 1;
            }
        }
    }
    assert!(compared >= 30, "only {compared} parts compared");
}

#[test]
fn damaged_files_give_errors_not_panics() {
    let Some(dir) = assets() else { return };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join("Damaged"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.retain(|p| p.extension().is_none_or(|e| e != "rst"));
    files.sort();
    assert!(files.len() >= 20, "{} damaged files", files.len());
    for path in files {
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let parts = subsampled::read_headers(&path).map_or(1, |h| h.len());
            (0..parts)
                .map(|part| subsampled::read_part(&path, part))
                .collect::<Vec<_>>()
        }));
        let results =
            outcome.unwrap_or_else(|_| panic!("{} made the reader panic", path.display()));
        for result in results {
            assert!(result.is_err(), "{} read as if undamaged", path.display());
        }
    }
}

/// Truncated and byte-damaged copies of files in every compression the assets hold (B44,
/// PIZ, PXR24, ZIP, ZIPS; one multi-part): the reader may read them (damage to pixel
/// bytes can decode to other pixels) but must not panic.
#[test]
fn corrupted_copies_never_panic() {
    let Some(dir) = assets() else { return };
    let scratch =
        std::env::temp_dir().join(format!("lumagraph-footage-yca-{}.exr", std::process::id()));
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for file in [
        "LuminanceChroma/Flowers.exr",
        "Chromaticities/Rec709_YC.exr",
        "TestImages/GrayRampsDiagonal.exr",
        "TestImages/WideColorGamut.exr",
        "Beachball/multipart.0001.exr",
    ] {
        let bytes = std::fs::read(dir.join(file)).unwrap();
        for trial in 0..24 {
            let mut damaged = bytes.clone();
            if trial < 6 {
                damaged.truncate(bytes.len() * (trial + 1) / 7);
            } else {
                // A third of the damage lands in the first KiB: headers and offset tables.
                let span = if trial % 3 == 0 {
                    1024.min(bytes.len())
                } else {
                    bytes.len()
                };
                for _ in 0..1 + next() % 8 {
                    let at = (next() % span as u64) as usize;
                    damaged[at] = next() as u8;
                }
            }
            std::fs::write(&scratch, &damaged).unwrap();
            let outcome = catch_unwind(|| {
                let parts = subsampled::read_headers(&scratch).map_or(1, |h| h.len());
                for part in 0..parts {
                    let _ = subsampled::read_part(&scratch, part);
                }
            });
            assert!(
                outcome.is_ok(),
                "{file}, damage {trial}: the reader panicked"
            );
        }
    }
    std::fs::remove_file(&scratch).unwrap();
}

#[test]
fn a_missing_part_is_an_error() {
    let Some(dir) = assets() else { return };
    let e = subsampled::read_part(&dir.join("LuminanceChroma/Flowers.exr"), 3).unwrap_err();
    assert!(matches!(e, Error::NoSuchPart { part: 3, count: 1 }), "{e}");
    let e =
        subsampled::read_part(&dir.join("MultiResolution/ColorCodedLevels.exr"), 0).unwrap_err();
    assert!(matches!(e, Error::Unsupported { .. }), "{e}");
}

#[test]
fn flowers_matches_openexr() {
    let Some(dir) = assets() else { return };
    let (width, rgba) = rgba_of(&dir.join("LuminanceChroma/Flowers.exr"));
    check_pixels(
        "Flowers.exr",
        width,
        &rgba,
        &[
            (0, 0, [0x3c0f, 0x3c1b, 0x40d9, 0x3c00]),
            (783, 0, [0x3809, 0x37ca, 0x3a3c, 0x3c00]),
            (0, 733, [0x3c0d, 0x3c04, 0x3f29, 0x3c00]),
            (783, 733, [0x3c96, 0x3c8a, 0x4165, 0x3c00]),
            (1, 1, [0x3c39, 0x3c2d, 0x40ea, 0x3c00]),
            (393, 368, [0x316e, 0x30fe, 0x37bf, 0x3c00]),
            (782, 732, [0x3c7b, 0x3c76, 0x4149, 0x3c00]),
            // Desaturated by `fixSaturation`.
            (757, 0, [0x1ade, 0x31f2, 0x3ddb, 0x3c00]),
        ],
    );
}

#[test]
fn xyz_yc_matches_openexr() {
    let Some(dir) = assets() else { return };
    let (width, rgba) = rgba_of(&dir.join("Chromaticities/XYZ_YC.exr"));
    check_pixels(
        "XYZ_YC.exr",
        width,
        &rgba,
        &[
            (0, 0, [0x3462, 0x3580, 0x30fc, 0x3c00]),
            (609, 0, [0x31d2, 0x3330, 0x2f05, 0x3c00]),
            (0, 405, [0x3611, 0x3738, 0x3346, 0x3c00]),
            (609, 405, [0x2a12, 0x2b70, 0x2863, 0x3c00]),
            (1, 1, [0x34c0, 0x35f8, 0x3187, 0x3c00]),
            (306, 204, [0x3c79, 0x3c28, 0x39a6, 0x3c00]),
            (608, 404, [0x292e, 0x2a58, 0x276f, 0x3c00]),
            (329, 199, [0x3e13, 0x3c98, 0x2a96, 0x3c00]),
        ],
    );
}

#[test]
fn rec709_yc_matches_openexr() {
    let Some(dir) = assets() else { return };
    let (width, rgba) = rgba_of(&dir.join("Chromaticities/Rec709_YC.exr"));
    check_pixels(
        "Rec709_YC.exr",
        width,
        &rgba,
        &[
            (0, 0, [0x347e, 0x362c, 0x2f38, 0x3c00]),
            (609, 0, [0x3226, 0x33f8, 0x2cff, 0x3c00]),
            (0, 405, [0x36b9, 0x37d3, 0x3158, 0x3c00]),
            (609, 405, [0x2a17, 0x2c20, 0x26c1, 0x3c00]),
            (1, 1, [0x34d7, 0x36b5, 0x2ff9, 0x3c00]),
            (306, 204, [0x3eb0, 0x3b29, 0x38ce, 0x3c00]),
            (608, 404, [0x2934, 0x2b08, 0x25c0, 0x3c00]),
            (553, 56, [0x381c, 0x3955, 0x1a0e, 0x3c00]),
        ],
    );
}

/// Garden.exr is tiled and luminance-only (`Y` alone), so the `exr` crate reads it; `OpenEXR`
/// gives `R = G = B = Y`.
#[test]
fn luminance_only_garden_matches_openexr() {
    let Some(dir) = assets() else { return };
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(dir.join("LuminanceChroma/Garden.exr"))
        .unwrap();
    let list = &image.layer_data.channel_data.list;
    assert_eq!(list.len(), 1);
    let y: Vec<f32> = match &list[0].sample_data {
        FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
        other => panic!("Garden.exr's Y is not half: {other:?}"),
    };
    let (width, height) = (image.layer_data.size.0, image.layer_data.size.1);
    let input = YcaInput {
        width,
        height,
        origin: (0, 0),
        y: &y,
        ry: None,
        by: None,
        a: None,
    };
    let rgba = yca::to_rgba(&input, yca::luminance_weights(None)).unwrap();
    check_pixels(
        "Garden.exr",
        width,
        &rgba,
        &[
            (0, 0, [0x255e, 0x255e, 0x255e, 0x3c00]),
            (873, 0, [0x216e, 0x216e, 0x216e, 0x3c00]),
            (0, 492, [0x22d1, 0x22d1, 0x22d1, 0x3c00]),
            (873, 492, [0x2d06, 0x2d06, 0x2d06, 0x3c00]),
            (438, 247, [0x4421, 0x4421, 0x4421, 0x3c00]),
        ],
    );
}

#[test]
fn weights_are_openexrs() {
    // Bits of `RgbaYca::computeYw` in OpenEXR 3.1.5 for its default (Rec. 709) primaries.
    let rec709 = yca::luminance_weights(None);
    assert_eq!(
        rec709.map(f32::to_bits),
        [0x3e59_be0a, 0x3f37_154c, 0x3d93_d98d]
    );
    for (w, expected) in rec709.iter().zip([0.2126, 0.7152, 0.0722]) {
        assert!((w - expected).abs() < 1e-4, "{rec709:?}");
    }
    assert_eq!(yca::luminance_weights(Some(yca::REC709)), rec709);
    // XYZ_YC.exr's primaries (X, Y and Z themselves): luminance is Y.
    let xyz = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0 / 3.0, 1.0 / 3.0];
    assert_eq!(yca::luminance_weights(Some(xyz)), [0.0, 1.0, 0.0]);
    // Degenerate primaries (OpenEXR throws) fall back to Rec. 709.
    assert_eq!(yca::luminance_weights(Some([0.3; 8])), rec709);
    assert_eq!(
        yca::luminance_weights(Some([0.6, 0.3, 0.3, 0.6, 0.15, 0.06, 0.3, 0.0])),
        rec709
    );
}

#[test]
fn constant_images_come_back_constant() {
    let (w, h) = (38, 30);
    let weights = yca::luminance_weights(None);
    // Grey: no chroma, so R = G = B = Y exactly.
    let y = vec![0.73; w * h];
    let zero = vec![0.0; (w / 2) * (h / 2)];
    let input = YcaInput {
        width: w,
        height: h,
        origin: (-4, 6),
        y: &y,
        ry: Some(&zero),
        by: Some(&zero),
        a: None,
    };
    let grey = f16::from_f32(0.73).to_f32();
    assert!(
        yca::to_rgba(&input, weights)
            .unwrap()
            .iter()
            .all(|p| *p == [grey, grey, grey, 1.0])
    );
    // A colour: every pixel the same, close to the colour encoded.
    let (r, g, b) = (0.8_f32, 0.5_f32, 0.2_f32);
    let luma = r * weights[0] + g * weights[1] + b * weights[2];
    let y = vec![luma; w * h];
    let ry = vec![(r - luma) / luma; (w / 2) * (h / 2)];
    let by = vec![(b - luma) / luma; (w / 2) * (h / 2)];
    let a = vec![0.5; w * h];
    let input = YcaInput {
        width: w,
        height: h,
        origin: (0, 0),
        y: &y,
        ry: Some(&ry),
        by: Some(&by),
        a: Some(&a),
    };
    let rgba = yca::to_rgba(&input, weights).unwrap();
    assert!(rgba.iter().all(|p| *p == rgba[0]), "not constant");
    for (got, want) in rgba[0].iter().zip([r, g, b, 0.5]) {
        assert!((got - want).abs() < 4e-3, "{:?}", rgba[0]);
    }
}

#[test]
fn bad_planes_are_errors() {
    let weights = yca::luminance_weights(None);
    let y = vec![0.5; 16];
    let c = vec![0.0; 4];
    let short = vec![0.0; 3];
    let input = |width, height, origin, ry| YcaInput {
        width,
        height,
        origin,
        y: &y,
        ry,
        by: None,
        a: None,
    };
    assert!(yca::to_rgba(&input(4, 4, (0, 0), Some(&c)), weights).is_ok());
    assert!(matches!(
        yca::to_rgba(&input(4, 4, (0, 0), Some(&short)), weights),
        Err(yca::Error::Length { .. })
    ));
    assert!(matches!(
        yca::to_rgba(&input(4, 4, (1, 0), Some(&c)), weights),
        Err(yca::Error::OddWindow { .. })
    ));
    assert!(yca::to_rgba(&input(2, 8, (0, 0), Some(&c)), weights).is_ok());
    assert!(matches!(
        yca::to_rgba(&input(4, 5, (0, 0), None), weights),
        Err(yca::Error::Length { .. })
    ));
    // Luminance only may be odd-sized and odd-placed.
    let odd = vec![0.25; 15];
    let input = YcaInput {
        width: 5,
        height: 3,
        origin: (1, 1),
        y: &odd,
        ry: None,
        by: None,
        a: None,
    };
    assert!(
        yca::to_rgba(&input, weights)
            .unwrap()
            .iter()
            .all(|p| *p == [0.25, 0.25, 0.25, 1.0])
    );
}
