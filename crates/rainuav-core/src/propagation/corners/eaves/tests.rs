//! Unit tests of [`super`].

use super::*;
use crate::propagation::obstacles::Prisms;

/// The `eave` scene of the tracer tests: a 40 m block hides the pixels behind it from a
/// 30 m mast at the origin; a long low building (roof 18 m) beside the line.
fn eave_scene<'a>(x: &'a [f64], y: &'a [f64], prisms: &'a Prisms) -> RayScene<'a> {
    RayScene {
        polarization: RayPolarization::H,
        prisms: Some(prisms),
        ..RayScene::bare(x, y, 20.0, 4.9e9)
    }
}

fn boxes() -> Prisms {
    Prisms::from_boxes(&[
        [100.0, 120.0, -70.0, 25.0, 40.0],
        [60.0, 220.0, 45.0, 70.0, 18.0],
    ])
    .unwrap()
}

#[test]
fn a_roof_edge_ray_takes_the_shortest_path_over_the_edge() {
    // Keller's point against brute force: the ray off the edge y = 45 (the low building's
    // side facing the mast) is as long as the shortest path from the mast over that edge
    // to the pixel, sampled every 0.1 mm along it.
    let prisms = boxes();
    let (x, y) = ([190.0], [2.0]);
    let scene = eave_scene(&x, &y, &prisms);
    let eps = [Complex64::new(5.24, -0.59); 2];
    let [_, eaves] = scene.edge_rays([0.0, 0.0, 30.0], &eps, true).unwrap();
    let path = |x: f64| {
        let leg = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        leg([x, 45.0, -12.0]) + leg([190.0 - x, 2.0 - 45.0, 2.0])
    };
    let shortest = (0..1_600_000)
        .map(|i| path(60.0 + 1e-4 * i as f64))
        .fold(f64::INFINITY, f64::min);
    let ray = eaves
        .iter()
        .min_by(|a, b| {
            (a.length_m - shortest)
                .abs()
                .total_cmp(&(b.length_m - shortest).abs())
        })
        .expect("the edge facing the mast diffracts to the pixel");
    assert!((ray.length_m - shortest).abs() < 1e-6, "{ray:?} {shortest}");
    // Toward the edge: down from the mast, north of east.
    assert!(
        ray.el_deg < 0.0 && ray.az_deg > 0.0 && ray.az_deg < 90.0,
        "{ray:?}"
    );
}

#[test]
fn roof_edges_light_only_hidden_pixels_and_no_ray_is_below_the_floor() {
    // A row of pixels from the open street (line of sight) into the block's shadow.
    let prisms = boxes();
    let x: Vec<f64> = (0..40).map(|i| 20.0 + 5.0 * i as f64).collect();
    let y = [2.0];
    let scene = eave_scene(&x, &y, &prisms);
    let eps = [Complex64::new(5.24, -0.59); 2];
    let site = [0.0, 0.0, 30.0];
    let [_, eaves] = scene.edge_rays(site, &eps, true).unwrap();
    assert!(!eaves.is_empty());
    let lambda = crate::SPEED_OF_LIGHT_M_S / scene.freq_hz;
    let mut sight = scene.sight(scene.bounds());
    for r in &eaves {
        let q = [x[r.pixel], y[0]];
        assert!(
            !sight.clear([0.0, 0.0], 30.0, q, 20.0),
            "{r:?}: the pixel is in sight"
        );
        let d2 = q[0] * q[0] + q[1] * q[1] + 100.0;
        let free = (lambda / (4.0 * PI)).powi(2) / d2;
        assert!(r.factor >= free * 10f64.powf(-0.1 * EAVE_FLOOR_DB), "{r:?}");
        assert!(
            r.factor < free,
            "{r:?}: an edge's ray is weaker than free space"
        );
    }
    // Without the flag, none.
    assert!(scene.edge_rays(site, &eps, false).unwrap()[1].is_empty());
}

#[test]
fn across_an_edge_square_to_the_ray_vertical_is_hard_and_horizontal_soft() {
    // The edge along y, the ray in the x-z plane: a vertical field lies across the edge
    // (hard), a horizontal one along it (soft). A ray oblique to the edge in the horizontal
    // plane keeps that split but for its elevation's share, and the receiver's projection
    // takes at most what came in.
    let edge = [0.0, 1.0, 0.0];
    let ai = normalized([1.0, 0.0, -0.2]);
    let ad = normalized([1.0, 0.0, 0.05]);
    let (s, h) = split(RayPolarization::V, edge, ai, ad);
    assert!(s.abs() < 1e-12 && (h.abs() - 1.0).abs() < 1e-12, "{s} {h}");
    let (s, h) = split(RayPolarization::H, edge, ai, ad);
    assert!((s.abs() - 1.0).abs() < 1e-12 && h.abs() < 1e-12, "{s} {h}");
    let ai = normalized([1.0, 0.8, -0.2]);
    let ad = normalized([1.0, 0.8, 0.05]); // on the edge's Keller cone: same angle to it
    for (pol, main) in [(RayPolarization::V, 1), (RayPolarization::H, 0)] {
        let (s, h) = split(pol, edge, ai, ad);
        let parts = [s.abs(), h.abs()];
        assert!(
            parts[1 - main] > 1e-3 && parts[1 - main] < 0.1,
            "{pol:?} {s} {h}"
        );
        assert!(
            parts[main] > 0.95 && s * s + h * h <= 1.0 + 1e-12,
            "{pol:?} {s} {h}"
        );
    }
}
