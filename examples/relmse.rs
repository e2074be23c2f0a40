//! relMSE of an image against a reference (`lumagraph::render::metrics::relmse`: the mean
//! over pixels and RGB of (x − ref)² / (ref² + 0.01)), as `docs/benchmarks.md` measures
//! renders against a high-spp reference. Run with
//! `cargo run --example relmse -- IMAGE.exr REFERENCE.exr`.

use std::path::Path;

use lumagraph::render::{image_io, metrics};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [image, reference] = args.as_slice() else {
        anyhow::bail!("usage: relmse IMAGE REFERENCE (EXR or any image lumagraph reads)");
    };
    let image = image_io::load(Path::new(image))?;
    let reference = image_io::load(Path::new(reference))?;
    anyhow::ensure!(
        (image.width, image.height) == (reference.width, reference.height),
        "the image is {}x{}, the reference {}x{}",
        image.width,
        image.height,
        reference.width,
        reference.height
    );
    println!("relMSE {:.4e}", metrics::relmse(&image, &reference));
    Ok(())
}
