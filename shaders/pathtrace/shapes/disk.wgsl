// The disk (crates/scene/src/shapes/disk.rs): `center`, `radius` and its front normal
// `axis`; flat and one-sided as a triangle is, lit by sampling its area uniformly.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/intersect/primitives.wgsl"
#import "common/sampling.wgsl"

// The hit in (0, t_max), or -1, of disk `prim` (its index | PRIM_SHAPE); a ray leaving it
// (`skip_prim`) cannot meet the flat disk again.
fn disk_intersect(prim: u32, s: Shape, ray: Ray, t_max: f32) -> f32 {
    let t = dot(s.axis, s.center - ray.origin) / dot(s.axis, ray.dir);
    let d = ray.origin + t * ray.dir - s.center;
    let hit = t > 0.0 && t < t_max && dot(d, d) <= s.radius * s.radius && prim != skip_prim;
    return select(-1.0, t, hit);
}

fn disk_normal(s: Shape, p: vec3f) -> vec3f {
    return s.axis;
}

// A uniform point of the disk (concentric map), as seen from `x`: its front side, or
// either where `two_sided`.
fn disk_sample(s: Shape, x: vec3f, u: vec2f, two_sided: bool) -> ShapeSample {
    var out = ShapeSample(vec3f(0.0), 0.0, vec2f(0.0), 0.0);
    let q = s.radius * sample_disk(u);
    let y = s.center + onb(s.axis) * vec3f(q, 0.0);
    let d = y - x;
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    let wi = d / dist;
    let cos_y = dot(s.axis, -wi);
    if !(cos_y > 0.0 || (two_sided && cos_y < 0.0)) {
        return out;
    }
    out.wi = wi;
    out.dist = dist;
    out.pdf = vec2f(dist2, PI * s.radius * s.radius * abs(cos_y));
    out.margin = 1e-4 * dist;
    return out;
}

fn disk_pdf(s: Shape, x: vec3f, y: vec3f) -> vec2f {
    let d = y - x;
    let dist2 = dot(d, d);
    let cos_y = abs(dot(s.axis, d)) / sqrt(dist2);
    return vec2f(dist2, PI * s.radius * s.radius * cos_y);
}
