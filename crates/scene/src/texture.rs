//! Decoded textures and their sampling, the exact CPU mirror of
//! `shaders/pathtrace/textures.wgsl`.
//!
//! A texture is RGBA8 texels (row 0 at the top: glTF's UV (0, 0) is the image's top-left
//! corner), a wrap mode per axis and a filter, and the coordinates it reads: a UV set and
//! a transform ([`UvTransform`], glTF's `KHR_texture_transform`). Sampling is bilinear between the four texels
//! around the point (texel centers at `(i + 0.5) / width`), after decoding each texel from
//! sRGB when asked (as a GPU filters an sRGB texture), or the nearest texel when the glTF
//! sampler's `magFilter` is `NEAREST`.
//!
//! Mip chains ([`Texture::mip_chain`], [`pack_atlas_with`]): each image halved again and
//! again down to 1×1, every texel the mean of the 2×2 it covers (a box filter), computed in
//! linear light for images a material reads as colour (sRGB: decoded, averaged, encoded)
//! and on the stored values for data (normals, roughness, alpha). The path tracer picks a
//! level per lookup from a ray cone ([`TextureAtlas::sample_lod`]) and blends the two
//! levels around it (trilinear); level 0 is what bilinear filtering alone reads.
//!
//! On the GPU all textures of a scene live in one 2D array texture of RGBA8 texels, an atlas
//! ([`TextureAtlas`], [`pack_atlas`]): square pages of one size, each texture placed whole
//! in one page, and one descriptor per texture saying where. The shader wraps and filters
//! itself, reading texels with `textureLoad`, so no texel of one texture bleeds into
//! another. An atlas holds what a device's 2D array textures can (pages up to its largest
//! 2D texture side, as many as its array layers): far more than one storage buffer binding
//! (128 MiB on many devices).

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use crate::gpu::GpuTexDesc;

/// How coordinates outside [0, 1] map into the texture (glTF sampler `wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The texture repeats (glTF's default).
    #[default]
    Repeat,
    /// The edge texels extend.
    ClampToEdge,
    /// The texture repeats, mirrored every other time.
    MirroredRepeat,
}

impl Wrap {
    /// The code the shader reads (`TEX_WRAP_*`).
    pub fn code(self) -> u32 {
        match self {
            Self::Repeat => 0,
            Self::ClampToEdge => 1,
            Self::MirroredRepeat => 2,
        }
    }

    /// The texel index for integer coordinate `i` in a row of `n` texels.
    pub fn index(self, i: i64, n: u32) -> u32 {
        let n = i64::from(n);
        let r = match self {
            Self::Repeat => i.rem_euclid(n),
            Self::ClampToEdge => i.clamp(0, n - 1),
            Self::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m >= n { 2 * n - 1 - m } else { m }
            }
        };
        u32::try_from(r).unwrap_or(0)
    }
}

/// An affine map of texture coordinates, `uv' = u · m[0..2] + v · m[2..4] + offset`: glTF's
/// `KHR_texture_transform` (see [`UvTransform::khr`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// The 2×2 matrix by columns: the image of U's axis (`m[0]`, `m[1]`), then V's.
    pub m: [f32; 4],
    /// Added after the matrix.
    pub offset: [f32; 2],
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl UvTransform {
    /// Coordinates unchanged (exactly: `u · 1 + v · 0 + 0 = u` in floating point).
    pub const IDENTITY: Self = Self {
        m: [1.0, 0.0, 0.0, 1.0],
        offset: [0.0, 0.0],
    };

    /// `KHR_texture_transform`'s matrix `T · R · S`: scale first, then rotate by `rotation`
    /// radians (counter-clockwise in UV space, so clockwise on the image, whose V goes down),
    /// then translate by `offset`.
    pub fn khr(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Self {
        let (sin, cos) = rotation.sin_cos();
        Self {
            m: [
                cos * scale[0],
                -sin * scale[0],
                sin * scale[1],
                cos * scale[1],
            ],
            offset,
        }
    }

    /// `uv` mapped: the shader's `tex_uv`, operation for operation.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let m = self.m;
        Vec2::new(
            m[0] * uv.x + m[2] * uv.y + self.offset[0],
            m[1] * uv.x + m[3] * uv.y + self.offset[1],
        )
    }
}

