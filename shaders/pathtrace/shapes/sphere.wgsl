// The sphere (crates/scene/src/shapes/sphere.rs): `center` and `radius`, seen from outside,
// lit by sampling the cone it subtends.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/intersect/primitives.wgsl"
#import "common/sampling.wgsl"

// Both roots (near, far) of ray/sphere in the robust form of Ray Tracing Gems, ch. 7; (-1, -1)
// when the ray misses.
fn sphere_roots(origin: vec3<f32>, dir: vec3<f32>, center: vec3<f32>, radius: f32) -> vec2<f32> {
    let f = origin - center;
    let a = dot(dir, dir);
    let b = -dot(f, dir);
    let l = f + (b / a) * dir;
    let disc = a * (radius * radius - dot(l, l));
    // Selected, not returned early: llvmpipe runs an if's body anyway (see intersect_triangle).
    let c = dot(f, f) - radius * radius;
    let root = sqrt(disc);
    let q = b + select(root, -root, b < 0.0);
    let t0 = c / q;
    let t1 = q / a;
    return select(vec2<f32>(-1.0), vec2<f32>(min(t0, t1), max(t0, t1)), disc >= 0.0);
}

// The first of the roots `r` (near, far) in (0, t_max), or -1.
fn nearest_root(r: vec2<f32>, t_max: f32) -> f32 {
    return select(select(-1.0, r.y, r.y > 0.0 && r.y < t_max), r.x, r.x > 0.0 && r.x < t_max);
}

// The nearest hit in (0, t_max), or -1, of sphere `prim` (its index | PRIM_SHAPE) by a ray
// that may be the one leaving it (`skip_prim`, from its surface, not offset): going out, it
// cannot meet that convex sphere again; going in (`skip_inward`), only at the far root, the
// near one being its own origin whichever side of the surface rounding put that.
fn sphere_intersect(prim: u32, s: Shape, ray: Ray, t_max: f32) -> f32 {
    let r = sphere_roots(ray.origin, ray.dir, s.center, s.radius);
    let own = select(-1.0, r.y, skip_inward && r.y > 0.0 && r.y < t_max);
    return select(own, nearest_root(r, t_max), prim != skip_prim);
}

fn sphere_normal(s: Shape, p: vec3f) -> vec3f {
    return normalize(p - s.center);
}

// A uniform direction in the cone the sphere subtends from `x` (nothing from inside it),
// the distance to its near side along it.
fn sphere_sample(s: Shape, x: vec3f, u: vec2f, two_sided: bool) -> ShapeSample {
    var out = ShapeSample(vec3f(0.0), 0.0, vec2f(0.0), 0.0);
    let r = s.radius;
    let to_c = s.center - x;
    let d2 = dot(to_c, to_c);
    if d2 <= r * r {
        return out;
    }
    let d = sqrt(d2);
    let cone = one_minus_sqrt_one_minus(r * r / d2);
    let cos_t = 1.0 - u.x * cone;
    let sin_t = sqrt(max(0.0, (1.0 - cos_t) * (1.0 + cos_t)));
    let phi = TWO_PI * u.y;
    let axis = to_c / d;
    let wi = normalize(onb(axis) * vec3f(sin_t * cos(phi), sin_t * sin(phi), cos_t));
    // Distance to the near intersection with the sphere.
    let b = dot(to_c, wi);
    let h = to_c - b * wi;
    let dist = b - sqrt(max(0.0, r * r - dot(h, h)));
    out.wi = wi;
    out.dist = dist;
    out.pdf = vec2f(1.0, TWO_PI * cone);
    out.margin = 1e-4 * dist;
    return out;
}

fn sphere_pdf(s: Shape, x: vec3f, y: vec3f) -> vec2f {
    let r = s.radius;
    let q = min(1.0, r * r / dot(s.center - x, s.center - x));
    let cone = one_minus_sqrt_one_minus(q);
    return vec2f(1.0, TWO_PI * cone);
}
