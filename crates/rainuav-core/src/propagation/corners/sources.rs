//! Where the corners' rays come from (module docs of [`super`]): the images of the site in the
//! walls near a corner, the heights at which the legs from the site reach a corner, and the
//! corners the site lights.

use num_complex::Complex64;
use rayon::prelude::*;

use std::f64::consts::PI;

use super::{
    CORNER_GAP_M, Corner, EXCESS_M, IMAGE_RADIUS_M, Image, LIT_RADIUS_M, material_left, unit,
};
use crate::propagation::rays::RayScene;
use crate::propagation::sight::Sight;

/// A lit item (a corner with its images, or a roof edge) with its azimuth (rad, in `[-pi, pi]`)
/// and distance (m) from the site, its slack (how far, m, the item reaches from the point it is
/// placed at) and that point.
type Placed<T> = (f64, f64, f64, [f64; 2], T);

/// The items (corners, roof edges) the site lights, for the pixels to look up those within
/// their ellipse (`excess` m of extra horizontal path, widened by twice an item's slack): in
/// bands of distance from the site (band 0 within `excess / 2`, where every item is inside
/// every pixel's ellipse; band `k` from `excess 2^(k-2)` to twice that), each sorted by azimuth
/// from the site. A pixel at distance `d` reads, in a band from `r`, the azimuths within
/// `acos((d + e) / d - e (2 d + e) / (2 r d))` of its own (`e` the excess widened by the
/// largest slack): no item at `r` or farther outside that lies inside the ellipse.
pub(crate) struct Lit<T> {
    site: [f64; 2],
    excess: f64,
    /// The largest slack of any item.
    slack: f64,
    /// Each band's inner radius and its items, sorted by azimuth.
    bands: Vec<(f64, Vec<Placed<T>>)>,
}

impl<T> Lit<T> {
    /// Places `items` (each with its point `[x, y]` and slack, m) for pixels' ellipses of
    /// `excess` m.
    pub(crate) fn new(site: [f64; 2], excess: f64, items: Vec<([f64; 2], f64, T)>) -> Self {
        let half = 0.5 * excess;
        let mut bands: Vec<(f64, Vec<Placed<T>>)> = Vec::new();
        let mut slack = 0.0f64;
        for (v, sl, item) in items {
            let (dx, dy) = (v[0] - site[0], v[1] - site[1]);
            let r = crate::norm(dx, dy);
            let k = if r < half {
                0
            } else {
                1 + (r / half).log2().floor() as usize
            };
            while bands.len() <= k {
                let inner = if bands.is_empty() {
                    0.0
                } else {
                    half * 2f64.powi(bands.len() as i32 - 1)
                };
                bands.push((inner, Vec::new()));
            }
            slack = slack.max(sl);
            bands[k].1.push((dy.atan2(dx), r, sl, v, item));
        }
        for (_, band) in &mut bands {
            band.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Self {
            site,
            excess,
            slack,
            bands,
        }
    }

    /// Calls `f` on every item whose point is inside the ellipse of the pixel `q` widened by
    /// twice its slack (in the order of the bands and azimuths).
    pub(crate) fn near(&self, q: [f64; 2], mut f: impl FnMut(&T)) {
        let (dx, dy) = (q[0] - self.site[0], q[1] - self.site[1]);
        let d = crate::norm(dx, dy);
        let aq = dy.atan2(dx);
        let e = self.excess + 2.0 * self.slack;
        let mut visit = |(_, r1, sl, v, item): &Placed<T>| {
            if r1 + crate::norm(v[0] - q[0], v[1] - q[1]) - d <= self.excess + 2.0 * sl {
                f(item);
            }
        };
        for (inner, band) in &self.bands {
            let g = if *inner > 0.0 && d > 1e-9 {
                (d + e) / d - e * (2.0 * d + e) / (2.0 * inner * d)
            } else {
                -1.0
            };
            if g > 1.0 {
                continue;
            }
            if g <= -1.0 {
                band.iter().for_each(&mut visit);
                continue;
            }
            let w = g.acos();
            let mut read = |lo: f64, hi: f64| {
                let i = band.partition_point(|(a, ..)| *a < lo);
                band[i..]
                    .iter()
                    .take_while(|(a, ..)| *a <= hi)
                    .for_each(&mut visit);
            };
            let (lo, hi) = (aq - w, aq + w);
            read(lo.max(-PI), hi.min(PI));
            if lo < -PI {
                read(lo + 2.0 * PI, PI);
            }
            if hi > PI {
                read(-PI, hi - 2.0 * PI);
            }
        }
    }
}

impl RayScene<'_> {
    /// The images of the site (horizontal position `s`) in the walls near corner `c` that face
    /// both (module docs), with each wall's permittivity from `eps` (a prism's).
    fn images_of(
        &self,
        s: [f64; 2],
        c: &Corner,
        eps: &[Complex64],
        near: &mut Vec<u32>,
    ) -> Vec<Image> {
        let Some(prisms) = self.prisms else {
            return Vec::new();
        };
        let r = IMAGE_RADIUS_M;
        prisms.near_box([c.v[0] - r, c.v[0] + r, c.v[1] - r, c.v[1] + r], near);
        let mut out = Vec::new();
        for &k in near.iter() {
            let k = k as usize;
            for (ri, ring) in prisms.rings_of(k).enumerate() {
                let m = ring.len();
                let left = material_left(ri, ring);
                for i in 0..m {
                    let (a, b) = (ring[i], ring[(i + 1) % m]);
                    if a == c.v || b == c.v {
                        continue; // the corner's own faces: the wedge's R0, Rn
                    }
                    let Some(t) = unit([b[0] - a[0], b[1] - a[1]]) else {
                        continue;
                    };
                    // Outward: right of a -> b where the material lies on its left.
                    let n = if left { [t[1], -t[0]] } else { [-t[1], t[0]] };
                    let ds = (s[0] - a[0]) * n[0] + (s[1] - a[1]) * n[1];
                    let dc = (c.v[0] - a[0]) * n[0] + (c.v[1] - a[1]) * n[1];
                    if ds <= 1e-6 || dc <= 1e-6 {
                        continue;
                    }
                    let at = [s[0] - 2.0 * ds * n[0], s[1] - 2.0 * ds * n[1]];
                    let u = ds / (ds + dc);
                    let p = [at[0] + u * (c.v[0] - at[0]), at[1] + u * (c.v[1] - at[1])];
                    let along = (p[0] - a[0]) * t[0] + (p[1] - a[1]) * t[1];
                    let len = crate::norm(b[0] - a[0], b[1] - a[1]);
                    if !(0.0..=len).contains(&along) {
                        continue;
                    }
                    out.push(Image {
                        at,
                        p,
                        d_sp: crate::norm(p[0] - s[0], p[1] - s[1]),
                        n,
                        top: prisms.items()[k].top,
                        eps: eps[k],
                        z_min: f64::INFINITY,
                    });
                }
            }
        }
        out
    }

