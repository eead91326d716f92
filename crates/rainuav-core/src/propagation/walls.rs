//! First-order reflections off building walls (docs/physics.md section 12), by the image method.
//!
//! A wall is a footprint edge extruded from `base` to `top` metres above the terrain, its
//! outward normal on the right of `a -> b` (outer rings counter-clockwise, holes clockwise).
//! For a site in front of the wall, its image in the wall's vertical plane sees the pixels
//! through the wall: per row of the map, the pixels inside the wedge from the image through
//! the wall's ends and in front of the wall form one interval of columns (three linear
//! conditions), so a wall visits only the pixels it can light. Each such pixel's specular
//! point is where the line from the image to the receiver crosses the wall; the ray exists
//! where that point lies between the wall's base and top and both legs clear the profile
//! (terrain and buildings), or where they pass over roofs at a loss the direct ray's method
//! finds on the unfolded path ([`roofs`]).
//!
//! The coefficient is the Fresnel coefficient of the wall's material (ITU-R P.2040:
//! `eps_c = eps_r - j sigma / (omega eps_0)`): with `theta` the angle from the wall's normal
//! and `S = sqrt(eps_c - sin^2 theta)`, `Gamma_perp = (cos theta - S) / (cos theta + S)`
//! for the field perpendicular to the plane of incidence and `Gamma_par = (eps_c cos theta -
//! S) / (eps_c cos theta + S)` for the field in it. The site's polarisation (vertical:
//! theta-hat of the incident direction; horizontal: phi-hat) is split between the two, and
//! `|Gamma|^2` added by parts. Each ray's power is `|Gamma|^2 (lambda / (4 pi d))^2` per mW
//! and unit gain, `d` the length of the unfolded path; the caller applies the antenna gain
//! toward the specular point (the departure direction each ray carries). Powers add
//! incoherently.

use num_complex::Complex64;
use rayon::prelude::*;

use crate::error::{CoreError, Result};
use crate::propagation::rays::{RayPolarization, RayScene};
use crate::propagation::sight::Sight;

mod roofs;
pub use roofs::{MAX_ROOF_LOSS_DB, ROOF_LEG_M};

/// A wall: a footprint edge `a -> b` (outward normal on its right), from `base` to `top` m
/// above the terrain, of complex relative permittivity `eps` (`eps_r - j sigma / (omega
/// eps_0)`, imaginary part <= 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    /// First end `[x, y]`, m.
    pub a: [f64; 2],
    /// Second end `[x, y]`, m.
    pub b: [f64; 2],
    /// Bottom of the wall above the terrain, m.
    pub base: f64,
    /// Top of the wall above the terrain, m.
    pub top: f64,
    /// The material's complex relative permittivity.
    pub eps: Complex64,
}

/// One ray reflected by one wall to one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallRay {
    /// The pixel, row-major (`i W + j`).
    pub pixel: usize,
    /// Departure azimuth toward the specular point, degrees from east toward north.
    pub az_deg: f64,
    /// Departure elevation toward the specular point (over the first leg's highest edge where
    /// the ray passes over roofs), degrees.
    pub el_deg: f64,
    /// Received power per mW radiated, isotropic antennas: `|Gamma|^2 (lambda / (4 pi d))^2`,
    /// times the diffraction loss of a ray over roofs ([`roofs`]).
    pub factor: f64,
    /// Length of the unfolded path, m.
    pub length_m: f64,
}

/// How far (m) each leg's visibility check stops short of the specular point: the wall's own
/// building is not in the way of a ray that touches it.
pub(crate) const LEG_GAP_M: f64 = 0.05;

/// `|Gamma|^2` of a wall of permittivity `eps` for an incident unit direction `k` and unit
/// horizontal normal `n`, the field split between the two polarisations by `pol`.
pub fn wall_reflectance(eps: Complex64, k: [f64; 3], n: [f64; 2], pol: RayPolarization) -> f64 {
    let cos_t = (k[0] * n[0] + k[1] * n[1]).abs().min(1.0);
    let sin2 = 1.0 - cos_t * cos_t;
    let root = (eps - sin2).sqrt();
    let perp = ((cos_t - root) / (cos_t + root)).norm_sqr();
    let par = ((eps * cos_t - root) / (eps * cos_t + root)).norm_sqr();
    // The perpendicular direction k x n (n horizontal), and the site's field direction.
    let s = [-k[2] * n[1], k[2] * n[0], k[0] * n[1] - k[1] * n[0]];
    let s_len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    let kh = crate::norm(k[0], k[1]);
    if s_len < 1e-12 || kh < 1e-12 {
        return 0.5 * (perp + par);
    }
    let e = match pol {
        RayPolarization::H => [-k[1] / kh, k[0] / kh, 0.0],
        RayPolarization::V => [k[0] * k[2] / kh, k[1] * k[2] / kh, -kh],
    };
    let f_perp = ((e[0] * s[0] + e[1] * s[1] + e[2] * s[2]) / s_len).powi(2);
    perp * f_perp + par * (1.0 - f_perp)
}

