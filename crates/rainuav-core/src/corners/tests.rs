//! Unit tests of [`super`].

use super::*;
use crate::obstacles::Prisms;
use crate::rays::RainField;

#[test]
fn a_corner_seen_from_both_ends_is_the_utd_wedge_and_a_hidden_pixel_gets_one_ray_a_side() {
    // One 40 m square block, roof 100 m (nothing over the roof); the site west of it, a
    // pixel due east behind it: the two corners facing the site are hidden from the pixel
    // and the two at the back from the site; nothing reaches it by one corner. A pixel
    // north-east of the block, hidden by it, sees the north-west corner: one ray, whose
    // power is the UTD wedge's by hand.
    let prisms = Prisms::from_boxes(&[[0.0, 40.0, -20.0, 20.0, 100.0]]).unwrap();
    let (x, y) = ([80.0], [0.0]);
    let scene = RayScene {
        x_m: &x,
        y_m: &y,
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
        prisms: Some(&prisms),
    };
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
