// The random numbers of a path. With the Sobol sampler (the default) the 2D dimensions that
// matter most are padded Owen-scrambled Sobol points (common/sobol.wgsl): the pixel
// position, the lens position, and at the first hit the light sample's point and the BSDF
// sample's direction. Each of these pairs is Sobol dimensions 0 and 1 under a seed of its
// own, drawn from (pixel, seed, pair), so the pairs are independent of each other and of
// the neighbouring pixels, and each is stratified over the pixel's samples: every aligned
// block of 2^k samples, in particular the first 2^k, puts one point in each of the 2^k
// elementary intervals of the square. Every other number (light and lobe choices, later
// bounces, Russian roulette) comes from the PCG stream of (pixel, sample, seed), as it all
// does with the independent sampler. Sobol indices run in blocks of 2^16 samples; each
// block has a seed of its own.
//
// With two replicates (`PathTrace.replicates` 2), frames alternate between two independent
// replicates of these sequences (seeds of their own): even frames take their samples from
// the first, odd frames from the second, each replicate's samples in order. So the mean of
// the even frames and that of the odd ones are independent, each from stratified points,
// and Accumulate's variance from the two halves is right for Sobol points (the spread of
// the frames is not: stratified frames are negatively correlated). Any even number of
// frames of the same total then splits the samples the same way: 2 frames of 8 samples or
// 16 of 1 take the same points and numbers. With one (the default), every frame goes on
// with the one sequence: a little less noise, and no independent halves.
#import "common/rng.wgsl"
#import "common/sobol.wgsl"

const SAMPLER_SOBOL: u32 = 0u;
const SAMPLER_INDEPENDENT: u32 = 1u;

// The 2D dimensions drawn from Sobol points.
const PAIR_PIXEL: u32 = 0u;
const PAIR_LENS: u32 = 1u;
const PAIR_LIGHT: u32 = 2u;
const PAIR_BSDF: u32 = 3u;

var<private> sampler_sobol: bool;
// Index of the sample within its block of 2^16, and the block's seed for this pixel.
var<private> sampler_index: u32;
var<private> sampler_seed: u32;

// `sample` is the index of the pixel's sample over the whole render, `per_frame` the
// samples each frame takes, `replicates` 1 or 2.
fn sampler_init(pixel: u32, sample: u32, seed: u32, kind: u32, per_frame: u32, replicates: u32) {
    var index = sample;
    var stream = sample;
    var block = sample >> 16u;
    if replicates == 2u {
        let n = max(per_frame, 1u);
        let frame = sample / n;
        // The replicate, and the index within it.
        let replicate = frame & 1u;
        index = (frame >> 1u) * n + sample % n;
        // The PCG stream too is the replicate's sample's (the same as `sample` at one
        // sample a frame), so the frames' split does not change the numbers.
        stream = index * 2u + replicate;
        block = ((index >> 16u) << 1u) | replicate;
    }
    rng_init(pixel, stream, seed);
    sampler_sobol = kind == SAMPLER_SOBOL;
    sampler_index = index & 0xffffu;
    sampler_seed = pcg_hash(pixel ^ pcg_hash(block ^ pcg_hash(seed ^ 0x3c6ef372u)));
}

// The point of 2D dimension `pair` for this sample (Sobol), or the next two numbers of the
// PCG stream (independent).
fn sample_2d(pair: u32) -> vec2f {
    if !sampler_sobol {
        return rand2();
    }
    let seed = pcg_hash(sampler_seed + pair);
    return vec2f(sobol_owen(sampler_index, 0u, seed), sobol_owen(sampler_index, 1u, seed));
}

// `sample_2d(pair)` on the first bounce, the PCG stream after it.
fn sample_2d_at(pair: u32, bounce: u32) -> vec2f {
    if bounce == 0u {
        return sample_2d(pair);
    }
    return rand2();
}