/// A decoded texture as a material reads it: an image, how it is wrapped and filtered, and
/// which texture coordinates it reads through which transform. Textures that share an
/// image share its texels ([`Arc`]), in memory and in the atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from, for messages (`"BoxTextured.gltf image 0 (CesiumLogoFlat.png)"`).
    pub name: String,
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// RGBA8 texels, row by row from the top.
    pub texels: Arc<[[u8; 4]]>,
    /// Wrap along U (glTF `wrapS`) and V (`wrapT`).
    pub wrap: [Wrap; 2],
    /// Nearest-texel lookup (glTF `magFilter: NEAREST`) instead of bilinear.
    pub nearest: bool,
    /// Which texture coordinates it reads: 0 ([`crate::Triangle::uvs`], glTF `TEXCOORD_0`)
    /// or 1 ([`crate::Triangle::uvs1`]).
    pub uv_set: u32,
    /// Applied to the coordinates before the lookup (glTF `KHR_texture_transform`).
    pub transform: UvTransform,
}

/// The smallest and largest texel byte of each channel (RGBA) of a texture: what the
/// shader specializer reads to know which values a textured factor can take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TexelRange {
    /// The smallest byte of each channel.
    pub min: [u8; 4],
    /// The largest byte of each channel.
    pub max: [u8; 4],
}

impl Texture {
    /// The image at half the size (odd sides rounded up, the last row or column then
    /// averaged with itself): each texel the mean of the 2×2 it covers, byte by byte in the
    /// stored encoding (sRGB for colours, so a high-contrast edge comes out slightly darker
    /// than a linear mean would make it).
    #[must_use]
    pub fn halved(&self) -> Self {
        let (w, h) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let texels: Vec<[u8; 4]> = halve(&self.texels, self.width, self.height, |q| {
            std::array::from_fn(|c| {
                let sum: u32 = q.iter().map(|p| u32::from(p[c])).sum();
                u8::try_from((sum + 2) / 4).unwrap_or(u8::MAX)
            })
        });
        Self {
            width: w,
            height: h,
            texels: texels.into(),
            ..self.clone()
        }
    }

    /// The mip levels below this image, level 1 first, down to 1×1 (none for a 1×1 image):
    /// each level half the size of the one above (odd sides rounded up, the last row or
    /// column then averaged with itself, as [`Texture::halved`]), each texel the mean of
    /// the 2×2 texels of the level above it covers: a box filter, so level k's texel is the
    /// mean of the 2^k × 2^k texels of level 0 under it (power-of-two sides). The means are
    /// taken in linear light when `srgb` (RGB decoded, averaged, encoded again; alpha is
    /// always linear) and on the stored values otherwise; each level is averaged from the
    /// unrounded one above, and rounded to bytes only when stored.
    #[must_use]
    pub fn mip_chain(&self, srgb: bool) -> Vec<Self> {
        let table = srgb_table();
        let decode = |c: usize, b: u8| {
            if srgb && c < 3 {
                table[b as usize]
            } else {
                f32::from(b) / 255.0
            }
        };
        let encode = |c: usize, v: f32| {
            if srgb && c < 3 {
                unorm8(srgb_encode(v))
            } else {
                unorm8(v)
            }
        };
        let (mut w, mut h) = (self.width, self.height);
        let mut level: Vec<[f32; 4]> = self
            .texels
            .iter()
            .map(|t| std::array::from_fn(|c| decode(c, t[c])))
            .collect();
        let mut out = Vec::new();
        while (w, h) != (1, 1) {
            let next = halve(&level, w, h, |q| {
                std::array::from_fn(|c| 0.25 * (q[0][c] + q[1][c] + q[2][c] + q[3][c]))
            });
            (level, w, h) = (next, w.div_ceil(2), h.div_ceil(2));
            let texels: Vec<[u8; 4]> = level
                .iter()
                .map(|t| std::array::from_fn(|c| encode(c, t[c])))
                .collect();
            out.push(Self {
                width: w,
                height: h,
                texels: texels.into(),
                ..self.clone()
            });
        }
        out
    }

    /// The range of each channel over every texel (bilinear filtering stays within it).
    pub fn range(&self) -> TexelRange {
        let mut r = TexelRange {
            min: [u8::MAX; 4],
            max: [0; 4],
        };
        for t in self.texels.iter() {
            for c in 0..4 {
                r.min[c] = r.min[c].min(t[c]);
                r.max[c] = r.max[c].max(t[c]);
            }
        }
        r
    }
}

/// Descriptor flag: nearest-texel lookup.
pub const TEX_NEAREST: u32 = 16;
/// Where a descriptor's flags hold how many mip levels its texture has after level 0 (4
/// bits: at most [`MAX_MIP_LEVELS`] − 1).
pub const TEX_MIPS_SHIFT: u32 = 8;
/// The most levels a mip chain has, level 0 included: a 16 384-texel side down to 1.
pub const MAX_MIP_LEVELS: u32 = 15;

