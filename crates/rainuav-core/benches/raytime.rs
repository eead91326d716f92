//! Criterion benchmarks of rain in time: one site's rain integral to every pixel of a 200x200
//! map of 10 m pixels through a raster of 10 m nodes, by the fan of lines
//! ([`polar_mean_gamma`]) against a line per pixel (the static ray engine's way), and one
//! slice of 21 cells at 7 sites ([`slice_power`]).
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use ndarray::{Array2, Array4};
use rainuav_core::propagation::rays::{RainField, Raster, RayGround, RayPolarization, RayScene};
use rainuav_core::propagation::raytime::{polar_mean_gamma, slice_power};

fn field() -> Array2<f64> {
    // A 300 m Gaussian cell over a light background, dB/m.
    Array2::from_shape_fn((201, 201), |(i, j)| {
        let (x, y) = (10.0 * j as f64 - 1100.0, 10.0 * i as f64 - 900.0);
        0.001 + 0.02 * (-(x * x + y * y) / 300.0_f64.powi(2)).exp()
    })
}

fn bench(c: &mut Criterion) {
    let values = field();
    let r = Raster {
        values: values.view(),
        origin_step: [0.0, 10.0, 0.0, 10.0],
    };
    let x: Vec<f64> = (0..200).map(|j| 10.0 * j as f64 + 5.0).collect();
    let y = x.clone();
    let mut g = c.benchmark_group("rain_integral_one_site");
    g.sample_size(20);
    g.bench_function("fan_of_lines", |b| {
        b.iter(|| polar_mean_gamma(&r, [1000.0, 1000.0], &x, &y))
    });
    g.bench_function("line_per_pixel", |b| {
        b.iter(|| rainuav_core::propagation::raytime::line_per_pixel(&r, [1000.0, 1000.0], &x, &y))
    });
    g.finish();
    let scene = RayScene {
        x_m: &x,
        y_m: &y,
        altitude_m: 100.0,
        pixel_m: [0.0, 0.0],
        freq_hz: 28e9,
        ground: RayGround::None,
        polarization: RayPolarization::H,
        rain: RainField::Raster(r),
        prisms: None,
        heights: None,
        terrain: None,
        altitude_msl: false,
        roughness_m: 0.0,
    };
    let sites: Vec<[f64; 3]> = (0..7)
        .map(|k| {
            let a = k as f64;
            [1000.0 + 500.0 * a.cos(), 1000.0 + 500.0 * a.sin(), 25.0]
        })
        .collect();
    let site_of: Vec<usize> = (0..21).map(|c| c / 3).collect();
    let terms = Array4::<f64>::from_elem((21, 200, 200, 7), 1e-9);
    let mut g = c.benchmark_group("rain_slice");
    g.sample_size(10);
    g.bench_function("21_cells_7_sites_200x200", |b| {
        b.iter(|| slice_power(&scene, terms.view(), &sites, &site_of).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
