//! `rainuav._core`: the Python face of `rainuav-core`. This crate only converts: numpy arrays
//! in as read-only views, owned arrays out without copying, core errors onto the
//! `rainuav.RainuavError` hierarchy, and long work without the GIL. Broadcasting, defaults
//! and docs live in `python/rainuav`.

use ndarray::{Array1, ArrayView1};
use num_complex::Complex64;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadwriteArray2, PyReadwriteArray3,
};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::drops::{self, Shape};
use rainuav_core::dsd::Dsd;
use rainuav_core::medium::{self, MediumOptions, RainKernel};
use rainuav_core::pwe::{
    self, C32, Ground, MarchSpec, Marcher, Propagator, Recording, StepMedium, StepObstacle,
};
use std::sync::Arc;

pyo3::import_exception!(rainuav.errors, RainuavError);
pyo3::import_exception!(rainuav.errors, InvalidInputError);

/// The one place core errors become Python exceptions.
fn to_py(err: CoreError) -> PyErr {
    match err {
        CoreError::InvalidArgument { .. } => InvalidInputError::new_err(err.to_string()),
        CoreError::Internal(_) => RainuavError::new_err(err.to_string()),
    }
}

/// Runs `work` without the GIL; a panic (a bug: inputs are validated first) becomes a
/// `RainuavError` instead of unwinding into Python.
fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> Result<T, CoreError> + Send,
{
    py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)).unwrap_or_else(|p| {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into());
            Err(CoreError::Internal(msg))
        })
    })
    .map_err(to_py)
}

fn same_len(name: &'static str, a: &ArrayView1<'_, f64>, b: &ArrayView1<'_, f64>) -> PyResult<()> {
    if a.len() == b.len() {
        Ok(())
    } else {
        Err(to_py(CoreError::invalid(
            name,
            format!("must have {} values", a.len()),
            b.len(),
        )))
    }
}

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
            .try_for_each(|&v| rainuav_core::water::check_temperature(v))?;
        Ok(f.iter()
            .zip(t.iter())
            .map(|(&f, &t)| rainuav_core::water::water_permittivity(f, t))
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
            .map(|(&f, &r)| rainuav_core::p838::specific_attenuation(f, r, tilt_deg, elevation_deg))
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
    let r = rainuav_core::mie::mie_forward(m, x);
    Ok((r.s0, r.qext, r.qsca))
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Golub-Welsch).
#[pyfunction]
fn gauss_legendre<'py>(py: Python<'py>, n: usize) -> PyResult<RealPair<'py>> {
    let (x, w) = rainuav_core::quadrature::gauss_legendre(n).map_err(to_py)?;
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

/// A split-step PE march in progress (see `rainuav.pwe.march`, which drives it in chunks).
#[pyclass(module = "rainuav._core")]
struct PeMarcher {
    inner: Option<Marcher>,
}

impl PeMarcher {
    fn marcher(&mut self) -> PyResult<&mut Marcher> {
        self.inner.as_mut().ok_or_else(|| {
            RainuavError::new_err("this march has finished; its field was handed over")
        })
    }
}

