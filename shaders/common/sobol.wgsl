// Owen-scrambled Sobol points (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)):
// the sample index is shuffled by a hash-based Owen scramble, the Sobol point of the shuffled
// index is computed from the direction vectors, and a second, per-dimension Owen scramble
// randomizes its digits. Bit for bit the `sobol_burley` crate's `sample(index, dimension,
// seed)` (Joe and Kuo direction numbers, Laine-Karras-style hash with the crate's constants) for
// index < 2^16 and the first four dimensions; `tests/light_transport/sampler.rs` checks it on the GPU.
// `_rev` values have their bits reversed, as in the crate.

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

// The Sobol point of dimension `dim` (< 4) for the index whose reversed bits are
// `index_rev` (its 16 least significant bits), bit-reversed. The direction vectors come from
// their recurrences (Joe and Kuo's numbers, as the crate builds them), bit-reversed:
// dimension 0 is the van der Corput sequence; 1 is x + 1 (m = 1); 2 is x^2 + x + 1
// (m = 1, 3); 3 is x^3 + x + 1 (m = 1, 3, 1). Dimension d > 0 has degree d, so its first d
// vectors are the m values. (A table indexed at run time compiled to a copy of the whole
// table per lookup on Mesa: 30x slower.)
fn sobol_rev(index_rev: u32, dim: u32) -> u32 {
    let index = reverseBits(index_rev) & 0xffffu;
    if dim == 0u {
        return index;
    }
    if dim == 1u {
        // Direction vector k of dimension 1 is row k of Pascal's triangle mod 2, whose bit j
        // is set where j's bits are a subset of k's (Lucas), so bit j of the point is the
        // parity of the index's bits at the supersets of j: that sum over the 4-bit
        // positions, one position bit at a time (4 steps, where the loop below takes one
        // step per index bit, 16 for most indices). The same integer.
        var x = index;
        x ^= (x >> 1u) & 0x5555u;
        x ^= (x >> 2u) & 0x3333u;
        x ^= (x >> 4u) & 0x0f0fu;
        x ^= (x >> 8u) & 0x00ffu;
        return x;
    }
    var sobol = 0u;
    // The previous three direction vectors.
    var h1 = 0u;
    var h2 = 0u;
    var h3 = 0u;
    for (var k = 0u; (index >> k) != 0u; k++) {
        var v: u32;
        if k < dim {
            v = select(select(4u, 3u, k == 1u), 1u, k == 0u);
        } else if dim == 1u {
            v = h1 ^ (h1 << 1u);
        } else if dim == 2u {
            v = h2 ^ (h2 << 2u) ^ h1;
        } else {
            v = h3 ^ (h3 << 3u) ^ h2;
        }
        if ((index >> k) & 1u) != 0u {
            sobol ^= v;
        }
        h3 = h2;
        h2 = h1;
        h1 = v;
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
