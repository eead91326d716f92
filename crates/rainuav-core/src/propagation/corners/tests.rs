//! Unit tests of [`super`].

use super::sources::Lit;
use super::*;
use crate::propagation::obstacles::Prisms;

/// Pixels at `x` x `y` 10 m up among `prisms`, 4.9 GHz, vertical polarisation, no ground or
/// rain.
fn flat_scene<'a>(x: &'a [f64], y: &'a [f64], prisms: &'a Prisms) -> RayScene<'a> {
    RayScene {
        prisms: Some(prisms),
        ..RayScene::bare(x, y, 10.0, 4.9e9)
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

#[test]
fn the_lit_corners_a_pixel_reads_are_exactly_those_inside_its_ellipse() {
    // Brute force: 2 000 corners scattered over 3 km round the site (every band, every
    // azimuth, the wrap at -pi included) and 300 pixels, near and far; the bands' look-up
    // must find the same corners as testing every one.
    let mut seed = 7u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let site = [120.0, -40.0];
    let corner = |v| Corner {
        v,
        a0: [1.0, 0.0],
        ext: 1.5 * PI,
        top: 10.0,
        prism: 0,
        z_min: 0.0,
    };
    let mut at = |r: f64| {
        let (t, s) = (2.0 * PI * next(), r * next().sqrt());
        [site[0] + s * t.cos(), site[1] + s * t.sin()]
    };
    let mut corners: Vec<Corner> = (0..2000).map(|_| corner(at(3000.0))).collect();
    corners.push(corner([site[0] - 500.0, site[1]])); // azimuth pi exactly
    let pixels: Vec<[f64; 2]> = (0..300)
        .map(|k| at(if k % 2 == 0 { 300.0 } else { 4000.0 }))
        .collect();
    let lit = Lit::new(
        site,
        EXCESS_M,
        corners
            .iter()
            .map(|&c| (c.v, 0.0, (c, Vec::<Image>::new())))
            .collect(),
    );
    let mut found = 0;
    for q in pixels {
        let d = crate::norm(q[0] - site[0], q[1] - site[1]);
        let mut want: Vec<[f64; 2]> = corners
            .iter()
            .filter(|c| {
                crate::norm(c.v[0] - site[0], c.v[1] - site[1])
                    + crate::norm(c.v[0] - q[0], c.v[1] - q[1])
                    - d
                    <= EXCESS_M
            })
            .map(|c| c.v)
            .collect();
        let mut got = Vec::new();
        lit.near(q, |(c, _)| got.push(c.v));
        let key = |a: &[f64; 2], b: &[f64; 2]| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1]));
        want.sort_by(key);
        got.sort_by(key);
        assert_eq!(got, want, "pixel {q:?}");
        found += want.len();
    }
    // The ellipses select: neither none nor every corner, on the whole.
    assert!(found > 300 && found < 300 * corners.len() / 2, "{found}");
}

#[test]
fn a_lit_corner_far_from_the_site_and_off_the_line_diffracts_inside_its_ellipse() {
    // Block A (x 0..40, y -30..10) hides the pixel (200, -5) from the site (-600, 0); block B
    // (x 0..40, y 110..150) stands 100 m across from it. B's south-east corner (40, 110) is
    // 649 m from the site and 114 m off the straight line, but going round it is only 46 m
    // longer than the line: it lights the pixel (a street below the roofs lit round a far
    // corner). With the site 1.2 km away, beyond the lit corners' radius, B sends nothing.
    let prisms = Prisms::from_boxes(&[
        [0.0, 40.0, -30.0, 10.0, 100.0],
        [0.0, 40.0, 110.0, 150.0, 100.0],
    ])
    .unwrap();
    let (x, y) = ([200.0], [-5.0]);
    let scene = flat_scene(&x, &y, &prisms);
    let eps = [Complex64::new(5.24, -0.5); 2];
    let az = |x: f64, y: f64| y.atan2(x).to_degrees();
    let rays = scene.corner_rays([-600.0, 0.0, 10.0], &eps).unwrap();
    let ray = rays
        .iter()
        .find(|r| (r.az_deg - az(640.0, 110.0)).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no ray round (40, 110): {rays:?}"));
    let (r1, r2) = (640.0f64.hypot(110.0), 160.0f64.hypot(115.0));
    assert!((ray.length_m - (r1 + r2)).abs() < 1e-9);
    assert!(r1 > 500.0 && r1 + r2 - 800.0f64.hypot(5.0) < EXCESS_M);
    let far = scene.corner_rays([-1200.0, 0.0, 10.0], &eps).unwrap();
    assert!(far.iter().all(|r| r.az_deg.abs() < 3.0), "{far:?}"); // A's corners at most
}