/// The columns `j0..j1` of the pixel centres `x` within `lo..=hi` (all of them where `x` is not
/// sorted: the caller's tests then decide pixel by pixel).
pub(crate) fn columns(x: &[f64], lo: f64, hi: f64, sorted: bool) -> (usize, usize) {
    if sorted {
        (
            x.partition_point(|&v| v < lo),
            x.partition_point(|&v| v <= hi),
        )
    } else {
        (0, x.len())
    }
}

/// The interval of `x` where every `alpha x + beta >= 0` holds (empty: `lo > hi`).
pub(crate) fn interval(conds: &[(f64, f64)]) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for &(alpha, beta) in conds {
        if alpha.abs() < 1e-15 {
            if beta < 0.0 {
                return (1.0, 0.0);
            }
        } else if alpha > 0.0 {
            lo = lo.max(-beta / alpha);
        } else {
            hi = hi.min(-beta / alpha);
        }
    }
    (lo, hi)
}

impl RayScene<'_> {
    /// Every ray that `walls` reflect from the site `site` (`[x, y, height above the
    /// terrain]`) to the map's pixels, in order of wall then pixel. Walls run in parallel.
    pub fn wall_rays(&self, site: [f64; 3], walls: &[Wall]) -> Result<Vec<WallRay>> {
        self.check()?;
        for w in walls {
            let ok = w.a.iter().chain(&w.b).all(|v| v.is_finite())
                && w.base.is_finite()
                && w.top.is_finite()
                && 0.0 <= w.base
                && w.base <= w.top
                && w.eps.re.is_finite()
                && w.eps.im.is_finite()
                && w.eps.re >= 1.0
                && w.eps.im <= 0.0;
            if !ok {
                return Err(CoreError::invalid(
                    "walls",
                    "must be finite, 0 <= base <= top, permittivity with Re >= 1, Im <= 0",
                    format!("{w:?}"),
                ));
            }
        }
        if !site.iter().all(|v| v.is_finite()) || site[2] <= 0.0 {
            return Err(CoreError::invalid(
                "sites",
                "must be finite, above the ground",
                format!("{site:?}"),
            ));
        }
        let sorted = self.x_m.windows(2).all(|w| w[0] < w[1]);
        let zs = self.terrain_at(site[0], site[1]) + site[2];
        let (zq_lo, zq_hi) = self
            .y_m
            .iter()
            .flat_map(|&y| self.x_m.iter().map(move |&x| self.receiver_height([x, y])))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
                (a.min(z), b.max(z))
            });
        let plan: Vec<bool> = walls
            .iter()
            .map(|w| self.wall_lit(site, zs, (zq_lo, zq_hi), w))
            .collect();
        // Refuse before allocating: at most one ray a visited pixel.
        let visits: usize = walls
            .iter()
            .zip(&plan)
            .filter(|(_, lit)| **lit)
            .map(|(w, _)| {
                self.wall_rows(site, w, sorted)
                    .map(|(_, a, b)| b - a)
                    .sum::<usize>()
            })
            .sum();
        crate::memory::check_memory_for(
            "walls",
            "use fewer buildings or a smaller map",
            visits * size_of::<WallRay>(),
        )?;
        let bounds = self.bounds();
        Ok(walls
            .par_iter()
            .zip(plan.par_iter())
            .filter(|(_, lit)| **lit)
            .flat_map_iter(|(w, _)| {
                let mut sight = self.sight(bounds);
                self.wall_rows(site, w, sorted)
                    .flat_map(|(i, j0, j1)| (j0..j1).map(move |j| (i, j)))
                    .filter_map(|(i, j)| self.wall_ray(site, zs, w, i, j, &mut sight))
                    .collect::<Vec<_>>()
            })
            .collect())
    }

    /// Whether a wall can reflect anything from the site at all: the site in front of it,
    /// and the wall's heights within those the rays can meet.
    pub(crate) fn wall_lit(
        &self,
        site: [f64; 3],
        zs: f64,
        (zq_lo, zq_hi): (f64, f64),
        w: &Wall,
    ) -> bool {
        let Some((n, _)) = normal(w) else {
            return false;
        };
        let ds = (site[0] - w.a[0]) * n[0] + (site[1] - w.a[1]) * n[1];
        if ds <= 1e-6 {
            return false;
        }
        let mid = [0.5 * (w.a[0] + w.b[0]), 0.5 * (w.a[1] + w.b[1])];
        let ground = [w.a, w.b, mid].map(|p| self.terrain_at(p[0], p[1]));
        let lo = ground.iter().copied().fold(f64::INFINITY, f64::min) + w.base;
        let hi = ground.iter().copied().fold(f64::NEG_INFINITY, f64::max) + w.top;
        // The specular point's height lies between the site's and the receiver's.
        hi >= zs.min(zq_lo) - 1.0 && lo <= zs.max(zq_hi) + 1.0
    }

    /// The pixels a wall can light from the site: per row `i`, the columns `j0..j1` inside
    /// the wedge from the site's image through the wall's ends and in front of the wall.
    fn wall_rows<'s>(
        &'s self,
        site: [f64; 3],
        w: &Wall,
        sorted: bool,
    ) -> impl Iterator<Item = (usize, usize, usize)> + 's {
        let (n, _) = normal(w).unwrap_or(([0.0, 0.0], 0.0));
        let ds = (site[0] - w.a[0]) * n[0] + (site[1] - w.a[1]) * n[1];
        let img = [site[0] - 2.0 * ds * n[0], site[1] - 2.0 * ds * n[1]];
        let (u0, u1) = (
            [w.a[0] - img[0], w.a[1] - img[1]],
            [w.b[0] - img[0], w.b[1] - img[1]],
        );
        let sgn = (u0[0] * u1[1] - u0[1] * u1[0]).signum();
        let a = w.a;
        let x = self.x_m;
        self.y_m.iter().enumerate().filter_map(move |(i, &y)| {
            let conds = [
                // sgn cross(u0, q - img) >= 0
                (-sgn * u0[1], sgn * (u0[0] * (y - img[1]) + u0[1] * img[0])),
                // sgn cross(q - img, u1) >= 0
                (sgn * u1[1], sgn * (-img[0] * u1[1] - (y - img[1]) * u1[0])),
                // (q - a) . n >= 0
                (n[0], -a[0] * n[0] + (y - a[1]) * n[1]),
            ];
            let (lo, hi) = interval(&conds);
            if lo.is_nan() || hi.is_nan() || lo > hi || n == [0.0, 0.0] {
                return None;
            }
            let (j0, j1) = columns(x, lo, hi, sorted);
            (j0 < j1).then_some((i, j0, j1))
        })
    }

    /// The ray the wall reflects from the site to pixel `(i, j)`, if there is one.
    fn wall_ray(
        &self,
        site: [f64; 3],
        zs: f64,
        w: &Wall,
        i: usize,
        j: usize,
        sight: &mut Sight,
    ) -> Option<WallRay> {
        let (n, len) = normal(w)?;
        let q = [self.x_m[j], self.y_m[i]];
        let ds = (site[0] - w.a[0]) * n[0] + (site[1] - w.a[1]) * n[1];
        let dq = (q[0] - w.a[0]) * n[0] + (q[1] - w.a[1]) * n[1];
        if dq <= 1e-6 {
            return None;
        }
        let img = [site[0] - 2.0 * ds * n[0], site[1] - 2.0 * ds * n[1]];
        let u = ds / (ds + dq);
        let p = [img[0] + u * (q[0] - img[0]), img[1] + u * (q[1] - img[1])];
        let along =
            ((p[0] - w.a[0]) * (w.b[0] - w.a[0]) + (p[1] - w.a[1]) * (w.b[1] - w.a[1])) / len;
        if !(0.0..=len).contains(&along) {
            return None;
        }
        let zq = self.receiver_height(q);
        let zp = zs + (zq - zs) * u;
        let zt = self.terrain_at(p[0], p[1]);
        if zp < zt + w.base || zp > zt + w.top {
            return None;
        }
        let rho = crate::norm(q[0] - img[0], q[1] - img[1]);
        let (rho1, rho2) = (u * rho, (1.0 - u) * rho);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        let s = [site[0], site[1]];
        let seen = leg_seen(sight, s, zs, p, zp, rho1) && leg_seen(sight, q, zq, p, zp, rho2);
        let (loss_db, el) = if seen {
            (0.0, (zp - zs).atan2(rho1))
        } else if self.terrain_at(q[0], q[1]) + self.obstacle_at(q[0], q[1]) >= zq {
            // A receiver inside a building: its own roof is no edge to diffract over.
            return None;
        } else {
            self.over_roofs(sight, (s, zs, rho1), (p, zp), (q, zq, rho2), lambda)?
        };
        let length = (rho * rho + (zq - zs).powi(2)).sqrt().max(1e-3);
        let k = [p[0] - site[0], p[1] - site[1], zp - zs];
        let k_len = (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]).sqrt().max(1e-9);
        let k = k.map(|v| v / k_len);
        let r2 = wall_reflectance(w.eps, k, n, self.polarization);
        let free = (lambda / (4.0 * std::f64::consts::PI * length)).powi(2);
        Some(WallRay {
            pixel: i * self.x_m.len() + j,
            az_deg: (p[1] - site[1]).atan2(p[0] - site[0]).to_degrees(),
            el_deg: el.to_degrees(),
            factor: r2 * free * 10f64.powf(-0.1 * loss_db),
            length_m: length,
        })
    }
}

