// Sampling routines and numeric guards shared by the path tracer.

const PI: f32 = 3.14159265358979;
const INV_PI: f32 = 0.318309886183791;
const TWO_PI: f32 = 6.28318530717959;

// Orthonormal basis around unit n (Duff et al. 2017, branchless).
fn onb(n: vec3f) -> mat3x3f {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3f(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3f(b, s + n.y * n.y * a, -n.y);
    return mat3x3f(t, bt, n);
}

// Cosine-weighted direction about unit n; pdf = cos / pi.
fn sample_cosine(n: vec3f, u: vec2f) -> vec3f {
    let r = sqrt(u.x);
    let phi = TWO_PI * u.y;
    let local = vec3f(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
    return normalize(onb(n) * local);
}

// Uniform point on the unit disk (concentric map).
fn sample_disk(u: vec2f) -> vec2f {
    let a = 2.0 * u - 1.0;
    if a.x == 0.0 && a.y == 0.0 {
        return vec2f(0.0);
    }
    var r: f32;
    var phi: f32;
    if abs(a.x) > abs(a.y) {
        r = a.x;
        phi = (PI / 4.0) * (a.y / a.x);
    } else {
        r = a.y;
        phi = (PI / 2.0) - (PI / 4.0) * (a.x / a.y);
    }
    return r * vec2f(cos(phi), sin(phi));
}

// Barycentrics (b1, b2) of a uniform point on a triangle.
fn sample_triangle(u: vec2f) -> vec2f {
    let su = sqrt(u.x);
    return vec2f(1.0 - su, u.y * su);
}

// 1 - sqrt(1 - x) without cancellation for small x (tiny or distant spheres).
fn one_minus_sqrt_one_minus(x: f32) -> f32 {
    return x / (1.0 + sqrt(max(0.0, 1.0 - x)));
}

// Whether every component is finite; checks the exponent bits, so a compiler that assumes
// finite math cannot fold it away.
fn all_finite(v: vec3f) -> bool {
    let e = bitcast<vec3u>(v) & vec3u(0x7f800000u);
    return all(e != vec3u(0x7f800000u));
}

// Power heuristic (beta = 2) weight of strategy a against b.
fn mis_power(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    return select(0.0, a2 / (a2 + b2), a2 + b2 > 0.0);
}
