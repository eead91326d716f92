//! Diffraction over a path's profile: ITU-R P.526-15 section 4.5.1, the Bullington
//! construction for a general path with its correction for real terrain (the same method as
//! ITU-R P.452-16 section 4.2.1). `docs/physics.md` section 12 gives the formulas; here they
//! are written in metres throughout.
//!
//! For a profile of heights `h_i` (m above sea level) at distances `d_i` (m) from the
//! transmitter, `0 < d_i < d`, and the antennas at `h_ts`, `h_rs` (m above sea level), with
//! the Earth's bulge `g_i = h_i + d_i (d - d_i) / (2 a_e)` (`a_e` = 8500 km, k = 4/3):
//!
//! - the steepest slope from the transmitter `S_tim = max (g_i - h_ts) / d_i` against the
//!   slope of the line between the ends `S_tr = (h_rs - h_ts) / d`;
//! - in line of sight (`S_tim < S_tr`), the edge of largest Fresnel-Kirchhoff parameter
//!   `nu_i = [g_i - (h_ts (d - d_i) + h_rs d_i) / d] sqrt(2 d / (lambda d_i (d - d_i)))`;
//! - otherwise the Bullington point where the steepest lines from both ends cross, at `d_bp =
//!   (h_rs - h_ts + S_rim d) / (S_tim + S_rim)`, `S_rim = max (g_i - h_rs) / (d - d_i)`;
//! - `L_uc = J(nu)` with `J` the knife-edge loss ([`knife_edge_loss_db`]), and
//!   `L = L_uc + (1 - exp(-L_uc / 6)) (10 + 0.02 d_km)`: the ITU's empirical correction for a
//!   real profile (up to about 10 dB), part of the method.
//!
//! The spherical-Earth term of the delta-Bullington method (`L_sph` against the Bullington
//! loss of the smooth profile) is neglected: over the few kilometres of a UAV's map and at its
//! heights the smooth Earth does not reach the path's first Fresnel zone, and the term is 0.

/// The effective Earth radius (k = 4/3), m.
pub const EFFECTIVE_EARTH_RADIUS_M: f64 = 8.5e6;

/// ITU-R P.526 single knife-edge loss in dB, eq. (31):
/// `J(nu) = 6.9 + 20 log10(sqrt((nu - 0.1)^2 + 1) + nu - 0.1)` for `nu > -0.78`, else 0.
pub fn knife_edge_loss_db(nu: f64) -> f64 {
    if nu <= -0.78 {
        return 0.0;
    }
    let v = nu - 0.1;
    6.9 + 20.0 * ((v * v + 1.0).sqrt() + v).log10()
}

/// The Bullington loss of a path and the edge it diffracts over.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bullington {
    /// `L = L_uc + (1 - exp(-L_uc / 6)) (10 + 0.02 d_km)`, dB (0: nothing within the first
    /// Fresnel zone's reach, `nu <= -0.78`).
    pub loss_db: f64,
    /// The uncorrected knife-edge loss `L_uc = J(nu)`, dB.
    pub knife_edge_db: f64,
    /// The diffracting edge, `(distance from the transmitter, height above sea level)` in m:
    /// the Bullington point beyond line of sight, the edge of largest `nu` in it; None where
    /// the loss is 0 (the antenna's gain is then taken along the direct line).
    pub edge: Option<(f64, f64)>,
}

impl Bullington {
    /// No loss and no edge.
    pub const CLEAR: Bullington = Bullington {
        loss_db: 0.0,
        knife_edge_db: 0.0,
        edge: None,
    };
}

