// Tone curves: linear scene color in, linear display color in [0, 1] out.
// Mirrored in crates/render/src/cpu.rs; the operator numbers follow the registry's order.
#import "common/color.wgsl"

const TONEMAP_CLAMP: u32 = 0u;
const TONEMAP_REINHARD: u32 = 1u;
const TONEMAP_ACES: u32 = 2u;
const TONEMAP_AGX: u32 = 3u;
const TONEMAP_PBR_NEUTRAL: u32 = 4u;

// Extended Reinhard on luminance: `white` maps to 1, hue kept.
fn tonemap_reinhard(c: vec3f, white: f32) -> vec3f {
    let l = luminance(c);
    if l <= 0.0 {
        return vec3f(0.0);
    }
    let ld = l * (1.0 + l / (white * white)) / (1.0 + l);
    return c * (ld / l);
}

// ACES filmic, Stephen Hill's fit of the RRT + sRGB ODT. Matrices are written row by row,
// so they are applied as `v * M`.
fn tonemap_aces(c: vec3f) -> vec3f {
    let input_mat = mat3x3f(
        vec3f(0.59719, 0.35458, 0.04823),
        vec3f(0.07600, 0.90834, 0.01566),
        vec3f(0.02840, 0.13383, 0.83777),
    );
    let output_mat = mat3x3f(
        vec3f(1.60475, -0.53108, -0.07367),
        vec3f(-0.10208, 1.10813, -0.00605),
        vec3f(-0.00327, -0.07276, 1.07602),
    );
    let v = c * input_mat;
    let a = v * (v + 0.0245786) - 0.000090537;
    let b = v * (0.983729 * v + 0.4329510) + 0.238081;
    return (a / b) * output_mat;
}

// AgX base (Troy Sobotka), with Benjamin Wrensch's 6th-order fit of the contrast curve.
// Matrices are column-major, applied as `M * v`.
fn agx_contrast(x: vec3f) -> vec3f {
    let x2 = x * x;
    let x4 = x2 * x2;
    return 15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.00232;
}

fn tonemap_agx(c: vec3f) -> vec3f {
    let inset = mat3x3f(
        vec3f(0.842479062253094, 0.0423282422610123, 0.0423756549057051),
        vec3f(0.0784335999999992, 0.878468636469772, 0.0784336),
        vec3f(0.0792237451477643, 0.0791661274605434, 0.879142973793104),
    );
    let outset = mat3x3f(
        vec3f(1.19687900512017, -0.0528968517574562, -0.0529716355144438),
        vec3f(-0.0980208811401368, 1.15190312990417, -0.0980434501171241),
        vec3f(-0.0990297440797205, -0.0989611768448433, 1.15107367264116),
    );
    let min_ev = -12.47393;
    let max_ev = 4.026069;
    var v = inset * max(c, vec3f(1e-10));
    v = clamp(log2(max(v, vec3f(1e-10))), vec3f(min_ev), vec3f(max_ev));
    v = (v - min_ev) / (max_ev - min_ev);
    v = agx_contrast(v);
    v = outset * v;
    return pow(max(v, vec3f(0.0)), vec3f(2.2));
}

// Khronos PBR Neutral.
fn tonemap_pbr_neutral(c_in: vec3f) -> vec3f {
    let start = 0.8 - 0.04;
    let desaturation = 0.15;
    var c = c_in;
    let x = min(c.r, min(c.g, c.b));
    let offset = select(0.04, x - 6.25 * x * x, x < 0.08);
    c -= offset;
    let peak = max(c.r, max(c.g, c.b));
    if peak < start {
        return c;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    c *= new_peak / peak;
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(c, vec3f(new_peak), g);
}

fn tonemap(c_in: vec3f, op: u32, white: f32) -> vec3f {
    let c = max(c_in, vec3f(0.0));
    var out: vec3f;
    switch op {
        case 1u: { out = tonemap_reinhard(c, white); }
        case 2u: { out = tonemap_aces(c); }
        case 3u: { out = tonemap_agx(c); }
        case 4u: { out = tonemap_pbr_neutral(c); }
        default: { out = c; }
    }
    return clamp(out, vec3f(0.0), vec3f(1.0));
}
