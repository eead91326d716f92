//! Where a path's ground reflection meets the ground: the line fitted to the terrain over the
//! first Fresnel zone, the specular point on it, and the terrain's roughness about it.

use super::*;

/// Where a path's ground reflection meets the ground ([`RayScene::path`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Specular {
    /// Distance along the ground from the site, m, and the fitted ground line's height there.
    pub(super) sb: f64,
    pub(super) zb: f64,
    /// The reflected ray's length (m) and grazing angle (rad) on the fitted line.
    pub(super) d2: f64,
    pub(super) psi: f64,
    /// The terrain's standard deviation about the fitted line, m, and the fit's half-length.
    pub(super) sigma: f64,
    pub(super) half: f64,
}

/// The straight line `z = z0 + slope (s - s0)` fitted by least squares to `ground(s)` at 17
/// points evenly over `s0 - a .. s0 + a`, and the standard deviation of the ground about it:
/// `(z0, slope, sigma)` (a fixed count: the fit moves smoothly with the window).
pub(super) fn fit_line(ground: &impl Fn(f64) -> f64, s0: f64, a: f64) -> (f64, f64, f64) {
    const N: usize = 17;
    let mut pts = [(0.0, 0.0); N];
    let (mut sx, mut sz, mut sxx, mut sxz) = (0.0, 0.0, 0.0, 0.0);
    for (i, p) in pts.iter_mut().enumerate() {
        let u = -a + 2.0 * a * i as f64 / (N - 1) as f64;
        let z = ground(s0 + u);
        *p = (u, z);
        sx += u;
        sz += z;
        sxx += u * u;
        sxz += u * z;
    }
    let m = N as f64;
    let den = m * sxx - sx * sx;
    let slope = if den.abs() > 1e-12 {
        (m * sxz - sx * sz) / den
    } else {
        0.0
    };
    let z0 = (sz - slope * sx) / m;
    let var = pts
        .iter()
        .map(|&(u, z)| (z - z0 - slope * u).powi(2))
        .sum::<f64>()
        / m;
    (z0, slope, var.sqrt())
}

impl RayScene<'_> {
    /// Half the terrain's spacing, m (1 without a terrain).
    pub(super) fn half_spacing(&self) -> f64 {
        self.terrain.as_ref().map_or(1.0, |t| 0.5 * t.spacing())
    }

    /// The specular point of the ground reflection from the transmitter `tx` (`[x, y, height
    /// above the terrain]`, at `zs` m above sea level) to the pixel centre `q` (receiver at
    /// `zq`), on the ground line of the path's vertical plane; None where there is none.
    ///
    /// Start from the flat-ground point of the heights above the terrain at both ends, then
    /// reflect the site in the straight line fitted to the terrain over the first Fresnel
    /// zone round the point (least squares: the reflecting area, not one facet of the DEM),
    /// and move the point to where the image's line to the receiver crosses it; four rounds.
    /// The terrain's standard deviation about that line is the roughness.
    pub(super) fn specular(
        &self,
        tx: [f64; 3],
        q: [f64; 2],
        zs: f64,
        zq: f64,
        lambda: f64,
    ) -> Option<Specular> {
        let [xs, ys, hs] = tx;
        let (ex, ey) = (q[0] - xs, q[1] - ys);
        let rho = crate::norm(ex, ey);
        let (ux, uy) = (ex / rho, ey / rho);
        let ground_at = |s: f64| {
            let (x, y) = (xs + ux * s, ys + uy * s);
            self.terrain_at(x, y)
        };
        let h = self.half_spacing();
        let (hs_g, hq_g) = (hs, zq - self.terrain_at(q[0], q[1]));
        if hq_g <= 0.0 {
            return None;
        }
        let mut sb = rho * hs_g / (hs_g + hq_g);
        let mut psi = ((hs_g + hq_g) / rho).atan();
        let (mut image, mut line) = ((0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0));
        for _ in 0..4 {
            let a = self.fresnel_half_length(sb, rho - sb, zs, zq, psi, lambda, h);
            let (zb, slope, sigma) = if self.terrain.is_some() {
                fit_line(&ground_at, sb, a)
            } else {
                (0.0, 0.0, 0.0)
            };
            let norm = (1.0 + slope * slope).sqrt();
            let (nx, nz) = (-slope / norm, 1.0 / norm);
            let dist_t = nx * (0.0 - sb) + nz * (zs - zb);
            let dist_r = nx * (rho - sb) + nz * (zq - zb);
            if dist_t <= 0.0 || dist_r <= 0.0 {
                return None;
            }
            image = (-2.0 * dist_t * nx, zs - 2.0 * dist_t * nz);
            let t = dist_t / (dist_t + dist_r);
            let s_new = image.0 + t * (rho - image.0);
            let d2 = ((rho - image.0).powi(2) + (zq - image.1).powi(2)).sqrt();
            psi = ((dist_t + dist_r) / d2).clamp(-1.0, 1.0).asin();
            line = (dist_t, dist_r, zb, sigma, a);
            if !(s_new > 0.0 && s_new < rho) {
                return None;
            }
            sb = s_new;
        }
        let (dist_t, dist_r, zb, sigma, half) = line;
        let d2 = ((rho - image.0).powi(2) + (zq - image.1).powi(2)).sqrt();
        Some(Specular {
            sb,
            zb,
            d2,
            psi: ((dist_t + dist_r) / d2).clamp(-1.0, 1.0).asin(),
            sigma,
            half,
        })
    }

    /// Half the length (m) along the path of the first Fresnel zone's footprint on the ground
    /// round a specular point `s1`, `s2` m (horizontally) from the ends at `zs`, `zq`, seen at
    /// grazing angle `psi`: the zone's radius `sqrt(lambda d1 d2 / (d1 + d2))` over `sin psi`,
    /// at least the terrain's spacing `2 h` (what a DEM does not resolve is not smooth: the
    /// window always spans its neighbouring cells) and at most the shorter leg.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn fresnel_half_length(
        &self,
        s1: f64,
        s2: f64,
        zs: f64,
        zq: f64,
        psi: f64,
        lambda: f64,
        h: f64,
    ) -> f64 {
        let (d1, d2) = (crate::norm(s1, zs), crate::norm(s2, zq));
        let r = (lambda * d1 * d2 / (d1 + d2).max(1e-9)).sqrt();
        (r / psi.sin().max(1e-3)).max(2.0 * h).min(s1.min(s2))
    }
}
