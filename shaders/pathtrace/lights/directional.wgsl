// The directional light (crates/scene/src/lights/directional.rs): irradiance `emission`
// travelling along the unit `e1`, from infinitely far away.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/intersect/primitives.wgsl"
#import "pathtrace/lights/sample.wgsl"

fn directional_light_sample(l: Light, x: vec3f) -> LightSample {
    return LightSample(-l.e1, F32_MAX, l.emission, 1.0, 0.0, true);
}
