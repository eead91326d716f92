//! Bindings of the diffraction formulas (ITU-R P.526: the knife edge, the UTD wedge,
//! Bullington), for the tests' independent checks and the tracer's wedge.

use crate::to_py;
use num_complex::Complex64;
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use rainuav_core::CoreError;

/// ITU-R P.526's knife-edge loss J(nu), dB, of each `nu`.
#[pyfunction]
fn knife_edge_loss_db<'py>(
    py: Python<'py>,
    nu: PyReadonlyArray1<'py, f64>,
) -> Bound<'py, numpy::PyArray1<f64>> {
    nu.as_array()
        .mapv(rainuav_core::propagation::diffraction::knife_edge_loss_db)
        .into_pyarray(py)
}

/// The UTD diffraction coefficient of a finitely conducting wedge (ITU-R P.526-15 section 6)
/// at each `phi2`: exterior angle `n pi`, incidence angle `phi1` and diffraction angles
/// `phi2` (rad, from face 0), distance parameter `l_m`, `sin_beta0`, wavenumber `k` and the
/// faces' reflection coefficients `r0`, `rn` (complex, or one a `phi2`); complex, sqrt(m).
#[pyfunction]
#[pyo3(signature = (n, phi1, phi2, *, l_m, sin_beta0, k, r0, rn))]
#[allow(clippy::too_many_arguments)]
fn utd_wedge<'py>(
    py: Python<'py>,
    n: f64,
    phi1: f64,
    phi2: PyReadonlyArray1<'py, f64>,
    l_m: f64,
    sin_beta0: f64,
    k: f64,
    r0: Complex64,
    rn: Complex64,
) -> PyResult<Bound<'py, numpy::PyArray1<Complex64>>> {
    let ok = n > 1.0 && n <= 2.0 && l_m > 0.0 && k > 0.0 && sin_beta0 > 0.0 && sin_beta0 <= 1.0;
    if !ok || !phi1.is_finite() {
        return Err(to_py(CoreError::invalid(
            "utd_wedge",
            "needs 1 < n <= 2, l_m > 0, k > 0, 0 < sin_beta0 <= 1",
            format!("n {n}, l_m {l_m}, k {k}, sin_beta0 {sin_beta0}"),
        )));
    }
    Ok(phi2
        .as_array()
        .mapv(|p| {
            rainuav_core::propagation::diffraction::utd_wedge(n, phi1, p, l_m, sin_beta0, k, r0, rn)
        })
        .into_pyarray(py))
}

/// The Bullington loss (P.526-15 section 4.5.1 with its correction) of the profile
/// `(d_m[i], h_m[i])` between antennas at `h_ts_m` and `h_rs_m` above sea level, `d_total_m`
/// apart: `(loss_db, knife_edge_db, edge_d_m, edge_h_m)` (the edge NaN where the loss is 0).
#[pyfunction]
#[pyo3(signature = (d_m, h_m, *, d_total_m, h_ts_m, h_rs_m, wavelength_m))]
fn bullington_loss(
    d_m: PyReadonlyArray1<'_, f64>,
    h_m: PyReadonlyArray1<'_, f64>,
    d_total_m: f64,
    h_ts_m: f64,
    h_rs_m: f64,
    wavelength_m: f64,
) -> PyResult<(f64, f64, f64, f64)> {
    let (d, h) = (d_m.as_array(), h_m.as_array());
    if d.len() != h.len() {
        return Err(to_py(CoreError::invalid(
            "h_m",
            "must have the length of d_m",
            h.len(),
        )));
    }
    let ok = [d_total_m, h_ts_m, h_rs_m, wavelength_m]
        .iter()
        .chain(d.iter())
        .chain(h.iter())
        .all(|v| v.is_finite())
        && d_total_m > 0.0
        && wavelength_m > 0.0;
    if !ok {
        return Err(to_py(CoreError::invalid(
            "profile",
            "must be finite, with d_total_m > 0 and wavelength_m > 0",
            "a bad value",
        )));
    }
    let profile: Vec<(f64, f64)> = d.iter().copied().zip(h.iter().copied()).collect();
    let b = rainuav_core::propagation::diffraction::bullington(
        &profile,
        d_total_m,
        h_ts_m,
        h_rs_m,
        wavelength_m,
    );
    let (ed, eh) = b.edge.unwrap_or((f64::NAN, f64::NAN));
    Ok((b.loss_db, b.knife_edge_db, ed, eh))
}

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(utd_wedge, m)?)?;
    m.add_function(wrap_pyfunction!(knife_edge_loss_db, m)?)?;
    m.add_function(wrap_pyfunction!(bullington_loss, m)?)?;
    Ok(())
}
