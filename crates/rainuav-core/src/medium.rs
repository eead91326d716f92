//! The rain medium, one layer: water's permittivity ([`water`]), drop sizes ([`dsd`]), shapes
//! and fall speed ([`drops`]), Mie scattering ([`mie`]), the quadrature ([`quadrature`]) and
//! ITU-R P.838-3 ([`p838`]), and here the effective medium of rain (docs/physics.md section 3):
//! the paper's quasi-static model and the forward-scattering (Mie, van de Hulst) model,
//! integrated over a drop-size distribution on a composite Gauss-Legendre rule.
//!
//! Everything that depends only on the frequency and the options (water permittivity,
//! Mie amplitudes, shape and wind factors on the quadrature nodes) is collected once in a
//! [`RainKernel`]; a rain rate then costs one pass over the nodes. Kernels are cached per
//! (frequency, options), so sweeping rain rates at fixed frequencies is cheap.
//!
//! Polarisation and shape in the forward-scattering model: Mie theory is for spheres, so
//! each drop's sphere amplitude is multiplied by `beta_p / beta_sphere`, the ratio of the
//! quasi-static polarisability of the (canted) spheroid along the polarisation to that of
//! the equal-volume sphere. This is exact in the Rayleigh limit and an approximation for
//! large drops (it ignores how shape changes the resonances); against ITU-R P.838-3 it
//! brings the H/V split to the right sign and size (see the tests and README).

pub mod drops;
pub mod dsd;
pub mod mie;
pub mod p838;
pub mod quadrature;
pub mod water;

use crate::error::{CoreError, Result, check_range};
use crate::medium::drops::{Shape, depolarisation_factors, polarisability, terminal_velocity_m_s};
use crate::medium::dsd::{DIAMETER_RANGE_MM, Dsd};
use crate::medium::mie::mie_forward_with;
use crate::medium::quadrature::{CompositeRule, panel_edges};
use crate::medium::water::{check_temperature, water_permittivity};
use crate::{SPEED_OF_LIGHT_M_S, wavenumber};
use ndarray::{Array1, ArrayView1};
use num_complex::Complex64;
use rayon::prelude::*;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::str::FromStr;
use std::sync::{Arc, Mutex, OnceLock};

/// Frequencies the medium models accept, Hz (1-1000 GHz).
pub const FREQ_RANGE_HZ: (f64, f64) = (1e9, 1e12);
/// Largest rain rate accepted, mm/h (above the heaviest rain ever measured).
pub const MAX_RAIN_RATE_MM_H: f64 = 500.0;
/// Largest horizontal wind speed accepted, m/s.
pub const MAX_WIND_SPEED_M_S: f64 = 60.0;
/// dB per neper of field amplitude per metre, expressed per km: `20 log10(e) * 1000`.
pub const DB_PER_KM_PER_NP_PER_M: f64 = 8685.889638065036;

/// Which effective-medium model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Model {
    /// The paper's dilute quasi-static (Maxwell Garnett) mixture, typos corrected.
    QuasiStatic,
    /// Van de Hulst's forward-scattering index with Mie amplitudes. Default.
    ForwardScattering,
}

impl FromStr for Model {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "quasi-static" => Ok(Model::QuasiStatic),
            "forward-scattering" => Ok(Model::ForwardScattering),
            _ => Err(CoreError::invalid(
                "model",
                "must be 'forward-scattering' or 'quasi-static'",
                format!("{s:?}"),
            )),
        }
    }
}

/// Field polarisation relative to the (vertical) drop symmetry axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Polarization {
    /// Horizontal: sees the drops' major axes (Lx).
    H,
    /// Vertical: sees the minor (symmetry) axis (Lz).
    V,
    /// The paper's orientation average `(1/3) sum_i beta_i`.
    Average,
}

impl FromStr for Polarization {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "h" => Ok(Polarization::H),
            "v" => Ok(Polarization::V),
            "average" => Ok(Polarization::Average),
            _ => Err(CoreError::invalid(
                "polarization",
                "must be 'h', 'v' or 'average'",
                format!("{s:?}"),
            )),
        }
    }
}

/// How wind changes the drops' effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WindModel {
    /// Drops cant by `atan(v_wind / v_t(D))` in the polarisation plane; polarisabilities are
    /// projected onto the field. Default.
    Canting,
    /// The paper's literal factor `1 / cos(atan(v_wind / v_t(D)))` on every drop; grows
    /// without bound in strong wind. `v_t` is floored at 0.1 m/s for this option because the
    /// Atlas fit reaches zero at 0.109 mm, where the literal factor diverges.
    Paper,
}

impl FromStr for WindModel {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "canting" => Ok(WindModel::Canting),
            "paper" => Ok(WindModel::Paper),
            _ => Err(CoreError::invalid(
                "wind_model",
                "must be 'canting' or 'paper'",
                format!("{s:?}"),
            )),
        }
    }
}

