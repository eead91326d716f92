//! Bindings of the ray model (`rainuav.radio.ray_engine` drives them).

use crate::{detached, to_py};
use ndarray::Array2;
use num_complex::Complex64;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::rays::{
    Building, RainField, Raster, RayGround, RayPolarization, RayScene, RayTransmitter,
};

/// Received power (mW) of every transmitter at every pixel, (M, H, W): direct and
/// ground-reflected rays with rain and knife-edge losses, averaged over each pixel.
#[pyfunction]
#[pyo3(signature = (tx_m, tx_power_mw, g_direct, g_reflect, x_m, y_m, *, altitude_m, pixel_m,
    freq_hz, ground, eps_ground, polarization, gamma_db_per_m, gamma_raster, gamma_origin_step,
    buildings, heights, heights_origin_step, gamma_per_tx=None))]
#[allow(clippy::too_many_arguments)]
fn ray_power<'py>(
    py: Python<'py>,
    tx_m: PyReadonlyArray2<'py, f64>,
    tx_power_mw: PyReadonlyArray1<'py, f64>,
    g_direct: PyReadonlyArray3<'py, f64>,
    g_reflect: PyReadonlyArray3<'py, f64>,
    x_m: PyReadonlyArray1<'py, f64>,
    y_m: PyReadonlyArray1<'py, f64>,
    altitude_m: f64,
    pixel_m: [f64; 2],
    freq_hz: f64,
    ground: &str,
    eps_ground: (f64, f64),
    polarization: &str,
    gamma_db_per_m: f64,
    gamma_raster: Option<PyReadonlyArray2<'py, f64>>,
    gamma_origin_step: [f64; 4],
    buildings: PyReadonlyArray2<'py, f64>,
    heights: Option<PyReadonlyArray2<'py, f64>>,
    heights_origin_step: [f64; 4],
    gamma_per_tx: Option<PyReadonlyArray3<'py, f64>>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let ground = match ground {
        "none" => RayGround::None,
        "pec" => RayGround::Pec,
        "dielectric" => RayGround::Dielectric(Complex64::new(eps_ground.0, eps_ground.1)),
        other => {
            return Err(to_py(CoreError::invalid(
                "ground",
                "must be 'none', 'pec' or 'dielectric'",
                other,
            )));
        }
    };
    let polarization = match polarization {
        "h" => RayPolarization::H,
        "v" => RayPolarization::V,
        other => {
            return Err(to_py(CoreError::invalid(
                "polarization",
                "must be 'h' or 'v'",
                other,
            )));
        }
    };
    let tx = tx_m.as_array();
    let pw = tx_power_mw.as_array();
    if tx.ncols() != 3 || tx.nrows() != pw.len() {
        return Err(to_py(CoreError::invalid(
            "tx_m",
            "must have shape (M, 3) with M = len(tx_power_mw)",
            format!("{:?}", tx.dim()),
        )));
    }
    let txs: Vec<RayTransmitter> = tx
        .rows()
        .into_iter()
        .zip(pw.iter())
        .map(|(r, &p)| RayTransmitter {
            position_m: [r[0], r[1], r[2]],
            power_mw: p,
        })
        .collect();
    let b = buildings.as_array();
    if b.ncols() != 5 && b.nrows() > 0 {
        return Err(to_py(CoreError::invalid(
            "buildings",
            "must have shape (B, 5): x0, x1, y0, y1, height",
            format!("{:?}", b.dim()),
        )));
    }
    let boxes: Vec<Building> = b
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2], r[3], r[4]])
        .collect();
    let x = x_m.as_array().to_vec();
    let y = y_m.as_array().to_vec();
    let gr: Option<Array2<f64>> = gamma_raster.map(|g| g.as_array().to_owned());
    let hr: Option<Array2<f64>> = heights.map(|h| h.as_array().to_owned());
    let gd = g_direct.as_array();
    let gf = g_reflect.as_array();
    let per_tx = gamma_per_tx.as_ref().map(|g| g.as_array());
    let out = detached(py, || {
        let rain = match (&per_tx, &gr) {
            (Some(g), _) => RainField::PerPixel(g.view()),
            (None, Some(v)) => RainField::Raster(Raster {
                values: v.view(),
                origin_step: gamma_origin_step,
            }),
            (None, None) => RainField::Uniform(gamma_db_per_m),
        };
        let scene = RayScene {
            x_m: &x,
            y_m: &y,
            altitude_m,
            pixel_m,
            freq_hz,
            ground,
            polarization,
            rain,
            buildings: &boxes,
            heights: hr.as_ref().map(|v| Raster {
                values: v.view(),
                origin_step: heights_origin_step,
            }),
        };
        scene.power(&txs, gd, gf)
    })?;
    Ok(out.into_pyarray(py))
}

/// The mean specific attenuation (dB/m) along the horizontal line from each source `(S, 2)`
/// to every pixel centre, `(S, H, W)`, through a raster (or a uniform) rain field: what
/// `ray_power(gamma_per_tx=...)` takes, computed once per site for all its cells.
#[pyfunction]
#[pyo3(signature = (sources_m, x_m, y_m, *, gamma_db_per_m, gamma_raster, gamma_origin_step))]
fn ray_mean_gamma<'py>(
    py: Python<'py>,
    sources_m: PyReadonlyArray2<'py, f64>,
    x_m: PyReadonlyArray1<'py, f64>,
    y_m: PyReadonlyArray1<'py, f64>,
    gamma_db_per_m: f64,
    gamma_raster: Option<PyReadonlyArray2<'py, f64>>,
    gamma_origin_step: [f64; 4],
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let src = sources_m.as_array().to_owned();
    if src.ncols() != 2 || !src.iter().all(|v| v.is_finite()) {
        return Err(to_py(CoreError::invalid(
            "sources_m",
            "must have shape (S, 2), finite",
            format!("{:?}", src.dim()),
        )));
    }
    let x = x_m.as_array().to_vec();
    let y = y_m.as_array().to_vec();
    let gr: Option<Array2<f64>> = gamma_raster.map(|g| g.as_array().to_owned());
    let out = detached(py, || {
        let rain = match &gr {
            Some(v) => RainField::Raster(Raster {
                values: v.view(),
                origin_step: gamma_origin_step,
            }),
            None => RainField::Uniform(gamma_db_per_m),
        };
        let scene = RayScene {
            x_m: &x,
            y_m: &y,
            altitude_m: 1.0,
            pixel_m: [0.0, 0.0],
            freq_hz: 1e9,
            ground: RayGround::None,
            polarization: RayPolarization::H,
            rain,
            buildings: &[],
            heights: None,
        };
        let mut out = ndarray::Array3::<f64>::zeros((src.nrows(), y.len(), x.len()));
        rainuav_core::memory::check_memory(out.len() * 8)?;
        for (k, row) in src.rows().into_iter().enumerate() {
            let plane = scene.mean_gamma_map([row[0], row[1]])?;
            out.index_axis_mut(ndarray::Axis(0), k).assign(&plane);
        }
        Ok::<_, CoreError>(out)
    })?;
    Ok(out.into_pyarray(py))
}

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ray_power, m)?)?;
    m.add_function(wrap_pyfunction!(ray_mean_gamma, m)?)?;
    Ok(())
}
