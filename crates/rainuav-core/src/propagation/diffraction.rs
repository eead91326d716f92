//! Diffraction (docs/physics.md section 12), in metres throughout.
//!
//! **Terrain**: ITU-R P.526-15 section 4.5.1, the Bullington construction for a general path
//! with its correction for real terrain (the same method as ITU-R P.452-16 section 4.2.1). For a
//! profile of heights `h_i` (m above sea level) at distances `d_i` (m) from the transmitter,
//! `0 < d_i < d`, and the antennas at `h_ts`, `h_rs` (m above sea level), with the Earth's bulge
//! `g_i = h_i + d_i (d - d_i) / (2 a_e)` (`a_e` = 8500 km, k = 4/3):
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
//!
//! **Buildings** are isolated edges, not terrain: the correction is not theirs. Over roofs,
//! Deygout's principal-edge construction ([`deygout`]: the edge of largest `nu`, then the
//! largest on each side of it, knife-edge losses added; three edges at most). Round a
//! building's vertical edges, the uniform theory of diffraction for a finitely conducting
//! wedge, ITU-R P.526-15 section 6 ([`utd_wedge`]).

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

/// Deygout's principal-edge loss (module docs) of the profile `(d_i, h_i)` between antennas at
/// `h_ts` and `h_rs` (m above sea level) `d` m apart, at wavelength `lambda`: the edge of
/// largest `nu` over the whole path, then the edge of largest `nu` on each sub-path (from each
/// end to the principal edge), each `J(nu)` added where `nu > -0.78`. The Earth's bulge is
/// added as in [`bullington`]. Returns the loss (dB, no correction) and the principal edge
/// `(distance, height)` (None: no loss).
pub fn deygout(
    profile: &[(f64, f64)],
    d: f64,
    h_ts: f64,
    h_rs: f64,
    lambda: f64,
) -> (f64, Option<(f64, f64)>) {
    deygout_with(profile, d, h_ts, h_rs, lambda, |nu, _, _, _| {
        knife_edge_loss_db(nu)
    })
}

/// [`deygout`] with each chosen edge's loss given by `edge_loss(nu, i, from, to)`: its `nu`, its
/// index in `profile` and the ends of its (sub-)path, `(distance, height)` with the Earth's
/// bulge added.
pub fn deygout_with(
    profile: &[(f64, f64)],
    d: f64,
    h_ts: f64,
    h_rs: f64,
    lambda: f64,
    edge_loss: impl Fn(f64, usize, (f64, f64), (f64, f64)) -> f64,
) -> (f64, Option<(f64, f64)>) {
    if d.is_nan() || d <= 0.0 {
        return (0.0, None);
    }
    let bulge = |di: f64| di * (d - di) / (2.0 * EFFECTIVE_EARTH_RADIUS_M);
    // The edge of largest nu strictly between (s0, z0) and (s1, z1).
    let best = |(s0, z0): (f64, f64), (s1, z1): (f64, f64)| {
        let span = s1 - s0;
        let mut out: Option<(f64, usize, (f64, f64))> = None;
        for (i, &(di, hi)) in profile.iter().enumerate() {
            if di <= s0 || di >= s1 {
                continue;
            }
            let g = hi + bulge(di);
            let (a, b) = (di - s0, s1 - di);
            let line = z0 + (z1 - z0) * a / span;
            let nu = (g - line) * (2.0 * span / (lambda * a * b)).sqrt();
            if out.is_none_or(|(n, _, _)| nu > n) {
                out = Some((nu, i, (di, g)));
            }
        }
        out.filter(|(nu, _, _)| *nu > -0.78)
    };
    let (t, r) = ((0.0, h_ts), (d, h_rs));
    let Some((nu_p, i_p, edge)) = best(t, r) else {
        return (0.0, None);
    };
    let mut loss = edge_loss(nu_p, i_p, t, r);
    for (a, b) in [(t, edge), (edge, r)] {
        if let Some((nu, i, _)) = best(a, b) {
            loss += edge_loss(nu, i, a, b);
        }
    }
    if loss == 0.0 {
        return (0.0, None);
    }
    (loss, Some(edge))
}