/// Everything besides frequency and rain rate that sets the medium.
#[derive(Debug, Clone, PartialEq)]
pub struct MediumOptions {
    /// Effective-medium model.
    pub model: Model,
    /// Polarisation.
    pub polarization: Polarization,
    /// Drop shape rule.
    pub shape: Shape,
    /// Water temperature, C (0-40).
    pub temperature_c: f64,
    /// Horizontal wind speed across the path, m/s (0-60).
    pub wind_speed_m_s: f64,
    /// How wind acts.
    pub wind_model: WindModel,
    /// Drop-size distribution.
    pub dsd: Dsd,
    /// Gauss-Legendre points per quadrature panel (the convergence test doubles it).
    pub nodes_per_panel: usize,
}

impl Default for MediumOptions {
    fn default() -> Self {
        MediumOptions {
            model: Model::ForwardScattering,
            polarization: Polarization::H,
            shape: Shape::BeardChuang,
            temperature_c: 20.0,
            wind_speed_m_s: 0.0,
            wind_model: WindModel::Canting,
            dsd: Dsd::marshall_palmer(),
            nodes_per_panel: 16,
        }
    }
}

impl MediumOptions {
    /// Checks the scalar options.
    pub fn validate(&self) -> Result<()> {
        check_temperature(self.temperature_c)?;
        check_range(
            "wind_speed_m_s",
            self.wind_speed_m_s,
            0.0,
            MAX_WIND_SPEED_M_S,
            "must be finite and within 0..60 m/s",
        )?;
        if !(4..=128).contains(&self.nodes_per_panel) {
            return Err(CoreError::invalid(
                "nodes_per_panel",
                "must be within 4..128",
                self.nodes_per_panel,
            ));
        }
        Ok(())
    }
}

/// Checks a frequency.
pub fn check_freq(freq_hz: f64) -> Result<()> {
    check_range(
        "freq_hz",
        freq_hz,
        FREQ_RANGE_HZ.0,
        FREQ_RANGE_HZ.1,
        "must be finite and within 1e9..1e12 Hz (1-1000 GHz)",
    )
}

/// Checks a rain rate.
pub fn check_rain_rate(rain_rate_mm_h: f64) -> Result<()> {
    check_range(
        "rain_rate_mm_h",
        rain_rate_mm_h,
        0.0,
        MAX_RAIN_RATE_MM_H,
        "must be finite and within 0..500 mm/h",
    )
}

/// Effective refractive index and permittivity of rain at one frequency and rain rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effective {
    /// Refractive index, `Im n <= 0`.
    pub n: Complex64,
    /// Relative permittivity `n^2`.
    pub eps: Complex64,
    /// Power specific attenuation, dB/km: `8685.9 k0 |Im n|`.
    pub gamma_db_per_km: f64,
}

/// What one frequency and one set of options contribute on the quadrature nodes.
#[derive(Debug, Clone)]
pub struct RainKernel {
    freq_hz: f64,
    model: Model,
    dsd: Dsd,
    nodes_mm: Vec<f64>,
    /// `w_i K(D_i)`: `eps - 1` (quasi-static) or `n - 1` (forward) per unit N(D_i), m^3 mm;
    /// for a gamma distribution the rate-independent `D_i^mu` is folded in too, so a rain
    /// rate costs one `exp` per node.
    weighted: Vec<Complex64>,
}

/// Largest quadrature panel in D, mm: resolves both the exponential fall of N(D) and the
/// Mie ripple (at most 3 units of size parameter per panel).
fn max_panel_width_mm(freq_hz: f64) -> f64 {
    let k0 = wavenumber(freq_hz);
    (2.0 * 3.0 / k0 * 1e3).min(1.0)
}

/// Per-drop factor for polarisation, shape and wind, relative to the sphere:
/// returns `(beta_p' / beta_sphere, extra)` with `extra` the paper's wind factor (1 when off).
fn drop_factor(eps_w: Complex64, d_mm: f64, opts: &MediumOptions) -> (Complex64, f64) {
    let r = opts.shape.axial_ratio(d_mm);
    let extra = match opts.wind_model {
        WindModel::Canting => 1.0,
        WindModel::Paper => {
            let vt = terminal_velocity_m_s(d_mm).max(0.1);
            1.0 / (opts.wind_speed_m_s / vt).atan().cos()
        }
    };
    if r >= 1.0 {
        // A sphere looks the same from every side: exactly the sphere amplitude.
        return (Complex64::new(1.0, 0.0), extra);
    }
    let beta_sphere = polarisability(eps_w, 1.0 / 3.0);
    let (lx, lz) = depolarisation_factors(r);
    let (bx, bz) = (polarisability(eps_w, lx), polarisability(eps_w, lz));
    let cant = match opts.wind_model {
        WindModel::Canting => opts.wind_speed_m_s.atan2(terminal_velocity_m_s(d_mm)),
        WindModel::Paper => 0.0,
    };
    let (s2, c2) = (cant.sin().powi(2), cant.cos().powi(2));
    let beta_p = match opts.polarization {
        Polarization::H => bx * c2 + bz * s2,
        Polarization::V => bz * c2 + bx * s2,
        Polarization::Average => (2.0 * bx + bz) / 3.0,
    };
    (beta_p / beta_sphere, extra)
}

