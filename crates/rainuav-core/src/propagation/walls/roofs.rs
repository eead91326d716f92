//! A wall's reflection over roofs (docs/physics.md section 12): the site's ray diffracted over
//! a roof (or the terrain) down to the wall, or the wall's ray over a roof to the pixel.
//!
//! Unfolded in the wall's plane, the reflected ray is a straight path from the site to the
//! pixel's image, as the direct ray is a straight path to the pixel; where a leg does not clear
//! the profile, the path is read as the direct ray's is ([`RayScene::path`]): the points of both
//! legs within the margin below the unfolded line, at their distance along it, Deygout's
//! isolated edges with each roof edge a wedge, without the correction for real terrain. The
//! specular point stays where the straight unfolded line meets the wall. Such a path is looked
//! for where the leg from the wall to the pixel is at most [`ROOF_LEG_M`], and left out where its
//! loss is over [`MAX_ROOF_LOSS_DB`] or the pixel is inside a building.

use crate::propagation::diffraction::deygout_with;
use crate::propagation::rays::RayScene;
use crate::propagation::sight::Sight;
use crate::propagation::walls::LEG_GAP_M;

/// The largest diffraction loss (dB) a wall's ray over roofs is kept with: deeper ones bring
/// less than 1e-3 of the power the wall would reflect there in sight; each kept one costs the
/// map a ray's rain and antenna gains.
pub const MAX_ROOF_LOSS_DB: f64 = 30.0;

/// The longest leg from the wall to the pixel (m) on which a wall's ray over roofs is looked
/// for: the street in front of the wall and the next blocks, where a UAV below the roofs is
/// lit by such rays. On the 10 000-footprint benchmark map (UAV at 100 m, above most roofs)
/// looking at every length finds 88 times as many of them and changes the total power by more
/// than 1 dB on 0.02% of the pixels (single cells' power by more than 0.1 dB on 2.7% of the
/// cell-pixels: weak cells deep in shadows), for 1.5-2 times the time of the walls' and corners'
/// rays; with this limit that time does not change (BENCHMARKS.md).
pub const ROOF_LEG_M: f64 = 150.0;

/// One end of a wall ray's leg: the ground point, its height above sea level and the leg's
/// horizontal length to the specular point.
type End = ([f64; 2], f64, f64);

impl RayScene<'_> {
    /// The diffraction loss (dB) of the wall ray from the site `(s, zs, rho1)` via the
    /// specular point `(p, zp)` to the pixel `(q, zq, rho2)` over the profile of its legs
    /// (module docs), and the departure elevation (rad) over the first leg's highest edge;
    /// None where the loss is over [`MAX_ROOF_LOSS_DB`].
    pub(crate) fn over_roofs(
        &self,
        sight: &mut Sight,
        (s, zs, rho1): End,
        (p, zp): ([f64; 2], f64),
        (q, zq, rho2): End,
        lambda: f64,
    ) -> Option<(f64, f64)> {
        if rho2 > ROOF_LEG_M {
            return None;
        }
        let rho = rho1 + rho2;
        // Stop at a point whose knife edge alone loses 3 dB more than the largest kept (the
        // principal edge loses at least about that much, whatever else the path meets).
        let g = 10f64.powf((MAX_ROOF_LOSS_DB + 3.0 - 6.9) / 20.0);
        let nu_cap = 0.1 + 0.5 * (g - 1.0 / g);
        let margin = 1.56 * (lambda * rho / 8.0).sqrt();
        let line = |d: f64| zs + (zq - zs) * d / rho;
        let mut prof = std::mem::take(&mut sight.prof);
        prof.clear();
        let mut el = (zp - zs).atan2(rho1);
        for (first, from, z_from, len) in [(true, s, zs, rho1), (false, q, zq, rho2)] {
            if len <= LEG_GAP_M {
                continue;
            }
            let f = 1.0 - LEG_GAP_M / len;
            let end = [
                from[0] + f * (p[0] - from[0]),
                from[1] + f * (p[1] - from[1]),
            ];
            let z_end = z_from + (zp - z_from) * f;
            let open = sight.above((from, z_from - margin), (end, z_end - margin), |t, h| {
                let d = if first {
                    t * f * len
                } else {
                    rho - t * f * len
                };
                let nu = (h - line(d)) * (2.0 * rho / (lambda * d * (rho - d))).sqrt();
                if nu > nu_cap {
                    return false;
                }
                if first {
                    el = el.max((h - zs).atan2(d));
                }
                prof.push((d, h));
                true
            });
            if !open {
                sight.prof = prof;
                return None;
            }
        }
        prof.sort_by(|a, b| a.0.total_cmp(&b.0));
        let at = |d: f64| {
            let (a, b, t) = if d <= rho1 {
                (s, p, d / rho1)
            } else {
                (p, q, (d - rho1) / rho2)
            };
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        };
        let (loss, _) = deygout_with(&prof, rho, zs, zq, lambda, |nu, i, from, to| {
            self.roof_edge_loss_db(&prof, (&at, rho), nu, i, from, to, lambda)
        });
        sight.prof = prof;
        (loss <= MAX_ROOF_LOSS_DB).then_some((loss, el))
    }
}

