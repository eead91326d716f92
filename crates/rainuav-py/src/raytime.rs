//! Bindings of the rays in time (`rainuav.radio.timemap` drives them): every cell's rays traced
//! once, their power at any instant of a weather.

use crate::detached;
use numpy::{
    IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray4, PyReadwriteArray3,
};
use pyo3::prelude::*;
use rainuav_core::propagation::rays::{RainField, Raster};

use crate::rays::parse_sites;

/// Every cell's rays over a map traced once (the clear-air terms and the rays' lengths
/// (M, H, W, 7) from `ray_power(..., terms_only=True)`), `sites` (S, 3): x, y, height,
/// `site_of` (M,): each
/// cell's site), and the power at any instant from its rain (`power`): weather in time.
#[pyclass(frozen, module = "rainuav._core")]
struct RaySlicer {
    inner: rainuav_core::propagation::raytime::RaySlicer,
}

#[pymethods]
impl RaySlicer {
    #[new]
    #[pyo3(signature = (terms, sites, site_of, x_m, y_m, *, node_spacing_m))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        terms: PyReadonlyArray4<'_, f64>,
        sites: PyReadonlyArray2<'_, f64>,
        site_of: PyReadonlyArray1<'_, i64>,
        x_m: PyReadonlyArray1<'_, f64>,
        y_m: PyReadonlyArray1<'_, f64>,
        node_spacing_m: f64,
    ) -> PyResult<Self> {
        let sites = parse_sites(&sites)?;
        let site_of: Vec<usize> = site_of
            .as_array()
            .iter()
            .map(|&v| usize::try_from(v).unwrap_or(usize::MAX))
            .collect();
        let x = x_m.as_array().to_vec();
        let y = y_m.as_array().to_vec();
        let t = terms.as_array();
        let inner = detached(py, || {
            rainuav_core::propagation::raytime::RaySlicer::new(
                t,
                &sites,
                &site_of,
                &x,
                &y,
                node_spacing_m,
            )
        })?;
        Ok(RaySlicer { inner })
    }

    /// The power (mW) of every cell at every pixel, (M, H, W), through this instant's rain
    /// (uniform dB/m, or a raster of nodes `node_spacing_m` apart); with `rss_dbm_out`
    /// (float32, (M, H, W)), also in dBm (floored) written there.
    #[pyo3(signature = (*, gamma_db_per_m, gamma_raster, gamma_origin_step, rss_dbm_out=None,
        rss_floor_dbm=-250.0))]
    fn power<'py>(
        &self,
        py: Python<'py>,
        gamma_db_per_m: f64,
        gamma_raster: Option<PyReadonlyArray2<'py, f64>>,
        gamma_origin_step: [f64; 4],
        rss_dbm_out: Option<PyReadwriteArray3<'py, f32>>,
        rss_floor_dbm: f64,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let gr = gamma_raster.as_ref().map(|g| g.as_array());
        let mut db = rss_dbm_out;
        let db_view = db.as_mut().map(|d| d.as_array_mut());
        let out = detached(py, || {
            let rain = match gr {
                Some(v) => RainField::Raster(Raster {
                    values: v,
                    origin_step: gamma_origin_step,
                }),
                None => RainField::Uniform(gamma_db_per_m),
            };
            let p = self.inner.power(rain)?;
            if let Some(v) = db_view {
                rainuav_core::propagation::raytime::to_dbm(p.view(), rss_floor_dbm, v)?;
            }
            Ok(p)
        })?;
        Ok(out.into_pyarray(py))
    }
}

/// Adds this layer's classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RaySlicer>()?;
    Ok(())
}
