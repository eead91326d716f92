//! Diffraction round the vertical edges of buildings (docs/physics.md section 12): where a
//! building hides a pixel from a site, each convex corner that sees both ends diffracts a ray
//! to the pixel, with the UTD coefficient of a finitely conducting wedge (ITU-R P.526-15
//! section 6, [`crate::propagation::diffraction::utd_wedge`]). The corners looked at: those of the
//! buildings in the way, and those the site lights (its line to the edge, or its image's in a
//! wall, clear somewhere between the terrain and the roof) among the buildings within
//! [`LIT_RADIUS_M`] of it, where going round the corner is at most [`EXCESS_M`] longer
//! (horizontally) than the straight line from the site to the pixel (the corner inside the
//! ellipse with the two as foci): a building across the street from those in the way, whose
//! corner the site sees down the street. The two limits bound the work; docs/physics.md
//! section 12 says what they leave out.
//!
//! A corner is a footprint vertex whose exterior angle `n pi` exceeds `pi` (a box's corners:
//! `n = 1.5`); its faces are the two walls that meet there, their material the building's. The
//! ray leaves the site, meets the vertical edge at the height where the unfolded path is
//! straight (Keller's law: `z = z_s + (z_q - z_s) r1 / (r1 + r2)` with `r1`, `r2` the horizontal
//! distances to the edge) and goes on to the pixel; it exists where that point lies on the edge
//! (between the terrain and the roof) and both legs clear every building and the terrain. The
//! angles `phi1` (toward the site) and `phi2` (toward the pixel) are measured in the horizontal
//! plane from face 0, the face nearer the site (the one it lights); `sin(beta0) = r1 / s1`. The
//! faces' Fresnel coefficients are P.2040's at each face's grazing angle (`phi1` for face 0,
//! `n pi - phi2` for face n, as the angle between the ray and the face's plane), for the field
//! along the edge (vertical polarisation: perpendicular to the horizontal plane of incidence) or
//! across it (horizontal polarisation).
//!
//! **A wall reflection, then the corner** (a corner of a building in the way or beside the
//! line; one beside the line that only an image lights is looked at too). A wall within
//! [`IMAGE_RADIUS_M`] of a corner that faces both the site and the corner mirrors the site:
//! its image diffracts at the corner as the site does, the reflection point where the line from
//! the image to the corner crosses the wall (it exists where that point lies on the wall,
//! between the terrain and the roof, and the legs site -> wall -> corner -> pixel are clear),
//! with the wall's P.2040 reflectance ([`crate::propagation::walls::wall_reflectance`]). The walls are the
//! prisms' edges. This is how a street lights its side streets: the site sees the corner at
//! grazing incidence along the street's wall, its image across the street at a wider angle.
//!
//! **The horizontal edges of roofs beside the line** diffract into the same hidden pixels:
//! [`eaves`] (Keller's point on each roof edge the site sees, the same wedge with the field split
//! into its soft and hard parts), traced in the same pass ([`RayScene::edge_rays`]).
//!
//! Each ray's power per mW radiated, isotropic antennas: `|Gamma|^2 (lambda / 4 pi)^2 |D|^2 /
//! (s1 s2 (s1 + s2))` (`|Gamma|^2 = 1` without a reflection, `s1` the unfolded length to the
//! edge); the caller applies the antenna gain toward the first interaction. Rays are returned as
//! [`WallRay`]s (one kind of extra ray: a departure direction, a power factor, a length) and add
//! incoherently to the rest.

use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::OnceLock;

use crate::error::{CoreError, Result};
use crate::propagation::diffraction::utd_wedge;
use crate::propagation::rays::{RayGround, RayPolarization, RayScene, reflection_coefficient};
use crate::propagation::sight::Sight;
use crate::propagation::walls::{WallRay, wall_reflectance};

/// How far (m) outside its corner, along the exterior bisector, a leg's visibility check ends:
/// the corner's own walls are not in the way of a ray that grazes them; and how far short of a
/// wall a leg to a reflection point stops.
const CORNER_GAP_M: f64 = 0.05;

/// The walls that may mirror the site into a corner: those of the buildings whose bounding box
/// comes within this distance (m) of the corner.
pub const IMAGE_RADIUS_M: f64 = 150.0;

/// The corners the site lights (module docs) are looked for among the buildings whose bounding
/// box comes within this distance (m) of the site: a city's streets show a site several blocks
/// each way (a street canyon 40 m below the roofs is lit round a corner 650 m from its site).
pub const LIT_RADIUS_M: f64 = 1000.0;

/// A corner the site lights diffracts to the pixels it hides for which the path round it is at
/// most this much (m, horizontally) longer than the straight line.
pub const EXCESS_M: f64 = 200.0;

/// A prism's corners, each with its images of the site.
type CornersOf = Vec<(Corner, Vec<Image>)>;

