//! Conductors with a complex index of refraction η + iκ: named presets of measured metals
//! and the exact (unpolarized) conductor Fresnel reflectance.
//!
//! The presets are the RGB values Mitsuba 3.9.1's RGB variants use for its `conductor`
//! materials of the same name (what `mi.traverse(mi.load_dict({'type': 'conductor',
//! 'material': 'Au'}))` reports as `eta` and `k`): Mitsuba's tabulated spectra of η and κ
//! over 360–830 nm, from E. D. Palik (ed.), *Handbook of Optical Constants of Solids*
//! (Academic Press, 1985), reduced to linear sRGB by its spectral upsampling. Taking the
//! same numbers lets the path tracer be compared with Mitsuba's `roughconductor` on equal
//! terms (`scripts/references/`). Other metals take `eta` and `k` in the scene file.

use glam::Vec3;

/// A conductor's complex index of refraction relative to the outside medium, per RGB
/// channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part η.
    pub eta: Vec3,
    /// Imaginary part (extinction coefficient) κ.
    pub k: Vec3,
}

/// Named conductors: name, η, κ (linear sRGB), what it is.
pub const PRESETS: &[(&str, [f32; 3], [f32; 3], &str)] = &[
    (
        "Ag",
        [0.155_276, 0.116_728, 0.138_388],
        [4.828_35, 3.122_22, 2.146_9],
        "silver",
    ),
    (
        "Al",
        [1.657_5, 0.880_405, 0.521_244],
        [9.223_81, 6.269_5, 4.837],
        "aluminium",
    ),
    (
        "Au",
        [0.143_036, 0.375_307, 1.442_05],
        [3.983, 2.385_56, 1.603_36],
        "gold",
    ),
    (
        "Be",
        [4.185_01, 3.185_03, 2.784_06],
        [3.835_47, 3.010_12, 2.868_99],
        "beryllium",
    ),
    (
        "Cr",
        [4.369_67, 2.916_51, 1.654_9],
        [5.206_55, 4.231_31, 3.754_7],
        "chromium",
    ),
    (
        "Cu",
        [0.201_005, 0.923_75, 1.102_22],
        [3.913_26, 2.453_05, 2.142_09],
        "copper",
    ),
    (
        "Hg",
        [2.398_94, 1.440_03, 0.909_57],
        [6.327_59, 4.371_92, 3.421_76],
        "mercury",
    ),
    (
        "Ir",
        [3.086_3, 2.082_19, 1.617_91],
        [5.592_15, 4.067_09, 3.267_31],
        "iridium",
    ),
    (
        "Li",
        [0.265_791, 0.195_618, 0.220_949],
        [3.540_15, 2.311_12, 1.668_61],
        "lithium",
    ),
    (
        "Mo",
        [4.483_97, 3.525_13, 2.776_31],
        [4.111_44, 3.420_83, 3.150_61],
        "molybdenum",
    ),
    (
        "Nb",
        [3.420_07, 2.790_09, 2.395_63],
        [3.441_39, 2.737_67, 2.579_75],
        "niobium",
    ),
    (
        "Ni",
        [2.367_3, 1.663_37, 1.467_08],
        [4.498_81, 3.050_15, 2.345_44],
        "nickel (Mitsuba `Ni_palik`)",
    ),
    (
        "Rh",
        [2.585_79, 1.860_22, 1.554_26],
        [6.782_26, 4.702_99, 3.976_07],
        "rhodium",
    ),
    (
        "Ta",
        [2.062_72, 2.392_94, 2.627_93],
        [2.408_36, 1.741_49, 1.947_03],
        "tantalum",
    ),
    (
        "TiN",
        [1.648_45, 1.150_52, 1.379_82],
        [3.368_33, 1.943_5, 1.102_07],
        "titanium nitride",
    ),
    (
        "W",
        [4.370_82, 3.300_25, 2.998_41],
        [3.500_64, 2.604_87, 2.273_23],
        "tungsten",
    ),
];

/// The preset called `name`, if there is one.
pub fn preset(name: &str) -> Option<Conductor> {
    PRESETS
        .iter()
        .find(|(n, ..)| *n == name)
        .map(|&(_, eta, k, _)| Conductor {
            eta: Vec3::from(eta),
            k: Vec3::from(k),
        })
}

