//! Unit tests of [`super`].

use super::*;
use crate::propagation::rays::{RayGround, RayPolarization, RayTransmitter};
use ndarray::Array3;

fn field() -> Array2<f64> {
    // Two Gaussian cells (250 m and 400 m) over a background, dB/m, nodes 10 m apart.
    Array2::from_shape_fn((121, 161), |(i, j)| {
        let (x, y) = (10.0 * j as f64, 10.0 * i as f64);
        let g = |cx: f64, cy: f64, r: f64| (-((x - cx).powi(2) + (y - cy).powi(2)) / (r * r)).exp();
        0.002 + 0.02 * g(500.0, 700.0, 250.0) + 0.01 * g(1200.0, 300.0, 400.0)
    })
}

fn grid(n: usize, step: f64) -> Vec<f64> {
    (0..n).map(|k| step * (k as f64 + 0.5)).collect()
}

#[test]
fn the_fan_agrees_with_a_line_to_every_pixel() {
    // Loss = mean gamma x distance: within 0.01 dB of the line per pixel (the issue's
    // tolerance for the path integral) from a site inside and one outside the map.
    let v = field();
    let r = Raster {
        values: v.view(),
        origin_step: [0.0, 10.0, 0.0, 10.0],
    };
    let (x, y) = (grid(80, 20.0), grid(60, 20.0));
    for from in [[800.0, 600.0], [-300.0, 1500.0], [3.0, 7.0]] {
        let fan = polar_mean_gamma(&r, from, &x, &y);
        let line = line_per_pixel(&r, from, &x, &y);
        for ((i, j), f) in fan.indexed_iter() {
            let rho = (x[j] - from[0]).hypot(y[i] - from[1]);
            let err = (f - line[[i, j]]).abs() * rho;
            assert!(err < 0.01, "{from:?} ({i}, {j}): {err} dB");
        }
    }
}

#[test]
fn a_slice_is_the_static_power_of_its_rain() {
    let v = field();
    let (x, y) = (grid(40, 40.0), grid(30, 40.0));
    let block = crate::propagation::rays::Prisms::from_boxes(&[[600.0, 700.0, 500.0, 560.0, 60.0]])
        .unwrap();
    let scene = RayScene {
        pixel_m: [40.0, 40.0],
        ground: RayGround::Pec,
        polarization: RayPolarization::H,
        rain: RainField::Raster(Raster {
            values: v.view(),
            origin_step: [0.0, 10.0, 0.0, 10.0],
        }),
        prisms: Some(&block),
        ..RayScene::bare(&x, &y, 100.0, 28e9)
    };
    let sites = [[300.0, 400.0, 25.0], [1300.0, 900.0, 30.0]];
    let site_of = [0, 0, 1];
    let txs: Vec<RayTransmitter> = site_of
        .iter()
        .map(|&s| RayTransmitter {
            position_m: sites[s],
            power_mw: 1000.0,
        })
        .collect();
    let gd = Array3::from_shape_fn((3, 30, 40), |(m, i, j)| 1.0 + ((m + i + j) % 5) as f64);
    let gr = gd.mapv(|g| 0.5 * g);
    // Wall rays: some pixels with, some without.
    let walls =
        ndarray::Array4::from_shape_fn((3, 30, 40, 2), |(m, i, j, k)| match ((i + j + m) % 3, k) {
            (0, _) => 0.0,
            (_, 0) => 1e-9 * (1 + i) as f64,
            _ => 900.0 + (j * 7) as f64,
        });
    let want = scene
        .power_with(&txs, gd.view(), gr.view(), Some(walls.view()), None)
        .unwrap();
    // The terms from paths traced beforehand (as the Python layer does, once for the
    // departures and the powers): the same paths.
    let table = scene.geometry_table(&sites).unwrap();
    let known = crate::propagation::rays::KnownPaths {
        sites: &sites,
        table: table.view(),
    };
    let terms = scene
        .terms(&txs, gd.view(), gr.view(), Some(walls.view()), Some(known))
        .unwrap();
    let got = slice_power(&scene, terms.view(), &sites, &site_of).unwrap();
    for (g, w) in got.iter().zip(want.iter()) {
        // 0.01 dB, the rain integral's tolerance; the rest is the same arithmetic.
        assert!((10.0 * (g / w).log10()).abs() < 0.01, "{g} vs {w}");
    }
    // Uniform rain: the same integral either way, so the same power to rounding.
    let uniform = RayScene {
        rain: RainField::Uniform(0.004),
        ..scene.clone()
    };
    let want = uniform
        .power_with(&txs, gd.view(), gr.view(), Some(walls.view()), None)
        .unwrap();
    let got = slice_power(&uniform, terms.view(), &sites, &site_of).unwrap();
    for (g, w) in got.iter().zip(want.iter()) {
        assert!((g - w).abs() <= 1e-12 * w.abs().max(1e-300), "{g} vs {w}");
    }
    // Bad input is an error, never a panic.
    assert!(slice_power(&scene, terms.view(), &sites, &[0, 0, 2]).is_err());
    assert!(slice_power(&scene, terms.view(), &sites, &[0, 0]).is_err());
    let slicer = RaySlicer::new(terms.view(), &sites, &site_of, &x, &y, 20.0).unwrap();
    assert!(
        slicer.power(scene.rain).is_err(),
        "nodes 10 m apart, slicer's 20 m"
    );
    assert!(slicer.power(RainField::Uniform(f64::NAN)).is_err());
    let mut bad = terms.clone();
    bad[[0, 0, 0, 0]] = f64::NAN;
    assert!(RaySlicer::new(bad.view(), &sites, &site_of, &x, &y, 10.0).is_err());
}

#[test]
fn dbm_of_powers() {
    let p = Array3::from_shape_vec((1, 1, 3), vec![1.0, 0.0, 1e-40]).unwrap();
    let mut out = Array3::<f32>::zeros((1, 1, 3));
    to_dbm(p.view(), -250.0, out.view_mut()).unwrap();
    assert_eq!(out.as_slice().unwrap(), &[0.0, -250.0, -250.0]);
    let mut wrong = Array3::<f32>::zeros((1, 1, 2));
    assert!(to_dbm(p.view(), -250.0, wrong.view_mut()).is_err());
}