/// The site mirrored in a wall toward one corner.
#[derive(Debug, Clone, Copy)]
struct Image {
    /// The image, `[x, y]`.
    at: [f64; 2],
    /// The reflection point on the wall (horizontal), and its distance from the site.
    p: [f64; 2],
    d_sp: f64,
    /// The wall's outward unit normal, roof above the terrain and permittivity.
    n: [f64; 2],
    top: f64,
    eps: Complex64,
    /// The legs site -> wall -> corner are clear exactly where the height at the corner
    /// exceeds this ([`Sight::lowest`]).
    z_min: f64,
}

/// One convex corner: position, the unit directions of its two faces (face 0 first, the
/// exterior counter-clockwise from it), the exterior angle (rad), the prism and its roof.
#[derive(Debug, Clone, Copy)]
struct Corner {
    v: [f64; 2],
    a0: [f64; 2],
    ext: f64,
    top: f64,
    prism: usize,
    /// The leg from the site is clear exactly where its height at the corner exceeds this.
    z_min: f64,
}

/// Counter-clockwise angle from `a` to `b` (unit or not), in `[0, 2 pi)`.
fn ccw(a: [f64; 2], b: [f64; 2]) -> f64 {
    let t = (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1]);
    if t < 0.0 { t + 2.0 * PI } else { t }
}

