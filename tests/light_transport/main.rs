//! Light transport, statistically: every BSDF lobe, media, the sampler, MIS strategies,
//! and stability on stiff and extreme cases.
//!
//! One test binary per area (`cargo test --test light_transport`); one module per subject
//! (`cargo test --test light_transport bsdf_lobes::`).

#[path = "../common/mod.rs"]
mod common;

mod bsdf_lobes;
mod layers;
mod media;
mod rough_diffuse;
mod sampler;
mod specular_color;
mod stability;
mod strategies;
