//! Drop-size distributions N(D) in m^-3 mm^-1, D in mm (docs/physics.md section 2).

use crate::error::{CoreError, Result};
use crate::medium::drops::terminal_velocity_m_s;

/// Smallest and largest drop diameter integrated over, in mm (larger drops break up).
pub const DIAMETER_RANGE_MM: (f64, f64) = (0.1, 8.0);

/// A drop-size distribution as a function of diameter and rain rate.
#[derive(Debug, Clone, PartialEq)]
pub enum Dsd {
    /// `N(D) = n0_coeff R^n0_exp D^mu exp(-Lambda D)`, `Lambda = lambda_coeff R^lambda_exp`.
    /// Marshall-Palmer is `n0 = 8000, mu = 0, Lambda = 4.1 R^-0.21`.
    Gamma {
        /// Intercept coefficient, m^-3 mm^-(1 + mu).
        n0_coeff: f64,
        /// Rain-rate exponent of the intercept.
        n0_exp: f64,
        /// Shape parameter (0: exponential).
        mu: f64,
        /// Slope coefficient, mm^-1.
        lambda_coeff: f64,
        /// Rain-rate exponent of the slope.
        lambda_exp: f64,
    },
    /// A measured spectrum: `N(D)` linearly interpolated between the tabulated diameters
    /// (zero outside). The table fixes the spectrum's shape; its concentration scales
    /// linearly with rain rate, `N(D; R) = table(D) R / R_table`, where `R_table` is the
    /// table's own rain rate from the Atlas terminal velocity
    /// (`R = 6 pi 1e-4 integral D^3 v_t(D) N(D) dD`). Passing `R_table` reproduces the table.
    Table {
        /// Tabulated diameters, mm, strictly increasing.
        diameter_mm: Vec<f64>,
        /// N at those diameters, m^-3 mm^-1, >= 0.
        density: Vec<f64>,
        /// The table's own rain rate, mm/h (computed by [`Dsd::table`]).
        table_rain_rate_mm_h: f64,
    },
}

impl Dsd {
    /// Marshall-Palmer (1948), the paper's and the default distribution.
    pub fn marshall_palmer() -> Self {
        Dsd::Gamma {
            n0_coeff: 8000.0,
            n0_exp: 0.0,
            mu: 0.0,
            lambda_coeff: 4.1,
            lambda_exp: -0.21,
        }
    }

    /// A general gamma distribution; see [`Dsd::Gamma`]. Checks its parameters.
    pub fn gamma(
        n0_coeff: f64,
        n0_exp: f64,
        mu: f64,
        lambda_coeff: f64,
        lambda_exp: f64,
    ) -> Result<Self> {
        let finite = |name: &'static str, v: f64, lo: f64, hi: f64, allowed: &str| {
            crate::error::check_range(name, v, lo, hi, allowed)
        };
        finite(
            "n0",
            n0_coeff,
            0.0,
            1e12,
            "must be finite and within 0..1e12",
        )?;
        finite(
            "n0_exp",
            n0_exp,
            -5.0,
            5.0,
            "must be finite and within -5..5",
        )?;
        finite("mu", mu, -2.0, 20.0, "must be finite and within -2..20")?;
        finite(
            "lambda_coeff",
            lambda_coeff,
            1e-3,
            1e3,
            "must be finite and within 1e-3..1e3 per mm",
        )?;
        finite(
            "lambda_exp",
            lambda_exp,
            -5.0,
            5.0,
            "must be finite and within -5..5",
        )?;
        Ok(Dsd::Gamma {
            n0_coeff,
            n0_exp,
            mu,
            lambda_coeff,
            lambda_exp,
        })
    }

    /// A tabulated spectrum; see [`Dsd::Table`]. Checks the table.
    pub fn table(diameter_mm: Vec<f64>, density: Vec<f64>) -> Result<Self> {
        if diameter_mm.len() != density.len() {
            return Err(CoreError::invalid(
                "dsd table",
                "must have as many densities as diameters",
                format!(
                    "{} diameters, {} densities",
                    diameter_mm.len(),
                    density.len()
                ),
            ));
        }
        if diameter_mm.len() < 2 {
            return Err(CoreError::invalid(
                "dsd table",
                "must have at least 2 rows",
                diameter_mm.len(),
            ));
        }
        for w in diameter_mm.windows(2) {
            if w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater) {
                return Err(CoreError::invalid(
                    "dsd diameter_mm",
                    "must be finite and strictly increasing",
                    format!("{} then {}", w[0], w[1]),
                ));
            }
        }
        let (dmin, dmax) = DIAMETER_RANGE_MM;
        for &d in &diameter_mm {
            crate::error::check_range(
                "dsd diameter_mm",
                d,
                0.0,
                20.0,
                "must be finite and within 0..20 mm",
            )?;
        }
        for &n in &density {
            crate::error::check_range(
                "dsd density",
                n,
                0.0,
                1e12,
                "must be finite and within 0..1e12 m^-3 mm^-1",
            )?;
        }
        // Rain rate of the table itself, by the trapezoid rule on a fine grid (the table is
        // piecewise linear, so this converges quickly).
        let mut raw = Dsd::Table {
            diameter_mm,
            density,
            table_rain_rate_mm_h: 1.0,
        };
        let m = 20_000;
        let h = (dmax - dmin) / m as f64;
        let mut acc = 0.0;
        for i in 0..=m {
            let d = dmin + h * i as f64;
            let w = if i == 0 || i == m { 0.5 } else { 1.0 };
            acc += w * d.powi(3) * terminal_velocity_m_s(d) * raw.density(d, 1.0);
        }
        let rate = 6.0 * std::f64::consts::PI * 1e-4 * acc * h;
        if rate.is_nan() || rate <= 0.0 {
            return Err(CoreError::invalid(
                "dsd table",
                "must hold some drops between 0.1 and 8 mm (its rain rate is zero)",
                rate,
            ));
        }
        if let Dsd::Table {
            table_rain_rate_mm_h,
            ..
        } = &mut raw
        {
            *table_rain_rate_mm_h = rate;
        }
        Ok(raw)
    }

    /// N(D) in m^-3 mm^-1 at `d_mm` for rain rate `rain_rate_mm_h > 0`.
    pub fn density(&self, d_mm: f64, rain_rate_mm_h: f64) -> f64 {
        match self {
            Dsd::Gamma {
                n0_coeff,
                n0_exp,
                mu,
                lambda_coeff,
                lambda_exp,
            } => {
                let lambda = lambda_coeff * rain_rate_mm_h.powf(*lambda_exp);
                let n0 = n0_coeff * rain_rate_mm_h.powf(*n0_exp);
                n0 * d_mm.powf(*mu) * (-lambda * d_mm).exp()
            }
            Dsd::Table {
                diameter_mm,
                density,
                table_rain_rate_mm_h,
            } => {
                let n = diameter_mm.len();
                if !(d_mm >= diameter_mm[0] && d_mm <= diameter_mm[n - 1]) {
                    return 0.0;
                }
                let k = diameter_mm.partition_point(|&x| x <= d_mm).clamp(1, n - 1);
                let (d0, d1) = (diameter_mm[k - 1], diameter_mm[k]);
                let t = (d_mm - d0) / (d1 - d0);
                let v = density[k - 1] * (1.0 - t) + density[k] * t;
                v * rain_rate_mm_h / table_rain_rate_mm_h
            }
        }
    }

    /// Diameters (mm) where N(D) has a kink; quadrature panels are split there.
    pub fn breakpoints_mm(&self) -> Vec<f64> {
        match self {
            Dsd::Gamma { .. } => Vec::new(),
            Dsd::Table { diameter_mm, .. } => diameter_mm.clone(),
        }
    }
}

