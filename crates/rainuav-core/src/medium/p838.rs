//! ITU-R P.838-3 (03/2005): specific attenuation of rain `gamma = k R^alpha` (dB/km)
//! from the recommendation's coefficient fits, for any polarisation tilt and elevation.

/// One fitted curve: Gaussian terms in `log10 f` plus a line.
struct Fit<const N: usize> {
    a: [f64; N],
    b: [f64; N],
    c: [f64; N],
    m: f64,
    c0: f64,
}

impl<const N: usize> Fit<N> {
    fn eval(&self, log_f: f64) -> f64 {
        let mut s = self.m * log_f + self.c0;
        for j in 0..N {
            s += self.a[j] * (-((log_f - self.b[j]) / self.c[j]).powi(2)).exp();
        }
        s
    }
}

// Tables 1-4 of the recommendation.
const K_H: Fit<4> = Fit {
    a: [-5.33980, -0.35351, -0.23789, -0.94158],
    b: [-0.10008, 1.26970, 0.86036, 0.64552],
    c: [1.13098, 0.45400, 0.15354, 0.16817],
    m: -0.18961,
    c0: 0.71147,
};
const K_V: Fit<4> = Fit {
    a: [-3.80595, -3.44965, -0.39902, 0.50167],
    b: [0.56934, -0.22911, 0.73042, 1.07319],
    c: [0.81061, 0.51059, 0.11899, 0.27195],
    m: -0.16398,
    c0: 0.63297,
};
const ALPHA_H: Fit<5> = Fit {
    a: [-0.14318, 0.29591, 0.32177, -5.37610, 16.1721],
    b: [1.82442, 0.77564, 0.63773, -0.96230, -3.29980],
    c: [-0.55187, 0.19822, 0.13164, 1.47828, 3.43990],
    m: 0.67849,
    c0: -1.95537,
};
const ALPHA_V: Fit<5> = Fit {
    a: [-0.07771, 0.56727, -0.20238, -48.2991, 48.5833],
    b: [2.33840, 0.95545, 1.14520, 0.791669, 0.791459],
    c: [-0.76284, 0.54039, 0.26809, 0.116226, 0.116479],
    m: -0.053739,
    c0: 0.83433,
};

/// Coefficients `(kH, alphaH, kV, alphaV)` at `freq_hz` (the fits hold for 1-1000 GHz).
pub fn coefficients_hv(freq_hz: f64) -> (f64, f64, f64, f64) {
    let lf = (freq_hz * 1e-9).log10();
    (
        10f64.powf(K_H.eval(lf)),
        ALPHA_H.eval(lf),
        10f64.powf(K_V.eval(lf)),
        ALPHA_V.eval(lf),
    )
}

/// `(k, alpha)` for polarisation tilt `tilt_deg` (0: horizontal, 90: vertical,
/// 45: circular) and path elevation `elevation_deg` (recommendation eqs. 4-5).
pub fn coefficients(freq_hz: f64, tilt_deg: f64, elevation_deg: f64) -> (f64, f64) {
    let (kh, ah, kv, av) = coefficients_hv(freq_hz);
    let c = elevation_deg.to_radians().cos().powi(2) * (2.0 * tilt_deg.to_radians()).cos();
    let k = (kh + kv + (kh - kv) * c) / 2.0;
    let alpha = (kh * ah + kv * av + (kh * ah - kv * av) * c) / (2.0 * k);
    (k, alpha)
}

/// Specific attenuation in dB/km; zero for a zero rain rate.
pub fn specific_attenuation(
    freq_hz: f64,
    rain_rate_mm_h: f64,
    tilt_deg: f64,
    elevation_deg: f64,
) -> f64 {
    if rain_rate_mm_h == 0.0 {
        return 0.0;
    }
    let (k, alpha) = coefficients(freq_hz, tilt_deg, elevation_deg);
    k * rain_rate_mm_h.powf(alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/physics.md section 3 reference values, given to 4 significant figures: 5e-4 relative.
    #[test]
    fn reference_values() {
        let (kh, ah, _, _) = coefficients_hv(4.9e9);
        assert!((kh / 1.937e-4 - 1.0).abs() < 5e-4, "{kh}");
        assert!((ah - 1.7019).abs() < 1e-4, "{ah}");
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(rel(specific_attenuation(4.9e9, 25.0, 0.0, 0.0), 0.04639) < 5e-4);
        assert!(rel(specific_attenuation(4.9e9, 25.0, 90.0, 0.0), 0.03068) < 5e-4);
        assert!(rel(specific_attenuation(28e9, 25.0, 0.0, 0.0), 4.624) < 5e-4);
    }

    /// At vertical incidence tilt no longer matters: k is the H/V mean.
    #[test]
    fn zenith_path_is_polarisation_free() {
        let (a, _) = coefficients(20e9, 0.0, 90.0);
        let (b, _) = coefficients(20e9, 90.0, 90.0);
        assert!((a / b - 1.0).abs() < 1e-12);
    }
}
