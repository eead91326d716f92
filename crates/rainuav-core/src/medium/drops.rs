//! Single raindrops: shape, depolarisation factors, quasi-static polarisability and fall
//! speed (docs/physics.md sections 2 and 3).

use crate::error::{CoreError, Result};
use num_complex::Complex64;
use std::str::FromStr;

/// Drops at or above this equivalent diameter (mm) are oblate spheroids (the paper's rule).
pub const SPHEROID_FROM_MM: f64 = 1.25;

/// How drop shape depends on size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Every drop is a sphere.
    Sphere,
    /// Oblate spheroids from 1.25 mm, axial ratio of Beard and Chuang (1987). Default.
    BeardChuang,
    /// Oblate spheroids from 1.25 mm, axial ratio `1.03 - 0.062 D` (Pruppacher and Beard 1970).
    PruppacherBeard,
}

impl FromStr for Shape {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "sphere" => Ok(Shape::Sphere),
            "beard-chuang" => Ok(Shape::BeardChuang),
            "pruppacher-beard" => Ok(Shape::PruppacherBeard),
            _ => Err(CoreError::invalid(
                "shape",
                "must be one of 'sphere', 'beard-chuang', 'pruppacher-beard'",
                format!("{s:?}"),
            )),
        }
    }
}

impl Shape {
    /// Axial ratio minor/major of a drop of equivalent diameter `d_mm` (1 for spheres).
    pub fn axial_ratio(self, d_mm: f64) -> f64 {
        if d_mm < SPHEROID_FROM_MM {
            return 1.0;
        }
        let r = match self {
            Shape::Sphere => 1.0,
            Shape::BeardChuang => {
                1.0048 + 5.7e-4 * d_mm - 2.628e-2 * d_mm.powi(2) + 3.682e-3 * d_mm.powi(3)
                    - 1.677e-4 * d_mm.powi(4)
            }
            Shape::PruppacherBeard => 1.03 - 0.062 * d_mm,
        };
        // Both fits exceed 1 just above 1.25 mm only by rounding of their coefficients;
        // a prolate drop is not what they describe.
        r.min(1.0)
    }
}

/// Depolarisation factors `(Lx, Lz)` of an oblate spheroid with axial ratio `r` = minor/major
/// (symmetry axis z), `Lx = Ly = (1 - Lz)/2`. A sphere (`r = 1`) gives `(1/3, 1/3)`.
pub fn depolarisation_factors(r: f64) -> (f64, f64) {
    let third = 1.0 / 3.0;
    if r >= 1.0 {
        return (third, third);
    }
    let f2 = 1.0 / (r * r) - 1.0;
    let lz = if f2 < 1e-4 {
        // Series of (1 + f^2)/f^2 (1 - atan(f)/f) in f^2: avoids cancellation near the sphere.
        third + 2.0 / 15.0 * f2 - 8.0 / 105.0 * f2 * f2
    } else {
        let f = f2.sqrt();
        (1.0 + f2) / f2 * (1.0 - f.atan() / f)
    };
    ((1.0 - lz) / 2.0, lz)
}

/// Quasi-static polarisability per unit volume for a field along an axis with
/// depolarisation factor `l`: `beta = (eps_w - 1)/(1 + l (eps_w - 1))`.
pub fn polarisability(eps_w: Complex64, l: f64) -> Complex64 {
    (eps_w - 1.0) / (1.0 + l * (eps_w - 1.0))
}

/// Terminal fall speed of a drop of diameter `d_mm` (Atlas et al. 1973), m/s, >= 0.
pub fn terminal_velocity_m_s(d_mm: f64) -> f64 {
    (9.65 - 10.3 * (-0.6 * d_mm).exp()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/physics.md gives 5 decimals: 1e-5 absolute.
    #[test]
    fn depolarisation_reference_values() {
        for (r, lx, lz) in [
            (0.9, 0.31909, 0.36182),
            (0.7, 0.28397, 0.43207),
            (0.5, 0.23640, 0.52720),
        ] {
            let (x, z) = depolarisation_factors(r);
            assert!(
                (x - lx).abs() < 1e-5 && (z - lz).abs() < 1e-5,
                "{r}: {x} {z}"
            );
        }
    }

    /// The near-sphere series and the closed form agree where both are accurate.
    #[test]
    fn depolarisation_is_continuous_near_sphere() {
        let r = (1.0f64 / (1.0 + 1e-4)).sqrt();
        let below = depolarisation_factors(r * (1.0 + 1e-12));
        let above = depolarisation_factors(r * (1.0 - 1e-12));
        assert!((below.1 - above.1).abs() < 1e-9);
        let (x, z) = depolarisation_factors(1.0);
        assert!((2.0 * x + z - 1.0).abs() < 1e-15);
    }

    #[test]
    fn shapes() {
        assert_eq!(Shape::BeardChuang.axial_ratio(1.0), 1.0);
        assert!(Shape::BeardChuang.axial_ratio(4.0) < 0.8);
        assert!((Shape::PruppacherBeard.axial_ratio(5.0) - 0.72).abs() < 1e-12);
        assert_eq!(Shape::Sphere.axial_ratio(6.0), 1.0);
        assert!("ellipse".parse::<Shape>().is_err());
    }
}
