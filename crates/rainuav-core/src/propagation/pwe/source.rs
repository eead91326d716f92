//! Apertures: the field a source puts on the march's first plane.

use crate::error::{Result, check_range};
use crate::wavenumber;
use ndarray::Array2;
use num_complex::Complex64;

use super::C32;
use super::march::to_c32;
use super::spec::{Ground, MarchSpec, Propagator};
use crate::memory::check_memory;
use rayon::prelude::*;

/// Gaussian-beam aperture (docs/physics.md section 4): height `height_m`, elevation tilt
/// `elevation_deg`, half-power beamwidth `beamwidth_deg`, on the grid `x = (ix - nx/2) dx`,
/// `y = iy dy`. Computed in f64, stored as complex64.
// Mirrors `rainuav.pwe.gaussian_beam`'s signature one to one.
#[allow(clippy::too_many_arguments)]
pub fn gaussian_beam(
    nx: usize,
    ny: usize,
    dx_m: f64,
    dy_m: f64,
    freq_hz: f64,
    height_m: f64,
    elevation_deg: f64,
    beamwidth_deg: f64,
) -> Result<Array2<C32>> {
    check_range(
        "beamwidth_deg",
        beamwidth_deg,
        1e-3,
        179.0,
        "must be finite and within 0.001..179 degrees",
    )?;
    check_range(
        "elevation_deg",
        elevation_deg,
        -89.0,
        89.0,
        "must be finite and within -89..89 degrees",
    )?;
    check_range("height_m", height_m, -1e6, 1e6, "must be finite")?;
    let spec = MarchSpec {
        nx,
        ny,
        dx_m,
        dy_m,
        dz_m: 1.0,
        freq_hz,
        propagator: Propagator::Wide,
        ground: Ground::None,
        absorber: 0.0,
        x_absorber_every: 1,
    };
    spec.validate()?;
    check_memory(nx * ny * size_of::<C32>())?;
    let k0 = wavenumber(freq_hz);
    let a = k0 * (0.5 * beamwidth_deg.to_radians()).sin();
    let c = a * a / (2.0 * std::f64::consts::LN_2);
    let kt = k0 * elevation_deg.to_radians().sin();
    let mut out = Array2::<C32>::zeros((nx, ny));
    out.axis_iter_mut(ndarray::Axis(0))
        .into_par_iter()
        .enumerate()
        .for_each(|(ix, mut row)| {
            let x = (ix as f64 - (nx / 2) as f64) * dx_m;
            for (iy, v) in row.iter_mut().enumerate() {
                let y = iy as f64 * dy_m - height_m;
                let amp = (-c * (x * x + y * y)).exp();
                *v = to_c32(Complex64::from_polar(amp, -kt * y));
            }
        });
    Ok(out)
}
