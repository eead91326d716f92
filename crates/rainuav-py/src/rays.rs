//! Bindings of the ray model (`rainuav.radio.ray_engine` and `rainuav.radio.timemap` drive
//! them).

use crate::{detached, to_py};
use ndarray::Array2;
use ndarray::ArrayView2;
use num_complex::Complex64;
use numpy::{
    IntoPyArray, PyArray3, PyArray4, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadonlyArray4,
};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::propagation::rays::{
    Building, KnownPaths, Prisms as CorePrisms, RainField, Raster, RayGround, RayPolarization,
    RayScene, RayTransmitter,
};
/// Buildings as prisms standing on the terrain: footprint rings (`xy` (N, 2) every vertex,
/// rings not closed; `ring_starts` (R + 1) offsets into `xy`; `prism_rings` (P + 1) offsets
/// into the rings, each prism's outer ring then its holes) and `tops` (P) roof heights above
/// the terrain, m. Built once (with its bucket grid) and passed to the ray functions.
#[pyclass(frozen, module = "rainuav._core")]
pub(crate) struct Prisms {
    inner: CorePrisms,
}

#[pymethods]
impl Prisms {
    #[new]
    fn new(
        xy: PyReadonlyArray2<'_, f64>,
        ring_starts: PyReadonlyArray1<'_, i64>,
        prism_rings: PyReadonlyArray1<'_, i64>,
        tops: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let v = xy.as_array();
        if v.ncols() != 2 && v.nrows() > 0 {
            return Err(to_py(CoreError::invalid(
                "xy",
                "must have shape (N, 2)",
                format!("{:?}", v.dim()),
            )));
        }
        let offsets = |a: &PyReadonlyArray1<'_, i64>| -> Vec<usize> {
            a.as_array()
                .iter()
                .map(|&k| usize::try_from(k).unwrap_or(usize::MAX))
                .collect()
        };
        let pts: Vec<[f64; 2]> = v.rows().into_iter().map(|r| [r[0], r[1]]).collect();
        let tops = tops.as_array().to_vec();
        let inner = CorePrisms::new(pts, &offsets(&ring_starts), &offsets(&prism_rings), &tops)
            .map_err(to_py)?;
        Ok(Prisms { inner })
    }

    /// How many prisms.
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// The tallest roof (m above the terrain) over each point `(x, y)`; 0 where none.
    fn height_at<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let (x, y) = (x.as_array(), y.as_array());
        if x.len() != y.len() {
            return Err(to_py(CoreError::invalid(
                "y",
                "must have the length of x",
                y.len(),
            )));
        }
        let out: Vec<f64> = x
            .iter()
            .zip(y.iter())
            .map(|(&a, &b)| self.inner.height_at(a, b))
            .collect();
        Ok(out.into_pyarray(py))
    }
}

/// The boxes and the prisms of a call as one set of prisms.
pub(crate) fn obstacles(
    boxes: &PyReadonlyArray2<'_, f64>,
    prisms: Option<&Bound<'_, Prisms>>,
) -> PyResult<Option<CorePrisms>> {
    let boxes = parse_buildings(boxes)?;
    let from_boxes = CorePrisms::from_boxes(&boxes).map_err(to_py)?;
    let all = match prisms {
        Some(p) if from_boxes.is_empty() => p.get().inner.clone(),
        Some(p) => from_boxes.join(&p.get().inner).map_err(to_py)?,
        None => from_boxes,
    };
    Ok((!all.is_empty()).then_some(all))
}

pub(crate) fn parse_ground(ground: &str, eps: (f64, f64)) -> PyResult<RayGround> {
    match ground {
        "none" => Ok(RayGround::None),
        "pec" => Ok(RayGround::Pec),
        "dielectric" => Ok(RayGround::Dielectric(Complex64::new(eps.0, eps.1))),
        other => Err(to_py(CoreError::invalid(
            "ground",
            "must be 'none', 'pec' or 'dielectric'",
            other,
        ))),
    }
}

pub(crate) fn parse_polarization(p: &str) -> PyResult<RayPolarization> {
    match p {
        "h" => Ok(RayPolarization::H),
        "v" => Ok(RayPolarization::V),
        other => Err(to_py(CoreError::invalid(
            "polarization",
            "must be 'h' or 'v'",
            other,
        ))),
    }
}