/// A `w`×`h` grid of texels halved: each texel of the result (`w`/2 × `h`/2, odd sides
/// rounded up, the last row or column then taken with itself) made by `mean` from the 2×2
/// texels it covers.
fn halve<T: Copy, U>(texels: &[T], w: u32, h: u32, mean: impl Fn([T; 4]) -> U) -> Vec<U> {
    let at = |x: u32, y: u32| texels[(y.min(h - 1) * w + x.min(w - 1)) as usize];
    let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
    let mut out = Vec::with_capacity(nw as usize * nh as usize);
    for y in 0..nh {
        for x in 0..nw {
            out.push(mean([
                at(2 * x, 2 * y),
                at(2 * x + 1, 2 * y),
                at(2 * x, 2 * y + 1),
                at(2 * x + 1, 2 * y + 1),
            ]));
        }
    }
    out
}

/// The 256 sRGB bytes decoded to linear light.
fn srgb_table() -> [f32; 256] {
    std::array::from_fn(|i| srgb_decode(i as f32 / 255.0))
}

/// A byte from a value in [0, 1], rounded to nearest.
fn unorm8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}
/// The finest subdivision [`Texture::triangle_mean`] uses: at most 64² = 4096 samples.
pub const TRIANGLE_MEAN_MAX_SPLIT: u32 = 64;

/// Linear → sRGB, one channel in [0, 1] (how vertex colours are stored).
pub fn srgb_encode(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB → linear, one channel in [0, 1] (the WGSL `srgb_decode`).
pub fn srgb_decode(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// The texel at integer coordinates, wrapped, as unorm floats (sRGB decoded in rgb when
    /// `srgb`; alpha is always linear).
    pub fn fetch(&self, x: i64, y: i64, srgb: bool) -> Vec4 {
        let xi = self.wrap[0].index(x, self.width);
        let yi = self.wrap[1].index(y, self.height);
        let t = self.texels[(yi * self.width + xi) as usize];
        let v = Vec4::from_array(t.map(|c| f32::from(c) / 255.0));
        if srgb {
            Vec4::new(srgb_decode(v.x), srgb_decode(v.y), srgb_decode(v.z), v.w)
        } else {
            v
        }
    }

    /// The filtered value at `uv` (see the module documentation).
    pub fn sample(&self, uv: Vec2, srgb: bool) -> Vec4 {
        let size = Vec2::new(self.width as f32, self.height as f32);
        let p = uv * size;
        if self.nearest {
            let f = p.floor();
            return self.fetch(f.x as i64, f.y as i64, srgb);
        }
        let p = p - 0.5;
        let f = p.floor();
        let t = p - f;
        let (x, y) = (f.x as i64, f.y as i64);
        let a = self.fetch(x, y, srgb).lerp(self.fetch(x + 1, y, srgb), t.x);
        let b = self
            .fetch(x, y + 1, srgb)
            .lerp(self.fetch(x + 1, y + 1, srgb), t.x);
        a.lerp(b, t.y)
    }

    /// The mean of the filtered value over the triangle with corners `uvs` in texture space
    /// (what [`Texture::sample`] returns, averaged over the triangle's area): the samples are
    /// the centroids of the n² congruent sub-triangles of an n-fold subdivision, n chosen so
    /// that there are about 16 per texel (4 ≤ n ≤ [`TRIANGLE_MEAN_MAX_SPLIT`]: fewer on
    /// footprints over 256 texels). Exact for a constant texture.
    pub fn triangle_mean(&self, uvs: [Vec2; 3], srgb: bool) -> Vec4 {
        let (d1, d2) = (uvs[1] - uvs[0], uvs[2] - uvs[0]);
        let texels = 0.5 * d1.perp_dot(d2).abs() * self.width as f32 * self.height as f32;
        let n = if texels.is_finite() {
            ((4.0 * texels.sqrt()).ceil() as u32).clamp(4, TRIANGLE_MEAN_MAX_SPLIT)
        } else {
            4
        };
        let at = |a: f32, b: f32| self.sample(uvs[0] + a * d1 + b * d2, srgb);
        let inv = 1.0 / n as f32;
        let mut sum = Vec4::ZERO;
        for i in 0..n {
            for j in 0..n - i {
                // The upright sub-triangle at (i, j), and the inverted one beside it.
                sum += at((i as f32 + 1.0 / 3.0) * inv, (j as f32 + 1.0 / 3.0) * inv);
                if i + j + 1 < n {
                    sum += at((i as f32 + 2.0 / 3.0) * inv, (j as f32 + 2.0 / 3.0) * inv);
                }
            }
        }
        sum / (n * n) as f32
    }

    /// The descriptor flags word.
    pub fn flags(&self) -> u32 {
        self.wrap[0].code()
            | (self.wrap[1].code() << 2)
            | if self.nearest { TEX_NEAREST } else { 0 }
    }

    /// Where this texture is looked up for a point whose coordinates are `uvs` (set 0, set
    /// 1): its set, transformed.
    pub fn uv(&self, uvs: [Vec2; 2]) -> Vec2 {
        self.transform.apply(uvs[(self.uv_set as usize).min(1)])
    }
}

/// Every texture of a scene placed in the pages of one 2D array texture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureAtlas {
    /// The side of every page, in texels (a power of two at least as large as the largest
    /// side of any texture); 0 without textures.
    pub page_size: u32,
    /// Pages (array layers).
    pub pages: u32,
    /// Per texture: where its image is, how it is wrapped and filtered, and which
    /// coordinates it reads through which transform; then, with mip chains, one per texture
    /// and mip level after level 0 (its place only).
    pub descriptors: Vec<GpuTexDesc>,
    /// The pages' RGBA8 texels (R in the low byte), page after page, row by row from the
    /// top; texels no texture covers are 0.
    pub texels: Vec<u32>,
    /// Bytes of texels of the mip levels (part of the pages, [`pack_atlas_with`]); 0
    /// without them.
    pub mip_bytes: u64,
    /// How many textures it holds (the first descriptors; the mip levels' follow).
    pub textures: usize,
}

