//! Bindings of the exact navigation planner (`rainuav.nav.planner` drives them).

use crate::{detached, to_py};
use ndarray::Array1;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::planner::NavTask;

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
    let task = NavTask {
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
    let plans = detached(py, || task.optimal_many(&pts))?;
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

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(plan_optimal, m)?)?;
    Ok(())
}
