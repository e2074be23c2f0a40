// Texture sampling and textured materials, mirrored exactly by crates/scene/src/texture.rs.
// The includer declares `textures: texture_2d_array<f32>` (the atlas: every image of the
// scene placed whole in one of its RGBA8 pages, crates/scene/src/texture.rs `pack_atlas`) and
// `texture_descs: array<TexDesc>` (per texture: where its image is, its wrap and filter, and
// which coordinates it reads through which transform), and calls these only when
// HAS_TEXTURES.
//
// A point's coordinates come as one vec4f: set 0 (TEXCOORD_0) in xy, set 1 in zw. Each
// texture picks its set and maps it (KHR_texture_transform) before the lookup. Sampling is
// bilinear between the four texels around the point (texel centers at (i + 0.5) / size),
// each decoded from sRGB first when asked; or the nearest texel when the glTF sampler says
// NEAREST. UV (0, 0) is the image's top-left corner. Wrapping and filtering are done here,
// texel by texel (`textureLoad`), so no texel of a neighbour in the atlas is ever read.
//
// Mip levels (the scene's `texture_mips`): a texture's descriptor says how many levels its
// image has after level 0 (TEX_MIPS_SHIFT) and where their descriptors are (`mips`). Shading
// looks textures up at a level of detail (`tex_sample_lod`): a point's footprint `lod`, per
// UV set log2 of its width in that set's units (from the ray cone, integrator/surface.wgsl;
// from screen-space derivatives in the G-buffer), plus log2 of the texture's size through
// its transform, gives the level; the two levels around it are blended (trilinear). The
// any-hit alpha test reads level 0 (`tex_sample`), so cut-outs keep their full-resolution
// coverage.
// requires: var texture_descs, var textures (integrator/pathtrace.wgsl or gbuffer/gbuffer.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "common/color.wgsl"

const NO_TEX: u32 = 0xffffu;
const TEX_WRAP_REPEAT: u32 = 0u;
const TEX_WRAP_CLAMP: u32 = 1u;
const TEX_WRAP_MIRROR: u32 = 2u;
const TEX_NEAREST: u32 = 16u;
const TEX_MIPS_SHIFT: u32 = 8u;
// A footprint that reads level 0: no lod known (shapes, light samples).
const TEX_LOD_NONE: f32 = -1e30;

fn tex_wrap(i: i32, n: i32, mode: u32) -> i32 {
    if mode == TEX_WRAP_CLAMP {
        return clamp(i, 0, n - 1);
    }
    if mode == TEX_WRAP_MIRROR {
        let m = ((i % (2 * n)) + 2 * n) % (2 * n);
        return select(m, 2 * n - 1 - m, m >= n);
    }
    return ((i % n) + n) % n;
}

fn tex_fetch(d: vec4u, x: i32, y: i32, srgb: bool) -> vec4f {
    let xi = tex_wrap(x, i32(d.z & 0xffffu), d.w & 3u);
    let yi = tex_wrap(y, i32(d.z >> 16u), (d.w >> 2u) & 3u);
    let at = vec2i(i32(d.x & 0xffffu) + xi, i32(d.x >> 16u) + yi);
    let c = textureLoad(textures, at, i32(d.y), 0);
    if srgb {
        return vec4f(srgb_decode(c.rgb), c.a);
    }
    return c;
}

// The filtered texel of the image placed at `d` at `uv` in its own coordinates. The texels
// are fetched in a loop, one fetch in the code rather than five (see `textured_material`).
fn tex_filter(d: vec4u, uv: vec2f, srgb: bool) -> vec4f {
    let p = uv * vec2f(f32(d.z & 0xffffu), f32(d.z >> 16u));
    let nearest = (d.w & TEX_NEAREST) != 0u;
    let q = p - 0.5;
    let f = floor(q);
    let t = q - f;
    let i = select(vec2i(f), vec2i(floor(p)), nearest);
    // The rows' mixes as the texels come (no array: a driver may keep one in memory, per
    // lane): a = mix(c0, c1, t.x), b = mix(c2, c3, t.x).
    var a = vec4f(0.0);
    var b = vec4f(0.0);
    let n = select(4u, 1u, nearest);
    for (var k = 0u; k < n; k++) {
        let c = tex_fetch(d, i.x + i32(k & 1u), i.y + i32(k >> 1u), srgb);
        if k == 0u {
            a = c;
        } else if k == 1u {
            a = mix(a, c, t.x);
        } else if k == 2u {
            b = c;
        } else {
            b = mix(b, c, t.x);
        }
    }
    if nearest {
        return a;
    }
    return mix(a, b, t.y);
}