impl TextureAtlas {
    /// Bytes of texels.
    pub fn bytes(&self) -> u64 {
        4 * self.texels.len() as u64
    }

    /// How many mip levels texture `id` has after level 0.
    pub fn mip_levels(&self, id: u32) -> u32 {
        (self.descriptors[id as usize].place[3] >> TEX_MIPS_SHIFT) & 0xF
    }

    /// The place (`GpuTexDesc::place`) of level `level` of texture `id` (0: its own),
    /// level clamped to its last: `tex_level` in `pathtrace/textures.wgsl`.
    pub fn level_place(&self, id: u32, level: u32) -> [u32; 4] {
        let d = &self.descriptors[id as usize];
        let k = level.min(self.mip_levels(id));
        if k == 0 {
            d.place
        } else {
            self.descriptors[(d.mips + k - 1) as usize].place
        }
    }

    /// The texel at integer coordinates of the image placed at `d`, wrapped.
    fn fetch_at(&self, d: [u32; 4], x: i64, y: i64, srgb: bool) -> Vec4 {
        let wrap = |code: u32| match code {
            1 => Wrap::ClampToEdge,
            2 => Wrap::MirroredRepeat,
            _ => Wrap::Repeat,
        };
        let xi = wrap(d[3] & 3).index(x, d[2] & 0xFFFF);
        let yi = wrap((d[3] >> 2) & 3).index(y, d[2] >> 16);
        let page = self.page_size as usize;
        let at = d[1] as usize * page * page
            + ((d[0] >> 16) + yi) as usize * page
            + ((d[0] & 0xFFFF) + xi) as usize;
        let v = Vec4::from_array(self.texels[at].to_le_bytes().map(|c| f32::from(c) / 255.0));
        if srgb {
            Vec4::new(srgb_decode(v.x), srgb_decode(v.y), srgb_decode(v.z), v.w)
        } else {
            v
        }
    }

    /// The bilinear (or nearest) value of the image placed at `d` at `uv`.
    fn filter_at(&self, d: [u32; 4], uv: Vec2, srgb: bool) -> Vec4 {
        let p = uv * Vec2::new((d[2] & 0xFFFF) as f32, (d[2] >> 16) as f32);
        if d[3] & TEX_NEAREST != 0 {
            let f = p.floor();
            return self.fetch_at(d, f.x as i64, f.y as i64, srgb);
        }
        let p = p - 0.5;
        let f = p.floor();
        let t = p - f;
        let (x, y) = (f.x as i64, f.y as i64);
        let a = self
            .fetch_at(d, x, y, srgb)
            .lerp(self.fetch_at(d, x + 1, y, srgb), t.x);
        let b = self
            .fetch_at(d, x, y + 1, srgb)
            .lerp(self.fetch_at(d, x + 1, y + 1, srgb), t.x);
        a.lerp(b, t.y)
    }

