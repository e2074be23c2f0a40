// Crop: the output's pixel (x, y) is the input's (x + params.x, y + params.y); the size
// comes from the node's size rule (the CPU reference is in tests/post/effects.rs).
#import "post/filter_at.wgsl"

struct Params {
    x: i32,
    y: i32,
    width: i32,
    height: i32,
}

fn source_pixel(pixel: vec2u) -> vec2u {
    return pixel + vec2u(u32(params.x), u32(params.y));
}
