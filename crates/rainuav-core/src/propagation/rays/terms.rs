//! What a path's rays are made of: its geometry ([`PathGeometry`], traced once a map), the
//! terms of a pixel's mean power that rain does not change ([`PixelTerms`]), and the ground's
//! reflection coefficient.

use super::*;

/// The geometry of one site-pixel path: everything of its rays but the antenna gains, the
/// transmit power and the rain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathGeometry {
    /// Length of the direct ray, m.
    pub d1: f64,
    /// Length of the ground-reflected ray, m.
    pub d2: f64,
    /// Diffraction loss of the direct ray (Bullington over the profile), dB.
    pub loss_db: f64,
    /// Departure elevation (rad) toward which the direct ray's antenna gain is taken: the
    /// diffracting edge where the profile costs a loss, else the receiver.
    pub el_direct: f64,
    /// Departure elevation (rad) toward the specular point.
    pub el_reflect: f64,
    /// Grazing angle (rad) on the local ground line at the specular point.
    pub psi: f64,
    /// The reflected ray's amplitude factor for the ground's roughness, `exp(-2 (k sigma_h sin
    /// psi)^2)` (1 over smooth ground), where it exists (a ground, its specular point bare
    /// and seen by both ends); 0 where it does not.
    pub reflect: f64,
}

impl PathGeometry {
    /// The geometry as a row: `[d1, d2, loss_db, el_direct, el_reflect, psi, reflect]`.
    pub fn to_row(&self) -> [f64; 7] {
        [
            self.d1,
            self.d2,
            self.loss_db,
            self.el_direct,
            self.el_reflect,
            self.psi,
            self.reflect,
        ]
    }

    /// The geometry of a row of [`PathGeometry::to_row`].
    pub fn from_row(r: &[f64]) -> Self {
        PathGeometry {
            d1: r[0],
            d2: r[1],
            loss_db: r[2],
            el_direct: r[3],
            el_reflect: r[4],
            psi: r[5],
            reflect: r[6],
        }
    }
}

/// Paths already traced ([`RayScene::geometry_table`]): the sites `[x, y, height]` and their
/// table `(S, H, W, 7)`; a transmitter at one of these sites reads its paths from the table.
#[derive(Debug, Clone, Copy)]
pub struct KnownPaths<'a> {
    /// The sites.
    pub sites: &'a [[f64; 3]],
    /// Their paths, rows of [`PathGeometry::to_row`].
    pub table: ArrayView4<'a, f64>,
}

/// One transmitter's mean power over one pixel (mW) split into what rain does not change:
/// with the rain's mean specific attenuation `gamma` (dB/m) along the rays' horizontal path,
/// `P = direct a1^2 + reflect a2^2 + cross a1 a2`, `a_i = 10^(-gamma d_i / 20)`
/// ([`PixelTerms::power`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelTerms {
    /// Power of the direct ray in clear air, mW.
    pub direct: f64,
    /// Power of the reflected ray in clear air, mW.
    pub reflect: f64,
    /// Their interference (the pixel mean of `2 Re(E1 conj E2)`) in clear air, mW.
    pub cross: f64,
    /// Length of the direct ray, m.
    pub d1: f64,
    /// Length of the reflected ray, m.
    pub d2: f64,
    /// Power of the rays reflected by walls in clear air (their sum, incoherent), mW
    /// ([`crate::propagation::walls`]; 0: none).
    pub wall: f64,
    /// The wall rays' mean length, weighted by their power, m.
    pub d3: f64,
}

impl PixelTerms {
    /// The power (mW) with rain of mean specific attenuation `gamma` (dB/m) along the path.
    pub fn power(&self, gamma: f64) -> f64 {
        let a1 = db_to_amplitude(gamma * self.d1);
        let a2 = db_to_amplitude(gamma * self.d2);
        Self::combine(self.direct, self.reflect, self.cross, a1, a2)
            + Self::wall_power(self.wall, self.d3, gamma)
    }

    /// The wall rays' power `wall` (mW in clear air) through rain of mean specific
    /// attenuation `gamma` (dB/m) along their mean length `d3` (m).
    pub fn wall_power(wall: f64, d3: f64, gamma: f64) -> f64 {
        if wall == 0.0 {
            0.0
        } else {
            wall * db_to_amplitude(gamma * d3).powi(2)
        }
    }

    /// `direct a1^2 + reflect a2^2 + cross a1 a2` (never below 0): the power of the terms
    /// with the rays' amplitude factors `a1`, `a2`.
    pub fn combine(direct: f64, reflect: f64, cross: f64, a1: f64, a2: f64) -> f64 {
        (direct * a1 * a1 + reflect * a2 * a2 + cross * a1 * a2).max(0.0)
    }
}

/// Fresnel reflection coefficient of the ground at grazing angle `psi` (radians).
pub fn reflection_coefficient(ground: RayGround, pol: RayPolarization, psi: f64) -> Complex64 {
    match (ground, pol) {
        (RayGround::None, _) => Complex64::new(0.0, 0.0),
        (RayGround::Pec, RayPolarization::H) => Complex64::new(-1.0, 0.0),
        (RayGround::Pec, RayPolarization::V) => Complex64::new(1.0, 0.0),
        (RayGround::Dielectric(eps), p) => {
            let (s, c) = psi.sin_cos();
            let root = (eps - c * c).sqrt();
            match p {
                RayPolarization::H => (s - root) / (s + root),
                RayPolarization::V => (eps * s - root) / (eps * s + root),
            }
        }
    }
}

/// The amplitude factor `10^(-loss / 20)` of a loss in dB (1 for no loss, without a `powf`).
pub(crate) fn db_to_amplitude(loss_db: f64) -> f64 {
    if loss_db == 0.0 {
        1.0
    } else {
        10f64.powf(-loss_db / 20.0)
    }
}

pub(super) fn sinc(u: f64) -> f64 {
    if u.abs() < 1e-8 { 1.0 } else { u.sin() / u }
}