// Where texture `d` is looked up for a point with coordinates `uvs`: its set, transformed.
fn tex_uv(d: TexDesc, uvs: vec4f) -> vec2f {
    let uv = select(uvs.xy, uvs.zw, d.uv_set != 0u);
    return vec2f(d.m.x * uv.x + d.m.z * uv.y + d.offset.x, d.m.y * uv.x + d.m.w * uv.y + d.offset.y);
}

// The filtered texel of texture `id` for a point with coordinates `uvs`, at level 0.
fn tex_sample(id: u32, uvs: vec4f, srgb: bool) -> vec4f {
    let d = texture_descs[id];
    return tex_filter(d.place, tex_uv(d, uvs), srgb);
}

// The place of level `k` of texture `d` (0: its own place).
fn tex_level(d: TexDesc, k: u32) -> vec4u {
    if k == 0u {
        return d.place;
    }
    return texture_descs[d.mips + k - 1u].place;
}

// Log2 of the footprint's width in texels of level 0 of texture `d`: the point's footprint
// in its UV set, scaled by the texture's size and its transform's determinant.
fn tex_lod(d: TexDesc, lod: vec2f) -> f32 {
    let size = f32(d.place.z & 0xffffu) * f32(d.place.z >> 16u);
    let det = abs(d.m.x * d.m.w - d.m.z * d.m.y);
    return select(lod.x, lod.y, d.uv_set != 0u) + 0.5 * log2(size * det);
}

// The filtered texel of texture `id` for a point with coordinates `uvs` and footprint `lod`:
// level 0 alone (exactly `tex_sample`) where the texture has no mip levels, is looked up
// nearest, or the level of detail is not above 0; else the two levels around it, blended.
// One `tex_filter` in the code, in a loop over the levels (see `textured_material`).
fn tex_sample_lod(id: u32, uvs: vec4f, lod: vec2f, srgb: bool) -> vec4f {
    let d = texture_descs[id];
    let uv = tex_uv(d, uvs);
    let levels = (d.place.w >> TEX_MIPS_SHIFT) & 15u;
    let lambda = tex_lod(d, lod);
    var k = 0u;
    var f = 0.0;
    if levels > 0u && (d.place.w & TEX_NEAREST) == 0u && lambda > 0.0 {
        let l = min(lambda, f32(levels));
        k = u32(floor(l));
        f = l - floor(l);
    }
    let n = select(1u, 2u, f > 0.0);
    var c = vec4f(0.0);
    for (var i = 0u; i < n; i++) {
        c += select(1.0 - f, f, i == 1u) * tex_filter(tex_level(d, k + i), uv, srgb);
    }
    return c;
}

fn tex_lo(packed: u32) -> u32 {
    return packed & 0xffffu;
}

fn tex_hi(packed: u32) -> u32 {
    return packed >> 16u;
}

// Both UV sets at barycentrics (u, v) of a triangle (set 0 in xy, set 1 in zw).
fn tri_uv(tc: TriTexcoords, u: f32, v: f32) -> vec4f {
    let w = 1.0 - u - v;
    return vec4f(
        w * tc.uv01.xy + u * tc.uv01.zw + v * tc.uv2,
        w * tc.uv1_01.xy + u * tc.uv1_01.zw + v * tc.uv1_2,
    );
}

