//! Bindings of the rays walls reflect and corners diffract (`rainuav.radio.wall_rays` drives
//! them).

use crate::{detached, to_py};
use num_complex::Complex64;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use rainuav_core::CoreError;
use rainuav_core::propagation::rays::{RainField, RayGround, RayScene};
use rainuav_core::propagation::walls::Wall;

use crate::rays::{Prisms, obstacles, parse_polarization, parse_sites, raster};

/// Every ray that `walls` reflect from each site to the map's pixels (image method, first
/// and second order: `rainuav_core::propagation::walls`, `rainuav_core::propagation::walls2`): `walls` (K, 6) `[ax, ay, bx, by, base, top]` (outward normal on the right of
/// `a -> b`; base and top above the terrain), `wall_eps` (K, 2) each wall's complex
/// permittivity (real, imaginary <= 0), `sites` (S, 3) x, y, height above the terrain.
/// Returns `(site, pixel, az_deg, el_deg, factor, length_m, kind)`, one entry a ray: its site,
/// its pixel (row-major), its departure direction toward its first interaction, its power per
/// mW for isotropic antennas, its length and its kind (1: one wall, 2: two walls, 3: a corner,
/// alone or after a wall). With `prism_eps` (P, 2: each prism's wall
/// permittivity), also the rays the prisms' corners diffract into the pixels they hide
/// (`rainuav_core::propagation::corners`), after the wall rays of the same site.
#[pyfunction]
#[pyo3(signature = (sites, x_m, y_m, walls, wall_eps, *, altitude_m, freq_hz, polarization,
    buildings, heights, heights_origin_step, terrain=None, terrain_origin_step=None,
    altitude_msl=false, terrain_roughness_m=0.0, prisms=None, prism_eps=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
// Long: the binding converts and checks its numpy arrays (each named in its errors) before the core
// is called; that conversion is most of its length.
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
                let [corners, eaves] = scene.edge_rays(site, eps, true)?;
                all.extend(corners.into_iter().map(|r| (k, 3, r)));
                all.extend(eaves.into_iter().map(|r| (k, 4, r)));
            }
        }
        Ok(all)
    })?;
    let site: Vec<i64> = rays.iter().map(|(k, _, _)| *k as i64).collect();
    let pixel: Vec<i64> = rays.iter().map(|(_, _, r)| r.pixel as i64).collect();
    let kind: Vec<i64> = rays.iter().map(|(_, t, _)| *t as i64).collect();
    let col = |f: fn(&rainuav_core::propagation::walls::WallRay) -> f64| -> Vec<f64> {
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

/// Adds this layer's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ray_walls, m)?)?;
    Ok(())
}
