// Resize: bilinear through the sampler, or Lanczos-3 widened by 1/scale when shrinking,
// normalized, negative results clipped to 0 (the CPU reference is in tests/post/resize.rs).
// Pixel centers map to pixel centers: u_in = (x + 0.5) · in / out − 0.5.
#import "post/resample.wgsl"

struct Params {
    width: i32,
    height: i32,
    scale: f32,
    kernel: u32,
}

const KERNEL_BILINEAR: u32 = 0u;
const KERNEL_LANCZOS3: u32 = 1u;

const PI: f32 = 3.14159265358979;

fn sinc(x: f32) -> f32 {
    if abs(x) < 1e-6 {
        return 1.0;
    }
    let p = PI * x;
    return sin(p) / p;
}

fn lanczos3(x: f32) -> f32 {
    if abs(x) >= 3.0 {
        return 0.0;
    }
    return sinc(x) * sinc(x / 3.0);
}

fn resample_pixel(pixel: vec2u, out_size: vec2u, in_size: vec2u) -> vec4f {
    let ratio = vec2f(in_size) / vec2f(out_size);
    if params.kernel == KERNEL_BILINEAR {
        let uv = (vec2f(pixel) + 0.5) / vec2f(out_size);
        return textureSampleLevel(input, linear_clamp, uv, 0.0);
    }
    // Lanczos-3: kernel in input pixels, stretched by the shrink factor.
    let center = (vec2f(pixel) + 0.5) * ratio - 0.5;
    let stretch = max(ratio, vec2f(1.0));
    let radius = 3.0 * stretch;
    let lo = vec2i(floor(center - radius)) + 1;
    let hi = vec2i(floor(center + radius));
    let last = vec2i(in_size) - 1;
    var sum = vec4f(0.0);
    var weight = 0.0;
    for (var y = lo.y; y <= hi.y; y++) {
        let wy = lanczos3((f32(y) - center.y) / stretch.y);
        if wy == 0.0 {
            continue;
        }
        var row = vec4f(0.0);
        var row_weight = 0.0;
        for (var x = lo.x; x <= hi.x; x++) {
            let wx = lanczos3((f32(x) - center.x) / stretch.x);
            let p = clamp(vec2i(x, y), vec2i(0), last);
            row += wx * textureLoad(input, p, 0);
            row_weight += wx;
        }
        sum += wy * row;
        weight += wy * row_weight;
    }
    let c = sum / weight;
    return vec4f(max(c.rgb, vec3f(0.0)), c.a);
}
