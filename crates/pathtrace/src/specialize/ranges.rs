//! What a material can do over every texel of its textures: the ranges of its factors once
//! its textures are applied, from which the decisions ([`super::features`]) leave out a lobe
//! only where no material can produce it (a metallic-roughness texture can lower a metallic
//! factor of 1 to 0 per texel).

use lumagraph_scene::{GpuMaterial, GpuScene};

/// The range of values a material's factor can take once its texture is applied: the
/// factor times the texture channel's smallest and largest texel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Range {
    pub(super) min: f32,
    pub(super) max: f32,
}

impl Range {
    fn of(factor: f32) -> Self {
        Self {
            min: factor,
            max: factor,
        }
    }

    /// `self` times a texture channel whose texels span `[lo, hi]` (texel bytes over 255).
    fn times(self, lo: f32, hi: f32) -> Self {
        let (a, b) = (self.min * lo, self.max * hi);
        Self {
            min: a.min(b).min(self.min * hi).min(self.max * lo),
            max: a.max(b).max(self.min * hi).max(self.max * lo),
        }
    }
}

/// What a material can do, over every texel of its textures.
#[derive(Clone, Copy, Debug)]
pub(super) struct MaterialRanges {
    pub(super) metallic: Range,
    pub(super) transmission: Range,
    pub(super) specular: Range,
    /// Opacity times the base colour texture's alpha.
    pub(super) opacity: Range,
}

/// The smallest and largest value of each channel (RGBA, over 255) of texture `id` in the
/// scene's packed textures; the full range [0, 1] where it is unknown.
fn channel_range(scene: &GpuScene, id: u32, channel: usize) -> (f32, f32) {
    match scene.texture_ranges.get(id as usize) {
        Some(r) if id != 0xFFFF => (
            f32::from(r.min[channel]) / 255.0,
            f32::from(r.max[channel]) / 255.0,
        ),
        _ => (0.0, 1.0),
    }
}

pub(super) fn material_ranges(scene: &GpuScene, index: usize, m: &GpuMaterial) -> MaterialRanges {
    let lo = |packed: u32| packed & 0xFFFF;
    let hi = |packed: u32| packed >> 16;
    let textured = |factor: f32, id: u32, channel: usize| {
        if id == 0xFFFF {
            Range::of(factor)
        } else {
            let (a, b) = channel_range(scene, id, channel);
            Range::of(factor).times(a, b)
        }
    };
    // The specular colour (factor and texture) colours F0 only: the grazing reflection of a
    // material with specular > 0 is there whatever the colour.
    let specular = textured(m.specular, hi(m.tex_transmission_specular), 3);
    let vertex_alpha =
        |i: usize| f32::from(scene.vertex_alpha_min.get(i).copied().unwrap_or(0)) / 255.0;
    MaterialRanges {
        opacity: textured(m.opacity, lo(m.tex_base_mr), 3).times(vertex_alpha(index), 1.0),
        metallic: textured(m.metallic, hi(m.tex_base_mr), 2),
        transmission: textured(m.transmission, lo(m.tex_transmission_specular), 0),
        specular,
    }
}