pub(crate) fn parse_transmitters(
    tx_m: &PyReadonlyArray2<'_, f64>,
    tx_power_mw: &PyReadonlyArray1<'_, f64>,
) -> PyResult<Vec<RayTransmitter>> {
    let tx = tx_m.as_array();
    let pw = tx_power_mw.as_array();
    if tx.ncols() != 3 || tx.nrows() != pw.len() {
        return Err(to_py(CoreError::invalid(
            "tx_m",
            "must have shape (M, 3) with M = len(tx_power_mw)",
            format!("{:?}", tx.dim()),
        )));
    }
    Ok(tx
        .rows()
        .into_iter()
        .zip(pw.iter())
        .map(|(r, &p)| RayTransmitter {
            position_m: [r[0], r[1], r[2]],
            power_mw: p,
        })
        .collect())
}

pub(crate) fn parse_buildings(buildings: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Building>> {
    let b = buildings.as_array();
    if b.ncols() != 5 && b.nrows() > 0 {
        return Err(to_py(CoreError::invalid(
            "buildings",
            "must have shape (B, 5): x0, x1, y0, y1, height",
            format!("{:?}", b.dim()),
        )));
    }
    Ok(b.rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2], r[3], r[4]])
        .collect())
}

/// The (S, 3) sites: x, y, height.
pub(crate) fn parse_sites(sites: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[f64; 3]>> {
    let s = sites.as_array();
    if s.ncols() != 3 {
        return Err(to_py(CoreError::invalid(
            "sites",
            "must have shape (S, 3): x, y, height",
            format!("{:?}", s.dim()),
        )));
    }
    Ok(s.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// A table and its `(x0, dx, y0, dy)` as the core's raster (the unit grid where no origin and
/// step are given).
pub(crate) fn raster<'a>(
    values: Option<ArrayView2<'a, f64>>,
    origin_step: Option<[f64; 4]>,
) -> Option<Raster<'a>> {
    values.map(|values| Raster {
        values,
        origin_step: origin_step.unwrap_or([0.0, 1.0, 0.0, 1.0]),
    })
}

/// The rain as the core takes it: a raster of nodes, or uniform.
pub(crate) fn rain_field(
    raster: Option<&Array2<f64>>,
    uniform: f64,
    origin_step: [f64; 4],
) -> RainField<'_> {
    match raster {
        Some(v) => RainField::Raster(Raster {
            values: v.view(),
            origin_step,
        }),
        None => RainField::Uniform(uniform),
    }
}

/// Received power (mW) of every transmitter at every pixel, (M, H, W): direct and
/// ground-reflected rays with rain and knife-edge losses, averaged over each pixel.
///
/// With `terms_only`, the clear-air parts and the rays' lengths instead, (M, H, W, 7):
/// `[direct, reflect, cross, d1, d2, wall, d3]`. `terrain` (heights above sea level at nodes,
/// `terrain_origin_step`) puts everything on the ground; `altitude_msl` measures the flight
/// altitude above sea level instead of above the terrain. `prisms` (:class:`Prisms`) are
/// buildings besides the `buildings` boxes; `walls` (M, H, W, 2) each cell's wall rays at each
/// pixel (clear-air power in mW and mean length in m, from `ray_walls` and the gains).
#[pyfunction]
#[pyo3(signature = (tx_m, tx_power_mw, g_direct, g_reflect, x_m, y_m, *, altitude_m, pixel_m,
    freq_hz, ground, eps_ground, polarization, gamma_db_per_m, gamma_raster, gamma_origin_step,
    buildings, heights, heights_origin_step, terrain=None, terrain_origin_step=None,
    altitude_msl=false, terrain_roughness_m=0.0, terms_only=false, prisms=None, walls=None, geometry=None,
    geometry_sites=None))]
