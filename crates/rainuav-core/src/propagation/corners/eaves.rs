//! Diffraction at the horizontal edges of roofs beside the straight line (docs/physics.md section
//! 12): where the buildings hide a pixel from a site, a roof edge that both see, off the line,
//! diffracts a ray to it. The tracer finds such paths in the deepest shadows of a district seen
//! from above its roofs: an edge a few metres below both ends, 200 m to the side, where the
//! site and the pixel both graze the roof.
//!
//! An edge is a footprint ring's side at the roof's height (above the terrain at its middle; in
//! pieces of at most [`EAVE_PIECE_M`], each at the terrain at its own middle),
//! a right-angled wedge (`n = 1.5`) whose faces are the roof (face 0, toward the footprint)
//! and the wall (face n, down), both of the building's material. The ray meets it where the
//! unfolded path is straight (Keller's law: along the edge, the point splits the distances
//! between the ends' projections on it in the ratio of their distances from the edge's line),
//! and exists where that point lies on the edge and both legs clear every building and the
//! terrain. The angles `phi1`, `phi2` are measured in the plane across the edge from the roof
//! face, through the vertical, to the wall face; the coefficient is
//! [`crate::propagation::diffraction::utd_wedge`]'s (ITU-R P.526-15 section 6).
//!
//! Such a ray is oblique: it runs along the edge as much as across it. So its field is split
//! in the edge's own frames (Kouyoumjian and Pathak's `beta` and `phi` unit vectors, in and
//! out): the part along the plane of the edge and the ray takes the soft coefficient (each
//! face's TE Fresnel coefficient), the part across it the hard one (TM), and the receiver, of
//! the site's polarisation, takes its projection of the sum. A vertically polarised ray
//! grazing a roof is mostly hard, a horizontally polarised one mostly soft. Each face's P.2040
//! coefficient is taken at the incident ray's angle with that face (-1 where the incident ray
//! does not light it), as Sionna RT does after Hashimoto et al., not at P.526's `phi1` and `n
//! pi - phi2`: the two agree at each face's reflection boundary for a ray square to the edge,
//! where the coefficient's reflection terms matter most, but an oblique ray grazes the roof
//! at a smaller angle than its `phi1` (6 against 15 degrees on the tracer tests' `eave` scene:
//! at its pixel (190, 2), P.526's angles leave the edge's ray 3.5 dB (H) and 5.1 dB (V) off
//! the path solver's, in opposite directions, the incident ray's angles 0.1 and 0.9 dB).
//!
//! The edges looked at: those of the buildings within [`EAVE_RADIUS_M`] of the site, in pieces
//! of at most [`EAVE_PIECE_M`] (each placed for the pixels at its middle), less the buildings the
//! straight line crosses (the direct ray's Deygout edges read those), for the pixels whose path
//! over the edge is at most [`EAVE_EXCESS_M`] longer (horizontally) than the straight line. The
//! leg from the site is read once a piece: the site's sight of its sample points (both ends and
//! at most [`EAVE_SAMPLE_M`] apart, each just outside the edge), and a ray's first leg is taken
//! as clear where the sample points on both sides of its diffraction point are seen (a
//! building in the way between two seen points is missed). The leg to the pixel is checked
//! whole, against the buildings that hide the pixel first. Far from the roof's and the wall's
//! shadow and reflection boundaries an edge's ray is weak: a ray weaker than free space over
//! the straight line by more than [`EAVE_FLOOR_DB`], or than the strongest corner's ray to the
//! same pixel by more than [`EAVE_BELOW_DB`], is dropped before its leg to the pixel is checked
//! (a bound on the coefficient first, `|F| <= 1` and `|R| <= 1`, then the coefficient itself).
//! Power per mW radiated, isotropic antennas: `(lambda / 4 pi)^2 |D|^2 / (s1 s2 (s1 + s2))`, as a
//! corner's.

use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

use super::sources::Lit;
use super::{CORNER_GAP_M, unit};
use crate::propagation::diffraction::utd_wedge;
use crate::propagation::rays::{RayGround, RayPolarization, RayScene, reflection_coefficient};
use crate::propagation::sight::{Bounds, Sight};

/// A roof edge diffracts to the pixels it hides for which the path over it is at most this much
/// (m, horizontally) longer than the straight line.
pub const EAVE_EXCESS_M: f64 = 300.0;

/// A roof edge's ray weaker than free space over the straight line by more than this (dB) is
/// dropped.
pub const EAVE_FLOOR_DB: f64 = 50.0;

/// The roof edges looked at are those of the buildings within this distance (m) of the site.
pub const EAVE_RADIUS_M: f64 = 500.0;

