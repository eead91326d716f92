//! Complex permittivity of liquid water: the double-Debye model of Liebe et al. (1991)
//! as used by ITU-R P.840, in the engineering convention `eps = eps' - j eps''`
//! (docs/physics.md sections 0 and 1).

use crate::error::{Result, check_range};
use num_complex::Complex64;

/// Lowest and highest temperature the model is used for, in degrees Celsius.
pub const TEMPERATURE_RANGE_C: (f64, f64) = (0.0, 40.0);

/// Checks a water temperature.
pub fn check_temperature(temperature_c: f64) -> Result<()> {
    check_range(
        "temperature_c",
        temperature_c,
        TEMPERATURE_RANGE_C.0,
        TEMPERATURE_RANGE_C.1,
        "must be finite and within 0..40 C",
    )
}

/// Relative permittivity of liquid water at `freq_hz` and `temperature_c`
/// (Im <= 0: lossy in the `exp(+j w t)` convention). Inputs are not checked here;
/// the public entry points of [`crate::medium`] check them.
pub fn water_permittivity(freq_hz: f64, temperature_c: f64) -> Complex64 {
    let f = freq_hz * 1e-9;
    let theta = 300.0 / (temperature_c + 273.15);
    let e0 = 77.66 + 103.3 * (theta - 1.0);
    let e1 = 0.0671 * e0;
    let e2 = 3.52;
    let fp = 20.20 - 146.0 * (theta - 1.0) + 316.0 * (theta - 1.0).powi(2);
    let fs = 39.8 * fp;
    let rp = 1.0 + (f / fp).powi(2);
    let rs = 1.0 + (f / fs).powi(2);
    let eps_im = f * (e0 - e1) / (fp * rp) + f * (e1 - e2) / (fs * rs);
    let eps_re = (e0 - e1) / rp + (e1 - e2) / rs + e2;
    Complex64::new(eps_re, -eps_im)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/physics.md section 1 gives the reference to 5 significant figures, so 1e-3 absolute.
    #[test]
    fn matches_physics_md_reference_values() {
        let cases = [
            (4.9e9, 20.0, 74.319, -19.932),
            (4.9e9, 10.0, 73.580, -26.384),
            (4.9e9, 0.0, 68.764, -34.641),
            (10e9, 20.0, 60.804, -32.709),
        ];
        for (f, t, re, im) in cases {
            let e = water_permittivity(f, t);
            assert!((e.re - re).abs() < 1e-3, "{f} {t}: {e}");
            assert!((e.im - im).abs() < 1e-3, "{f} {t}: {e}");
        }
    }
}