/// Marshall-Palmer N(D) in m^-3 mm^-1 (docs/physics.md section 2); zero for a zero rate.
pub fn marshall_palmer(d_mm: f64, rain_rate_mm_h: f64) -> f64 {
    if rain_rate_mm_h == 0.0 {
        return 0.0;
    }
    Dsd::marshall_palmer().density(d_mm, rain_rate_mm_h)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/physics.md gives 4 significant figures: 1e-4 relative.
    #[test]
    fn marshall_palmer_reference_values() {
        let lam = |r: f64| 4.1 * r.powf(-0.21);
        assert!((lam(12.5) - 2.4123).abs() < 1e-4);
        assert!((lam(25.0) - 2.0855).abs() < 1e-4);
        assert!((marshall_palmer(1.0, 25.0) / 993.9 - 1.0).abs() < 1e-4);
        assert!((marshall_palmer(2.0, 25.0) / 123.5 - 1.0).abs() < 1e-3);
    }

    /// A table sampled from Marshall-Palmer at 25 mm/h reproduces it at its own rate
    /// (exactly at the nodes) and scales linearly with rate.
    #[test]
    fn table_reproduces_and_scales() {
        let d: Vec<f64> = (0..=80).map(|i| 0.1 * i as f64 + 0.05).collect();
        let n: Vec<f64> = d.iter().map(|&x| marshall_palmer(x, 25.0)).collect();
        let t = Dsd::table(d.clone(), n.clone()).unwrap();
        let Dsd::Table {
            table_rain_rate_mm_h: r,
            ..
        } = t
        else {
            unreachable!()
        };
        // Marshall-Palmer with Atlas velocities carries roughly its nominal rate.
        assert!(r > 15.0 && r < 35.0, "{r}");
        assert!((t.density(d[10], r) - n[10]).abs() < 1e-9 * n[10]);
        assert!((t.density(d[10], 2.0 * r) - 2.0 * n[10]).abs() < 1e-9 * n[10]);
        assert_eq!(t.density(9.0, r), 0.0);
    }

    #[test]
    fn bad_tables_are_rejected() {
        assert!(Dsd::table(vec![1.0, 1.0], vec![1.0, 1.0]).is_err());
        assert!(Dsd::table(vec![1.0, 2.0], vec![1.0]).is_err());
        assert!(Dsd::table(vec![1.0, 2.0], vec![-1.0, 1.0]).is_err());
        assert!(Dsd::table(vec![1.0, f64::NAN], vec![1.0, 1.0]).is_err());
        assert!(Dsd::table(vec![1.0, 2.0], vec![0.0, 0.0]).is_err());
    }
}
