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

#[test]
fn a_flat_roofs_far_edge_diffracts_as_a_right_angled_wedge_with_the_roof_as_its_lit_face() {
    // One 60 m deep building, roof 20 m, seen from a 30 m mast over flat ground; the
    // receiver at 5 m behind it. The near edge lies below the line from the site to the far
    // edge (no loss), so the loss is the far edge's alone: the wedge of the roof (face 0, lit
    // from above) and the back wall (face n, n = 1.5), angles worked out here from the
    // geometry, concrete faces (P.2040), the UTD coefficient of a finitely conducting wedge.
    use crate::propagation::diffraction::{EFFECTIVE_EARTH_RADIUS_M, utd_wedge};
    use crate::propagation::obstacles::Prisms;
    use crate::propagation::rays::{RayGround, RayPolarization, RayScene, reflection_coefficient};
    use std::f64::consts::PI;
    let prisms = Prisms::from_boxes(&[[100.0, 160.0, -50.0, 50.0, 20.0]]).unwrap();
    let (x, y) = ([200.0], [0.0]);
    for pol in [RayPolarization::V, RayPolarization::H] {
        let scene = RayScene {
            polarization: pol,
            prisms: Some(&prisms),
            ..RayScene::bare(&x, &y, 5.0, 4.9e9)
        };
        let mut sight = scene.sight(scene.bounds());
        let got = scene
            .path([0.0, 0.0, 30.0], [200.0, 0.0], &mut sight)
            .loss_db;
        // The far edge at 160 m, 20 m (and the Earth's bulge over 200 m).
        let g = 20.0 + 160.0 * 40.0 / (2.0 * EFFECTIVE_EARTH_RADIUS_M);
        let (to_site, to_rx) = ([-160.0, 30.0 - g], [40.0, 5.0 - g]);
        // From the roof (pointing back, toward the site) over the top to the wall (down).
        let phi1 = (to_site[1] / -to_site[0]).atan();
        let phi2 = PI + (-to_rx[1] / to_rx[0]).atan();
        let (s1, s2) = (to_site[0].hypot(to_site[1]), to_rx[0].hypot(to_rx[1]));
        let lambda = 299_792_458.0 / 4.9e9;
        let f = 4.9_f64;
        let concrete = num_complex::Complex64::new(5.24, -17.98 * 0.0462 * f.powf(0.7822) / f);
        let r0 = reflection_coefficient(RayGround::Dielectric(concrete), pol, phi1);
        let rn = reflection_coefficient(RayGround::Dielectric(concrete), pol, 1.5 * PI - phi2);
        let d = utd_wedge(
            1.5,
            phi1,
            phi2,
            s1 * s2 / (s1 + s2),
            1.0,
            2.0 * PI / lambda,
            r0,
            rn,
        );
        let want = -20.0 * (d.norm() * ((s1 + s2) / (s1 * s2)).sqrt()).log10();
        // The profile reads the far face a hair inside the building: 1e-3 dB.
        assert!((got - want).abs() < 1e-3, "{pol:?}: {got} against {want}");
        // Not the knife edge: the wedge's faces matter here (several dB apart).
        let nu =
            (g - (30.0 - 25.0 * 160.0 / 200.0)) * (2.0 * 200.0 / (lambda * 160.0 * 40.0)).sqrt();
        assert!((got - knife_edge_loss_db(nu)).abs() > 1.0, "{pol:?}");
    }
}