#[pymethods]
impl PeMarcher {
    #[new]
    #[pyo3(signature = (u0, *, dx_m, dy_m, dz_m, freq_hz, propagator, ground, absorber, n_fixed=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        u0: PyReadonlyArray2<'_, C32>,
        dx_m: f64,
        dy_m: f64,
        dz_m: f64,
        freq_hz: f64,
        propagator: &str,
        ground: &str,
        absorber: f64,
        n_fixed: Option<PyReadonlyArray2<'_, Complex64>>,
    ) -> PyResult<Self> {
        let propagator: Propagator = propagator.parse().map_err(to_py)?;
        let ground: Ground = ground.parse().map_err(to_py)?;
        let u = u0.as_array();
        let (nx, ny) = u.dim();
        let spec = MarchSpec {
            nx,
            ny,
            dx_m,
            dy_m,
            dz_m,
            freq_hz,
            propagator,
            ground,
            absorber,
        };
        let n = n_fixed.as_ref().map(|a| a.as_array());
        let inner = detached(py, || {
            spec.validate()?;
            pwe::check_memory(spec.working_bytes(n.is_some()))?;
            let mut m = Marcher::new(spec, u)?;
            if let Some(n) = n {
                m.set_fixed_index(n)?;
            }
            Ok(m)
        })?;
        Ok(PeMarcher { inner: Some(inner) })
    }

    /// Steps done so far.
    #[getter]
    fn steps_done(&self) -> usize {
        self.inner.as_ref().map_or(0, Marcher::steps_done)
    }

    /// Advances `steps` steps without the GIL. Per-step inputs cover exactly these steps.
    #[pyo3(signature = (steps, *, n_uniform=None, n_fixed=false, n_steps=None, n_cross_range=None, mask_fixed=None,
        mask_steps=None, heights_fixed=None, heights_steps=None, record_rows, rows_out=None,
        record_column=None, column_out=None))]
    #[allow(clippy::too_many_arguments)]
    fn advance(
        &mut self,
        py: Python<'_>,
        steps: usize,
        n_uniform: Option<Complex64>,
        n_fixed: bool,
        n_steps: Option<PyReadonlyArray3<'_, Complex64>>,
        n_cross_range: Option<PyReadonlyArray2<'_, Complex64>>,
        mask_fixed: Option<PyReadonlyArray2<'_, bool>>,
        mask_steps: Option<PyReadonlyArray3<'_, bool>>,
        heights_fixed: Option<PyReadonlyArray1<'_, f64>>,
        heights_steps: Option<PyReadonlyArray2<'_, f64>>,
        record_rows: PyReadonlyArray1<'_, u64>,
        rows_out: Option<PyReadwriteArray3<'_, C32>>,
        record_column: Option<usize>,
        column_out: Option<PyReadwriteArray2<'_, C32>>,
    ) -> PyResult<()> {
        let m = self.marcher()?;
        let start = m.steps_done();
        let n_steps = n_steps.as_ref().map(|a| a.as_array());
        let n_cross = n_cross_range.as_ref().map(|a| a.as_array());
        let mask_fixed = mask_fixed.as_ref().map(|a| a.as_array());
        let mask_steps = mask_steps.as_ref().map(|a| a.as_array());
        let heights_fixed = heights_fixed.as_ref().map(|a| a.as_array());
        let heights_steps = heights_steps.as_ref().map(|a| a.as_array());
        for (name, len) in [
            ("n", n_steps.map(|a| a.dim().0)),
            ("n_cross_range", n_cross.map(|a| a.dim().0)),
            ("obstacles", mask_steps.map(|a| a.dim().0)),
            ("obstacles", heights_steps.map(|a| a.dim().0)),
        ] {
            if let Some(len) = len
                && len != steps
            {
                return Err(to_py(CoreError::invalid(
                    name,
                    format!("per-step inputs must cover the {steps} steps of this chunk"),
                    len,
                )));
            }
        }
        let rows: Vec<usize> = record_rows.as_array().iter().map(|&r| r as usize).collect();
        let mut rows_out = rows_out;
        let mut column_out = column_out;
        let mut recording = Recording {
            record_rows: &rows,
            rows: rows_out.as_mut().map(|a| a.as_array_mut()),
            column: match (record_column, column_out.as_mut()) {
                (Some(c), Some(out)) => Some((c, out.as_array_mut())),
                _ => None,
            },
        };
        let medium = move |g: usize| {
            if let Some(a) = n_steps {
                StepMedium::Index(a.index_axis_move(ndarray::Axis(0), g - start))
            } else if let Some(a) = n_cross {
                StepMedium::CrossRange(a.index_axis_move(ndarray::Axis(0), g - start))
            } else if let Some(n) = n_uniform {
                StepMedium::Uniform(n)
            } else if n_fixed {
                StepMedium::Fixed
            } else {
                StepMedium::Uniform(Complex64::new(1.0, 0.0))
            }
        };
        let obstacle = move |g: usize| {
            if let Some(a) = mask_steps {
                StepObstacle::Mask(a.index_axis_move(ndarray::Axis(0), g - start))
            } else if let Some(a) = mask_fixed {
                StepObstacle::Mask(a)
            } else if let Some(a) = heights_steps {
                StepObstacle::Heights(a.index_axis_move(ndarray::Axis(0), g - start))
            } else if let Some(a) = heights_fixed {
                StepObstacle::Heights(a)
            } else {
                StepObstacle::None
            }
        };
        detached(py, || m.advance(steps, &medium, &obstacle, &mut recording))
    }

    /// Hands the final (nx, ny) complex64 field over (no copy); the marcher is spent after.
    fn finish<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<C32>>> {
        let m = self.inner.take().ok_or_else(|| {
            RainuavError::new_err("this march has finished; its field was handed over")
        })?;
        Ok(m.into_field().into_pyarray(py))
    }
}

