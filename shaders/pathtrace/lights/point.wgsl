// The point light (crates/scene/src/lights/point.rs): radiant intensity `emission` from
// `p0`, the same in every direction.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/lights/sample.wgsl"

fn point_light_sample(l: Light, x: vec3f) -> LightSample {
    var out = toward_point(l.p0, x);
    let d = l.p0 - x;
    out.radiance = l.emission * (1.0 / dot(d, d));
    return out;
}
