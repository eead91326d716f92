//! `rainuav._core`: the Python face of `rainuav-core`. This crate only converts: numpy arrays
//! in as read-only views, owned arrays out without copying, core errors onto the
//! `rainuav.RainuavError` hierarchy, and long work without the GIL. Broadcasting, defaults
//! and docs live in `python/rainuav`. One file per layer of the core (`medium`, `pwe`,
//! `planner`, `rays`, `walls`, `raytime`, `diffraction`); this file holds what they share and
//! registers them.

mod diffraction;
mod medium;
mod planner;
mod pwe;
mod rays;
mod raytime;
mod walls;

use ndarray::ArrayView1;
use pyo3::prelude::*;
use rainuav_core::CoreError;

pyo3::import_exception!(rainuav.errors, RainuavError);
pyo3::import_exception!(rainuav.errors, InvalidInputError);

/// The one place core errors become Python exceptions.
pub(crate) fn to_py(err: CoreError) -> PyErr {
    match err {
        CoreError::InvalidArgument { .. } => InvalidInputError::new_err(err.to_string()),
        CoreError::Internal(_) => RainuavError::new_err(err.to_string()),
    }
}

/// Runs `work` without the GIL; a panic (a bug: inputs are validated first) becomes a
/// `RainuavError` instead of unwinding into Python.
pub(crate) fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
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

/// Checks that two paired arrays have the same length.
pub(crate) fn same_len(
    name: &'static str,
    a: &ArrayView1<'_, f64>,
    b: &ArrayView1<'_, f64>,
) -> PyResult<()> {
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

/// Refuses a job needing `bytes` if it exceeds 80% of the available memory (the shared
/// check of `rainuav_core::memory`; the radio-map builder calls it before its marches).
#[pyfunction]
fn check_memory(bytes: usize) -> PyResult<()> {
    rainuav_core::memory::check_memory(bytes).map_err(to_py)
}

/// Memory this machine reports as available (Linux `MemAvailable`), bytes; None where it
/// cannot be read. The Python-side size checks (networks, replay, ray arrays, vector envs)
/// compare against it with the same 80% rule as `check_memory`.
#[pyfunction]
fn available_memory_bytes() -> Option<usize> {
    rainuav_core::memory::available_memory_bytes()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    medium::register(m)?;
    pwe::register(m)?;
    planner::register(m)?;
    rays::register(m)?;
    walls::register(m)?;
    raytime::register(m)?;
    diffraction::register(m)?;
    m.add_function(wrap_pyfunction!(check_memory, m)?)?;
    m.add_function(wrap_pyfunction!(available_memory_bytes, m)?)?;
    Ok(())
}