/// A roof edge's ray weaker than the strongest corner's ray to the same pixel by more than this
/// (dB) is dropped.
pub const EAVE_BELOW_DB: f64 = 30.0;

/// The power per mW (isotropic antennas) [`EAVE_FLOOR_DB`] below free space at 1 m: divided by
/// the squared distance, the least power of a roof edge's ray.
pub(super) fn floor(freq_hz: f64) -> f64 {
    let lambda = crate::SPEED_OF_LIGHT_M_S / freq_hz;
    10f64.powf(-0.1 * EAVE_FLOOR_DB) * (lambda / (4.0 * PI)).powi(2)
}

/// The site's sight of a roof edge's piece is read at its points at most this far apart (m)
/// along it, both ends included.
pub const EAVE_SAMPLE_M: f64 = 5.0;

/// A roof edge is looked at in pieces of at most this length (m), each placed for the pixels at
/// its middle ([`Lit`]: a long edge would widen every pixel's search).
pub const EAVE_PIECE_M: f64 = 20.0;

/// The exterior angle of a roof edge over a vertical wall, `n pi`.
const EAVE_N: f64 = 1.5;

/// One roof edge: its first end and unit direction (horizontal), length, outward unit normal
/// (horizontal, away from the footprint), the roof's height above sea level at its middle, and
/// the prism.
#[derive(Debug, Clone, Copy)]
pub(super) struct Eave {
    pub(super) a: [f64; 2],
    pub(super) u: [f64; 2],
    pub(super) len: f64,
    pub(super) n: [f64; 2],
    pub(super) z: f64,
    pub(super) prism: usize,
    /// Bit `i`: the site sees the edge at its `i`-th sample point ([`Eave::samples`]).
    pub(super) seen: u32,
    /// The site's projection on the edge's line (m from `a`), its distance from that line (m)
    /// and its position across it (m outward, m above the roof).
    pub(super) site: (f64, f64, f64, f64),
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The angle (rad, in `[0, 2 pi)`) across an edge of a point `h` m outward of its wall's plane
/// and `v` m above its roof, from the roof face through the vertical to the wall face.
fn across(h: f64, v: f64) -> f64 {
    let a = v.atan2(-h);
    if a < 0.0 { a + 2.0 * PI } else { a }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalized(a: [f64; 3]) -> [f64; 3] {
    let n = dot3(a, a).sqrt().max(1e-300);
    a.map(|v| v / n)
}

/// The unit field of an antenna of polarisation `pol` radiating (or receiving) along the unit
/// direction `d`: the elevation unit vector (vertical) or the azimuth one (horizontal).
fn field(pol: RayPolarization, d: [f64; 3]) -> [f64; 3] {
    match pol {
        RayPolarization::V => normalized([d[0] * d[2], d[1] * d[2], -(d[0] * d[0] + d[1] * d[1])]),
        RayPolarization::H => normalized([-d[1], d[0], 0.0]),
    }
}

/// The amplitudes a ray of polarisation `pol` brings to a receiver of the same polarisation
/// through an edge of unit direction `edge`, incident along `ai` and diffracted along `ad`
/// (unit vectors), by the soft and the hard coefficient: each the product of the incident
/// field's part and the receiver's projection of the diffracted field's, in the edge-fixed
/// frames (Kouyoumjian and Pathak's: `phi = edge x s / |edge x s|`, `beta = s x phi`).
fn split(pol: RayPolarization, edge: [f64; 3], ai: [f64; 3], ad: [f64; 3]) -> (f64, f64) {
    let frame = |s: [f64; 3]| {
        let phi = normalized(cross(edge, s));
        (cross(s, phi), phi)
    };
    let ((bi, fi), (bd, fd)) = (frame(ai), frame(ad));
    let (ei, er) = (field(pol, ai), field(pol, ad));
    (dot3(ei, bi) * dot3(bd, er), dot3(ei, fi) * dot3(fd, er))
}

impl Eave {
    /// The number of intervals between the piece's sample points: at most [`EAVE_SAMPLE_M`]
    /// apart, both ends included (`samples() + 1` points).
    fn samples(&self) -> usize {
        (self.len / EAVE_SAMPLE_M).ceil().clamp(1.0, 30.0) as usize
    }

    /// Whether the site sees the sample points on both sides of `t` m along the piece.
    fn seen_at(&self, t: f64) -> bool {
        let m = self.samples();
        let i = ((t / self.len * m as f64).floor() as usize).min(m - 1);
        self.seen >> i & 0b11 == 0b11
    }

    /// The point at `t` m along the edge, and the point [`CORNER_GAP_M`] outside it along the
    /// wedge's exterior bisector (outward and up), where the legs' checks end, with its height.
    fn at(&self, t: f64) -> ([f64; 2], [f64; 2], f64) {
        let p = [self.a[0] + t * self.u[0], self.a[1] + t * self.u[1]];
        let g = CORNER_GAP_M * std::f64::consts::FRAC_1_SQRT_2;
        (p, [p[0] + g * self.n[0], p[1] + g * self.n[1]], self.z + g)
    }
}

impl RayScene<'_> {
    /// Whether the line from `(a, za)` to `(b, zb)` passes below the roof of one of the
    /// buildings `hits` where it crosses its footprint's outline (`ts`: scratch).
    pub(super) fn crosses_below(
        &self,
        hits: &[u32],
        (a, za): ([f64; 2], f64),
        (b, zb): ([f64; 2], f64),
        ts: &mut Vec<f64>,
    ) -> bool {
        let Some(prisms) = self.prisms else {
            return false;
        };
        hits.iter().any(|&k| {
            ts.clear();
            prisms.crossings(k as usize, a, b, ts);
            ts.iter().any(|&t| {
                let (x, y) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
                self.terrain_at(x, y) + prisms.items()[k as usize].top >= za + (zb - za) * t
            })
        })
    }

    /// The roof edges of prism `k` (module docs).
    fn eaves_of(&self, k: usize, out: &mut Vec<Eave>) {
        for (top, ring, left) in self.sided_rings(k) {
            let m = ring.len();
            for i in 0..m {
                let (a, b) = (ring[i], ring[(i + 1) % m]);
                let Some(u) = unit([b[0] - a[0], b[1] - a[1]]) else {
                    continue;
                };
                let whole = crate::norm(b[0] - a[0], b[1] - a[1]);
                let pieces = (whole / EAVE_PIECE_M).ceil().max(1.0);
                let len = whole / pieces;
                for i in 0..pieces as usize {
                    let t = len * i as f64;
                    let a = [a[0] + t * u[0], a[1] + t * u[1]];
                    let mid = [a[0] + 0.5 * len * u[0], a[1] + 0.5 * len * u[1]];
                    out.push(Eave {
                        a,
                        u,
                        len,
                        // Outward: right of a -> b where the material lies on its left.
                        n: if left { [u[1], -u[0]] } else { [-u[1], u[0]] },
                        z: self.terrain_at(mid[0], mid[1]) + top,
                        prism: k,
                        seen: 0,
                        site: (0.0, 0.0, 0.0, 0.0),
                    });
                }
            }
        }
    }

    /// The roof edges' pieces within [`EAVE_RADIUS_M`] of the site (at `zs`) that it sees at one
    /// of their sample points, with the site's terms and sight, for the pixels to look up.
    pub(super) fn lit_eaves(&self, (site, zs): ([f64; 2], f64), bounds: Bounds) -> Lit<Eave> {
        let r = EAVE_RADIUS_M;
        let mut near = Vec::new();
        if let Some(prisms) = self.prisms {
            prisms.near_box(
                [site[0] - r, site[0] + r, site[1] - r, site[1] + r],
                &mut near,
            );
        }
        let eaves = near
            .par_iter()
            .flat_map_iter(|&k| {
                let mut sight = self.sight(bounds);
                let mut eaves = Vec::new();
                self.eaves_of(k as usize, &mut eaves);
                eaves.into_iter().filter_map(move |e| {
                    let (mid, ..) = e.at(0.5 * e.len);
                    if crate::norm(mid[0] - site[0], mid[1] - site[1]) > r {
                        return None; // its building's box is near, the piece is not
                    }
                    let ps = [site[0] - e.a[0], site[1] - e.a[1]];
                    let (t, h, v) = (dot(ps, e.u), dot(ps, e.n), zs - e.z);
                    if across(h, v) >= EAVE_N * PI || crate::norm(h, v) < 1e-6 {
                        return None; // the site is under the roof's plane, inside the wall's
                    }
                    let mut e = e;
                    e.site = (t, crate::norm(h, v), h, v);
                    let m = e.samples();
                    for i in 0..=m {
                        let (_, out, zo) = e.at(e.len * i as f64 / m as f64);
                        if sight.clear(site, zs, out, zo) {
                            e.seen |= 1 << i;
                        }
                    }
                    (e.seen != 0).then_some((mid, 0.5 * e.len, e))
                })
            })
            .collect();
        Lit::new(site, EAVE_EXCESS_M, eaves)
    }

    /// The ray roof edge `e` diffracts from the site (`zs` m above sea level) to the pixel `q`
    /// (receiver at `zq`), if it is strong enough (module docs) and both legs are clear.
    #[allow(clippy::too_many_arguments)]
    // Long: both legs' checks, the edge's coefficients and the power bound share the site's terms
    // and the edge's geometry.
    pub(super) fn eave_ray(
        &self,
        s: [f64; 2],
        zs: f64,
        q: [f64; 2],
        zq: f64,
        e: &Eave,
        eps: Complex64,
        least: f64,
        hits: &[u32],
        sight: &mut Sight,
    ) -> Option<(f64, f64, f64, f64)> {
        // The site's terms were found once a piece ([`Self::lit_eaves`]).
        let (ts, rs, hs, vs) = e.site;
        let pq = [q[0] - e.a[0], q[1] - e.a[1]];
        let (tq, hq, vq) = (dot(pq, e.u), dot(pq, e.n), zq - e.z);
        let rq = crate::norm(hq, vq);
        let t = ts + (tq - ts) * rs / (rs + rq);
        if !(0.0..e.len).contains(&t) || rq < 1e-6 {
            return None;
        }
        let p = [e.a[0] + t * e.u[0], e.a[1] + t * e.u[1]];
        let excess = crate::norm(p[0] - s[0], p[1] - s[1]) + crate::norm(q[0] - p[0], q[1] - p[1])
            - crate::norm(q[0] - s[0], q[1] - s[1]);
        if excess > EAVE_EXCESS_M || !e.seen_at(t) {
            return None;
        }
        let ext = EAVE_N * PI;
        let (phi1, phi2) = (across(hs, vs), across(hq, vq));
        if !(phi1 > 0.0 && phi1 < ext && phi2 > 0.0 && phi2 < ext) {
            return None;
        }
        // The buildings that hide the pixel often hide it from the edge too: those first.
        let (_, out, zo) = e.at(t);
        if self.crosses_below(hits, (out, zo), (q, zq), &mut sight.ts) {
            return None;
        }
        let s1 = crate::norm(t - ts, rs);
        let s2 = crate::norm(tq - t, rq);
        let sin_b = rs / s1;
        let k = crate::wavenumber(self.freq_hz);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        // The field's parts (module docs): (soft, hard) amplitudes from the site's polarisation
        // through the edge to the pixel's.
        let p = [p[0], p[1], e.z];
        let (ai, ad) = (
            [p[0] - s[0], p[1] - s[1], p[2] - zs].map(|v| v / s1),
            [q[0] - p[0], q[1] - p[1], zq - p[2]].map(|v| v / s2),
        );
        let (soft, hard) = split(self.polarization, [e.u[0], e.u[1], 0.0], ai, ad);
        // The least power worth tracing, in the units of |D|^2.
        let need = least * s1 * s2 * (s1 + s2) / (lambda / (4.0 * PI)).powi(2);
        // The coefficients' bound: |F| <= 1 and |R| <= 1 in each of their four terms.
        let pre = 1.0 / (2.0 * EAVE_N * (2.0 * PI * k).sqrt() * sin_b.max(1e-9));
        let cot = |b: f64| 1.0 / ((PI + b) / (2.0 * EAVE_N)).tan().abs().max(1e-12);
        let bound = pre
            * (cot(phi2 - phi1) + cot(phi1 - phi2) + cot(-(phi2 + phi1)) + cot(phi2 + phi1))
            * (soft.abs() + hard.abs());
        if bound * bound < need {
            return None;
        }
        let l = s1 * s2 * sin_b * sin_b / (s1 + s2);
        let ground = RayGround::Dielectric(eps);
        // Each face's coefficient at the incident ray's angle with it (module docs), -1 where
        // the incident ray does not light the face.
        let (g0, gn) = (ai[2].abs().asin(), dot([ai[0], ai[1]], e.n).abs().asin());
        let face = |lit: bool, g: f64, pol| {
            if lit {
                reflection_coefficient(ground, pol, g)
            } else {
                Complex64::new(-1.0, 0.0)
            }
        };
        let wedge = |pol| {
            let r0 = face(vs > 0.0, g0, pol);
            let rn = face(hs > 0.0, gn, pol);
            utd_wedge(EAVE_N, phi1, phi2, l, sin_b, k, r0, rn)
        };
        // Soft: the field along the edge, perpendicular to each face's plane of incidence (the
        // ground's horizontal formula); hard: across it.
        let d = (wedge(RayPolarization::H) * soft + wedge(RayPolarization::V) * hard).norm_sqr();
        if d < need {
            return None;
        }
        if !sight.clear(out, zo, q, zq) {
            return None;
        }
        let factor = (lambda / (4.0 * PI)).powi(2) * d / (s1 * s2 * (s1 + s2));
        let az = ai[1].atan2(ai[0]).to_degrees();
        let el = ai[2].atan2(crate::norm(ai[0], ai[1])).to_degrees();
        Some((az, el, factor, s1 + s2))
    }
}

#[cfg(test)]
mod tests;
