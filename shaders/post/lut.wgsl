// LUT: each pixel's rgb, mapped from the LUT's domain to [0, 1] (clamped), looked up in the
// 3D LUT (red the fastest axis, as in .cube files) with trilinear or tetrahedral
// interpolation of its texels; alpha kept (crates/render/src/nodes/lut.rs has the CPU
// reference, tests/post/lut.rs compares them).

struct Params {
    size: u32,
    tetrahedral: u32,
    pad0: u32,
    pad1: u32,
    domain_min: vec4f,
    domain_max: vec4f,
}

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var lut: texture_3d<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var<uniform> params: Params;

fn at(base: vec3i, offset: vec3i) -> vec3f {
    return textureLoad(lut, base + offset, 0).rgb;
}

fn look_up(rgb: vec3f) -> vec3f {
    let n = f32(params.size - 1u);
    let span = params.domain_max.rgb - params.domain_min.rgb;
    let t = clamp((rgb - params.domain_min.rgb) / span, vec3f(0.0), vec3f(1.0)) * n;
    let i = min(vec3i(floor(t)), vec3i(i32(params.size) - 2));
    let f = t - vec3f(i);
    let c000 = at(i, vec3i(0, 0, 0));
    let c111 = at(i, vec3i(1, 1, 1));
    if params.tetrahedral == 0u {
        let c100 = at(i, vec3i(1, 0, 0));
        let c010 = at(i, vec3i(0, 1, 0));
        let c110 = at(i, vec3i(1, 1, 0));
        let c001 = at(i, vec3i(0, 0, 1));
        let c101 = at(i, vec3i(1, 0, 1));
        let c011 = at(i, vec3i(0, 1, 1));
        let x0 = mix(mix(c000, c100, f.x), mix(c010, c110, f.x), f.y);
        let x1 = mix(mix(c001, c101, f.x), mix(c011, c111, f.x), f.y);
        return mix(x0, x1, f.z);
    }
    // Tetrahedral: the tetrahedron of the cube's diagonal that holds f.
    if f.x > f.y {
        if f.y > f.z {
            return (1.0 - f.x) * c000 + (f.x - f.y) * at(i, vec3i(1, 0, 0)) + (f.y - f.z) * at(i, vec3i(1, 1, 0)) + f.z * c111;
        }
        if f.x > f.z {
            return (1.0 - f.x) * c000 + (f.x - f.z) * at(i, vec3i(1, 0, 0)) + (f.z - f.y) * at(i, vec3i(1, 0, 1)) + f.y * c111;
        }
        return (1.0 - f.z) * c000 + (f.z - f.x) * at(i, vec3i(0, 0, 1)) + (f.x - f.y) * at(i, vec3i(1, 0, 1)) + f.y * c111;
    }
    if f.z > f.y {
        return (1.0 - f.z) * c000 + (f.z - f.y) * at(i, vec3i(0, 0, 1)) + (f.y - f.x) * at(i, vec3i(0, 1, 1)) + f.x * c111;
    }
    if f.z > f.x {
        return (1.0 - f.y) * c000 + (f.y - f.z) * at(i, vec3i(0, 1, 0)) + (f.z - f.x) * at(i, vec3i(0, 1, 1)) + f.x * c111;
    }
    return (1.0 - f.y) * c000 + (f.y - f.x) * at(i, vec3i(0, 1, 0)) + (f.x - f.z) * at(i, vec3i(1, 1, 0)) + f.z * c111;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let c = textureLoad(input, id.xy, 0);
    textureStore(output, id.xy, vec4f(look_up(c.rgb), c.a));
}
