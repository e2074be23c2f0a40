//! The texture atlas: every texture placed whole in a page, none overlapping, its texels
//! copied where its descriptor says (GPU-free).

use lumagraph_scene::{GpuTexDesc, Texture, UvTransform, Wrap, pack_atlas};

fn texture(i: usize, width: u32, height: u32) -> Texture {
    Texture {
        name: format!("t{i}"),
        width,
        height,
        texels: (0..width * height)
            .map(|k| (k + 977 * i as u32).to_le_bytes())
            .collect(),
        wrap: [Wrap::Repeat, Wrap::ClampToEdge],
        nearest: i.is_multiple_of(3),
        uv_set: 0,
        transform: UvTransform::IDENTITY,
    }
}

/// Textures of 61 sizes (1×1 to 700×300, powers of two and not), in the order given.
#[test]
fn every_texture_lands_whole_in_one_page_and_none_overlap() {
    let textures: Vec<Texture> = (0..61)
        .map(|i| {
            let (w, h) = match i % 4 {
                0 => (1 << (i % 10), 1 << ((i / 2) % 10)),
                1 => (1 + (i as u32 * 37) % 700, 1 + (i as u32 * 13) % 300),
                2 => (64, 64),
                _ => (3, 250),
            };
            texture(i, w, h)
        })
        .collect();
    let atlas = pack_atlas(&textures);
    let page = atlas.page_size;
    assert!(page.is_power_of_two() && page >= 700, "page {page}");
    assert_eq!(atlas.descriptors.len(), textures.len());
    assert_eq!(
        atlas.texels.len(),
        (page * page * atlas.pages) as usize,
        "texels"
    );
    let rect = |d: &GpuTexDesc| {
        let d = d.place;
        (d[0] & 0xFFFF, d[0] >> 16, d[1], d[2] & 0xFFFF, d[2] >> 16)
    };
    for (i, (t, d)) in textures.iter().zip(&atlas.descriptors).enumerate() {
        let (x, y, p, w, h) = rect(d);
        assert_eq!((w, h), (t.width, t.height), "texture {i}'s size");
        assert!(
            x + w <= page && y + h <= page && p < atlas.pages,
            "texture {i} out of its page"
        );
        assert_eq!(d.place[3], t.flags(), "texture {i}'s flags");
        for (k, texel) in t.texels.iter().enumerate() {
            let (tx, ty) = (k as u32 % w, k as u32 / w);
            let at = (p * page * page + (y + ty) * page + x + tx) as usize;
            assert_eq!(
                atlas.texels[at],
                u32::from_le_bytes(*texel),
                "texture {i} texel {k}"
            );
        }
        for (j, e) in atlas.descriptors.iter().enumerate().skip(i + 1) {
            let (x2, y2, p2, w2, h2) = rect(e);
            let apart = p != p2 || x + w <= x2 || x2 + w2 <= x || y + h <= y2 || y2 + h2 <= y;
            assert!(apart, "textures {i} and {j} overlap");
        }
    }
    // Shelf packing keeps pages reasonably full: at most twice the texels in pages.
    let used: u64 = textures.iter().map(|t| u64::from(t.width * t.height)).sum();
    assert!(
        atlas.texels.len() as u64 <= 2 * used + u64::from(page * page),
        "{} texels in pages for {used}",
        atlas.texels.len()
    );
}

/// Powers of two fill pages without gaps: one texture of 2048², 20 of 1024² and 8 of 512²
/// take 7 pages of 2048² (one for the largest, 5 full of 1024² ones, one holding the 512²
/// ones).
#[test]
fn power_of_two_textures_fill_their_pages() {
    let mut textures: Vec<Texture> = (0..20).map(|i| texture(i, 1024, 1024)).collect();
    textures.extend((20..28).map(|i| texture(i, 512, 512)));
    textures.push(texture(28, 2048, 2048));
    let atlas = pack_atlas(&textures);
    assert_eq!(atlas.page_size, 2048);
    // 2048² + 20 × 1024² + 8 × 512² = 1 + 5 + 0.5 pages.
    assert_eq!(atlas.pages, 7);
}

#[test]
fn no_textures_no_pages() {
    let atlas = pack_atlas(&[]);
    assert_eq!((atlas.pages, atlas.texels.len()), (0, 0));
}