/// The Bullington loss (module docs) of the profile `(d_i, h_i)` (m; only points strictly
/// between the ends are used) between antennas at `h_ts` and `h_rs` (m above sea level) `d` m
/// apart, at wavelength `lambda` (m).
pub fn bullington(profile: &[(f64, f64)], d: f64, h_ts: f64, h_rs: f64, lambda: f64) -> Bullington {
    if d.is_nan() || d <= 0.0 {
        return Bullington::CLEAR;
    }
    let bulge = |di: f64| di * (d - di) / (2.0 * EFFECTIVE_EARTH_RADIUS_M);
    let inner = || {
        profile
            .iter()
            .filter(move |&&(di, _)| di > 0.0 && di < d)
            .map(move |&(di, hi)| (di, hi + bulge(di)))
    };
    let s_tr = (h_rs - h_ts) / d;
    let mut s_tim = f64::NEG_INFINITY;
    for (di, gi) in inner() {
        s_tim = s_tim.max((gi - h_ts) / di);
    }
    if s_tim == f64::NEG_INFINITY {
        return Bullington::CLEAR;
    }
    let nu_at = |di: f64, clearance: f64| clearance * (2.0 * d / (lambda * di * (d - di))).sqrt();
    let (nu, edge) = if s_tim < s_tr {
        // Line of sight: the edge of largest nu.
        let mut best = (f64::NEG_INFINITY, (0.0, 0.0));
        for (di, gi) in inner() {
            let line = (h_ts * (d - di) + h_rs * di) / d;
            let nu = nu_at(di, gi - line);
            if nu > best.0 {
                best = (nu, (di, gi));
            }
        }
        best
    } else {
        // Beyond line of sight: the Bullington point.
        let mut s_rim = f64::NEG_INFINITY;
        for (di, gi) in inner() {
            s_rim = s_rim.max((gi - h_rs) / (d - di));
        }
        let d_bp = ((h_rs - h_ts + s_rim * d) / (s_tim + s_rim)).clamp(1e-6 * d, d * (1.0 - 1e-6));
        let h_bp = h_ts + s_tim * d_bp;
        let line = (h_ts * (d - d_bp) + h_rs * d_bp) / d;
        (nu_at(d_bp, h_bp - line), (d_bp, h_bp))
    };
    let l_uc = knife_edge_loss_db(nu);
    if l_uc == 0.0 {
        return Bullington::CLEAR;
    }
    Bullington {
        loss_db: l_uc + (1.0 - (-l_uc / 6.0).exp()) * (10.0 + 0.02 * d / 1000.0),
        knife_edge_db: l_uc,
        edge: Some(edge),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knife_edge_values() {
        // P.526 Figure 9 / eq. (31): J(0) = 6.0 dB, J(1) ~ 13.9 dB, J(-0.78) = 0.
        assert!((knife_edge_loss_db(0.0) - 6.0).abs() < 0.05);
        assert!((knife_edge_loss_db(1.0) - 13.9).abs() < 0.1);
        assert_eq!(knife_edge_loss_db(-0.8), 0.0);
    }

    #[test]
    fn one_thin_wall_beyond_line_of_sight_is_its_knife_edge_plus_the_correction() {
        // Ends at 25 m and 100 m, 1000 m apart, a wall of 200 m at 500 m (no bulge to speak
        // of: 500 * 500 / 1.7e7 = 0.015 m). By hand: the Bullington point is the wall's top.
        let lam = 0.06;
        let b = bullington(&[(500.0, 200.0)], 1000.0, 25.0, 100.0, lam);
        let g = 200.0 + 500.0 * 500.0 / (2.0 * EFFECTIVE_EARTH_RADIUS_M);
        let nu = (g - 62.5) * (2.0 * 1000.0 / (lam * 500.0 * 500.0)).sqrt();
        let j = knife_edge_loss_db(nu);
        assert!(
            (b.knife_edge_db - j).abs() < 1e-9,
            "{} vs {j}",
            b.knife_edge_db
        );
        let want = j + (1.0 - (-j / 6.0).exp()) * (10.0 + 0.02);
        assert!((b.loss_db - want).abs() < 1e-9);
        let (de, he) = b.edge.unwrap();
        assert!((de - 500.0).abs() < 1e-6 && (he - g).abs() < 1e-6);
    }

    #[test]
    fn a_clear_path_costs_nothing_and_has_no_edge() {
        let b = bullington(&[(300.0, 0.0), (600.0, 5.0)], 1000.0, 25.0, 100.0, 0.06);
        assert_eq!(b, Bullington::CLEAR);
        assert_eq!(
            bullington(&[], 1000.0, 25.0, 100.0, 0.06),
            Bullington::CLEAR
        );
    }
}