    /// The corners of the buildings within [`LIT_RADIUS_M`] of the site (at `zs`) whose edge it
    /// sees somewhere between the terrain and the roof, directly or by a wall within
    /// [`IMAGE_RADIUS_M`] of the corner, each with its `z_min` and the images that light it,
    /// for the pixels to look up; less those whose roof is below `z_low` (m above sea level).
    pub(super) fn lit_corners(
        &self,
        (site, zs): ([f64; 2], f64),
        z_low: f64,
        eps: &[Complex64],
        bounds: crate::propagation::sight::Bounds,
    ) -> Lit<(Corner, Vec<Image>)> {
        let Some(prisms) = self.prisms else {
            return Lit::new(site, EXCESS_M, Vec::new());
        };
        let r = LIT_RADIUS_M;
        let mut near = Vec::new();
        prisms.near_box(
            [site[0] - r, site[0] + r, site[1] - r, site[1] + r],
            &mut near,
        );
        let corners = near
            .par_iter()
            .flat_map_iter(|&k| {
                let (mut sight, mut scratch) = (self.sight(bounds), Vec::new());
                let mut corners = Vec::new();
                self.corners_of(k as usize, &mut corners);
                corners
                    .into_iter()
                    .filter_map(|mut c| {
                        if crate::norm(c.v[0] - site[0], c.v[1] - site[1]) > r {
                            return None;
                        }
                        let z_lo = self.terrain_at(c.v[0], c.v[1]);
                        let top = z_lo + c.top;
                        if top < z_low {
                            return None;
                        }
                        let images =
                            self.sources_of((site, zs), &mut c, eps, &mut scratch, &mut sight);
                        (c.z_min < top || !images.is_empty()).then_some((c.v, 0.0, (c, images)))
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        Lit::new(site, EXCESS_M, corners)
    }

    /// Corner `c`'s images of the site (at `zs`; [`Self::images_of`]) with the heights above
    /// which their legs and the direct one reach it ([`Self::first_legs`], which sets
    /// `c.z_min`), less the images whose legs clear nothing below the roof (no ray of theirs
    /// would pass `corner_ray`'s height test).
    pub(super) fn sources_of(
        &self,
        (site, zs): ([f64; 2], f64),
        c: &mut Corner,
        eps: &[Complex64],
        scratch: &mut Vec<u32>,
        sight: &mut Sight,
    ) -> Vec<Image> {
        let mut images = self.images_of(site, c, eps, scratch);
        self.first_legs((site, zs), c, &mut images, sight);
        let top = self.terrain_at(c.v[0], c.v[1]) + c.top;
        images.retain(|m| m.z_min < top);
        images
    }

    /// The heights at corner `c` above which the legs from the site (at `zs`) reach it: the
    /// direct leg into `c.z_min`, and site -> wall -> corner into each image's (module docs).
    /// They depend on the height at the corner alone (where the unfolded ray meets the edge),
    /// not on the pixel: found once a corner, each a [`Sight::lowest`].
    fn first_legs(
        &self,
        (site, zs): ([f64; 2], f64),
        c: &mut Corner,
        images: &mut [Image],
        sight: &mut Sight,
    ) {
        let out = c.outside();
        let z_lo = self.terrain_at(c.v[0], c.v[1]);
        c.z_min = sight.lowest((site, zs, 0.0), (out, 0.0, 1.0), z_lo);
        for m in images {
            let r1 = crate::norm(m.at[0] - c.v[0], m.at[1] - c.v[1]);
            if r1 < 1e-6 {
                continue;
            }
            // The reflection point's height is zs (1 - f) + f z at a height z at the corner.
            let f = m.d_sp / r1;
            let g = CORNER_GAP_M;
            let before = |a: [f64; 2], b: [f64; 2], f: f64| {
                [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
            };
            let (d1, d2) = (m.d_sp.max(g), (r1 - m.d_sp).max(g));
            let (u1, u2) = (1.0 - g / d1, g / d2);
            let (p1, p2) = (before(site, m.p, u1), before(m.p, out, u2));
            let leg1 = sight.lowest((site, zs, 0.0), (p1, zs - u1 * f * zs, u1 * f), z_lo);
            let at_p2 = ((1.0 - u2) * zs * (1.0 - f), (1.0 - u2) * f + u2);
            let leg2 = sight.lowest((p2, at_p2.0, at_p2.1), (out, 0.0, 1.0), z_lo);
            m.z_min = leg1.max(leg2);
        }
    }
}