impl RainKernel {
    /// Builds the kernel (Mie sums on every node for the forward model). Checks inputs.
    pub fn new(freq_hz: f64, opts: &MediumOptions) -> Result<Self> {
        check_freq(freq_hz)?;
        opts.validate()?;
        let (dmin, dmax) = DIAMETER_RANGE_MM;
        let mut breaks = vec![drops::SPHEROID_FROM_MM];
        breaks.extend(opts.dsd.breakpoints_mm());
        let edges = panel_edges(dmin, dmax, &breaks, max_panel_width_mm(freq_hz));
        let rule = CompositeRule::new(&edges, opts.nodes_per_panel)?;
        let k0 = wavenumber(freq_hz);
        let eps_w = water_permittivity(freq_hz, opts.temperature_c);
        let m_bh = eps_w.sqrt().conj();
        let mut scratch = Vec::new();
        let weighted = rule
            .nodes
            .iter()
            .zip(&rule.weights)
            .map(|(&d_mm, &w)| {
                let (ratio, extra) = drop_factor(eps_w, d_mm, opts);
                let base = match opts.model {
                    Model::QuasiStatic => {
                        let vol_m3 = PI / 6.0 * (d_mm * 1e-3).powi(3);
                        vol_m3 * polarisability(eps_w, 1.0 / 3.0)
                    }
                    Model::ForwardScattering => {
                        let x = k0 * d_mm * 1e-3 / 2.0;
                        let s0 = mie_forward_with(m_bh, x, &mut scratch).s0;
                        Complex64::new(0.0, -2.0 * PI / k0.powi(3)) * s0.conj()
                    }
                };
                let shape_of_n = match &opts.dsd {
                    Dsd::Gamma { mu, .. } => d_mm.powf(*mu),
                    Dsd::Table { .. } => 1.0,
                };
                w * extra * ratio * base * shape_of_n
            })
            .collect();
        Ok(RainKernel {
            freq_hz,
            model: opts.model,
            dsd: opts.dsd.clone(),
            nodes_mm: rule.nodes,
            weighted,
        })
    }

    /// Number of quadrature nodes.
    pub fn len(&self) -> usize {
        self.nodes_mm.len()
    }

    /// Whether the rule is empty (never, for a kernel built by [`RainKernel::new`]).
    pub fn is_empty(&self) -> bool {
        self.nodes_mm.is_empty()
    }

    /// The medium at `rain_rate_mm_h` (checked). A zero rate is clear air exactly.
    pub fn evaluate(&self, rain_rate_mm_h: f64) -> Result<Effective> {
        check_rain_rate(rain_rate_mm_h)?;
        Ok(self.evaluate_unchecked(rain_rate_mm_h))
    }

    /// The medium at each rain rate (all checked first), in parallel.
    pub fn evaluate_many(&self, rain_rate_mm_h: ArrayView1<'_, f64>) -> Result<Vec<Effective>> {
        rain_rate_mm_h
            .iter()
            .try_for_each(|&r| check_rain_rate(r))?;
        let rates: Vec<f64> = rain_rate_mm_h.iter().copied().collect();
        Ok(rates
            .par_iter()
            .with_min_len(256)
            .map(|&r| self.evaluate_unchecked(r))
            .collect())
    }

    fn evaluate_unchecked(&self, rain_rate_mm_h: f64) -> Effective {
        let one = Complex64::new(1.0, 0.0);
        if rain_rate_mm_h == 0.0 {
            return Effective {
                n: one,
                eps: one,
                gamma_db_per_km: 0.0,
            };
        }
        let nodes = self.nodes_mm.iter().zip(&self.weighted);
        let s: Complex64 = match &self.dsd {
            Dsd::Gamma {
                n0_coeff,
                n0_exp,
                lambda_coeff,
                lambda_exp,
                ..
            } => {
                let lambda = lambda_coeff * rain_rate_mm_h.powf(*lambda_exp);
                let n0 = n0_coeff * rain_rate_mm_h.powf(*n0_exp);
                n0 * nodes
                    .map(|(&d, &k)| k * (-lambda * d).exp())
                    .sum::<Complex64>()
            }
            Dsd::Table { .. } => nodes
                .map(|(&d, &k)| k * self.dsd.density(d, rain_rate_mm_h))
                .sum(),
        };
        let (n, eps) = match self.model {
            Model::QuasiStatic => ((one + s).sqrt(), one + s),
            Model::ForwardScattering => (one + s, (one + s) * (one + s)),
        };
        Effective {
            n,
            eps,
            gamma_db_per_km: -DB_PER_KM_PER_NP_PER_M * wavenumber(self.freq_hz) * n.im,
        }
    }
}
/// Free-space wavelength, m.
pub fn wavelength_m(freq_hz: f64) -> f64 {
    SPEED_OF_LIGHT_M_S / freq_hz
}

mod many;
pub use many::{cached_kernel, clear_kernel_cache, effective_many, specific_attenuation_many};

#[cfg(test)]
mod tests;
