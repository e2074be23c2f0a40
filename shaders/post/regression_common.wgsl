// Helpers shared by RegressionDenoise's passes.
#import "common/color.wgsl"

// Floor of the albedo the color is divided by (as Denoise's).
const EPS: f32 = 1e-3;

// Pixel classes. The preparation pass stores them in its `features` image (normal, depth):
// depth 0 where nothing was hit, depth negated on emitters (albedo alpha 2, as GBuffer
// writes it), and the normal zeroed on boundary pixels (regression_prepare.wgsl).
const CLASS_MISS: u32 = 0u;
const CLASS_SURFACE: u32 = 1u;
const CLASS_EMITTER: u32 = 2u;
const CLASS_BOUNDARY: u32 = 3u;

fn class_of(features: vec4f) -> u32 {
    if features.w == 0.0 {
        return CLASS_MISS;
    }
    if dot(features.xyz, features.xyz) < 0.25 {
        return CLASS_BOUNDARY;
    }
    return select(CLASS_SURFACE, CLASS_EMITTER, features.w < 0.0);
}

// `v` with every non-finite component replaced by 0 (exponent bits, so a compiler that
// assumes finite math cannot fold the test away).
fn finite(v: vec4f) -> vec4f {
    let e = bitcast<vec4u>(v) & vec4u(0x7f800000u);
    return select(vec4f(0.0), v, e != vec4u(0x7f800000u));
}
