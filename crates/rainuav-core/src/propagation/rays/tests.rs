//! Unit tests of [`super`].

use super::*;
use ndarray::Array2;

fn scene<'a>(x: &'a [f64], y: &'a [f64], ground: RayGround) -> RayScene<'a> {
    RayScene {
        ground,
        polarization: RayPolarization::H,
        ..RayScene::bare(x, y, 100.0, 4.9e9)
    }
}

fn one(s: &RayScene<'_>, tx: RayTransmitter) -> f64 {
    let g = Array3::<f64>::ones((1, 1, 1));
    s.power(&[tx], g.view(), g.view()).unwrap()[[0, 0, 0]]
}

const TX: RayTransmitter = RayTransmitter {
    position_m: [0.0, 0.0, 25.0],
    power_mw: 1.0,
};

#[test]
fn free_space_is_friis() {
    // Friis: P = Pt (lambda / (4 pi d))^2 for isotropic antennas; exact to rounding.
    let (x, y) = ([1000.0], [0.0]);
    let s = scene(&x, &y, RayGround::None);
    let d = (1000.0_f64.powi(2) + 75.0_f64.powi(2)).sqrt();
    let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
    let want = (lam / (4.0 * std::f64::consts::PI * d)).powi(2);
    assert!((one(&s, TX) / want - 1.0).abs() < 1e-12);
}

#[test]
fn pec_two_ray_matches_closed_form_and_averages_to_the_incoherent_sum() {
    // Closed form for a PEC ground, H polarisation: |1/d1 e^{-jk d1} - 1/d2 e^{-jk d2}|^2.
    let (x, y) = ([1000.0], [0.0]);
    let mut s = scene(&x, &y, RayGround::Pec);
    let k = crate::wavenumber(4.9e9);
    let d1 = (1000.0_f64.powi(2) + 75.0_f64.powi(2)).sqrt();
    let d2 = (1000.0_f64.powi(2) + 125.0_f64.powi(2)).sqrt();
    let e = Complex64::from_polar(1.0 / d1, -k * d1) - Complex64::from_polar(1.0 / d2, -k * d2);
    let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
    let scale = (lam / (4.0 * std::f64::consts::PI)).powi(2);
    assert!((one(&s, TX) / (scale * e.norm_sqr()) - 1.0).abs() < 1e-9);
    // A pixel holding many fringes (fringe spacing ~12 m here; 200 m pixel) averages to
    // the incoherent sum within 2% (sinc tails: |sinc| < 0.02 at this width).
    s.pixel_m = [200.0, 200.0];
    let inc = scale * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
    assert!((one(&s, TX) / inc - 1.0).abs() < 0.02);
}

#[test]
fn dielectric_reflection_limits() {
    // Grazing incidence reflects with -1 for either polarisation; normal incidence gives
    // (1 - sqrt(eps)) / (1 + sqrt(eps)) for H.
    let eps = Complex64::new(15.0, -1.0);
    for p in [RayPolarization::H, RayPolarization::V] {
        let g = reflection_coefficient(RayGround::Dielectric(eps), p, 1e-9);
        assert!((g + 1.0).norm() < 1e-6);
    }
    let g = reflection_coefficient(
        RayGround::Dielectric(eps),
        RayPolarization::H,
        std::f64::consts::FRAC_PI_2,
    );
    let want = (1.0 - eps.sqrt()) / (1.0 + eps.sqrt());
    assert!((g - want).norm() < 1e-12);
}

#[test]
fn uniform_rain_is_gamma_times_length_and_a_raster_of_the_same_value_agrees() {
    let (x, y) = ([800.0], [300.0]);
    let mut s = scene(&x, &y, RayGround::None);
    let clear = one(&s, TX);
    s.rain = RainField::Uniform(0.01);
    let d = (800.0_f64.powi(2) + 300.0_f64.powi(2) + 75.0_f64.powi(2)).sqrt();
    let a = 10.0 * (clear / one(&s, TX)).log10();
    assert!((a - 0.01 * d).abs() < 1e-9);
    let vals = Array2::from_elem((3, 4), 0.01);
    s.rain = RainField::Raster(Raster {
        values: vals.view(),
        origin_step: [0.0, 500.0, 0.0, 500.0],
    });
    let a = 10.0 * (clear / one(&s, TX)).log10();
    assert!((a - 0.01 * d).abs() < 1e-9);
}