/// Unpolarized Fresnel reflectance of a conductor of index `eta + i k` at incidence
/// cosine `cos_i` (exact; pbrt's `FrComplex` in real arithmetic). Mirrored by
/// `fresnel_conductor` in `shaders/pathtrace/bsdf/bsdf.wgsl`.
pub fn fresnel(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c2 = (cos_i * cos_i).clamp(0.0, 1.0);
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * k * k).max(0.0).sqrt();
    let t1 = a2b2 + c2;
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t2 = 2.0 * cos_i.abs() * a;
    let rs = (t1 - t2) / (t1 + t2).max(f32::MIN_POSITIVE);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(f32::MIN_POSITIVE);
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

impl Conductor {
    /// A conductor of index `eta + i k`.
    pub fn new(eta: Vec3, k: Vec3) -> Self {
        Self { eta, k }
    }

    /// Fresnel reflectance per channel at incidence cosine `cos_i`.
    pub fn reflectance(&self, cos_i: f32) -> Vec3 {
        Vec3::new(
            fresnel(cos_i, self.eta.x, self.k.x),
            fresnel(cos_i, self.eta.y, self.k.y),
            fresnel(cos_i, self.eta.z, self.k.z),
        )
    }

    /// Reflectance at normal incidence, `((η−1)² + κ²) / ((η+1)² + κ²)`: the metal's
    /// colour, used as its albedo.
    pub fn normal_reflectance(&self) -> Vec3 {
        self.reflectance(1.0)
    }

    /// Cosine-weighted hemispherical average of the reflectance, `2 ∫ F(μ) μ dμ` (for the
    /// multiple-scattering compensation), by 256-point midpoint quadrature in μ² (exact to
    /// about 1e-5 for these smooth curves).
    pub fn average_reflectance(&self) -> Vec3 {
        const N: usize = 256;
        let mut sum = glam::DVec3::ZERO;
        for i in 0..N {
            // μ² uniform on [0, 1]: 2 μ dμ = d(μ²).
            #[expect(clippy::cast_precision_loss, reason = "small counts")]
            let mu = ((i as f32 + 0.5) / N as f32).sqrt();
            sum += self.reflectance(mu).as_dvec3();
        }
        #[expect(clippy::cast_precision_loss, reason = "small counts")]
        let mean = sum / N as f64;
        mean.as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_the_closed_form() {
        for &(name, eta, k, _) in PRESETS {
            let c = preset(name).unwrap();
            for ch in 0..3 {
                let (n, kk) = (eta[ch], k[ch]);
                let f0 = ((n - 1.0).powi(2) + kk * kk) / ((n + 1.0).powi(2) + kk * kk);
                let got = c.normal_reflectance()[ch];
                assert!(
                    (got - f0).abs() < 1e-5,
                    "{name} channel {ch}: {got} vs {f0}"
                );
            }
        }
    }

    #[test]
    fn a_dielectric_without_absorption_gives_the_dielectric_fresnel() {
        // κ = 0: the conductor formula reduces to the dielectric one.
        let eta: f32 = 1.5;
        for i in 0..=20 {
            let c = i as f32 / 20.0;
            let s2t = (1.0 - c * c) / (eta * eta);
            let ct = (1.0 - s2t).sqrt();
            let rs = (c - eta * ct) / (c + eta * ct);
            let rp = (eta * c - ct) / (eta * c + ct);
            let want = 0.5 * (rs * rs + rp * rp);
            let got = fresnel(c, eta, 0.0);
            assert!((got - want).abs() < 1e-5, "cos {c}: {got} vs {want}");
        }
    }

    #[test]
    fn grazing_reflectance_is_one_and_the_average_lies_within_the_curve() {
        for &(name, ..) in PRESETS {
            let c = preset(name).unwrap();
            assert!((c.reflectance(0.0) - Vec3::ONE).abs().max_element() < 1e-6);
            // F dips below F0 towards grazing for some metals: the average lies between
            // the curve's least value and 1.
            let least = (0..=1000)
                .map(|i| c.reflectance(i as f32 / 1000.0))
                .fold(Vec3::ONE, Vec3::min);
            let avg = c.average_reflectance();
            assert!(
                avg.cmpge(least).all() && avg.cmple(Vec3::ONE).all(),
                "{name}: {avg} vs least {least}"
            );
        }
    }
}