#[allow(clippy::too_many_arguments)]
// Long: the binding converts and checks its numpy arrays (each named in its errors) before the core
// is called; that conversion is most of its length.
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
    terrain: Option<PyReadonlyArray2<'py, f64>>,
    terrain_origin_step: Option<[f64; 4]>,
    altitude_msl: bool,
    terrain_roughness_m: f64,
    terms_only: bool,
    prisms: Option<Bound<'py, Prisms>>,
    walls: Option<PyReadonlyArray4<'py, f64>>,
    geometry: Option<PyReadonlyArray4<'py, f64>>,
    geometry_sites: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<Bound<'py, PyAny>> {
    let known_sites = geometry_sites.as_ref().map(parse_sites).transpose()?;
    let known = match (&geometry, &known_sites) {
        (Some(t), Some(s)) => Some(KnownPaths {
            sites: s,
            table: t.as_array(),
        }),
        (None, None) => None,
        _ => {
            return Err(to_py(CoreError::invalid(
                "geometry",
                "needs geometry_sites (and the other way round)",
                "one of them",
            )));
        }
    };
    let ground = parse_ground(ground, eps_ground)?;
    let polarization = parse_polarization(polarization)?;
    let txs = parse_transmitters(&tx_m, &tx_power_mw)?;
    let obst = obstacles(&buildings, prisms.as_ref())?;
    let wr = walls.as_ref().map(|w| w.as_array());
    let x = x_m.as_array().to_vec();
    let y = y_m.as_array().to_vec();
    let gr: Option<Array2<f64>> = gamma_raster.map(|g| g.as_array().to_owned());
    let hr: Option<Array2<f64>> = heights.map(|h| h.as_array().to_owned());
    let tr = terrain.as_ref().map(|t| t.as_array());
    let gd = g_direct.as_array();
    let gf = g_reflect.as_array();
    let scene = RayScene {
        x_m: &x,
        y_m: &y,
        altitude_m,
        pixel_m,
        freq_hz,
        ground,
        polarization,
        rain: rain_field(gr.as_ref(), gamma_db_per_m, gamma_origin_step),
        prisms: obst.as_ref(),
        heights: raster(hr.as_ref().map(|v| v.view()), Some(heights_origin_step)),
        terrain: raster(tr, terrain_origin_step),
        altitude_msl,
        roughness_m: terrain_roughness_m,
    };
    if terms_only {
        let out = detached(py, || scene.terms(&txs, gd, gf, wr, known))?;
        let arr: Bound<'py, PyArray4<f64>> = out.into_pyarray(py);
        return Ok(arr.into_any());
    }
    let out = detached(py, || scene.power_with(&txs, gd, gf, wr, known))?;
    let arr: Bound<'py, PyArray3<f64>> = out.into_pyarray(py);
    Ok(arr.into_any())
}

/// The departure elevations (degrees) toward which each site's antenna gains are taken,
/// (S, H, W, 2): the direct ray's (toward the diffracting edge where the path's profile costs
/// a loss, else the pixel) and the reflected ray's (toward the specular point). `sites` (S, 3):
/// x, y, height above the terrain. With `full`, every path's whole geometry instead,
/// (S, H, W, 7): `[d1, d2, loss_db, el_direct, el_reflect, psi, reflect]` (elevations in
/// radians), which `ray_power` takes back as `geometry` (with `geometry_sites`) so each path
/// is traced once. `polarization` (`"v"` or `"h"`) sets the roofs' wedge coefficients in the
/// diffraction loss.
#[pyfunction]
#[pyo3(signature = (sites, x_m, y_m, *, altitude_m, freq_hz, ground, buildings, heights,
    heights_origin_step, terrain=None, terrain_origin_step=None, altitude_msl=false,
    terrain_roughness_m=0.0,
    prisms=None, full=false, polarization="h"))]
#[allow(clippy::too_many_arguments)]
fn ray_departures<'py>(
    py: Python<'py>,
    sites: PyReadonlyArray2<'py, f64>,
    x_m: PyReadonlyArray1<'py, f64>,
    y_m: PyReadonlyArray1<'py, f64>,
    altitude_m: f64,
    freq_hz: f64,
    ground: &str,
    buildings: PyReadonlyArray2<'py, f64>,
    heights: Option<PyReadonlyArray2<'py, f64>>,
    heights_origin_step: [f64; 4],
    terrain: Option<PyReadonlyArray2<'py, f64>>,
    terrain_origin_step: Option<[f64; 4]>,
    altitude_msl: bool,
    terrain_roughness_m: f64,
    prisms: Option<Bound<'py, Prisms>>,
    full: bool,
    polarization: &str,
) -> PyResult<Bound<'py, PyArray4<f64>>> {
    let sites = parse_sites(&sites)?;
    let polarization = parse_polarization(polarization)?;
    let ground = parse_ground(ground, (1.0, 0.0))?;
    let obst = obstacles(&buildings, prisms.as_ref())?;
    let x = x_m.as_array().to_vec();
    let y = y_m.as_array().to_vec();
    let hr = heights.as_ref().map(|h| h.as_array());
    let tr = terrain.as_ref().map(|t| t.as_array());
    let scene = RayScene {
        x_m: &x,
        y_m: &y,
        altitude_m,
        pixel_m: [0.0, 0.0],
        freq_hz,
        ground,
        polarization,
        rain: RainField::Uniform(0.0),
        prisms: obst.as_ref(),
        heights: raster(hr, Some(heights_origin_step)),
        terrain: raster(tr, terrain_origin_step),
        altitude_msl,
        roughness_m: terrain_roughness_m,
    };
    let out = if full {
        detached(py, || scene.geometry_table(&sites))?
    } else {
        detached(py, || scene.departures(&sites))?
    };
    Ok(out.into_pyarray(py))
}

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ray_power, m)?)?;
    m.add_function(wrap_pyfunction!(ray_departures, m)?)?;
    m.add_class::<Prisms>()?;
    Ok(())
}
