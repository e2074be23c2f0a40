// Random numbers: a PCG hash per (pixel, sample, seed) starts an independent stream, so a
// render is a pure function of the seed and the sample range: bit-identical on the same
// adapter, whatever the frame split.

const INV_2_24: f32 = 5.9604645e-8;

var<private> rng_state: u32;

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rng_init(pixel: u32, sample: u32, seed: u32) {
    rng_state = pcg_hash(pixel ^ pcg_hash(sample ^ pcg_hash(seed)));
}

// Uniform in [0, 1).
fn rand() -> f32 {
    rng_state = rng_state * 747796405u + 2891336453u;
    let s = rng_state;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return f32(((word >> 22u) ^ word) >> 8u) * INV_2_24;
}

fn rand2() -> vec2f {
    let a = rand();
    return vec2f(a, rand());
}
