//! Invariants of the core that hold for every input, checked on random inputs (proptest):
//! the quadrature that every rain integral rests on, the panels it integrates over, and the
//! physical monotonicity of rain attenuation.

use proptest::prelude::*;
use rainuav_core::medium::p838;
use rainuav_core::medium::quadrature::{CompositeRule, gauss_legendre, panel_edges};
use rainuav_core::medium::{MediumOptions, RainKernel};

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// An n-point Gauss-Legendre rule has positive weights summing to 2, ascending
    /// symmetric nodes inside (-1, 1), and integrates x^k exactly for every k <= 2n - 1
    /// (checked up to k = 24, where the monomials stay well conditioned). Tolerance: 64
    /// ulps of the result per node, the eigensolver's rounding.
    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1(n in 1usize..64) {
        let (x, w) = gauss_legendre(n).unwrap();
        let tol = 64.0 * f64::EPSILON * n as f64;
        prop_assert!(w.iter().all(|&v| v > 0.0));
        prop_assert!((w.iter().sum::<f64>() - 2.0).abs() < tol);
        prop_assert!(x.windows(2).all(|p| p[0] < p[1]));
        prop_assert!(x.iter().all(|&v| v > -1.0 && v < 1.0));
        for i in 0..n {
            prop_assert_eq!(x[i], -x[n - 1 - i]);
        }
        for k in 0..=(2 * n - 1).min(24) {
            let got: f64 = x.iter().zip(&w).map(|(&xi, &wi)| wi * xi.powi(k as i32)).sum();
            let want = if k % 2 == 0 { 2.0 / (k as f64 + 1.0) } else { 0.0 };
            prop_assert!((got - want).abs() < tol, "n {} k {}: {} vs {}", n, k, got, want);
        }
    }

    /// Panels cover [lo, hi] with strictly increasing edges no wider than asked, cut at
    /// every breakpoint inside; a composite rule on them integrates a cubic exactly.
    #[test]
    fn panels_cover_the_interval_and_keep_every_breakpoint(
        lo in -10.0f64..10.0,
        len in 0.01f64..20.0,
        width in 0.05f64..5.0,
        cuts in proptest::collection::vec(0.0f64..1.0, 0..5),
    ) {
        let hi = lo + len;
        let breaks: Vec<f64> = cuts.iter().map(|c| lo + c * len).collect();
        let e = panel_edges(lo, hi, &breaks, width);
        prop_assert_eq!(e[0], lo);
        prop_assert_eq!(*e.last().unwrap(), hi);
        prop_assert!(e.windows(2).all(|p| p[0] < p[1] && p[1] - p[0] <= width * (1.0 + 1e-12)));
        for b in breaks.iter().filter(|&&b| b > lo && b < hi) {
            prop_assert!(e.contains(b), "breakpoint {} lost", b);
        }
        let rule = CompositeRule::new(&e, 2).unwrap();
        let got = rule.integrate(|t| t * t * t - 2.0 * t);
        let want = (hi.powi(4) - lo.powi(4)) / 4.0 - (hi * hi - lo * lo);
        prop_assert!((got - want).abs() < 1e-9 * (1.0 + want.abs() + hi.abs().powi(4)));
    }

    /// ITU-R P.838-3 attenuation k R^alpha is zero in clear air and grows with the rain rate.
    #[test]
    fn p838_grows_with_rain_rate(f_ghz in 1.0f64..1000.0, r in 0.0f64..300.0, dr in 0.1f64..50.0) {
        let f = f_ghz * 1e9;
        let a = p838::specific_attenuation(f, r, 0.0, 0.0);
        let b = p838::specific_attenuation(f, r + dr, 0.0, 0.0);
        prop_assert!(a >= 0.0 && b > a);
        prop_assert_eq!(p838::specific_attenuation(f, 0.0, 0.0, 0.0), 0.0);
    }
}

proptest! {
    // Each case builds a Mie kernel (milliseconds): fewer cases.
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// The forward-scattering model's attenuation is zero in clear air, positive in rain and
    /// grows with the rain rate (more drops of every size under Marshall-Palmer).
    #[test]
    fn rain_attenuation_grows_with_rain_rate(f_ghz in 1.0f64..100.0, r in 0.5f64..150.0) {
        let kernel = RainKernel::new(f_ghz * 1e9, &MediumOptions::default()).unwrap();
        let g0 = kernel.evaluate(0.0).unwrap().gamma_db_per_km;
        let g1 = kernel.evaluate(r).unwrap().gamma_db_per_km;
        let g2 = kernel.evaluate(1.5 * r).unwrap().gamma_db_per_km;
        prop_assert_eq!(g0, 0.0);
        prop_assert!(g1 > 0.0 && g2 > g1, "{} GHz: {} {} {}", f_ghz, g0, g1, g2);
    }
}
