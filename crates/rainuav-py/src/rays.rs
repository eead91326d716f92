//! Bindings of the ray model (`rainuav.radio.ray_engine` and `rainuav.radio.timemap` drive
//! them).

use crate::{detached, to_py};
use ndarray::Array2;
use ndarray::ArrayView2;
use num_complex::Complex64;
use numpy::{
    IntoPyArray, PyArray3, PyArray4, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadonlyArray4, PyReadwriteArray3,
};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::rays::{
    Building, KnownPaths, Prisms as CorePrisms, RainField, Raster, RayGround, RayPolarization,
    RayScene, RayTransmitter,
};
use rainuav_core::walls::Wall;

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
fn obstacles(
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

fn parse_ground(ground: &str, eps: (f64, f64)) -> PyResult<RayGround> {
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

fn parse_polarization(p: &str) -> PyResult<RayPolarization> {
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

fn parse_transmitters(
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

fn parse_buildings(buildings: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Building>> {
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
fn parse_sites(sites: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[f64; 3]>> {
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
fn raster<'a>(
    values: Option<ArrayView2<'a, f64>>,
    origin_step: Option<[f64; 4]>,
) -> Option<Raster<'a>> {
    values.map(|values| Raster {
        values,
        origin_step: origin_step.unwrap_or([0.0, 1.0, 0.0, 1.0]),
    })
}

/// The rain as the core takes it: a raster of nodes, or uniform.
fn rain_field(raster: Option<&Array2<f64>>, uniform: f64, origin_step: [f64; 4]) -> RainField<'_> {
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
/// is traced once.
#[pyfunction]
#[pyo3(signature = (sites, x_m, y_m, *, altitude_m, freq_hz, ground, buildings, heights,
    heights_origin_step, terrain=None, terrain_origin_step=None, altitude_msl=false,
    terrain_roughness_m=0.0,
    prisms=None, full=false))]
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
) -> PyResult<Bound<'py, PyArray4<f64>>> {
    let sites = parse_sites(&sites)?;
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
        polarization: RayPolarization::H,
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

/// Every ray that `walls` reflect from each site to the map's pixels (image method, first
/// and second order: `rainuav_core::walls`, `rainuav_core::walls2`): `walls` (K, 6) `[ax, ay, bx, by, base, top]` (outward normal on the right of
/// `a -> b`; base and top above the terrain), `wall_eps` (K, 2) each wall's complex
/// permittivity (real, imaginary <= 0), `sites` (S, 3) x, y, height above the terrain.
/// Returns `(site, pixel, az_deg, el_deg, factor, length_m, kind)`, one entry a ray: its site,
/// its pixel (row-major), its departure direction toward its first interaction, its power per
/// mW for isotropic antennas, its length and its kind (1: one wall, 2: two walls, 3: a corner,
/// alone or after a wall). With `prism_eps` (P, 2: each prism's wall
/// permittivity), also the rays the prisms' corners diffract into the pixels they hide
/// (`rainuav_core::corners`), after the wall rays of the same site.
#[pyfunction]
#[pyo3(signature = (sites, x_m, y_m, walls, wall_eps, *, altitude_m, freq_hz, polarization,
    buildings, heights, heights_origin_step, terrain=None, terrain_origin_step=None,
    altitude_msl=false, terrain_roughness_m=0.0, prisms=None, prism_eps=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn ray_walls<'py>(
    py: Python<'py>,
    sites: PyReadonlyArray2<'py, f64>,
    x_m: PyReadonlyArray1<'py, f64>,
    y_m: PyReadonlyArray1<'py, f64>,
    walls: PyReadonlyArray2<'py, f64>,
    wall_eps: PyReadonlyArray2<'py, f64>,
    altitude_m: f64,
    freq_hz: f64,
    polarization: &str,
    buildings: PyReadonlyArray2<'py, f64>,
    heights: Option<PyReadonlyArray2<'py, f64>>,
    heights_origin_step: [f64; 4],
    terrain: Option<PyReadonlyArray2<'py, f64>>,
    terrain_origin_step: Option<[f64; 4]>,
    altitude_msl: bool,
    terrain_roughness_m: f64,
    prisms: Option<Bound<'py, Prisms>>,
    prism_eps: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<(
    Bound<'py, numpy::PyArray1<i64>>,
    Bound<'py, numpy::PyArray1<i64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<i64>>,
)> {
    let sites = parse_sites(&sites)?;
    let polarization = parse_polarization(polarization)?;
    let obst = obstacles(&buildings, prisms.as_ref())?;
    let (w, e) = (walls.as_array(), wall_eps.as_array());
    if (w.ncols() != 6 && w.nrows() > 0)
        || (e.ncols() != 2 && e.nrows() > 0)
        || w.nrows() != e.nrows()
    {
        return Err(to_py(CoreError::invalid(
            "walls",
            "must have shape (K, 6) with wall_eps (K, 2)",
            format!("{:?}, {:?}", w.dim(), e.dim()),
        )));
    }
    let walls: Vec<Wall> = w
        .rows()
        .into_iter()
        .zip(e.rows())
        .map(|(r, q)| Wall {
            a: [r[0], r[1]],
            b: [r[2], r[3]],
            base: r[4],
            top: r[5],
            eps: Complex64::new(q[0], q[1]),
        })
        .collect();
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
        ground: RayGround::None,
        polarization,
        rain: RainField::Uniform(0.0),
        prisms: obst.as_ref(),
        heights: raster(hr, Some(heights_origin_step)),
        terrain: raster(tr, terrain_origin_step),
        altitude_msl,
        roughness_m: terrain_roughness_m,
    };
    let corner_eps: Option<Vec<Complex64>> = match &prism_eps {
        None => None,
        Some(e) => {
            let e = e.as_array();
            if e.ncols() != 2 && e.nrows() > 0 {
                return Err(to_py(CoreError::invalid(
                    "prism_eps",
                    "must have shape (P, 2)",
                    format!("{:?}", e.dim()),
                )));
            }
            Some(
                e.rows()
                    .into_iter()
                    .map(|r| Complex64::new(r[0], r[1]))
                    .collect(),
            )
        }
    };
    let rays = detached(py, || {
        let mut all = Vec::new();
        for (k, &site) in sites.iter().enumerate() {
            all.extend(
                scene
                    .wall_rays(site, &walls)?
                    .into_iter()
                    .map(|r| (k, 1, r)),
            );
            all.extend(
                scene
                    .wall_rays2(site, &walls)?
                    .into_iter()
                    .map(|r| (k, 2, r)),
            );
            if let Some(eps) = &corner_eps {
                all.extend(scene.corner_rays(site, eps)?.into_iter().map(|r| (k, 3, r)));
            }
        }
        Ok(all)
    })?;
    let site: Vec<i64> = rays.iter().map(|(k, _, _)| *k as i64).collect();
    let pixel: Vec<i64> = rays.iter().map(|(_, _, r)| r.pixel as i64).collect();
    let kind: Vec<i64> = rays.iter().map(|(_, t, _)| *t as i64).collect();
    let col = |f: fn(&rainuav_core::walls::WallRay) -> f64| -> Vec<f64> {
        rays.iter().map(|(_, _, r)| f(r)).collect()
    };
    Ok((
        site.into_pyarray(py),
        pixel.into_pyarray(py),
        col(|r| r.az_deg).into_pyarray(py),
        col(|r| r.el_deg).into_pyarray(py),
        col(|r| r.factor).into_pyarray(py),
        col(|r| r.length_m).into_pyarray(py),
        kind.into_pyarray(py),
    ))
}

/// Every cell's rays over a map traced once (the clear-air terms and the rays' lengths
/// (M, H, W, 7) from `ray_power(..., terms_only=True)`), `sites` (S, 3): x, y, height,
/// `site_of` (M,): each
/// cell's site), and the power at any instant from its rain (`power`): weather in time.
#[pyclass(frozen, module = "rainuav._core")]
struct RaySlicer {
    inner: rainuav_core::raytime::RaySlicer,
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
            rainuav_core::raytime::RaySlicer::new(t, &sites, &site_of, &x, &y, node_spacing_m)
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
                rainuav_core::raytime::to_dbm(p.view(), rss_floor_dbm, v)?;
            }
            Ok(p)
        })?;
        Ok(out.into_pyarray(py))
    }
}

