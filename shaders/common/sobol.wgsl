// Owen-scrambled Sobol points (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)):
// the sample index is shuffled by a hash-based Owen scramble, the Sobol point of the shuffled
// index is computed from the direction vectors, and a second, per-dimension Owen scramble
// randomizes its digits. Bit for bit the `sobol_burley` crate's `sample(index, dimension,
// seed)` (Kuo-Joe direction numbers, Laine-Karras-style hash with the crate's constants) for
// index < 2^16 and the first four dimensions; `tests/sampler.rs` checks it on the GPU.
// `_rev` values have their bits reversed, as in the crate.

// Direction vectors of dimensions 0..3, 16 per dimension, bit-reversed (the 16 bits of a
// sample index reach the 16 most significant bits of the point).
const SOBOL_REV_DIRECTIONS = array<u32, 64>(
    // dimension 0 (van der Corput)
    0x00000001u, 0x00000002u, 0x00000004u, 0x00000008u,
    0x00000010u, 0x00000020u, 0x00000040u, 0x00000080u,
    0x00000100u, 0x00000200u, 0x00000400u, 0x00000800u,
    0x00001000u, 0x00002000u, 0x00004000u, 0x00008000u,
    // dimension 1
    0x00000001u, 0x00000003u, 0x00000005u, 0x0000000fu,
    0x00000011u, 0x00000033u, 0x00000055u, 0x000000ffu,
    0x00000101u, 0x00000303u, 0x00000505u, 0x00000f0fu,
    0x00001111u, 0x00003333u, 0x00005555u, 0x0000ffffu,
    // dimension 2
    0x00000001u, 0x00000003u, 0x00000006u, 0x00000009u,
    0x00000017u, 0x0000003au, 0x00000071u, 0x000000a3u,
    0x00000116u, 0x00000339u, 0x00000677u, 0x000009aau,
    0x00001601u, 0x00003903u, 0x00007706u, 0x0000aa09u,
    // dimension 3
    0x00000001u, 0x00000003u, 0x00000004u, 0x0000000au,
    0x0000001fu, 0x0000002eu, 0x00000045u, 0x000000c9u,
    0x0000011bu, 0x000002a4u, 0x0000079au, 0x00000b67u,
    0x0000101eu, 0x0000302du, 0x00004041u, 0x0000a0c3u,
);

const SOBOL_DIMENSIONS: u32 = 4u;

fn sobol_hash(x: u32) -> u32 {
    var n = x ^ 0xe6fe3bebu;
    n ^= n >> 16u;
    n *= 0x7feb352du;
    n ^= n >> 15u;
    n *= 0x846ca68bu;
    n ^= n >> 16u;
    return n;
}

// Nested uniform scramble of a bit-reversed value: each bit is flipped by a hash of the bits
// above it (in the reversed order: the less significant bits of the unreversed value).
fn owen_scramble_rev(x_rev: u32, scramble: u32) -> u32 {
    var n = x_rev;
    n ^= n * 0x3d20adeau;
    n += scramble;
    n *= (scramble >> 16u) | 1u;
    n ^= n * 0x05526c56u;
    n ^= n * 0x53a22864u;
    return n;
}

// The Sobol point of dimension `dim` for the index whose reversed bits are `index_rev`
// (its 16 least significant bits), bit-reversed.
fn sobol_rev(index_rev: u32, dim: u32) -> u32 {
    let index = reverseBits(index_rev) & 0xffffu;
    var sobol = 0u;
    for (var k = 0u; k < 16u; k++) {
        if ((index >> k) & 1u) != 0u {
            sobol ^= SOBOL_REV_DIRECTIONS[dim * 16u + k];
        }
    }
    return sobol;
}

// Point `index` (< 2^16) of the Owen-scrambled Sobol sequence `seed`, dimension `dim` (< 4),
// in [0, 1).
fn sobol_owen(index: u32, dim: u32, seed: u32) -> f32 {
    let shuffled_rev = owen_scramble_rev(reverseBits(index), sobol_hash(seed ^ 0x79c68e4au));
    let sobol = sobol_rev(shuffled_rev, min(dim, SOBOL_DIMENSIONS - 1u));
    var salt = 0x912f69bau;
    switch dim & 3u {
        case 1u: { salt = 0x174f18abu; }
        case 2u: { salt = 0x691e72cau; }
        case 3u: { salt = 0xb40cc1b8u; }
        default: {}
    }
    let scramble = (dim >> 2u) ^ (seed * 0x9c8f2d3bu) ^ salt;
    let bits = reverseBits(owen_scramble_rev(sobol, sobol_hash(scramble)));
    return bitcast<f32>((bits >> 9u) | 0x3f800000u) - 1.0;
}
