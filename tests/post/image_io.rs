//! Image files in and out, without a GPU: every input format decodes to the right linear
//! values, and every write is atomic.

use lumagraph::render::cpu::{self, Image};
use lumagraph::render::image_io;

fn ramp() -> Image {
    let mut img = Image::filled(16, 8, [0.0, 0.0, 0.0, 1.0]);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        let x = i as f32 / 8.0;
        *p = [x, x * 0.5 + 0.01, 100.0 - x, 1.0];
    }
    img
}

#[test]
fn exr_round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.exr");
    image_io::save(&path, &ramp(), true).unwrap();
    assert_eq!(image_io::load(&path).unwrap(), ramp());
    let dims = image_io::dimensions(&path).unwrap();
    assert_eq!((dims.width, dims.height), (16, 8));
}

#[test]
fn radiance_hdr_is_linear() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.hdr");
    let img = ramp();
    let rgb: Vec<image::Rgb<f32>> = img
        .pixels
        .iter()
        .map(|p| image::Rgb([p[0], p[1], p[2]]))
        .collect();
    let file = std::fs::File::create(&path).unwrap();
    image::codecs::hdr::HdrEncoder::new(file)
        .encode(&rgb, 16, 8)
        .unwrap();
    let loaded = image_io::load(&path).unwrap();
    // RGBE keeps 8 bits of mantissa per channel relative to the largest channel
    for (a, b) in loaded.pixels.iter().zip(&img.pixels) {
        let scale = b[0].max(b[1]).max(b[2]);
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= scale / 128.0, "{a:?} vs {b:?}");
        }
        assert!((a[3] - 1.0).abs() < 1e-6);
    }
}

#[test]
fn jpeg_is_decoded_from_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grey.jpg");
    let grey = image::RgbImage::from_pixel(16, 16, image::Rgb([128, 128, 128]));
    grey.save(&path).unwrap();
    let loaded = image_io::load(&path).unwrap();
    let expected = cpu::srgb_decode(128.0 / 255.0);
    for p in &loaded.pixels {
        assert!((p[0] - expected).abs() < 0.01, "{p:?} vs {expected}");
    }
}

#[test]
fn unknown_extensions_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.tiff");
    std::fs::write(&path, b"II*").unwrap();
    let e = image_io::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("a.tiff") && e.contains("unsupported image extension"),
        "{e}"
    );
    let e = image_io::save(&dir.path().join("b.bmp"), &ramp(), true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("b.bmp") && e.contains("use .png or .exr"), "{e}");
    assert!(!dir.path().join("b.bmp").exists());
}

#[test]
fn failed_write_keeps_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keep.png");
    std::fs::write(&path, b"old").unwrap();
    // an image whose pixel count does not match its size fails to encode
    let broken = Image {
        width: 4,
        height: 4,
        pixels: vec![[0.0; 4]; 3],
    };
    assert!(image_io::save(&path, &broken, true).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "temporary file left behind"
    );
}