#[test]
fn a_building_on_the_path_costs_its_two_isolated_edges() {
    // Transmitter at 25 m, receiver at 100 m, 1000 m away; a 200 m tall wall, 10 m thick,
    // at 500 m. By hand (docs/physics.md section 12): both faces are profile points; the
    // principal edge is the face of larger nu, the other face diffracts on its sub-path;
    // their knife-edge losses add, with no terrain correction (a building, flat ground).
    let (x, y) = ([1000.0], [0.0]);
    let mut s = scene(&x, &y, RayGround::None);
    let clear = one(&s, TX);
    let wall = Prisms::from_boxes(&[[495.0, 505.0, -50.0, 50.0, 200.0]]).unwrap();
    s.prisms = Some(&wall);
    let loss = 10.0 * (clear / one(&s, TX)).log10();
    let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
    let (d, hts, hrs) = (1000.0_f64, 25.0, 100.0);
    let g = |di: f64| 200.0 + di * (d - di) / (2.0 * 8.5e6);
    let nu = |s0: f64, z0: f64, s1: f64, z1: f64, di: f64| {
        let line = z0 + (z1 - z0) * (di - s0) / (s1 - s0);
        (g(di) - line) * (2.0 * (s1 - s0) / (lam * (di - s0) * (s1 - di))).sqrt()
    };
    let (n1, n2) = (nu(0.0, hts, d, hrs, 495.0), nu(0.0, hts, d, hrs, 505.0));
    let want = if n1 >= n2 {
        knife_edge_loss_db(n1) + knife_edge_loss_db(nu(495.0, g(495.0), d, hrs, 505.0))
    } else {
        knife_edge_loss_db(n2) + knife_edge_loss_db(nu(0.0, hts, 505.0, g(505.0), 495.0))
    };
    assert!((loss - want).abs() < 1e-6, "{loss} vs {want}");
}

#[test]
fn a_flat_terrain_at_any_height_is_the_flat_ground() {
    // Terrain at 437 m everywhere: every height is measured from it, so the rays are
    // those of the flat ground at 0 to rounding (the general path against the closed form).
    let x: Vec<f64> = (0..9).map(|k| 120.0 * k as f64 + 5.0).collect();
    let y = [-300.0, 10.0, 700.0];
    let flat = scene(&x, &y, RayGround::Dielectric(Complex64::new(15.0, -1.0)));
    let dem = Array2::from_elem((4, 4), 437.0);
    let mut hilly = flat.clone();
    hilly.terrain = Some(Raster {
        values: dem.view(),
        origin_step: [-2000.0, 1500.0, -2000.0, 1500.0],
    });
    let g = Array3::<f64>::ones((1, 3, 9));
    let a = flat.power(&[TX], g.view(), g.view()).unwrap();
    let b = hilly.power(&[TX], g.view(), g.view()).unwrap();
    for (p, q) in a.iter().zip(b.iter()) {
        assert!((p / q - 1.0).abs() < 1e-9, "{p} vs {q}");
    }
}

#[test]
fn a_ridge_hides_the_reflection_and_costs_the_direct_ray() {
    // A ridge 150 m high between the site and the pixel: the direct ray diffracts, the
    // reflection's legs cannot see its specular point.
    let (x, y) = ([1000.0], [0.0]);
    let mut s = scene(&x, &y, RayGround::Pec);
    let dem = Array2::from_shape_fn((3, 21), |(_, j)| if j == 10 { 150.0 } else { 0.0 });
    s.terrain = Some(Raster {
        values: dem.view(),
        origin_step: [0.0, 50.0, -50.0, 50.0],
    });
    let geo = s.path(TX.position_m, [1000.0, 0.0], &mut s.sight(s.bounds()));
    assert!(geo.reflect < 0.01, "{}", geo.reflect); // faded by the ridge: 40 dB or more
    assert!(geo.loss_db > 10.0, "{}", geo.loss_db);
    // The gain is taken toward the ridge's Bullington point: upward, not along the line.
    assert!(geo.el_direct > (75.0_f64).atan2(1000.0));
}

#[test]
fn bad_inputs_are_errors() {
    let (x, y) = ([1000.0], [0.0]);
    let mut s = scene(&x, &y, RayGround::None);
    s.rain = RainField::Uniform(f64::NAN);
    let g = Array3::<f64>::ones((1, 1, 1));
    assert!(s.power(&[TX], g.view(), g.view()).is_err());
    let s = scene(&x, &y, RayGround::None);
    let g2 = Array3::<f64>::ones((2, 1, 1));
    assert!(s.power(&[TX], g2.view(), g.view()).is_err());
}