/// ITU-R P.526's knife-edge loss J(nu), dB, of each `nu`.
#[pyfunction]
fn knife_edge_loss_db<'py>(
    py: Python<'py>,
    nu: PyReadonlyArray1<'py, f64>,
) -> Bound<'py, numpy::PyArray1<f64>> {
    nu.as_array()
        .mapv(rainuav_core::diffraction::knife_edge_loss_db)
        .into_pyarray(py)
}

/// The UTD diffraction coefficient of a finitely conducting wedge (ITU-R P.526-15 section 6)
/// at each `phi2`: exterior angle `n pi`, incidence angle `phi1` and diffraction angles
/// `phi2` (rad, from face 0), distance parameter `l_m`, `sin_beta0`, wavenumber `k` and the
/// faces' reflection coefficients `r0`, `rn` (complex, or one a `phi2`); complex, sqrt(m).
#[pyfunction]
#[pyo3(signature = (n, phi1, phi2, *, l_m, sin_beta0, k, r0, rn))]
#[allow(clippy::too_many_arguments)]
fn utd_wedge<'py>(
    py: Python<'py>,
    n: f64,
    phi1: f64,
    phi2: PyReadonlyArray1<'py, f64>,
    l_m: f64,
    sin_beta0: f64,
    k: f64,
    r0: Complex64,
    rn: Complex64,
) -> PyResult<Bound<'py, numpy::PyArray1<Complex64>>> {
    let ok = n > 1.0 && n <= 2.0 && l_m > 0.0 && k > 0.0 && sin_beta0 > 0.0 && sin_beta0 <= 1.0;
    if !ok || !phi1.is_finite() {
        return Err(to_py(CoreError::invalid(
            "utd_wedge",
            "needs 1 < n <= 2, l_m > 0, k > 0, 0 < sin_beta0 <= 1",
            format!("n {n}, l_m {l_m}, k {k}, sin_beta0 {sin_beta0}"),
        )));
    }
    Ok(phi2
        .as_array()
        .mapv(|p| rainuav_core::diffraction::utd_wedge(n, phi1, p, l_m, sin_beta0, k, r0, rn))
        .into_pyarray(py))
}

