//! Colour management through OpenColorIO configs, with the pure-Rust `ocio` crate (a port
//! of OpenColorIO 2.5, checked against PyOpenColorIO; MIT and BSD-3-Clause).
//!
//! A [`ColorConfig`] is a config: one of OpenColorIO's built-in ones (by default
//! [`DEFAULT_CONFIG`], the CG config with ACES 2.0; `ocio://studio-config-latest`, or any
//! full name), a
//! `config.ocio` file, or the one the `OCIO` environment variable names, as Blender and Nuke
//! read it. Its [`Processor`]s convert between colour spaces or to a display and view (with
//! looks), on the CPU ([`Processor::apply`]) and on the GPU ([`Processor::gpu_program`]: a
//! WGSL compute shader with its LUT textures and uniforms).
//!
//! lumagraph's working space is scene-linear Rec. 709 (sRGB primaries, D65):
//! [`ColorConfig::working_space`] finds it in a config.

mod config;
mod gpu;

pub use config::{
    BLENDER, ColorConfig, DEFAULT_CONFIG, Error, Result, WORKING_SPACE_NAMES, blender_config,
};
pub use gpu::{GpuProgram, LutTexture, Slot};

use std::sync::Arc;

/// A colour conversion of a config: on the CPU and as a GPU program.
#[derive(Clone)]
pub struct Processor {
    processor: ocio::Processor,
    cpu: Arc<ocio::CpuProcessor>,
    /// What it converts, for messages (`"ACEScg" → "Linear Rec.709 (sRGB)"`).
    pub description: String,
}

impl std::fmt::Debug for Processor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Processor")
            .field("description", &self.description)
            .finish_non_exhaustive()
    }
}

impl Processor {
    fn new(processor: ocio::Processor, description: String) -> Self {
        let cpu = Arc::new(processor.default_cpu_processor());
        Self {
            processor,
            cpu,
            description,
        }
    }

    /// Converts interleaved RGBA values in place (alpha is left as it is).
    pub fn apply(&self, rgba: &mut [f32]) {
        self.cpu.apply_rgba_slice(rgba);
    }

    /// Converts one RGB value.
    pub fn apply_rgb(&self, rgb: [f32; 3]) -> [f32; 3] {
        let mut v = rgb;
        self.cpu.apply_rgb(&mut v);
        v
    }

    /// Whether it leaves every value as it is.
    pub fn is_no_op(&self) -> bool {
        self.processor.is_no_op()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_config_has_the_working_space_and_validating_wgsl() {
        let c = ColorConfig::load(DEFAULT_CONFIG, std::path::Path::new(".")).unwrap();
        assert_eq!(c.working_space(), "Linear Rec.709 (sRGB)");
        let p = c.processor("ACEScg", "").unwrap();
        let white = p.apply_rgb([1.0, 1.0, 1.0]);
        assert!(white.iter().all(|v| (v - 1.0).abs() < 1e-3), "{white:?}");
        for (from, to) in [("ACEScg", ""), ("sRGB Encoded Rec.709 (sRGB)", "")] {
            let program = c
                .processor(from, to)
                .unwrap()
                .gpu_program("rgba32float")
                .unwrap();
            naga::front::wgsl::parse_str(&program.wgsl)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&program.wgsl)));
        }
        let (display, view) = c.default_display_view();
        let program = c
            .display_processor("", &display, &view, "")
            .unwrap()
            .gpu_program("rgba8unorm")
            .unwrap();
        naga::front::wgsl::parse_str(&program.wgsl)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&program.wgsl)));
        assert!(!program.luts.is_empty() || program.uniforms.is_some() || program.slots.len() == 2);
    }

    #[test]
    fn unknown_names_list_what_the_config_has() {
        let c = ColorConfig::load(DEFAULT_CONFIG, std::path::Path::new(".")).unwrap();
        let e = c.processor("Nope", "").unwrap_err().0;
        assert!(
            e.contains("no colour space \"Nope\"") && e.contains("ACEScg"),
            "{e}"
        );
        let e = c.display_processor("", "Nope", "", "").unwrap_err().0;
        assert!(e.contains("no display") && e.contains("sRGB"), "{e}");
        let e = ColorConfig::load("ocio://nope", std::path::Path::new("."))
            .unwrap_err()
            .0;
        assert!(e.contains("ocio://nope"), "{e}");
        let e = ColorConfig::load("missing/config.ocio", std::path::Path::new("."))
            .unwrap_err()
            .0;
        assert!(e.contains("no file"), "{e}");
    }
}
