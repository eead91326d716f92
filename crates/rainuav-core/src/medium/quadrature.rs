//! Gauss-Legendre quadrature by the Golub-Welsch method (eigen-decomposition of the
//! symmetric Jacobi matrix, done with faer), and composite rules over panels.

use crate::error::{CoreError, Result};
use faer::{Mat, Side};

/// Gauss-Legendre nodes (ascending) and weights on [-1, 1] for `n` points.
///
/// The Jacobi matrix of the Legendre polynomials has a zero diagonal and off-diagonal
/// `k / sqrt(4 k^2 - 1)`; its eigenvalues are the nodes and the weights are
/// `2 v_0^2` with `v_0` the first component of each normalised eigenvector.
pub fn gauss_legendre(n: usize) -> Result<(Vec<f64>, Vec<f64>)> {
    if n == 0 || n > 512 {
        return Err(CoreError::invalid("nodes", "must be within 1..512", n));
    }
    let jacobi = Mat::<f64>::from_fn(n, n, |i, j| {
        if i.abs_diff(j) == 1 {
            let k = i.max(j) as f64;
            k / (4.0 * k * k - 1.0).sqrt()
        } else {
            0.0
        }
    });
    let evd = jacobi
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| CoreError::Internal(format!("Golub-Welsch eigensolver: {e:?}")))?;
    let s = evd.S();
    let u = evd.U();
    let mut pairs: Vec<(f64, f64)> = (0..n)
        .map(|k| (s[k], 2.0 * u[(0, k)] * u[(0, k)]))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    // The rule is symmetric; symmetrising removes the eigensolver's last-bit asymmetry.
    let mut nodes: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let mut weights: Vec<f64> = pairs.iter().map(|p| p.1).collect();
    for i in 0..n / 2 {
        let j = n - 1 - i;
        let x = 0.5 * (nodes[j] - nodes[i]);
        let w = 0.5 * (weights[i] + weights[j]);
        nodes[i] = -x;
        nodes[j] = x;
        weights[i] = w;
        weights[j] = w;
    }
    if n % 2 == 1 {
        nodes[n / 2] = 0.0;
    }
    Ok((nodes, weights))
}

/// A composite Gauss-Legendre rule: the same n-point rule on each of several panels.
#[derive(Debug, Clone, PartialEq)]
pub struct CompositeRule {
    /// Abscissae, ascending.
    pub nodes: Vec<f64>,
    /// Weights (sum to the length of the interval).
    pub weights: Vec<f64>,
}

impl CompositeRule {
    /// `n`-point Gauss-Legendre on each panel `[edges[i], edges[i+1]]`.
    /// `edges` must be strictly increasing.
    pub fn new(edges: &[f64], n: usize) -> Result<Self> {
        let (x, w) = gauss_legendre(n)?;
        let mut nodes = Vec::with_capacity(n * edges.len().saturating_sub(1));
        let mut weights = Vec::with_capacity(nodes.capacity());
        for p in edges.windows(2) {
            let (a, b) = (p[0], p[1]);
            if b.is_nan() || a.is_nan() || b <= a {
                return Err(CoreError::Internal(format!(
                    "panel edges {a} {b} not increasing"
                )));
            }
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            for k in 0..n {
                nodes.push(mid + half * x[k]);
                weights.push(half * w[k]);
            }
        }
        Ok(CompositeRule { nodes, weights })
    }

    /// `sum w_k f(x_k)`.
    pub fn integrate(&self, f: impl Fn(f64) -> f64) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(x))
            .sum()
    }
}

/// Panel edges covering `[lo, hi]`: split at every breakpoint strictly inside, then each
/// piece into equal panels no wider than `max_width`.
pub fn panel_edges(lo: f64, hi: f64, breakpoints: &[f64], max_width: f64) -> Vec<f64> {
    let mut cuts: Vec<f64> = breakpoints
        .iter()
        .copied()
        .filter(|&b| b > lo && b < hi)
        .collect();
    cuts.push(lo);
    cuts.push(hi);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut edges = vec![lo];
    for piece in cuts.windows(2) {
        let (a, b) = (piece[0], piece[1]);
        let k = ((b - a) / max_width).ceil().max(1.0) as usize;
        for i in 1..=k {
            edges.push(if i == k {
                b
            } else {
                a + (b - a) * i as f64 / k as f64
            });
        }
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n-point rule integrates polynomials of degree 2n-1 exactly: 1e-14 relative
    /// allows for rounding in the eigensolver.
    #[test]
    fn exact_for_polynomials() {
        for n in [1, 2, 5, 16, 40] {
            let (x, w) = gauss_legendre(n).unwrap();
            for deg in 0..(2 * n) {
                let got: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(&x, &w)| w * x.powi(deg as i32))
                    .sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!(
                    (got - exact).abs() < 1e-13,
                    "n={n} deg={deg}: {got} vs {exact}"
                );
            }
        }
    }

    /// Known 3-point rule: nodes ±sqrt(3/5), weights 5/9, 8/9.
    #[test]
    fn three_point_rule() {
        let (x, w) = gauss_legendre(3).unwrap();
        assert!((x[2] - (0.6f64).sqrt()).abs() < 1e-15);
        assert!((w[0] - 5.0 / 9.0).abs() < 1e-15 && (w[1] - 8.0 / 9.0).abs() < 1e-15);
    }

    /// Composite rule on exp over split panels: 1e-13 relative (16 points per panel is
    /// far beyond what exp needs; the residue is rounding).
    #[test]
    fn composite_exp() {
        let edges = panel_edges(0.1, 8.0, &[1.25], 1.0);
        assert!(edges.contains(&1.25));
        let rule = CompositeRule::new(&edges, 16).unwrap();
        let got = rule.integrate(|d| (-2.0 * d).exp());
        let exact = ((-0.2f64).exp() - (-16.0f64).exp()) / 2.0;
        assert!((got / exact - 1.0).abs() < 1e-13);
    }
}
