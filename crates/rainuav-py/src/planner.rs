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
use rainuav_core::planning::planlevels::{LevelTask, LevelTimeline};
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

/// Exact plans with altitude as a decision (`rainuav_core::planning::planlevels`): the signal of each
/// level `sinr_db` (K, L, H, W) at the instants `t_s` (K,; one slice: a signal that does not
/// change), lowest level first, and optionally each level's not-flyable pixels `blocked`
/// (L, H', W'); `starts` (N, 3): x, y and the start level (-1: the best). Six moves (the
/// plane's four, a climb, a descent); `climb[k]` and `descend[k]` (L - 1 each) are how many
/// ticks (horizontal moves of `dt_s` seconds) the climb from level k to k + 1 and the
/// descent back last; take-off at `t0_s`.
#[pyfunction]
#[pyo3(signature = (sinr_db, t_s, extent_m, goal_m, starts, *, t0_s, dt_s, step_m, tol_m,
    max_steps, mu, reward, sir_min_db, goal_reward, out_of_bounds_penalty, climb, descend,
    blocked=None))]
#[allow(clippy::too_many_arguments)]
// Long: the binding converts and checks its numpy arrays and the task's numbers (each named in its
// errors) before the core is called; that conversion is most of its length.
fn plan_optimal_levels<'py>(
    py: Python<'py>,
    sinr_db: PyReadonlyArray4<'py, f64>,
    t_s: PyReadonlyArray1<'py, f64>,
    extent_m: [f64; 4],
    goal_m: [f64; 2],
    starts: PyReadonlyArray2<'py, f64>,
    t0_s: f64,
    dt_s: f64,
    step_m: f64,
    tol_m: f64,
    max_steps: usize,
    mu: f64,
    reward: &str,
    sir_min_db: f64,
    goal_reward: f64,
    out_of_bounds_penalty: f64,
    climb: Vec<usize>,
    descend: Vec<usize>,
    blocked: Option<PyReadonlyArray3<'py, u8>>,
) -> PyResult<Vec<LevelPlanOut<'py>>> {
    let slices = sinr_db.as_array();
    let masks = blocked.as_ref().map(|b| b.as_array());
    let (nk, nl) = (slices.shape()[0], slices.shape()[1]);
    if nk == 0 || nl == 0 {
        return Err(to_py(CoreError::invalid(
            "sinr_db",
            "must hold at least one slice and one level",
            format!("{:?}", slices.shape()),
        )));
    }
    if let Some(b) = &masks
        && b.shape()[0] != nl
    {
        return Err(to_py(CoreError::invalid(
            "blocked",
            format!("must hold one mask a level ({nl})"),
            b.shape()[0],
        )));
    }
    let times = instants(&t_s)?;
    let kind = reward.parse().map_err(to_py)?;
    let first = slices.index_axis(ndarray::Axis(0), 0);
    let levels = (0..nl)
        .map(|l| NavTask {
            sir_db: first.index_axis(ndarray::Axis(0), l),
            extent: extent_m,
            goal: goal_m,
            step_m,
            tol_m,
            max_steps,
            mu,
            reward: kind,
            sir_min_db,
            goal_reward,
            out_of_bounds_penalty,
            blocked: masks.as_ref().map(|b| b.index_axis(ndarray::Axis(0), l)),
        })
        .collect();
    let task = LevelTask {
        levels,
        climb,
        descend,
    };
    let tl = LevelTimeline {
        slices: slices.view(),
        t_s: times,
        t0_s,
        dt_s,
    };
    let st = starts.as_array();
    if st.ncols() != 3 {
        return Err(to_py(CoreError::invalid(
            "starts",
            "must have shape (N, 3): x, y, level",
            format!("{:?}", st.dim()),
        )));
    }
    let mut pts = Vec::with_capacity(st.nrows());
    for r in st.rows() {
        let l = r[2];
        if l == -1.0 {
            pts.push(([r[0], r[1]], rainuav_core::planning::planlevels::ANY_LEVEL));
            continue;
        }
        if !(l.is_finite() && l >= 0.0 && l.fract() == 0.0 && (l as usize) < nl) {
            return Err(to_py(CoreError::invalid(
                "starts",
                format!("levels must be whole numbers in 0..{nl}, or -1 (the best)"),
                l,
            )));
        }
        pts.push(([r[0], r[1]], l as usize));
    }
    let moving = (nk > 1).then_some(&tl);
    let plans = detached(py, || task.optimal_many(moving, &pts))?;
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