// A vertex colour (RGBA8, RGB sRGB-encoded) decoded as a texel is.
fn vertex_color(c: u32) -> vec4f {
    let v = vec4f(f32(c & 0xffu), f32((c >> 8u) & 0xffu), f32((c >> 16u) & 0xffu), f32(c >> 24u)) / 255.0;
    return vec4f(srgb_decode(v.rgb), v.a);
}

// The vertex colour at barycentrics (u, v) of a triangle (white where the mesh has none).
// Exactly white where all three corners are (the weights need not sum to 1 exactly).
fn tri_color(tc: TriTexcoords, u: f32, v: f32) -> vec4f {
    if all(tc.colors == vec3u(0xffffffffu)) {
        return vec4f(1.0);
    }
    return (1.0 - u - v) * vertex_color(tc.colors.x) + u * vertex_color(tc.colors.y) + v * vertex_color(tc.colors.z);
}

// Emission of `m` at `uv`: factor x texture (sRGB), at level 0 (a light sample: no cone).
fn textured_emission(m: Material, uv: vec4f) -> vec3f {
    let id = tex_lo(m.tex_emissive_normal);
    if id == NO_TEX {
        return m.emission;
    }
    return m.emission * tex_sample(id, uv, true).rgb;
}

// `m` with its textures and the vertex colour `color` applied at `uv` (footprint `lod`, see
// `tex_sample_lod`; emission at level 0): base color x texture
// (sRGB; alpha is the any-hit test's) x vertex colour, roughness x G and metallic x B of the
// metallic-roughness texture, emission x texture (sRGB), transmission x R of the
// transmission texture, specular x A of the specular texture, specular colour x the specular
// colour texture (sRGB), clear coat x R and its roughness x G of their textures, sheen colour x
// its texture (sRGB) and sheen roughness x A of its texture.
fn textured_material(m_in: Material, uv: vec4f, lod: vec2f, color: vec4f) -> Material {
    var m = m_in;
    m.base_color *= color.rgb;
    // One lookup in a loop over the material's texture slots rather than one per slot: a
    // driver inlines every call, and ten inlined bilinear lookups made up a third of the
    // path tracer's code, which the driver compiles before the first frame (seconds on a
    // CPU adapter). The slots are visited in the order the factors were once multiplied.
    for (var k = 0u; k < TEX_SLOTS; k++) {
        let id = tex_slot(m, k);
        if id == NO_TEX {
            continue;
        }
        // Emission at level 0, as light sampling reads it (`textured_emission`): the two
        // strategies MIS weighs must see one emitter, or the mix is neither.
        let footprint = select(lod, vec2f(TEX_LOD_NONE), k == 2u);
        let t = tex_sample_lod(id, uv, footprint, tex_slot_srgb(k));
        switch k {
            case 0u: { m.base_color *= t.rgb; }
            case 1u: {
                m.roughness *= t.g;
                m.metallic *= t.b;
            }
            case 2u: { m.emission *= t.rgb; }
            case 3u: { m.transmission *= t.r; }
            case 4u: { m.specular *= t.a; }
            case 5u: { m.specular_color *= t.rgb; }
            case 6u: { m.clearcoat *= t.r; }
            case 7u: { m.clearcoat_roughness *= t.g; }
            case 8u: { m.sheen_color *= t.rgb; }
            default: { m.sheen_roughness *= t.a; }
        }
    }
    return m;
}

// The texture slots `textured_material` applies, in its order: base colour, metallic-roughness,
// emission, transmission, specular, specular colour, clear coat, its roughness, sheen colour,
// sheen roughness.
const TEX_SLOTS: u32 = 10u;

fn tex_slot(m: Material, k: u32) -> u32 {
    switch k {
        case 0u: { return tex_lo(m.tex_base_mr); }
        case 1u: { return tex_hi(m.tex_base_mr); }
        case 2u: { return tex_lo(m.tex_emissive_normal); }
        case 3u: { return tex_lo(m.tex_transmission_specular); }
        case 4u: { return tex_hi(m.tex_transmission_specular); }
        case 5u: { return tex_lo(m.tex_specular_color); }
        case 6u: { return tex_lo(m.tex_coat); }
        case 7u: { return tex_hi(m.tex_coat); }
        case 8u: { return tex_lo(m.tex_sheen); }
        default: { return tex_hi(m.tex_sheen); }
    }
}