/// Whether the straight leg from `(from, z_from)` to the specular point `(p, zp)`, `rho`
/// apart horizontally, clears the profile (stopping [`LEG_GAP_M`] short of the wall):
/// [`Sight::clear`] on the leg.
fn leg_seen(
    sight: &mut Sight,
    from: [f64; 2],
    z_from: f64,
    p: [f64; 2],
    zp: f64,
    rho: f64,
) -> bool {
    if rho <= LEG_GAP_M {
        return true;
    }
    let f = 1.0 - LEG_GAP_M / rho;
    let end = [
        from[0] + f * (p[0] - from[0]),
        from[1] + f * (p[1] - from[1]),
    ];
    sight.clear(from, z_from, end, z_from + (zp - z_from) * f)
}

/// The wall's outward unit normal (right of `a -> b`) and length; None for a point.
pub(crate) fn normal(w: &Wall) -> Option<([f64; 2], f64)> {
    let (dx, dy) = (w.b[0] - w.a[0], w.b[1] - w.a[1]);
    let len = crate::norm(dx, dy);
    (len > 1e-9).then(|| ([dy / len, -dx / len], len))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene<'a>(x: &'a [f64], y: &'a [f64]) -> RayScene<'a> {
        RayScene::bare(x, y, 30.0, 3.5e9)
    }

    #[test]
    fn one_wall_is_the_image_method() {
        // A wall along x = 100 (normal toward -x), site at the origin 30 m up, receiver at
        // (20, 50) 30 m up: the image at (200, 0), the specular point where the image's line
        // to the receiver crosses x = 100, d = |(-180, 50)|; horizontal incidence on a
        // vertical wall, so a vertical field is perpendicular to the plane of incidence.
        let (x, y) = ([20.0], [50.0]);
        let s = scene(&x, &y);
        let eps = Complex64::new(5.24, -1.0);
        let wall = Wall {
            a: [100.0, 200.0],
            b: [100.0, -100.0],
            base: 0.0,
            top: 60.0,
            eps,
        };
        let rays = s.wall_rays([0.0, 0.0, 30.0], &[wall]).unwrap();
        assert_eq!(rays.len(), 1);
        let d = 180.0_f64.hypot(50.0);
        let cos_t = 180.0 / d;
        let root = (eps - (1.0 - cos_t * cos_t)).sqrt();
        let g = ((cos_t - root) / (cos_t + root)).norm_sqr();
        let lam = crate::SPEED_OF_LIGHT_M_S / 3.5e9;
        let want = g * (lam / (4.0 * std::f64::consts::PI * d)).powi(2);
        assert!((rays[0].factor / want - 1.0).abs() < 1e-12);
        assert!((rays[0].length_m - d).abs() < 1e-9);
        let y_spec: f64 = 50.0 * 100.0 / 180.0;
        assert!((rays[0].az_deg - y_spec.atan2(100.0).to_degrees()).abs() < 1e-9);
        // Facing away from the site (reversed edge), or too low to reach: no ray.
        let back = Wall {
            a: wall.b,
            b: wall.a,
            ..wall
        };
        assert!(s.wall_rays([0.0, 0.0, 30.0], &[back]).unwrap().is_empty());
        let low = Wall { top: 20.0, ..wall };
        assert!(s.wall_rays([0.0, 0.0, 30.0], &[low]).unwrap().is_empty());
    }

    #[test]
    fn reflectance_limits() {
        // Grazing: |Gamma| = 1 either way; a metal-like wall reflects everything.
        let eps = Complex64::new(5.24, -0.5);
        let r = wall_reflectance(eps, [0.0, 1.0, 0.0], [1.0, 0.0], RayPolarization::H);
        assert!((r - 1.0).abs() < 1e-9);
        let metal = Complex64::new(1.0, -1e9);
        let k = [0.6, 0.8, 0.0];
        for pol in [RayPolarization::H, RayPolarization::V] {
            let r = wall_reflectance(metal, k, [-1.0, 0.0], pol);
            assert!((r - 1.0).abs() < 1e-3, "{r}");
        }
    }
}