/// Textures that share an image (glTF textures read through different transforms or UV
/// sets) share its place in the atlas: the image is stored once, and each descriptor keeps
/// its own transform and set.
#[test]
fn textures_sharing_an_image_share_its_place() {
    let a = texture(1, 64, 32);
    let turned = Texture {
        uv_set: 1,
        transform: UvTransform::khr([0.25, -0.5], 1.0, [2.0, 3.0]),
        ..a.clone()
    };
    let other = texture(2, 64, 32);
    let atlas = pack_atlas(&[a.clone(), turned.clone(), other]);
    let d = &atlas.descriptors;
    assert_eq!(d[0].place, d[1].place, "shared image, one place");
    assert_ne!(d[0].place, d[2].place, "another image, another place");
    assert_eq!(
        (d[0].uv_set, d[0].m, d[0].offset),
        (0, [1.0, 0.0, 0.0, 1.0], [0.0, 0.0])
    );
    assert_eq!(
        (d[1].uv_set, d[1].m, d[1].offset),
        (1, turned.transform.m, turned.transform.offset)
    );
    // Two images of 64×32 fit one page: the shared one is not stored twice.
    let single = pack_atlas(&[a.clone(), texture(2, 64, 32)]);
    assert_eq!(atlas.texels.len(), single.texels.len());
    // KHR_texture_transform: scale, then rotate, then offset.
    let t = UvTransform::khr([0.5, 0.25], std::f32::consts::FRAC_PI_2, [2.0, 4.0]);
    let p = t.apply(glam::Vec2::new(1.0, 1.0));
    // Scaled (2, 4); rotated by 90° with the spec's matrix [cos sin; -sin cos]: (4, -2).
    assert!((p - glam::Vec2::new(4.5, -1.75)).length() < 1e-6, "{p}");
}

/// Textures of 1024², 512² (shared by two textures), 300×200 and 64²: 3 pages of 1024².
fn to_fit() -> Vec<Texture> {
    let mut all = vec![texture(0, 1024, 1024), texture(1, 512, 512)];
    all.push(Texture {
        name: "t1 again".to_owned(),
        transform: UvTransform::khr([0.5, 0.0], 0.0, [2.0, 2.0]),
        ..all[1].clone()
    });
    all.push(texture(3, 300, 200));
    all.push(texture(4, 64, 64));
    all
}

#[test]
fn fitting_halves_the_largest_images_until_the_atlas_fits() {
    use lumagraph_scene::{AtlasLimits, fit_textures};
    let all = to_fit();
    let before = pack_atlas(&all);
    assert_eq!((before.page_size, before.pages), (1024, 2));
    let limits = |max_side, max_pages, max_bytes| AtlasLimits {
        max_side,
        max_pages,
        max_bytes,
    };
    // Fits already: nothing changes.
    let (same, notes) = fit_textures(&all, limits(1024, 2, None)).unwrap();
    assert!(notes.is_empty());
    assert_eq!(pack_atlas(&same).texels, before.texels);
    // One page: the 1024² image halved, then the largest again until one page holds all.
    let (fitted, notes) = fit_textures(&all, limits(16384, 1, None)).unwrap();
    let after = pack_atlas(&fitted);
    assert_eq!(after.pages, 1);
    assert_eq!(notes[0].name, "t0");
    assert_eq!(notes[0].from, (1024, 1024));
    assert!(notes[0].to.0 < 1024);
    assert!(
        notes.iter().all(|n| n.name != "t4"),
        "the smallest image stays: {notes:?}"
    );
    // Two textures that shared an image share its smaller one, each with its own transform.
    assert!(std::sync::Arc::ptr_eq(&fitted[1].texels, &fitted[2].texels));
    assert_eq!(fitted[1].width, fitted[2].width);
    assert_eq!(fitted[2].transform, all[2].transform);
    // A largest side: every image wider is halved until it is not.
    let (fitted, _) = fit_textures(&all, limits(256, 64, None)).unwrap();
    assert_eq!(
        fitted
            .iter()
            .map(|t| (t.width, t.height))
            .collect::<Vec<_>>(),
        [(256, 256), (256, 256), (256, 256), (150, 100), (64, 64)]
    );
    // A byte budget: one page of 256² is the least an atlas takes.
    let (fitted, _) = fit_textures(&all, limits(16384, 64, Some(4 * 256 * 256))).unwrap();
    let after = pack_atlas(&fitted);
    assert_eq!((after.page_size, after.pages), (256, 1));
    assert!(fit_textures(&all, limits(16384, 64, Some(4 * 256 * 256 - 1))).is_none());
}

#[test]
fn a_halved_image_averages_each_two_by_two_block() {
    let t = Texture {
        texels: vec![
            [0, 10, 255, 255],
            [4, 10, 255, 0],
            [9, 30, 0, 255],
            [8, 10, 255, 255],
            [3, 50, 0, 0],
            [100, 200, 0, 255],
        ]
        .into(),
        width: 3,
        height: 2,
        ..texture(0, 1, 1)
    };
    let h = t.halved();
    assert_eq!((h.width, h.height), (2, 1));
    // (0 + 4 + 8 + 3) / 4 = 3.75 -> 4; the odd column averaged with itself.
    assert_eq!(h.texels[0], [4, 20, 191, 128]);
    assert_eq!(h.texels[1], [55, 115, 0, 255]);
    assert_eq!((h.wrap, h.nearest, h.uv_set), (t.wrap, t.nearest, t.uv_set));
}
