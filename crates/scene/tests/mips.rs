//! Texture mip chains (GPU-free): every level against a box filter computed here from
//! level 0, in linear light for colour; the levels' places in the atlas; and the CPU mirror
//! of the shader's trilinear lookup (`TextureAtlas::sample_lod`).

use glam::{Vec2, Vec4};
use lumagraph_scene::texture::{AtlasLimits, TEX_MIPS_SHIFT, srgb_decode, srgb_encode};
use lumagraph_scene::{
    Texture, TextureAtlas, UvTransform, Wrap, fit_textures_with, pack_atlas, pack_atlas_with,
};

/// A texture of pseudo-random texels (a fixed LCG), `nearest` as given.
fn noise(width: u32, height: u32, seed: u32, nearest: bool) -> Texture {
    let mut s = seed.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let mut next = || {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (s >> 24) as u8
    };
    Texture {
        name: format!("noise{seed}"),
        width,
        height,
        texels: (0..width * height)
            .map(|_| [next(), next(), next(), next()])
            .collect(),
        wrap: [Wrap::Repeat, Wrap::Repeat],
        nearest,
        uv_set: 0,
        transform: UvTransform::IDENTITY,
    }
}

/// The texel (bytes) at `(x, y)` of level `level` of texture `id` in `atlas`.
fn level_texel(atlas: &TextureAtlas, id: u32, level: u32, x: u32, y: u32) -> [u8; 4] {
    let d = atlas.level_place(id, level);
    let page = atlas.page_size;
    assert!(x < (d[2] & 0xFFFF) && y < d[2] >> 16);
    let at = d[1] * page * page + ((d[0] >> 16) + y) * page + (d[0] & 0xFFFF) + x;
    atlas.texels[at as usize].to_le_bytes()
}

/// The reference: level `k`'s texel `(x, y)` of a power-of-two texture is the mean of the
/// 2^k × 2^k texels of level 0 under it (rows or columns past the image's edge, once a side
/// is down to 1, clamped: each level's halving repeats the last one), averaged in linear
/// light when `srgb` (alpha always linear), then encoded and rounded.
fn box_mean(t: &Texture, k: u32, x: u32, y: u32, srgb: bool) -> [f64; 4] {
    let n = 1u32 << k;
    let (x0, y0) = (x * n, y * n);
    let (x1, y1) = ((x0 + n).min(t.width), (y0 + n).min(t.height));
    let mut sum = [0.0_f64; 4];
    for yy in y0..y1 {
        for xx in x0..x1 {
            let p = t.texels[(yy * t.width + xx) as usize];
            for c in 0..4 {
                let v = f32::from(p[c]) / 255.0;
                sum[c] += f64::from(if srgb && c < 3 { srgb_decode(v) } else { v });
            }
        }
    }
    let count = f64::from((x1 - x0) * (y1 - y0));
    std::array::from_fn(|c| {
        let m = sum[c] / count;
        255.0
            * if srgb && c < 3 {
                f64::from(srgb_encode(m as f32))
            } else {
                m
            }
    })
}

/// Every level of a 64×32 colour texture and of a 16×16 data texture is the box mean of
/// level 0 under each texel, within rounding (half a byte of the exact mean, plus float
/// error: 0.51).
#[test]
fn levels_are_box_filtered_means_of_level_zero_in_linear_light() {
    let colour = noise(64, 32, 1, false);
    let data = noise(16, 16, 2, false);
    let atlas = pack_atlas_with(&[colour.clone(), data.clone()], Some(&[true, false]));
    for (id, t, srgb) in [(0u32, &colour, true), (1, &data, false)] {
        let levels = atlas.mip_levels(id);
        let expected = t.width.max(t.height).ilog2();
        assert_eq!(levels, expected, "texture {id}: levels below level 0");
        let mut worst = 0.0_f64;
        for k in 1..=levels {
            let d = atlas.level_place(id, k);
            let (w, h) = (d[2] & 0xFFFF, d[2] >> 16);
            assert_eq!(
                (w, h),
                ((t.width >> k).max(1), (t.height >> k).max(1)),
                "texture {id} level {k}'s size"
            );
            assert_eq!(
                d[3] & 0xFF,
                t.flags(),
                "texture {id} level {k} wraps as its texture"
            );
            for y in 0..h {
                for x in 0..w {
                    let got = level_texel(&atlas, id, k, x, y);
                    let want = box_mean(t, k, x, y, srgb);
                    for c in 0..4 {
                        worst = worst.max((f64::from(got[c]) - want[c]).abs());
                    }
                }
            }
        }
        assert!(worst <= 0.51, "texture {id}: worst texel off by {worst}");
    }
}

