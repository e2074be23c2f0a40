// The energy-preserving Oren-Nayar diffuse BRDF (EON: Portsmouth, Kutz and Hill, "EON: A
// practical energy-preserving rough diffuse BRDF", JCGT 14(1), 2025; OpenPBR's diffuse base
// with `base_diffuse_roughness`), for roughness r in (0, 1]:
//   f = f_ss + f_ms,
//   f_ss = rho/pi A (1 + r s/t): Fujii's Oren-Nayar (FON), A = 1/(1 + c1 r), c1 = 1/2 - 2/(3 pi),
//          s = wi.wo - mu_i mu_o, s/t = s / max(mu_i, mu_o) where s > 0, else s;
//   f_ms = rho_ms/pi (1 - E(mu_o))(1 - E(mu_i)) / (1 - E_avg): the energy FON loses, given
//          back as Kulla-Conty do, with E the exact directional albedo of f_ss at rho = 1
//          (closed form, `eon_fon_albedo`), E_avg = A (1 + c2 r), c2 = 2/3 - 28/(15 pi), and
//          rho_ms = rho^2 E_avg / (1 - rho (1 - E_avg)).
// With rho = 1 it reflects everything from every direction (reciprocal, white furnace white).
// Sampling: the paper's clipped linearly transformed cosine (CLTC) fitted to f_ss, mixed with
// uniform hemisphere sampling for the flatter f_ms (`eon_sample`, `eon_pdf`).
// Vectors are in the shading frame (normal = +z), both above the surface.
#import "common/sampling.wgsl"

const EON_C1: f32 = 0.5 - 2.0 / (3.0 * PI);
const EON_C2: f32 = 2.0 / 3.0 - 28.0 / (15.0 * PI);

// Directional albedo of the FON lobe with rho = 1 at view cosine mu, exact:
// A (1 + r/pi G(mu)), G = sin(acos(mu) - sin mu) + 2/3 (sin/mu (1 - sin^3) - sin),
// with sin/mu (1 - sin^3) written as sin mu (1 + sin + sin^2) / (1 + sin) (no 0/0 at
// grazing, no cancellation near it).
fn eon_fon_albedo(mu: f32, r: f32) -> f32 {
    let c = clamp(mu, 0.0, 1.0);
    let s = sqrt(max(1.0 - c * c, 0.0));
    let g = s * (acos(c) - s * c) + (2.0 / 3.0) * (s * c * (1.0 + s + s * s) / (1.0 + s) - s);
    return (1.0 + r * INV_PI * g) / (1.0 + EON_C1 * r);
}

// f (not times cos) of EON with single-scattering albedo rho and roughness r.
fn eon_f(rho: vec3f, r: f32, wo: vec3f, wi: vec3f) -> vec3f {
    let s = dot(wi, wo) - wi.z * wo.z;
    let s_over_t = select(s, s / max(wi.z, wo.z), s > 0.0);
    let a = 1.0 / (1.0 + EON_C1 * r);
    let f_ss = rho * (INV_PI * a * (1.0 + r * s_over_t));
    let e_avg = a * (1.0 + EON_C2 * r);
    let rho_ms = rho * rho * e_avg / (1.0 - rho * (1.0 - e_avg));
    let eps = 1e-7;
    let ms = max(1.0 - eon_fon_albedo(wo.z, r), eps) * max(1.0 - eon_fon_albedo(wi.z, r), eps)
        / max(1.0 - e_avg, eps);
    return f_ss + rho_ms * (INV_PI * ms);
}