#[cfg(test)]
mod tests {
    use crate::propagation::obstacles::Prisms;
    use crate::propagation::rays::{RayPolarization, RayScene};
    use crate::propagation::walls::{Wall, wall_reflectance};
    use num_complex::Complex64;

    fn scene<'a>(x: &'a [f64], y: &'a [f64], prisms: &'a Prisms) -> RayScene<'a> {
        RayScene {
            prisms: Some(prisms),
            ..RayScene::bare(x, y, 20.0, 4.9e9)
        }
    }

    #[test]
    fn a_wall_ray_over_a_roof_is_the_direct_ray_to_the_pixels_image() {
        // A wall along x = 100 (facing the site at the origin, 40 m up) and a low block in the
        // way of one leg: unfolded in the wall's plane, the reflected ray is the direct ray to
        // the pixel's image (140, 30) past the block's image, so its diffraction loss is the
        // one the direct path's own method (the profile along the line, Deygout's edges) finds
        // there without the wall: the same to rounding. Leg one: the block between the site
        // and the wall; leg two: between the wall and the pixel (its image for the direct ray).
        let wall = Wall {
            a: [100.0, 200.0],
            b: [100.0, -100.0],
            base: 0.0,
            top: 60.0,
            eps: Complex64::new(5.24, -0.5),
        };
        let site = [0.0, 0.0, 40.0];
        let (x, y) = ([60.0], [30.0]);
        for (block, image) in [
            (
                [40.0, 50.0, -100.0, 100.0, 36.0],
                [40.0, 50.0, -100.0, 100.0, 36.0],
            ),
            (
                [70.0, 78.0, -100.0, 100.0, 22.0],
                [122.0, 130.0, -100.0, 100.0, 22.0],
            ),
        ] {
            let prisms = Prisms::from_boxes(&[block]).unwrap();
            let rays = scene(&x, &y, &prisms).wall_rays(site, &[wall]).unwrap();
            assert_eq!(rays.len(), 1, "{block:?}");
            let mirrored = Prisms::from_boxes(&[image]).unwrap();
            let unfolded = scene(&[], &[], &mirrored);
            let geom = unfolded.path(site, [140.0, 30.0], &mut unfolded.sight(unfolded.bounds()));
            assert!(
                geom.loss_db > 3.0,
                "the block is in the way: {}",
                geom.loss_db
            );
            let d = 140.0_f64.hypot(30.0).hypot(20.0);
            let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
            let p: [f64; 2] = [100.0, 30.0 * 100.0 / 140.0];
            let k: [f64; 3] = [p[0], p[1], -20.0 * 100.0 / 140.0];
            let kn = (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]).sqrt();
            let r2 = wall_reflectance(wall.eps, k.map(|v| v / kn), [-1.0, 0.0], RayPolarization::V);
            let lit = r2 * (lam / (4.0 * std::f64::consts::PI * d)).powi(2);
            let loss = -10.0 * (rays[0].factor / lit).log10();
            assert!(
                (loss - geom.loss_db).abs() < 1e-9,
                "{loss} vs {}",
                geom.loss_db
            );
        }
    }
}