    /// The level of detail of texture `id` for a footprint `lod` (per coordinate set: log2
    /// of the footprint's width in that set's UV units, see `Surface::lod` in
    /// `pathtrace/integrator/surface.wgsl`): log2 of its width in level-0 texels, through the
    /// texture's transform (`tex_lod` in `pathtrace/textures.wgsl`). Not finite or ≤ 0
    /// means level 0.
    pub fn lod(&self, id: u32, lod: Vec2) -> f32 {
        let d = &self.descriptors[id as usize];
        let size = ((d.place[2] & 0xFFFF) as f32) * ((d.place[2] >> 16) as f32);
        let det = (d.m[0] * d.m[3] - d.m[2] * d.m[1]).abs();
        let set = if d.uv_set == 0 { lod.x } else { lod.y };
        set + 0.5 * (size * det).log2()
    }

    /// [`TextureAtlas::sample`] at the level of detail `lod` (see [`TextureAtlas::lod`]):
    /// level 0 alone (bilinear, exactly `sample`) where the texture has no mip levels,
    /// is looked up nearest, or the level is not above 0; else the two levels around it
    /// blended (trilinear), the last level beyond the chain. `tex_sample_lod` in
    /// `pathtrace/textures.wgsl`.
    pub fn sample_lod(&self, id: u32, uvs: Vec4, lod: Vec2, srgb: bool) -> Vec4 {
        let levels = self.mip_levels(id);
        let lambda = self.lod(id, lod);
        let d = &self.descriptors[id as usize];
        // Not above 0, or NaN: level 0.
        if levels == 0
            || d.place[3] & TEX_NEAREST != 0
            || lambda.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        {
            return self.sample(id, uvs, srgb);
        }
        let uv = self.uv(id, uvs);
        let lambda = lambda.min(levels as f32);
        let k = lambda.floor();
        let f = lambda - k;
        let k = k as u32;
        let a = self.filter_at(self.level_place(id, k), uv, srgb);
        if f == 0.0 {
            return a;
        }
        a.lerp(self.filter_at(self.level_place(id, k + 1), uv, srgb), f)
    }

    /// The texel of texture `id` at integer coordinates, wrapped: `tex_fetch` in
    /// `pathtrace/textures.wgsl`, line for line.
    pub fn fetch(&self, id: u32, x: i64, y: i64, srgb: bool) -> Vec4 {
        self.fetch_at(self.descriptors[id as usize].place, x, y, srgb)
    }

    /// The filtered value of texture `id` for a point whose coordinates are `uvs` (set 0 in
    /// xy, set 1 in zw): `tex_sample` in `pathtrace/textures.wgsl`, and
    /// [`Texture::sample`] at [`Texture::uv`] of the texture placed there.
    pub fn sample(&self, id: u32, uvs: Vec4, srgb: bool) -> Vec4 {
        self.filter(id, self.uv(id, uvs), srgb)
    }

    /// Texture `id`'s coordinates at a point whose coordinates are `uvs` (set 0 in xy, set 1
    /// in zw): its UV set, through its transform (`tex_uv` in `pathtrace/textures.wgsl`).
    fn uv(&self, id: u32, uvs: Vec4) -> Vec2 {
        let d = &self.descriptors[id as usize];
        let uv = if d.uv_set == 0 {
            uvs.truncate().truncate()
        } else {
            Vec2::new(uvs.z, uvs.w)
        };
        UvTransform {
            m: d.m,
            offset: d.offset,
        }
        .apply(uv)
    }

    /// The filtered value of texture `id` at `uv` in its own coordinates (after its
    /// transform): `tex_filter` in `pathtrace/textures.wgsl`.
    pub fn filter(&self, id: u32, uv: Vec2, srgb: bool) -> Vec4 {
        self.filter_at(self.descriptors[id as usize].place, uv, srgb)
    }
}

/// One entry per image: for each texture the index of its image, and the first texture
/// showing each image (textures sharing [`Texture::texels`], the same [`Arc`], share it).
fn images(all: &[Texture]) -> (Vec<usize>, Vec<&Texture>) {
    let mut image_of = Vec::with_capacity(all.len());
    let mut first: std::collections::HashMap<*const [u8; 4], usize> =
        std::collections::HashMap::new();
    let mut textures: Vec<&Texture> = Vec::new();
    for t in all {
        let at = *first.entry(t.texels.as_ptr()).or_insert_with(|| {
            textures.push(t);
            textures.len() - 1
        });
        image_of.push(at);
    }
    (image_of, textures)
}

