// White balance: the image's white (a color temperature on the Planckian locus, moved
// along the isotherm by `tint`) adapted with the Bradford transform to the locus's white
// at 6504 K (so the defaults change nothing), in linear Rec.709 / sRGB primaries (the CPU
// reference is in tests/post/grade.rs).
#import "post/filter.wgsl"

struct Params {
    temperature: f32,
    tint: f32,
}

// A rational function (n0 + n1 t + n2 t²) / (1 + d1 t + d2 t²) and its derivative in t.
fn rational(t: f32, n: vec3f, d: vec2f) -> vec2f {
    let num = n.x + n.y * t + n.z * t * t;
    let den = 1.0 + d.x * t + d.y * t * t;
    let dnum = n.y + 2.0 * n.z * t;
    let dden = d.x + 2.0 * d.y * t;
    return vec2f(num / den, (dnum * den - num * dden) / (den * den));
}

// XYZ (Y = 1) of the white at `t` kelvin on the Planckian locus (CIE 1960 u, v after
// Krystek 1985, 1000-15000 K), moved `tint` × 0.02 along the isotherm (the locus's
// normal: towards magenta for positive `tint`, green for negative, as photo editors do).
fn white_xyz(t: f32, tint: f32) -> vec3f {
    let u = rational(t, vec3f(0.860117757, 1.54118254e-4, 1.28641212e-7), vec2f(8.42420235e-4, 7.08145163e-7));
    let v = rational(t, vec3f(0.317398726, 4.22806245e-5, 4.20481691e-8), vec2f(-2.89741816e-5, 1.61456053e-7));
    let normal = normalize(vec2f(-v.y, u.y)); // v falls: towards magenta
    let p = vec2f(u.x, v.x) + 0.02 * tint * normal;
    let x = 3.0 * p.x / (2.0 * p.x - 8.0 * p.y + 4.0);
    let y = 2.0 * p.y / (2.0 * p.x - 8.0 * p.y + 4.0);
    return vec3f(x / y, 1.0, (1.0 - x - y) / y);
}

const RGB_TO_XYZ = mat3x3f(
    vec3f(0.4123908, 0.2126390, 0.0193308),
    vec3f(0.3575843, 0.7151687, 0.1191948),
    vec3f(0.1804808, 0.0721923, 0.9505322),
);
const XYZ_TO_RGB = mat3x3f(
    vec3f(3.2409699, -0.9692436, 0.0556301),
    vec3f(-1.5373832, 1.8759675, -0.2039770),
    vec3f(-0.4986108, 0.0415551, 1.0569715),
);
const BRADFORD = mat3x3f(
    vec3f(0.8951, -0.7502, 0.0389),
    vec3f(0.2664, 1.7135, -0.0685),
    vec3f(-0.1614, 0.0367, 1.0296),
);
const BRADFORD_INV = mat3x3f(
    vec3f(0.9869929, 0.4323053, -0.0085287),
    vec3f(-0.1470543, 0.5183603, 0.0400428),
    vec3f(0.1599627, 0.0492912, 0.9684867),
);

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let src = BRADFORD * white_xyz(params.temperature, params.tint);
    let dst = BRADFORD * white_xyz(6504.0, 0.0);
    let lms = BRADFORD * (RGB_TO_XYZ * c.rgb);
    let xyz = BRADFORD_INV * (lms * dst / src);
    return vec4f(XYZ_TO_RGB * xyz, c.a);
}