/// The Fresnel integrals `(C(x), S(x))`, `C(x) = integral_0^x cos(pi t^2 / 2) dt`, `x >= 0`:
/// the power series below `x = 1.5`, the continued fraction (modified Lentz) above, both to
/// 1e-12 (the method of Press et al., Numerical Recipes, section 6.9).
pub fn fresnel_integrals(x: f64) -> (f64, f64) {
    use num_complex::Complex64;
    use std::f64::consts::PI;
    const EPS: f64 = 1e-12;
    let ax = x.abs();
    if ax < 1e-150 {
        return (ax, 0.0);
    }
    if ax <= 1.5 {
        let fact = 0.5 * PI * ax * ax;
        let (mut sum, mut sums, mut sumc) = (0.0, 0.0, ax);
        let (mut sign, mut term, mut n, mut odd) = (1.0, ax, 3.0, true);
        for k in 1..200 {
            term *= fact / k as f64;
            sum += sign * term / n;
            let test = sum.abs() * EPS;
            if odd {
                sign = -sign;
                sums = sum;
                sum = sumc;
            } else {
                sumc = sum;
                sum = sums;
            }
            if term < test {
                break;
            }
            odd = !odd;
            n += 2.0;
        }
        return (sumc, sums);
    }
    let pix2 = PI * ax * ax;
    let mut b = Complex64::new(1.0, -pix2);
    let mut cc = Complex64::new(1e300, 0.0);
    let mut d = b.inv();
    let mut h = d;
    let mut n = -1.0;
    for _ in 2..200 {
        n += 2.0;
        let a = -n * (n + 1.0);
        b += 4.0;
        d = (a * d + b).inv();
        cc = b + a / cc;
        let del = cc * d;
        h *= del;
        if (del.re - 1.0).abs() + del.im.abs() < EPS {
            break;
        }
    }
    h *= Complex64::new(ax, -ax);
    let cs = Complex64::new(0.5, 0.5) * (1.0 - Complex64::from_polar(1.0, 0.5 * pix2) * h);
    (cs.re, cs.im)
}

/// The UTD transition function `F(X) = 2 j sqrt(X) exp(j X) integral_{sqrt X}^inf exp(-j t^2)
/// dt` (ITU-R P.526-15 section 6), `X >= 0`, from the Fresnel integrals
/// ([`fresnel_integrals`]): the tail is `sqrt(pi / 2) [(1/2 - C(z)) - j (1/2 - S(z))]` at
/// `z = sqrt(2 X / pi)`.
pub fn utd_transition(x: f64) -> num_complex::Complex64 {
    use num_complex::Complex64;
    let x = x.max(0.0);
    let (c, s) = fresnel_integrals((2.0 * x / std::f64::consts::PI).sqrt());
    let tail = (std::f64::consts::PI / 2.0).sqrt() * Complex64::new(0.5 - c, -(0.5 - s));
    Complex64::new(0.0, 2.0 * x.sqrt()) * Complex64::from_polar(1.0, x) * tail
}

