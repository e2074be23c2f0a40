//! GGX albedo tables, computed here (not copied from anywhere) and uploaded for the path
//! tracer's material model (`shaders/pathtrace/bsdf/bsdf.wgsl`).
//!
//! With Schlick's Fresnel `F = F0 + (1 − F0)(1 − c)^5`, the directional albedo of a GGX
//! reflection lobe is linear in `F0`: `E(μ) = F0·A(μ, r) + B(μ, r)`, where
//! `A = ∫ f(F=1) (1 − (1 − c)^5) cos` and `B = ∫ f(F=1) (1 − c)^5 cos` over the hemisphere.
//! One table of `(A, B)` over view cosine `μ` and roughness `r` (α = r²) serves both the
//! dielectric layer (its Lambertian base receives exactly `1 − E`) and the metal's
//! Kulla–Conty multiple-scattering term (which needs `E` at F0 = 1 and its average).
//!
//! After them, the directional albedo `E_s(μ, r)` of glTF's sheen lobe at colour 1
//! ([`sheen_albedo`], `shaders/pathtrace/bsdf/sheen.wgsl`), which the layers below a sheen lose.
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

/// Perceptual sheen roughness below this is taken as this (`SHEEN_ROUGHNESS_MIN` in
/// `sheen.wgsl`).
pub const SHEEN_ROUGHNESS_MIN: f64 = 0.07;

/// glTF's sheen lobe (`sheen.wgsl`): `D · V · μ_i` at colour 1, for α = roughness², view
/// cosine `mu_o` and `wi = (sin θ cos φ, sin θ sin φ, mu_i)` with `wo` in the xz-plane.
pub fn sheen_f_cos(alpha: f64, mu_o: f64, mu_i: f64, phi: f64) -> f64 {
    let wo = [(1.0 - mu_o * mu_o).max(0.0).sqrt(), 0.0, mu_o];
    let s = (1.0 - mu_i * mu_i).max(0.0).sqrt();
    let wi = [s * phi.cos(), s * phi.sin(), mu_i];
    let h = normalize([wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]]);
    let inv = 1.0 / alpha;
    let d = (2.0 + inv) * (1.0 - h[2] * h[2]).max(0.0).powf(0.5 * inv) / (2.0 * PI);
    let fit = |x: f64| {
        let t = (1.0 - alpha) * (1.0 - alpha);
        let mix = |a: f64, b: f64| a + (b - a) * t;
        mix(21.5473, 25.3245) / (1.0 + mix(3.82987, 3.32435) * x.powf(mix(0.19823, 0.16801)))
            + mix(-1.97760, -1.27393) * x
            + mix(-4.32054, -4.85967)
    };
    let lambda = |mu: f64| {
        if mu < 0.5 {
            fit(mu).exp()
        } else {
            (2.0 * fit(0.5) - fit(1.0 - mu)).exp()
        }
    };
    let v = (1.0 / ((1.0 + lambda(mu_o) + lambda(mu_i)) * 4.0 * mu_o * mu_i)).clamp(0.0, 1.0);
    d * v * mu_i
}

/// `E_s` at view cosine `mu` and perceptual roughness `r`: `∫ sheen_f_cos dω_i` by the
/// midpoint rule in `μ_i = t²` (dense towards grazing, where the lobe is) and `φ` (over
/// half the circle: the lobe is symmetric about the plane of `wo`).
pub fn sheen_albedo(mu: f64, r: f64) -> f64 {
    const T: usize = 64;
    const P: usize = 48;
    let mu = mu.clamp(1e-3, 1.0);
    let r = r.clamp(SHEEN_ROUGHNESS_MIN, 1.0);
    let alpha = r * r;
    let mut sum = 0.0;
    for i in 0..T {
        #[expect(clippy::cast_precision_loss, reason = "small counts")]
        let t = (i as f64 + 0.5) / T as f64;
        for j in 0..P {
            #[expect(clippy::cast_precision_loss, reason = "small counts")]
            let phi = PI * (j as f64 + 0.5) / P as f64;
            sum += sheen_f_cos(alpha, mu, t * t, phi) * 2.0 * t;
        }
    }
    #[expect(clippy::cast_precision_loss, reason = "small counts")]
    let cell = (1.0 / T as f64) * (PI / P as f64);
    // Both halves of the circle.
    2.0 * sum * cell
}

fn build_sheen() -> Vec<[f32; 2]> {
    let mut out = vec![[0.0_f32; 2]; N * N];
    std::thread::scope(|s| {
        let rows: Vec<_> = (0..N)
            .map(|k| {
                s.spawn(move || {
                    (0..N)
                        .map(|j| sheen_albedo(axis(j), axis(k)) as f32)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for (k, row) in rows.into_iter().enumerate() {
            let row = row.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
            for (j, e) in row.into_iter().enumerate() {
                out[k * N + j] = [e, 0.0];
            }
        }
    });
    out
}

/// The sheen table as uploaded: `N × N` entries `(E_s, 0)` (roughness-major).
pub fn sheen_table() -> &'static [[f32; 2]] {
    static TABLE: LazyLock<Vec<[f32; 2]>> = LazyLock::new(build_sheen);
    &TABLE
}

/// The tables in a storage buffer, as `shaders/pathtrace/bsdf/bsdf.wgsl` reads them
/// (`ggx_table`): the GGX tables, then the sheen table where `sheen` says some material has
/// one (zeros, never read, where none has: it takes a moment to compute).
pub fn upload(ctx: &lumagraph_render::GpuContext, sheen: bool) -> wgpu::Buffer {
    let mut data = ggx_table().to_vec();
    if sheen {
        data.extend_from_slice(sheen_table());
    } else {
        data.resize(data.len() + N * N, [0.0; 2]);
    }
    lumagraph_render::kernel::storage_buffer(ctx, "ggx albedo table", bytemuck::cast_slice(&data))
}

/// The table as uploaded: `N × N` entries `(A, B)` (roughness-major), then `N` averages.
pub fn ggx_table() -> &'static [[f32; 2]] {
    static TABLE: LazyLock<Vec<[f32; 2]>> = LazyLock::new(build);
    &TABLE
}