/// Colour is averaged in linear light: a black and white checker's 1×1 level is 50 % grey
/// in linear light (byte 188), not byte 128 (the sRGB bytes' mean); data (and alpha) is
/// averaged as stored.
#[test]
fn colour_levels_average_light_not_bytes() {
    let px = |v: u8| [v, v, v, v];
    let checker = Texture {
        name: "checker".into(),
        width: 2,
        height: 2,
        texels: vec![px(0), px(255), px(255), px(0)].into(),
        wrap: [Wrap::Repeat; 2],
        nearest: false,
        uv_set: 0,
        transform: UvTransform::IDENTITY,
    };
    let colour = checker.mip_chain(true);
    let data = checker.mip_chain(false);
    assert_eq!(colour.len(), 1);
    assert_eq!(colour[0].texels[0], [188, 188, 188, 128]);
    assert_eq!(data[0].texels[0], [128, 128, 128, 128]);
}

/// Odd and mixed sizes: each level half the one above, rounded up, down to 1×1; every
/// level of every texture placed whole in a page and none overlapping; nearest textures
/// and `pack_atlas` have no levels; textures sharing an image share its levels.
#[test]
fn levels_of_any_size_are_placed_whole_and_apart() {
    let mut all: Vec<Texture> = [(37, 5), (1, 1), (300, 17), (64, 64), (2, 9)]
        .iter()
        .enumerate()
        .map(|(i, &(w, h))| noise(w, h, 10 + i as u32, false))
        .collect();
    all.push(noise(8, 8, 99, true));
    let mut shared = all[0].clone();
    shared.wrap = [Wrap::ClampToEdge; 2];
    all.push(shared);
    let srgb = vec![true; all.len()];
    let atlas = pack_atlas_with(&all, Some(&srgb));
    assert_eq!(atlas.textures, all.len());
    let mut rects = Vec::new();
    for (i, t) in all.iter().enumerate() {
        let id = i as u32;
        let levels = atlas.mip_levels(id);
        if t.nearest || (t.width, t.height) == (1, 1) {
            assert_eq!(levels, 0, "texture {i}");
            continue;
        }
        let (mut w, mut h) = (t.width, t.height);
        for k in 1..=levels {
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
            let d = atlas.level_place(id, k);
            assert_eq!((d[2] & 0xFFFF, d[2] >> 16), (w, h), "texture {i} level {k}");
            assert_eq!(d[3] & 0xFF, t.flags(), "texture {i} level {k}'s flags");
            rects.push((d[0] & 0xFFFF, d[0] >> 16, d[1], w, h));
        }
        assert_eq!((w, h), (1, 1), "texture {i}'s chain ends at 1x1");
    }
    // The shared image's levels are the first texture's (one copy), wrapped its own way.
    assert_eq!(atlas.level_place(0, 1)[..3], atlas.level_place(6, 1)[..3]);
    assert_ne!(atlas.level_place(0, 1)[3], atlas.level_place(6, 1)[3]);
    rects.sort_unstable();
    rects.dedup();
    for i in 0..atlas.textures {
        let d = atlas.descriptors[i].place;
        rects.push((d[0] & 0xFFFF, d[0] >> 16, d[1], d[2] & 0xFFFF, d[2] >> 16));
    }
    rects.sort_unstable();
    rects.dedup();
    let page = atlas.page_size;
    for (i, a) in rects.iter().enumerate() {
        assert!(a.0 + a.3 <= page && a.1 + a.4 <= page && a.2 < atlas.pages);
        for b in &rects[i + 1..] {
            let apart = a.2 != b.2
                || a.0 + a.3 <= b.0
                || b.0 + b.3 <= a.0
                || a.1 + a.4 <= b.1
                || b.1 + b.4 <= a.1;
            assert!(apart, "{a:?} overlaps {b:?}");
        }
    }
    assert!(atlas.mip_bytes > 0);
    let plain = pack_atlas(&all);
    assert_eq!(plain.descriptors.len(), all.len());
    assert_eq!(plain.mip_bytes, 0);
    assert!((0..all.len() as u32).all(|i| plain.mip_levels(i) == 0));
    assert!(
        plain
            .descriptors
            .iter()
            .all(|d| d.place[3] >> TEX_MIPS_SHIFT == 0)
    );
}