/// Whether a prism's material lies left of the walk along its ring number `r` (0: the outer
/// ring): on an outer ring walked counter-clockwise and on a hole walked clockwise.
fn material_left(r: usize, ring: &[[f64; 2]]) -> bool {
    let m = ring.len();
    let area: f64 = (0..m)
        .map(|i| {
            let (p, q) = (ring[i], ring[(i + 1) % m]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum();
    (r == 0) == (area > 0.0)
}

impl Corner {
    /// The point [`CORNER_GAP_M`] outside the corner along its exterior bisector, where the
    /// legs' visibility checks end.
    fn outside(&self) -> [f64; 2] {
        let (bs, bc) = (0.5 * self.ext).sin_cos();
        [
            self.v[0] + CORNER_GAP_M * (self.a0[0] * bc - self.a0[1] * bs),
            self.v[1] + CORNER_GAP_M * (self.a0[0] * bs + self.a0[1] * bc),
        ]
    }
}

fn unit(d: [f64; 2]) -> Option<[f64; 2]> {
    let n = crate::norm(d[0], d[1]);
    (n > 1e-9).then(|| [d[0] / n, d[1] / n])
}

impl RayScene<'_> {
    /// Prism `k`'s rings, each with its roof height and whether its material lies on the left
    /// of the ring's order (none without prisms): what its corners and roof edges are read from.
    fn sided_rings(&self, k: usize) -> impl Iterator<Item = (f64, &[[f64; 2]], bool)> {
        self.prisms.into_iter().flat_map(move |p| {
            let top = p.items()[k].top;
            p.rings_of(k)
                .enumerate()
                .map(move |(r, ring)| (top, ring, material_left(r, ring)))
        })
    }

    /// The convex corners of prism `k` (its rings' vertices with an exterior angle above pi).
    fn corners_of(&self, k: usize, out: &mut Vec<Corner>) {
        for (top, ring, left) in self.sided_rings(k) {
            let m = ring.len();
            for i in 0..m {
                let v = ring[i];
                let (prev, next) = (ring[(i + m - 1) % m], ring[(i + 1) % m]);
                let (Some(tp), Some(tn)) = (
                    unit([prev[0] - v[0], prev[1] - v[1]]),
                    unit([next[0] - v[0], next[1] - v[1]]),
                ) else {
                    continue;
                };
                let (a0, an) = if left { (tp, tn) } else { (tn, tp) };
                let ext = ccw(a0, an);
                if ext > PI + 1e-6 {
                    out.push(Corner {
                        v,
                        a0,
                        ext,
                        top,
                        prism: k,
                        z_min: f64::INFINITY,
                    });
                }
            }
        }
    }

    /// The ray corner `c` diffracts from the site (`zs` m above sea level) to the pixel `q`
    /// (receiver at `zq`), if both legs are clear.
    #[allow(clippy::too_many_arguments)]
    fn corner_ray(
        &self,
        site: [f64; 2],
        zs: f64,
        q: [f64; 2],
        zq: f64,
        c: &Corner,
        eps: Complex64,
        image: Option<&Image>,
        sight: &mut Sight,
    ) -> Option<(f64, f64, f64, f64)> {
        let src = image.map_or(site, |m| m.at);
        let to_s = [src[0] - c.v[0], src[1] - c.v[1]];
        let to_q = [q[0] - c.v[0], q[1] - c.v[1]];
        let (r1, r2) = (crate::norm(to_s[0], to_s[1]), crate::norm(to_q[0], to_q[1]));
        if r1 < 1e-6 || r2 < 1e-6 {
            return None;
        }
        let zv = zs + (zq - zs) * r1 / (r1 + r2);
        let zt = self.terrain_at(c.v[0], c.v[1]);
        if zv < zt || zv > zt + c.top || (image.is_none() && zv <= c.z_min) {
            return None;
        }
        let (mut phi1, mut phi2) = (ccw(c.a0, to_s), ccw(c.a0, to_q));
        if !(phi1 > 0.0 && phi1 < c.ext && phi2 > 0.0 && phi2 < c.ext) {
            return None;
        }
        if phi1 > 0.5 * c.ext {
            // Face 0 is the face the site lights: measure from the other face.
            (phi1, phi2) = (c.ext - phi1, c.ext - phi2);
        }
        let out = c.outside();
        // The legs: site -> (wall ->) corner -> pixel.
        let mut reflectance = 1.0;
        let first = match image {
            None => (c.v, zv, r1),
            Some(m) => {
                let zp = zs + (zv - zs) * m.d_sp / r1;
                let zt = self.terrain_at(m.p[0], m.p[1]);
                if zp < zt || zp > zt + m.top {
                    return None;
                }
                if zv <= m.z_min {
                    return None;
                }
                let k = [m.p[0] - site[0], m.p[1] - site[1], zp - zs];
                let kn = (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]).sqrt().max(1e-9);
                reflectance = wall_reflectance(m.eps, k.map(|v| v / kn), m.n, self.polarization);
                (m.p, zp, m.d_sp)
            }
        };
        if !sight.clear(out, zv, q, zq) {
            return None;
        }
        let s1 = (r1 * r1 + (zv - zs).powi(2)).sqrt();
        let s2 = (r2 * r2 + (zq - zv).powi(2)).sqrt();
        let sin_b = r1 / s1;
        let l = s1 * s2 * sin_b * sin_b / (s1 + s2);
        // The field along a vertical edge is perpendicular to the horizontal plane of
        // incidence: the ground's horizontal-polarisation formula, and the other way round.
        let face = match self.polarization {
            RayPolarization::V => RayPolarization::H,
            RayPolarization::H => RayPolarization::V,
        };
        let ground = RayGround::Dielectric(eps);
        // Each face's grazing angle: the angle between the ray and the face's plane.
        let grazing = |g: f64| g.sin().abs().asin();
        let r0 = reflection_coefficient(ground, face, grazing(phi1));
        let rn = reflection_coefficient(ground, face, grazing(c.ext - phi2));
        let k = crate::wavenumber(self.freq_hz);
        let d = utd_wedge(c.ext / PI, phi1, phi2, l, sin_b, k, r0, rn);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        let factor =
            reflectance * (lambda / (4.0 * PI)).powi(2) * d.norm_sqr() / (s1 * s2 * (s1 + s2));
        let (p, zp, dp) = first;
        let az = (p[1] - site[1]).atan2(p[0] - site[0]).to_degrees();
        let el = (zp - zs).atan2(dp).to_degrees();
        Some((az, el, factor, s1 + s2))
    }

    /// Every ray that the corners of the buildings diffract from the site `site` (`[x, y,
    /// height above the terrain]`) to the pixels the buildings hide from it (module docs);
    /// `eps` is each prism's wall permittivity. Rows run in parallel.
    pub fn corner_rays(&self, site: [f64; 3], eps: &[Complex64]) -> Result<Vec<WallRay>> {
        let [corners, _] = self.edge_rays(site, eps, false)?;
        Ok(corners)
    }

    /// The corners' rays ([`Self::corner_rays`]) and, with `eaves`, the rays the roof edges
    /// beside the line diffract to the same pixels ([`eaves`]).
    // Long: the corners' and the eaves' rays share one parallel pass over the rows, with the
    // corners and their images of the site found once for every row.
    pub fn edge_rays(
        &self,
        site: [f64; 3],
        eps: &[Complex64],
        eaves: bool,
    ) -> Result<[Vec<WallRay>; 2]> {
        self.check()?;
        let Some(prisms) = self.prisms else {
            return Ok([Vec::new(), Vec::new()]);
        };
        if eps.len() != prisms.len() {
            return Err(CoreError::invalid(
                "prism_eps",
                format!("must have one permittivity a prism ({})", prisms.len()),
                eps.len(),
            ));
        }
        if let Some(e) = eps
            .iter()
            .find(|e| !(e.re.is_finite() && e.im.is_finite() && e.re >= 1.0 && e.im <= 0.0))
        {
            return Err(CoreError::invalid(
                "prism_eps",
                "must be finite with Re >= 1 and Im <= 0",
                e,
            ));
        }
        if !site.iter().all(|v| v.is_finite()) || site[2] <= 0.0 {
            return Err(CoreError::invalid(
                "sites",
                "must be finite, above the ground",
                format!("{site:?}"),
            ));
        }
        let s = [site[0], site[1]];
        let zs = self.terrain_at(s[0], s[1]) + site[2];
        let w = self.x_m.len();
        // Each blocking prism's corners and their images of the site, found once (the first
        // row that needs them) and shared by every row.
        let cache: Vec<OnceLock<CornersOf>> = (0..prisms.len()).map(|_| OnceLock::new()).collect();
        let bounds = self.bounds();
        // The ray meets a corner's edge between the site's height and the pixel's: a corner whose
        // roof is below both never diffracts.
        let zq_min = (0..self.y_m.len())
            .flat_map(|i| (0..w).map(move |j| [self.x_m[j], self.y_m[i]]))
            .map(|q| self.receiver_height(q))
            .fold(f64::INFINITY, f64::min);
        let lit = self.lit_corners((s, zs), zs.min(zq_min), eps, bounds);
        let lit_eaves = eaves.then(|| self.lit_eaves((s, zs), bounds));
        let (corners, eaves): (Vec<_>, Vec<_>) = (0..self.y_m.len())
            .into_par_iter()
            .flat_map_iter(|i| {
                let mut sight = self.sight(bounds);
                let (mut hits, mut ts) = (Vec::new(), Vec::new());
                let mut rays = Vec::new();
                for j in 0..w {
                    let q = [self.x_m[j], self.y_m[i]];
                    let zq = self.receiver_height(q);
                    if sight.clear_listing(s, zs, q, zq) {
                        continue;
                    }
                    let start = rays.len();
                    let to_ray = |(az_deg, el_deg, factor, length_m)| WallRay {
                        pixel: i * w + j,
                        az_deg,
                        el_deg,
                        factor,
                        length_m,
                    };
                    let corner = |r| (false, to_ray(r));
                    // The buildings in the way of the straight line: among those the check
                    // just read.
                    hits.clone_from(&sight.near);
                    hits.retain(|&k| self.crosses_below(&[k], (s, zs), (q, zq), &mut ts));
                    for &k in &hits {
                        let found = cache[k as usize].get_or_init(|| {
                            let (mut corners, mut scratch) = (Vec::new(), Vec::new());
                            self.corners_of(k as usize, &mut corners);
                            corners
                                .into_iter()
                                .map(|mut c| {
                                    let imgs = self.sources_of(
                                        (s, zs),
                                        &mut c,
                                        eps,
                                        &mut scratch,
                                        &mut sight,
                                    );
                                    (c, imgs)
                                })
                                .collect()
                        });
                        for (c, imgs) in found {
                            let sources = std::iter::once(None).chain(imgs.iter().map(Some));
                            for m in sources {
                                let ray =
                                    self.corner_ray(s, zs, q, zq, c, eps[c.prism], m, &mut sight);
                                rays.extend(ray.map(corner));
                            }
                        }
                    }
                    // The corners the site, or its image in a wall, lights beside the line
                    // (their buildings not in the way; `hits` is sorted).
                    lit.near(q, |(c, imgs)| {
                        if hits.binary_search(&(c.prism as u32)).is_ok() {
                            return;
                        }
                        let sources = std::iter::once(None).chain(imgs.iter().map(Some));
                        for m in sources {
                            let ray = self.corner_ray(s, zs, q, zq, c, eps[c.prism], m, &mut sight);
                            rays.extend(ray.map(corner));
                        }
                    });
                    // The roof edges beside the line, of buildings not in the way, where their
                    // rays can count beside free space and the corners' ([`eaves`]).
                    if let Some(lit) = &lit_eaves {
                        let d2 = (q[0] - s[0]).powi(2) + (q[1] - s[1]).powi(2) + (zq - zs).powi(2);
                        let strongest = rays[start..]
                            .iter()
                            .map(|(_, r): &(bool, WallRay)| r.factor)
                            .fold(0.0, f64::max);
                        let least = (eaves::floor(self.freq_hz) / d2)
                            .max(strongest * 10f64.powf(-0.1 * eaves::EAVE_BELOW_DB));
                        lit.near(q, |e| {
                            if hits.binary_search(&(e.prism as u32)).is_ok() {
                                return;
                            }
                            let ray = self.eave_ray(
                                s,
                                zs,
                                q,
                                zq,
                                e,
                                eps[e.prism],
                                least,
                                &hits,
                                &mut sight,
                            );
                            rays.extend(ray.map(|r| (true, to_ray(r))));
                        });
                    }
                }
                rays
            })
            .partition(|(eave, _)| !eave);
        let strip = |v: Vec<(bool, WallRay)>| v.into_iter().map(|(_, r)| r).collect();
        Ok([strip(corners), strip(eaves)])
    }
}

pub mod eaves;
mod sources;
#[cfg(test)]
mod tests;
