//! Colour primaries: a file's `chromaticities` converted to lumagraph's working space
//! (linear Rec. 709 primaries, D65 white), with the matrices OpenEXR derives
//! (`Imf::RGBtoXYZ`, `Imf::XYZtoRGB`): through CIE XYZ, with no chromatic adaptation, so
//! a file whose white differs from D65 keeps its white's colour, as OpenEXR's own
//! conversion does.

/// The CIE xy chromaticities of a colour space's red, green and blue primaries and of its
/// white, as an EXR `chromaticities` attribute stores them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chromaticities {
    /// Red primary (x, y).
    pub red: [f32; 2],
    /// Green primary (x, y).
    pub green: [f32; 2],
    /// Blue primary (x, y).
    pub blue: [f32; 2],
    /// White point (x, y).
    pub white: [f32; 2],
}

/// Rec. 709 / sRGB primaries with a D65 white: the working space, and what OpenEXR
/// assumes of a file without a `chromaticities` attribute.
pub const REC709: Chromaticities = Chromaticities {
    red: [0.64, 0.33],
    green: [0.30, 0.60],
    blue: [0.15, 0.06],
    white: [0.3127, 0.3290],
};

/// A 3×3 matrix applied to column vectors (`out = m · rgb`), rows first.
pub type Matrix3 = [[f64; 3]; 3];

impl Chromaticities {
    /// Whether these are Rec. 709's primaries and white (to the 1e-4 a file's rounded
    /// values allow).
    pub fn is_rec709(&self) -> bool {
        self.is_near(&REC709)
    }

    /// Whether these are `other`'s primaries and white, to 1e-4.
    pub fn is_near(&self, other: &Self) -> bool {
        let pairs = [
            (self.red, other.red),
            (self.green, other.green),
            (self.blue, other.blue),
            (self.white, other.white),
        ];
        pairs
            .iter()
            .all(|(a, b)| (a[0] - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4)
    }

    /// The chromaticities of the eight numbers of [`Chromaticities::to_array`].
    pub fn from_array(a: [f32; 8]) -> Self {
        Self {
            red: [a[0], a[1]],
            green: [a[2], a[3]],
            blue: [a[4], a[5]],
            white: [a[6], a[7]],
        }
    }

    /// The eight numbers in the attribute's order: red, green, blue, white, x then y.
    pub fn to_array(&self) -> [f32; 8] {
        [
            self.red[0],
            self.red[1],
            self.green[0],
            self.green[1],
            self.blue[0],
            self.blue[1],
            self.white[0],
            self.white[1],
        ]
    }

    /// Linear RGB in these primaries to CIE XYZ, white at luminance `y`
    /// (`Imf::RGBtoXYZ`: the white's XYZ solved for the primaries' scales).
    pub fn rgb_to_xyz(&self, y: f64) -> Matrix3 {
        // Each primary as (x, y, 1 − x − y), scaled below (so a primary with y = 0, as
        // XYZ's blue, needs no division); the white as XYZ at luminance `y`.
        let unscaled = |p: [f32; 2]| {
            let (x, yy) = (f64::from(p[0]), f64::from(p[1]));
            [x, yy, 1.0 - x - yy]
        };
        let (r, g, b) = (
            unscaled(self.red),
            unscaled(self.green),
            unscaled(self.blue),
        );
        let (wx, wy) = (f64::from(self.white[0]), f64::from(self.white[1]));
        let w = [wx / wy * y, y, (1.0 - wx - wy) / wy * y];
        // Solve for the primaries' scales so that r·sr + g·sg + b·sb = white.
        let primaries = [[r[0], g[0], b[0]], [r[1], g[1], b[1]], [r[2], g[2], b[2]]];
        let s = mul_vec(&invert(&primaries), w);
        let mut m = [[0.0; 3]; 3];
        for row in 0..3 {
            for col in 0..3 {
                m[row][col] = primaries[row][col] * s[col];
            }
        }
        m
    }

    /// CIE XYZ to linear RGB in these primaries (`Imf::XYZtoRGB`).
    pub fn xyz_to_rgb(&self, y: f64) -> Matrix3 {
        invert(&self.rgb_to_xyz(y))
    }

    /// Linear RGB in these primaries to linear Rec. 709 (the working space).
    pub fn to_rec709(&self) -> Matrix3 {
        mul(&REC709.xyz_to_rgb(1.0), &self.rgb_to_xyz(1.0))
    }

    /// The luminance weights of red, green and blue (the middle row of
    /// [`Chromaticities::rgb_to_xyz`] at white luminance 1).
    pub fn luminance_weights(&self) -> [f64; 3] {
        self.rgb_to_xyz(1.0)[1]
    }
}

/// `a · b`.
pub fn mul(a: &Matrix3, b: &Matrix3) -> Matrix3 {
    let mut m = [[0.0; 3]; 3];
    for row in 0..3 {
        for col in 0..3 {
            m[row][col] = (0..3).map(|k| a[row][k] * b[k][col]).sum();
        }
    }
    m
}

/// `m · v`.
pub fn mul_vec(m: &Matrix3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|row| (0..3).map(|k| m[row][k] * v[k]).sum())
}