// The LTC matrix M = ((a, 0, b), (0, c, 0), (d, 0, 1)) (rows) fitted to f_ss seen from view
// cosine mu, in the frame whose x axis is wo's direction in the tangent plane (the paper's
// fit, section 5).
fn eon_ltc(mu: f32, r: f32) -> vec4f {
    let a = 1.0 + r * (0.303392 + (-0.518982 + 0.111709 * mu) * mu + (-0.276266 + 0.335918 * mu) * r);
    let b = r * (-1.16407 + 1.15859 * mu + (0.150815 - 0.150105 * mu) * r) / (mu * mu * mu - 1.43545);
    let c = 1.0 + (0.20013 + (-0.506373 + 0.261777 * mu) * mu) * r;
    let d = ((0.540852 + (-1.01625 + 0.475392 * mu) * mu) * r) / (-1.0743 + mu * (0.0725628 + mu));
    return vec4f(a, b, c, d);
}

// Tangent x axis of the LTC frame: towards wo (any axis when wo is the normal).
fn eon_ltc_x(wo: vec3f) -> vec2f {
    let l2 = dot(wo.xy, wo.xy);
    return select(vec2f(1.0, 0.0), wo.xy * inverseSqrt(l2), l2 > 0.0);
}

// Share of uniform hemisphere samples (the rest CLTC), the paper's fit.
fn eon_uniform_prob(mu: f32, r: f32) -> f32 {
    return pow(r, 0.1) * (0.162925 + mu * (-0.372058 + (0.538233 - 0.290822 * mu) * mu));
}

// Density of CLTC samples at wi: the cosine density of M^-1 wi over the part of the disk
// that M maps above the surface (a fraction (1 + 1/sqrt(1 + d^2)) / 2 of it), times the
// Jacobian |M^-1| / |M^-1 wi|^3, written with adj(M) = |M| M^-1.
fn eon_cltc_pdf(wo: vec3f, wi: vec3f, r: f32) -> f32 {
    let x = eon_ltc_x(wo);
    let w = vec3f(x.x * wi.x + x.y * wi.y, x.x * wi.y - x.y * wi.x, wi.z);
    let m = eon_ltc(wo.z, r);
    let det = m.z * (m.x - m.y * m.w);
    let h = vec3f(m.z * (w.x - m.y * w.z), (m.x - m.y * m.w) * w.y, m.z * (m.x * w.z - m.w * w.x));
    let len2 = dot(h, h);
    let clip = 0.5 * (1.0 + inverseSqrt(m.w * m.w + 1.0));
    let q = det / len2;
    return q * q * max(h.z, 0.0) / (PI * clip);
}

fn eon_pdf(wo: vec3f, wi: vec3f, r: f32) -> f32 {
    let pu = eon_uniform_prob(wo.z, r);
    return pu * (0.5 * INV_PI) + (1.0 - pu) * eon_cltc_pdf(wo, wi, r);
}

// A direction drawn with density `eon_pdf`.
fn eon_sample(wo: vec3f, r: f32, u: vec2f) -> vec3f {
    let pu = eon_uniform_prob(wo.z, r);
    if u.x < pu {
        // Uniform over the hemisphere.
        let z = u.x / pu;
        let s = sqrt(max(1.0 - z * z, 0.0));
        let phi = TWO_PI * u.y;
        return vec3f(s * cos(phi), s * sin(phi), z);
    }
    // A point of the clipped unit disk, uniform in area (its cosine-distributed direction),
    // then mapped by M and turned into the shading frame.
    let v = (u.x - pu) / (1.0 - pu);
    let m = eon_ltc(wo.z, r);
    let rad = sqrt(v);
    let phi = TWO_PI * u.y;
    let y = rad * sin(phi);
    let clip = 0.5 * (1.0 + inverseSqrt(m.w * m.w + 1.0));
    let x = -mix(sqrt(max(1.0 - y * y, 0.0)), rad * cos(phi), clip);
    let h = vec3f(x, y, sqrt(max(1.0 - x * x - y * y, 0.0)));
    let w = vec3f(m.x * h.x + m.y * h.z, m.z * h.y, m.w * h.x + h.z);
    let xa = eon_ltc_x(wo);
    return normalize(vec3f(xa.x * w.x - xa.y * w.y, xa.y * w.x + xa.x * w.y, w.z));
}
