// RegressionDenoise, second pass: the guide its luminance weight compares, the mean
// luminance of the illumination over the pixels of the same kind in the 5×5 window around
// each pixel and the variance of that mean: (mean, variance, 0, 0). A box mean of n pixels
// has 1/n of a pixel's variance, so the weight can tell a shadow's edge from noise where
// single pixels cannot (NFOR compares patches for the same reason).

@group(0) @binding(0) var illumination: texture_2d<f32>;
@group(0) @binding(1) var features: texture_2d<f32>;
@group(0) @binding(2) var guide: texture_storage_2d<rgba32float, write>;

#import "post/regression_common.wgsl"

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2i(textureDimensions(guide));
    let p = vec2i(id.xy);
    if any(p >= size) {
        return;
    }
    let kind = class_of(textureLoad(features, p, 0));
    var sum = 0.0;
    var var_sum = 0.0;
    var n = 0.0;
    if kind == CLASS_SURFACE || kind == CLASS_EMITTER {
        for (var dy = -2; dy <= 2; dy++) {
            for (var dx = -2; dx <= 2; dx++) {
                let q = p + vec2i(dx, dy);
                if all(q >= vec2i(0)) && all(q < size)
                    && class_of(textureLoad(features, q, 0)) == kind {
                    let d = textureLoad(illumination, q, 0);
                    sum += luminance(d.rgb);
                    var_sum += d.a;
                    n += 1.0;
                }
            }
        }
    }
    n = max(n, 1.0);
    textureStore(guide, p, finite(vec4f(sum / n, var_sum / (n * n), 0.0, 0.0)));
}
