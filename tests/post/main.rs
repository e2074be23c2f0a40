//! Post nodes against their CPU references, image files and metrics.
//!
//! One test binary per area (`cargo test --test post`); one module per subject
//! (`cargo test --test post analysis::`).

#[path = "../common/mod.rs"]
mod common;

mod analysis;
mod blur_bloom;
mod combine;
mod effects;
mod gpu_nodes;
mod grade;
mod image_io;
mod lut;
mod metrics;
mod ocio;
mod resize;
mod vignette;
mod working_space;
