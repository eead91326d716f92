//! Second-order reflections off building walls (docs/physics.md section 12): the street canyon,
//! by the image method twice.
//!
//! The site's image `I1` in a first wall, then `I1`'s image `I2` in a second wall that faces
//! the first: a pixel sees `I2` through the second wall and through the first wall's image in
//! the second (two wedges from `I2`, and in front of the second wall: per row of the map, one
//! interval of columns, as for one wall in [`crate::propagation::walls`]). The path unfolds into the straight
//! line from `I2` to the pixel: its second reflection point is where that line crosses the
//! second wall, its first where the line from `I1` to that point crosses the first; the heights
//! grow linearly along the unfolded horizontal length. The ray exists where both points lie on
//! their walls (between base and top) and the three legs clear every building and the terrain.
//!
//! Its power per mW radiated, isotropic antennas: `|Gamma_1|^2 |Gamma_2|^2 (lambda / (4 pi
//! d))^2` with `d` the unfolded length and each `|Gamma|^2` the wall's P.2040 reflectance
//! ([`crate::propagation::walls::wall_reflectance`]) for its incident direction, the site's polarisation
//! split at each wall as at the first (the rotation of the field between the bounces is
//! neglected). Powers add incoherently to the rest.
//!
//! **Which pairs.** A first wall lit by the site, and a second wall that faces it (each in front
//! of the other), faces the first image, and lies within [`PAIR_RADIUS_M`] of it (between their
//! midpoints, less their half-lengths): the street's other side, not the far end of the town;
//! and rays no longer than [`MAX_LENGTH_M`] (the first wall no farther from the site). Both
//! limits are symmetric in the ends, so the rays stay reciprocal.

use rayon::prelude::*;
use std::collections::HashMap;

use crate::error::Result;
use crate::propagation::rays::RayScene;
use crate::propagation::sight::Sight;
use crate::propagation::walls::{
    LEG_GAP_M, Wall, WallRay, columns, interval, normal, wall_reflectance,
};

/// The longest twice-reflected ray, m (unfolded length).
pub const MAX_LENGTH_M: f64 = 1000.0;

/// A second wall counts within this distance (m) of the first (midpoints, less half-lengths).
pub const PAIR_RADIUS_M: f64 = 120.0;

fn mirror(p: [f64; 2], a: [f64; 2], n: [f64; 2]) -> [f64; 2] {
    let d = (p[0] - a[0]) * n[0] + (p[1] - a[1]) * n[1];
    [p[0] - 2.0 * d * n[0], p[1] - 2.0 * d * n[1]]
}

fn side(p: [f64; 2], a: [f64; 2], n: [f64; 2]) -> f64 {
    (p[0] - a[0]) * n[0] + (p[1] - a[1]) * n[1]
}

/// The two conditions (per row `y`, linear in `x`) that put a pixel in the wedge from `apex`
/// through the segment `e0 -> e1`.
fn wedge(apex: [f64; 2], e0: [f64; 2], e1: [f64; 2], y: f64) -> [(f64, f64); 2] {
    let (u0, u1) = (
        [e0[0] - apex[0], e0[1] - apex[1]],
        [e1[0] - apex[0], e1[1] - apex[1]],
    );
    let sgn = (u0[0] * u1[1] - u0[1] * u1[0]).signum();
    [
        (
            -sgn * u0[1],
            sgn * (u0[0] * (y - apex[1]) + u0[1] * apex[0]),
        ),
        (
            sgn * u1[1],
            sgn * (-apex[0] * u1[1] - (y - apex[1]) * u1[0]),
        ),
    ]
}

fn seg_distance(w: &Wall, p: [f64; 2]) -> f64 {
    let d = [w.b[0] - w.a[0], w.b[1] - w.a[1]];
    let l2 = (d[0] * d[0] + d[1] * d[1]).max(1e-18);
    let t = (((p[0] - w.a[0]) * d[0] + (p[1] - w.a[1]) * d[1]) / l2).clamp(0.0, 1.0);
    crate::norm(p[0] - w.a[0] - t * d[0], p[1] - w.a[1] - t * d[1])
}

