//! Bindings of the rain medium: water, drop sizes and shapes, Mie, quadrature, the effective
//! medium and ITU-R P.838 (`rainuav.medium` drives them).

use crate::{detached, same_len, to_py};
use ndarray::Array1;
use num_complex::Complex64;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::medium::drops::{self, Shape};
use rainuav_core::medium::dsd::Dsd;
use rainuav_core::medium::{self, MediumOptions, RainKernel};
use std::sync::Arc;

/// Water permittivity for pairs of (frequency, temperature); checks both.
#[pyfunction]
fn water_permittivity<'py>(
    py: Python<'py>,
    freq_hz: PyReadonlyArray1<'py, f64>,
    temperature_c: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<Complex64>>> {
    let (f, t) = (freq_hz.as_array(), temperature_c.as_array());
    same_len("temperature_c", &f, &t)?;
    let out = detached(py, || {
        f.iter().try_for_each(|&v| medium::check_freq(v))?;
        t.iter()
            .try_for_each(|&v| medium::water::check_temperature(v))?;
        Ok(f.iter()
            .zip(t.iter())
            .map(|(&f, &t)| medium::water::water_permittivity(f, t))
            .collect::<Array1<Complex64>>())
    })?;
    Ok(out.into_pyarray(py))
}

/// A drop-size distribution (see `rainuav.medium`).
#[pyclass(frozen, module = "rainuav._core")]
struct DropSizeDistribution {
    inner: Dsd,
}

#[pymethods]
impl DropSizeDistribution {
    /// Marshall-Palmer: N = 8000 exp(-4.1 R^-0.21 D) m^-3 mm^-1.
    #[staticmethod]
    fn marshall_palmer() -> Self {
        DropSizeDistribution {
            inner: Dsd::marshall_palmer(),
        }
    }

    /// Gamma: N = n0 R^n0_exp D^mu exp(-lambda_coeff R^lambda_exp D).
    #[staticmethod]
    #[pyo3(signature = (n0, mu, lambda_coeff, lambda_exp, n0_exp=0.0))]
    fn gamma(n0: f64, mu: f64, lambda_coeff: f64, lambda_exp: f64, n0_exp: f64) -> PyResult<Self> {
        Ok(DropSizeDistribution {
            inner: Dsd::gamma(n0, n0_exp, mu, lambda_coeff, lambda_exp).map_err(to_py)?,
        })
    }

    /// A tabulated N(D), linearly interpolated; scales with rain rate / table_rain_rate_mm_h.
    #[staticmethod]
    fn table(
        diameter_mm: PyReadonlyArray1<'_, f64>,
        density: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        Ok(DropSizeDistribution {
            inner: Dsd::table(diameter_mm.as_array().to_vec(), density.as_array().to_vec())
                .map_err(to_py)?,
        })
    }

    /// The rain rate the table itself carries (Atlas fall speeds); None for parametric forms.
    #[getter]
    fn table_rain_rate_mm_h(&self) -> Option<f64> {
        match &self.inner {
            Dsd::Table {
                table_rain_rate_mm_h,
                ..
            } => Some(*table_rain_rate_mm_h),
            Dsd::Gamma { .. } => None,
        }
    }

    /// N(D) in m^-3 mm^-1 for pairs (diameter_mm, rain_rate_mm_h); zero rate gives zero.
    fn density<'py>(
        &self,
        py: Python<'py>,
        diameter_mm: PyReadonlyArray1<'py, f64>,
        rain_rate_mm_h: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (d, r) = (diameter_mm.as_array(), rain_rate_mm_h.as_array());
        same_len("rain_rate_mm_h", &d, &r)?;
        let out = detached(py, || {
            d.iter().try_for_each(|&v| {
                rainuav_core::error::check_range(
                    "diameter_mm",
                    v,
                    0.0,
                    20.0,
                    "must be finite and within 0..20 mm",
                )
            })?;
            r.iter().try_for_each(|&v| medium::check_rain_rate(v))?;
            Ok(d.iter()
                .zip(r.iter())
                .map(|(&d, &r)| {
                    if r == 0.0 {
                        0.0
                    } else {
                        self.inner.density(d, r)
                    }
                })
                .collect::<Array1<f64>>())
        })?;
        Ok(out.into_pyarray(py))
    }

    fn __repr__(&self) -> String {
        match &self.inner {
            Dsd::Gamma {
                n0_coeff,
                n0_exp,
                mu,
                lambda_coeff,
                lambda_exp,
            } => format!(
                "DropSizeDistribution.gamma(n0={n0_coeff}, mu={mu}, lambda_coeff={lambda_coeff}, \
                 lambda_exp={lambda_exp}, n0_exp={n0_exp})"
            ),
            Dsd::Table { diameter_mm, .. } => {
                format!("DropSizeDistribution.table(<{} rows>)", diameter_mm.len())
            }
        }
    }
}

