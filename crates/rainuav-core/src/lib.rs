//! # rainuav-core
//!
//! The pure-Rust core of rainuav, in three layers that do not import one another (the Python
//! bindings join them; `tests/test_layout.py` checks it):
//!
//! - [`medium`]: the rain medium (water permittivity, drop sizes and shapes, Mie scattering,
//!   the effective medium of rain, ITU-R P.838-3);
//! - [`propagation`]: the split-step parabolic equation and the ray engine (ground, terrain,
//!   buildings; rain along every path);
//! - [`planning`]: the exact planners, in space, time and among flight levels.
//!
//! Conventions follow `docs/physics.md`: time dependence `exp(+j w t)`, lossy media have
//! `Im eps <= 0`, drop diameters in mm.
//!
//! ```
//! use rainuav_core::medium::{MediumOptions, RainKernel};
//! // Specific attenuation of 25 mm/h Marshall-Palmer rain at 28 GHz, horizontal polarisation.
//! let kernel = RainKernel::new(28e9, &MediumOptions::default()).unwrap();
//! let gamma = kernel.evaluate(25.0).unwrap().gamma_db_per_km;
//! let itu = rainuav_core::medium::p838::specific_attenuation(28e9, 25.0, 0.0, 0.0);
//! // Above 10 GHz the model is within 0.8-1.3 of P.838-3 over 12.5-150 mm/h (README table,
//! // `python -m rainuav.validate rain`); here 1.08.
//! assert!(gamma / itu > 0.8 && gamma / itu < 1.3, "{}", gamma / itu);
//! ```

pub mod error;
pub mod medium;
pub mod memory;
pub mod planning;
pub mod propagation;

pub use error::{CoreError, Result};

/// Speed of light in vacuum, m/s.
pub const SPEED_OF_LIGHT_M_S: f64 = 299_792_458.0;

/// The length of the vector `(x, y)`: `sqrt(x^2 + y^2)`, without the overflow guard of
/// `f64::hypot` (several times slower, and lengths in metres never come near it).
#[inline]
pub(crate) fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// Free-space wavenumber `k0 = 2 pi f / c`, rad/m.
pub fn wavenumber(freq_hz: f64) -> f64 {
    2.0 * std::f64::consts::PI * freq_hz / SPEED_OF_LIGHT_M_S
}

/// A seeded uniform stream in `0..1` for the tests' random cases: a 64-bit linear
/// congruential generator (Knuth's MMIX constants), its top 53 bits.
#[cfg(test)]
pub(crate) fn test_stream(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
