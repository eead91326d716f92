//! Unit tests of [`super`].

use super::*;
use ndarray::array;

fn opts(model: Model, pol: Polarization, shape: Shape) -> MediumOptions {
    MediumOptions {
        model,
        polarization: pol,
        shape,
        ..Default::default()
    }
}

fn gamma(f: f64, r: f64, o: &MediumOptions) -> f64 {
    RainKernel::new(f, o)
        .unwrap()
        .evaluate(r)
        .unwrap()
        .gamma_db_per_km
}

/// docs/physics.md's measured values for Marshall-Palmer, 20 C, spheres (2 significant
/// figures quoted, so 2% relative).
#[test]
fn forward_scattering_matches_physics_md() {
    let o = opts(Model::ForwardScattering, Polarization::H, Shape::Sphere);
    for (f, want) in [(4.9e9, 0.044), (10e9, 0.59), (28e9, 4.80), (60e9, 12.3)] {
        let g = gamma(f, 25.0, &o);
        assert!((g / want - 1.0).abs() < 0.02, "{f}: {g} vs {want}");
    }
}

/// Doubling the Gauss points per panel changes the attenuation by < 1e-6 relative,
/// for both models and across the band (the convergence criterion).
#[test]
fn quadrature_converged() {
    for model in [Model::ForwardScattering, Model::QuasiStatic] {
        for f in [1e9, 4.9e9, 30e9, 100e9, 300e9, 1e12] {
            for r in [0.5, 12.5, 150.0] {
                let mut o = opts(model, Polarization::V, Shape::BeardChuang);
                let a = gamma(f, r, &o);
                o.nodes_per_panel *= 2;
                let b = gamma(f, r, &o);
                assert!((a / b - 1.0).abs() < 1e-6, "{model:?} {f} {r}: {a} {b}");
            }
        }
    }
}

/// Small drops at low frequency: forward scattering tends to the quasi-static sphere
/// model. With drops of at most 0.5 mm at 1 GHz, |m| x <= 0.05, so the leading
/// correction O((|m| x)^2) is below 3e-3: 1% relative on the attenuation.
#[test]
fn models_agree_in_rayleigh_limit() {
    let small = Dsd::table(vec![0.1, 0.5], vec![1000.0, 1000.0]).unwrap();
    let mut fs = opts(Model::ForwardScattering, Polarization::H, Shape::Sphere);
    fs.dsd = small.clone();
    let mut qs = opts(Model::QuasiStatic, Polarization::H, Shape::Sphere);
    qs.dsd = small;
    let (a, b) = (gamma(1e9, 1.0, &fs), gamma(1e9, 1.0, &qs));
    assert!((a / b - 1.0).abs() < 0.01, "{a} {b}");
}

#[test]
fn clear_air_and_batch() {
    let o = MediumOptions::default();
    let e = RainKernel::new(5e9, &o).unwrap().evaluate(0.0).unwrap();
    assert_eq!(e.eps, Complex64::new(1.0, 0.0));
    let g = specific_attenuation_many(
        array![5e9, 5e9, 6e9].view(),
        array![0.0, 10.0, 10.0].view(),
        &o,
    )
    .unwrap();
    assert_eq!(g[0], 0.0);
    assert!(g[2] > g[1] && g[1] > 0.0);
    let bad = specific_attenuation_many(array![5e9].view(), array![-1.0].view(), &o);
    assert!(matches!(
        bad,
        Err(CoreError::InvalidArgument {
            name: "rain_rate_mm_h",
            ..
        })
    ));
}
