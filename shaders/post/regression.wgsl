// RegressionDenoise, third pass: per-pixel weighted first-order regression of the
// illumination (color / albedo) on the G-buffer's features, in the spirit of NFOR (Bitterli
// et al. 2016) and of weighted local regression (Moon et al. 2014).
//
// Around pixel p, the taps q of a (2 radius + 1)² window (every `stride`-th pixel) of p's
// kind (surface or emitter; see regression_prepare.wgsl) fit
//     y_q ≈ β0 + β · x_q,   x_q = (Δx / r, Δy / r, (z_q − z_p) / z_p, n_q − n_p, a_q − a_p)
// by weighted least squares, per color channel, and the output is the fit at p (x_p = 0),
// multiplied back by the albedo a_p. Diffuse lighting varies smoothly with the normal and
// the position, so the fit averages over a curved surface where an edge-stop on the normal
// would refuse to. The albedo term is for what demodulation leaves: where the reflectance
// is not albedo × lighting (a metal's Fresnel term whitens it at grazing angles, so
// color / albedo comes out larger on a texel of low albedo), the fit tells texels apart
// instead of averaging them. Weight of tap q:
//     w = exp(−2 |Δ|² / r²)                              spatial (σ = r / 2)
//       · exp(−max(1 − n_p·n_q, 0) / sigma_normal)       normal
//       · exp(−(e / (sigma_depth z_p))²)                 depth, e = z_q − z_p − ∇z·Δ
//       · exp(−max(d² − v, 0) / (sigma_color² v))        luminance, when sigma_color > 0:
//                                                        d = g_p − g_q, v = v_p + v_q of
//                                                        the guide (regression_guide.wgsl)
// and 0 for a tap of another kind.
//
// The system (9 features: position, normal and albedo, each a 3-vector whose sums are kept
// as 3×3 blocks) is solved centered on the weighted means (m, ȳ): (C + R) β = b with
// C = Σ w (x − m)(x − m)ᵀ, b = Σ w (x − m)(y − ȳ), and the fit at p is ȳ − β · m.
// R = ridge · diag(C) + 1e-7 Σw I: relative to each feature's own spread, so it does not
// depend on the features' units, and positive where a feature is constant over the window
// (a flat wall's normal), whose coefficient then comes out 0. A non-finite fit falls back
// to ȳ, a negative one to 0. Pixels where nothing was hit and boundary pixels pass through.

struct Params {
    radius: i32,
    stride: i32,
    guided: u32,
    sigma_normal: f32,
    sigma_depth: f32,
    sigma_color: f32,
    ridge: f32,
    pad: f32,
}

@group(0) @binding(0) var illumination: texture_2d<f32>;
@group(0) @binding(1) var features: texture_2d<f32>;
@group(0) @binding(2) var guide: texture_2d<f32>;
@group(0) @binding(3) var albedo: texture_2d<f32>;
@group(0) @binding(4) var dst: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var<uniform> params: Params;

#import "post/regression_common.wgsl"

// Features besides the constant.
const K: i32 = 9;

fn in_image(p: vec2i, size: vec2i) -> bool {
    return all(p >= vec2i(0)) && all(p < size);
}

// Depth at `p` when `p` is of kind `kind`, else 1e30.
fn same_class_depth(p: vec2i, size: vec2i, kind: u32) -> f32 {
    if !in_image(p, size) {
        return 1e30;
    }
    let f = textureLoad(features, p, 0);
    return select(1e30, abs(f.w), class_of(f) == kind);
}

// One-sided difference of smaller magnitude along each axis, within p's kind.
fn depth_gradient(p: vec2i, size: vec2i, z: f32, kind: u32) -> vec2f {
    var g = vec2f(0.0);
    for (var axis = 0; axis < 2; axis++) {
        let e = select(vec2i(0, 1), vec2i(1, 0), axis == 0);
        var best = 1e30;
        let f = same_class_depth(p + e, size, kind);
        if f < 1e29 {
            best = f - z;
        }
        let b = same_class_depth(p - e, size, kind);
        if b < 1e29 && abs(z - b) < abs(best) {
            best = z - b;
        }
        g[axis] = select(0.0, best, abs(best) < 1e29);
    }
    return g;
}