/// Gaussian-beam aperture (nx, ny) complex64: see `rainuav.pwe.gaussian_beam`.
#[pyfunction]
#[pyo3(signature = (nx, ny, dx_m, dy_m, *, freq_hz, height_m, elevation_deg, beamwidth_deg))]
#[allow(clippy::too_many_arguments)]
fn gaussian_beam<'py>(
    py: Python<'py>,
    nx: usize,
    ny: usize,
    dx_m: f64,
    dy_m: f64,
    freq_hz: f64,
    height_m: f64,
    elevation_deg: f64,
    beamwidth_deg: f64,
) -> PyResult<Bound<'py, PyArray2<C32>>> {
    let out = detached(py, || {
        pwe::gaussian_beam(
            nx,
            ny,
            dx_m,
            dy_m,
            freq_hz,
            height_m,
            elevation_deg,
            beamwidth_deg,
        )
    })?;
    Ok(out.into_pyarray(py))
}

/// Refuses a job needing `bytes` if it exceeds 80% of the available memory.
#[pyfunction]
fn check_memory(bytes: usize) -> PyResult<()> {
    pwe::check_memory(bytes).map_err(to_py)
}

/// One plan handed to Python: (return, actions, path).
type PlanOut<'py> = (f64, Bound<'py, PyArray1<u8>>, Bound<'py, PyArray2<f64>>);

/// Exact optimal plans from many starts: a list of (return, actions (T,) u8, path (T+1, 2)).
#[pyfunction]
#[pyo3(signature = (sir_db, extent_m, goal_m, starts_m, *, step_m, tol_m, max_steps, mu, reward,
    sir_min_db, goal_reward, out_of_bounds_penalty))]
#[allow(clippy::too_many_arguments)]
fn plan_optimal<'py>(
    py: Python<'py>,
    sir_db: PyReadonlyArray2<'py, f64>,
    extent_m: [f64; 4],
    goal_m: [f64; 2],
    starts_m: PyReadonlyArray2<'py, f64>,
    step_m: f64,
    tol_m: f64,
    max_steps: usize,
    mu: f64,
    reward: &str,
    sir_min_db: f64,
    goal_reward: f64,
    out_of_bounds_penalty: f64,
) -> PyResult<Vec<PlanOut<'py>>> {
    use rayon::prelude::*;
    let task = rainuav_core::plan::NavTask {
        sir_db: sir_db.as_array(),
        extent: extent_m,
        goal: goal_m,
        step_m,
        tol_m,
        max_steps,
        mu,
        reward: reward.parse().map_err(to_py)?,
        sir_min_db,
        goal_reward,
        out_of_bounds_penalty,
    };
    let starts = starts_m.as_array();
    if starts.ncols() != 2 {
        return Err(to_py(CoreError::invalid(
            "starts_m",
            "must have shape (N, 2)",
            format!("{:?}", starts.dim()),
        )));
    }
    let pts: Vec<[f64; 2]> = starts.rows().into_iter().map(|r| [r[0], r[1]]).collect();
    let plans = detached(py, || {
        task.validate()?;
        pts.par_iter()
            .map(|&p| task.optimal(p))
            .collect::<Result<Vec<_>, _>>()
    })?;
    Ok(plans
        .into_iter()
        .map(|p| {
            let n = p.path.len();
            let path = ndarray::Array2::from_shape_fn((n, 2), |(i, k)| p.path[i][k]);
            (
                p.return_,
                Array1::from(p.actions).into_pyarray(py),
                path.into_pyarray(py),
            )
        })
        .collect())
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
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
    m.add_class::<PeMarcher>()?;
    m.add_function(wrap_pyfunction!(gaussian_beam, m)?)?;
    m.add_function(wrap_pyfunction!(check_memory, m)?)?;
    m.add_function(wrap_pyfunction!(plan_optimal, m)?)?;
    Ok(())
}