/// Options of the rain medium (see `rainuav.medium.effective_permittivity`).
#[pyclass(frozen, module = "rainuav._core")]
struct MediumConfig {
    inner: MediumOptions,
}

#[pymethods]
impl MediumConfig {
    #[new]
    #[pyo3(signature = (*, model, polarization, shape, temperature_c, wind_speed_m_s, wind_model, dsd, nodes_per_panel=16))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: &str,
        polarization: &str,
        shape: &str,
        temperature_c: f64,
        wind_speed_m_s: f64,
        wind_model: &str,
        dsd: PyRef<'_, DropSizeDistribution>,
        nodes_per_panel: usize,
    ) -> PyResult<Self> {
        let inner = MediumOptions {
            model: model.parse().map_err(to_py)?,
            polarization: polarization.parse().map_err(to_py)?,
            shape: shape.parse().map_err(to_py)?,
            temperature_c,
            wind_speed_m_s,
            wind_model: wind_model.parse().map_err(to_py)?,
            dsd: dsd.inner.clone(),
            nodes_per_panel,
        };
        inner.validate().map_err(to_py)?;
        Ok(MediumConfig { inner })
    }

    fn __repr__(&self) -> String {
        format!("MediumConfig({:?})", self.inner)
    }
}

/// Two real arrays handed to Python.
type RealPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

type MediumArrays<'py> = (
    Bound<'py, PyArray1<Complex64>>,
    Bound<'py, PyArray1<Complex64>>,
    Bound<'py, PyArray1<f64>>,
);

fn split(py: Python<'_>, all: Vec<medium::Effective>) -> MediumArrays<'_> {
    let eps: Array1<Complex64> = all.iter().map(|e| e.eps).collect();
    let n: Array1<Complex64> = all.iter().map(|e| e.n).collect();
    let g: Array1<f64> = all.iter().map(|e| e.gamma_db_per_km).collect();
    (eps.into_pyarray(py), n.into_pyarray(py), g.into_pyarray(py))
}

/// (eps, n, gamma_db_per_km) for pairs (freq_hz[i], rain_rate_mm_h[i]).
#[pyfunction]
fn effective_medium<'py>(
    py: Python<'py>,
    freq_hz: PyReadonlyArray1<'py, f64>,
    rain_rate_mm_h: PyReadonlyArray1<'py, f64>,
    config: PyRef<'py, MediumConfig>,
) -> PyResult<MediumArrays<'py>> {
    let (f, r) = (freq_hz.as_array(), rain_rate_mm_h.as_array());
    same_len("rain_rate_mm_h", &f, &r)?;
    let opts = &config.inner;
    let all = detached(py, || medium::effective_many(f, r, opts))?;
    Ok(split(py, all))
}

/// The rain medium at one frequency: precomputed on the quadrature nodes, then cheap per rate.
#[pyclass(frozen, module = "rainuav._core")]
struct RainMediumKernel {
    inner: Arc<RainKernel>,
}

#[pymethods]
impl RainMediumKernel {
    #[new]
    fn new(py: Python<'_>, freq_hz: f64, config: PyRef<'_, MediumConfig>) -> PyResult<Self> {
        let opts = &config.inner;
        let inner = detached(py, || medium::cached_kernel(freq_hz, opts))?;
        Ok(RainMediumKernel { inner })
    }

    /// Number of quadrature nodes.
    #[getter]
    fn nodes(&self) -> usize {
        self.inner.len()
    }

    /// (eps, n, gamma_db_per_km) for each rain rate.
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        rain_rate_mm_h: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<MediumArrays<'py>> {
        let r = rain_rate_mm_h.as_array();
        let kernel = &self.inner;
        let all = detached(py, || kernel.evaluate_many(r))?;
        Ok(split(py, all))
    }
}