// Whether slot `k` of `tex_slot` holds colour (sRGB-encoded) rather than data.
fn tex_slot_srgb(k: u32) -> bool {
    return k == 0u || k == 2u || k == 5u || k == 8u;
}

// The shading normal with `m`'s normal map applied at `uv` (footprint `lod`; a level's
// averaged normal is renormalized here): the texel's xyz in [-1, 1],
// x and y scaled by `normal_scale`, in the frame (tangent, bitangent, ns) where the tangent
// is made orthogonal to ns and the bitangent is w * ns x tangent. Falls back to `ns` when the
// result is degenerate or faces away from the geometric normal `ng` (front side).
fn normal_mapped(m: Material, ns: vec3f, ng: vec3f, uv: vec4f, lod: vec2f, tangent: vec4f) -> vec3f {
    return normal_mapped_by(tex_hi(m.tex_emissive_normal), m.normal_scale, ns, ng, uv, lod, tangent);
}

// `normal_mapped` with the normal map `id` (none: NO_TEX) of scale `scale`: the base's, or
// the clear coat's.
fn normal_mapped_by(id: u32, scale: f32, ns: vec3f, ng: vec3f, uv: vec4f, lod: vec2f, tangent: vec4f) -> vec3f {
    if id == NO_TEX {
        return ns;
    }
    let t = tex_sample_lod(id, uv, lod, false).xyz * 2.0 - 1.0;
    let tn = vec3f(t.xy * scale, t.z);
    let tg = tangent.xyz - ns * dot(ns, tangent.xyz);
    if !(dot(tg, tg) > 0.0) {
        return ns;
    }
    let tu = normalize(tg);
    let bt = select(1.0, -1.0, tangent.w < 0.0) * cross(ns, tu);
    let n = tn.x * tu + tn.y * bt + tn.z * ns;
    let len2 = dot(n, n);
    if !(len2 > 0.0) || dot(n, ng) <= 0.0 {
        return ns;
    }
    return n / sqrt(len2);
}

// The interpolated tangent at barycentrics (u, v).
fn tri_tangent(tc: TriTexcoords, u: f32, v: f32) -> vec4f {
    return vec4f((1.0 - u - v) * tc.t0.xyz + u * tc.t1.xyz + v * tc.t2.xyz, tc.t0.w);
}

// The footprint (`tex_sample_lod`'s `lod`) of a ray cone `width` wide meeting a triangle whose
// placed edges are `e1`, `e2` at cosine `cos_theta` to its normal (Akenine-Moller et al. 2021,
// "Improved Shader and Texture Level of Detail Using Ray Cones", eq. 34 without the texture's
// size): per UV set, 0.5 log2(UV area / world area) + log2(width / |cos|). A footprint too
// small to measure, or a triangle without UV area in a set, gives a level below 0.
fn tri_lod(tc: TriTexcoords, e1: vec3f, e2: vec3f, width: f32, cos_theta: f32) -> vec2f {
    let world = length(cross(e1, e2));
    let a0 = tc.uv01.zw - tc.uv01.xy;
    let b0 = tc.uv2 - tc.uv01.xy;
    let a1 = tc.uv1_01.zw - tc.uv1_01.xy;
    let b1 = tc.uv1_2 - tc.uv1_01.xy;
    let uv_area = abs(vec2f(a0.x * b0.y - a0.y * b0.x, a1.x * b1.y - a1.y * b1.x));
    let w = width / max(abs(cos_theta), 1e-6);
    // The squared footprint in UV units; log2 of its square root.
    let r = clamp(uv_area / max(world, 1e-30) * (w * w), vec2f(1e-30), vec2f(1e30));
    return 0.5 * log2(r);
}
