// RegressionDenoise, first pass: packs what the later passes read at every tap into two
// images, so that each tap costs two loads instead of five:
//
//   illumination = (color / max(albedo, EPS), variance / luminance(max(albedo, EPS))²)
//   features     = (normal, depth), with the pixel's kind (regression_common.wgsl)
//
// Classes: nothing hit (depth 0; passed through), surface, emitter (albedo alpha 2; depth
// stored negated), boundary (normal stored as 0): a surface pixel with an emitter among its
// 8 neighbors, or an emitter pixel with a non-emitter one. A boundary pixel's color is a
// blend of the light and what is around it (the G-buffer sees the pixel's center, the color
// the whole pixel), so it is passed through and no other pixel's fit uses it; otherwise the
// light's radiance spreads into a dark ceiling around the light (as docs/denoise.md tells
// of Denoise). Every input is loaded through `finite`, so NaN or Inf becomes 0.

@group(0) @binding(0) var color: texture_2d<f32>;
@group(0) @binding(1) var variance: texture_2d<f32>;
@group(0) @binding(2) var albedo: texture_2d<f32>;
@group(0) @binding(3) var normal: texture_2d<f32>;
@group(0) @binding(4) var depth: texture_2d<f32>;
@group(0) @binding(5) var illumination: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var features: texture_storage_2d<rgba32float, write>;

#import "post/regression_common.wgsl"

// Class before the boundary test.
fn raw_class(p: vec2i) -> u32 {
    if finite(textureLoad(depth, p, 0)).r <= 0.0 {
        return CLASS_MISS;
    }
    return select(CLASS_SURFACE, CLASS_EMITTER, finite(textureLoad(albedo, p, 0)).a > 1.5);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2i(textureDimensions(illumination));
    let p = vec2i(id.xy);
    if any(p >= size) {
        return;
    }
    let a = max(finite(textureLoad(albedo, p, 0)).rgb, vec3f(EPS));
    let la = max(luminance(a), EPS);
    let c = max(finite(textureLoad(color, p, 0)).rgb, vec3f(0.0)) / a;
    let v = max(finite(textureLoad(variance, p, 0)).a, 0.0) / (la * la);
    textureStore(illumination, p, finite(vec4f(c, v)));

    let kind = raw_class(p);
    var boundary = false;
    if kind != CLASS_MISS {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = p + vec2i(dx, dy);
                if all(q >= vec2i(0)) && all(q < size) {
                    let o = raw_class(q);
                    boundary = boundary || (kind == CLASS_SURFACE && o == CLASS_EMITTER)
                        || (kind == CLASS_EMITTER && o != CLASS_EMITTER);
                }
            }
        }
    }
    let z = max(finite(textureLoad(depth, p, 0)).r, 0.0);
    var n = finite(textureLoad(normal, p, 0)).xyz;
    // A hit's normal has length 1; one that does not cannot take part in the fit.
    if boundary || dot(n, n) < 0.25 {
        n = vec3f(0.0);
    }
    textureStore(features, p, vec4f(n, select(z, -z, kind == CLASS_EMITTER)));
}
