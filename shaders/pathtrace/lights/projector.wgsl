// The projector (crates/scene/src/lights/projector.rs), Mitsuba's `projector` with a
// constant irradiance: from `p0` along the unit axis `e1` (local z), with local x `e2`, it
// lights the pyramid |x| <= params.x z, |y| <= params.y z and sends a point at local depth z
// and distance d the radiance π E d / z³ (E = `emission`): a plane at depth 1 facing it
// receives a constant irradiance.
#import "pathtrace/scene_types.wgsl"
#import "common/sampling.wgsl"
#import "pathtrace/lights/sample.wgsl"

fn projector_light_sample(l: Light, x: vec3f) -> LightSample {
    var out = toward_point(l.p0, x);
    let v = x - l.p0;
    let z = dot(v, l.e1);
    let lx = dot(v, l.e2);
    let ly = dot(v, cross(l.e1, l.e2));
    if !(z > 0.0 && abs(lx) <= l.params.x * z && abs(ly) <= l.params.y * z) {
        out.pdf = 0.0;
        return out;
    }
    out.radiance = l.emission * (PI * out.dist / (z * z * z));
    return out;
}
