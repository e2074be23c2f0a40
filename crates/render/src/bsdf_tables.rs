//! GGX albedo tables, computed here (not copied from anywhere) and uploaded for the path
//! tracer's material model (`shaders/pathtrace/bsdf.wgsl`).
//!
//! With Schlick's Fresnel `F = F0 + (1 − F0)(1 − c)^5`, the directional albedo of a GGX
//! reflection lobe is linear in `F0`: `E(μ) = F0·A(μ, r) + B(μ, r)`, where
//! `A = ∫ f(F=1) (1 − (1 − c)^5) cos` and `B = ∫ f(F=1) (1 − c)^5 cos` over the hemisphere.
//! One table of `(A, B)` over view cosine `μ` and roughness `r` (α = r²) serves both the
//! dielectric layer (its Lambertian base receives exactly `1 − E`) and the metal's
//! Kulla–Conty multiple-scattering term (which needs `E` at F0 = 1 and its average).
//!
//! Entries are estimated with stratified visible-normal sampling, in f64, exactly the
//! estimator the shader's sampling uses, so the furnace balance holds to the table's
//! accuracy; the averages integrate the table's own piecewise-linear interpolant exactly,
//! so the compensation terms balance the interpolated table.

use std::f64::consts::PI;
use std::sync::LazyLock;

/// Table size along each axis.
pub const N: usize = 32;
/// Below this α a lobe is a perfect mirror (as `ALPHA_MIN` in the shader).
pub const ALPHA_MIN: f64 = 1e-3;
/// Strata per axis when estimating one entry.
const STRATA: usize = 48;

fn smith_term(z: f64, a2: f64) -> f64 {
    (a2 + (1.0 - a2) * z * z).sqrt()
}

fn vndf(wo: [f64; 3], alpha: f64, u: [f64; 2]) -> [f64; 3] {
    let v = normalize([wo[0] * alpha, wo[1] * alpha, wo[2]]);
    let phi = 2.0 * PI * u[0];
    let z = (1.0 - u[1]) * (1.0 + v[2]) - v[2];
    let sin_t = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
    let h = [sin_t * phi.cos() + v[0], sin_t * phi.sin() + v[1], z + v[2]];
    normalize([h[0] * alpha, h[1] * alpha, h[2].max(1e-12)])
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `(A, B)` at view cosine `mu` and roughness `r`.
pub fn albedo(mu: f64, r: f64) -> [f64; 2] {
    let mu = mu.clamp(1e-3, 1.0);
    let alpha = r * r;
    let fw = (1.0 - mu).powi(5);
    if alpha < ALPHA_MIN {
        return [1.0 - fw, fw];
    }
    let a2 = alpha * alpha;
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let g1 = 2.0 * mu / (mu + smith_term(mu, a2));
    let (mut a, mut b) = (0.0, 0.0);
    #[expect(clippy::cast_precision_loss, reason = "small counts")]
    let n = STRATA as f64;
    for i in 0..STRATA {
        for j in 0..STRATA {
            #[expect(clippy::cast_precision_loss, reason = "small counts")]
            let u = [(i as f64 + 0.5) / n, (j as f64 + 0.5) / n];
            let m = vndf(wo, alpha, u);
            let c = dot(wo, m);
            let wi = [
                2.0 * c * m[0] - wo[0],
                2.0 * c * m[1] - wo[1],
                2.0 * c * m[2] - wo[2],
            ];
            if wi[2] <= 0.0 {
                continue;
            }
            let g2 = 2.0 * mu * wi[2] / (mu * smith_term(wi[2], a2) + wi[2] * smith_term(mu, a2));
            let weight = g2 / g1;
            let f = (1.0 - c).clamp(0.0, 1.0).powi(5);
            a += weight * (1.0 - f);
            b += weight * f;
        }
    }
    [a / (n * n), b / (n * n)]
}

/// Axis value of index `i`: `i / (N − 1)`.
#[expect(clippy::cast_precision_loss, reason = "small counts")]
pub fn axis(i: usize) -> f64 {
    i as f64 / (N - 1) as f64
}

fn build() -> Vec<[f32; 2]> {
    let mut rows = vec![[0.0_f64; 2]; N * N];
    for k in 0..N {
        for j in 0..N {
            rows[k * N + j] = albedo(axis(j), axis(k));
        }
    }
    let mut out: Vec<[f32; 2]> = rows.iter().map(|e| e.map(|v| v as f32)).collect();
    for k in 0..N {
        // 2 ∫ E(μ) μ dμ of the piecewise-linear interpolant, segment by segment.
        let mut avg = [0.0; 2];
        for j in 0..N - 1 {
            let (x0, x1) = (axis(j), axis(j + 1));
            for c in 0..2 {
                let (e0, e1) = (
                    f64::from(out[k * N + j][c]),
                    f64::from(out[k * N + j + 1][c]),
                );
                avg[c] += 2.0 * (x1 - x0) / 6.0 * (e0 * (2.0 * x0 + x1) + e1 * (x0 + 2.0 * x1));
            }
        }
        out.push(avg.map(|v| v as f32));
    }
    out
}

/// The table in a storage buffer, as `shaders/pathtrace/bsdf.wgsl` reads it (`ggx_table`).
pub fn upload(ctx: &crate::GpuContext) -> wgpu::Buffer {
    crate::kernel::storage_buffer(ctx, "ggx albedo table", bytemuck::cast_slice(ggx_table()))
}

/// The table as uploaded: `N × N` entries `(A, B)` (roughness-major), then `N` averages.
pub fn ggx_table() -> &'static [[f32; 2]] {
    static TABLE: LazyLock<Vec<[f32; 2]>> = LazyLock::new(build);
    &TABLE
}