/// Where images of the given sizes go in an atlas.
struct AtlasLayout {
    /// The page side.
    page: u32,
    /// Pages used.
    pages: u32,
    /// Per image: x, y and page.
    place: Vec<(u32, u32, u32)>,
}

/// Shelf packing of images of `sizes` (width, height) in pages of one size, tallest first.
fn atlas_layout(sizes: &[(u32, u32)]) -> AtlasLayout {
    let side = sizes.iter().map(|&(w, h)| w.max(h)).max().unwrap_or(1);
    let page = side.next_power_of_two().max(ATLAS_MIN_PAGE);
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&i| {
        (
            std::cmp::Reverse(sizes[i].1),
            std::cmp::Reverse(sizes[i].0),
            i,
        )
    });
    // Shelves: rows of textures left to right; a new shelf under the last, a new page when
    // the page is full.
    let (mut p, mut x, mut y, mut shelf) = (0u32, 0u32, 0u32, 0u32);
    let mut place = vec![(0u32, 0u32, 0u32); sizes.len()];
    for &i in &order {
        let (w, h) = sizes[i];
        if x + w > page {
            (x, y, shelf) = (0, y + shelf, 0);
        }
        if y + h > page {
            (p, x, y, shelf) = (p + 1, 0, 0, 0);
        }
        place[i] = (x, y, p);
        x += w;
        shelf = shelf.max(h);
    }
    AtlasLayout {
        page,
        pages: p + 1,
        place,
    }
}

/// What an atlas may use: its page side and page count (a device's largest 2D texture and
/// array layers) and, if given, its bytes of texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtlasLimits {
    /// The largest page side, in texels.
    pub max_side: u32,
    /// The most pages.
    pub max_pages: u32,
    /// The most bytes of texels in all pages (a memory budget), if any.
    pub max_bytes: Option<u64>,
}

impl AtlasLimits {
    /// Whether an atlas of `pages` pages of `page`² texels fits.
    pub fn hold(&self, page: u32, pages: u32) -> bool {
        let bytes = 4 * u64::from(page) * u64::from(page) * u64::from(pages);
        page <= self.max_side
            && pages <= self.max_pages
            && self.max_bytes.is_none_or(|b| bytes <= b)
    }
}

/// An image made smaller to fit an atlas's limits ([`fit_textures`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Downscaled {
    /// The first texture showing the image ([`Texture::name`]).
    pub name: String,
    /// Its size before, width and height.
    pub from: (u32, u32),
    /// And after.
    pub to: (u32, u32),
}

/// The textures with their images halved, largest first, until their atlas fits `limits`
/// (each image halved at most until it is 1×1), and what was made smaller; `None` when even
/// then they do not fit. Textures that share an image share its smaller one.
pub fn fit_textures(
    all: &[Texture],
    limits: AtlasLimits,
) -> Option<(Vec<Texture>, Vec<Downscaled>)> {
    fit_textures_with(all, limits, None)
}

/// [`fit_textures`] for an atlas with mip chains where `srgb` is given
/// ([`pack_atlas_with`]): the levels count in what must fit.
pub fn fit_textures_with(
    all: &[Texture],
    limits: AtlasLimits,
    srgb: Option<&[bool]>,
) -> Option<(Vec<Texture>, Vec<Downscaled>)> {
    let (image_of, textures) = images(all);
    let chain_of = srgb.map_or_else(
        || vec![None; textures.len()],
        |s| chains(all, &image_of, textures.len(), s),
    );
    let mut sizes: Vec<(u32, u32)> = textures.iter().map(|t| (t.width, t.height)).collect();
    loop {
        let mut every = sizes.clone();
        for (&(w, h), c) in sizes.iter().zip(&chain_of) {
            if c.is_some() {
                every.extend(chain_sizes(w, h));
            }
        }
        let layout = atlas_layout(&every);
        if limits.hold(layout.page, layout.pages) {
            break;
        }
        // Halve every image wider than a page may be, else the one with the most texels.
        let too_wide: Vec<usize> = (0..sizes.len())
            .filter(|&i| sizes[i].0.max(sizes[i].1) > limits.max_side)
            .collect();
        let halve = if too_wide.is_empty() {
            let i = (0..sizes.len()).max_by_key(|&i| {
                (
                    u64::from(sizes[i].0) * u64::from(sizes[i].1),
                    std::cmp::Reverse(i),
                )
            })?;
            vec![i]
        } else {
            too_wide
        };
        for i in halve {
            let (w, h) = sizes[i];
            if (w, h) == (1, 1) {
                return None;
            }
            sizes[i] = (w.div_ceil(2), h.div_ceil(2));
        }
    }
    let mut notes = Vec::new();
    let smaller: Vec<Option<Arc<[[u8; 4]]>>> = textures
        .iter()
        .zip(&sizes)
        .map(|(t, &size)| {
            if size == (t.width, t.height) {
                return None;
            }
            notes.push(Downscaled {
                name: t.name.clone(),
                from: (t.width, t.height),
                to: size,
            });
            let mut img = (*t).clone();
            while (img.width, img.height) != size {
                img = img.halved();
            }
            Some(img.texels)
        })
        .collect();
    let out = all
        .iter()
        .zip(&image_of)
        .map(|(t, &i)| {
            let mut t = t.clone();
            if let Some(texels) = &smaller[i] {
                (t.width, t.height) = sizes[i];
                t.texels = Arc::clone(texels);
            }
            t
        })
        .collect();
    Some((out, notes))
}

