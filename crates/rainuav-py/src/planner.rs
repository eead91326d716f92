//! Bindings of the exact navigation planner (`rainuav.nav.planner` drives it: the plane is its
//! case of one level) and of the
//! sampler the environment reads its signal in time with (`rainuav._sampling.in_time`).

use crate::{detached, to_py};
use ndarray::Array1;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadonlyArray4,
};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::planning::planlevels::{ANY_LEVEL, LevelSignal, LevelTask};
use rainuav_core::planning::planner::NavTask;

/// The instants of a signal in time, a contiguous 1-D array.
fn instants<'a>(t_s: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    t_s.as_slice().map_err(|_| {
        to_py(CoreError::invalid(
            "t_s",
            "must be a contiguous 1-D array",
            "strided",
        ))
    })
}

/// The signal at many points, each between two slices of a stack (S, H, W): bilinear in
/// space, linear in time (`rainuav_core::planning::sampling::sample_slices`). The 1-D arrays must be
/// contiguous; `x` and `y` of one length, `k0`, `k1` and `f` one value per row of consecutive
/// points (as many as the points, or a divisor of their number).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn sample_slices<'py>(
    py: Python<'py>,
    slices: PyReadonlyArray3<'py, f64>,
    extent_m: [f64; 4],
    x: PyReadonlyArray1<'py, f64>,
    y: PyReadonlyArray1<'py, f64>,
    k0: PyReadonlyArray1<'py, i64>,
    k1: PyReadonlyArray1<'py, i64>,
    f: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    fn flat<'a, T: numpy::Element>(
        name: &'static str,
        a: &'a PyReadonlyArray1<'_, T>,
    ) -> PyResult<&'a [T]> {
        a.as_slice().map_err(|_| {
            to_py(CoreError::invalid(
                name,
                "must be contiguous",
                "a strided view",
            ))
        })
    }
    let (xs, ys) = (flat("x", &x)?, flat("y", &y)?);
    let (k0s, k1s, fs) = (flat("k0", &k0)?, flat("k1", &k1)?, flat("f", &f)?);
    let view = slices.as_array();
    let out = detached(py, || {
        rainuav_core::planning::sampling::sample_slices(&view, extent_m, xs, ys, k0s, k1s, fs)
    })?;
    Ok(Array1::from(out).into_pyarray(py))
}

/// One plan among levels handed to Python: (return, actions (T,) u8, path (T+1, 3): x, y,
/// level, ticks (T+1,): the clock at each position).
type LevelPlanOut<'py> = (
    f64,
    Bound<'py, PyArray1<u8>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<u64>>,
);

/// The task a plan solves, read from a dict's items (`rainuav.nav.planner.rust_task` builds
/// it from a `NavConfig`): the geometry, rewards and horizon, the clock, and the climbs and
/// descents between neighbouring levels in ticks.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct PlanSpec {
    extent_m: [f64; 4],
    goal_m: [f64; 2],
    step_m: f64,
    tol_m: f64,
    max_steps: usize,
    mu: f64,
    reward: String,
    sir_min_db: f64,
    goal_reward: f64,
    out_of_bounds_penalty: f64,
    t0_s: f64,
    dt_s: f64,
    climb: Vec<usize>,
    descend: Vec<usize>,
}

/// The starts (N, 3): x, y and a level in `0..levels`, or -1 (the best).
fn start_points(
    st: ndarray::ArrayView2<'_, f64>,
    levels: usize,
) -> PyResult<Vec<([f64; 2], usize)>> {
    if st.ncols() != 3 {
        return Err(to_py(CoreError::invalid(
            "starts",
            "must have shape (N, 3): x, y, level",
            format!("{:?}", st.dim()),
        )));
    }
    st.rows()
        .into_iter()
        .map(|r| {
            let l = r[2];
            if l == -1.0 {
                return Ok(([r[0], r[1]], ANY_LEVEL));
            }
            if !(l.is_finite() && l >= 0.0 && l.fract() == 0.0 && (l as usize) < levels) {
                return Err(to_py(CoreError::invalid(
                    "starts",
                    format!("levels must be whole numbers in 0..{levels}, or -1 (the best)"),
                    l,
                )));
            }
            Ok(([r[0], r[1]], l as usize))
        })
        .collect()
}

/// Exact plans with altitude as a decision (`rainuav_core::planning::planlevels`): the signal
/// `sinr_db` (K, L, H, W) of every level at the instants `t_s` (K,; one slice: a signal that
/// does not change), lowest level first; `starts` (N, 3): x, y and the start level (-1: the
/// best); `task` the [`PlanSpec`]'s items; optionally each level's not-flyable pixels
/// `blocked` (L, H', W'). Six moves (the plane's four, a climb, a descent).
#[pyfunction]
#[pyo3(signature = (sinr_db, t_s, starts, task, blocked=None))]
fn plan_optimal_levels<'py>(
    py: Python<'py>,
    sinr_db: PyReadonlyArray4<'py, f64>,
    t_s: PyReadonlyArray1<'py, f64>,
    starts: PyReadonlyArray2<'py, f64>,
    task: PlanSpec,
    blocked: Option<PyReadonlyArray3<'py, u8>>,
) -> PyResult<Vec<LevelPlanOut<'py>>> {
    let plan = LevelTask {
        task: NavTask {
            extent: task.extent_m,
            goal: task.goal_m,
            step_m: task.step_m,
            tol_m: task.tol_m,
            max_steps: task.max_steps,
            mu: task.mu,
            reward: task.reward.parse().map_err(to_py)?,
            sir_min_db: task.sir_min_db,
            goal_reward: task.goal_reward,
            out_of_bounds_penalty: task.out_of_bounds_penalty,
        },
        signal: LevelSignal {
            slices: sinr_db.as_array(),
            t_s: instants(&t_s)?,
            t0_s: task.t0_s,
            dt_s: task.dt_s,
        },
        blocked: blocked.as_ref().map(|b| b.as_array()),
        climb: task.climb,
        descend: task.descend,
    };
    let pts = start_points(starts.as_array(), plan.levels())?;
    let plans = detached(py, || plan.optimal_many(&pts))?;
    Ok(plans
        .into_iter()
        .map(|p| {
            let n = p.path.len();
            let path = ndarray::Array2::from_shape_fn((n, 3), |(i, k)| p.path[i][k]);
            let ticks: Vec<u64> = p.ticks.iter().map(|&t| t as u64).collect();
            (
                p.return_,
                Array1::from(p.actions).into_pyarray(py),
                path.into_pyarray(py),
                Array1::from(ticks).into_pyarray(py),
            )
        })
        .collect())
}

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(plan_optimal_levels, m)?)?;
    m.add_function(wrap_pyfunction!(sample_slices, m)?)?;
    Ok(())
}
