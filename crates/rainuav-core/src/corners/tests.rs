//! Unit tests of [`super`].

use super::*;
use crate::obstacles::Prisms;
use crate::rays::RainField;

/// Pixels at `x` x `y` 10 m up among `prisms`, 4.9 GHz, vertical polarisation, no ground or
/// rain.
fn flat_scene<'a>(x: &'a [f64], y: &'a [f64], prisms: &'a Prisms) -> RayScene<'a> {
    RayScene {
        x_m: x,
        y_m: y,
        altitude_m: 10.0,
        pixel_m: [0.0, 0.0],
        freq_hz: 4.9e9,
        polarization: RayPolarization::V,
        ground: RayGround::None,
        rain: RainField::Uniform(0.0),
        heights: None,
        terrain: None,
        altitude_msl: false,
        roughness_m: 0.0,
        prisms: Some(prisms),
    }
}

#[test]
fn a_corner_seen_from_both_ends_is_the_utd_wedge_and_a_hidden_pixel_gets_one_ray_a_side() {
    // One 40 m square block, roof 100 m (nothing over the roof); the site west of it, a
    // pixel due east behind it: the two corners facing the site are hidden from the pixel
    // and the two at the back from the site; nothing reaches it by one corner. A pixel
    // north-east of the block, hidden by it, sees the north-west corner: one ray, whose
    // power is the UTD wedge's by hand.
    let prisms = Prisms::from_boxes(&[[0.0, 40.0, -20.0, 20.0, 100.0]]).unwrap();
    let (x, y) = ([80.0], [0.0]);
    let scene = flat_scene(&x, &y, &prisms);
    let eps = [Complex64::new(5.24, -0.5)];
    let site = [-60.0, 0.0, 10.0];
    assert!(scene.corner_rays(site, &eps).unwrap().is_empty());
    let (x, y) = ([60.0], [30.0]);
    let scene = RayScene {
        x_m: &x,
        y_m: &y,
        ..scene
    };
    let rays = scene.corner_rays(site, &eps).unwrap();
    assert_eq!(rays.len(), 1, "{rays:?}"); // one block: no other wall mirrors the site
    // By hand: corner (0, 20); the site lights the west face, face 0, toward (0, -20)
    // (south); the exterior 270 degrees clockwise from it to the north face (east).
    let (r1, r2) = ((60.0f64).hypot(20.0), (60.0f64).hypot(10.0));
    let phi1 = 1.5 * PI - ccw([1.0, 0.0], [-60.0, -20.0]);
    let phi2 = 1.5 * PI - ccw([1.0, 0.0], [60.0, 10.0]);
    let l = r1 * r2 / (r1 + r2);
    let ground = RayGround::Dielectric(eps[0]);
    let r0 = reflection_coefficient(ground, RayPolarization::H, phi1.sin().abs().asin());
    let rn = reflection_coefficient(
        ground,
        RayPolarization::H,
        (1.5 * PI - phi2).sin().abs().asin(),
    );
    let k = crate::wavenumber(4.9e9);
    let d = utd_wedge(1.5, phi1, phi2, l, 1.0, k, r0, rn);
    let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
    let want = (lam / (4.0 * PI)).powi(2) * d.norm_sqr() / (r1 * r2 * (r1 + r2));
    assert!((rays[0].factor / want - 1.0).abs() < 1e-9);
    assert!((rays[0].length_m - (r1 + r2)).abs() < 1e-9);
    assert!((rays[0].az_deg - (20.0f64).atan2(60.0).to_degrees()).abs() < 1e-9);
}

#[test]
fn a_corner_across_the_street_from_the_building_in_the_way_diffracts_too() {
    // Block A (x 0..40, y -30..10) hides the pixel (200, -5) from the site (-100, 0); block B
    // (x 0..40, y 30..70) stands across a 20 m street, beside the line. The site sees B's
    // south-east corner (40, 30) down the street and the corner sees the pixel: one ray, the
    // UTD wedge's by hand, though B is not in the way. A's corners reach nothing (each is
    // hidden from one end by A itself).
    let prisms = Prisms::from_boxes(&[
        [0.0, 40.0, -30.0, 10.0, 100.0],
        [0.0, 40.0, 30.0, 70.0, 100.0],
    ])
    .unwrap();
    let (x, y) = ([200.0], [-5.0]);
    let scene = flat_scene(&x, &y, &prisms);
    let eps = [Complex64::new(5.24, -0.5); 2];
    let rays = scene.corner_rays([-100.0, 0.0, 10.0], &eps).unwrap();
    assert_eq!(rays.len(), 2, "{rays:?}");
    let az = |x: f64, y: f64| y.atan2(x).to_degrees();
    assert!(
        rays.iter()
            .any(|r| (r.az_deg - az(100.0, 30.0)).abs() < 1e-9)
    ); // (0, 30)
    let ray = rays
        .iter()
        .find(|r| (r.az_deg - az(140.0, 30.0)).abs() < 1e-9)
        .unwrap();
    // Face 0 is B's south wall, from the corner toward -x; the exterior runs counter-clockwise
    // through south and east to the east wall.
    let (to_s, to_q) = ([-140.0, -30.0], [160.0, -35.0]);
    let (phi1, phi2) = (ccw([-1.0, 0.0], to_s), ccw([-1.0, 0.0], to_q));
    let (r1, r2) = (140.0f64.hypot(30.0), 160.0f64.hypot(35.0));
    let ground = RayGround::Dielectric(eps[1]);
    let r0 = reflection_coefficient(ground, RayPolarization::H, phi1.sin().abs().asin());
    let rn = reflection_coefficient(
        ground,
        RayPolarization::H,
        (1.5 * PI - phi2).sin().abs().asin(),
    );
    let k = crate::wavenumber(4.9e9);
    let d = utd_wedge(1.5, phi1, phi2, r1 * r2 / (r1 + r2), 1.0, k, r0, rn);
    let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
    let want = (lam / (4.0 * PI)).powi(2) * d.norm_sqr() / (r1 * r2 * (r1 + r2));
    assert!(
        (ray.factor / want - 1.0).abs() < 1e-9,
        "{} {want}",
        ray.factor
    );
    assert!((ray.length_m - (r1 + r2)).abs() < 1e-9);
}