/// The UTD diffraction coefficient of a finitely conducting wedge, ITU-R P.526-15 section 6
/// (Kouyoumjian and Pathak's form): the exterior angle `n pi`, incidence and diffraction
/// angles `phi1`, `phi2` (rad, from face 0, `0 < phi < n pi`), `l = s1 s2 sin^2(beta0) / (s1 +
/// s2)` (m), `sin_beta0` the sine of the angle between the incident ray and the edge, `k` the
/// wavenumber and `r0`, `rn` the faces' reflection coefficients (at grazing angles `phi1` and `n
/// pi - phi2`). The diffracted field is `E0 exp(-j k s1) / s1 D sqrt(s1 / (s2 (s1 + s2)))
/// exp(-j k s2)`. Where a cotangent's argument meets a boundary, the angle is moved by 1e-6 rad
/// (the product `cot F` is finite there).
#[allow(clippy::too_many_arguments)]
pub fn utd_wedge(
    n: f64,
    phi1: f64,
    phi2: f64,
    l: f64,
    sin_beta0: f64,
    k: f64,
    r0: num_complex::Complex64,
    rn: num_complex::Complex64,
) -> num_complex::Complex64 {
    use num_complex::Complex64;
    use std::f64::consts::PI;
    let term = |beta: f64, sign: f64| {
        let mut b = beta;
        let mut arg = (PI + sign * b) / (2.0 * n);
        if arg.sin().abs() < 1e-9 {
            b += 1e-6;
            arg = (PI + sign * b) / (2.0 * n);
        }
        let big_n = ((b + sign * PI) / (2.0 * n * PI)).round();
        let a = 2.0 * ((2.0 * n * PI * big_n - b) / 2.0).cos().powi(2);
        (1.0 / arg.tan()) * utd_transition(k * l * a)
    };
    let sum = term(phi2 - phi1, 1.0)
        + term(phi2 - phi1, -1.0)
        + r0 * term(phi2 + phi1, -1.0)
        + rn * term(phi2 + phi1, 1.0);
    let pre = -Complex64::from_polar(1.0, -PI / 4.0)
        / (2.0 * n * (2.0 * PI * k).sqrt() * sin_beta0.max(1e-9));
    pre * sum
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

    #[test]
    fn fresnel_integrals_match_published_values() {
        // Abramowitz and Stegun Table 7.7 (9-10 digits).
        for (x, c, s) in [
            (0.5, 0.4923442, 0.0647324),
            (1.0, 0.7798934, 0.4382591),
            (2.0, 0.4882534, 0.3434157),
            (5.0, 0.5636312, 0.4991914),
        ] {
            let (cc, ss) = fresnel_integrals(x);
            assert!(
                (cc - c).abs() < 1e-6 && (ss - s).abs() < 1e-6,
                "{x}: {cc} {ss}"
            );
        }
    }

    #[test]
    fn the_transition_function_tends_to_one_and_to_sqrt_pi_x() {
        // Large X: F -> 1; small X: |F| ~ sqrt(pi X) (P.526 section 6).
        assert!((utd_transition(400.0).norm() - 1.0).abs() < 1e-4);
        let x = 1e-4;
        let r = utd_transition(x).norm() / (std::f64::consts::PI * x).sqrt();
        assert!((r - 1.0).abs() < 0.02, "{r}");
    }

    #[test]
    fn a_conducting_half_plane_at_its_shadow_boundary_halves_the_field() {
        // n = 2 (a screen), PEC (soft: R = -1): on the shadow boundary (phi2 = phi1 + pi) the
        // diffracted field is half the incident one (the geometrical-optics jump), to the
        // approximation's accuracy.
        use num_complex::Complex64;
        let (s1, s2, k) = (100.0, 100.0, 2.0 * std::f64::consts::PI / 0.06);
        let l = s1 * s2 / (s1 + s2);
        let phi1 = 0.5;
        let d = utd_wedge(
            2.0,
            phi1,
            phi1 + std::f64::consts::PI,
            l,
            1.0,
            k,
            Complex64::new(-1.0, 0.0),
            Complex64::new(-1.0, 0.0),
        );
        let diffracted = d.norm() * (s1 / (s2 * (s1 + s2))).sqrt() / s1;
        let incident = 1.0 / (s1 + s2);
        let ratio = diffracted / incident;
        assert!((ratio - 0.5).abs() < 0.02, "{ratio}");
    }

    #[test]
    fn deep_in_a_screen_shadow_utd_is_the_knife_edge() {
        // A half plane (n = 2) deep in its shadow: the UTD field against P.526's J(nu) with
        // the same geometry; the two are the same asymptotic solution (within 1 dB at nu ~ 3).
        use num_complex::Complex64;
        use std::f64::consts::PI;
        let (lam, s1, s2) = (0.06, 200.0, 200.0);
        let k = 2.0 * PI / lam;
        // Source on the line phi1 = pi / 2 (normal to the screen); the field point at an
        // angle theta into the shadow: phi2 = phi1 + pi + theta.
        let theta: f64 = 0.15;
        let d = utd_wedge(
            2.0,
            PI / 2.0,
            1.5 * PI + theta,
            s1 * s2 / (s1 + s2),
            1.0,
            k,
            Complex64::new(-1.0, 0.0),
            Complex64::new(-1.0, 0.0),
        );
        let e = d.norm() * (s1 / (s2 * (s1 + s2))).sqrt() / s1;
        // The straight path's length and the edge's clearance above it.
        let h = s2 * theta.sin() * s1 / (s1 + s2 * theta.cos());
        let nu = h * (2.0 / lam * (1.0 / s1 + 1.0 / s2)).sqrt();
        let utd_db = -20.0 * (e * (s1 + s2)).log10();
        let j = knife_edge_loss_db(nu);
        assert!(
            (utd_db - j).abs() < 1.0,
            "UTD {utd_db} dB, J {j} dB (nu {nu})"
        );
    }

    #[test]
    fn deygout_of_one_edge_is_its_knife_edge_without_the_correction() {
        let lam = 0.06;
        let (loss, edge) = deygout(&[(500.0, 200.0)], 1000.0, 25.0, 100.0, lam);
        let g = 200.0 + 500.0 * 500.0 / (2.0 * EFFECTIVE_EARTH_RADIUS_M);
        let nu = (g - 62.5) * (2.0 * 1000.0 / (lam * 500.0 * 500.0)).sqrt();
        assert!((loss - knife_edge_loss_db(nu)).abs() < 1e-9);
        assert!((edge.unwrap().0 - 500.0).abs() < 1e-9);
        assert_eq!(
            deygout(&[(300.0, 0.0)], 1000.0, 25.0, 100.0, lam),
            (0.0, None)
        );
    }
}
