//! Unit tests of [`super`].

use super::*;

#[test]
fn the_fresnel_zone_line_fits_a_plane_exactly_and_measures_a_curve_spread() {
    // A straight ground: the line itself, no spread. A parabola over -a..a: the fitted
    // line is its mean (slope 0) and the spread its standard deviation at the 17 points.
    let (z0, slope, sigma) = fit_line(&|s: f64| 2.0 + 0.1 * s, 50.0, 20.0);
    assert!((z0 - 7.0).abs() < 1e-12 && (slope - 0.1).abs() < 1e-12 && sigma < 1e-9);
    let (z0, slope, sigma) = fit_line(&|s: f64| (s - 10.0).powi(2), 10.0, 4.0);
    let u: Vec<f64> = (0..17).map(|i| -4.0 + 0.5 * i as f64).collect();
    let mean = u.iter().map(|v| v * v).sum::<f64>() / 17.0;
    let var = u.iter().map(|v| (v * v - mean).powi(2)).sum::<f64>() / 17.0;
    assert!((z0 - mean).abs() < 1e-9 && slope.abs() < 1e-9);
    assert!((sigma - var.sqrt()).abs() < 1e-9);
}