impl RayScene<'_> {
    /// The pairs `(first, second)` of walls that may reflect twice from the site (module docs).
    fn wall_pairs(&self, site: [f64; 3], zs: f64, walls: &[Wall]) -> Vec<(usize, usize)> {
        let s = [site[0], site[1]];
        let zq: Vec<f64> = self
            .y_m
            .iter()
            .flat_map(|&y| self.x_m.iter().map(move |&x| [x, y]))
            .map(|q| self.receiver_height(q))
            .collect();
        let span = zq
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| {
                (a.min(z), b.max(z))
            });
        // Walls bucketed by midpoint on a grid of PAIR_RADIUS_M.
        let cell = PAIR_RADIUS_M;
        let key = |w: &Wall| {
            let m = [0.5 * (w.a[0] + w.b[0]), 0.5 * (w.a[1] + w.b[1])];
            ((m[0] / cell).floor() as i64, (m[1] / cell).floor() as i64)
        };
        let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        let mut longest: f64 = 0.0;
        for (k, w) in walls.iter().enumerate() {
            grid.entry(key(w)).or_default().push(k);
            longest = longest.max(crate::norm(w.b[0] - w.a[0], w.b[1] - w.a[1]));
        }
        let reach = 1 + (longest / cell).ceil() as i64;
        let first: Vec<usize> = (0..walls.len())
            .filter(|&k| {
                seg_distance(&walls[k], s) <= MAX_LENGTH_M
                    && self.wall_lit(site, zs, span, &walls[k])
            })
            .collect();
        first
            .par_iter()
            .flat_map_iter(|&k1| {
                let w1 = &walls[k1];
                let Some((n1, l1)) = normal(w1) else {
                    return Vec::new();
                };
                let img = mirror(s, w1.a, n1);
                let (cx, cy) = key(w1);
                let mut out = Vec::new();
                for gx in cx - reach..=cx + reach {
                    for gy in cy - reach..=cy + reach {
                        for &k2 in grid.get(&(gx, gy)).map_or(&[][..], |v| &v[..]) {
                            let w2 = &walls[k2];
                            let Some((n2, l2)) = normal(w2) else {
                                continue;
                            };
                            let m1 = [0.5 * (w1.a[0] + w1.b[0]), 0.5 * (w1.a[1] + w1.b[1])];
                            let m2 = [0.5 * (w2.a[0] + w2.b[0]), 0.5 * (w2.a[1] + w2.b[1])];
                            let near = crate::norm(m1[0] - m2[0], m1[1] - m2[1]) - 0.5 * (l1 + l2);
                            let facing = side(img, w2.a, n2) > 1e-6
                                && (side(w2.a, w1.a, n1) > 1e-6 || side(w2.b, w1.a, n1) > 1e-6)
                                && (side(w1.a, w2.a, n2) > 1e-6 || side(w1.b, w2.a, n2) > 1e-6);
                            if k2 != k1 && near <= PAIR_RADIUS_M && facing {
                                out.push((k1, k2));
                            }
                        }
                    }
                }
                out
            })
            .collect()
    }

    /// Every ray that two walls in turn reflect from the site `site` (`[x, y, height above
    /// the terrain]`) to the map's pixels (module docs). `walls` as
    /// [`RayScene::wall_rays`] takes them (checked there). Pairs run in parallel.
    pub fn wall_rays2(&self, site: [f64; 3], walls: &[Wall]) -> Result<Vec<WallRay>> {
        self.check()?;
        let zs = self.terrain_at(site[0], site[1]) + site[2];
        let pairs = self.wall_pairs(site, zs, walls);
        let sorted = self.x_m.windows(2).all(|w| w[0] < w[1]);
        let bounds = self.bounds();
        Ok(pairs
            .par_iter()
            .flat_map_iter(|&(k1, k2)| {
                let mut sight = self.sight(bounds);
                let (w1, w2) = (&walls[k1], &walls[k2]);
                let (n1, _) = normal(w1).unwrap_or(([0.0, 0.0], 0.0));
                let (n2, _) = normal(w2).unwrap_or(([0.0, 0.0], 0.0));
                let i1 = mirror([site[0], site[1]], w1.a, n1);
                let i2 = mirror(i1, w2.a, n2);
                let (f0, f1) = (mirror(w1.a, w2.a, n2), mirror(w1.b, w2.a, n2));
                let x = self.x_m;
                let rows = self.y_m.iter().enumerate().filter_map(move |(i, &y)| {
                    let [c0, c1] = wedge(i2, w2.a, w2.b, y);
                    let [c2, c3] = wedge(i2, f0, f1, y);
                    let front = (n2[0], -w2.a[0] * n2[0] + (y - w2.a[1]) * n2[1]);
                    let (lo, hi) = interval(&[c0, c1, c2, c3, front]);
                    if lo.is_nan() || hi.is_nan() || lo > hi {
                        return None;
                    }
                    let (j0, j1) = columns(x, lo, hi, sorted);
                    (j0 < j1).then_some((i, j0, j1))
                });
                rows.flat_map(|(i, j0, j1)| (j0..j1).map(move |j| (i, j)))
                    .filter_map(|(i, j)| {
                        self.ray2(site, zs, (w1, n1, i1), (w2, n2, i2), i, j, &mut sight)
                    })
                    .collect::<Vec<_>>()
            })
            .collect())
    }

    /// The ray the walls `w1` then `w2` reflect from the site to pixel `(i, j)`, if any.
    #[allow(clippy::too_many_arguments)]
    // Long: the two images, both reflection points and the three legs' checks of one double bounce,
    // each using the one before.
    fn ray2(
        &self,
        site: [f64; 3],
        zs: f64,
        (w1, n1, i1): (&Wall, [f64; 2], [f64; 2]),
        (w2, n2, i2): (&Wall, [f64; 2], [f64; 2]),
        i: usize,
        j: usize,
        sight: &mut Sight,
    ) -> Option<WallRay> {
        let q = [self.x_m[j], self.y_m[i]];
        let s = [site[0], site[1]];
        let on = |w: &Wall, p: [f64; 2]| {
            let d = [w.b[0] - w.a[0], w.b[1] - w.a[1]];
            let t = ((p[0] - w.a[0]) * d[0] + (p[1] - w.a[1]) * d[1])
                / (d[0] * d[0] + d[1] * d[1]).max(1e-18);
            (0.0..=1.0).contains(&t)
        };
        let (di, dq) = (side(i1, w2.a, n2), side(q, w2.a, n2));
        if di <= 1e-6 || dq <= 1e-6 {
            return None;
        }
        let u = di / (di + dq);
        let p2 = [i2[0] + u * (q[0] - i2[0]), i2[1] + u * (q[1] - i2[1])];
        let (ds, dp) = (side(s, w1.a, n1), side(p2, w1.a, n1));
        if !on(w2, p2) || ds <= 1e-6 || dp <= 1e-6 {
            return None;
        }
        let v = ds / (ds + dp);
        let p1 = [i1[0] + v * (p2[0] - i1[0]), i1[1] + v * (p2[1] - i1[1])];
        if !on(w1, p1) {
            return None;
        }
        let h1 = crate::norm(p1[0] - s[0], p1[1] - s[1]);
        let h2 = crate::norm(p2[0] - p1[0], p2[1] - p1[1]);
        let h3 = crate::norm(q[0] - p2[0], q[1] - p2[1]);
        let rho = h1 + h2 + h3;
        let zq = self.receiver_height(q);
        let length = (rho * rho + (zq - zs).powi(2)).sqrt().max(1e-3);
        if length > MAX_LENGTH_M {
            return None;
        }
        let z1 = zs + (zq - zs) * h1 / rho;
        let z2 = zs + (zq - zs) * (h1 + h2) / rho;
        for (w, p, z) in [(w1, p1, z1), (w2, p2, z2)] {
            let zt = self.terrain_at(p[0], p[1]);
            if z < zt + w.base || z > zt + w.top {
                return None;
            }
        }
        // The legs, each stopping LEG_GAP_M short of the walls it touches.
        let leg = |sight: &mut Sight,
                   a: [f64; 2],
                   za: f64,
                   b: [f64; 2],
                   zb: f64,
                   len: f64,
                   ga: bool,
                   gb: bool| {
            if len <= 2.0 * LEG_GAP_M {
                return true;
            }
            let (fa, fb) = (
                if ga { LEG_GAP_M / len } else { 0.0 },
                if gb { 1.0 - LEG_GAP_M / len } else { 1.0 },
            );
            let at = |f: f64| [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            sight.clear(at(fa), za + fa * (zb - za), at(fb), za + fb * (zb - za))
        };
        if !(leg(sight, s, zs, p1, z1, h1, false, true)
            && leg(sight, p1, z1, p2, z2, h2, true, true)
            && leg(sight, p2, z2, q, zq, h3, true, false))
        {
            return None;
        }
        let unit = |a: [f64; 2], za: f64, b: [f64; 2], zb: f64| {
            let k = [b[0] - a[0], b[1] - a[1], zb - za];
            let n = (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]).sqrt().max(1e-9);
            k.map(|v| v / n)
        };
        let r = wall_reflectance(w1.eps, unit(s, zs, p1, z1), n1, self.polarization)
            * wall_reflectance(w2.eps, unit(p1, z1, p2, z2), n2, self.polarization);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        Some(WallRay {
            pixel: i * self.x_m.len() + j,
            az_deg: (p1[1] - s[1]).atan2(p1[0] - s[0]).to_degrees(),
            el_deg: (z1 - zs).atan2(h1).to_degrees(),
            factor: r * (lambda / (4.0 * std::f64::consts::PI * length)).powi(2),
            length_m: length,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::propagation::rays::RayPolarization;
    use num_complex::Complex64;

    #[test]
    fn two_parallel_walls_are_the_double_image() {
        // A street: wall A along y = 10 facing south (-y), wall B along y = -10 facing north;
        // the site at (0, 0, 10), the pixel at (100, 4) at 10 m. Bounce on A then B: the
        // image in A is (0, 20), its image in B is (0, -40): the unfolded length is the
        // distance from (0, -40) to (100, 4); the reflection points by hand.
        let eps = Complex64::new(5.24, -0.3);
        let walls = [
            Wall {
                a: [-50.0, 10.0],
                b: [150.0, 10.0],
                base: 0.0,
                top: 30.0,
                eps,
            },
            Wall {
                a: [150.0, -10.0],
                b: [-50.0, -10.0],
                base: 0.0,
                top: 30.0,
                eps,
            },
        ];
        let (x, y) = ([100.0], [4.0]);
        let scene = RayScene::bare(&x, &y, 10.0, 4.9e9);
        let rays = scene.wall_rays2([0.0, 0.0, 10.0], &walls).unwrap();
        // A then B, and B then A (images (0, -20), then (0, 40)).
        assert_eq!(rays.len(), 2, "{rays:?}");
        let d_ab = 100.0f64.hypot(44.0);
        let d_ba = 100.0f64.hypot(36.0);
        let mut lengths: Vec<f64> = rays.iter().map(|r| r.length_m).collect();
        lengths.sort_by(f64::total_cmp);
        assert!((lengths[0] - d_ba).abs() < 1e-9 && (lengths[1] - d_ab).abs() < 1e-9);
        // A then B: first point on A where the line from (0, -40) to (100, 4) ... unfolded:
        // crosses y = -10 at x = 100 * 30 / 44 (the point on B), and the line from (0, 20) to
        // it crosses y = 10 at x = (100 * 30 / 44) / 3 (on A).
        let ab = rays
            .iter()
            .find(|r| (r.length_m - d_ab).abs() < 1e-9)
            .unwrap();
        let xb = 100.0 * 30.0 / 44.0;
        let xa = xb / 3.0;
        assert!((ab.az_deg - (10.0f64).atan2(xa).to_degrees()).abs() < 1e-9);
        let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
        let k1 = [xa, 10.0, 0.0];
        let k2 = [xb - xa, -20.0, 0.0];
        let unit = |k: [f64; 3]| {
            let n = (k[0] * k[0] + k[1] * k[1]).sqrt();
            [k[0] / n, k[1] / n, 0.0]
        };
        let r = wall_reflectance(eps, unit(k1), [0.0, -1.0], RayPolarization::V)
            * wall_reflectance(eps, unit(k2), [0.0, 1.0], RayPolarization::V);
        let want = r * (lam / (4.0 * std::f64::consts::PI * d_ab)).powi(2);
        assert!((ab.factor / want - 1.0).abs() < 1e-9);
    }
}
