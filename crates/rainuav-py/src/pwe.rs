//! Bindings of the split-step PE march (`rainuav.pwe` drives them).

use crate::{RainuavError, detached, to_py};
use num_complex::Complex64;
use numpy::{
    IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray2,
    PyReadwriteArray3,
};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::propagation::pwe::{
    self, C32, Ground, MarchSpec, Marcher, Propagator, Recording, StepMedium, StepObstacle,
};

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
    #[pyo3(signature = (u0, *, dx_m, dy_m, dz_m, freq_hz, propagator, ground, absorber, x_absorber_every=1, n_fixed=None))]
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
        x_absorber_every: usize,
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
            x_absorber_every,
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
        record_column=None, column_out=None, row_offsets=None))]
    #[allow(clippy::too_many_arguments)]
    // Long: the binding converts and checks the chunk's optional arrays (each named in its errors)
    // before the core steps; that conversion is most of its length.
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
        row_offsets: Option<PyReadonlyArray2<'_, i64>>,
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
            (
                "row_offsets",
                row_offsets.as_ref().map(|a| a.as_array().dim().0),
            ),
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
            row_offsets: row_offsets.as_ref().map(|a| (start, a.as_array())),
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

/// Adds this layer's classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PeMarcher>()?;
    m.add_function(wrap_pyfunction!(gaussian_beam, m)?)?;
    Ok(())
}