/// The smallest page side: pages of tiny textures are not made smaller than this.
pub const ATLAS_MIN_PAGE: u32 = 256;

/// Places the images of `textures` in pages of one size (shelf packing, tallest first:
/// images whose sides are powers of two fill pages without gaps) and copies their texels
/// there; textures sharing an image ([`Texture::texels`], the same [`Arc`], share it).
/// No mip levels: [`pack_atlas_with`] without them.
pub fn pack_atlas(all: &[Texture]) -> TextureAtlas {
    pack_atlas_with(all, None)
}

/// The sizes of an image's mip levels after level 0 ([`Texture::mip_chain`]'s).
fn chain_sizes(w: u32, h: u32) -> Vec<(u32, u32)> {
    let (mut w, mut h) = (w, h);
    let mut out = Vec::new();
    while (w, h) != (1, 1) {
        (w, h) = (w.div_ceil(2), h.div_ceil(2));
        out.push((w, h));
    }
    out
}

/// Which images get a mip chain, and whether it is averaged in linear light: per image of
/// `images`, `None` where every texture showing it is looked up nearest (glTF `NEAREST`,
/// no levels), else `Some(srgb)`, sRGB where some texture showing it is read as colour.
fn chains(all: &[Texture], image_of: &[usize], images: usize, srgb: &[bool]) -> Vec<Option<bool>> {
    let mut out = vec![None; images];
    for (i, t) in all.iter().enumerate() {
        if t.nearest {
            continue;
        }
        let c = srgb.get(i).copied().unwrap_or(false);
        let e = &mut out[image_of[i]];
        *e = Some(e.unwrap_or(false) || c);
    }
    out
}

/// The mip chain of each image where `chain_of` asks for one, built on as many threads as
/// the machine has (each takes the next image, largest first).
fn mip_chains(images: &[&Texture], chain_of: &[Option<bool>]) -> Vec<Vec<Texture>> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let mut order: Vec<usize> = (0..images.len())
        .filter(|&i| chain_of[i].is_some())
        .collect();
    order.sort_by_key(|&i| std::cmp::Reverse(images[i].texels.len()));
    let out: Vec<Mutex<Vec<Texture>>> = images.iter().map(|_| Mutex::new(Vec::new())).collect();
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map_or(1, std::num::NonZeroUsize::get)
        .min(order.len());
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                while let Some(&i) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let chain = images[i].mip_chain(chain_of[i].unwrap_or(false));
                    if let Ok(mut slot) = out[i].lock() {
                        *slot = chain;
                    }
                }
            });
        }
    });
    out.into_iter()
        .map(|m| m.into_inner().unwrap_or_default())
        .collect()
}