/// ITU-R P.838-3 specific attenuation (dB/km) for pairs; tilt 0 = H, 90 = V, 45 = circular.
#[pyfunction]
fn itu_p838<'py>(
    py: Python<'py>,
    freq_hz: PyReadonlyArray1<'py, f64>,
    rain_rate_mm_h: PyReadonlyArray1<'py, f64>,
    tilt_deg: f64,
    elevation_deg: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (f, r) = (freq_hz.as_array(), rain_rate_mm_h.as_array());
    same_len("rain_rate_mm_h", &f, &r)?;
    let out = detached(py, || {
        rainuav_core::error::check_range(
            "tilt_deg",
            tilt_deg,
            -360.0,
            360.0,
            "must be finite and within -360..360 degrees",
        )?;
        rainuav_core::error::check_range(
            "elevation_deg",
            elevation_deg,
            -90.0,
            90.0,
            "must be finite and within -90..90 degrees",
        )?;
        f.iter().try_for_each(|&v| medium::check_freq(v))?;
        r.iter().try_for_each(|&v| medium::check_rain_rate(v))?;
        Ok(f.iter()
            .zip(r.iter())
            .map(|(&f, &r)| medium::p838::specific_attenuation(f, r, tilt_deg, elevation_deg))
            .collect::<Array1<f64>>())
    })?;
    Ok(out.into_pyarray(py))
}

/// Bohren-Huffman Mie forward amplitude: (S(0), Q_ext, Q_sca) for m (Im m >= 0) and x.
#[pyfunction]
fn mie_forward(m: Complex64, x: f64) -> PyResult<(Complex64, f64, f64)> {
    if !(m.re.is_finite() && m.im.is_finite() && m.re > 0.0 && m.im >= 0.0) {
        return Err(to_py(CoreError::invalid(
            "m",
            "must be finite with Re m > 0 and Im m >= 0 (Bohren-Huffman convention)",
            m,
        )));
    }
    rainuav_core::error::check_range("x", x, 1e-8, 1e4, "must be finite and within 1e-8..1e4")
        .map_err(to_py)?;
    let r = medium::mie::mie_forward(m, x);
    Ok((r.s0, r.qext, r.qsca))
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Golub-Welsch).
#[pyfunction]
fn gauss_legendre<'py>(py: Python<'py>, n: usize) -> PyResult<RealPair<'py>> {
    let (x, w) = medium::quadrature::gauss_legendre(n).map_err(to_py)?;
    Ok((x.into_pyarray(py), w.into_pyarray(py)))
}

/// Depolarisation factors (Lx, Lz) of an oblate spheroid with axial ratio r in (0, 1].
#[pyfunction]
fn depolarisation_factors(axial_ratio: f64) -> PyResult<(f64, f64)> {
    rainuav_core::error::check_range(
        "axial_ratio",
        axial_ratio,
        1e-3,
        1.0,
        "must be finite and within 0.001..1",
    )
    .map_err(to_py)?;
    Ok(drops::depolarisation_factors(axial_ratio))
}

/// Axial ratio (minor/major) of a drop of diameter_mm under a shape rule.
#[pyfunction]
fn axial_ratio(shape: &str, diameter_mm: f64) -> PyResult<f64> {
    let shape: Shape = shape.parse().map_err(to_py)?;
    rainuav_core::error::check_range(
        "diameter_mm",
        diameter_mm,
        0.0,
        20.0,
        "must be finite and within 0..20 mm",
    )
    .map_err(to_py)?;
    Ok(shape.axial_ratio(diameter_mm))
}

/// Atlas et al. (1973) terminal velocity, m/s.
#[pyfunction]
fn terminal_velocity_m_s(diameter_mm: f64) -> PyResult<f64> {
    rainuav_core::error::check_range(
        "diameter_mm",
        diameter_mm,
        0.0,
        20.0,
        "must be finite and within 0..20 mm",
    )
    .map_err(to_py)?;
    Ok(drops::terminal_velocity_m_s(diameter_mm))
}

/// Adds this layer's classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<DropSizeDistribution>()?;
    m.add_class::<MediumConfig>()?;
    m.add_class::<RainMediumKernel>()?;
    m.add_function(wrap_pyfunction!(water_permittivity, m)?)?;
    m.add_function(wrap_pyfunction!(effective_medium, m)?)?;
    m.add_function(wrap_pyfunction!(itu_p838, m)?)?;
    m.add_function(wrap_pyfunction!(mie_forward, m)?)?;
    m.add_function(wrap_pyfunction!(gauss_legendre, m)?)?;
    m.add_function(wrap_pyfunction!(depolarisation_factors, m)?)?;
    m.add_function(wrap_pyfunction!(axial_ratio, m)?)?;
    m.add_function(wrap_pyfunction!(terminal_velocity_m_s, m)?)?;
    Ok(())
}
