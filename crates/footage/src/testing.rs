//! For tests and scripts that hold lumagraph's reading and writing to OpenEXR's own: where
//! the OpenEXR project's sample images are, and a channel's hash as the reference
//! (`tests/exr/openexr_reference.json`, `scripts/exr/reference.py`) stores it.

use std::path::{Path, PathBuf};

use sha2::{Digest as _, Sha256};

use crate::exr::{RawChannel, SampleKind};

/// The OpenEXR sample images: `LUMAGRAPH_OPENEXR_IMAGES`, else `default` (the caller's
/// `../shared/assets/openexr-images`), made absolute. Without them, `None` after saying
/// the test is skipped, except where `CI` is set, where it panics naming the folder.
///
/// # Panics
/// Under CI, when the folder is not there.
pub fn openexr_images(default: &Path) -> Option<PathBuf> {
    let dir = std::env::var_os("LUMAGRAPH_OPENEXR_IMAGES")
        .map_or_else(|| default.to_path_buf(), PathBuf::from);
    if dir.is_dir() {
        return Some(dir.canonicalize().unwrap_or(dir));
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "the OpenEXR sample images are not at {} (set LUMAGRAPH_OPENEXR_IMAGES)",
        dir.display()
    );
    eprintln!("skipped: no OpenEXR sample images at {}", dir.display());
    None
}

/// The SHA-256 of a channel's samples as stored (little-endian; halves as 16 bits), in
/// hex: what the reference holds per channel.
pub fn channel_sha256(channel: &RawChannel) -> String {
    let mut hash = Sha256::new();
    for &b in &channel.bits {
        match channel.sample {
            SampleKind::Half => hash.update(u16::try_from(b).unwrap_or(u16::MAX).to_le_bytes()),
            SampleKind::Float | SampleKind::Uint => hash.update(b.to_le_bytes()),
        }
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}