/// [`pack_atlas`], with a mip chain ([`Texture::mip_chain`]) for every image some texture
/// filters (not nearest) when `srgb` is given: per texture, whether a material reads it as
/// colour (its chain is then averaged in linear light). Each level is an image of its own
/// in the pages; its descriptor (after all the textures', one per texture and level: the
/// texture's flags, the level's place) is found from the texture's (`GpuTexDesc::mips`).
pub fn pack_atlas_with(all: &[Texture], srgb: Option<&[bool]>) -> TextureAtlas {
    if all.is_empty() {
        return TextureAtlas::default();
    }
    let (image_of, textures) = images(all);
    let chain_of = srgb.map_or_else(
        || vec![None; textures.len()],
        |s| chains(all, &image_of, textures.len(), s),
    );
    // The images, then each one's levels (image i's from `first_level[i]`).
    let levels = mip_chains(&textures, &chain_of);
    let mut sizes: Vec<(u32, u32)> = textures.iter().map(|t| (t.width, t.height)).collect();
    let mut first_level = Vec::with_capacity(levels.len());
    for l in &levels {
        first_level.push(sizes.len());
        sizes.extend(l.iter().map(|t| (t.width, t.height)));
    }
    let AtlasLayout { page, pages, place } = atlas_layout(&sizes);
    let page_texels = page as usize * page as usize;
    let mut texels = vec![0u32; page_texels * pages as usize];
    let every = textures.iter().copied().chain(levels.iter().flatten());
    let mut mip_bytes = 0u64;
    for (n, (t, &(x, y, p))) in every.zip(&place).enumerate() {
        if n >= textures.len() {
            mip_bytes += 4 * u64::from(t.width) * u64::from(t.height);
        }
        for row in 0..t.height as usize {
            let src = &t.texels[row * t.width as usize..(row + 1) * t.width as usize];
            let at = p as usize * page_texels + (y as usize + row) * page as usize + x as usize;
            for (d, s) in texels[at..at + src.len()].iter_mut().zip(src) {
                *d = u32::from_le_bytes(*s);
            }
        }
    }
    let place_of = |image: usize, w: u32, h: u32, flags: u32| {
        let (x, y, p) = place[image];
        [x | (y << 16), p, w | (h << 16), flags]
    };
    let mut descriptors: Vec<GpuTexDesc> = all
        .iter()
        .zip(&image_of)
        .map(|(t, &i)| GpuTexDesc {
            place: place_of(i, t.width, t.height, t.flags()),
            m: t.transform.m,
            offset: t.transform.offset,
            uv_set: t.uv_set.min(1),
            mips: 0,
        })
        .collect();
    for (k, (t, &i)) in all.iter().zip(&image_of).enumerate() {
        if t.nearest || levels[i].is_empty() {
            continue;
        }
        let n = u32::try_from(levels[i].len())
            .unwrap_or(u32::MAX)
            .min(MAX_MIP_LEVELS - 1);
        let first = u32::try_from(descriptors.len()).unwrap_or(u32::MAX);
        for (j, l) in levels[i].iter().take(n as usize).enumerate() {
            descriptors.push(GpuTexDesc {
                place: place_of(first_level[i] + j, l.width, l.height, t.flags()),
                ..GpuTexDesc::default()
            });
        }
        descriptors[k].place[3] |= n << TEX_MIPS_SHIFT;
        descriptors[k].mips = first;
    }
    TextureAtlas {
        page_size: page,
        pages,
        descriptors,
        texels,
        mip_bytes,
        textures: all.len(),
    }
}

/// The tangents of a triangle at its corners (xyz unit and orthogonal to the corner's
/// normal, w = ±1 the handedness), generated from the UV gradient when the source has none.
///
/// The triangle's tangent is dP/du (the direction in which U grows on its plane) and its
/// bitangent dP/dv, solved from the edges and their UV differences; at each corner the
/// tangent is made orthogonal to that corner's normal (Gram–Schmidt) and w is the sign that
/// makes `w · normal × tangent` point along dP/dv. One tangent per triangle, not averaged
/// over shared vertices (`MikkTSpace` would): a normal map baked against `MikkTSpace` tangents
/// shades with a small difference across curved, unevenly mapped surfaces. Without usable
/// UVs (zero UV area), any tangent orthogonal to the normal is returned, with w = 1.
pub fn triangle_tangents(positions: [Vec3; 3], normals: [Vec3; 3], uvs: [Vec2; 3]) -> [Vec4; 3] {
    let (e1, e2) = (positions[1] - positions[0], positions[2] - positions[0]);
    let (d1, d2) = (uvs[1] - uvs[0], uvs[2] - uvs[0]);
    let det = d1.x * d2.y - d2.x * d1.y;
    let (dpdu, dpdv) = if det.abs() > 1e-20 {
        ((e1 * d2.y - e2 * d1.y) / det, (e2 * d1.x - e1 * d2.x) / det)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    };
    normals.map(|n| {
        let t = dpdu - n * n.dot(dpdu);
        if t.is_finite() && t.length_squared() > 1e-12 * dpdu.length_squared() {
            let t = t.normalize();
            let w = if n.cross(t).dot(dpdv) < 0.0 {
                -1.0
            } else {
                1.0
            };
            t.extend(w)
        } else {
            n.any_orthonormal_vector().extend(1.0)
        }
    })
}
