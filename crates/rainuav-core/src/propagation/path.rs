//! The geometry of one site-pixel path (docs/physics.md sections 8 and 12): the profile of
//! the terrain and the buildings along its ground line, the direct ray's diffraction loss (the
//! principal edge decides: Bullington with its correction on terrain, Deygout's isolated edges
//! on buildings), and the ground reflection's specular point on the line fitted over the first
//! Fresnel zone, its roughness and the fading of its legs. The rest of the ray engine (antenna
//! gains, powers, rain, maps) is in [`crate::propagation::rays`].

use crate::propagation::diffraction::knife_edge_loss_db;
use crate::propagation::rays::{PathGeometry, RayGround, RayScene, db_to_amplitude, ray_lengths};
use crate::propagation::sight::Sight;

impl RayScene<'_> {
    /// The profile of the surface (terrain + obstacles, m above sea level) along the ground
    /// line `a -> b`, as `(distance from a, height)` strictly between the ends, in order of
    /// distance: the terrain and the obstacle raster every half of their finest spacing, and
    /// each building where the line enters and leaves its footprint. Written into `out`
    /// (cleared first).
    pub fn profile(&self, a: [f64; 2], b: [f64; 2], out: &mut Vec<(f64, f64)>) {
        let mut sight = self.sight(self.bounds());
        self.profile_over(a, b, |_, _| f64::NEG_INFINITY, &mut sight);
        std::mem::swap(out, &mut sight.prof);
    }

    /// [`RayScene::profile`] into `sight.prof`, leaving out the buildings whose roof stays
    /// below `floor(lo, hi)` (m above sea level) wherever the line `a + t (b - a)`,
    /// `t in lo..=hi`, passes over their footprint's box: those the caller has shown cannot
    /// change its answer ([`crate::propagation::obstacles::Prisms::near_segment_over`]).
    // Long: the terrain's samples, the obstacle raster and the faces of the footprints the line
    // crosses are read in one walk along the line.
    pub fn profile_over(
        &self,
        a: [f64; 2],
        b: [f64; 2],
        floor: impl Fn(f64, f64) -> f64,
        sight: &mut Sight,
    ) {
        let out = &mut sight.prof;
        out.clear();
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let rho = crate::norm(dx, dy);
        if rho < 1e-9 {
            return;
        }
        // The samples: the terrain and the obstacle raster (the buildings' roofs over them
        // below), and the terrain alone on the terrain's own grid.
        let ground = &mut sight.ground;
        ground.clear();
        let spacing = [self.terrain.as_ref(), self.heights.as_ref()]
            .into_iter()
            .flatten()
            .map(|r| r.spacing())
            .fold(f64::INFINITY, f64::min);
        let n = if spacing.is_finite() {
            ((rho / (0.5 * spacing)).ceil() as usize).max(1)
        } else {
            0
        };
        for k in 1..n {
            let t = k as f64 / n as f64;
            let (x, y) = (a[0] + t * dx, a[1] + t * dy);
            let z = self.terrain_at(x, y);
            if self.terrain.is_some() {
                ground.push((t * rho, z));
            }
            out.push((
                t * rho,
                z + self.heights.as_ref().map_or(0.0, |r| r.cell(x, y)),
            ));
        }
        if let Some(tr) = &self.terrain
            && ((rho / (0.5 * tr.spacing())).ceil() as usize).max(1) != n
        {
            let m = ((rho / (0.5 * tr.spacing())).ceil() as usize).max(1);
            ground.clear();
            ground.extend((1..m).map(|k| {
                let t = k as f64 / m as f64;
                (t * rho, self.terrain_at(a[0] + t * dx, a[1] + t * dy))
            }));
        }
        let before = out.len();
        if let Some(prisms) = self.prisms {
            // Each face a building's footprint crosses, read just inside it at its roof (a roof
            // is flat, so its faces are where the extremes of the construction lie); the
            // samples within its footprint (between crossings, inside at the middle) rise to
            // its roof.
            let eps = 1e-9_f64.max(1e-6 / rho);
            let (near, ts) = (&mut sight.near, &mut sight.ts);
            prisms.near_segment_over(a, b, floor, sight.terrain_top, near);
            for &k in near.iter() {
                let (k, top) = (k as usize, prisms.items()[k as usize].top);
                ts.clear();
                prisms.crossings(k, a, b, ts);
                for &t0 in ts.iter() {
                    for t in [t0 - eps, t0 + eps] {
                        let (x, y) = (a[0] + t * dx, a[1] + t * dy);
                        if t > 0.0 && t < 1.0 && prisms.contains(k, x, y) {
                            out.push((t * rho, self.terrain_at(x, y) + top));
                        }
                    }
                }
                if n < 2 {
                    continue;
                }
                ts.sort_by(f64::total_cmp);
                ts.insert(0, 0.0);
                ts.push(1.0);
                for w in ts.windows(2) {
                    let (t0, t1) = (w[0], w[1]);
                    let mid = 0.5 * (t0 + t1);
                    if t1 <= t0 || !prisms.contains(k, a[0] + mid * dx, a[1] + mid * dy) {
                        continue;
                    }
                    // The samples i / n strictly between t0 and t1 (i in 1..n).
                    let (lo, hi) = (
                        (t0 * n as f64) as usize + 1,
                        (t1 * n as f64).ceil() as usize,
                    );
                    for i in lo..hi.min(n) {
                        let t = i as f64 / n as f64;
                        if t > t0 && t < t1 {
                            let (x, y) = (a[0] + t * dx, a[1] + t * dy);
                            let roof = self.terrain_at(x, y) + top;
                            out[i - 1].1 = out[i - 1].1.max(roof);
                        }
                    }
                }
            }
        }
        if out.len() > before {
            out.sort_by(|p, q| p.0.total_cmp(&q.0));
        }
    }

    /// The knife-edge loss (dB, ITU-R P.526 eq. (31)) of the profile point of largest `nu` on the
    /// straight leg from `(s0, z0)` to `(s1, z1)` (distance along the ground line, height above
    /// sea level), leaving out the points within `skip` m of `s_skip`.
    fn leg_loss_db(
        prof: &[(f64, f64)],
        (s0, z0): (f64, f64),
        (s1, z1): (f64, f64),
        s_skip: f64,
        skip: f64,
        lambda: f64,
    ) -> f64 {
        let span = s1 - s0;
        let nu = prof
            .iter()
            .filter(|&&(s, _)| s > s0 && s < s1 && (s - s_skip).abs() > skip)
            .map(|&(s, h)| {
                let (a, b) = (s - s0, s1 - s);
                let line = z0 + (z1 - z0) * a / span;
                (h - line) * (2.0 * span / (lambda * a * b)).sqrt()
            })
            .fold(f64::NEG_INFINITY, f64::max);
        knife_edge_loss_db(nu)
    }

    /// The loss (dB) of the profile's edge `i` on the (sub-)path from `(s0, z0)` to `(s1, z1)`
    /// (distances along the path's ground line, `rho` long, whose point at distance `d` is
    /// `at(d)`; heights with the Earth's bulge),
    /// of Fresnel parameter `nu` (docs/physics.md section 12). Where the edge is lit past
    /// grazing (`nu > 0`) and is a building's (a roof on one side of it along the path, lower
    /// ground or a lower roof on the other), the edge is the right-angled wedge of a roof and a
    /// wall: ITU-R P.526-15 section 6's coefficient in the path's vertical plane, face 0 the
    /// face the path's start lights (the roof from above its plane, else the wall), the faces
    /// P.2040 concrete (a footprint names its walls' material, not its roof's), the field along
    /// the edge for horizontal polarisation and across it for vertical. Elsewhere the knife
    /// edge, `J(nu)`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn roof_edge_loss_db(
        &self,
        prof: &[(f64, f64)],
        (at, rho): (&dyn Fn(f64) -> [f64; 2], f64),
        nu: f64,
        i: usize,
        (s0, z0): (f64, f64),
        (s1, z1): (f64, f64),
        lambda: f64,
    ) -> f64 {
        use crate::propagation::diffraction::{EFFECTIVE_EARTH_RADIUS_M, utd_wedge};
        use crate::propagation::rays::{RayGround, reflection_coefficient};
        use std::f64::consts::PI;
        if nu <= 0.0 {
            return knife_edge_loss_db(nu);
        }
        let (de, h) = prof[i];
        // Which way the roof runs from the edge: the scene's obstacles a centimetre on either
        // side along the path (the profile reads a face a micrometre inside its building).
        let top = |d: f64| {
            let [x, y] = at(d);
            self.obstacle_at(x, y)
        };
        let (here, back, on) = (top(de), top(de - 0.01), top(de + 0.01));
        let face0 = if here <= 0.0 {
            return knife_edge_loss_db(nu);
        } else if on == here && back < here {
            [1.0, 0.0]
        } else if back == here && on < here {
            [-1.0, 0.0]
        } else {
            return knife_edge_loss_db(nu);
        };
        let g = h + de * (rho - de) / (2.0 * EFFECTIVE_EARTH_RADIUS_M);
        let (u, v) = ([s0 - de, z0 - g], [s1 - de, z1 - g]);
        // Angles from the roof (face 0) through the air to the wall (face n, straight down):
        // counter-clockwise where the roof runs on along the path, clockwise where it runs back.
        let angle = |w: [f64; 2]| {
            let t = w[1].atan2(face0[0] * w[0]);
            if t < 0.0 { t + 2.0 * PI } else { t }
        };
        let n = 1.5;
        let (mut phi1, mut phi2) = (angle(u), angle(v));
        if !(phi1 > 0.0 && phi1 < n * PI && phi2 > 0.0 && phi2 < n * PI) {
            return knife_edge_loss_db(nu);
        }
        if phi1 > PI {
            // A site below the roof's plane lights the wall alone: the wall is face 0.
            (phi1, phi2) = (n * PI - phi1, n * PI - phi2);
        }
        let (sp, sd) = (crate::norm(u[0], u[1]), crate::norm(v[0], v[1]));
        let f_ghz = self.freq_hz / 1e9;
        let concrete =
            num_complex::Complex64::new(5.24, -17.98 * 0.0462 * f_ghz.powf(0.7822) / f_ghz);
        let face = RayGround::Dielectric(concrete);
        let grazing = |t: f64| t.sin().abs().asin();
        let r0 = reflection_coefficient(face, self.polarization, grazing(phi1));
        let rn = reflection_coefficient(face, self.polarization, grazing(n * PI - phi2));
        let k = 2.0 * PI / lambda;
        let d = utd_wedge(n, phi1, phi2, sp * sd / (sp + sd), 1.0, k, r0, rn);
        // Relative to the free field over the unfolded length.
        let amp = d.norm() * ((sp + sd) / (sp * sd)).sqrt();
        -20.0 * amp.max(1e-30).log10()
    }

    /// The diffraction loss (dB) of the direct ray over the profile `prof` of the ground line
    /// `a -> b` between the ends at `za`, `zb` (m above sea level), and the edge toward which
    /// the antenna's gain is taken (docs/physics.md section 12). The principal edge (Deygout's:
    /// largest `nu`) decides the method: on terrain, P.526's Bullington construction with its
    /// correction for real terrain; on a building or the obstacle raster, Deygout's isolated
    /// edges without it, plus the correction of the terrain's own Bullington loss where a terrain
    /// is under the path (0 where the terrain alone clears the path), over `ground`, the
    /// terrain alone every half of its spacing.
    #[allow(clippy::too_many_arguments)]
    fn diffraction_loss(
        &self,
        prof: &[(f64, f64)],
        ground: &[(f64, f64)],
        a: [f64; 2],
        b: [f64; 2],
        za: f64,
        zb: f64,
        lambda: f64,
    ) -> (f64, Option<(f64, f64)>) {
        use crate::propagation::diffraction::{bullington, deygout_with};
        let rho = crate::norm(b[0] - a[0], b[1] - a[1]);
        let bull = bullington(prof, rho, za, zb, lambda);
        let obstacles = self.prisms.is_some_and(|p| !p.is_empty()) || self.heights.is_some();
        if !obstacles {
            return (bull.loss_db, bull.edge);
        }
        let at = |d: f64| {
            let t = d / rho;
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        };
        let (l_d, edge) = deygout_with(prof, rho, za, zb, lambda, |nu, i, from, to| {
            self.roof_edge_loss_db(prof, (&at, rho), nu, i, from, to, lambda)
        });
        let Some((de, _)) = edge else {
            return (bull.loss_db, bull.edge);
        };
        let t = de / rho;
        if self.obstacle_at(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])) <= 0.0 {
            return (bull.loss_db, bull.edge);
        }
        let corr = if self.terrain.is_some() {
            let l_t = bullington(ground, rho, za, zb, lambda).knife_edge_db;
            (1.0 - (-l_t / 6.0).exp()) * (10.0 + 0.02 * rho / 1000.0)
        } else {
            0.0
        };
        (l_d + corr, edge)
    }

    /// The geometry of the rays from the transmitter at `tx` (`[x, y, height above the
    /// terrain]`) to the pixel centre `q`; `sight` holds the scene's bounds and scratch space
    /// ([`RayScene::sight`]).
    ///
    /// The profile is read only where it can change the answer: a building is left out where
    /// its roof stays more than `2 (0.78) sqrt(lambda d / 8)` plus the Earth's bulge below both
    /// the direct ray and the ground-reflected ray's legs. There every construction that reads
    /// the profile gives it `nu < -0.78` (no loss): Bullington's and Deygout's (whose
    /// principal edge, if below the direct ray, is within `0.78 sqrt(lambda d / 8)` of it),
    /// and each leg's knife edge; and beyond line of sight only the points above the direct
    /// ray set Bullington's slopes. The geometry is the whole profile's.
    pub fn path(&self, tx: [f64; 3], q: [f64; 2], sight: &mut Sight) -> PathGeometry {
        self.path_over(tx, q, sight, true)
    }

    /// [`RayScene::path`], reading the whole profile where `prune` is false (the check that
    /// what it leaves out changes nothing).
    // Long: the line-of-sight test, each leg's knife edge and Bullington's slopes read the same
    // profile samples in one pass.
    pub(crate) fn path_over(
        &self,
        tx: [f64; 3],
        q: [f64; 2],
        sight: &mut Sight,
        prune: bool,
    ) -> PathGeometry {
        let [xs, ys, hs] = tx;
        let (ex, ey) = (q[0] - xs, q[1] - ys);
        let rho = crate::norm(ex, ey);
        if self.flat_open() {
            let hq = self.altitude_m;
            let (d1, d2) = ray_lengths(rho, hs, hq);
            return PathGeometry {
                d1,
                d2,
                loss_db: 0.0,
                el_direct: (hq - hs).atan2(rho),
                el_reflect: -(hq + hs).atan2(rho),
                psi: ((hs + hq) / rho.max(1e-9)).atan(),
                reflect: if self.ground != RayGround::None {
                    1.0
                } else {
                    0.0
                },
            };
        }
        let zt_s = self.terrain_at(xs, ys);
        let zs = zt_s + hs;
        let zq = self.receiver_height(q);
        let d1 = (rho * rho + (zq - zs).powi(2)).sqrt().max(1e-3);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        let spec = if self.ground == RayGround::None || rho < 1e-6 {
            None
        } else {
            self.specular(tx, q, zs, zq, lambda)
        };
        // The lowest a building must reach to matter (doc above), over t in lo..=hi.
        let margin = 1.56 * (lambda * rho / 8.0).sqrt()
            + rho * rho / (8.0 * crate::propagation::diffraction::EFFECTIVE_EARTH_RADIUS_M);
        let direct = |t: f64| zs + (zq - zs) * t;
        let floor = |lo: f64, hi: f64| {
            if !prune {
                return f64::NEG_INFINITY;
            }
            let mut z = direct(lo).min(direct(hi));
            if let Some(sp) = &spec {
                let tb = sp.sb / rho;
                let legs = |t: f64| {
                    if t <= tb {
                        zs + (sp.zb - zs) * t / tb.max(1e-12)
                    } else {
                        sp.zb + (zq - sp.zb) * (t - tb) / (1.0 - tb).max(1e-12)
                    }
                };
                z = z.min(legs(lo)).min(legs(hi));
                if lo <= tb && tb <= hi {
                    z = z.min(sp.zb);
                }
            }
            z - margin
        };
        self.profile_over([xs, ys], q, floor, sight);
        let prof = &sight.prof;
        let (loss_db, edge) =
            self.diffraction_loss(prof, &sight.ground, [xs, ys], q, zs, zq, lambda);
        let el_direct = match edge {
            Some((de, he)) => (he - zs).atan2(de),
            None => (zq - zs).atan2(rho),
        };
        let mut g = PathGeometry {
            d1,
            d2: d1,
            loss_db,
            el_direct,
            el_reflect: el_direct,
            psi: 0.0,
            reflect: 0.0,
        };
        let Some(Specular {
            sb,
            zb,
            d2,
            psi,
            sigma,
            half,
        }) = spec
        else {
            return g;
        };
        let (ux, uy) = (ex / rho, ey / rho);
        let bare = self.obstacle_at(xs + ux * sb, ys + uy * sb) <= 0.0;
        // Each leg's knife-edge loss over the profile (the reflecting zone left out): a leg
        // the terrain or a building half hides fades the ray instead of cutting it.
        let skip = self.half_spacing().max(half);
        let legs = Self::leg_loss_db(prof, (0.0, zs), (sb, zb), sb, skip, lambda)
            + Self::leg_loss_db(prof, (sb, zb), (rho, zq), sb, skip, lambda);
        g.d2 = d2;
        g.el_reflect = (zb - zs).atan2(sb);
        g.psi = psi;
        let k = crate::wavenumber(self.freq_hz);
        let sigma = if self.terrain.is_some() {
            crate::norm(sigma, self.roughness_m)
        } else {
            sigma
        };
        let rough = (-2.0 * (k * sigma * g.psi.sin()).powi(2)).exp();
        g.reflect = if bare {
            rough * db_to_amplitude(legs)
        } else {
            0.0
        };
        g
    }
}

mod specular;
use specular::Specular;
#[cfg(test)]
use specular::fit_line;

#[cfg(test)]
mod tests;