/// The Bullington loss (P.526-15 section 4.5.1 with its correction) of the profile
/// `(d_m[i], h_m[i])` between antennas at `h_ts_m` and `h_rs_m` above sea level, `d_total_m`
/// apart: `(loss_db, knife_edge_db, edge_d_m, edge_h_m)` (the edge NaN where the loss is 0).
#[pyfunction]
#[pyo3(signature = (d_m, h_m, *, d_total_m, h_ts_m, h_rs_m, wavelength_m))]
fn bullington_loss(
    d_m: PyReadonlyArray1<'_, f64>,
    h_m: PyReadonlyArray1<'_, f64>,
    d_total_m: f64,
    h_ts_m: f64,
    h_rs_m: f64,
    wavelength_m: f64,
) -> PyResult<(f64, f64, f64, f64)> {
    let (d, h) = (d_m.as_array(), h_m.as_array());
    if d.len() != h.len() {
        return Err(to_py(CoreError::invalid(
            "h_m",
            "must have the length of d_m",
            h.len(),
        )));
    }
    let ok = [d_total_m, h_ts_m, h_rs_m, wavelength_m]
        .iter()
        .chain(d.iter())
        .chain(h.iter())
        .all(|v| v.is_finite())
        && d_total_m > 0.0
        && wavelength_m > 0.0;
    if !ok {
        return Err(to_py(CoreError::invalid(
            "profile",
            "must be finite, with d_total_m > 0 and wavelength_m > 0",
            "a bad value",
        )));
    }
    let profile: Vec<(f64, f64)> = d.iter().copied().zip(h.iter().copied()).collect();
    let b =
        rainuav_core::diffraction::bullington(&profile, d_total_m, h_ts_m, h_rs_m, wavelength_m);
    let (ed, eh) = b.edge.unwrap_or((f64::NAN, f64::NAN));
    Ok((b.loss_db, b.knife_edge_db, ed, eh))
}

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ray_power, m)?)?;
    m.add_function(wrap_pyfunction!(ray_departures, m)?)?;
    m.add_function(wrap_pyfunction!(ray_walls, m)?)?;
    m.add_function(wrap_pyfunction!(utd_wedge, m)?)?;
    m.add_class::<Prisms>()?;
    m.add_function(wrap_pyfunction!(knife_edge_loss_db, m)?)?;
    m.add_function(wrap_pyfunction!(bullington_loss, m)?)?;
    m.add_class::<RaySlicer>()?;
    Ok(())
}