// Σ w a bᵀ's term: column k is a b_k.
fn outer(a: vec3f, b: vec3f) -> mat3x3f {
    return mat3x3f(a * b.x, a * b.y, a * b.z);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2i(textureDimensions(dst));
    let p = vec2i(id.xy);
    if !in_image(p, size) {
        return;
    }
    let a = max(finite(textureLoad(albedo, p, 0)).rgb, vec3f(EPS));
    let center = textureLoad(illumination, p, 0);
    let f_p = textureLoad(features, p, 0);
    let kind = class_of(f_p);
    if kind == CLASS_MISS || kind == CLASS_BOUNDARY {
        textureStore(dst, p, vec4f(center.rgb * a, 1.0));
        return;
    }
    let z_p = abs(f_p.w);
    let n_p = f_p.xyz;
    let grad = depth_gradient(p, size, z_p, kind);
    let g_p = textureLoad(guide, p, 0).xy;

    let r = max(params.radius, 1);
    let stride = max(params.stride, 1);
    let steps = r / stride;
    let inv_r = 1.0 / f32(r);
    let n_denom = max(params.sigma_normal, 1e-6);
    let z_denom = max(params.sigma_depth, 1e-6) * z_p + 1e-6;
    let guided = params.guided == 1u;
    let c2 = params.sigma_color * params.sigma_color;

    // Sums over the taps: of w, w x (position part x1 = (Δx/r, Δy/r, Δz/z), normal part
    // x2 = Δn, albedo part x3 = Δa), w y, w x xᵀ (blocks x_i x_jᵀ, i <= j) and w y xᵀ.
    var s = 0.0;
    var s1 = vec3f(0.0);
    var s2 = vec3f(0.0);
    var s3 = vec3f(0.0);
    var sy = vec3f(0.0);
    var s11 = mat3x3f();
    var s12 = mat3x3f();
    var s22 = mat3x3f();
    var s13 = mat3x3f();
    var s23 = mat3x3f();
    var s33 = mat3x3f();
    var sy3 = mat3x3f();
    var sy1 = mat3x3f();
    var sy2 = mat3x3f();
    for (var j = -steps; j <= steps; j++) {
        for (var i = -steps; i <= steps; i++) {
            let d = vec2i(i, j) * stride;
            let q = p + d;
            if !in_image(q, size) {
                continue;
            }
            let f_q = textureLoad(features, q, 0);
            if class_of(f_q) != kind {
                continue;
            }
            let y = textureLoad(illumination, q, 0).rgb;
            let a_q = max(finite(textureLoad(albedo, q, 0)).rgb, vec3f(EPS));
            let z_q = abs(f_q.w);
            let df = vec2f(d);
            let e = (z_q - z_p - dot(grad, df)) / z_denom;
            var arg = 2.0 * dot(df, df) * inv_r * inv_r;
            arg += max(1.0 - dot(n_p, f_q.xyz), 0.0) / n_denom;
            arg += e * e;
            if guided {
                let g_q = textureLoad(guide, q, 0).xy;
                let dl = g_p.x - g_q.x;
                let v = g_p.y + g_q.y;
                arg += max(dl * dl - v, 0.0) / (c2 * v + 1e-12);
            }
            let w = exp(-arg);
            let x1 = vec3f(df * inv_r, (z_q - z_p) / z_p);
            let x2 = f_q.xyz - n_p;
            let x3 = a_q - a;
            let w1 = w * x1;
            let w2 = w * x2;
            let w3 = w * x3;
            s += w;
            s1 += w1;
            s2 += w2;
            s3 += w3;
            sy += w * y;
            s11 += outer(w1, x1);
            s12 += outer(w1, x2);
            s22 += outer(w2, x2);
            s13 += outer(w1, x3);
            s23 += outer(w2, x3);
            s33 += outer(w3, x3);
            sy3 += outer(y, w3);
            sy1 += outer(y, w1);
            sy2 += outer(y, w2);
        }
    }

    // The center tap always counts (weight 1), so s >= 1.
    let mean_y = sy / s;
    var m: array<f32, K>;
    var b: array<vec3f, K>;
    for (var u = 0; u < 3; u++) {
        m[u] = s1[u] / s;
        m[u + 3] = s2[u] / s;
        m[u + 6] = s3[u] / s;
        b[u] = sy1[u];
        b[u + 3] = sy2[u];
        b[u + 6] = sy3[u];
    }
    // Centered, ridged normal equations (lower triangle of the row-major 9×9 `l`), factored
    // in place (Cholesky) and solved for the three channels at once.
    var l: array<f32, 81>;
    for (var u = 0; u < K; u++) {
        b[u] -= s * m[u] * mean_y;
        for (var v = 0; v <= u; v++) {
            // Σ w x_u x_v from the blocks: block (i, j), i <= j, holds Σ w x_i x_jᵀ with
            // column k for x_j's k-th component.
            let bu = u / 3;
            let bv = v / 3;
            let iu = u % 3;
            let iv = v % 3;
            var c: f32;
            switch bv * 3 + bu {
                case 0: { c = s11[iv][iu]; }
                case 1: { c = s12[iu][iv]; }
                case 2: { c = s13[iu][iv]; }
                case 4: { c = s22[iv][iu]; }
                case 5: { c = s23[iu][iv]; }
                default: { c = s33[iv][iu]; }
            }
            c -= s * m[u] * m[v];
            if u == v {
                c = max(c, 0.0) * (1.0 + params.ridge) + 1e-7 * s;
            }
            l[u * K + v] = c;
        }
    }
    for (var u = 0; u < K; u++) {
        var diag = l[u * K + u];
        for (var k = 0; k < u; k++) {
            diag -= l[u * K + k] * l[u * K + k];
        }
        let root = sqrt(max(diag, 1e-7 * s));
        l[u * K + u] = root;
        for (var v = u + 1; v < K; v++) {
            var c = l[v * K + u];
            for (var k = 0; k < u; k++) {
                c -= l[v * K + k] * l[u * K + k];
            }
            l[v * K + u] = c / root;
        }
    }
    // L z = b, then Lᵀ β = z (β over b).
    for (var u = 0; u < K; u++) {
        var c = b[u];
        for (var k = 0; k < u; k++) {
            c -= l[u * K + k] * b[k];
        }
        b[u] = c / l[u * K + u];
    }
    for (var u = K - 1; u >= 0; u--) {
        var c = b[u];
        for (var k = u + 1; k < K; k++) {
            c -= l[k * K + u] * b[k];
        }
        b[u] = c / l[u * K + u];
    }
    var fit = mean_y;
    for (var u = 0; u < K; u++) {
        fit -= b[u] * m[u];
    }
    let ok = finite(vec4f(fit, 1.0));
    fit = select(mean_y, fit, all(ok.rgb == fit));
    textureStore(dst, p, finite(vec4f(max(fit, vec3f(0.0)) * a, 1.0)));
}