/// The trilinear lookup: at a level of detail ≤ 0 (or not finite) exactly the bilinear
/// level-0 lookup; at a whole level k that level's bilinear lookup; between two levels
/// their blend; past the chain, the 1×1 level (the texture's mean).
#[test]
fn lod_lookup_blends_the_two_levels_around_it() {
    let t = noise(32, 32, 5, false);
    let atlas = pack_atlas_with(std::slice::from_ref(&t), Some(&[true]));
    let uv = Vec4::new(0.3, 0.7, 0.0, 0.0);
    let at = |texels: f32| Vec2::splat(texels.log2() - 5.0);
    for lod in [
        Vec2::splat(-6.0),
        Vec2::splat(f32::NEG_INFINITY),
        Vec2::splat(f32::NAN),
        at(1.0),
    ] {
        assert_eq!(
            atlas.sample_lod(0, uv, lod, true),
            atlas.sample(0, uv, true),
            "lod {lod} ({})",
            atlas.lod(0, lod)
        );
    }
    let level = |k: u32| {
        let chain = t.mip_chain(true);
        chain[k as usize - 1].sample(Vec2::new(0.3, 0.7), true)
    };
    let close = |a: Vec4, b: Vec4| (a - b).abs().max_element() < 1e-6;
    assert!(close(atlas.sample_lod(0, uv, at(4.0), true), level(2)));
    let half = atlas.sample_lod(0, uv, at(4.0 * 2f32.sqrt()), true);
    assert!(close(half, level(2).lerp(level(3), 0.5)), "{half}");
    let mean = atlas.sample_lod(0, uv, at(1e6), true);
    assert!(close(mean, level(5)));
    // The transform's scale counts: UVs scaled by 4 see 4× the texels per UV unit.
    let mut scaled = t.clone();
    scaled.transform = UvTransform::khr([0.0, 0.0], 0.0, [4.0, 4.0]);
    let atlas = pack_atlas_with(&[scaled], Some(&[true]));
    assert!((atlas.lod(0, at(1.0)) - 2.0).abs() < 1e-5);
}

/// Fitting an atlas with mip levels counts them: a budget the images alone fit but not
/// with their levels halves them.
#[test]
fn fitting_counts_the_mip_levels() {
    let all = vec![noise(256, 256, 1, false), noise(256, 256, 2, false)];
    let srgb = [true, true];
    let budget = AtlasLimits {
        max_side: 256,
        max_pages: 2,
        max_bytes: None,
    };
    let (same, notes) = fit_textures_with(&all, budget, None).unwrap();
    assert!(notes.is_empty());
    assert_eq!(same[0].width, 256);
    let (fitted, notes) = fit_textures_with(&all, budget, Some(&srgb)).unwrap();
    assert_eq!(notes.len(), 1, "{notes:?}");
    let atlas = pack_atlas_with(&fitted, Some(&srgb));
    assert!(budget.hold(atlas.page_size, atlas.pages));
}
