// The spot light (crates/scene/src/lights/spot.rs): radiant intensity `emission` from `p0`
// along the unit axis `e1`, full within the beam width `params.y` and linear in angle to 0
// at the cutoff `params.x` (half-angles, radians), as Mitsuba's `spot`.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/lights/sample.wgsl"

fn spot_light_sample(l: Light, x: vec3f) -> LightSample {
    var out = toward_point(l.p0, x);
    let theta = acos(clamp(dot(-out.wi, l.e1), -1.0, 1.0));
    let falloff = clamp((l.params.x - theta) / max(l.params.x - l.params.y, 1e-12), 0.0, 1.0);
    let d = l.p0 - x;
    out.radiance = l.emission * (falloff / dot(d, d));
    return out;
}