/// The inverse of `m` (by its adjugate; primaries that span no volume give infinities,
/// which [`Chromaticities::to_rec709`]'s callers check for).
pub fn invert(m: &Matrix3) -> Matrix3 {
    let c =
        |r0: usize, c0: usize, r1: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let adj = [
        [c(1, 1, 2, 2), -c(0, 1, 2, 2), c(0, 1, 1, 2)],
        [-c(1, 0, 2, 2), c(0, 0, 2, 2), -c(0, 0, 1, 2)],
        [c(1, 0, 2, 1), -c(0, 0, 2, 1), c(0, 0, 1, 1)],
    ];
    let det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
    adj.map(|row| row.map(|x| x / det))
}

/// Whether every entry of `m` is finite (primaries on a line give none).
pub fn is_finite(m: &Matrix3) -> bool {
    m.iter().flatten().all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rec709_to_rec709_is_the_identity() {
        let m = REC709.to_rec709();
        for row in 0..3 {
            for col in 0..3 {
                let want = if row == col { 1.0 } else { 0.0 };
                assert!((m[row][col] - want).abs() < 1e-12, "{m:?}");
            }
        }
    }

    #[test]
    fn rec709_luminance_weights_are_the_familiar_ones() {
        let w = REC709.luminance_weights();
        assert!((w[0] - 0.2126).abs() < 1e-3, "{w:?}");
        assert!((w[1] - 0.7152).abs() < 1e-3, "{w:?}");
        assert!((w[2] - 0.0722).abs() < 1e-3, "{w:?}");
    }

    #[test]
    fn xyz_primaries_give_the_xyz_to_rec709_matrix() {
        // XYZ as primaries with an equal-energy white: RGB is XYZ itself.
        let xyz = Chromaticities {
            red: [1.0, 0.0],
            green: [0.0, 1.0],
            blue: [0.0, 0.0],
            white: [1.0 / 3.0, 1.0 / 3.0],
        };
        let to_xyz = xyz.rgb_to_xyz(1.0);
        for row in 0..3 {
            for col in 0..3 {
                let want = if row == col { 1.0 } else { 0.0 };
                assert!((to_xyz[row][col] - want).abs() < 1e-6, "{to_xyz:?}");
            }
        }
        // The familiar XYZ → sRGB matrix's first row, 3.2406 −1.5372 −0.4986.
        let m = xyz.to_rec709();
        assert!(
            (m[0][0] - 3.2406).abs() < 2e-3 && (m[0][1] + 1.5372).abs() < 2e-3,
            "{m:?}"
        );
    }
}
