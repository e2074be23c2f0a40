//! Footage: image files as compositors read them.
//!
//! - [`exr`]: every part, layer and channel of an OpenEXR file, its windows, colour
//!   primaries and attributes; layers read into the display window; luminance/chroma
//!   images reconstructed as OpenEXR's `RgbaInputFile` does.
//! - [`subsampled`]: scan-line parts whose channels are subsampled (luminance/chroma
//!   images), read through the `exr` crate's block layer, which its image layer refuses.
//! - [`yca`]: the luminance/chroma reconstruction itself.
//! - [`color`]: colour primaries (`chromaticities`) converted to the working space,
//!   linear Rec. 709.
//! - [`sequence`]: frame numbers in paths (`####`, `%04d`, `$F4`) and frame ranges
//!   (`1-100x2`).
//! - [`testing`]: for the tests held to OpenEXR's reader: where its sample images are, a
//!   channel's hash.
//!
//! Nothing here touches a GPU.

pub mod color;
pub mod exr;
pub mod sequence;
pub mod subsampled;
pub mod testing;
pub mod yca;
